"""Projection and rasterisation of posed populations into part-label maps with a depth test.

Every pixel of a candidate's map holds one int32 *key*: the depth of the nearest surface
seen through the pixel centre in the high bits and that surface's part label in the low
``PART_BITS`` bits, or ``BACKGROUND``. Triangles write their keys with ``wp.atomic_min``,
so the front-most surface wins and the result does not depend on thread order: the
rasteriser is race-free on CUDA and gives the same maps on every device.

Coverage rule: a triangle covers a pixel when the pixel centre lies inside it or on its
edge (centre sampling, the rule of GPU rasterisers); that keeps silhouettes unbiased,
with no half-pixel dilation. Triangles facing away from the camera are skipped (the body
mesh is closed, so front faces alone make the silhouette and the visible labels).

One thread per (candidate, triangle) on CUDA, per (candidate, block of 64 triangles) on
a CPU. On one CPU core the cost is dominated by the per-triangle setup of the many
sub-pixel triangles of hands, face and feet.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from bodyfit.kernels.view_camera import ViewCamera, project_point
from bodyfit.kernels.device import device_array, resolve_device

__all__ = [
    "BACKGROUND",
    "PART_BITS",
    "MAX_PARTS",
    "project",
    "rasterize",
    "launch_projection",
    "launch_raster",
    "decode_labels",
]

#: Key of a pixel that no triangle covers (int32 max: larger than every surface key).
BACKGROUND = 0x7FFFFFFF
#: Low bits of a key that hold the part label.
PART_BITS = 4
MAX_PARTS = 1 << PART_BITS
_PART_MASK = MAX_PARTS - 1
#: Depth quantisation of the key: 2**20 steps per metre (about 1 micrometre) below 128 m.
_DEPTH_STEPS_PER_METRE = float(1 << 20)
_MAX_DEPTH_STEP = (1 << (31 - PART_BITS)) - 1
#: Barycentric tolerance of the inside test (pixel centres on an edge count as inside,
#: and rounding cannot open a crack between two triangles that share an edge).
_INSIDE_TOLERANCE = 1.0e-5
#: Triangles whose bounding box is at least this many pixels wide scan only the part of
#: each row between their edges; narrower ones test every pixel centre of the box.
_SPAN_MIN_WIDTH = 4
#: Triangles per CPU thread (Warp runs CPU threads one after the other: fewer, longer
#: threads save the per-thread overhead); one per thread on CUDA.
_CPU_FACES_PER_THREAD = 64


@wp.kernel(enable_backward=False)
def _project_kernel(cam: ViewCamera, vertices: wp.array2d(dtype=wp.vec3),
                    screen: wp.array2d(dtype=wp.vec3)):
    p, v = wp.tid()
    screen[p, v] = project_point(cam, vertices[p, v])


@wp.func
def _ceil_nonnegative(x: float):
    """ceil(x) for x >= 0, without a libm call."""
    i = int(x)
    if float(i) < x:
        i = i + 1
    return i


@wp.func
def _span_bound(slope: float, offset: float, lo: float, hi: float):
    """Narrow [lo, hi] to the dx where slope * dx + offset >= 0, widened by one pixel."""
    if slope > 0.0:
        lo = wp.max(lo, -offset / slope - 1.0)
    elif slope < 0.0:
        hi = wp.min(hi, -offset / slope + 1.0)
    return wp.vec2(lo, hi)


@wp.kernel(enable_backward=False)
def _raster_kernel(cam: ViewCamera, screen: wp.array2d(dtype=wp.vec3),
                   faces: wp.array(dtype=wp.vec3i), face_parts: wp.array(dtype=wp.int32),
                   faces_per_thread: int, keys: wp.array3d(dtype=wp.int32)):
    p, block = wp.tid()
    first_face = block * faces_per_thread
    for f in range(first_face, wp.min(first_face + faces_per_thread, faces.shape[0])):
        tri = faces[f]
        a = screen[p, tri[0]]
        b = screen[p, tri[1]]
        c = screen[p, tri[2]]
        e1x = b[0] - a[0]
        e1y = b[1] - a[1]
        e2x = c[0] - a[0]
        e2y = c[1] - a[1]
        # Twice the signed area in (column, row) coordinates: negative when the triangle,
        # counter-clockwise seen from outside, faces the camera (see view_camera.py for the frame).
        area = e1x * e2y - e1y * e2x
        if area >= 0.0:
            continue
        if cam.pinhole != 0 and (a[2] <= 0.0 or b[2] <= 0.0 or c[2] <= 0.0):
            continue  # a vertex behind the camera
        height = keys.shape[1]
        width = keys.shape[2]
        min_x = wp.max(wp.min(wp.min(a[0], b[0]), c[0]), 0.0)
        max_x = wp.min(wp.max(wp.max(a[0], b[0]), c[0]), float(width - 1))
        min_y = wp.max(wp.min(wp.min(a[1], b[1]), c[1]), 0.0)
        max_y = wp.min(wp.max(wp.max(a[1], b[1]), c[1]), float(height - 1))
        if max_x < min_x or max_y < min_y:
            continue  # off the image
        x0 = _ceil_nonnegative(min_x)
        x1 = int(max_x)
        y0 = _ceil_nonnegative(min_y)
        y1 = int(max_y)
        if x0 > x1 or y0 > y1:
            continue  # no pixel centre inside the bounding box (most sub-pixel triangles)
        # Barycentric coordinates of the point a + (dx, dy) are affine:
        # l_b = bx * dx + by * dy, l_c = cx * dx + cy * dy, l_a = 1 - l_b - l_c.
        inv_area = 1.0 / area
        bx = e2y * inv_area
        by = -e2x * inv_area
        cx = -e1y * inv_area
        cy = e1x * inv_area
        qa = a[2]
        qb = b[2] - qa
        qc = c[2] - qa
        key_part = face_parts[f]
        pinhole = cam.pinhole != 0
        narrow = x1 - x0 < _SPAN_MIN_WIDTH
        for y in range(y0, y1 + 1):
            dy = float(y) - a[1]
            b0 = by * dy
            c0 = cy * dy
            xs = x0
            xe = x1
            if not narrow:  # skip the pixels of the row that are clearly outside
                span = _span_bound(bx, b0, float(x0) - a[0], float(x1) - a[0])
                span = _span_bound(cx, c0, span[0], span[1])
                span = _span_bound(-bx - cx, 1.0 - b0 - c0, span[0], span[1])
                if span[1] < span[0]:
                    continue
                # another half pixel of slack absorbs rounding; each pixel is tested anyway
                xs = wp.max(x0, _ceil_nonnegative(wp.max(span[0] + a[0] - 0.5, 0.0)))
                xe = wp.min(x1, int(wp.max(span[1] + a[0] + 0.5, 0.0)))
            for x in range(xs, xe + 1):
                # branch-free: a pixel outside the triangle writes BACKGROUND, a no-op for min
                dx = float(x) - a[0]
                lb = b0 + bx * dx
                lc = c0 + cx * dx
                q = qa + qb * lb + qc * lc
                if pinhole:
                    q = 1.0 / q
                step = int(wp.clamp(q * _DEPTH_STEPS_PER_METRE, 0.0, float(_MAX_DEPTH_STEP)))
                inside = wp.min(wp.min(lb, lc), 1.0 - lb - lc) >= -_INSIDE_TOLERANCE
                wp.atomic_min(keys, p, y, x, wp.where(inside, (step << PART_BITS) | key_part,
                                                      BACKGROUND))


@wp.kernel(enable_backward=False)
def _decode_kernel(keys: wp.array3d(dtype=wp.int32), labels: wp.array3d(dtype=wp.int8)):
    p, y, x = wp.tid()
    key = keys[p, y, x]
    if key == BACKGROUND:
        labels[p, y, x] = wp.int8(-1)
    else:
        labels[p, y, x] = wp.int8(key & _PART_MASK)


def launch_projection(cam: ViewCamera, vertices: wp.array, screen: wp.array) -> None:
    """Project checked (P, V) vec3 vertices into (P, V) vec3 ``screen`` = (u, v, q)."""
    wp.launch(_project_kernel, dim=vertices.shape, device=vertices.device,
              inputs=[cam, vertices], outputs=[screen])


def launch_raster(cam: ViewCamera, screen: wp.array, faces: wp.array, face_parts: wp.array,
                  keys: wp.array) -> None:
    """Clear (P, H, W) int32 ``keys`` to ``BACKGROUND`` and rasterise into them (no checks)."""
    keys.fill_(BACKGROUND)
    per_thread = 1 if screen.device.is_cuda else _CPU_FACES_PER_THREAD
    blocks = (faces.shape[0] + per_thread - 1) // per_thread
    wp.launch(_raster_kernel, dim=(screen.shape[0], blocks), device=screen.device,
              inputs=[cam, screen, faces, face_parts, per_thread], outputs=[keys])


def decode_labels(keys: wp.array) -> wp.array:
    """(P, H, W) int8 part labels (-1 = background) of (P, H, W) int32 keys."""
    labels = wp.empty(keys.shape, dtype=wp.int8, device=keys.device)
    wp.launch(_decode_kernel, dim=keys.shape, device=keys.device, inputs=[keys],
              outputs=[labels])
    return labels


def project(vertices, camera: ViewCamera, device: str = "cpu") -> wp.array:
    """Pixel coordinates and depth values of every vertex of a population.

    Args:
        vertices: (P, V, 3) float, metres, model frame (or a (P, V) vec3 Warp array).
        camera: the view's camera.
        device: where to compute (a Warp array input must already live there).

    Returns:
        (P, V) vec3 Warp array: (u, v) pixels (column, row), and q = z_cam (orthographic)
        or 1/z_cam (pinhole), the screen-linear depth value.
    """
    dev = resolve_device(device)
    vertices = device_array("vertices", vertices, ("P", "V", 3), {}, "float", wp.vec3, dev)
    screen = wp.empty(vertices.shape, dtype=wp.vec3, device=dev)
    launch_projection(camera, vertices, screen)
    return screen


def rasterize(vertices, faces, face_parts, camera: ViewCamera, height: int, width: int,
              device: str = "cpu") -> wp.array:
    """Part-label maps of a population seen by one camera, front-most part winning.

    Args:
        vertices: (P, V, 3) float, metres, model frame (or a (P, V) vec3 Warp array).
        faces: (F, 3) int, vertex indices, counter-clockwise seen from outside.
        face_parts: (F,) int, part label of each face, in [0, 16).
        camera: the view's camera.
        height, width: image size, pixels (at most 4096 each).
        device: where to compute.

    Returns:
        (P, H, W) int8 Warp array: the part label of each pixel, -1 for background.

    Raises:
        ValueError: wrong shapes or dtypes, labels outside [0, 16), indices outside
            [0, V), or an image size outside [1, 4096].
    """
    dev = resolve_device(device)
    if not (1 <= height <= 4096 and 1 <= width <= 4096):
        raise ValueError(f"height and width must be in [1, 4096], got {height} x {width}")
    dims: dict[str, int] = {}
    vertices = device_array("vertices", vertices, ("P", "V", 3), dims, "float", wp.vec3, dev)
    faces_np = np.asarray(faces)
    parts_np = np.asarray(face_parts)
    faces_wp = device_array("faces", faces_np, ("F", 3), dims, "int", wp.vec3i, dev)
    parts_wp = device_array("face_parts", parts_np, ("F",), dims, "int", wp.int32, dev)
    if faces_np.size and (faces_np.min() < 0 or faces_np.max() >= dims["V"]):
        raise ValueError(f"faces must index vertices in [0, V={dims['V']})")
    if parts_np.size and (parts_np.min() < 0 or parts_np.max() >= MAX_PARTS):
        raise ValueError(f"face_parts must lie in [0, {MAX_PARTS})")
    screen = wp.empty(vertices.shape, dtype=wp.vec3, device=dev)
    launch_projection(camera, vertices, screen)
    keys = wp.empty((dims["P"], height, width), dtype=wp.int32, device=dev)
    launch_raster(camera, screen, faces_wp, parts_wp, keys)
    return decode_labels(keys)
