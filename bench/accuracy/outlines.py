"""How far an extracted silhouette lies from the exact one, per pixel of its outline."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["outline_errors"]


def outline_errors(mask: np.ndarray, exact: np.ndarray) -> tuple[float, float]:
    """(outward offset, wrong pixels) of ``mask`` against ``exact`` ((H, W) bool), each per
    pixel of the exact silhouette's outer outline (its traced contour's length): the extra
    minus the missed pixels (how far the outline lies outside, pixels), and the extra plus
    the missed."""
    contours, _ = cv2.findContours(exact.astype(np.uint8), cv2.RETR_EXTERNAL,
                                   cv2.CHAIN_APPROX_NONE)
    outline = max(sum(len(contour) for contour in contours), 1)
    extra, missed = int(np.sum(mask & ~exact)), int(np.sum(~mask & exact))
    return (extra - missed) / outline, (extra + missed) / outline
