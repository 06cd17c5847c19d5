"""The learned start (fitter/fit/learned_start.py) and its training
(fitter/training/start_training.py): the width profile of analytic silhouettes, the
ridge on an exact linear map, the weights' round trip and the one-line errors of
missing, corrupt and foreign weights, and the shipped weights' prediction of bodies
photographed by the demo's renderer (not the training's)."""

import dataclasses

import numpy as np
import pytest

from bodyfit.common.errors import UserError
from bodyfit.fitter.demo.studio_photos import pinhole_silhouette
from bodyfit.fitter.fit.canvas import extreme_bodies
from bodyfit.fitter.fit.learned_start import (BANDS, LearnedStart, model_fingerprint,
                                              shipped_start_path, silhouette_profile)
from bodyfit.fitter.fit.local_solver import SolverSettings
from bodyfit.fitter.fit.person_fit import FitSettings
from bodyfit.fitter.fit.search import SearchSettings
from bodyfit.fitter.fit.side_arms import side_photo_pose
from bodyfit.fitter.fit.stature import StatureConditioner
from bodyfit.fitter.measure.measurements import IMPORTANT
from bodyfit.fitter.model.body_model import PART_NAMES, forward, rest_shape
from bodyfit.fitter.training.start_training import (TrainingSettings, _ridge,
                                                    photographed_masks, training_bodies)

K_PHONE = np.array([[700.0, 0.0, 359.5], [0.0, 700.0, 479.5], [0.0, 0.0, 1.0]])
SIZE_PX = (720, 960)


def test_profile_of_a_rectangle_is_its_width_and_half_widths():
    mask = np.zeros((300, 200), bool)
    mask[20:260, 50:110] = True  # 240 rows, 60 columns
    profile = silhouette_profile(mask).reshape(3, BANDS)
    np.testing.assert_allclose(profile[0], 60 / 240)
    np.testing.assert_allclose(profile[1:], 29.5 / 240)  # centre column 79.5


def test_profile_ignores_where_and_how_large_the_person_is():
    mask = np.zeros((400, 300), bool)
    mask[10:106, 40:60] = True  # a head and a body, 192 rows in all
    mask[106:202, 20:92] = True
    moved = np.zeros((900, 700), bool)  # twice as large, elsewhere in a larger photo
    moved[300:684, 100:700] = np.kron(mask[10:202], np.ones((2, 2), bool))
    np.testing.assert_allclose(silhouette_profile(moved), silhouette_profile(mask), atol=1e-2)
    with pytest.raises(ValueError):
        silhouette_profile(np.zeros((5, 5), bool))


def test_ridge_recovers_an_exact_linear_map():
    rng = np.random.default_rng(0)
    z = rng.normal(size=(200, 6))
    truth = rng.normal(size=(7, 3))
    targets = np.c_[z, np.ones(200)] @ truth
    np.testing.assert_allclose(_ridge(z, targets, 0.0), truth, atol=1e-9)
    shrunk = _ridge(z, targets, 10.0)
    assert np.abs(shrunk[:6]).sum() < np.abs(truth[:6]).sum()


def test_training_photos_keep_the_body_in_the_frame(body_model):
    settings = TrainingSettings(bodies=100)
    rng = np.random.default_rng(3)
    bodies = training_bodies(body_model, settings, rng)
    assert bodies.betas.shape == (100, 40) and np.abs(bodies.betas).max() <= 3.0 + 1e-9
    assert set(bodies.sex) == {"female", "male"} and 0 < bodies.told.mean() < 1
    posed = forward(body_model, bodies.betas[:1], bodies.front_deg[:1])[0]
    masks = photographed_masks(body_model, {"front": posed, "side": posed}, settings, rng)
    for mask in masks.values():
        assert mask.shape == (960, 720) and mask.sum() > 10_000
        assert not (mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())


def test_weights_round_trip_and_one_line_errors(body_model, tmp_path):
    features = 6 * BANDS + 2
    rng = np.random.default_rng(1)
    start = LearnedStart(rng.normal(size=features), rng.uniform(1, 2, features),
                         rng.normal(size=(features + 1, 43)), 40,
                         model_fingerprint(body_model, 40), {"note": "test"})
    path = tmp_path / "start.npz"
    start.save(path)
    loaded = LearnedStart.load(path)
    inputs = rng.normal(size=(3, features))
    for got, want in zip(loaded.predict(inputs), start.predict(inputs)):
        np.testing.assert_array_equal(got, want)
    loaded.check_model(body_model, path)
    with pytest.raises(UserError, match="no learned start"):
        LearnedStart.load(tmp_path / "missing.npz")
    (tmp_path / "corrupt.npz").write_bytes(path.read_bytes()[:300])
    with pytest.raises(UserError, match="corrupt") as corrupt:
        LearnedStart.load(tmp_path / "corrupt.npz")
    assert "\n" not in str(corrupt.value)
    (tmp_path / "text.npz").write_text("not weights")
    with pytest.raises(UserError, match="corrupt"):
        LearnedStart.load(tmp_path / "text.npz")
    foreign = dataclasses.replace(start, fingerprint="0" * 16)
    with pytest.raises(UserError, match="another body model"):
        foreign.check_model(body_model, path)


def test_learned_start_settings_that_cannot_go_together_are_refused(body_model):
    learned = SolverSettings(iterations=0, start="learned")
    FitSettings(solver=learned).validate(body_model.num_components)  # the start alone
    with pytest.raises(UserError, match="--searches 0"):
        FitSettings(search=SearchSettings(), solver=learned).validate(60)
    with pytest.raises(UserError, match="--start"):
        FitSettings(solver=SolverSettings(iterations=5, start="median")).validate(60)


# Bodies of the model's space (not drawn by the training), each photographed front and side
# by the demo's renderer through a horizontal pinhole at 2.8 m, 1.3 m high.
BODIES = [(np.array([1.2, 0.7, -0.8, 0.4, 0.5, -0.6, 0.3, 0.2]), [5.0, 7.0, 3.0, 4.0], "female"),
          (np.array([-0.9, -1.1, 0.6, 0.8, -0.4, 0.2, -0.5, 0.3]), [9.0, 8.0, 2.0, 2.0], "male"),
          (np.array([0.3, 1.5, 1.0, -0.7, 0.0, 0.6, 0.4, -0.6]), [2.0, 4.0, 6.0, 5.0], "unknown")]


@pytest.mark.parametrize("betas, pose, sex", BODIES)
def test_shipped_start_predicts_a_photographed_body(body_model, measurer, betas, pose, sex):
    learned = LearnedStart.load(shipped_start_path())
    learned.check_model(body_model, shipped_start_path())
    k = learned.components
    betas = np.r_[betas, np.zeros(k - len(betas))][None]
    pose = np.array([pose])
    posed = {"front": forward(body_model, betas, pose)[0],
             "side": forward(body_model, betas,
                             side_photo_pose(body_model, betas[0], pose[0])[None])[0]}
    masks = {view: pinhole_silhouette(vertices, body_model, view, PART_NAMES, K_PHONE, SIZE_PX,
                                      2.8, 1.3)
             for view, vertices in posed.items()}
    rest = rest_shape(body_model, betas)[0][0]
    stature = float(np.ptp(rest[:, 2]))
    others, angles = learned.start(masks, stature, sex)
    search = SearchSettings()
    conditioner = StatureConditioner(body_model, k, stature, 3.0, extreme_bodies(
        body_model, k, search.pose_lower_deg, search.pose_upper_deg, 3.0))
    predicted = rest_shape(body_model, conditioner.complete(others[None], angles[None]))[0][0]
    got, want = measurer.measure(predicted), measurer.measure(rest)
    errors = np.array([got[key] - want[key] for key in IMPORTANT])
    # the shipped weights' held-out error (their metadata): the 7 within 7.0 mm on average,
    # the angles 0.6 degrees rms; these three bodies came within 5.6, 4.9 and 2.7 mm and
    # 0.9 degrees (the mean body of their stature misses them by 21.7, 15.5 and 34.6 mm)
    assert np.abs(errors).mean() < 9.0
    np.testing.assert_allclose(angles, pose[0], atol=2.0)
