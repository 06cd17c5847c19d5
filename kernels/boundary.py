"""Silhouette boundaries of candidate label maps, and exact nearest-boundary queries.

A *boundary pixel* is a silhouette pixel with at least one 4-neighbour outside the
silhouette or outside the image (the inner boundary, an 8-connected contour like the one
the paper's Moore-neighbour tracing follows); :func:`bodyfit.kernels.target.boundary_mask`
is the same definition for the person's mask.

Row scan: one thread per (candidate, row) skips the background, and for each span of
silhouette pixels adds its moments in closed form (for the alignment) and writes the
row's boundary *runs*, maximal sequences of consecutive boundary pixels of one part (at
most W per row): span ends, and span pixels with the background above or below.

Nearest boundary pixel of a query point (x, y): visit rows in order of increasing
|row - y| and stop once (row - y)^2 is no smaller than the best squared distance found;
within a row the nearest pixel of a run [s, e] is clamp(round(x), s, e). The result is the
exact Euclidean distance to the nearest boundary pixel centre (what
``scipy.ndimage.distance_transform_edt`` computes on a pixel grid) and that pixel's part.
Candidates are aligned to the person, so the person's boundary points lie a few pixels
from the candidate's boundary and a query visits a handful of rows: this does the work of
the paper's direction (person point -> nearest model point) without a full-image distance
transform per candidate.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import warp as wp

from bodyfit.kernels.device import device_array, resolve_device
from bodyfit.kernels.raster import BACKGROUND, MAX_PARTS

__all__ = [
    "BoundaryRuns",
    "allocate_runs",
    "launch_row_scan",
    "launch_nearest",
    "scan_label_maps",
    "nearest_boundary",
    "unpack_runs",
    "transform_point",
    "nearest_boundary_pixel",
    "run_start",
    "run_end",
    "run_part",
]

_PART_MASK = MAX_PARTS - 1
_COLUMN_BITS = 12  # runs pack start | end << 12 | part << 24: widths up to 4096
_COLUMN_MASK = (1 << _COLUMN_BITS) - 1
_PART_SHIFT = 2 * _COLUMN_BITS
_FAR = 1.0e30


@wp.func
def run_start(packed: wp.int32):
    """First column of a packed boundary run."""
    return int(packed & _COLUMN_MASK)


@wp.func
def run_end(packed: wp.int32):
    """Last column (inclusive) of a packed boundary run."""
    return int((packed >> _COLUMN_BITS) & _COLUMN_MASK)


@wp.func
def run_part(packed: wp.int32):
    """Part label of a packed boundary run."""
    return int(packed >> _PART_SHIFT)


@wp.func
def _pack_run(start: int, end: int, part: int):
    return wp.int32(start | (end << _COLUMN_BITS) | (part << _PART_SHIFT))


@wp.func
def _is_inside(keys: wp.array3d(dtype=wp.int32), p: int, y: int, x: int):
    return keys[p, y, x] != BACKGROUND


@wp.func
def _sum_of_integers(first: wp.int64, last: wp.int64):
    """first + (first + 1) + ... + last, exactly."""
    return (first + last) * (last - first + wp.int64(1)) / wp.int64(2)


@wp.func
def _sum_of_squares(first: wp.int64, last: wp.int64):
    """first^2 + ... + last^2 for 0 <= first <= last, exactly."""
    one = wp.int64(1)
    two = wp.int64(2)
    upper = last * (last + one) * (two * last + one)
    lower = (first - one) * first * (two * first - one)
    return (upper - lower) / wp.int64(6)


@wp.kernel(enable_backward=False)
def _row_scan_kernel(keys: wp.array3d(dtype=wp.int32), runs: wp.array3d(dtype=wp.int32),
                     run_counts: wp.array2d(dtype=wp.int32),
                     row_moments: wp.array2d(dtype=wp.vec3d)):
    p, y = wp.tid()
    height = keys.shape[1]
    width = keys.shape[2]
    edge_row = y == 0 or y == height - 1
    count = int(0)
    pixels = wp.int64(0)
    sum_x = wp.int64(0)
    sum_xx = wp.int64(0)
    first = int(-1)
    last = int(-2)
    part_open = int(-1)
    x = int(0)
    while x < width:
        while x < width and keys[p, y, x] == BACKGROUND:  # skip the background
            x = x + 1
        span_start = x
        while x < width and keys[p, y, x] != BACKGROUND:  # a span of silhouette pixels
            x = x + 1
        span_end = x - 1
        if span_end < span_start:
            break
        lo = wp.int64(span_start)
        hi = wp.int64(span_end)
        pixels = pixels + hi - lo + wp.int64(1)
        sum_x = sum_x + _sum_of_integers(lo, hi)
        sum_xx = sum_xx + _sum_of_squares(lo, hi)
        for c in range(span_start, span_end + 1):
            # span ends, and pixels next to the background above or below, are boundary
            on_boundary = edge_row or c == span_start or c == span_end
            if not on_boundary:
                on_boundary = not _is_inside(keys, p, y - 1, c) or not _is_inside(keys, p, y + 1, c)
            if on_boundary:
                part = int(keys[p, y, c] & _PART_MASK)
                if c == last + 1 and part == part_open:
                    last = c
                else:
                    if part_open >= 0:
                        runs[p, y, count] = _pack_run(first, last, part_open)
                        count = count + 1
                    first = c
                    last = c
                    part_open = part
    if part_open >= 0:
        runs[p, y, count] = _pack_run(first, last, part_open)
        count = count + 1
    run_counts[p, y] = count
    row_moments[p, y] = wp.vec3d(wp.float64(pixels), wp.float64(sum_x), wp.float64(sum_xx))


@wp.func
def transform_point(m: wp.mat33, x: wp.vec2):
    """Apply a 2D affine transform stored as a homogeneous 3x3 matrix."""
    return wp.vec2(m[0, 0] * x[0] + m[0, 1] * x[1] + m[0, 2],
                   m[1, 0] * x[0] + m[1, 1] * x[1] + m[1, 2])


@wp.func
def _row_nearest(runs: wp.array3d(dtype=wp.int32), run_counts: wp.array2d(dtype=wp.int32),
                 p: int, y: int, qx: float, dy2: float, best: wp.vec2):
    """Improve best = (squared distance, part) with the boundary pixels of row y."""
    rx = float(int(wp.floor(qx + 0.5)))
    for i in range(run_counts[p, y]):
        packed = runs[p, y, i]
        start = float(run_start(packed))
        dx = wp.clamp(rx, start, float(run_end(packed))) - qx
        d2 = dx * dx + dy2
        if d2 < best[0]:
            best = wp.vec2(d2, float(run_part(packed)))
        elif start > qx:
            break  # runs are sorted left to right: the rest of the row is farther
    return best


@wp.func
def nearest_boundary_pixel(runs: wp.array3d(dtype=wp.int32),
                           run_counts: wp.array2d(dtype=wp.int32), p: int, q: wp.vec2):
    """(squared distance in px^2, part as a float) of candidate p's boundary pixel nearest
    to q = (column, row); (1e30, -1) when the candidate has no boundary."""
    height = runs.shape[1]
    best = wp.vec2(_FAR, -1.0)
    start_row = int(wp.clamp(wp.floor(q[1] + 0.5), 0.0, float(height - 1)))
    up = start_row
    down = start_row + 1
    while up >= 0 or down < height:
        du = _FAR
        dd = _FAR
        if up >= 0:
            du = wp.abs(q[1] - float(up))
        if down < height:
            dd = wp.abs(float(down) - q[1])
        row = down
        dy = dd
        if du <= dd:
            row = up
            dy = du
            up = up - 1
        else:
            down = down + 1
        if dy * dy >= best[0]:
            break
        best = _row_nearest(runs, run_counts, p, row, q[0], dy * dy, best)
    return best


@wp.kernel(enable_backward=False)
def _nearest_kernel(runs: wp.array3d(dtype=wp.int32), run_counts: wp.array2d(dtype=wp.int32),
                    points: wp.array(dtype=wp.vec2), transforms: wp.array(dtype=wp.mat33),
                    distances: wp.array2d(dtype=wp.float32), parts: wp.array2d(dtype=wp.int32)):
    p, i = wp.tid()
    best = nearest_boundary_pixel(runs, run_counts, p, transform_point(transforms[p], points[i]))
    if best[1] < 0.0:
        distances[p, i] = wp.inf
        parts[p, i] = -1
    else:
        distances[p, i] = wp.sqrt(best[0])
        parts[p, i] = int(best[1])


@dataclasses.dataclass(frozen=True, eq=False)
class BoundaryRuns:
    """The row scan of P candidates' label maps (Warp arrays on one device).

    Attributes:
        runs: (P, H, W) int32; row r's first ``run_counts[p, r]`` entries are its boundary
            runs, packed start | end << 12 | part << 24 (columns, inclusive), left to right.
        run_counts: (P, H) int32.
        row_moments: (P, H) vec3d: (silhouette pixels, sum of their columns, sum of the
            squared columns) per row.
    """

    runs: wp.array
    run_counts: wp.array
    row_moments: wp.array


def allocate_runs(num: int, height: int, width: int, device) -> BoundaryRuns:
    """Uninitialised buffers for the row scan of ``num`` maps of height x width."""
    return BoundaryRuns(wp.empty((num, height, width), dtype=wp.int32, device=device),
                        wp.empty((num, height), dtype=wp.int32, device=device),
                        wp.empty((num, height), dtype=wp.vec3d, device=device))


def launch_row_scan(keys: wp.array, out: BoundaryRuns) -> None:
    """Row-scan checked (P, H, W) int32 keys (``BACKGROUND`` or part in the low bits)."""
    wp.launch(_row_scan_kernel, dim=keys.shape[:2], device=keys.device, inputs=[keys],
              outputs=[out.runs, out.run_counts, out.row_moments])


def launch_nearest(scan: BoundaryRuns, points: wp.array, transforms: wp.array,
                   distances: wp.array, parts: wp.array) -> None:
    """Nearest boundary pixel of every candidate for every (transformed) point, no checks.

    Args:
        points: (N,) vec2 query points, pixels (column, row).
        transforms: (P,) mat33, homogeneous 2D transforms applied to the points per candidate.
        distances: (P, N) float32 output, pixels; inf for a candidate without boundary.
        parts: (P, N) int32 output, the nearest pixel's part; -1 without boundary.
    """
    wp.launch(_nearest_kernel, dim=(scan.runs.shape[0], points.shape[0]),
              device=points.device, inputs=[scan.runs, scan.run_counts, points, transforms],
              outputs=[distances, parts])


def _keys_from_labels(label_maps, device) -> wp.array:
    labels = np.asarray(label_maps)
    dims: dict[str, int] = {}
    device_array("label_maps", labels, ("P", "H", "W"), dims, "int", wp.int32, device)
    if dims["W"] > 1 << _COLUMN_BITS:
        raise ValueError(f"label_maps may be at most {1 << _COLUMN_BITS} pixels wide")
    if labels.size and labels.max() >= MAX_PARTS:
        raise ValueError(f"label_maps must hold -1 (background) or parts in [0, {MAX_PARTS})")
    keys = np.where(labels < 0, BACKGROUND, labels.astype(np.int32))  # depth 0, part in low bits
    return wp.array(keys, dtype=wp.int32, device=device)


def scan_label_maps(label_maps, device: str = "cpu") -> BoundaryRuns:
    """Row-scan label maps: boundary runs and row moments.

    Args:
        label_maps: (P, H, W) int, part labels, -1 for background; W <= 4096.
        device: where to compute.
    """
    dev = resolve_device(device)
    keys = _keys_from_labels(label_maps, dev)
    out = allocate_runs(*keys.shape, dev)
    launch_row_scan(keys, out)
    return out


def nearest_boundary(label_maps, points, device: str = "cpu") -> tuple[np.ndarray, np.ndarray]:
    """Distance to, and part of, each map's boundary pixel nearest to each query point.

    Args:
        label_maps: (P, H, W) int, part labels, -1 for background; W <= 4096.
        points: (N, 2) float, query points, pixels (column, row), in the maps' frame.
        device: where to compute.

    Returns:
        distances: (P, N) float32, pixels (inf for a map without silhouette).
        parts: (P, N) int32, part of the nearest boundary pixel (-1 without silhouette).
    """
    dev = resolve_device(device)
    scan = scan_label_maps(label_maps, dev)
    points = device_array("points", points, ("N", 2), {}, "float", wp.vec2, dev)
    num = scan.runs.shape[0]
    identity = wp.array(np.tile(np.eye(3, dtype=np.float32), (num, 1, 1)), dtype=wp.mat33,
                        device=dev)
    distances = wp.empty((num, points.shape[0]), dtype=wp.float32, device=dev)
    parts = wp.empty((num, points.shape[0]), dtype=wp.int32, device=dev)
    launch_nearest(scan, points, identity, distances, parts)
    return distances.numpy(), parts.numpy()


def unpack_runs(scan: BoundaryRuns) -> np.ndarray:
    """(P, H, W) int8 map of the boundary pixels' parts (-1 elsewhere), from the runs."""
    runs = scan.runs.numpy()
    counts = scan.run_counts.numpy()
    out = np.full(runs.shape, -1, np.int8)
    for p, y in zip(*np.nonzero(counts)):
        for packed in runs[p, y, :counts[p, y]]:
            start, end = packed & _COLUMN_MASK, (packed >> _COLUMN_BITS) & _COLUMN_MASK
            out[p, y, start:end + 1] = packed >> _PART_SHIFT
    return out
