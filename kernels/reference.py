"""NumPy/OpenCV/SciPy reference of the kernel pipeline, for the tests and the benchmark.

Written independently of the kernels and for clarity, not speed:

- skinning: the body model's NumPy forward, :func:`bodyfit.kernels.body_forward.forward`
  (the paper's Eq. 1-3);
- projection: the camera equations in float64;
- rasterisation: ``cv2.fillPoly`` of every projected triangle (no back-face culling),
  painted far to near by mean depth (the painter's algorithm). ``cv2.fillPoly`` also draws
  each polygon's outline, which dilates a silhouette by about half a pixel; with
  ``supersample`` = S > 1 the triangles are painted on an S-times finer grid (band by band)
  and each pixel takes the label found at its centre, which makes the reference
  centre-sampled like the kernels, to within 1/(2S) pixel;
- boundaries and the person's distance transform: :mod:`bodyfit.kernels.target`;
  nearest boundary pixels: ``scipy.spatial.cKDTree``;
- alignment: :func:`bodyfit.kernels.alignment.silhouette_moments` and ``rigid_transform``;
- cost: Eq. 17-18 in NumPy.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.spatial import cKDTree

from bodyfit.kernels.body_forward import forward
from bodyfit.kernels.body_layout import PART_NAMES
from bodyfit.kernels.alignment import rigid_transform, silhouette_moments
from bodyfit.kernels.view_camera import ViewCamera, camera_matrices
from bodyfit.kernels.cost import MATCHING_WEIGHTS, TERM_NAMES, CostSettings
from bodyfit.kernels.skinning import SkinnableModel
from bodyfit.kernels.target import ViewTarget, boundary_mask, visible_faces

__all__ = ["project_vertices", "render_label_maps", "interpolate_distance",
           "view_terms", "population_cost"]

_SHIFT = 8  # fixed-point bits of the cv2.fillPoly coordinates
_BAND_PIXELS = 1 << 20  # fine-grid pixels painted per band


def project_vertices(camera: ViewCamera, vertices: np.ndarray) -> np.ndarray:
    """(..., 3) float64 (u, v, z_cam): pixels (column, row) and depth in metres.

    Args:
        camera: a camera of :mod:`bodyfit.kernels.view_camera`.
        vertices: (..., 3) float, metres, model frame.
    """
    k, r, t = camera_matrices(camera)
    cam = np.asarray(vertices, dtype=np.float64) @ r.T + t
    xy = cam[..., :2] / cam[..., 2:3] if camera.pinhole else cam[..., :2]
    u = k[0, 0] * xy[..., 0] + k[0, 1] * xy[..., 1] + k[0, 2]
    v = k[1, 1] * xy[..., 1] + k[1, 2]
    return np.stack([u, v, cam[..., 2]], axis=-1)


def _render_one(screen: np.ndarray, faces: np.ndarray, face_parts: np.ndarray, height: int,
                width: int, supersample: int) -> np.ndarray:
    s = supersample
    order = np.argsort(-screen[faces, 2].mean(axis=1), kind="stable")  # far to near
    fine = screen[:, :2] * s + (s - 1) / 2  # pixel centres land on fine pixel centres
    points = np.round(fine * (1 << _SHIFT)).astype(np.int64)
    rows = fine[faces, 1] / s
    low, high = rows.min(axis=1), rows.max(axis=1)
    band = max(1, _BAND_PIXELS // (s * s * width))
    labels = np.full((height, width), -1, np.int8)
    for top in range(0, height, band):
        bottom = min(height, top + band)
        canvas = np.zeros((s * (bottom - top), s * width), np.uint8)
        offset = np.array([0, s * top << _SHIFT])
        for f in order[(high[order] >= top - 1) & (low[order] <= bottom)]:
            polygon = (points[faces[f]] - offset).astype(np.int32)
            cv2.fillPoly(canvas, [polygon], int(face_parts[f]) + 1, cv2.LINE_8, _SHIFT)
        labels[top:bottom] = canvas[(s - 1) // 2::s, (s - 1) // 2::s].astype(np.int16) - 1
    return labels


def render_label_maps(screen: np.ndarray, faces: np.ndarray, face_parts: np.ndarray,
                      height: int, width: int, supersample: int = 1) -> np.ndarray:
    """(P, H, W) int8 part labels (-1 background) by painting triangles far to near.

    Args:
        screen: (P, V, 3) float (u, v, z_cam) from :func:`project_vertices`.
        faces: (F, 3) int triangles.
        face_parts: (F,) int part labels in [0, 254].
        height, width: image size, pixels.
        supersample: odd S >= 1; see the module docstring.
    """
    if supersample < 1 or supersample % 2 == 0:
        raise ValueError("supersample must be an odd integer >= 1")
    return np.stack([_render_one(s, faces, face_parts, height, width, supersample)
                     for s in screen])


def interpolate_distance(distance: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Bilinear values of a (H, W) distance map at (N, 2) points (column, row); outside the
    image, the value at the nearest image point plus the distance to it."""
    height, width = distance.shape
    clamped = np.clip(points, 0, [width - 1, height - 1])
    outside = np.linalg.norm(points - clamped, axis=1)
    x0, y0 = np.floor(clamped).astype(int).T
    x1, y1 = np.minimum(x0 + 1, width - 1), np.minimum(y0 + 1, height - 1)
    fx, fy = (clamped - np.stack([x0, y0], axis=1)).T
    upper = (1 - fx) * distance[y0, x0] + fx * distance[y0, x1]
    lower = (1 - fx) * distance[y1, x0] + fx * distance[y1, x1]
    return (1 - fy) * upper + fy * lower + outside


def view_terms(label_map: np.ndarray, view: ViewTarget, settings: CostSettings) -> np.ndarray:
    """(12,) float64 weighted terms (``TERM_NAMES``) of one candidate in one view, mm."""
    moments = silhouette_moments(label_map >= 0)
    if moments.area_px == 0:
        return np.full(len(TERM_NAMES), np.inf)
    to_candidate = rigid_transform(moments, view.moments, settings.align_rotation,
                                   settings.vertical_anchor)
    to_person = np.linalg.inv(to_candidate)
    rows, cols = np.nonzero(boundary_mask(label_map >= 0))
    model_points = np.stack([cols, rows], axis=1).astype(np.float64)
    model_parts = label_map[rows, cols]
    weights = np.asarray(settings.part_weights)
    num_parts = len(PART_NAMES)
    person = view.boundary_points.numpy().astype(np.float64)
    forward_sums = np.zeros(num_parts)
    if settings.matching != "model_to_person":
        moved = person @ to_candidate[:2, :2].T + to_candidate[:2, 2]
        distances, nearest = cKDTree(model_points).query(moved)
        np.add.at(forward_sums, model_parts[nearest], distances)
        forward_sums /= len(person)
    backward_sums = np.zeros(num_parts)
    if settings.matching != "person_to_model":
        moved = model_points @ to_person[:2, :2].T + to_person[:2, 2]
        distances = interpolate_distance(view.boundary_distance.numpy(), moved)
        np.add.at(backward_sums, model_parts, distances)
        backward_sums /= len(model_points)
    mix = MATCHING_WEIGHTS[settings.matching]
    parts = weights * (mix[0] * forward_sums + mix[1] * backward_sums)
    top = abs((to_person[:2, :2] @ moments.top + to_person[:2, 2] - view.moments.top)[1])
    bottom = abs((to_person[:2, :2] @ moments.bottom + to_person[:2, 2]
                  - view.moments.bottom)[1])
    extremes = [settings.top_weight * top, settings.bottom_weight * bottom]
    scale = settings.view_weight(view.name) * view.millimetres_per_pixel
    return scale * np.concatenate([parts, extremes])


def population_cost(model: SkinnableModel, betas: np.ndarray, pose_deg: np.ndarray,
                    views: list[ViewTarget], settings: CostSettings = CostSettings(),
                    supersample: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The reference pipeline: costs (P,) and part costs (P, 12), float64, millimetres.

    Each view skins the candidates with its own pose (``ViewTarget.view_pose``: the
    candidates' angles, with the view's fixed angles put in).
    """
    part_costs = np.zeros((len(betas), len(TERM_NAMES)))
    for view in views:
        vertices = forward(model, betas, view.view_pose(pose_deg))
        faces, face_parts = visible_faces(model.faces, model.face_parts, view.visible_parts)
        screen = project_vertices(view.camera, vertices)
        maps = render_label_maps(screen, faces, face_parts, view.height, view.width,
                                 supersample)
        part_costs += np.stack([view_terms(m, view, settings) for m in maps])
    return part_costs.sum(axis=1), part_costs
