"""The person's silhouettes on the kernels' canvases, with the paper's orthographic cameras.

The kernels render every candidate body of a search into one canvas per view and compare
it with the person's silhouette there (:mod:`bodyfit.kernels`). This module makes those
canvases from the person's masks:

- **Scale from the stature** (the paper, Section 3.3): the person's silhouette is
  ``stature`` tall, so the canvas holds ``pixels_per_metre = body_height_px / stature_m``
  and the mask is resized so that the person is ``body_height_px`` pixels tall (area
  resampling of the 0/1 mask, cut at one half: the outline keeps sub-pixel accuracy).
  Each view is scaled on its own, so the person's distance to the camera need not be
  known; a photo's perspective is not modelled (the orthographic approximation: at
  2.5-3.5 m a phone's perspective makes near parts a few per cent larger).
- **Room for every candidate**: the canvas covers the model's extent over the search's
  bound (``SearchSettings.beta_limit``, 3 sigma) of each shape component and the whole
  pose range (both ends at once), plus a margin, so no candidate is cut by the canvas
  edge (docs/kernels.md, Known limits). The model's
  origin is put where that extent fits; the person's silhouette is centred on where the
  mean body lands, and the kernels' alignment moves each candidate onto it.

Frames: photo and canvas pixels are (column, row) with OpenCV's centre convention; the
model frame is metres, z up, the body facing -y.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from bodyfit import kernels
from bodyfit.common.errors import UserError
from bodyfit.fitter.model.body_model import PART_NAMES, BodyModel, forward
from bodyfit.kernels.view_camera import camera_matrices

__all__ = ["CanvasSettings", "PAPER_CANVAS", "extreme_bodies", "orthographic_view", "scaled_person"]

#: The parts each view renders: the side photo is taken with the arms hanging against
#: the body, which the model's four pose angles cannot reproduce (kernels.SIDE_VIEW_PARTS).
VIEW_PARTS = {"front": PART_NAMES, "side": kernels.SIDE_VIEW_PARTS}
_VIEW_DEG = {"front": kernels.FRONT_VIEW_DEG, "side": kernels.SIDE_VIEW_DEG}


@dataclasses.dataclass(frozen=True)
class CanvasSettings:
    """Canvas geometry.

    Attributes:
        body_height_px: the person's height on the canvas, pixels. 600 (bodyfit's
            default): about a phone photo's own resolution of a person 2.5-3.5 m away;
            on the accuracy benchmark's first 10 in-space subjects 400 missed the 7
            important measurements by 5.1 mm, 600 and 800 by 3.6 (docs/history.md). The
            paper's canvases are 512 px high (:data:`PAPER_CANVAS`: 400 px of body leaves
            room for taller candidates).
        margin_px: free pixels around the largest candidate.

    The candidates' room is the search's: :func:`extreme_bodies` at
    ``SearchSettings.beta_limit``.
    """

    body_height_px: int = 600
    margin_px: int = 6

    def validate(self) -> None:
        if not 32 <= self.body_height_px <= 2048:
            raise UserError(f"the canvas body height must be 32-2048 px, got {self.body_height_px}")


#: The paper's canvas: 512 px high, the person 400 px of it (``--method paper``).
PAPER_CANVAS = CanvasSettings(body_height_px=400)


def extreme_bodies(model: BodyModel, num_components: int, pose_lower, pose_upper,
                   beta_limit: float = 3.0) -> np.ndarray:
    """(B, V, 3) float32 posed bodies, metres, that bound every candidate the search may
    ask for: the mean body and, for each of the first ``num_components`` components at
    +-``beta_limit`` sigma, the body with every pose angle at its lower and at its upper
    bound (B = 2 (2 K + 1)). A candidate's silhouette lies within the extent of their
    vertices up to the interactions of several components, which the canvas margin
    absorbs; the stature conditioning takes its highest and lowest vertices from them.
    """
    k = num_components
    betas = np.concatenate([np.zeros((1, k)), beta_limit * np.eye(k), -beta_limit * np.eye(k)])
    poses = [np.broadcast_to(np.asarray(p, np.float64), (len(betas), 4))
             for p in (pose_lower, pose_upper)]
    return np.concatenate([forward(model, betas, pose) for pose in poses]).astype(np.float32)


def _project(camera, points: np.ndarray) -> np.ndarray:
    """(N, 2) pixel coordinates of model-frame points under an orthographic camera."""
    k, r, t = camera_matrices(camera)
    cam = points.astype(np.float64) @ r.T + t
    return cam[:, :2] @ k[:2, :2].T + k[:2, 2]


def scaled_person(mask: np.ndarray, scale: float) -> np.ndarray:
    """The person's bounding box of a (H, W) bool ``mask`` resized by ``scale``: (h, w) bool,
    area resampling cut at one half. The scale is exactly ``scale`` both ways (OpenCV keeps
    ``fx``/``fy``; a size rounded per axis would stretch the person by up to half a pixel)."""
    rows, cols = np.nonzero(mask)
    crop = mask[rows.min():rows.max() + 1, cols.min():cols.max() + 1].astype(np.float32)
    return cv2.resize(crop, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA) > 0.5


def orthographic_view(name: str, mask: np.ndarray, stature_m: float, extent: np.ndarray,
                      mean_body: np.ndarray, settings: CanvasSettings = CanvasSettings(),
                      device: str = "cpu", **view_options) -> kernels.ViewTarget:
    """One view of the person on a canvas with the paper's orthographic camera.

    Args:
        name: ``"front"`` or ``"side"``.
        mask: (H, W) bool, the person's silhouette in the (undistorted, upright) photo.
        stature_m: the person's stature, metres.
        extent: (M, 3) float32 metres, the vertices of :func:`extreme_bodies`.
        mean_body: (V, 3) float32 metres, the mean body in its default pose.
        settings: canvas geometry.
        device: where the kernels run.
        view_options: ``visible_parts`` (default ``VIEW_PARTS[name]``) and
            ``fixed_pose_deg`` of ``kernels.prepare_view_target`` (the side view's arms,
            :func:`bodyfit.fitter.fit.side_arms.side_view_options`).

    Returns:
        The kernels' target; its camera renders candidates at the person's scale.
    """
    rows = np.flatnonzero(mask.any(axis=1))
    person_px = rows[-1] - rows[0] + 1
    pixels_per_metre = settings.body_height_px / stature_m
    person = scaled_person(mask, settings.body_height_px / person_px)
    origin = kernels.orthographic_camera(_VIEW_DEG[name], pixels_per_metre, (0.0, 0.0))
    bound = _project(origin, extent)
    mean_px = _project(origin, mean_body)
    # the person's box, centred on the mean body's box, must fit as well as the extent
    centre = (mean_px.min(axis=0) + mean_px.max(axis=0)) / 2
    half = np.array(person.shape[::-1]) / 2
    low = np.minimum(bound.min(axis=0), centre - half) - settings.margin_px
    high = np.maximum(bound.max(axis=0), centre + half) + settings.margin_px
    width, height = (np.ceil(high - low)).astype(int) + 1
    camera = kernels.orthographic_camera(_VIEW_DEG[name], pixels_per_metre, -low)
    canvas = np.zeros((height, width), bool)
    top, left = np.round(centre - low - half).astype(int)[::-1]
    canvas[top:top + person.shape[0], left:left + person.shape[1]] = person
    view_options = {"visible_parts": VIEW_PARTS[name]} | view_options
    return kernels.prepare_view_target(name, canvas, camera, 1000.0 / pixels_per_metre,
                                       device=device, **view_options)
