"""Cameras, projection and rasterisation against NumPy and an OpenCV polygon-fill reference."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi

from bodyfit.fitter.model.body_model import forward
from bodyfit.kernels.raster import project, rasterize
from bodyfit.kernels.reference import project_vertices, render_label_maps
from bodyfit.kernels.view_camera import (FRONT_VIEW_DEG, SIDE_VIEW_DEG, orthographic_camera,
                                         paper_rotation, pinhole_camera)

from kernel_scenes import (DEVICES, FRONT_WIDTH, HEIGHT, SIDE_WIDTH, box_mesh, front_camera,
                           random_bodies, side_camera)


def _pinhole(width):
    """A phone-like camera 3 m in front of the body, looking at it (model -y is forward)."""
    rotation = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # x right, -z down, y ahead
    intrinsics = [[600.0, 0, width / 2], [0, 600.0, HEIGHT / 2], [0, 0, 1]]
    return pinhole_camera(intrinsics, rotation, [0.0, 0.05, 3.0])


def test_paper_projections_orient_the_body():
    front, side = paper_rotation(FRONT_VIEW_DEG), paper_rotation(SIDE_VIEW_DEG)
    # front: the body's left (+x) to the image's right, up (+z) to the image's top, depth +y
    assert np.allclose(front, [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-12)
    # side: the body's front (-y) to the image's left, seen from the body's left (+x)
    assert np.allclose(side, [[0, 1, 0], [0, 0, -1], [-1, 0, 0]], atol=1e-12)


@pytest.mark.parametrize("camera", [front_camera(), side_camera(), _pinhole(FRONT_WIDTH)],
                         ids=["front", "side", "pinhole"])
def test_project_matches_numpy(body_model, camera):
    vertices = forward(body_model, *random_bodies(2, seed=3))
    screen = project(vertices, camera).numpy()
    expected = project_vertices(camera, vertices)
    assert np.abs(screen[..., :2] - expected[..., :2]).max() < 1e-3
    depth = expected[..., 2] if not camera.pinhole else 1.0 / expected[..., 2]
    assert np.allclose(screen[..., 2], depth, rtol=1e-6)


def _far_from_part_borders(labels, radius=2):
    """Pixels whose (2 radius + 1)^2 neighbourhood holds a single label."""
    size = 2 * radius + 1
    low = ndi.minimum_filter(labels, size, mode="nearest")
    high = ndi.maximum_filter(labels, size, mode="nearest")
    return low == high


@pytest.mark.parametrize("view", ["front", "side", "pinhole"])
def test_rasterize_matches_opencv_fill(body_model, view):
    camera, width = {"front": (front_camera(), FRONT_WIDTH), "side": (side_camera(), SIDE_WIDTH),
                     "pinhole": (_pinhole(FRONT_WIDTH), FRONT_WIDTH)}[view]
    vertices = forward(body_model, *random_bodies(1, seed=4))
    labels = rasterize(vertices, body_model.faces, body_model.face_parts, camera, HEIGHT,
                       width).numpy()[0]
    reference = render_label_maps(project_vertices(camera, vertices), body_model.faces,
                                  body_model.face_parts, HEIGHT, width, supersample=65)[0]
    ours, theirs = labels >= 0, reference >= 0
    assert ours.sum() > 15000  # the body fills the canvas
    assert (ours & theirs).sum() / (ours | theirs).sum() >= 0.999
    interior = ours & theirs & _far_from_part_borders(reference)
    assert interior.sum() > 0.6 * ours.sum()
    assert np.array_equal(labels[interior], reference[interior])


def test_front_most_part_wins():
    near, near_faces = box_mesh([-0.1, -0.3, -0.1], [0.1, -0.1, 0.1])      # part 1, nearer
    far, far_faces = box_mesh([0.0, 0.2, -0.2], [0.3, 0.4, 0.05])           # part 2, behind
    vertices = np.concatenate([near, far])[None]
    faces = np.concatenate([near_faces, far_faces + 8])
    parts = np.repeat([1, 2], 12)
    camera = orthographic_camera(FRONT_VIEW_DEG, 100.0, (50.0, 50.0))
    labels = rasterize(vertices, faces, parts, camera, 100, 100).numpy()[0]
    cols, rows = np.meshgrid(np.arange(100), np.arange(100))
    x, z = (cols - 50.0) / 100.0, (50.0 - rows) / 100.0
    in_near = (np.abs(x) <= 0.1) & (np.abs(z) <= 0.1)
    in_far = (x >= 0.0) & (x <= 0.3) & (z >= -0.2) & (z <= 0.05)
    expected = np.where(in_near, 1, np.where(in_far, 2, -1))
    # pixel centres on a box edge are covered by the edge's tolerance: compare off the edges
    on_edge = np.isclose(np.abs(x), 0.1) | np.isclose(np.abs(z), 0.1) | np.isclose(x, 0.0) \
        | np.isclose(x, 0.3) | np.isclose(z, -0.2) | np.isclose(z, 0.05)
    assert np.array_equal(labels[~on_edge], expected[~on_edge])
    # seen from behind (D_y = 180 degrees) the other box is in front where they overlap
    back = orthographic_camera((90.0, 180.0, 0.0), 100.0, (50.0, 50.0))
    labels_back = rasterize(vertices, faces, parts, back, 100, 100).numpy()[0]
    assert labels_back[50, 45] == 2 and labels[50, 55] == 1


@pytest.mark.parametrize("device", DEVICES)
def test_rasterize_is_deterministic_on_every_device(body_model, device):
    vertices = forward(body_model, *random_bodies(3, seed=5))
    args = (body_model.faces, body_model.face_parts, front_camera(), HEIGHT, FRONT_WIDTH)
    first = rasterize(vertices, *args, device=device).numpy()
    again = rasterize(vertices, *args, device=device).numpy()
    on_cpu = rasterize(vertices, *args, device="cpu").numpy()
    assert np.array_equal(first, again) and np.array_equal(first, on_cpu)


def test_pinhole_perspective_shrinks_with_distance():
    corners, faces = box_mesh([-0.2, -0.2, -0.2], [0.2, 0.2, 0.2])
    rotation = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    widths = []
    for distance in (2.0, 4.0):
        camera = pinhole_camera([[500.0, 0, 100], [0, 500.0, 100], [0, 0, 1]], rotation,
                                [0, 0, distance])
        labels = rasterize(corners[None], faces, np.zeros(12, int), camera, 200, 200).numpy()[0]
        widths.append((labels[100] >= 0).sum())
    # the front face (nearest, at distance - 0.2) spans 500 * 0.4 / (distance - 0.2) pixels
    assert abs(widths[0] - 500 * 0.4 / 1.8) <= 1 and abs(widths[1] - 500 * 0.4 / 3.8) <= 1


@pytest.mark.parametrize("kwargs, message", [
    (dict(height=0), "height and width"),
    (dict(width=5000), "height and width"),
    (dict(faces=np.array([[0, 1, 99]])), "faces must index vertices"),
    (dict(face_parts=np.array([16])), r"face_parts must lie in \[0, 16\)"),
    (dict(face_parts=np.array([0, 1])), r"face_parts must have shape \(F=1,\)"),
    (dict(vertices=np.zeros((1, 3, 2))), r"vertices must have shape \(P, V, 3\)"),
    (dict(faces=np.array([[0.0, 1.0, 2.0]])), "faces must be an int array"),
])
def test_rasterize_rejects_bad_input(kwargs, message):
    args = dict(vertices=np.zeros((1, 3, 3)), faces=np.array([[0, 1, 2]]),
                face_parts=np.array([0]), camera=front_camera(), height=8, width=8)
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        rasterize(**args)


def test_camera_constructors_reject_bad_input():
    with pytest.raises(ValueError, match="proper rotation"):
        pinhole_camera(np.eye(3), np.diag([1.0, 1.0, -1.0]), np.zeros(3))
    with pytest.raises(ValueError, match="fx, fy > 0"):
        pinhole_camera([[-1.0, 0, 0], [0, 1, 0], [0, 0, 1]], np.eye(3), np.zeros(3))
    with pytest.raises(ValueError, match="shape"):
        pinhole_camera(np.eye(3), np.eye(3), np.zeros(4))
    with pytest.raises(ValueError, match="pixels_per_metre"):
        orthographic_camera(FRONT_VIEW_DEG, 0.0, (1.0, 1.0))
