"""Where the board corners fell across the frame: a picture and a number.

Distortion grows towards the frame's edges and corners, so a calibration is only as
good there as the corners it saw there. The frame is split into a grid of
``COVERAGE_GRID`` cells; the coverage fraction is the share of cells holding at least
one corner of a used view, and the picture shows every used view's corners in its own
colour over that grid, empty cells tinted red, with a legend below the frame.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from bodyfit.calib.capture import BoardView, BoardViewStatus

__all__ = ["COVERAGE_GRID", "coverage_fraction", "coverage_picture"]

COVERAGE_GRID = (8, 6)  # cells across, cells down
_PICTURE_WIDTH_PX = 1200
_EMPTY_CELL = (40, 40, 140)  # BGR: red tint
_GRID_LINE = (90, 90, 90)
_LEGEND_LINE_PX = 24
_LEGEND_COLUMNS = 4  # view entries per legend line


def _used_points(views: list[BoardView]) -> list[np.ndarray]:
    return [view.detection.image_points for view in views if view.status is BoardViewStatus.USED]


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


def coverage_fraction(views: list[BoardView], image_size_px: tuple[int, int]) -> float:
    """Share (0..1) of the frame's grid cells that hold a corner of a used view."""
    return float(_occupied_cells(_used_points(views), image_size_px).mean())


def _view_colour(index: int, count: int) -> tuple[int, int, int]:
    """BGR colour of the ``index``-th of ``count`` views: hues spread around the circle."""
    hue = int(180 * index / max(1, count))
    return tuple(cv2.cvtColor(np.uint8([[[hue, 200, 255]]]), cv2.COLOR_HSV2BGR)[0, 0].tolist())


def _frame_picture(points: list[np.ndarray], occupied: np.ndarray, size: tuple[int, int], scale: float) -> np.ndarray:
    """(size[1], size[0], 3) uint8: the frame's grid, empty cells tinted red, each view's corners
    and outline in its colour, with its number (as in the legend) at the corners' centre."""
    picture = np.full((size[1], size[0], 3), 40, np.uint8)
    columns, rows = COVERAGE_GRID
    for row in range(rows):
        for column in range(columns):
            top_left = (round(column * size[0] / columns), round(row * size[1] / rows))
            bottom_right = (round((column + 1) * size[0] / columns) - 1, round((row + 1) * size[1] / rows) - 1)
            if not occupied[row, column]:
                cv2.rectangle(picture, top_left, bottom_right, _EMPTY_CELL, cv2.FILLED)
            cv2.rectangle(picture, top_left, bottom_right, _GRID_LINE, 1)
    for index, view_points in enumerate(points):
        colour = _view_colour(index, len(points))
        scaled = view_points * scale
        hull = cv2.convexHull(scaled.reshape(-1, 1, 2)).round().astype(np.int32)
        cv2.polylines(picture, [hull], True, colour, 1, cv2.LINE_AA)
        for x, y in scaled.round().astype(int):
            cv2.circle(picture, (int(x), int(y)), 2, colour, cv2.FILLED, cv2.LINE_AA)
    for index, view_points in enumerate(points):  # numbers last, over every view's dots
        centre = tuple(int(v) for v in (view_points * scale).mean(axis=0).round())
        cv2.putText(picture, str(index + 1), centre, cv2.FONT_HERSHEY_SIMPLEX, 0.8, (0, 0, 0), 4, cv2.LINE_AA)
        cv2.putText(
            picture, str(index + 1), centre, cv2.FONT_HERSHEY_SIMPLEX, 0.8, _view_colour(index, len(points)), 2,
            cv2.LINE_AA,
        )
    return picture


def _text(picture: np.ndarray, text: str, origin: tuple[int, int], colour=(230, 230, 230)) -> None:
    cv2.putText(picture, text, origin, cv2.FONT_HERSHEY_SIMPLEX, 0.5, colour, 1, cv2.LINE_AA)


def _legend(names: list[str], occupied: np.ndarray, width: int) -> np.ndarray:
    """(H, width, 3) uint8 panel: the coverage line, what the red cells and the grid mean,
    and one swatch per view (dots and outline of that view's corners) with its number and name."""
    per_row = _LEGEND_COLUMNS
    entry_width = width // per_row
    view_rows = -(-len(names) // per_row)
    panel = np.full(((3 + view_rows) * _LEGEND_LINE_PX + 10, width, 3), 25, np.uint8)
    columns, rows = COVERAGE_GRID
    _text(
        panel,
        f"{len(names)} views, {occupied.sum()} of {occupied.size} cells covered ({occupied.mean():.0%})",
        (10, _LEGEND_LINE_PX - 6),
    )
    line = 2 * _LEGEND_LINE_PX
    cv2.rectangle(panel, (10, line - 14), (34, line - 2), _EMPTY_CELL, cv2.FILLED)
    cv2.rectangle(panel, (10, line - 14), (34, line - 2), _GRID_LINE, 1)
    _text(
        panel,
        f"cell with no corner: add views there. Grid: the frame in {columns}x{rows} cells. "
        "Dots: a view's corners, outline: its board",
        (44, line - 4),
    )
    for index, name in enumerate(names):
        x = 10 + (index % per_row) * entry_width
        y = (3 + index // per_row) * _LEGEND_LINE_PX
        colour = _view_colour(index, len(names))
        cv2.rectangle(panel, (x, y - 14), (x + 24, y - 2), colour, 1, cv2.LINE_AA)
        cv2.circle(panel, (x + 12, y - 8), 3, colour, cv2.FILLED, cv2.LINE_AA)
        label = f"{index + 1}: {name}"
        max_chars = (entry_width - 44) // 9
        if len(label) > max_chars:
            label = label[: max_chars - 3] + "..."
        _text(panel, label, (x + 32, y - 4), colour)
    return panel


def coverage_picture(views: list[BoardView], image_size_px: tuple[int, int]) -> np.ndarray:
    """(H', 1200, 3) uint8 BGR picture of the frame with the used corners, and a legend below.

    Each used view's corners are dots joined by their convex hull, one colour per view;
    grid cells without any corner are tinted red. The legend under the frame names every
    used view in its colour, says what the red cells and the grid are, and gives the
    share of cells covered.
    """
    width, height = image_size_px
    scale = _PICTURE_WIDTH_PX / width
    size = (_PICTURE_WIDTH_PX, max(1, round(height * scale)))
    used = [view for view in views if view.status is BoardViewStatus.USED]
    points = _used_points(used)
    occupied = _occupied_cells(points, image_size_px)
    frame = _frame_picture(points, occupied, size, scale)
    names = [Path(view.source).name + ("" if view.frame_index is None else f"@{view.frame_index}") for view in used]
    return np.vstack([frame, _legend(names, occupied, _PICTURE_WIDTH_PX)])
