"""Girths and the shoulder breadth scaled to the extents the photos show.

The silhouette fit places each outline of the body to about a canvas pixel (at 600 px a
pixel is the stature over 600, some 3 mm), and where the model cannot follow the person
everywhere at once it compromises: out-of-space the neck's section came out 2.7 mm too
wide or narrow on average, its circumference 7.9 mm off (docs/history.md, [26] and [28]).
The photo itself shows that width at its own resolution. So for the girths of
:data:`PHOTO_EXTENTS`, after the fit, each listed view's photo is
compared with the fitted body rendered through the same camera at the photo's resolution:
the ratio of the person's outline width to the body's, averaged over the lines along the
tape around its centre, scales the fitted section along that view's silhouette axis
(:func:`silhouette_axis`, the direction in the tape's plane across the view's line of
sight: for the head, neck and trunk the front view's is across the body, the side
view's front to back), and the tape is the scaled section's convex hull. The wrist's,
the bicep's and the forearm's two tapes are scaled each by its arm's width across its
tape in the front photo (the wrist's read :data:`WRIST_RISE_M` up the forearm; the
bicep's whole section, :data:`WHOLE_SECTION`), the calf's and the ankle's by its leg's,
the girth their mean. The shoulder breadth (the acromions' distance) is
scaled the same way, by the front photo's outline width across the deltoids
:data:`SHOULDER_DROP_M` below the acromions.

- The camera is placed from the fitted body in the view's pose (as the search places it:
  :func:`~bodyfit.fitter.fit.pinhole_canvas.solve_placement`), so the body's crown and toes
  fall on the silhouette's top and bottom rows and the tape's rows are the person's.
- The view is first turned about its camera's optical axis (:func:`turned_to_tape`) so
  that the tape's line in the photo, its silhouette axis through its centre, runs along
  a row:
  the front photo's trunk tapes lie along its rows already, the side photo's neck tape is
  tilted 8-15 degrees, down towards the throat, and a row through its centre would meet
  the chin.
- A width is the foreground run of a (turned) photo row that holds the projected
  section's centre (or lies nearest it), in the person's mask and in the body's render
  alike, averaged over 6 rows either side of the tape's (2 for the neck, between chin
  and shoulders, and the shoulder breadth, on the deltoids' rounding; for the others 6
  came out better than 2 or 4 on the same fits, if within noise); only the band of rows
  around the tape is rendered (a crop of the camera), so photos of any size cost the
  same. The person's width in a turned photo sums the turned mask's shares of each pixel
  (:func:`person_width`), not its pixels over one half: a tilted outline's staircase,
  turned upright, spreads over partial pixels whose threshold would round each row's
  width to whole pixels again (on a strip tilted 10 degrees, 45.7 px wide, a row's width
  off by 0.44 px (sd) thresholded, 0.02 px summed; the side photo's neck tape and the
  arms' are tilted; the held-out fits' neck, wrist and forearm: docs/accuracy.md, step
  39).
- The scaling is skipped (the fitted value kept) where the rendered body's outline at
  those rows is not the measurement's own part (an arm against the chest, the jaw over
  the neck in the front photo; in the side photo the jaw's underside, the head's part,
  is the neck tape's front end and counts as the neck's), where the person's outline
  reaches into another part of the rendered body (the person's arm touches the chest
  where the body's does not), where the ratio strays beyond :data:`MAX_CHANGE` (hair
  or clothing, not the body, makes that outline), or, for the neck, where the rows'
  ratios spread over more than :data:`MAX_ROW_SPREAD` (the person's outline widens
  across the band where the body's does not: on a subject of the benchmark's hard share
  the jaw's underside, lower than the fitted body's, reached into the side photo's tape
  rows, their ratios 1.12-1.25 where the truth's depth over the fit's is 0.99, and the
  neck came out 36 mm large; the other 107 neck readings of 54 fits spread 0.07 at
  most: docs/history.md, [36]), or, for the neck, where the rendered outline's sides
  lean further from upright than :data:`MAX_OUTLINE_LEAN_DEG` across the band (the
  tape's rows lie on the neck's flare into the shoulders: there a row's width reads the
  slope's height, not the section, and an offset of a row between the person and the
  body changes it by twice the lean's tangent; on a short-necked subject of the hard
  share the front photo read 1.19 where the truth's width over the fit's is 1.04, and
  the neck came out 47 mm large: docs/history.md [37]).
- Which measurements and views: chosen by measured error (docs/accuracy.md steps
  28-32 and 43): the head's width from the front photo and its depth from the side photo
  (its tape horizontal; hair, which the benchmark's subjects lack, would widen both and
  the girth with them, within :data:`MAX_CHANGE`), the neck's, the chest's, the waist's
  and the hip's width from the front photo, the chest's and the waist's depth from the
  side photo (docs/history.md [43]: on the choice rows' fits the chest 5.43 -> 4.81 mm
  out-of-space, 1.75 -> 1.69 in-space; the waist 3.50 -> 3.37 and 1.91 -> 1.76),
  the neck's depth from the side photo along its tilted tape, the shoulder breadth from
  the front photo 2 cm below the acromions (at them the outline is the shoulders'
  rounded top; 2 cm came out better than 1 cm above, 0 or 4 cm below on the same fits),
  the bicep's, the forearm's and the wrist's width from the front photo (their tapes
  tilted with the A-pose's arm; the forearm reaches forward, so its silhouette axis is
  some 30 degrees off the section's first; the wrist's tape lies where the thumb starts,
  and read there it lost on both sets: 3 cm up the forearm came out better than 1.5 or
  4.5), the calf's and the ankle's width from the front photo (the A-pose's legs stand
  apart; docs/history.md [32]). The hip's side depth is not read: the side photo's hands
  hang at its tape (:data:`_OWN_PARTS` refused 93 of 104 choice fits' readings; the other
  11 moved its mean error by 0.02 mm at most); the side photo's arms hang against the body and
  its legs overlap; the thigh's front width lost out-of-space (at the gluteal fold the
  outline's outer end is the buttock's), so the thigh is not scaled.

Pinhole views only (the photos' own camera); the paper's orthographic method measures
the fitted mesh alone.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from bodyfit import kernels
from bodyfit.fitter.fit.pinhole_canvas import solve_placement
from bodyfit.fitter.measure.measurements import ACROSS, LIMB_SECTIONS, Measurer
from bodyfit.fitter.measure.sections import hull_perimeter
from bodyfit.fitter.model.body_model import PART_NAMES, BodyModel
from bodyfit.kernels.target import visible_vertices

__all__ = ["PHOTO_EXTENTS", "SCALED", "MAX_CHANGE", "MAX_ROW_SPREAD", "MAX_OUTLINE_LEAN_DEG",
           "SHOULDER_DROP_M", "SHARE_REACH_PX", "WRIST_RISE_M", "WHOLE_SECTION", "ViewPhoto",
           "outline_width", "person_width", "placed_camera",
           "silhouette_axis", "turned_to_tape", "extent_ratio", "section_scales",
           "scaled_section", "photo_scaled_measurements"]

#: tape key -> the views whose photo sets its extent (along the view's
#: :func:`silhouette_axis`: for the head, neck and trunk "front" is across the body, "side"
#: front to back): the girths of
#: ``SECTION_GIRTHS``, the arms' and the lower legs' tapes (``LIMB_SECTIONS``: wrist,
#: bicep, forearm, calf, ankle, two each) and the shoulder breadth "P".
PHOTO_EXTENTS = {"A": ("front", "side"), "B": ("front", "side"), "D": ("front", "side"),
                 "E": ("front", "side"), "F": ("front",),
                 "G.L": ("front",), "G.R": ("front",), "H.L": ("front",), "H.R": ("front",),
                 "I.L": ("front",), "I.R": ("front",), "P": ("front",),
                 "M.L": ("front",), "M.R": ("front",), "N.L": ("front",), "N.R": ("front",)}
#: Tapes whose front photo's ratio scales their whole section, not its width alone: the
#: bicep's. No photo shows the upper arm's depth (the side photo's arm hangs against the
#: body), and an arm fitted too thin or too thick is so both ways: on the out-of-space
#: choice rows its mean error 3.79 -> 2.97 mm, where the forearm's, the wrist's, the
#: calf's and the ankle's lost 0.7-1.0 mm each so (docs/history.md, [41]).
WHOLE_SECTION = ("H.L", "H.R")
#: The measurements (MEASUREMENTS keys) the photos scale: a tape key's part before its
#: ".L"/".R".
SCALED = tuple(dict.fromkeys(tape.split(".")[0] for tape in PHOTO_EXTENTS))
#: The largest relative change of an extent the photos may make.
MAX_CHANGE = 0.2
#: tape key -> the largest spread (max - min) its band's per-row ratios (the person's
#: width over the body's) may have: the neck's band is short (5 rows), a wider spread
#: there is a feature the fitted body lacks (the jaw's underside) crossing it.
MAX_ROW_SPREAD = {"B": 0.1}
#: tape key -> the largest lean (degrees from upright) the rendered outline's sides may
#: have across its band, from its widths' mean change per row (a width changing by 2
#: pixels a row: each side 1 pixel a row, 45 degrees).
MAX_OUTLINE_LEAN_DEG = {"B": 45.0}
#: The shoulder breadth's line lies this far (metres) below the acromions' midpoint.
SHOULDER_DROP_M = 0.02
#: Pixels beyond a run's ends whose shares of the person count to its width
#: (:func:`person_width`): a bilinear resampling spreads an outline over two.
SHARE_REACH_PX = 2
#: The wrist's width is read this far (metres) up the forearm from its tape, whose rows
#: the thumb's base crosses; the ratio there scales the wrist's section.
WRIST_RISE_M = 0.03
#: (key, view) -> its own parts: the rendered outline at the tape's rows must be of these.
_OWN_PARTS = {("A", "front"): ("head",), ("A", "side"): ("head",),
              ("B", "front"): ("neck",), ("B", "side"): ("neck", "head"),
              ("D", "front"): ("chest",), ("D", "side"): ("chest",),
              ("E", "front"): ("waist",), ("E", "side"): ("waist",),
              ("F", "front"): ("hip", "leg"), ("P", "front"): ("arm",),
              ("H.L", "front"): ("arm",), ("H.R", "front"): ("arm",),
              ("I.L", "front"): ("arm", "elbow"), ("I.R", "front"): ("arm", "elbow"),
              ("G.L", "front"): ("elbow", "hand"), ("G.R", "front"): ("elbow", "hand"),
              ("M.L", "front"): ("leg",), ("M.R", "front"): ("leg",),
              ("N.L", "front"): ("leg", "foot"), ("N.R", "front"): ("leg", "foot")}
#: tape key -> the rows above and below its centre row whose widths are averaged
#: (_OTHER_BAND elsewhere): the neck's and the shoulder breadth's features are short (chin
#: and shoulders, the deltoids' rounding).
_BAND_ROWS = {"B": 2, "P": 2}
_OTHER_BAND = 6
_SUBPIXELS = 4  # the body's render cuts each photo column into as many
_MARGIN_PX = 8
_AXES = {"front": 0, "side": 1}
#: view -> its line of sight in the model's frame (the front camera looks along the
#: model's y, the side camera along its x)
_SIGHTS = {"front": np.array([0.0, 1.0, 0.0]), "side": np.array([1.0, 0.0, 0.0])}


@dataclasses.dataclass(frozen=True)
class ViewPhoto:
    """One photo and the fitted body as its view renders it.

    Attributes:
        name: "front" or "side".
        mask: (H, W) bool, the person's silhouette in the undistorted, upright photo.
        intrinsics: (3, 3) K of that photo, pixels.
        body: (V, 3) float metres, model frame: the fitted body in the view's pose (the
            side view's arms hanging down), at any scale (the placement follows it).
        visible_parts: the part names the view renders (its camera is placed from them).
        share: (H, W) float32 in [0, 1], each pixel's share of the person where the mask
            was resampled (:func:`turned_to_tape`'s warp, whose mask is this over one half),
            or None: the mask itself.
        pitch_deg: the camera's pitch as the fit placed it, degrees (positive looks down).
    """

    name: str
    mask: np.ndarray
    intrinsics: np.ndarray
    body: np.ndarray
    visible_parts: tuple[str, ...]
    share: np.ndarray | None = None
    pitch_deg: float = 0.0


def _runs(row: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(first columns, last columns) of the foreground runs of the (W,) bool ``row``."""
    cols = np.flatnonzero(row)
    if len(cols) == 0:
        return cols, cols
    gaps = np.flatnonzero(np.diff(cols) > 1)
    return np.r_[cols[0], cols[gaps + 1]], np.r_[cols[gaps], cols[-1]]


def outline_width(row: np.ndarray, column: float) -> tuple[int, int]:
    """(first, last) column of the foreground run of the (W,) bool ``row`` that holds
    ``column`` or, if none does, lies nearest it; (0, -1) for an empty row."""
    starts, ends = _runs(row)
    if len(starts) == 0:
        return 0, -1
    distance = np.maximum(np.maximum(starts - column, column - ends), 0)
    i = int(np.argmin(distance))
    return int(starts[i]), int(ends[i])


def person_width(photo: ViewPhoto, row: int, columns: range, run: tuple[int, int]) -> float:
    """Pixels: the width of the foreground run ``run`` (first, last column within
    ``columns``) of the photo's mask row ``row``: its length, or where the photo holds a
    :attr:`ViewPhoto.share`, the shares summed over the run and :data:`SHARE_REACH_PX`
    pixels either side that no other run holds (a resampled outline's partial pixels,
    which the mask's threshold rounds to whole ones)."""
    first, last = run
    if photo.share is None:
        return float(last - first + 1)
    lo = max(columns.start, columns.start + first - SHARE_REACH_PX)
    hi = min(columns.stop, columns.start + last + SHARE_REACH_PX + 1)
    shares = photo.share[row, lo:hi].copy()
    others = photo.mask[row, lo:hi].copy()
    others[first + columns.start - lo:last + columns.start - lo + 1] = False
    shares[others] = 0.0
    return float(shares.sum())


def _meets_another_run(row: np.ndarray, run: tuple[int, int], other: tuple[int, int]) -> bool:
    """Whether the columns ``other`` (first, last) reach into a foreground run of the
    (W,) bool ``row`` other than ``run``."""
    starts, ends = _runs(row)
    apart = (starts != run[0]) & (ends >= other[0]) & (starts <= other[1])
    return bool(apart.any())


def placed_camera(model: BodyModel, photo: ViewPhoto) -> tuple[np.ndarray, np.ndarray]:
    """(R (3, 3), t (3,) metres): the photo's camera placed from its fitted body
    (:func:`~bodyfit.fitter.fit.pinhole_canvas.solve_placement` on the parts the view shows)."""
    shown = visible_vertices(model.vertex_parts, photo.visible_parts)
    placement = solve_placement(photo.name, photo.mask, np.asarray(photo.intrinsics, float),
                                np.asarray(photo.body, np.float64)[shown], photo.pitch_deg)
    return placement.extrinsics(photo.name)


def silhouette_axis(measurer: Measurer, body: np.ndarray, key: str, view: str) -> np.ndarray:
    """(3,) unit, body frame: the direction in girth ``key``'s plane (on ``body`` (V, 3)
    metres) across the ``view``'s line of sight, along which the view's photo shows the
    section's extent: the head's, the neck's and the trunk's first section axis (across
    the body) in the front view, their second (front to back) in the side view; a limb
    tape's lies between, its limb not in the photo's plane (the A-pose's forearm reaches
    forward)."""
    axis = np.cross(measurer.girth_plane(body, key)[1], _SIGHTS[view])
    return axis / np.linalg.norm(axis)


def _tape_line(measurer: Measurer, body: np.ndarray, key: str,
               view: str) -> tuple[np.ndarray, np.ndarray]:
    """((3,) centre, (3,) unit direction), metres, body frame: where measurement ``key``'s
    extent is read on ``body`` (V, 3) in the ``view``'s photo: a girth's section centre and
    its :func:`silhouette_axis` (the wrist's centre moved :data:`WRIST_RISE_M` up the
    forearm); the shoulder breadth's point :data:`SHOULDER_DROP_M` below the acromions'
    midpoint, across the body."""
    if key == "P":
        return measurer.acromions(body).mean(axis=0) - [0.0, 0.0, SHOULDER_DROP_M], ACROSS
    centre = measurer.girth_centre(body, key)
    if key in LIMB_SECTIONS["G"]:
        towards_wrist = measurer.girth_plane(body, key)[1]
        centre = centre - WRIST_RISE_M * towards_wrist / np.linalg.norm(towards_wrist)
    return centre, silhouette_axis(measurer, body, key, view)


def turned_to_tape(measurer: Measurer, key: str, photo: ViewPhoto,
                   camera: tuple[np.ndarray, np.ndarray]
                   ) -> tuple[ViewPhoto, tuple[np.ndarray, np.ndarray]]:
    """The view's photo and camera (R, t) turned about the camera's optical axis so that
    measurement ``key``'s line (:func:`_tape_line`: for a girth its section's axis of the
    view through its centre) runs along a row, the centre's pixel kept where it was: the
    mask warped by the turn's homography (K Rz K^-1, then a shift; bilinear, over half
    covered is person), K shifted by the same, R and t turned by Rz. The line's direction
    is taken within a quarter turn of the rows, so the photo stays upright. The turned
    photo's :attr:`ViewPhoto.share` is the warp before its threshold."""
    rotation, translation = camera
    k = np.asarray(photo.intrinsics, float)
    centre, axis = _tape_line(measurer, photo.body, key, photo.name)
    ends = np.stack([centre, centre + 0.05 * axis]) @ rotation.T + translation
    pixels = (ends / ends[:, 2:]) @ k.T
    du, dv = pixels[1, :2] - pixels[0, :2]
    angle = (np.arctan2(dv, du) + np.pi / 2) % np.pi - np.pi / 2
    c, s = np.cos(-angle), np.sin(-angle)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    homography = k @ turn @ np.linalg.inv(k)
    moved = homography @ pixels[0]
    shift = np.eye(3)
    shift[:2, 2] = pixels[0, :2] - moved[:2] / moved[2]
    homography = shift @ homography
    height, width = photo.mask.shape
    share = cv2.warpPerspective(photo.mask.astype(np.float32), homography, (width, height),
                                flags=cv2.INTER_LINEAR)
    turned = dataclasses.replace(photo, mask=share > 0.5, share=share, intrinsics=shift @ k)
    return turned, (turn @ rotation, turn @ translation)


def _band_render(model: BodyModel, photo: ViewPhoto, rotation, translation, rows: range,
                 columns: range) -> np.ndarray:
    """(len(rows), len(columns) * _SUBPIXELS) int8 part labels (-1: background) of the
    body rendered through the photo's camera, in that crop of the photo, each pixel cut
    into ``_SUBPIXELS`` columns (photo column c covers sub-columns s c .. s c + s - 1)."""
    s = _SUBPIXELS
    k = np.asarray(photo.intrinsics, float).copy()
    k[0] *= s  # column u' = s (u + 1/2) - 1/2 of the photo's column u, over the crop
    k[0, 2] += (s - 1) / 2 - s * columns.start
    k[1, 2] -= rows.start
    camera = kernels.pinhole_camera(k, rotation, translation)
    return kernels.rasterize(photo.body[None].astype(np.float32), model.faces,
                             model.face_parts, camera, len(rows), len(columns) * s).numpy()[0]


def extent_ratio(model: BodyModel, measurer: Measurer, key: str, photo: ViewPhoto,
                 camera: tuple[np.ndarray, np.ndarray]) -> float | None:
    """The person's outline width over the fitted body's along the rows of the view's
    photo around measurement ``key``'s line (module docstring; the photo turned by
    :func:`turned_to_tape`), the photo's camera (R, t) placed by :func:`placed_camera` (and
    turned with it); None where the rendered outline there is not the measurement's own
    part, where the person's outline reaches into another run of the render, where
    the ratio strays beyond :data:`MAX_CHANGE`, where the rows' ratios spread beyond the
    key's :data:`MAX_ROW_SPREAD`, or where the rendered outline's sides lean beyond the
    key's :data:`MAX_OUTLINE_LEAN_DEG`."""
    rotation, translation = camera
    k = np.asarray(photo.intrinsics, float)
    cam = rotation @ _tape_line(measurer, photo.body, key, photo.name)[0] + translation
    u, v = (k[:2, :2] @ (cam[:2] / cam[2])) + k[:2, 2]
    height, width = photo.mask.shape
    row = int(round(v))
    band = _BAND_ROWS.get(key, _OTHER_BAND)
    if not band <= row < height - band:
        return None
    rows = range(row - band, row + band + 1)
    mask_cols = np.flatnonzero(photo.mask[rows.start:rows.stop].any(axis=0))
    if len(mask_cols) == 0:
        return None
    columns = range(max(0, mask_cols[0] - _MARGIN_PX), min(width, mask_cols[-1] + _MARGIN_PX + 1))
    labels = _band_render(model, photo, rotation, translation, rows, columns)
    own = [PART_NAMES.index(p) for p in _OWN_PARTS[key, photo.name]]
    person, fitted = [], []
    s = _SUBPIXELS
    for i, r in enumerate(rows):
        rendered = labels[i] >= 0
        run = outline_width(rendered, s * (u - columns.start + 0.5) - 0.5)
        if run[1] < run[0] or labels[i, run[0]] not in own or labels[i, run[1]] not in own:
            return None
        first, last = outline_width(photo.mask[r, columns.start:columns.stop], u - columns.start)
        if _meets_another_run(rendered, run, (s * first, s * last + s - 1)):
            return None  # the person's outline there holds more (an arm against the chest)
        fitted.append((run[1] - run[0] + 1) / s)
        person.append(person_width(photo, r, columns, (first, last)))
    if np.ptp(np.divide(person, fitted)) > MAX_ROW_SPREAD.get(key, np.inf):
        return None  # the person's outline widens across the band where the body's does not
    lean = np.degrees(np.arctan(np.abs(np.diff(fitted)).mean() / 2.0))
    if lean > MAX_OUTLINE_LEAN_DEG.get(key, 90.0):
        return None  # the band lies on a slope (the neck's flare into the shoulders)
    ratio = float(np.mean(person) / np.mean(fitted))
    return ratio if abs(ratio - 1.0) <= MAX_CHANGE else None


def section_scales(model: BodyModel, measurer: Measurer,
                   photos: dict[str, ViewPhoto]) -> dict[str, np.ndarray]:
    """key -> (2,) the factors of the measurements of :data:`PHOTO_EXTENTS` along their
    front and side views' :func:`silhouette_axis` (the shoulder breadth's second unused):
    each the :func:`extent_ratio` of its view's photo in ``photos`` (views missing there:
    none), turned to the tape (:func:`turned_to_tape`), 1 where none applies, the front
    one's along both for the tapes of :data:`WHOLE_SECTION`; each view's camera placed
    once."""
    cameras = {name: placed_camera(model, photo) for name, photo in photos.items()}
    scales = {}
    for key, views in PHOTO_EXTENTS.items():
        scales[key] = np.ones(2)
        for name in set(views) & set(photos):
            ratio = extent_ratio(model, measurer, key,
                                 *turned_to_tape(measurer, key, photos[name], cameras[name]))
            if ratio is not None:
                scales[key][_AXES[name]] = ratio
        if key in WHOLE_SECTION:
            scales[key][1] = scales[key][0]
    return scales


def scaled_section(measurer: Measurer, rest: np.ndarray, key: str,
                   scale: np.ndarray) -> np.ndarray:
    """(n, 2) metres: girth ``key``'s section of ``rest`` (V, 3) metres
    (:meth:`Measurer.girth_section`) stretched by the factors ``scale`` (2,) along its
    front and side views' :func:`silhouette_axis` in turn."""
    section = measurer.girth_section(rest, key)
    frame = measurer.girth_axes(rest, key)
    for view, factor in zip(_AXES, scale):
        axis = frame @ silhouette_axis(measurer, rest, key, view)
        section = section + (factor - 1.0) * np.outer(section @ axis, axis)
    return section


def photo_scaled_measurements(model: BodyModel, measurer: Measurer, rest: np.ndarray,
                              photos: dict[str, ViewPhoto]) -> dict[str, float]:
    """key -> mm: the measurements :data:`SCALED` of the fitted body ``rest`` (V, 3)
    metres (rest A-pose, at the person's stature), their tapes of :data:`PHOTO_EXTENTS`
    scaled by their :func:`section_scales`: a girth its section (:func:`scaled_section`;
    a limb's girth: the mean of its two), the shoulder breadth its length (a tape no ratio
    applies to keeps its fitted value)."""
    tapes: dict[str, list[float]] = {}  # measurement -> its tapes' values, mm
    for tape, scale in section_scales(model, measurer, photos).items():
        if tape == "P":
            left, right = measurer.acromions(rest)
            value = float(np.linalg.norm(left - right) * scale[0])
        else:
            value = hull_perimeter(scaled_section(measurer, rest, tape, scale))
        tapes.setdefault(tape.split(".")[0], []).append(1000.0 * value)
    return {key: float(np.mean(values)) for key, values in tapes.items()}
