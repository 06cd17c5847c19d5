"""The person's silhouette in one view, prepared once for the kernels.

Per view, once: the boundary pixels of the person's mask (the points z_i of the paper's
Eq. 15 and 18), the exact Euclidean distance transform of that boundary (for the
model -> person matching direction), and the silhouette's moments
(:class:`bodyfit.kernels.alignment.SilhouetteMoments`: centroid, orientation, top and bottom
points, for the alignment and the paper's highest- and lowest-point terms). Host-side NumPy,
OpenCV and SciPy; the results go to the device once.
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np
import scipy.ndimage as ndi
import warp as wp

from bodyfit.kernels.body_layout import PART_NAMES, POSE_NAMES
from bodyfit.kernels.alignment import SilhouetteMoments, silhouette_moments
from bodyfit.kernels.view_camera import ViewCamera
from bodyfit.kernels.device import resolve_device

__all__ = ["VIEW_NAMES", "SIDE_VIEW_PARTS", "ViewTarget", "prepare_view_target",
           "visible_faces", "visible_vertices", "boundary_mask", "boundary_distance"]

#: The two views of the paper, in the order their weights appear in Table 2.
VIEW_NAMES = ("front", "side")
#: Parts rendered in a side view whose arms are left out (the paper's side photo is taken
#: with the hands against the body, so no arm silhouette appears there): arm, elbow and
#: hand are left out. The other way is to render every part with the arms posed down, see
#: ``prepare_view_target(fixed_pose_deg=...)``.
SIDE_VIEW_PARTS = ("head", "chest", "waist", "hip", "leg", "foot")

def visible_faces(faces: np.ndarray, face_parts: np.ndarray,
                  visible_parts) -> tuple[np.ndarray, np.ndarray]:
    """The (F', 3) faces and (F',) parts of the faces whose part is named in
    ``visible_parts`` (names from ``PART_NAMES``)."""
    keep = np.isin(face_parts, [PART_NAMES.index(name) for name in visible_parts])
    return faces[keep], face_parts[keep]


def visible_vertices(vertex_parts: np.ndarray, visible_parts) -> np.ndarray:
    """(V,) bool: the vertices whose part (``vertex_parts`` (V,), indices into
    ``PART_NAMES``) is named in ``visible_parts``."""
    return np.isin(vertex_parts, [PART_NAMES.index(name) for name in visible_parts])


_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))


def boundary_mask(mask: np.ndarray) -> np.ndarray:
    """(H, W) bool: silhouette pixels with a 4-neighbour outside the silhouette or image.

    Args:
        mask: (H, W) bool silhouette.
    """
    mask = np.asarray(mask, dtype=np.uint8)
    eroded = cv2.erode(mask, _CROSS, borderType=cv2.BORDER_CONSTANT, borderValue=0)
    return (mask > 0) & (eroded == 0)


def boundary_distance(boundary: np.ndarray) -> np.ndarray:
    """(H, W) float32 exact Euclidean distance (pixels) from every pixel centre to the
    nearest True pixel of a (H, W) bool ``boundary``.

    SciPy's exact transform, not OpenCV's: ``cv2.distanceTransform`` is multithreaded and
    its results differ in the last bit from call to call, which would make runs differ.
    """
    return ndi.distance_transform_edt(~np.asarray(boundary, dtype=bool)).astype(np.float32)


@dataclasses.dataclass(frozen=True, eq=False)
class ViewTarget:
    """One view of the person, ready for :class:`bodyfit.kernels.evaluator.PopulationEvaluator`.

    Attributes:
        name: ``"front"`` or ``"side"``; selects the view weight of the cost settings.
        camera: the view's camera; candidates are rendered with it into height x width maps.
        height, width: the person's mask size, pixels.
        millimetres_per_pixel: image scale at the person, to report costs in millimetres.
        visible_parts: the parts rendered for this view (the others are left out of the
            candidates' silhouettes, e.g. the arms in a side photo taken with the hands
            against the body).
        boundary_points: (N,) vec2 Warp array, the person's boundary pixels (column, row).
        boundary_distance: (H, W) float32 Warp array, pixels, exact EDT of that boundary.
        moments: the person's silhouette moments (centroid, orientation, top/bottom points).
        silhouette: (H, W) bool, the person's mask (host copy, for references and overlays).
        fixed_pose_deg: ((pose column, degrees), ...) sorted by column: pose angles this
            view renders every candidate with in place of the candidate's own (e.g. the
            shoulders at the arms-down angle of a side photo); empty: the candidate's pose.
    """

    name: str
    camera: ViewCamera
    height: int
    width: int
    millimetres_per_pixel: float
    visible_parts: tuple[str, ...]
    boundary_points: wp.array
    boundary_distance: wp.array
    moments: SilhouetteMoments
    silhouette: np.ndarray
    fixed_pose_deg: tuple[tuple[int, float], ...] = ()

    def view_pose(self, pose_deg: np.ndarray) -> np.ndarray:
        """(P, 4) float pose this view renders for candidate poses (P, 4) degrees
        (``POSE_NAMES`` order): a copy with the fixed angles put in."""
        pose = np.array(pose_deg, copy=True)
        for column, degrees in self.fixed_pose_deg:
            pose[:, column] = degrees
        return pose


def _fixed_pose(fixed_pose_deg) -> tuple[tuple[int, float], ...]:
    """Checked ``{pose name: degrees}`` as ``ViewTarget.fixed_pose_deg``."""
    fixed = dict(fixed_pose_deg or {})
    unknown = set(fixed) - set(POSE_NAMES)
    if unknown:
        raise ValueError(f"fixed_pose_deg names must be in {POSE_NAMES}, got {sorted(unknown)}")
    checked = []
    for name, degrees in fixed.items():
        try:
            value = float(degrees)
        except (TypeError, ValueError):
            value = math.nan
        if not -180.0 <= value <= 180.0:
            raise ValueError(f"fixed_pose_deg[{name!r}] must be a number of degrees in "
                             f"[-180, 180], got {degrees!r}")
        checked.append((POSE_NAMES.index(name), value))
    return tuple(sorted(checked))


def prepare_view_target(name: str, mask, camera: ViewCamera, millimetres_per_pixel: float,
                        visible_parts=PART_NAMES, device: str = "cpu",
                        fixed_pose_deg=None) -> ViewTarget:
    """Prepare the person's silhouette of one view (boundary, distance transform, moments).

    Args:
        name: ``"front"`` or ``"side"``.
        mask: (H, W) bool, the person's silhouette in the canvas the candidates are
            rendered into (same camera); H, W <= 4096.
        camera: the view's camera.
        millimetres_per_pixel: > 0, image scale at the person.
        visible_parts: names from ``PART_NAMES`` rendered in this view.
        device: where the kernels run.
        fixed_pose_deg: ``{name in POSE_NAMES: degrees}``, angles every candidate is
            rendered with in this view in place of its own (None: its own pose).

    Raises:
        ValueError: an unknown view, part or pose name, a mask that is not 2D bool (or
            0/1), an empty mask, a size outside [1, 4096], a non-positive scale, or a
            fixed angle that is not a finite number in [-180, 180].
    """
    if name not in VIEW_NAMES:
        raise ValueError(f"name must be one of {VIEW_NAMES}, got {name!r}")
    unknown = set(visible_parts) - set(PART_NAMES)
    if unknown or not visible_parts:
        raise ValueError(f"visible_parts must be a non-empty subset of {PART_NAMES}, "
                         f"got {tuple(visible_parts)}")
    mask = np.asarray(mask)
    if mask.ndim != 2 or mask.dtype.kind not in "biu" or (mask.size and mask.max() > 1):
        raise ValueError(f"mask must be a (H, W) bool array, got shape {mask.shape} "
                         f"and dtype {mask.dtype}")
    height, width = mask.shape
    if not (1 <= height <= 4096 and 1 <= width <= 4096):
        raise ValueError(f"mask must be at most 4096 x 4096 pixels, got {mask.shape}")
    if not mask.any():
        raise ValueError("mask is empty: the person's silhouette has no pixel")
    if not millimetres_per_pixel > 0:
        raise ValueError("millimetres_per_pixel must be > 0")
    fixed_pose = _fixed_pose(fixed_pose_deg)
    dev = resolve_device(device)
    mask = mask.astype(bool)
    boundary = boundary_mask(mask)
    rows, cols = np.nonzero(boundary)
    points = np.stack([cols, rows], axis=1).astype(np.float32)
    return ViewTarget(
        name=name, camera=camera, height=height, width=width,
        millimetres_per_pixel=float(millimetres_per_pixel),
        visible_parts=tuple(p for p in PART_NAMES if p in visible_parts),
        boundary_points=wp.array(points, dtype=wp.vec2, device=dev),
        boundary_distance=wp.array(boundary_distance(boundary), dtype=wp.float32, device=dev),
        moments=silhouette_moments(mask),
        silhouette=mask,
        fixed_pose_deg=fixed_pose)
