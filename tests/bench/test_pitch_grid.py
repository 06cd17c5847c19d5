"""The pitch probe's quadratic rule (``bench.probes.pitch_grid``) on analytic grids."""

from __future__ import annotations

import numpy as np
import pytest

from bench.probes.pitch_grid import STEPS, _interpolated, quadratic_pitches


def grid_record(score, error) -> dict:
    """A probe record whose 3 x 3 grid's costs are ``score(front, side)`` and whose one
    error (key "D") is ``error(front, side)``."""
    return {"grid": [{"front": f, "side": s, "cost": score(f, s), "err": {"D": error(f, s)}}
                     for f in STEPS for s in STEPS]}


def test_quadratic_rule_finds_a_bowls_least_point():
    """Scores on a tilted bowl whose least point is (1.5, -2.5) degrees: the surface fitted
    to the grid is the bowl itself, so its least point comes back exactly; a prior per
    squared degree moves it to the bowl-plus-prior's least point."""
    def bowl(f, s):
        return 10 + 2 * (f - 1.5) ** 2 + 0.5 * (f - 1.5) * (s + 2.5) + 3 * (s + 2.5) ** 2
    record = grid_record(bowl, lambda f, s: 0.0)
    assert quadratic_pitches(record, 0.0) == pytest.approx((1.5, -2.5), abs=1e-9)
    # with the prior 1 per squared degree: solve the gradient of bowl + f^2 + s^2 = 0
    hessian = np.array([[6.0, 0.5], [0.5, 8.0]])
    gradient_at_zero = np.array([-6.0 + 1.25, 15.0 - 0.75])
    expected = np.linalg.solve(hessian, -gradient_at_zero)
    assert quadratic_pitches(record, 1.0) == pytest.approx(tuple(expected), abs=1e-9)


def test_quadratic_rule_stays_within_a_step_and_falls_back_to_the_best_point():
    """A bowl centred beyond the grid is clipped to one step; a saddle (no least point)
    gives the grid's best point."""
    far = grid_record(lambda f, s: (f - 20) ** 2 + s ** 2, lambda f, s: 0.0)
    assert quadratic_pitches(far, 0.0) == pytest.approx((STEPS[-1], 0.0))
    saddle = grid_record(lambda f, s: f ** 2 - s ** 2 + 0.1 * s, lambda f, s: 0.0)
    assert quadratic_pitches(saddle, 0.0) == pytest.approx((0.0, STEPS[0]))


def test_interpolated_errors_are_exact_for_a_quadratic_and_at_the_grid():
    """Errors quadratic in each pitch are interpolated exactly anywhere; at a grid point
    the interpolation is that point's own error."""
    def error(f, s):
        return 1 + 0.3 * f - 0.2 * s + 0.05 * f * f * s + 0.01 * s * s
    record = grid_record(lambda f, s: 0.0, error)
    assert _interpolated(record, 1.7, -3.1)["err"]["D"] == pytest.approx(error(1.7, -3.1))
    assert _interpolated(record, STEPS[0], STEPS[2])["err"]["D"] == pytest.approx(
        error(STEPS[0], STEPS[2]))
