"""Image sharpness as the width of an edge: how many pixels a black-to-white step takes.

For a step edge of contrast C blurred by a Gaussian of standard deviation s, the
steepest gradient is C / (s * sqrt(2 pi)) and the 10 %-90 % rise takes 2.563 s pixels,
so ``rise = 1.0225 * C / steepest gradient``. :func:`edge_rise_px` measures C (local
max - min) and the gradient at the crest of every strong edge and returns the median
rise. It is the quantity ``cv2.estimateChessboardSharpness`` reports for chessboards
(OpenCV suggests calibration views stay below ~3 px), but works on any image region,
so it serves chessboards, ChArUco boards and whole video frames alike.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

__all__ = ["edge_rise_px"]

_RISE_PER_CONTRAST_OVER_SLOPE = 2.563 / math.sqrt(2.0 * math.pi)
# Local contrast is measured over this many pixels either side; rises wider than about
# twice this read as this wide, which is far beyond any threshold worth using.
_CONTRAST_RADIUS_PX = 8
# Only edges with at least this fraction of the region's strong contrast are measured.
_STRONG_EDGE_FRACTION = 0.5


def edge_rise_px(gray: np.ndarray, region: np.ndarray | None = None) -> float:
    """Median 10 %-90 % rise width of the strong edges in ``gray``, pixels.

    Args:
        gray: (H, W) uint8 image.
        region: optional (H, W) bool mask; only edges inside it are measured (e.g. the
            hull of a detected board).

    Returns:
        The rise width in pixels (about 1-2 for a sharp photo, growing with blur), or
        ``inf`` when the region holds no strong edge.
    """
    if gray.ndim != 2:
        raise ValueError(f"edge_rise_px() takes an (H, W) image, got shape {gray.shape}")
    if gray.dtype != np.uint8:
        raise ValueError(f"edge_rise_px() takes a uint8 image, got {gray.dtype}")
    if region is not None and region.shape != gray.shape:
        raise ValueError(f"region {region.shape} does not match the image {gray.shape}")
    inside = np.ones(gray.shape, bool) if region is None else np.asarray(region, bool)
    image = gray.astype(np.float32)
    # Sobel 3x3 responds with 8x the slope; divide to get grey levels per pixel.
    slope8 = cv2.magnitude(cv2.Sobel(image, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(image, cv2.CV_32F, 0, 1, ksize=3))
    if not inside.any():
        return math.inf
    steep = float(np.percentile(slope8[inside], 99.5))
    if steep <= 0:
        return math.inf
    # Canny's non-maximum suppression keeps the crest of every edge, one pixel wide.
    crest = cv2.Canny(gray, 0.25 * steep, 0.5 * steep, L2gradient=True) > 0
    window = cv2.getStructuringElement(cv2.MORPH_RECT, (2 * _CONTRAST_RADIUS_PX + 1,) * 2)
    contrast = cv2.dilate(image, window) - cv2.erode(image, window)
    strong = inside & crest & (contrast >= _STRONG_EDGE_FRACTION * np.percentile(contrast[inside], 95))
    if not strong.any():
        return math.inf
    return float(np.median(_RISE_PER_CONTRAST_OVER_SLOPE * contrast[strong] / (slope8[strong] / 8)))
