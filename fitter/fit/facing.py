"""Which way the person in a side photo faces, told from the silhouette's feet.

The fit's side view looks at the person's left side, the person facing the image's left
(:mod:`bodyfit.fitter.fit.pinhole_canvas`). A side photo taken from the person's right
shows them facing the image's right; its mirror image is, for a left-right symmetric
body, the photo from the left that the fit expects (the model's bodies are symmetric;
:func:`bodyfit.fitter.fit.person.person_masks` mirrors such a mask and its camera).

The cue is the feet: seen from the side, each foot reaches from the leg far forward (the
toes) and only a little back (the heel). The legs' axis is the median centre of the
silhouette's rows across the shins (:data:`_SHIN_BAND`, where the two legs overlap); the
feet's band (:data:`_FEET_BAND`) reaches further from it towards the way the person
faces. The shins, not the ankles, give the axis: a camera above the floor sees the far
foot higher in the photo than the near one, and its toes then reach into the ankles'
rows. Fractions are of the person's height in the mask.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FACING_MARGIN", "SIDES", "SIDE_FROM", "facing_reach", "side_seen", "side_text"]

#: Which side of the person a side photo shows: "left" faces the image's left.
SIDES = ("left", "right")
#: ``--side-from``: a side of :data:`SIDES`, or "auto": told by the feet
#: (:func:`side_seen`), and where they do not tell, the fit tries both
#: (:func:`bodyfit.fitter.fit.person_fit.fit_inputs`).
SIDE_FROM = ("auto", *SIDES)
_FEET_BAND = (0.0, 0.05)  # rows above the lowest person row, fraction of the height
_SHIN_BAND = (0.12, 0.2)
#: The toes must reach this much further (fraction of the height) one way than the
#: heels the other for the facing to be told. The standing set's 200 side photos read
#: 0.067-0.11 towards the way the person faces, their front photos under 0.02.
FACING_MARGIN = 0.04


def facing_reach(mask: np.ndarray) -> float:
    """How much further the feet reach left than right of the legs' axis, as a fraction
    of the person's height in ``mask`` (H, W) bool: positive faces the image's left."""
    rows = np.flatnonzero(mask.any(axis=1))
    top, bottom = rows[0], rows[-1]
    height = bottom - top + 1

    def band(fractions):
        lo, hi = (int(round(bottom - f * height)) for f in fractions[::-1])
        return mask[max(lo, top):hi + 1]

    shins = band(_SHIN_BAND)
    shins = shins[shins.any(axis=1)]
    feet = np.flatnonzero(band(_FEET_BAND).any(axis=0))
    if shins.size == 0 or feet.size == 0:
        return 0.0
    first = shins.argmax(axis=1)
    last = shins.shape[1] - 1 - shins[:, ::-1].argmax(axis=1)
    centre = float(np.median((first + last) / 2))
    return float((centre - feet[0]) - (feet[-1] - centre)) / height


def side_seen(mask: np.ndarray) -> str | None:
    """"left" or "right": the side of the person a side silhouette (H, W) bool shows
    (left: facing the image's left); None when the feet do not tell."""
    reach = facing_reach(mask)
    if abs(reach) < FACING_MARGIN:
        return None
    return "left" if reach > 0 else "right"


def side_text(photos: dict) -> str:
    """Which side of the person the side photo shows, in words, for the summary and the
    report, from a fit's ``photos`` record (``side_from``, and ``side_costs`` where the
    fit tried both sides)."""
    text = f"the person's {photos['side_from']} side"
    costs = photos.get("side_costs")
    if costs:
        other = next(side for side in costs if side != photos["side_from"])
        text += (f" (the feet do not tell; fitted both ways, its cost "
                 f"{costs[photos['side_from']]:.1f} against {costs[other]:.1f})")
    return text
