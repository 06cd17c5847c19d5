"""Where the board corners fell across the frame: a picture and a number.

Distortion grows towards the frame's edges and corners, so a calibration is only as
good there as the corners it saw there. The frame is split into a grid of
``COVERAGE_GRID`` cells; the coverage fraction is the share of cells holding at least
one corner of a used view, and the picture shows every used view's corners in its own
colour over that grid, empty cells tinted red.
"""

from __future__ import annotations

import cv2
import numpy as np

from bodyfit.calib.capture import View, ViewStatus

__all__ = ["COVERAGE_GRID", "coverage_fraction", "coverage_picture"]

COVERAGE_GRID = (8, 6)  # cells across, cells down
_PICTURE_WIDTH_PX = 1200


def _used_points(views: list[View]) -> list[np.ndarray]:
    return [view.detection.image_points for view in views if view.status is ViewStatus.USED]


def _occupied_cells(points: list[np.ndarray], image_size_px: tuple[int, int]) -> np.ndarray:
    """(rows, cols) bool: grid cells holding at least one corner."""
    columns, rows = COVERAGE_GRID
    width, height = image_size_px
    occupied = np.zeros((rows, columns), bool)
    if points:
        allpoints = np.concatenate(points)
        cx = np.clip((allpoints[:, 0] / width * columns).astype(int), 0, columns - 1)
        cy = np.clip((allpoints[:, 1] / height * rows).astype(int), 0, rows - 1)
        occupied[cy, cx] = True
    return occupied


def coverage_fraction(views: list[View], image_size_px: tuple[int, int]) -> float:
    """Share (0..1) of the frame's grid cells that hold a corner of a used view."""
    return float(_occupied_cells(_used_points(views), image_size_px).mean())


def coverage_picture(views: list[View], image_size_px: tuple[int, int]) -> np.ndarray:
    """(H', W', 3) uint8 BGR picture of the frame, 1200 pixels wide, with the used corners.

    Each used view's corners are dots joined by their convex hull, one colour per view;
    grid cells without any corner are tinted red.
    """
    width, height = image_size_px
    scale = _PICTURE_WIDTH_PX / width
    size = (_PICTURE_WIDTH_PX, max(1, round(height * scale)))
    picture = np.full((size[1], size[0], 3), 40, np.uint8)
    points = _used_points(views)
    occupied = _occupied_cells(points, image_size_px)
    columns, rows = COVERAGE_GRID
    for row in range(rows):
        for column in range(columns):
            top_left = (round(column * size[0] / columns), round(row * size[1] / rows))
            bottom_right = (round((column + 1) * size[0] / columns) - 1, round((row + 1) * size[1] / rows) - 1)
            if not occupied[row, column]:
                cv2.rectangle(picture, top_left, bottom_right, (40, 40, 120), cv2.FILLED)
            cv2.rectangle(picture, top_left, bottom_right, (90, 90, 90), 1)
    for index, view_points in enumerate(points):
        hue = int(180 * index / max(1, len(points)))
        colour = cv2.cvtColor(np.uint8([[[hue, 200, 255]]]), cv2.COLOR_HSV2BGR)[0, 0].tolist()
        scaled = view_points * scale
        hull = cv2.convexHull(scaled.reshape(-1, 1, 2)).round().astype(np.int32)
        cv2.polylines(picture, [hull], True, colour, 1, cv2.LINE_AA)
        for x, y in scaled.round().astype(int):
            cv2.circle(picture, (int(x), int(y)), 2, colour, cv2.FILLED, cv2.LINE_AA)
    label = f"{len(points)} views, {occupied.sum()} of {occupied.size} cells covered"
    cv2.putText(picture, label, (10, size[1] - 12), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 1, cv2.LINE_AA)
    return picture
