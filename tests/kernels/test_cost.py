"""The weighted cost (Eq. 17-18) and the evaluator against the NumPy/OpenCV reference."""

from __future__ import annotations

import numpy as np
import pytest

from bodyfit.fitter.model.body_model import PART_NAMES, POSE_NAMES
from bodyfit.kernels.cost import MATCHING_DIRECTIONS, TERM_NAMES, CostSettings
from bodyfit.kernels.evaluator import PopulationEvaluator, evaluate_population
from bodyfit.kernels.reference import population_cost, view_terms
from bodyfit.kernels.skinning import ModelArrays
from bodyfit.kernels.target import SIDE_VIEW_PARTS, prepare_view_target
from bodyfit.kernels.view_camera import SIDE_VIEW_DEG, orthographic_camera

from kernel_scenes import (DEVICES, FRONT_WIDTH, HEIGHT, PIXELS_PER_METRE, SIDE_WIDTH,
                           front_camera, random_bodies, render_labels, side_camera)

MM_PER_PX = 1000.0 / PIXELS_PER_METRE


@pytest.fixture(scope="module")
def truth():
    return random_bodies(1, seed=11, spread=1.5)


def _views(body_model, betas, pose, device="cpu", side_parts=SIDE_VIEW_PARTS):
    """Front and side views of a person who is the body (betas, pose)."""
    front = render_labels(body_model, betas, pose, front_camera(), FRONT_WIDTH)[0] >= 0
    side = render_labels(body_model, betas, pose, side_camera(), SIDE_WIDTH, side_parts)[0] >= 0
    return [prepare_view_target("front", front, front_camera(), MM_PER_PX, device=device),
            prepare_view_target("side", side, side_camera(), MM_PER_PX, side_parts, device)]


@pytest.fixture(scope="module")
def views(body_model, truth):
    return _views(body_model, *truth)


@pytest.fixture(scope="module")
def candidates(truth):
    betas, pose = random_bodies(4, seed=12, spread=1.5)
    return np.concatenate([truth[0], betas]), np.concatenate([truth[1], pose])


@pytest.mark.parametrize("matching,anchor", [(m, "centroid") for m in MATCHING_DIRECTIONS]
                         + [("person_to_model", "extremes"), ("symmetric", "extremes")])
def test_cost_terms_equal_the_numpy_formula(body_model, model_arrays, views, candidates,
                                            matching, anchor):
    settings = CostSettings(matching=matching, vertical_anchor=anchor)
    costs, part_costs = evaluate_population(model_arrays, views, *candidates, settings)
    expected = np.zeros_like(part_costs, dtype=np.float64)
    for view, camera, width in zip(views, (front_camera(), side_camera()),
                                   (FRONT_WIDTH, SIDE_WIDTH)):
        maps = render_labels(body_model, *candidates, camera, width, view.visible_parts)
        expected += np.stack([view_terms(m, view, settings) for m in maps])
    assert part_costs.shape == (5, len(TERM_NAMES))
    assert np.allclose(costs, part_costs.sum(axis=1), rtol=1e-5)
    assert np.allclose(costs, expected.sum(axis=1), rtol=1e-4, atol=1e-2)
    # parts can differ only where a person point is equally far from two candidate parts
    assert np.allclose(part_costs, expected, rtol=1e-3, atol=0.02 * costs.max())
    assert costs[0] < 1e-3 and (costs[1:] > 100).all()


def test_cost_grows_away_from_the_true_body(model_arrays, views, truth):
    rng = np.random.default_rng(13)
    direction = rng.normal(size=(1, 20)).astype(np.float32)
    steps = np.array([0.0, 0.1, 0.3, 0.9], np.float32)[:, None]
    betas = truth[0] + steps * direction
    costs, _ = evaluate_population(model_arrays, views, betas, np.repeat(truth[1], 4, 0))
    assert costs[0] < 1e-3 and np.all(np.diff(costs) > 0)


def test_evaluator_matches_the_reference_pipeline(body_model, model_arrays, views, candidates):
    betas, pose = candidates[0][1:3], candidates[1][1:3]
    costs, part_costs = evaluate_population(model_arrays, views, betas, pose)
    expected, expected_parts = population_cost(body_model, betas, pose, views, supersample=65)
    assert np.allclose(costs, expected, rtol=0.02)
    assert np.abs(part_costs - expected_parts).max() < 0.05 * costs.min()


def test_side_view_leaves_out_arms_held_against_the_body(body_model, model_arrays, truth):
    """A person photographed from the side with the hands against the body shows no arm
    silhouette. Rendering the model's A-pose arms, which hang forward, puts an artefact
    into the side cost of the true body (it shifts the alignment, so the torso and
    stature terms pay too); leaving the arms out of the side view does not."""
    views = _views(body_model, *truth)
    with_arms = [views[0], prepare_view_target("side", views[1].silhouette, side_camera(),
                                               MM_PER_PX)]
    for matching in MATCHING_DIRECTIONS:
        settings = CostSettings(matching=matching)
        default = evaluate_population(model_arrays, views, *truth, settings).costs[0]
        artefact = evaluate_population(model_arrays, with_arms, *truth, settings).part_costs[0]
        assert default < 1e-3
        assert artefact.sum() > 300.0 and artefact[TERM_NAMES.index("chest")] > 20.0


#: Both shoulders at the arms-down angle (about -41 degrees hangs the mean body's arms down).
ARMS_DOWN = {POSE_NAMES[0]: -40.0, POSE_NAMES[1]: -40.0}


#: Side canvas width for the arms down: the forearms hang forward beyond SIDE_WIDTH.
ARMS_DOWN_WIDTH = 320


def _arms_down(pose):
    pose = np.array(pose, copy=True)
    pose[:, :2] = -40.0
    return pose


def test_view_with_fixed_shoulders_skins_like_the_numpy_forward_in_that_pose(
        body_model, model_arrays, views, truth, candidates):
    """A side photo with the arms hanging down, every part visible: the side view renders
    each candidate with its shoulders at the fixed angle (its own pose in the front view),
    equal to the NumPy forward of that pose drawn by the same rasteriser."""
    camera = orthographic_camera(SIDE_VIEW_DEG, PIXELS_PER_METRE,
                                 (ARMS_DOWN_WIDTH / 2, HEIGHT / 2))
    person = render_labels(body_model, truth[0], _arms_down(truth[1]), camera,
                           ARMS_DOWN_WIDTH)[0] >= 0
    assert not (person[:, [0, -1]].any() or person[[0, -1]].any())  # not cut by the canvas
    side = prepare_view_target("side", person, camera, MM_PER_PX, PART_NAMES,
                               fixed_pose_deg=ARMS_DOWN)
    both = [views[0], side]
    settings = CostSettings()
    costs = evaluate_population(model_arrays, both, *candidates, settings).costs
    betas, pose = candidates
    expected = np.stack([view_terms(m, views[0], settings) for m in render_labels(
        body_model, betas, pose, front_camera(), FRONT_WIDTH, views[0].visible_parts)])
    expected += np.stack([view_terms(m, side, settings) for m in render_labels(
        body_model, betas, _arms_down(pose), camera, ARMS_DOWN_WIDTH)])
    assert np.allclose(costs, expected.sum(axis=1), rtol=1e-4, atol=1e-2)
    assert costs[0] < 1e-3 and (costs[1:] > 100).all()
    # without the fixed angles the true body's A-pose arms miss the person's
    own_pose = prepare_view_target("side", person, camera, MM_PER_PX, PART_NAMES)
    assert evaluate_population(model_arrays, [views[0], own_pose], *truth).costs[0] > 100
    # the side view ignores the candidates' shoulder angles
    turned = pose.copy()
    turned[:, :2] += 15.0
    assert np.array_equal(evaluate_population(model_arrays, [side], betas, pose).costs,
                          evaluate_population(model_arrays, [side], betas, turned).costs)


def test_chunks_do_not_change_the_costs(model_arrays, views, candidates):
    whole = PopulationEvaluator(model_arrays, views, chunk_size=8).evaluate(*candidates)
    chunked = PopulationEvaluator(model_arrays, views, chunk_size=2).evaluate(*candidates)
    assert np.array_equal(whole.costs, chunked.costs)
    assert np.array_equal(whole.part_costs, chunked.part_costs)


@pytest.mark.parametrize("workers", [2, 3])
def test_threads_do_not_change_the_costs(model_arrays, views, candidates, workers):
    """Slices of the population on several CPU threads (3 workers: uneven slices) give
    the costs of one thread to the last bit, and the buffers are reused for a second,
    smaller population."""
    one = PopulationEvaluator(model_arrays, views, workers=1).evaluate(*candidates)
    threaded = PopulationEvaluator(model_arrays, views, chunk_size=2, workers=workers)
    assert threaded.workers == workers
    for count in (len(one.costs), 3):
        result = threaded.evaluate(*(c[:count] for c in candidates))
        assert np.array_equal(result.costs, one.costs[:count])
        assert np.array_equal(result.part_costs, one.part_costs[:count])


def test_workers_must_be_positive(model_arrays, views):
    with pytest.raises(ValueError, match="workers"):
        PopulationEvaluator(model_arrays, views, workers=0)


def test_profile_times_every_stage(model_arrays, views, candidates):
    evaluator = PopulationEvaluator(model_arrays, views, profile=True)
    evaluator.evaluate(*candidates)
    assert all(seconds > 0 for seconds in evaluator.stage_seconds.values())


def test_empty_silhouette_costs_infinity(model_arrays, views, truth):
    off_canvas = orthographic_camera((90.0, 0.0, 0.0), PIXELS_PER_METRE, (-5000.0, -5000.0))
    view = prepare_view_target("front", views[0].silhouette, off_canvas, MM_PER_PX)
    costs, part_costs = evaluate_population(model_arrays, [view], *truth)
    assert np.isinf(costs).all() and np.isinf(part_costs).all()


@pytest.mark.parametrize("device", DEVICES)
def test_costs_are_the_same_on_every_device(body_model, model_arrays, views, truth,
                                            candidates, device):
    model = ModelArrays.from_body_model(body_model, num_components=20, device=device)
    costs = evaluate_population(model, _views(body_model, *truth, device=device), *candidates)
    on_cpu = evaluate_population(model_arrays, views, *candidates)
    assert np.allclose(costs.costs, on_cpu.costs, rtol=1e-5)


@pytest.mark.parametrize("kwargs, message", [
    (dict(matching="both"), "matching must be one of"),
    (dict(part_weights=(1.0,) * 8), "part_weights needs 10 values"),
    (dict(top_weight=-1.0), ">= 0"),
])
def test_settings_reject_bad_values(kwargs, message):
    with pytest.raises(ValueError, match=message):
        CostSettings(**kwargs)


@pytest.mark.parametrize("kwargs, message", [
    (dict(name="back"), "name must be one of"),
    (dict(mask=np.zeros((4, 4), bool)), "mask is empty"),
    (dict(mask=np.ones((2, 4, 4), bool)), r"mask must be a \(H, W\) bool array"),
    (dict(visible_parts=("tail",)), "visible_parts must be a non-empty subset"),
    (dict(millimetres_per_pixel=0.0), "millimetres_per_pixel must be > 0"),
    (dict(fixed_pose_deg={"knee": 3.0}), "fixed_pose_deg names must be in"),
    (dict(fixed_pose_deg={POSE_NAMES[0]: float("nan")}), "must be a number of degrees"),
    (dict(fixed_pose_deg={POSE_NAMES[0]: "down"}), "must be a number of degrees"),
])
def test_view_target_rejects_bad_input(kwargs, message):
    args = dict(name="front", mask=np.ones((4, 4), bool), camera=front_camera(),
                millimetres_per_pixel=1.0, visible_parts=PART_NAMES)
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        prepare_view_target(**args)


def test_evaluator_rejects_bad_views_and_populations(model_arrays, views):
    with pytest.raises(ValueError, match="distinct views"):
        PopulationEvaluator(model_arrays, [views[0], views[0]])
    with pytest.raises(ValueError, match=r"pose_deg must have shape \(P=2, 4\)"):
        PopulationEvaluator(model_arrays, views).evaluate(np.zeros((2, 20)), np.zeros((3, 4)))


def test_posed_bodies_cost_what_their_parameters_cost(body_model, model_arrays, views,
                                                      candidates):
    """evaluate_posed of the bodies the NumPy forward poses from the candidates (each as
    its view renders it) gives evaluate's costs; a view missing or a wrong shape is
    refused."""
    from bodyfit.kernels.body_forward import forward

    betas, pose = candidates
    evaluator = PopulationEvaluator(model_arrays, views)
    by_parameters = evaluator.evaluate(betas, pose)
    k = model_arrays.num_components
    posed = {view.name: forward(body_model, betas[:, :k], view.view_pose(pose)) for view in views}
    by_bodies = evaluator.evaluate_posed(posed)
    np.testing.assert_allclose(by_bodies.costs, by_parameters.costs, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(by_bodies.part_costs, by_parameters.part_costs, rtol=1e-5,
                               atol=1e-3)
    with pytest.raises(ValueError, match="views"):
        evaluator.evaluate_posed({"front": posed["front"]})
    with pytest.raises(ValueError, match="must be"):
        evaluator.evaluate_posed({name: bodies[:, :10] for name, bodies in posed.items()})
