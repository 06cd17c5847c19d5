"""Alignment of candidates to the person: recovers a known in-image rotation and shift."""

from __future__ import annotations

import numpy as np
import pytest

from bodyfit.kernels.alignment import align_label_maps, rigid_transform, silhouette_moments
from bodyfit.kernels.view_camera import orthographic_camera
from bodyfit.kernels.target import boundary_mask

from kernel_scenes import FRONT_WIDTH, HEIGHT, PIXELS_PER_METRE, random_bodies, render_labels

CENTRE = np.array([FRONT_WIDTH / 2, HEIGHT / 2])
SCALE = 0.85 * PIXELS_PER_METRE  # margin for the moved silhouettes to stay in the canvas


def _moved_camera(roll_deg: float, shift_px):
    """The front camera rolled about its axis by roll_deg and shifted by shift_px."""
    return orthographic_camera((90.0, 0.0, roll_deg), SCALE, CENTRE + shift_px)


@pytest.fixture(scope="module")
def person_and_moved(body_model):
    betas, pose = random_bodies(1, seed=7)
    person = render_labels(body_model, betas, pose, _moved_camera(0.0, (0, 0)), FRONT_WIDTH)[0]
    moved = render_labels(body_model, np.repeat(betas, 2, 0), np.repeat(pose, 2, 0),
                         _moved_camera(4.0, (11.3, -6.7)), FRONT_WIDTH)
    moved[1] = render_labels(body_model, betas, pose, _moved_camera(0.0, (-8.4, 5.2)),
                            FRONT_WIDTH)[0]
    return person, moved


def _true_map(points, roll_deg, shift):
    """Where the moved camera sees what the front camera sees at ``points`` (column, row)."""
    t = np.deg2rad(roll_deg)
    rot = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    return (points - CENTRE) @ rot.T + CENTRE + shift


def test_alignment_recovers_a_known_rotation_and_shift(person_and_moved):
    person, moved = person_and_moved
    target = silhouette_moments(person >= 0)
    transforms, extremes, areas = align_label_maps(moved, target)
    rows, cols = np.nonzero(boundary_mask(person >= 0))
    points = np.stack([cols, rows], axis=1).astype(float)
    for transform, roll, shift in zip(transforms, (4.0, 0.0), ((11.3, -6.7), (-8.4, 5.2))):
        estimated = points @ transform[:2, :2].T + transform[:2, 2]
        assert np.abs(estimated - _true_map(points, roll, shift)).max() < 0.6
        assert np.rad2deg(np.arctan2(transform[1, 0], transform[0, 0])) == pytest.approx(roll,
                                                                                          abs=0.1)
    for labels, ext, area in zip(moved, extremes, areas):
        moments = silhouette_moments(labels >= 0)
        assert area == moments.area_px
        assert np.allclose(ext, [moments.top, moments.bottom], atol=1e-3)


@pytest.mark.parametrize("anchor", ["centroid", "extremes"])
def test_kernel_alignment_equals_numpy_reference(person_and_moved, anchor):
    person, moved = person_and_moved
    target = silhouette_moments(person >= 0)
    for rotate in (True, False):
        transforms = align_label_maps(moved, target, align_rotation=rotate,
                                      vertical_anchor=anchor)[0]
        for labels, transform in zip(moved, transforms):
            expected = rigid_transform(silhouette_moments(labels >= 0), target, rotate, anchor)
            assert np.allclose(transform, expected, atol=2e-3)
    translation_only = align_label_maps(moved, target, align_rotation=False)[0]
    assert np.allclose(translation_only[:, :2, :2], np.eye(2))


def test_empty_silhouette_has_zero_area(person_and_moved):
    person, _ = person_and_moved
    _, _, areas = align_label_maps(np.full((1, 8, 8), -1, np.int8),
                                   silhouette_moments(person >= 0))
    assert areas[0] == 0


def test_extremes_anchor_puts_the_middle_rows_together(person_and_moved):
    """With the vertical anchor on the extremes, the middle of the person's top and bottom
    rows lands on the middle of the candidate's (at the person's centroid column), while the
    horizontal shift stays the centroid's."""
    person, moved = person_and_moved
    target = silhouette_moments(person >= 0)
    by_centroid = align_label_maps(moved, target, align_rotation=False)[0]
    by_extremes = align_label_maps(moved, target, align_rotation=False,
                                   vertical_anchor="extremes")[0]
    for labels, centroid, extremes in zip(moved, by_centroid, by_extremes):
        candidate = silhouette_moments(labels >= 0)
        middle = np.array([target.centroid[0], (target.top[1] + target.bottom[1]) / 2, 1.0])
        assert (extremes @ middle)[1] == pytest.approx(
            (candidate.top[1] + candidate.bottom[1]) / 2, abs=1e-3)
        assert extremes[0, 2] == pytest.approx(centroid[0, 2], abs=1e-4)


def test_unknown_vertical_anchor_is_an_error(person_and_moved):
    person, moved = person_and_moved
    with pytest.raises(ValueError, match="vertical_anchor must be one of"):
        align_label_maps(moved, silhouette_moments(person >= 0), vertical_anchor="extreme")
