"""Synthetic studio photos of bodies from the model's space, with their truth.

For the tests and the fitter benchmark (tools/bench_fitter.py): a body whose
measurements are known, photographed so that ``fitter run`` can be checked against them.

Painted by :func:`bodyfit.fitter.render.render_parts` (OpenCV polygons far to near), not
by the kernels, on a plain backdrop. The paper's orthographic projection: the body is
scaled to ``body_px`` pixels tall. The front photo shows the body in its pose (an
A-pose). The side photo shows the body's left side (facing the image's left, as a camera
at the person's left sees it), with ``side_arms``:

- ``"down"`` (default, as users photograph it): the arms hang straight down, the
  shoulders at the body's own arms-down angle
  (:func:`bodyfit.fitter.side_arms.side_photo_pose`), rendered with the arms, which show
  in front of and beside the torso's profile;
- ``"hidden"``: the body in the front photo's pose without arm, elbow and hand: a side
  photo whose arms hide within the torso's profile.
"""

from __future__ import annotations

import cv2
import numpy as np

from bodyfit.fitter.body_model import PART_NAMES, forward, rest_shape
from bodyfit.fitter.measurements import Measurer
from bodyfit.fitter.render import render_parts
from bodyfit.fitter.side_arms import side_photo_pose

BACKDROP_BGR = (170, 185, 200)
SIDE_PARTS = ("head", "chest", "waist", "hip", "leg", "foot")


def photo(vertices, model, view: str, parts, body_px: int = 700,
          size_px: tuple[int, int] = (600, 800)) -> np.ndarray:
    """(H, W, 3) uint8 BGR photo of posed ``vertices`` (V, 3) metres, one view."""
    keep = np.isin(model.face_parts, [PART_NAMES.index(p) for p in parts])
    image = render_parts(vertices, model.faces[keep], model.face_parts[keep], view, body_px,
                         margin_px=0)
    if view == "side":  # render_parts draws the side view mirrored
        image = image[:, ::-1]
    width, height = size_px
    canvas = np.full((height, width, 3), BACKDROP_BGR, np.uint8)
    h, w = image.shape[:2]
    top, left = (height - h) // 2, (width - w) // 2
    body = image.min(axis=2) < 250
    canvas[top:top + h, left:left + w][body] = image[body]
    return canvas


__all__ = ["SIDE_ARMS", "photo", "write_subject"]


SIDE_ARMS = ("down", "hidden")


def write_subject(folder, model, betas, pose_deg, side_arms: str = "down") -> dict[str, float]:
    """Write front.png and side.png of one body into ``folder``; return its true
    measurements (key -> mm) of the rest body.

    Args:
        folder: an existing folder (``pathlib.Path``).
        betas: (K,) shape coefficients, sigma.
        pose_deg: (4,) front photo's abduction angles, degrees, ``POSE_NAMES`` order.
        side_arms: ``"down"`` or ``"hidden"`` (module docstring).
    """
    if side_arms not in SIDE_ARMS:
        raise ValueError(f"side_arms must be one of {SIDE_ARMS}, got {side_arms!r}")
    betas, pose_deg = np.atleast_2d(betas), np.atleast_2d(pose_deg)
    posed = forward(model, betas, pose_deg)[0]
    cv2.imwrite(str(folder / "front.png"), photo(posed, model, "front", PART_NAMES))
    if side_arms == "down":
        side_pose = side_photo_pose(model, betas[0], pose_deg[0])[None]
        side = photo(forward(model, betas, side_pose)[0], model, "side", PART_NAMES)
    else:
        side = photo(posed, model, "side", SIDE_PARTS)
    cv2.imwrite(str(folder / "side.png"), side)
    return Measurer.from_model(model).measure(rest_shape(model, betas)[0][0])
