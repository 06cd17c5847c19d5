"""Shared scenes of the kernel tests: canvas sizes, cameras, random bodies, a box mesh."""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp

from bodyfit.fitter.model.body_model import PART_NAMES, forward
from bodyfit.kernels.raster import rasterize
from bodyfit.kernels.target import visible_faces
from bodyfit.kernels.view_camera import FRONT_VIEW_DEG, SIDE_VIEW_DEG, orthographic_camera

#: The canvas of the tests: 512 px high like the benchmark; widths fit each view.
HEIGHT = 512
FRONT_WIDTH = 352
SIDE_WIDTH = 192
PIXELS_PER_METRE = 270.0

DEVICES = [
    "cpu",
    pytest.param("cuda:0", marks=pytest.mark.skipif(not wp.is_cuda_available(),
                                                     reason="no CUDA device")),
]


def front_camera():
    return orthographic_camera(FRONT_VIEW_DEG, PIXELS_PER_METRE, (FRONT_WIDTH / 2, HEIGHT / 2))


def side_camera():
    return orthographic_camera(SIDE_VIEW_DEG, PIXELS_PER_METRE, (SIDE_WIDTH / 2, HEIGHT / 2))


def random_bodies(num: int, seed: int, spread: float = 2.0):
    """(betas (num, 20), pose_deg (num, 4)) float32 within +-spread sigma and 0-30 degrees."""
    rng = np.random.default_rng(seed)
    return (rng.uniform(-spread, spread, (num, 20)).astype(np.float32),
            rng.uniform(0.0, 30.0, (num, 4)).astype(np.float32))


def render_labels(body_model, betas, pose_deg, camera, width, parts=PART_NAMES):
    """(P, H, W) int8 label maps of bodies, by the kernel rasteriser."""
    faces, face_parts = visible_faces(body_model.faces, body_model.face_parts, parts)
    vertices = forward(body_model, betas, pose_deg)
    return rasterize(vertices, faces, face_parts, camera, HEIGHT, width).numpy()


def box_mesh(low, high):
    """(8, 3) float32 corners and (12, 3) int32 triangles of an axis-aligned box,
    counter-clockwise seen from outside."""
    low, high = np.asarray(low, float), np.asarray(high, float)
    corners = np.array([[(high if (i >> a) & 1 else low)[a] for a in range(3)] for i in range(8)])
    quads = [(0, 2, 6, 4), (1, 3, 7, 5), (0, 1, 5, 4), (2, 3, 7, 6), (0, 1, 3, 2), (4, 5, 7, 6)]
    centre = corners.mean(axis=0)
    faces = []
    for a, b, c, d in quads:
        for tri in ((a, b, c), (a, c, d)):
            p = corners[list(tri)]
            normal = np.cross(p[1] - p[0], p[2] - p[0])
            faces.append(tri if normal @ (p.mean(axis=0) - centre) > 0 else tri[::-1])
    return corners.astype(np.float32), np.array(faces, np.int32)
