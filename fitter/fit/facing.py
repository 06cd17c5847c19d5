"""Which way the person in a side photo faces, told from the silhouette's feet.

The fit's side view looks at the person's left side, the person facing the image's left
(:mod:`bodyfit.fitter.fit.pinhole_canvas`). A side photo taken from the person's right
shows them facing the image's right; its mirror image is, for a left-right symmetric
body, the photo from the left that the fit expects (the model's bodies are symmetric;
:func:`bodyfit.fitter.fit.person.person_masks` mirrors such a mask and its camera).

The cue is the feet: seen from the side, each foot reaches from the ankle far forward
(the toes) and only a little back (the heel). The ankles' centre is the middle of the
silhouette a little above the soles (:data:`_ANKLE_BAND`); the soles' band
(:data:`_SOLE_BAND`) reaches further from it towards the way the person faces.
Fractions are of the person's height in the mask.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FACING_MARGIN", "SIDES", "facing_reach", "side_seen"]

#: Which side of the person a side photo shows: "left" faces the image's left.
SIDES = ("left", "right")
_SOLE_BAND = (0.0, 0.025)  # rows above the lowest person row, fraction of the height
_ANKLE_BAND = (0.05, 0.08)
#: The toes must reach this much further (fraction of the height) one way than the
#: heels the other for the facing to be told.
FACING_MARGIN = 0.02


def facing_reach(mask: np.ndarray) -> float:
    """How much further the soles reach left than right of the ankles, as a fraction of
    the person's height in ``mask`` (H, W) bool: positive faces the image's left."""
    rows = np.flatnonzero(mask.any(axis=1))
    top, bottom = rows[0], rows[-1]
    height = bottom - top + 1

    def band(fractions):
        lo, hi = (int(round(bottom - f * height)) for f in fractions[::-1])
        return mask[max(lo, top):hi + 1]

    ankles = np.flatnonzero(band(_ANKLE_BAND).any(axis=0))
    soles = np.flatnonzero(band(_SOLE_BAND).any(axis=0))
    if ankles.size == 0 or soles.size == 0:
        return 0.0
    centre = (ankles[0] + ankles[-1]) / 2
    return float((centre - soles[0]) - (soles[-1] - centre)) / height


def side_seen(mask: np.ndarray) -> str | None:
    """"left" or "right": the side of the person a side silhouette (H, W) bool shows
    (left: facing the image's left); None when the feet do not tell."""
    reach = facing_reach(mask)
    if abs(reach) < FACING_MARGIN:
        return None
    return "left" if reach > 0 else "right"
