"""The accuracy benchmark's parts: its bodies, photos, statistics and tables against
references (its commands: test_accuracy_commands.py)."""

import dataclasses

import cv2
import numpy as np
import pytest
from scipy import stats

from bench.accuracy.bodies import draw_bodies, flexion_rotations, pose_bodies
from bench.accuracy.photos import PhotoEffects, record
from bench.accuracy.report import ISO_ALLOWANCE_MM, iso_verdicts
from bench.accuracy.scores import error_stats
from bodyfit.fitter.fit.side_arms import side_photo_pose
from bodyfit.fitter.model.body_model import forward, project_shape, rest_shape


def test_in_space_bodies_alternate_sexes_and_pose_like_the_model(body_model):
    bodies = draw_bodies(body_model, "in-space", 6, seed=3)
    assert list(bodies.sex) == ["female", "male"] * 3
    again = draw_bodies(body_model, "in-space", 6, seed=3)
    np.testing.assert_array_equal(bodies.vertices, again.vertices)
    # in the space: projecting onto 20 components gives the body back
    betas = project_shape(body_model, bodies.vertices, bodies.joints, 20)
    np.testing.assert_allclose(rest_shape(body_model, betas)[0], bodies.vertices, atol=2e-5)
    # no flexion: the model's own forward, front and side (arms down)
    front, side = pose_bodies(body_model, bodies, 2)
    np.testing.assert_allclose(front, forward(body_model, betas[2:3], bodies.abduction_deg[2:3])[0],
                               atol=2e-5)
    side_pose = side_photo_pose(body_model, betas[2], bodies.abduction_deg[2])
    np.testing.assert_allclose(side, forward(body_model, betas[2:3], side_pose[None])[0],
                               atol=2e-5)
    # limbs bent: the front photo only
    bent = dataclasses.replace(bodies, flexion_deg=np.full((6, 4), 4.0))
    bent_front, bent_side = pose_bodies(body_model, bent, 2)
    np.testing.assert_array_equal(bent_side, side)
    assert np.abs(bent_front - front).max() > 0.02  # the hands move by centimetres


def test_out_of_space_bodies_are_human_and_outside_the_space(body_model, measurer):
    bodies = draw_bodies(body_model, "out-of-space", 4, seed=1, pool_per_sex=60)
    betas = project_shape(body_model, bodies.vertices, bodies.joints, 20)
    residual = np.abs(rest_shape(body_model, betas)[0] - bodies.vertices).mean(axis=(1, 2))
    assert np.all(residual > 2e-4)  # at least 0.2 mm per vertex outside the space
    for vertices in bodies.vertices:
        assert 1400 < measurer.measure(vertices)["O"] < 2100
    assert np.all(np.abs(bodies.flexion_deg) <= 4.0) and np.any(bodies.flexion_deg != 0)


def test_flexion_swings_a_hanging_limb_forward():
    rot = flexion_rotations(np.array([[10.0, 0.0, 0.0, 0.0]]))[0, 0]
    np.testing.assert_allclose(rot @ [0.0, 0.0, -1.0],
                               [0.0, -np.sin(np.radians(10)), -np.cos(np.radians(10))])
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)


def test_recorded_photo_is_a_jpeg_with_the_light_and_noise_asked_for():
    image = np.full((400, 300, 3), 128, np.uint8)
    effects = PhotoEffects(light_slope=0.15, vignette=0.0, noise_dn=3.0, jpeg_quality=95)
    decoded = cv2.imdecode(np.frombuffer(record(image, effects, np.random.default_rng(0)),
                                         np.uint8), cv2.IMREAD_COLOR)
    assert decoded.shape == image.shape
    grey = decoded.astype(float).mean(axis=2)
    # a linear light slope of at most 15 % each way: the corners differ, within the bound
    corners = [grey[:20, :20].mean(), grey[-20:, -20:].mean()]
    assert 128 * 0.7 - 3 < min(corners) and max(corners) < 128 * 1.3 + 3
    flat = cv2.imdecode(np.frombuffer(record(image, PhotoEffects(0.0, 0.0, 3.0, 100),
                                             np.random.default_rng(1)), np.uint8),
                        cv2.IMREAD_COLOR)
    assert 2.0 < flat.astype(float).std() < 4.0  # the sensor noise, through the JPEG


def test_error_stats_agree_with_scipy():
    rng = np.random.default_rng(0)
    errors = rng.normal(1.0, 3.0, (50, 3))
    spreads = np.full((50, 3), 3.0)
    s = error_stats(errors, spreads)
    lo, hi = stats.t.interval(0.95, 49, loc=errors[:, 0].mean(), scale=stats.sem(errors[:, 0]))
    assert s.bias[0] == pytest.approx((lo + hi) / 2)
    assert s.bias_ci[0] == pytest.approx((hi - lo) / 2)
    lo, hi = stats.t.interval(0.95, 49, loc=np.abs(errors[:, 1]).mean(),
                              scale=stats.sem(np.abs(errors[:, 1])))
    assert s.mae_ci[1] == pytest.approx((hi - lo) / 2)
    assert s.covered[2] == pytest.approx(np.mean(np.abs(errors[:, 2]) <= 3.0))
    with pytest.raises(ValueError, match="at least 2"):
        error_stats(errors[:1])


def test_iso_verdict_is_the_bias_interval_inside_the_allowance():
    errors = np.zeros((40, 16))
    errors[:, 3] = 8.0 + np.tile([-0.1, 0.1], 20)  # chest: +8 mm, tight: inside 9 mm
    errors[:, 0] = 4.5  # head: +4.5 mm, outside 4 mm
    verdicts = iso_verdicts(error_stats(errors))
    assert ISO_ALLOWANCE_MM["D"] == 9 and verdicts["D"] == "pass"
    assert ISO_ALLOWANCE_MM["A"] == 4 and verdicts["A"] == "fail"
    assert verdicts["B"] == "pass"


def test_failures_are_counted_by_reason():
    from bench.accuracy.report import failure_lines
    from bench.accuracy.scores import RunScores

    scores = RunScores([], np.zeros((0, 16)), np.zeros((0, 16)), np.zeros(0),
                       [("s1", "no person found in /x/s1/front.jpg"),
                        ("s2", "no person found in /x/s2/front.jpg"),
                        ("s3", "the person is cut off by the frame")], np.zeros(0, bool),
                       np.zeros(0))
    assert failure_lines(scores) == ["- 2 x no person found in /x/<id>/front.jpg",
                                     "- 1 x the person is cut off by the frame"]


def _scores(subjects: list[str], errors: np.ndarray):
    """RunScores of ``subjects`` with these (N, 16) errors, nothing else."""
    from bench.accuracy.scores import RunScores

    n = len(subjects)
    return RunScores(subjects, errors, np.zeros((n, 16)), np.zeros(n), [], np.zeros(n, bool),
                     np.zeros(n))


def test_paired_difference_is_scipys_paired_t_interval_over_common_subjects():
    from bench.accuracy.report import important_table, paired_difference
    from bench.accuracy.scores import IMPORTANT_COLUMNS

    rng = np.random.default_rng(1)
    base_errors, run_errors = rng.normal(0, 5, (30, 16)), rng.normal(1, 5, (30, 16))
    ids = [f"s{i:04d}" for i in range(30)]

    # the run fitted subjects 5..29 only, in another order: pairing must follow the ids
    order = rng.permutation(np.arange(5, 30))
    base = _scores(ids, base_errors)
    run = _scores([ids[i] for i in order], run_errors[order])
    diff, ci, count = paired_difference(run, base)
    a = np.abs(run_errors[5:, IMPORTANT_COLUMNS]).mean(axis=1)
    b = np.abs(base_errors[5:, IMPORTANT_COLUMNS]).mean(axis=1)
    interval = stats.ttest_rel(a, b).confidence_interval(0.95)
    assert count == 25
    assert diff == pytest.approx((interval.low + interval.high) / 2)
    assert ci == pytest.approx((interval.high - interval.low) / 2)
    table = important_table({"base": base, "run": run}, {"run": "base"})
    assert table[0].endswith("paired difference (95 % CI) |")
    assert table[3].endswith(f"{diff:+.2f} (±{ci:.2f}) from base |")
    assert table[2].endswith("| |")  # the baseline's own row has no difference


def test_paired_measurement_table_is_scipys_paired_t_per_measurement():
    from bench.accuracy.report import paired_difference, paired_measurement_table

    rng = np.random.default_rng(2)
    base_errors, run_errors = rng.normal(0, 5, (12, 16)), rng.normal(0, 3, (12, 16))
    ids = [f"s{i:04d}" for i in range(12)]

    order = rng.permutation(np.arange(2, 12))  # the run holds 10 of the 12, shuffled
    base, run = _scores(ids, base_errors), _scores([ids[i] for i in order], run_errors[order])
    table = paired_measurement_table(run, base)
    assert table[0].endswith("closer for (of 10) |") and len(table) == 2 + 16 + 1
    for j, line in enumerate(table[2:18]):
        a, b = np.abs(run_errors[2:, j]), np.abs(base_errors[2:, j])
        interval = stats.ttest_rel(a, b).confidence_interval(0.95)
        cells = [cell.strip() for cell in line.split("|")[1:-1]]
        assert cells[1:3] == [f"{b.mean():.2f}", f"{a.mean():.2f}"]
        assert cells[3] == (f"{(interval.low + interval.high) / 2:+.2f} "
                            f"(±{(interval.high - interval.low) / 2:.2f})")
        assert cells[4] == str(int((a < b).sum()))
    diff, ci, _ = paired_difference(run, base)
    assert table[-1].split("|")[4].strip() == f"{diff:+.2f} (±{ci:.2f})"
