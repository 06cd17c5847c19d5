"""Synthetic studio photos of bodies from the model's space, with their truth.

For the tests and the fitter benchmark (tools/bench_fitter.py): a body whose
measurements are known, photographed so that ``fitter run`` can be checked against them.

Painted by :func:`bodyfit.fitter.render.render_parts` (OpenCV polygons far to near), not
by the kernels, on a plain backdrop. The paper's orthographic projection: the body is
scaled to ``body_px`` pixels tall. The side photo shows the body's left side (facing the
image's left, as a camera at the person's left sees it) without the arms: the model's
four pose angles cannot hang the arms down against the body, so this scene stands for a
side photo whose arms hide within the torso's profile.
"""

from __future__ import annotations

import cv2
import numpy as np

from bodyfit.fitter.body_model import PART_NAMES, forward, rest_shape
from bodyfit.fitter.measurements import Measurer
from bodyfit.fitter.render import render_parts

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


__all__ = ["photo", "write_subject"]


def write_subject(folder, model, betas, pose_deg) -> dict[str, float]:
    """Write front.png and side.png of one body into ``folder``; return its true
    measurements (key -> mm) of the rest body."""
    betas, pose_deg = np.atleast_2d(betas), np.atleast_2d(pose_deg)
    posed = forward(model, betas, pose_deg)[0]
    cv2.imwrite(str(folder / "front.png"), photo(posed, model, "front", PART_NAMES))
    cv2.imwrite(str(folder / "side.png"), photo(posed, model, "side", SIDE_PARTS))
    return Measurer.from_model(model).measure(rest_shape(model, betas)[0][0])
