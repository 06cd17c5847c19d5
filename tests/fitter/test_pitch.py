"""The cameras' pitch (fitter/fit/pitch.py, fitter/fit/pinhole_canvas.py): the search over
known costs, and a pitched photo's camera placed."""

import numpy as np
import pytest

from bodyfit.fitter.demo.studio_photos import pinhole_photo
from bodyfit.fitter.fit.canvas import VIEW_PARTS, extreme_bodies
from bodyfit.fitter.fit.pinhole_canvas import (Placement, pinhole_view, placed_anew,
                                               solve_placement, view_pitch_deg)
from bodyfit.fitter.fit.pitch import PITCH_PRIOR, PITCH_STEP_DEG, searched_pitches
from bodyfit.fitter.model.body_model import forward
from bodyfit.kernels.target import visible_vertices
from bodyfit.kernels.view_camera import camera_matrices
from tests.fitter.test_pinhole import K_TRUE, SIZE_PX, person_mask, project


def test_search_takes_each_views_best_pitch_and_solves_them_together():
    """Each view's cost a parabola in its own pitch (front lowest at +2.5, side at -3), no
    prior: each view takes its nearest step (+4, -4), the two are solved together (the
    fifth solve), and that answer is the lowest; every solve starts from the level one."""
    calls = []

    def solve_at(pitches, start):
        calls.append((dict(pitches), start))
        cost = 10.0 + (pitches["front"] - 2.5) ** 2 + 2.0 * (pitches["side"] + 3.0) ** 2
        return cost, f"answer at {pitches['front']:+.0f}, {pitches['side']:+.0f}"

    answer, pitches = searched_pitches(solve_at, (10.0 + 6.25 + 18.0, "level"), prior=0.0)
    assert pitches == {"front": PITCH_STEP_DEG, "side": -PITCH_STEP_DEG}
    assert answer == "answer at +4, -4"
    assert [call for call, _ in calls] == [
        {"front": -4.0, "side": 0.0}, {"front": 4.0, "side": 0.0},
        {"front": 0.0, "side": -4.0}, {"front": 0.0, "side": 4.0},
        {"front": 4.0, "side": -4.0}]
    assert {start for _, start in calls} == {"level"}


@pytest.mark.parametrize("gain, pitched", [(0.9 * PITCH_PRIOR * 16, False),
                                           (1.1 * PITCH_PRIOR * 16, True)])
def test_a_pitch_must_win_its_prior(gain, pitched):
    """The side camera pitched 4 degrees down lowers the cost by ``gain`` and nothing else
    does: it is taken where the gain beats the prior's 16 PITCH_PRIOR, and without a
    second pitched view there is no fifth solve."""
    calls = []

    def solve_at(pitches, start):
        calls.append(pitches)
        won = pitches == {"front": 0.0, "side": PITCH_STEP_DEG}
        return 30.0 - gain if won else 31.0, dict(pitches)

    answer, pitches = searched_pitches(solve_at, (30.0, "level"))
    assert len(calls) == 4
    expected = {"front": 0.0, "side": PITCH_STEP_DEG if pitched else 0.0}
    assert pitches == expected
    assert answer == (expected if pitched else "level")


@pytest.mark.parametrize("pitch_deg", [-4.0, 5.0])
def test_a_pitched_photo_placed_with_its_pitch(body_model, pitch_deg):
    """The mean body photographed by a camera pitched ``pitch_deg``: placed with that pitch,
    the camera stands where it stood (distance within 1 %, height within 2 cm) and projects
    the body where the photo has it; placed level, its height is off by about the distance
    times the pitch's tangent, down for a camera looking down."""
    body = forward(body_model, np.zeros((1, 20)), np.zeros((1, 4)))[0].astype(np.float64)
    truth = Placement(3.0, 1.2, 0.0, -body[:, 2].min(), pitch_deg)
    for view, parts in VIEW_PARTS.items():
        mask = person_mask(pinhole_photo(body, body_model, view, parts, K_TRUE, SIZE_PX,
                                         truth.distance_m, truth.camera_height_m,
                                         (pitch_deg, 0.0)))
        shown = visible_vertices(body_model.vertex_parts, parts)
        placed = solve_placement(view, mask, K_TRUE, body[shown], pitch_deg)
        assert placed.pitch_deg == pitch_deg
        assert placed.distance_m == pytest.approx(truth.distance_m, rel=0.01), view
        assert placed.camera_height_m == pytest.approx(truth.camera_height_m, abs=0.02), view
        points = body[::97]
        assert np.abs(project(K_TRUE, *placed.extrinsics(view), points)
                      - project(K_TRUE, *truth.extrinsics(view), points)).max() < 2.0, view
        level = solve_placement(view, mask, K_TRUE, body[shown])
        # looking down, the camera sees the person higher up the photo, as a lower one would
        shift = -truth.distance_m * np.tan(np.deg2rad(pitch_deg))
        assert level.camera_height_m - truth.camera_height_m == pytest.approx(shift, abs=0.05)


def test_a_view_placed_anew_keeps_or_takes_a_pitch(body_model):
    body = forward(body_model, np.zeros((1, 20)), np.zeros((1, 4)))[0].astype(np.float64)
    parts = VIEW_PARTS["front"]
    mask = person_mask(pinhole_photo(body, body_model, "front", parts, K_TRUE, SIZE_PX,
                                     3.0, 1.2, (3.0, 0.0)))
    extent = extreme_bodies(body_model, 20, [-5.0] * 4, [30.0] * 4).reshape(-1, 3)
    view = pinhole_view("front", mask, K_TRUE, float(np.ptp(body[:, 2])), extent,
                        body.astype(np.float32), body_model.vertex_parts)
    shown = body[visible_vertices(body_model.vertex_parts, parts)]
    assert view_pitch_deg(view) == pytest.approx(0.0, abs=1e-9)
    pitched = placed_anew(view, mask, K_TRUE, shown, 3.0)
    assert view_pitch_deg(pitched) == pytest.approx(3.0)
    kept = placed_anew(pitched, mask, K_TRUE, shown)
    assert view_pitch_deg(kept) == pytest.approx(3.0)
    np.testing.assert_allclose(camera_matrices(kept.camera)[2],
                               camera_matrices(pitched.camera)[2], atol=1e-9)
