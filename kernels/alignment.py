"""Alignment of every candidate's silhouette to the person's, before scoring.

The paper normalises both contours and registers them rigidly (rotation + translation,
ICP with a KD-tree; Section 3.3, Eq. 13-16). Here the scale is already shared: the
person's image is scaled from the known stature and candidates are rendered at that
scale, so a candidate's height error stays visible to the cost. What is left, the rigid
transform, comes in closed form from the two silhouettes' moments (:class:`SilhouetteMoments`):

    translation: the person's centroid goes to the candidate's centroid;
    rotation:    the person's principal axis turns onto the candidate's principal axis.

The vertical shift can instead match the middle of the top and bottom rows
(``vertical_anchor="extremes"``): for candidates as tall as the person (the fitter
conditions them on the stature) this keeps the top and bottom terms from rewarding a
candidate for moving its mass up or down.

This is exact for a silhouette that is a rotated and shifted copy of the other, costs
one pass over per-row sums per candidate, and needs no iterations (ICP needs a
nearest-neighbour pass per iteration). With ``align_rotation`` off only the translation is
used (for photos known to be level). The CPU ICP of the paper, for overlays, is
:mod:`bodyfit.fitter.fit.contour`.

Transforms map person pixels (column, row) to candidate pixels: x = R (z - c_person) +
c_candidate, stored as homogeneous (3, 3) matrices.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import warp as wp

from bodyfit.kernels.boundary import scan_label_maps
from bodyfit.kernels.device import resolve_device

__all__ = [
    "VERTICAL_ANCHORS",
    "anchors_on_extremes",
    "SilhouetteMoments",
    "WarpSilhouetteMoments",
    "silhouette_moments",
    "rigid_transform",
    "launch_alignment",
    "align_label_maps",
]


#: How candidates are shifted vertically onto the person (:func:`launch_alignment`).
VERTICAL_ANCHORS = ("centroid", "extremes")


def anchors_on_extremes(vertical_anchor: str) -> bool:
    """Whether ``vertical_anchor`` is ``"extremes"``; ValueError unless one of
    ``VERTICAL_ANCHORS``."""
    if vertical_anchor not in VERTICAL_ANCHORS:
        raise ValueError(f"vertical_anchor must be one of {VERTICAL_ANCHORS}, "
                         f"got {vertical_anchor!r}")
    return vertical_anchor == "extremes"


@wp.struct
class WarpSilhouetteMoments:
    """:class:`SilhouetteMoments` as a Warp struct, for the kernels (float32, no area): the
    person's, which every candidate of a view is aligned to.

    Attributes:
        centroid: pixels (column, row).
        orientation2: twice the principal-axis angle, radians, atan2(2 mu11, mu20 - mu02)
            (doubled so that it is continuous for an upright body).
        top: the highest silhouette point: mean column of the top row, and that row.
        bottom: the lowest silhouette point, likewise.
    """

    centroid: wp.vec2
    orientation2: float
    top: wp.vec2
    bottom: wp.vec2


@dataclasses.dataclass(frozen=True)
class SilhouetteMoments:
    """A silhouette's moments: what aligns a candidate to the person (host side, float64).

    bodyfit's one name for this summary of a silhouette: its area (zeroth moment),
    centroid (first moments) and principal-axis orientation (second central moments),
    plus its top and bottom points (for the alignment check and the cost's highest- and
    lowest-point terms). :func:`silhouette_moments` computes it from a mask; the kernels
    compute the candidates' from the row scan's ``row_moments``.

    Attributes:
        area_px: number of silhouette pixels (0: empty, the rest is meaningless).
        centroid: (2,) pixels (column, row).
        orientation2: radians, see :class:`WarpSilhouetteMoments`.
        top, bottom: (2,) pixels (column, row).
    """

    area_px: float
    centroid: np.ndarray
    orientation2: float
    top: np.ndarray
    bottom: np.ndarray

    def to_warp(self) -> WarpSilhouetteMoments:
        moments = WarpSilhouetteMoments()
        moments.centroid = wp.vec2(*self.centroid)
        moments.orientation2 = float(self.orientation2)
        moments.top = wp.vec2(*self.top)
        moments.bottom = wp.vec2(*self.bottom)
        return moments


def silhouette_moments(mask: np.ndarray) -> SilhouetteMoments:
    """Centroid, principal-axis orientation and top/bottom points of a (H, W) bool mask."""
    mask = np.asarray(mask, dtype=bool)
    rows, cols = np.nonzero(mask)
    if rows.size == 0:
        zero = np.zeros(2)
        return SilhouetteMoments(0.0, zero, 0.0, zero, zero)
    x, y = cols.astype(np.float64), rows.astype(np.float64)
    cx, cy = x.mean(), y.mean()
    mu20, mu02, mu11 = ((x - cx) ** 2).sum(), ((y - cy) ** 2).sum(), ((x - cx) * (y - cy)).sum()
    top, bottom = rows.min(), rows.max()
    return SilhouetteMoments(
        float(rows.size), np.array([cx, cy]), float(np.arctan2(2 * mu11, mu20 - mu02)),
        np.array([x[rows == top].mean(), top]), np.array([x[rows == bottom].mean(), bottom]))


def rigid_transform(candidate: SilhouetteMoments, target: SilhouetteMoments,
                    align_rotation: bool, vertical_anchor: str = "centroid") -> np.ndarray:
    """(3, 3) float64 homogeneous transform from person pixels to candidate pixels
    (``vertical_anchor`` as in :func:`launch_alignment`)."""
    delta = 0.0
    if align_rotation:
        d2 = candidate.orientation2 - target.orientation2
        delta = 0.5 * np.arctan2(np.sin(d2), np.cos(d2))
    rot = np.array([[np.cos(delta), -np.sin(delta)], [np.sin(delta), np.cos(delta)]])
    out = np.eye(3)
    out[:2, :2] = rot
    out[:2, 2] = candidate.centroid - rot @ target.centroid
    if anchors_on_extremes(vertical_anchor):
        person_mid = np.array([target.centroid[0], (target.top[1] + target.bottom[1]) / 2])
        moved = rot @ person_mid + out[:2, 2]
        out[1, 2] += (candidate.top[1] + candidate.bottom[1]) / 2 - moved[1]
    return out


@wp.kernel(enable_backward=False)
def _align_kernel(row_moments: wp.array2d(dtype=wp.vec3d), target: WarpSilhouetteMoments,
                  align_rotation: int, anchor_extremes: int, transforms: wp.array(dtype=wp.mat33),
                  extremes: wp.array2d(dtype=wp.vec2), areas: wp.array(dtype=wp.float32)):
    p = wp.tid()
    height = row_moments.shape[1]
    n = wp.float64(0.0)
    sx = wp.float64(0.0)
    sy = wp.float64(0.0)
    sxx = wp.float64(0.0)
    syy = wp.float64(0.0)
    sxy = wp.float64(0.0)
    top = wp.vec2(0.0, 0.0)
    bottom = wp.vec2(0.0, 0.0)
    for y in range(height):
        m = row_moments[p, y]
        if m[0] > wp.float64(0.0):
            yy = wp.float64(y)
            mean_x = wp.float32(m[1] / m[0])
            if n == wp.float64(0.0):
                top = wp.vec2(mean_x, float(y))
            bottom = wp.vec2(mean_x, float(y))
            n = n + m[0]
            sx = sx + m[1]
            sy = sy + yy * m[0]
            sxx = sxx + m[2]
            syy = syy + yy * yy * m[0]
            sxy = sxy + yy * m[1]
    areas[p] = wp.float32(n)
    extremes[p, 0] = top
    extremes[p, 1] = bottom
    if n == wp.float64(0.0):
        transforms[p] = wp.identity(n=3, dtype=wp.float32)
        return
    cx = sx / n
    cy = sy / n
    mu20 = sxx - n * cx * cx
    mu02 = syy - n * cy * cy
    mu11 = sxy - n * cx * cy
    delta = float(0.0)
    if align_rotation != 0:
        d2 = wp.float32(wp.atan2(wp.float64(2.0) * mu11, mu20 - mu02)) - target.orientation2
        delta = 0.5 * wp.atan2(wp.sin(d2), wp.cos(d2))
    cs = wp.cos(delta)
    sn = wp.sin(delta)
    c = target.centroid
    tx = wp.float32(cx) - (cs * c[0] - sn * c[1])
    ty = wp.float32(cy) - (sn * c[0] + cs * c[1])
    if anchor_extremes != 0:
        person_mid = 0.5 * (target.top[1] + target.bottom[1])
        moved = sn * c[0] + cs * person_mid + ty
        ty = ty + 0.5 * (top[1] + bottom[1]) - moved
    transforms[p] = wp.mat33(cs, -sn, tx, sn, cs, ty, 0.0, 0.0, 1.0)


def launch_alignment(row_moments: wp.array, target: WarpSilhouetteMoments, align_rotation: bool,
                     transforms: wp.array, extremes: wp.array, areas: wp.array,
                     vertical_anchor: str = "centroid") -> None:
    """Align every candidate to the person (no checks, no allocation).

    Args:
        row_moments: (P, H) vec3d from the row scan (:mod:`bodyfit.kernels.boundary`).
        target: the person's silhouette moments in this view.
        align_rotation: also rotate (else translate only).
        vertical_anchor: ``"centroid"`` (the moments: the person's centroid goes to the
            candidate's) or ``"extremes"``: the vertical shift instead puts the middle of
            the person's top and bottom rows on the middle of the candidate's, so a
            candidate as tall as the person matches its top and bottom rows whatever its
            mass distribution (the horizontal shift stays the centroid's).
        transforms: (P,) mat33 output, person pixels -> candidate pixels.
        extremes: (P, 2) vec2 output, the candidate's top and bottom points, its pixels.
        areas: (P,) float32 output, silhouette pixels (0 = empty silhouette).
    """
    wp.launch(_align_kernel, dim=row_moments.shape[0], device=row_moments.device,
              inputs=[row_moments, target, int(align_rotation),
                      int(anchors_on_extremes(vertical_anchor))],
              outputs=[transforms, extremes, areas])


def align_label_maps(label_maps, target: SilhouetteMoments, align_rotation: bool = True,
                     device: str = "cpu", vertical_anchor: str = "centroid"
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Align candidates' label maps to the person's silhouette.

    Args:
        label_maps: (P, H, W) int, part labels, -1 for background.
        target: the person's :func:`silhouette_moments`.
        align_rotation: also rotate (else translate only).
        vertical_anchor: as in :func:`launch_alignment`.
        device: where to compute.

    Returns:
        transforms: (P, 3, 3) float32, person pixels -> candidate pixels (homogeneous).
        extremes: (P, 2, 2) float32, each candidate's top and bottom points (column, row).
        areas: (P,) float32, silhouette pixels.
    """
    dev = resolve_device(device)
    scan = scan_label_maps(label_maps, dev)
    num = scan.runs.shape[0]
    transforms = wp.empty(num, dtype=wp.mat33, device=dev)
    extremes = wp.empty((num, 2), dtype=wp.vec2, device=dev)
    areas = wp.empty(num, dtype=wp.float32, device=dev)
    launch_alignment(scan.row_moments, target.to_warp(), align_rotation, transforms, extremes,
                     areas, vertical_anchor)
    return transforms.numpy(), extremes.numpy(), areas.numpy()
