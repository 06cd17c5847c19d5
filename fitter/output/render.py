"""Pictures of bodies coloured by part (for people to look at, not for fitting).

A painter's-algorithm rendering with OpenCV polygon fill: triangles sorted far to near,
each filled with its part's colour shaded by how squarely it faces the viewer; scaled
orthographic (:func:`render_parts`) or through a pinhole camera (:func:`render_pinhole`). Front
view looks at the body from -y (the body's left appears on the image's right); side view
looks from the body's left (+x), the body facing the image's right.
"""

from __future__ import annotations

import cv2
import numpy as np

from bodyfit.fitter.model.body_model import PART_NAMES

__all__ = ["PART_COLOURS_BGR", "render_parts", "render_colours", "orthographic_pixels", "render_pinhole",
           "pinhole_pixels", "coverage_mask", "centre_samples", "parts_legend"]

#: One BGR colour per part, ``PART_NAMES`` order.
PART_COLOURS_BGR = np.array([
    (170, 160, 0),    # head: teal (the person is grey in the overlays)
    (40, 40, 230),    # chest
    (0, 150, 255),    # waist
    (0, 220, 240),    # hip
    (60, 180, 60),    # leg
    (120, 60, 20),    # foot
    (230, 80, 30),    # arm
    (220, 60, 220),   # elbow
    (120, 20, 110),   # hand
    (90, 110, 0),     # neck: a darker teal than the head it was split from
], np.uint8)

_VIEWS = {  # view -> (image-right axis, toward-viewer axis)
    "front": (np.array([1.0, 0.0, 0.0]), np.array([0.0, -1.0, 0.0])),
    "side": (np.array([0.0, -1.0, 0.0]), np.array([1.0, 0.0, 0.0])),
}
_SUBPIXEL_BITS = 2


def render_parts(vertices: np.ndarray, faces: np.ndarray, face_parts: np.ndarray,
                 view: str, height_px: int = 600, margin_px: float = 10) -> np.ndarray:
    """Render one view of a body.

    Args:
        vertices: (V, 3) float, metres, model frame.
        faces: (F, 3) int triangles.
        face_parts: (F,) int part label of each face.
        view: "front" or "side".
        height_px, margin_px: :func:`orthographic_pixels`.

    Returns:
        (height_px, W, 3) uint8 BGR image on white, W fitted to the body.
    """
    return render_colours(vertices, faces, PART_COLOURS_BGR[face_parts], view, height_px,
                          margin_px)


def render_colours(vertices: np.ndarray, faces: np.ndarray, face_colours: np.ndarray,
                   view: str, height_px: int = 600, margin_px: float = 10) -> np.ndarray:
    """:func:`render_parts` with any colour per face: ``face_colours`` (F, 3) BGR 0-255."""
    right, toward = _VIEWS[view]
    px = orthographic_pixels(vertices, view, height_px, margin_px)
    width = int(np.ceil(px[:, 0].max() + margin_px))
    image = np.full((height_px, width, 3), 255, np.uint8)
    return _paint(image, px, vertices @ toward, vertices, faces, face_colours, toward)


def orthographic_pixels(vertices: np.ndarray, view: str, height_px: int,
                        margin_px: float) -> np.ndarray:
    """(V, 2) float pixel coordinates (pixel centres at integers) of :func:`render_parts`'
    picture: the body scaled to ``height_px - 2 margin_px`` pixels tall, ``margin_px`` from
    the top and the left."""
    right, _ = _VIEWS[view]
    u, z = vertices @ right, vertices[:, 2]
    scale = (height_px - 2 * margin_px) / np.ptp(z)
    return np.stack([(u - u.min()) * scale + margin_px, (z.max() - z) * scale + margin_px], 1)


def render_pinhole(vertices: np.ndarray, faces: np.ndarray, face_parts: np.ndarray,
                   intrinsics: np.ndarray, rotation: np.ndarray, translation_m: np.ndarray,
                   size_px: tuple[int, int], face_colours: np.ndarray | None = None
                   ) -> np.ndarray:
    """Render a body through a pinhole camera (no lens distortion), painter's algorithm.

    Args:
        vertices: (V, 3) float, metres, model frame.
        faces: (F, 3) int triangles.
        face_parts: (F,) int part label of each face.
        intrinsics: (3, 3) K, pixels; rotation (3, 3) and translation_m (3,): model frame ->
            camera frame (x right, y down, z forward), as :mod:`bodyfit.kernels.view_camera`.
        size_px: (width, height) of the image.
        face_colours: (F, 3) BGR 0-255 per face, or None for ``PART_COLOURS_BGR`` by part.

    Returns:
        (height, width, 3) uint8 BGR image on white; every vertex must be in front of the camera.
    """
    px, depth = pinhole_pixels(vertices, intrinsics, rotation, translation_m)
    image = np.full((size_px[1], size_px[0], 3), 255, np.uint8)
    colours = PART_COLOURS_BGR[face_parts] if face_colours is None else face_colours
    return _paint(image, px, -depth, vertices, faces, colours, -np.asarray(rotation, float)[2])


def pinhole_pixels(vertices: np.ndarray, intrinsics: np.ndarray, rotation: np.ndarray,
                   translation_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(V, 2) pixels and (V,) depths, metres, of ``vertices`` (V, 3) through a pinhole
    (arguments as :func:`render_pinhole`); ValueError if a vertex is not in front of it."""
    cam = vertices @ np.asarray(rotation, float).T + np.asarray(translation_m, float)
    if not np.all(cam[:, 2] > 0):
        raise ValueError("a pinhole rendering needs every vertex in front of the camera")
    return (cam[:, :2] / cam[:, 2:]) @ np.asarray(intrinsics, float)[:2, :2].T \
        + np.asarray(intrinsics, float)[:2, 2], cam[:, 2]


def coverage_mask(px: np.ndarray, faces: np.ndarray, size_px: tuple[int, int],
                  supersample: int = 5) -> np.ndarray:
    """(H, W) bool: the pixels that triangles ``px[faces]`` ((V, 2) pixels, pixel centres at
    integers) cover by more than half: the union of the triangles sampled at the centres
    of a ``supersample`` times finer grid (:func:`centre_samples`), area-averaged.

    Unbiased, where two earlier versions were not (each made every synthetic fit come out
    about 2 mm large): OpenCV's polygon fill takes every fine pixel an outline touches
    (0.4 px too wide per row of a body at 4x), and an even ``supersample`` leaves pixels
    covered by exactly one half, all of them dropped (0.2 px too narrow at 4x); an odd one
    has no such ties.
    """
    if supersample % 2 == 0:
        raise ValueError(f"supersample must be odd (no pixel covered by exactly one half), "
                         f"got {supersample}")
    width, height = size_px
    corners = (np.asarray(px, np.float64) + 0.5) * supersample - 0.5
    fine = centre_samples(corners, faces, (width * supersample, height * supersample))
    return cv2.resize(fine.astype(np.float32), (width, height), interpolation=cv2.INTER_AREA) > 0.5


def centre_samples(px: np.ndarray, faces: np.ndarray, size_px: tuple[int, int]) -> np.ndarray:
    """(H, W) bool: the pixels whose centre (integer coordinates) lies inside or on an edge
    of a triangle ``px[faces]`` ((V, 2) float pixels, either winding): the GPU's coverage
    rule, computed on the host, triangles batched by the size of their bounding boxes."""
    width, height = size_px
    out = np.zeros((height, width), bool)
    tri = np.asarray(px, np.float64)[np.asarray(faces)]  # (F, 3, 2)
    lo = np.maximum(np.ceil(tri.min(axis=1)), 0).astype(np.int64)  # first centre (x, y)
    hi = np.minimum(np.floor(tri.max(axis=1)), [width - 1, height - 1]).astype(np.int64)
    span = hi - lo + 1  # (F, 2) centres across the box
    edge1, edge2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    area = edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0]
    live = np.all(span > 0, axis=1) & (area != 0)
    tri, lo, span = tri[live], lo[live], span[live]
    tri = np.where((area[live] < 0)[:, None, None], tri[:, ::-1], tri)  # one winding
    # batches: triangles whose boxes round up to the same powers of two, about 2**22
    # samples at a time
    bucket = 2 ** np.ceil(np.log2(span)).astype(np.int64)  # (F, 2)
    for box in np.unique(bucket, axis=0):
        members = np.flatnonzero(np.all(bucket == box, axis=1))
        for batch in np.array_split(members, -(-len(members) * int(np.prod(box)) // (1 << 22))):
            xs = lo[batch, 0, None, None] + np.arange(box[0])[None, None, :]  # (T, 1, bw)
            ys = lo[batch, 1, None, None] + np.arange(box[1])[None, :, None]  # (T, bh, 1)
            inside = (xs < (lo[batch, 0] + span[batch, 0])[:, None, None]) \
                & (ys < (lo[batch, 1] + span[batch, 1])[:, None, None])
            for a, b in ((0, 1), (1, 2), (2, 0)):
                pa, pb = tri[batch, a, :, None, None], tri[batch, b, :, None, None]
                inside &= (pb[:, 0] - pa[:, 0]) * (ys - pa[:, 1]) \
                    - (pb[:, 1] - pa[:, 1]) * (xs - pa[:, 0]) >= -1e-9
            t, r, c = np.nonzero(inside)
            out[lo[batch[t], 1] + r, lo[batch[t], 0] + c] = True
    return out


def _paint(image, px, toward_depth, vertices, faces, face_colours, toward) -> np.ndarray:
    """Fill each triangle of ``px`` ((V, 2) pixels) far to near (small ``toward_depth``
    first) with its colour ((F, 3) BGR), shaded by how squarely it faces ``toward`` (unit
    vector to the viewer)."""
    tri = vertices[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True) + 1e-12
    shade = 0.35 + 0.65 * np.abs(normals @ toward)
    colours = np.asarray(face_colours, np.float64) * shade[:, None]
    polygons = np.round(px[faces] * (1 << _SUBPIXEL_BITS)).astype(np.int32)
    for f in np.argsort(toward_depth[faces].mean(axis=1)):  # far (small "toward") to near
        cv2.fillPoly(image, [polygons[f]], colours[f].tolist(), lineType=cv2.LINE_AA,
                     shift=_SUBPIXEL_BITS)
    return image


def parts_legend(height_px: int) -> np.ndarray:
    """(height_px, 120, 3) uint8 BGR legend: one swatch and name per part."""
    legend = np.full((height_px, 120, 3), 255, np.uint8)
    for i, name in enumerate(PART_NAMES):
        y = 20 + 24 * i
        cv2.rectangle(legend, (8, y - 12), (26, y + 4), PART_COLOURS_BGR[i].tolist(), -1)
        cv2.putText(legend, name, (34, y + 2), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1,
                    cv2.LINE_AA)
    return legend
