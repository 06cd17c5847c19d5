"""Small line charts drawn with OpenCV (no plotting library needed at run time)."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["line_chart"]

_COLOURS_BGR = ((200, 90, 20), (30, 140, 240), (60, 160, 60), (40, 40, 200))
_FONT = cv2.FONT_HERSHEY_SIMPLEX


def _ticks(low: float, high: float, count: int = 5) -> np.ndarray:
    """Round tick values covering [low, high]."""
    step = (high - low) / max(1, count)
    magnitude = 10 ** np.floor(np.log10(step)) if step > 0 else 1.0
    step = min((m * magnitude for m in (1, 2, 5, 10) if m * magnitude >= step),
               default=10 * magnitude)
    return np.arange(np.ceil(low / step) * step, high + step / 2, step)


def _ink_width(text: str, scale: float) -> int:
    """Pixels from ``text``'s first to its last inked column as ``cv2.putText`` draws it in
    ``_FONT`` at ``scale`` (OpenCV 5 draws its own font, in steps of size, not as
    ``cv2.getTextSize`` says)."""
    size = cv2.getTextSize(text, _FONT, scale, 1)[0]
    scratch = np.zeros((3 * size[1] + 8, 3 * size[0] + 8), np.uint8)
    cv2.putText(scratch, text, (4, 2 * size[1]), _FONT, scale, 255, 1, cv2.LINE_AA)
    columns = np.flatnonzero(scratch.any(axis=0))
    return int(columns[-1] - columns[0] + 1) if len(columns) else 0


def line_chart(series: dict[str, np.ndarray], title: str, x_label: str, y_label: str,
               size_px: tuple[int, int] = (800, 480), log_y: bool = False,
               x_values: dict[str, np.ndarray] | None = None) -> np.ndarray:
    """(H, W, 3) uint8 BGR chart of one or more series.

    Args:
        series: name -> (N,) float values; non-finite values are left out.
        title, x_label, y_label: texts.
        size_px: (width, height).
        log_y: logarithmic y axis (values must then be > 0).
        x_values: name -> (N,) x of each value, the points then marked; None: the values'
            index 1, 2, ... (a generation, say).
    """
    width, height = size_px
    left, right, top, bottom = 80, 20, 52, 50
    image = np.full((height, width, 3), 255, np.uint8)
    values = {name: np.asarray(v, np.float64) for name, v in series.items()}
    xs = {name: (np.arange(1, len(v) + 1, dtype=np.float64) if x_values is None
                 else np.asarray(x_values[name], np.float64)) for name, v in values.items()}
    shown = {name: np.isfinite(v) & ((v > 0) if log_y else True) for name, v in values.items()}
    finite = np.concatenate([v[shown[name]] for name, v in values.items()])
    if finite.size == 0:
        raise ValueError("line_chart needs at least one finite value")
    scale = np.log10 if log_y else (lambda v: v)
    y_low, y_high = scale(finite.min()), scale(finite.max())
    if y_high - y_low < 1e-9:
        y_low, y_high = y_low - 1, y_high + 1
    all_x = np.concatenate(list(xs.values()))
    x_low, x_high = (1.0, max(2.0, all_x.max())) if x_values is None else (0.0, all_x.max())

    def to_px(x, y):
        px = left + (x - x_low) / (x_high - x_low) * (width - left - right)
        return int(round(px)), int(round(top + (y_high - y) / (y_high - y_low) * (height - top - bottom)))

    cv2.rectangle(image, (left, top), (width - right, height - bottom), (0, 0, 0), 1)
    if log_y:  # 1-2-5 steps per decade; round linear steps within less than a 1-2-5 step
        decades = np.arange(np.floor(y_low), np.ceil(y_high) + 1)
        ticks = np.log10(np.outer(10 ** decades, (1, 2, 5)).ravel())
        if np.count_nonzero((ticks >= y_low - 1e-9) & (ticks <= y_high + 1e-9)) < 2:
            ticks = np.log10(_ticks(10 ** y_low, 10 ** y_high))
    else:
        ticks = _ticks(y_low, y_high)
    for y in ticks:
        if y_low - 1e-9 <= y <= y_high + 1e-9:
            _, py = to_px(x_low, y)
            cv2.line(image, (left, py), (width - right, py), (225, 225, 225), 1)
            text = f"{10 ** y:g}" if log_y else f"{y:g}"
            cv2.putText(image, text, (8, py + 5), _FONT, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    for x in _ticks(x_low, x_high):
        if x_low <= x <= x_high and (x_values is not None or float(x).is_integer()):
            px, _ = to_px(x, y_low)
            cv2.putText(image, f"{x:g}", (px - 8, height - bottom + 18), _FONT, 0.45,
                        (0, 0, 0), 1, cv2.LINE_AA)
    for index, (name, v) in enumerate(values.items()):
        colour = _COLOURS_BGR[index % len(_COLOURS_BGR)]
        points = np.array([to_px(x, scale(y)) for x, y, ok in zip(xs[name], v, shown[name])
                           if ok], np.int32)
        if len(points) > 1:
            cv2.polylines(image, [points], False, colour, 2, cv2.LINE_AA)
        if x_values is not None or len(points) == 1:
            for point in points:
                cv2.circle(image, tuple(int(c) for c in point), 4, colour, cv2.FILLED)
    # the legend goes into the plot's corner that the lines cross least
    rows = 20 * len(values)
    corners = [(width - right - 260, top + 22), (width - right - 260, height - bottom - rows),
               (left + 10, top + 22), (left + 10, height - bottom - rows)]
    ink = image.min(axis=2) < 200  # lines and points, not the light grid

    def crossed(corner):
        x, y = corner
        return int(ink[max(y - 25, 0):y + rows, max(x - 10, 0):x + 260].sum())

    x, y = min(corners, key=crossed)  # the first of the least crossed
    for index, name in enumerate(values):
        cv2.putText(image, name, (x, y + 20 * index), _FONT, 0.5,
                    _COLOURS_BGR[index % len(_COLOURS_BGR)], 1, cv2.LINE_AA)
    title_scale = 0.6  # smaller until the title fits within the chart (the font's sizes
    while title_scale > 0.3 and _ink_width(title, title_scale) > width - 16:  # are steps)
        title_scale -= 0.02
    cv2.putText(image, title, ((width - _ink_width(title, title_scale)) // 2, 22), _FONT,
                title_scale, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(image, x_label, (width // 2 - 40, height - 12), _FONT, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(image, y_label, (8, top - 10), _FONT, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    return image
