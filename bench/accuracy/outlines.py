"""How far an extracted silhouette lies from the exact one: per pixel of its outline, and
in its height (from which the fit takes each view's scale)."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["HEIGHT_OFF_SHARE", "height_error", "outline_errors"]

#: A silhouette whose height is off by more than this share of the exact one's is counted
#: apart: its view's scale, and so every girth, is off by as much.
HEIGHT_OFF_SHARE = 0.02


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


def height_error(mask: np.ndarray, exact: np.ndarray) -> float:
    """(rows ``mask`` spans - rows ``exact`` spans) / rows ``exact`` spans, of (H, W) bool
    silhouettes: positive when the extracted one is the taller."""
    def rows(m):
        found = np.flatnonzero(m.any(axis=1))
        return found[-1] - found[0] + 1
    return (rows(mask) - rows(exact)) / rows(exact)
