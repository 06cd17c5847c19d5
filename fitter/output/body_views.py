"""The fitted body from several angles, shaded, for the report.

Each view is :func:`bodyfit.fitter.output.render.render_colours` of the body turned about
the vertical axis and seen from the front: one even colour, shaded by how squarely each
triangle faces the viewer, so that the shape reads as a sculpture would.
"""

from __future__ import annotations

import cv2
import numpy as np

from bodyfit.fitter.output.render import render_colours

__all__ = ["BODY_BGR", "VIEW_TURNS_DEG", "body_views_image"]

#: The angles the body is shown from: the turn of the body about its vertical axis,
#: degrees (positive turns its left side towards the viewer).
VIEW_TURNS_DEG = {"front": 0.0, "three-quarter": 45.0, "side": 90.0}
#: The body's colour, BGR (a light clay).
BODY_BGR = (170, 190, 215)


def _turned(vertices: np.ndarray, degrees: float) -> np.ndarray:
    """(V, 3) vertices turned about the z axis through their centre: +x (the body's left)
    turns towards -y (the viewer of a front view)."""
    angle = np.deg2rad(degrees)
    turn = np.array([[np.cos(angle), np.sin(angle), 0.0], [-np.sin(angle), np.cos(angle), 0.0],
                     [0.0, 0.0, 1.0]])
    centre = vertices.mean(axis=0) * [1.0, 1.0, 0.0]
    return (vertices - centre) @ turn.T + centre


def body_views_image(vertices: np.ndarray, faces: np.ndarray, height_px: int = 480
                     ) -> np.ndarray:
    """(height_px + 30, W, 3) uint8 BGR: the body of ``vertices`` ((V, 3) metres, model
    frame) from each angle of :data:`VIEW_TURNS_DEG`, side by side on white, each titled."""
    colours = np.tile(np.array(BODY_BGR, np.float64), (len(faces), 1))
    panels = []
    for name, degrees in VIEW_TURNS_DEG.items():
        picture = render_colours(_turned(np.asarray(vertices, np.float64), degrees), faces,
                                 colours, "front", height_px)
        panel = np.full((height_px + 30, max(picture.shape[1], 150), 3), 255, np.uint8)
        left = (panel.shape[1] - picture.shape[1]) // 2
        panel[30:, left:left + picture.shape[1]] = picture
        cv2.putText(panel, name, (8, 21), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 0), 1,
                    cv2.LINE_AA)
        panels.append(panel)
    return np.hstack(panels)
