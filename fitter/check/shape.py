"""What a person's silhouette shows of their pose and framing, for the photography check.

Measured on the (H, W) bool mask of an upright photo, in shares of the person's height in
pixels (``height_px``: the rows from the top of the head to the soles), so that they do
not depend on the photo's resolution or the person's distance:

- **margins**: the free rows above the head and below the feet, and the free columns
  left and right of the person;
- **feet_gap**: the widest gap between the legs in their lowest ``FEET_SHARE`` of the
  height, the ankles and feet (0 when they touch; a shoe the silhouette lost does not
  hide the ankles' gap);
- **leg_split**: how high the background between the legs reaches from the soles, the
  highest column of it between the legs where they are farthest apart (0 with the feet
  together). Bare or fitted legs
  part at the crotch, 0.45-0.53 of the height on the standing set's bodies; a long top, a
  skirt or a dress hides the thighs and parts them lower;
- **arm_gaps**: on each side, the widest background between the outermost part of a row
  and the next one, over the rows above the legs' split: the clearance between an arm
  and the torso (the right one of the image first).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FEET_SHARE", "SilhouetteShape", "silhouette_shape"]

#: The lowest share of the height that holds the feet and ankles.
FEET_SHARE = 0.08


@dataclass(frozen=True)
class SilhouetteShape:
    """One silhouette's measures (module docstring); shares of ``height_px``.

    Attributes:
        height_px: the person's height, pixels (rows).
        width_px: the person's width, pixels (columns).
        margins: free space (top, bottom, left, right) beside the person.
        feet_gap, leg_split: see the module docstring.
        arm_gaps: (image left, image right) clearances between arm and torso.
    """

    height_px: int
    width_px: int
    margins: tuple[float, float, float, float]
    feet_gap: float
    leg_split: float
    arm_gaps: tuple[float, float]


def _runs(row: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(starts, ends) of the True runs of a 1-D bool array, ends exclusive."""
    steps = np.diff(np.concatenate([[0], row.astype(np.int8), [0]]))
    return np.flatnonzero(steps == 1), np.flatnonzero(steps == -1)


def silhouette_shape(mask: np.ndarray) -> SilhouetteShape:
    """The measures of an (H, W) bool silhouette with at least one True pixel."""
    rows, cols = np.nonzero(mask)
    top, bottom, left, right = rows.min(), rows.max(), cols.min(), cols.max()
    height = int(bottom - top + 1)
    margins = (top / height, (mask.shape[0] - 1 - bottom) / height, left / height,
               (mask.shape[1] - 1 - right) / height)
    feet_gap = leg_split = 0.0
    between = None  # the columns between the feet, where they are farthest apart
    for row in mask[bottom - max(1, round(FEET_SHARE * height)) + 1:bottom + 1]:
        starts, ends = _runs(row)
        if len(starts) >= 2 and (starts[-1] - ends[0]) / height > feet_gap:
            feet_gap, between = (starts[-1] - ends[0]) / height, (ends[0], starts[-1])
    if between is not None:
        band = mask[top:bottom + 1, between[0]:between[1]][::-1]  # from the soles up
        free = np.where(band.any(0), band.argmax(0), height)
        leg_split = free.max() / height
    arm_gaps = [0.0, 0.0]
    for row in mask[top:bottom + 1 - round(leg_split * height)]:
        starts, ends = _runs(row)
        if len(starts) >= 3:
            arm_gaps[0] = max(arm_gaps[0], (starts[1] - ends[0]) / height)
            arm_gaps[1] = max(arm_gaps[1], (starts[-1] - ends[-2]) / height)
    return SilhouetteShape(height, int(right - left + 1), margins, float(feet_gap),
                           float(leg_split), (float(arm_gaps[0]), float(arm_gaps[1])))
