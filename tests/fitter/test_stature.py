"""Candidates conditioned on the stature: the solved first beta gives the rest stature, or the
posed height."""

import numpy as np
import pytest

from bodyfit.fitter.fit.canvas import extreme_bodies
from bodyfit.fitter.fit.search import SearchSettings
from bodyfit.fitter.fit.stature import StatureConditioner, scaled_to_stature, stature_scale
from bodyfit.fitter.model.body_model import forward, rest_shape


def range_bodies(model):
    """The extreme bodies of the default search's range."""
    return extreme_bodies(model, 20, [-10] * 4, [30] * 4)


@pytest.mark.parametrize("stature_m", [1.55, 1.75, 1.95])
def test_solved_first_beta_gives_the_posed_height(body_model, stature_m):
    """Checked with the NumPy forward on every vertex (the solver sees only the extremes
    through its linear map)."""
    rng = np.random.default_rng(2)
    conditioner = StatureConditioner(body_model, 20, stature_m, 3.0, range_bodies(body_model),
                                     posed=True)
    other, pose = rng.uniform(-1.5, 1.5, (12, 19)), rng.uniform(-10, 30, (12, 4))
    betas = conditioner.complete(other, pose)
    np.testing.assert_array_equal(betas[:, 1:], other)
    z = forward(body_model, betas, pose)[..., 2]
    heights = z.max(axis=1) - z.min(axis=1)
    free = np.abs(betas[:, 0]) < 3.0  # bodies that can reach the height within +-3 sigma
    assert free.sum() >= 8
    np.testing.assert_allclose(heights[free], stature_m, atol=2e-4)
    assert np.all(np.abs(heights[~free] - stature_m) > 2e-4)


@pytest.mark.parametrize("stature_m", [1.55, 1.9])
def test_solved_first_beta_gives_the_rest_stature_whatever_the_pose(body_model, stature_m):
    """The default: the rest body (NumPy, every vertex) is the stature tall; the pose does
    not change the solved beta, and the same body posed with its legs apart is lower."""
    rng = np.random.default_rng(3)
    conditioner = StatureConditioner(body_model, 20, stature_m, 3.0, range_bodies(body_model))
    other, pose = rng.uniform(-1.5, 1.5, (12, 19)), rng.uniform(-10, 30, (12, 4))
    betas = conditioner.complete(other, pose)
    np.testing.assert_array_equal(betas, conditioner.complete(other, np.zeros_like(pose)))
    free = np.abs(betas[:, 0]) < 3.0
    assert free.sum() >= 6
    rest, _ = rest_shape(body_model, betas[free])
    np.testing.assert_allclose(np.ptp(rest[..., 2], axis=1), stature_m, atol=2e-4)
    apart = np.array([0.0, 0.0, 15.0, 15.0])
    posed = forward(body_model, betas[free], np.tile(apart, (free.sum(), 1)))[..., 2]
    assert np.all(np.ptp(posed, axis=1) < stature_m - 2e-3)


def test_unreachable_height_keeps_the_beta_limit(body_model):
    conditioner = StatureConditioner(body_model, 20, 2.6, 3.0, range_bodies(body_model))
    betas = conditioner.complete(np.zeros((1, 19)), np.zeros((1, 4)))
    assert abs(betas[0, 0]) == pytest.approx(3.0)


def test_stature_scale_restores_the_stature(body_model):
    rest, _ = rest_shape(body_model, np.full((1, 20), 0.3))
    scale = stature_scale(rest[0], 1.8)
    assert np.ptp(rest[0][:, 2] * scale) == pytest.approx(1.8)


def test_scaled_to_stature_scales_each_body_by_its_own_factor(body_model):
    rest, _ = rest_shape(body_model, np.array([[0.3] * 20, [-1.5] * 20]))
    scaled = scaled_to_stature(rest, 1.8)
    assert np.ptp(scaled[:, :, 2], axis=1) == pytest.approx([1.8, 1.8])
    assert scaled[1] == pytest.approx(rest[1] * stature_scale(rest[1], 1.8))
    each = scaled_to_stature(rest, np.array([1.6, 1.9]))  # one stature per body
    assert np.ptp(each[:, :, 2], axis=1) == pytest.approx([1.6, 1.9])


def test_conditioned_search_leaves_the_first_beta_out_of_the_genes():
    conditioned, free = SearchSettings(), SearchSettings(condition_stature=False)
    assert conditioned.lower.shape == (19 + 4,) and free.lower.shape == (20 + 4,)
    np.testing.assert_array_equal(conditioned.upper[-4:], free.upper[-4:])
