"""Boundary row scan and nearest-boundary queries against SciPy's exact distance transform."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import scipy.ndimage as ndi
from scipy.spatial import cKDTree

from bodyfit.kernels.body_layout import PART_NAMES
from bodyfit.kernels.boundary import nearest_boundary, scan_label_maps, unpack_runs
from bodyfit.kernels.target import boundary_distance, boundary_mask, prepare_view_target

from kernel_scenes import FRONT_WIDTH, front_camera, random_bodies, render_labels


def blob_maps(num: int, height: int = 96, width: int = 128, seed: int = 0) -> np.ndarray:
    """(num, H, W) int8 label maps: overlapping ellipses of several parts, some cut by the
    image border, a one-pixel line and an isolated pixel."""
    rng = np.random.default_rng(seed)
    maps = np.full((num, height, width), -1, np.int8)
    for m in maps:
        for _ in range(6):
            centre = (int(rng.integers(-10, width + 10)), int(rng.integers(-10, height + 10)))
            axes = (int(rng.integers(3, 40)), int(rng.integers(3, 30)))
            cv2.ellipse(m, centre, axes, float(rng.uniform(0, 180)), 0, 360,
                        int(rng.integers(0, len(PART_NAMES))), -1)
        cv2.line(m, (5, int(rng.integers(0, height))), (width - 5, int(rng.integers(0, height))),
                 int(rng.integers(0, len(PART_NAMES))), 1)
        m[int(rng.integers(0, height)), int(rng.integers(0, width))] = 3
    return maps


@pytest.fixture(scope="module")
def body_maps(body_model):
    return render_labels(body_model, *random_bodies(2, seed=6), front_camera(), FRONT_WIDTH)


def _boundary_parts(labels: np.ndarray) -> np.ndarray:
    return np.where(boundary_mask(labels >= 0), labels, -1)


def test_row_scan_finds_every_boundary_pixel_and_its_part(body_maps):
    maps = np.concatenate([blob_maps(4), np.full((1, 96, 128), -1, np.int8)])
    for labels in (maps, body_maps):
        found = unpack_runs(scan_label_maps(labels))
        assert np.array_equal(found, np.stack([_boundary_parts(m) for m in labels]))


def test_row_moments_are_the_silhouette_sums(body_maps):
    moments = scan_label_maps(body_maps).row_moments.numpy()
    inside = body_maps >= 0
    cols = np.arange(body_maps.shape[2])
    assert np.array_equal(moments[..., 0], inside.sum(axis=2))
    assert np.array_equal(moments[..., 1], (inside * cols).sum(axis=2))
    assert np.array_equal(moments[..., 2], (inside * cols ** 2).sum(axis=2))


def _check_against_scipy(labels: np.ndarray) -> tuple[float, float]:
    """Query every pixel centre; return the (mean, max) distance error in pixels."""
    height, width = labels.shape[1:]
    rows, cols = np.mgrid[0:height, 0:width]
    points = np.stack([cols.ravel(), rows.ravel()], axis=1)
    distances, parts = nearest_boundary(labels, points)
    errors = []
    for m, dist, part in zip(labels, distances, parts):
        boundary = _boundary_parts(m)
        exact = ndi.distance_transform_edt(boundary < 0).ravel()
        errors.append(np.abs(dist - exact))
        # the part returned is the part of a boundary pixel at exactly that distance
        per_part = np.stack([ndi.distance_transform_edt(boundary != k).ravel()
                             if (boundary == k).any() else np.full(exact.size, np.inf)
                             for k in range(len(PART_NAMES))])
        assert np.abs(per_part[part, np.arange(part.size)] - exact).max() < 1e-4
    errors = np.concatenate(errors)
    return float(errors.mean()), float(errors.max())


def test_nearest_boundary_equals_scipy_edt_on_blobs():
    mean_error, max_error = _check_against_scipy(blob_maps(3, seed=1))
    assert max_error < 1e-4 and mean_error < 1e-5


def test_nearest_boundary_equals_scipy_edt_on_a_body(body_maps):
    mean_error, max_error = _check_against_scipy(body_maps[:1])
    assert max_error < 1e-4 and mean_error < 1e-5


def test_nearest_boundary_at_subpixel_points_outside_too():
    labels = blob_maps(2, seed=2)
    rng = np.random.default_rng(3)
    points = rng.uniform([-20, -20], [148, 116], (500, 2)).astype(np.float32)
    distances, parts = nearest_boundary(labels, points)
    for m, dist, part in zip(labels, distances, parts):
        rows, cols = np.nonzero(boundary_mask(m >= 0))
        exact, index = cKDTree(np.stack([cols, rows], axis=1)).query(points)
        assert np.abs(dist - exact).max() < 1e-3
        unique = np.abs(np.sort(cKDTree(np.stack([cols, rows], axis=1)).query(points, k=2)[0], 1)
                        [:, 1] - exact) > 1e-3
        assert np.array_equal(part[unique], m[rows[index], cols[index]][unique])


def test_empty_map_has_no_nearest_pixel():
    distances, parts = nearest_boundary(np.full((1, 8, 8), -1, np.int8), [[3.0, 4.0]])
    assert np.isinf(distances).all() and (parts == -1).all()


@pytest.mark.parametrize("labels, points, message", [
    (np.zeros((8, 8), np.int8), [[0.0, 0.0]], r"label_maps must have shape \(P, H, W\)"),
    (np.full((1, 2, 5000), -1, np.int8), [[0.0, 0.0]], "at most 4096 pixels wide"),
    (np.full((1, 4, 4), 16, np.int8), [[0.0, 0.0]], r"parts in \[0, 16\)"),
    (np.zeros((1, 4, 4), np.int8), [0.0, 0.0], r"points must have shape \(N, 2\)"),
    (np.zeros((1, 4, 4), np.float32), [[0.0, 0.0]], "label_maps must be an int array"),
])
def test_nearest_boundary_rejects_bad_input(labels, points, message):
    with pytest.raises(ValueError, match=message):
        nearest_boundary(labels, points)


def test_person_target_has_the_boundary_and_its_exact_distance_transform():
    mask = blob_maps(1, seed=4)[0] >= 0
    view = prepare_view_target("front", mask, front_camera(), 1.0)
    boundary = boundary_mask(mask)
    points = view.boundary_points.numpy().astype(int)
    assert np.array_equal(points[:, ::-1], np.argwhere(boundary))
    rows, cols = np.nonzero(boundary)
    pixels = np.argwhere(np.ones_like(mask))[:, ::-1]
    brute_force = cKDTree(np.stack([cols, rows], axis=1)).query(pixels)[0].reshape(mask.shape)
    assert np.abs(view.boundary_distance.numpy() - brute_force).max() < 1e-4
    assert np.array_equal(boundary_distance(boundary), view.boundary_distance.numpy())
