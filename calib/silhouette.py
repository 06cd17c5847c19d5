"""Silhouettes: the person on a plain backdrop as a binary mask.

Algorithm (background subtraction with a shadow-tolerant colour test, after
Horprasert, Harwood and Davis, "A statistical approach for real-time robust background
subtraction and shadow detection", 1999):

1. Backdrop colour E at every pixel: a quadratic surface in (x, y) per BGR channel,
   fitted robustly to a band along the frame border (which must show only backdrop),
   so smooth lighting falloff is modelled; or a background plate photo taken from the
   same spot without the person.
2. Each pixel I is compared with E by its brightness ratio ``a = I.E / E.E`` and its
   chroma distortion ``|I - a E|`` (the colour change a shadow cannot explain, in grey
   levels of 0..255; sensor noise gives it the same spread in light and shadow). A
   shadow darkens the backdrop without changing its chroma, so pixels of small chroma
   distortion with ``shadow_min_brightness <= a <= max_highlight_brightness`` are
   backdrop; the rest is person. The chroma threshold is ``noise_factor`` times the border's median chroma
   distortion (robust to a little of the person in the border), never below
   ``min_chroma_distortion``. The threshold sits low, inside the noise's tail, so that
   clothes close to the backdrop's colour are found; step 3 removes the specks of
   backdrop noise that this lets through.
3. A ``median_px`` median filter votes away most noise specks and pinholes; kornia
   morphology, an opening then a closing with a ``morphology_px`` disc, removes what is
   left and smooths the outline; the largest 8-connected region is the person.
4. The low threshold puts the outline where an edge pixel is only slightly person;
   within ``outline_band_px`` of the outline each pixel is re-decided by its mixing
   fraction between the local person and backdrop colours, so the outline runs where a
   blurred or anti-aliased edge is half and half (on blurred synthetic photos this
   raises the IoU from 0.96 to 0.997). The step runs ``outline_passes`` times, each
   from the outline the last one left: JPEG's ringing lets the low threshold put the
   first outline 2-3 px outside the edge, so one pass still takes the local person
   colour partly from mixed pixels; on the accuracy benchmark's JPEG photos it left the
   outline 0.24 px outside the exact one on average, four passes leave 0.05 px
   (docs/history.md). Where no backdrop pixel lies in a pixel's
   window (a gap between fingers, which the low threshold fills), the
   modelled backdrop colour of step 1 stands for the local one, and each pass carves
   ``outline_band_px`` further into such a gap: eight passes reopen the gaps between
   the fingers that four left filled, which made the hands look larger and the fitted
   arms longer (docs/history.md, [35]). A pixel must be half person also against
   the colour two pixels inside the outline: a limb shaded darker at its outline than
   further in had its edge pixels taken for more person than they are, its outline a
   fifth of a pixel wide of the truth on the benchmark's wrists (docs/history.md [38]).
5. Enclosed holes smaller than ``max_hole_fraction`` of the person are filled (larger
   ones are real gaps, e.g. between an arm and the body with a hand on the hip).

A backdrop that is not plain, a missing person, a person touching the frame edge and
several people are UserErrors. A backdrop of the clothes' or skin's colour cannot work.

**Rooms** (``segmenter="learned"``, or ``"auto"`` where no plain backdrop surrounds the
person: the border is not plain, or the region found reaches the frame's edges or has
others as large beside it, as a room's floor or door frames give):

1. the learned segmentation (:mod:`bodyfit.calib.segment`): the region where its person
   probability is at least one half (step 3's region checks apply); its outline runs a
   few pixels loose at the hair and hands and loses dark shoes on a dark floor;
2. OpenCV's GrabCut from that region (colour models of the person and the room, the cut
   drawn along the photo's edges): person for sure ``grabcut_inside_px`` inside its
   outline, room ``grabcut_outside_px`` outside, either between (on the room benchmark
   the wrong pixels per outline pixel 1.40 -> 1.06, docs/history.md). The head is
   bounded by the landmarks: above the middle of the neck (halfway from the ears'
   midpoint to the shoulders'), what lies over ``head_radius`` from the ears' midpoint is
   room for sure, and what lies over ``head_core_radius`` is room at first, person again
   where GrabCut finds it of the person's colours (both radii in eyes-to-ankles lengths).
   The learned mask takes in what stands behind the head with a probability of 0.6-0.9
   (a picture on the wall read as hair, the silhouette 5-10 % too tall); on the room
   benchmark's truth masks the head reaches 0.078-0.113 of that length from the ears;
3. with a background plate of the room, GrabCut cuts the photo minus the plate (scaled by the
   exposure's ratio), where the room is nearly uniform and the person is not; patches
   unlike the plate's colour (over ``plate_unlike_grey`` off, and no shadow or highlight
   of it) that touch the learned region's band are person at first (a foot it lost), and
   solid patches of the plate's colour (within ``plate_same_grey``) are room for sure,
   inside the learned region too (a chair it took in). On the room benchmark's photos
   (in-space and out-of-space, 48 each) the wrong pixels per outline pixel go from
   0.61 and 0.64 (front) and 1.31 and 1.26 (side) without the plate to 0.38 and 0.42,
   and 0.70 and 0.59 with it (the backdrop's colour model against the same plates,
   which takes dark trousers on a dark floor for a shadow, fits worse than no plate);
4. step 4's refinement, each pixel's backdrop colour the mean of the photo outside the
   region within ``surroundings_window_px`` (whatever lies behind that stretch of the
   outline: a wall, a floor, the shadow at the feet), except where the person's and the
   backdrop's local colours differ by less than ``learned_min_contrast`` (a grey sole on
   a grey floor) or the backdrop's pixels spread over ``learned_max_backdrop_spread``
   (striped blinds), where the region's side stands; then step 5.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import torch
from kornia.morphology import closing, opening

from bodyfit.calib.camera import Camera
from bodyfit.calib.images import read_image_file, read_photo, to_upright
from bodyfit.calib.segmenters import check_segmenter
from bodyfit.calib.undistort import undistort_image
from bodyfit.common.errors import UserError

__all__ = ["SilhouetteSettings", "extract_silhouette", "load_mask", "photo_silhouette"]

log = logging.getLogger(__name__)

_MAX_BORDER_SAMPLES = 40_000
_SIDE_NAMES = ("top", "bottom", "left", "right")


# Smaller photos leave the backdrop fit and the filters nothing to work on.
MIN_PHOTO_SIDE_PX = 64
#: A learned probability of at least this is person.
_LEARNED_THRESHOLD = 0.5
#: A plate's exposure is matched on the pixels this far from the learned region.
_EXPOSURE_MARGIN_PX = 40
#: Patches of a plate's colour narrower than this disc are no room for sure (a dark
#: trouser pixel can match a dark floor's).
_ROOM_PATCH_RADIUS_PX = 3
#: A plate whose colour less of the room away from the person has than this share is
#: not the photo's room (another spot, the phone moved): a matching plate of the room
#: benchmark holds 0.92-0.97 of it, one shifted by 6 px 0.62 (0.87 in a white room).
_MIN_PLATE_MATCH = 0.5


class _NotSurrounded(UserError):
    """No plain backdrop surrounds the person: the border is not plain, the plate does not
    match it, the person's region reaches the frame's edges, or other regions as large
    stand beside it (``"auto"`` turns to the learned segmentation)."""


@dataclass(frozen=True)
class SilhouetteSettings:
    """Thresholds of :func:`extract_silhouette` (see the module docstring).

    Attributes:
        border_band_fraction: width of the border band that models the backdrop,
            fraction of the image's shorter side.
        min_chroma_distortion: smallest chroma distortion that separates person from
            backdrop, grey levels (0..255).
        noise_factor: chroma threshold over the border's median chroma distortion.
        shadow_min_brightness: backdrop darkened down to this fraction of its modelled
            brightness still counts as backdrop (a shadow).
        max_highlight_brightness: backdrop brighter than this fraction of its modelled
            brightness counts as person (white clothes on a grey backdrop).
        max_backdrop_chroma_distortion: the border's 95th-percentile chroma distortion
            above this (grey levels) means the backdrop is not plain.
        max_border_foreground_fraction: more of the border band than this unlike the
            backdrop means the backdrop is not plain.
        median_px: side of the median filter's window, pixels (odd; 1 disables it).
        morphology_px: diameter of the disc for the opening and closing, pixels.
        min_person_fraction: the person must cover at least this fraction of the image
            (a side view from 4 m through a phone's main camera covers about 1 %).
        max_second_region_ratio: a second region at least this fraction of the largest
            means several people (or a large object) in the picture.
        outline_band_px: pixels either side of the outline that step 4 re-decides (0: none).
        outline_window_px: side of the window for the local person and backdrop colours, pixels.
        outline_passes: times step 4 runs, each from the outline of the last.
        max_hole_fraction: enclosed holes up to this fraction of the person's area are filled.
        surroundings_window_px: side of the window whose pixels outside the learned region
            give the backdrop colour behind the outline, pixels.
        learned_min_contrast: on the learned region's outline, a pixel whose local person
            and backdrop colours differ by less (grey levels) keeps the learned side.
        learned_max_backdrop_spread: so does one whose window's outside pixels spread more
            than this (RMS about their mean, grey levels: a textured backdrop).
        grabcut_inside_px, grabcut_outside_px: the learned region's pixels this far inside
            its outline are person for GrabCut, and those this far outside it room.
        grabcut_iterations: GrabCut's iterations.
        head_radius, head_core_radius: above the neck's middle, the learned region's
            pixels further than these from the ears' midpoint are room for sure, and room
            until GrabCut finds them of the person's colours; eyes-to-ankles lengths.
        plate_same_grey: with a room's background plate, a pixel within this of the
            plate's colour (grey levels, every channel, after the exposure's ratio) is room
            for GrabCut, in solid patches even inside the learned region.
        plate_unlike_grey, plate_unlike_chroma: one further than the first from the
            plate's colour, and unlike a shadow or highlight of it (chroma distortion over
            the second, or a brightness outside the shadow's and highlight's bounds), is
            person at first where its patch touches the learned region's surroundings.
    """

    border_band_fraction: float = 0.04
    min_chroma_distortion: float = 6.0
    noise_factor: float = 2.5
    shadow_min_brightness: float = 0.45
    max_highlight_brightness: float = 1.35
    max_backdrop_chroma_distortion: float = 25.0
    max_border_foreground_fraction: float = 0.25
    median_px: int = 3
    morphology_px: int = 3
    min_person_fraction: float = 0.005
    max_second_region_ratio: float = 0.15
    outline_band_px: int = 2
    outline_window_px: int = 11
    outline_passes: int = 8
    max_hole_fraction: float = 0.01
    surroundings_window_px: int = 51
    learned_min_contrast: float = 30.0
    learned_max_backdrop_spread: float = 20.0
    grabcut_inside_px: int = 8
    grabcut_outside_px: int = 12
    grabcut_iterations: int = 4
    head_radius: float = 0.13
    head_core_radius: float = 0.08
    plate_same_grey: float = 8.0
    plate_unlike_grey: float = 30.0
    plate_unlike_chroma: float = 15.0

    def __post_init__(self) -> None:
        if self.median_px < 1 or self.median_px % 2 == 0:
            raise ValueError(f"median_px must be odd and positive, got {self.median_px}")
        if self.morphology_px < 1:
            raise ValueError(f"morphology_px must be positive, got {self.morphology_px}")
        if self.outline_passes < 0:
            raise ValueError(f"outline_passes must not be negative, got {self.outline_passes}")


def _border_band(shape: tuple[int, int], fraction: float) -> np.ndarray:
    """(H, W) bool, True in a band of ``fraction`` x the shorter side along the edges."""
    height, width = shape
    width_px = max(2, round(fraction * min(height, width)))
    band = np.ones(shape, bool)
    band[width_px:-width_px, width_px:-width_px] = False
    return band


def _quadratic_terms(x: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
    return [np.ones_like(x * y), x, y, x * x, x * y, y * y]


def _fit_backdrop(image: np.ndarray, band: np.ndarray) -> np.ndarray:
    """(H, W, 3) float32 modelled backdrop colour, a robust quadratic fit to the band."""
    height, width = band.shape
    rows, cols = np.nonzero(band)
    stride = max(1, len(rows) // _MAX_BORDER_SAMPLES)
    rows, cols = rows[::stride], cols[::stride]
    x, y = cols / (width - 1) * 2 - 1, rows / (height - 1) * 2 - 1
    design = np.stack(_quadratic_terms(x, y), axis=1)
    colours = image[rows, cols].astype(np.float64)
    inliers = np.ones(len(rows), bool)
    for _ in range(4):
        coefficients, *_ = np.linalg.lstsq(design[inliers], colours[inliers], rcond=None)
        residual = np.linalg.norm(colours - design @ coefficients, axis=1)
        inliers = residual <= 3.0 * max(float(np.median(residual)), 1.0)
    grid_x = (np.arange(width, dtype=np.float32) / (width - 1) * 2 - 1)[None, :]
    grid_y = (np.arange(height, dtype=np.float32) / (height - 1) * 2 - 1)[:, None]
    terms = _quadratic_terms(grid_x, grid_y)
    backdrop = np.empty((height, width, 3), np.float32)
    for channel in range(3):
        backdrop[..., channel] = sum(float(c) * term for c, term in zip(coefficients[:, channel], terms))
    return backdrop


def _compare(image: np.ndarray, backdrop: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Brightness ratio and chroma distortion of ``image`` against ``backdrop``.

    Brightness ratio ``a = I.E / E.E`` (unitless); chroma distortion ``|I - a E|``, the
    colour change a shadow cannot explain, grey levels. Returns two (H, W) float32 arrays.
    """
    pixels = image.astype(np.float32)
    backdrop_sq = np.maximum(np.einsum("hwc,hwc->hw", backdrop, backdrop), 1e-6)
    brightness = np.einsum("hwc,hwc->hw", pixels, backdrop) / backdrop_sq
    off_axis = pixels - brightness[..., None] * backdrop
    distortion = np.sqrt(np.einsum("hwc,hwc->hw", off_axis, off_axis))
    return brightness, distortion


def _clean(mask: np.ndarray, settings: SilhouetteSettings) -> np.ndarray:
    """Median filter, then opening and closing with a disc (kornia); (H, W) bool -> (H, W) bool."""
    if settings.median_px > 1:
        mask = cv2.medianBlur(mask.astype(np.uint8), settings.median_px) > 0
    diameter = settings.morphology_px
    if diameter <= 1:
        return mask
    disc = torch.from_numpy(cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (diameter, diameter))).float()
    tensor = torch.from_numpy(mask.astype(np.float32))[None, None]
    with torch.inference_mode():
        cleaned = closing(opening(tensor, disc), disc)
    return cleaned[0, 0].numpy() > 0.5


def _components(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """8-connected regions: (labels (H, W) int32, stats (regions, 5)); stats row i is label i + 1."""
    _, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    return labels, stats[1:]


def _largest_region(areas: np.ndarray, settings: SilhouetteSettings) -> tuple[int, int]:
    """(index of the largest of the regions' ``areas`` (n,), n >= 1; how many regions are
    person-sized: at least ``settings.max_second_region_ratio`` of its area, itself
    included)."""
    largest = int(np.argmax(areas))
    return largest, int(np.sum(areas >= settings.max_second_region_ratio * areas[largest]))


def _person_region(mask: np.ndarray, settings: SilhouetteSettings) -> np.ndarray:
    """The largest region of ``mask``; UserError if it is no person, not alone or cut by the frame."""
    height, width = mask.shape
    labels, stats = _components(mask)
    areas = stats[:, cv2.CC_STAT_AREA]
    if len(areas) == 0 or areas.max() < settings.min_person_fraction * height * width:
        raise UserError(
            "no person found: nothing in the photo differs from the backdrop over more than "
            f"{settings.min_person_fraction:.1%} of the image; stand the person in front of the backdrop, "
            "in clothes that do not match its colour"
        )
    largest, similar = _largest_region(areas, settings)
    if similar > 1:
        raise _NotSurrounded(
            f"{similar} person-sized regions differ from the backdrop; photograph one person at a time, "
            "with nothing else in front of the backdrop"
        )
    left, top, box_width, box_height = stats[largest, :4]
    edges = (top == 0, top + box_height == height, left == 0, left + box_width == width)
    touching = [side for side, touches in zip(_SIDE_NAMES, edges) if touches]
    if touching:
        raise _NotSurrounded(
            f"the person touches the {' and '.join(touching)} edge of the photo; step back so that the "
            "whole body is inside the frame with backdrop all around it"
        )
    return labels == largest + 1


def _mixing_fraction(pixels: np.ndarray, person: np.ndarray, backdrop: np.ndarray) -> np.ndarray:
    """(N,) float32: how much of the person's colour each pixel holds,
    ``(I - B).(P - B) / |P - B|^2``, for (N, 3) float32 ``pixels`` I, ``person`` P and
    ``backdrop`` B colours."""
    contrast = person - backdrop
    return np.einsum("nc,nc->n", pixels - backdrop, contrast) / np.maximum(
        np.einsum("nc,nc->n", contrast, contrast), 1e-6
    )


def _window_mean(values: np.ndarray, selected: np.ndarray, window_px: int
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(the mean of the ``selected`` (H, W) bool pixels of ``values`` ((H, W) or (H, W, C)
    float32) within a ``window_px`` square about each pixel, 0 where there are none;
    (H, W) float32 how many there are)."""
    window = (window_px, window_px)
    weight = cv2.boxFilter(selected.astype(np.float32), -1, window, normalize=False)
    chosen = values * (selected[..., None] if values.ndim == 3 else selected)
    total = cv2.boxFilter(chosen, -1, window, normalize=False)
    share = np.maximum(weight, 1e-6)
    return total / (share[..., None] if values.ndim == 3 else share), weight


def _disc(radius: int) -> np.ndarray:
    """A disc of ``radius`` pixels as OpenCV's structuring element."""
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1,) * 2)


def _refine_outline(image: np.ndarray, region: np.ndarray, backdrop: np.ndarray,
                    settings: SilhouetteSettings, min_contrast: float = 0.0,
                    max_backdrop_spread: float = np.inf) -> np.ndarray:
    """Move the outline to where edge pixels are half person, half backdrop.

    Near the outline a pixel's colour I mixes the person's local colour P and the
    backdrop's local colour B (each the mean of the confidently inside or outside pixels
    in a ``outline_window_px`` window, so a shadow next to the person is part of B). In
    a gap too narrow to hold a confidently outside pixel (between fingers, where the
    first threshold joins both fingers' blurred edges) B is the modelled ``backdrop``
    (H, W, 3) float32 there. The pixel is person when its mixing fraction
    ``(I - B).(P - B) / |P - B|^2`` is at least one half, with P the window's inside
    colour and again with P the mean of the window's pixels two pixels inside the
    outline (where there are any): a limb turns away from the camera at its outline, and
    shaded darker there than further in it made edge pixels look more person than they
    are; a blurred edge makes the nearer colour partly backdrop instead, and the window's
    decides. Where the person's and the backdrop's colours differ by less than
    ``min_contrast`` (grey levels), or the window's outside pixels spread (RMS about their
    mean) over ``max_backdrop_spread`` (a textured backdrop, whose mean is no colour behind
    the edge), the pixel keeps its side (the fraction is noise there).
    Returns the largest region of the result.
    """
    pixels = image.astype(np.float32)
    marked = region.astype(np.uint8)
    shrink = _disc(settings.outline_band_px)
    inside = cv2.erode(marked, shrink).astype(bool)
    outside = cv2.erode(1 - marked, shrink).astype(bool)
    step = _disc(1)
    second = cv2.erode(marked, step)
    near_inside = second.astype(bool) & ~cv2.erode(second, step).astype(bool)
    window = settings.outline_window_px
    person_colour, person_weight = _window_mean(pixels, inside, window)
    edge_colour, edge_weight = _window_mean(pixels, near_inside, window)
    backdrop_colour, backdrop_weight = _window_mean(pixels, outside, window)
    square, _ = _window_mean(np.einsum("hwc,hwc->hw", pixels, pixels), outside, window)
    spread = np.sqrt(np.maximum(square - np.einsum("hwc,hwc->hw", backdrop_colour,
                                                   backdrop_colour), 0))
    no_backdrop_near = backdrop_weight == 0
    backdrop_colour[no_backdrop_near] = backdrop[no_backdrop_near]
    band = ~inside & ~outside & (person_weight > 0)
    at, backdrop_at = pixels[band], backdrop_colour[band]
    fraction = _mixing_fraction(at, person_colour[band], backdrop_at)
    edge_fraction = np.where(edge_weight[band] > 0,
                             _mixing_fraction(at, edge_colour[band], backdrop_at), fraction)
    decided = np.minimum(fraction, edge_fraction) >= 0.5
    trusted = ((np.linalg.norm(person_colour[band] - backdrop_at, axis=1) >= min_contrast)
               & (spread[band] <= max_backdrop_spread))
    refined = region.copy()
    refined[band] = np.where(trusted, decided, region[band])
    labels, stats = _components(refined)
    return labels == int(np.argmax(stats[:, cv2.CC_STAT_AREA])) + 1


def _fill_small_holes(region: np.ndarray, settings: SilhouetteSettings) -> np.ndarray:
    """Fill enclosed background pieces smaller than ``max_hole_fraction`` of the region."""
    # 4-connected background, the complement of 8-connected foreground.
    _, labels, stats, _ = cv2.connectedComponentsWithStats((~region).astype(np.uint8), connectivity=4)
    small = stats[:, cv2.CC_STAT_AREA] <= settings.max_hole_fraction * region.sum()
    small[0] = False  # label 0: the region itself (zero in the complement)
    small[labels[0, 0]] = False  # the backdrop around the person (the region does not touch the frame)
    return region | small[labels]


def extract_silhouette(
    image_bgr: np.ndarray,
    background: np.ndarray | None = None,
    settings: SilhouetteSettings = SilhouetteSettings(),
    segmenter: str = "auto",
) -> np.ndarray:
    """The person's silhouette in a photo.

    Args:
        image_bgr: (H, W, 3) uint8 BGR photo, any orientation, as recorded or undistorted
            (the border band must show backdrop, not the black corners undistortion can leave).
        background: optional (H, W, 3) uint8 BGR background plate: the same view
            without the person. Without one the backdrop is modelled from the frame border.
            The learned segmentation takes it as evidence (the module docstring's "Rooms").
        settings: thresholds.
        segmenter: one of :data:`~bodyfit.calib.segmenters.SEGMENTERS`: ``"backdrop"``
            steps 1-5, ``"learned"`` the module docstring's "Rooms", ``"auto"`` the
            backdrop's where a plain backdrop surrounds the person (judged without the
            plate), else the learned.

    Returns:
        (H, W) bool mask, True on the person.

    Raises:
        UserError: backdrop not plain (or plate not matching) with ``"backdrop"``, no
            person, person touching the frame edge, several people.
    """
    if image_bgr.ndim != 3 or image_bgr.shape[2] != 3 or image_bgr.dtype != np.uint8:
        raise ValueError(
            f"extract_silhouette() takes an (H, W, 3) uint8 image, got {image_bgr.shape} {image_bgr.dtype}"
        )
    if min(image_bgr.shape[:2]) < MIN_PHOTO_SIDE_PX:
        raise UserError(
            f"the photo is {image_bgr.shape[1]}x{image_bgr.shape[0]} pixels; a silhouette needs a photo of at "
            f"least {MIN_PHOTO_SIDE_PX} pixels each way (use the camera's full resolution)"
        )
    check_segmenter(segmenter)
    if background is not None and background.shape != image_bgr.shape:
        raise UserError(
            f"the background plate is {background.shape[1]}x{background.shape[0]} but the photo is "
            f"{image_bgr.shape[1]}x{image_bgr.shape[0]}; take both with the same camera setting"
        )
    if segmenter != "learned":
        try:
            if segmenter == "auto" and background is not None:
                _backdrop_silhouette(image_bgr, None, settings)  # surrounded without the plate?
            return _backdrop_silhouette(image_bgr, background, settings)
        except _NotSurrounded as refused:
            if segmenter == "backdrop":
                raise
            log.info("no plain backdrop surrounds the person (%s): the learned segmentation",
                     refused)
    return _learned_silhouette(image_bgr, background, settings)


def _learned_silhouette(image_bgr: np.ndarray, plate: np.ndarray | None,
                        settings: SilhouetteSettings) -> np.ndarray:
    """(H, W) bool: the learned segmentation's person, its outline refined (module
    docstring, "Rooms"), with the room's background ``plate`` (H, W, 3) uint8 if given."""
    from bodyfit.calib.segment import person_segmenter  # LiteRT loads only when used

    found = person_segmenter()(image_bgr)
    region = _person_region(found.probability >= _LEARNED_THRESHOLD, settings)
    region = _person_region(_graph_cut(image_bgr, region, found.landmarks, settings, plate),
                            settings)
    backdrop, _ = _window_mean(image_bgr.astype(np.float32), ~region,
                               settings.surroundings_window_px)
    for _ in range(settings.outline_passes):
        region = _refine_outline(image_bgr, region, backdrop, settings,
                                 settings.learned_min_contrast,
                                 settings.learned_max_backdrop_spread)
    return _fill_small_holes(region, settings)


def _head_zones(landmarks: np.ndarray, rows: np.ndarray, cols: np.ndarray,
                settings: SilhouetteSettings) -> tuple[np.ndarray, np.ndarray]:
    """(beyond, loose): (len(rows), len(cols)) bool over the pixels at ``rows`` x ``cols``
    (1-D pixel indices), True above the neck's middle further than ``head_radius`` and
    ``head_core_radius`` from the ears' midpoint. The neck's middle is halfway from the
    ears' midpoint to the shoulders' along the body's axis (ankles to eyes), so the zones
    hold in a photo of any orientation; ``landmarks`` (33, 5) are BlazePose's (x, y in
    pixels; :class:`~bodyfit.calib.segment.PersonFound`)."""
    ears, eyes = landmarks[[7, 8], :2].mean(0), landmarks[[2, 5], :2].mean(0)
    shoulders, ankles = landmarks[[11, 12], :2].mean(0), landmarks[[27, 28], :2].mean(0)
    length = float(np.linalg.norm(eyes - ankles))
    up = (eyes - ankles) / max(length, 1e-6)
    dx, dy = (cols[None, :] - ears[0]).astype(np.float32), (rows[:, None] - ears[1]).astype(np.float32)
    above = dx * up[0] + dy * up[1] > 0.5 * float((shoulders - ears) @ up)
    squared = dx * dx + dy * dy
    return (above & (squared > (settings.head_radius * length) ** 2),
            above & (squared > (settings.head_core_radius * length) ** 2))


def _plate_evidence(image: np.ndarray, plate: np.ndarray, learned: np.ndarray,
                    settings: SilhouetteSettings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What a room's background ``plate`` (H, W, 3) uint8 tells of the ``image`` (H, W, 3)
    uint8 about the ``learned`` (H, W) bool region: (the photo minus the plate, plus 128,
    (H, W, 3) uint8; unlike (H, W) bool, pixels unlike the plate's colour or a shadow or
    highlight of it; room (H, W) bool, solid patches of the plate's colour). The plate is
    first scaled by the exposure's ratio, the median over the pixels
    ``_EXPOSURE_MARGIN_PX`` away from the region (a phone meters the empty room a little
    differently).

    Raises:
        UserError: less than ``_MIN_PLATE_MATCH`` of those pixels have the plate's colour.
    """
    pixels, room_colour = image.astype(np.float32), plate.astype(np.float32)
    away = ~cv2.dilate(learned.astype(np.uint8), _disc(_EXPOSURE_MARGIN_PX)).astype(bool)
    if away.any():
        room_colour *= float(np.median(pixels[away].sum(axis=1)
                                       / np.maximum(room_colour[away].sum(axis=1), 1.0)))
    difference = np.abs(pixels - room_colour).max(axis=2)
    brightness, chroma = _compare(image, room_colour)
    unlike = (difference > settings.plate_unlike_grey) & (
        (chroma > settings.plate_unlike_chroma) | (brightness < settings.shadow_min_brightness)
        | (brightness > settings.max_highlight_brightness))
    unlike = cv2.morphologyEx(unlike.astype(np.uint8), cv2.MORPH_OPEN, _disc(1)).astype(bool)
    room = cv2.morphologyEx((difference <= settings.plate_same_grey).astype(np.uint8),
                            cv2.MORPH_OPEN, _disc(_ROOM_PATCH_RADIUS_PX)).astype(bool)
    matched = float(room[away].mean()) if away.any() else 1.0
    if matched < _MIN_PLATE_MATCH:
        raise UserError(
            f"the background plate does not match the photo: only {matched:.0%} of the room "
            "around the person has the plate's colour; take the plate from the same spot "
            "without moving the phone (a tripod), or leave it out")
    return np.clip(pixels - room_colour + 128, 0, 255).astype(np.uint8), unlike, room


def _graph_cut(image: np.ndarray, learned: np.ndarray, landmarks: np.ndarray,
               settings: SilhouetteSettings, plate: np.ndarray | None = None) -> np.ndarray:
    """(H, W) bool: OpenCV's GrabCut (colour models of the person and the room, the cut
    drawn along the photo's edges) started from the ``learned`` region: person for sure
    ``grabcut_inside_px`` inside its outline, room for sure ``grabcut_outside_px`` outside
    it, either in between; over the box about that band only. About the head the
    ``landmarks``' zones (:func:`_head_zones`) are room: the further one for sure, the
    nearer one at first. With a room's background ``plate`` (:func:`_plate_evidence`)
    GrabCut cuts the photo minus the plate; the patches unlike the plate that touch the
    band are person at first (a foot the learned region lost), with a band about them,
    and the solid patches of the plate's colour are room for sure (a chair the learned
    region took in). The same photo gives the same cut whatever ran before (OpenCV's
    generator is seeded)."""
    marked = learned.astype(np.uint8)
    near = cv2.dilate(marked, _disc(settings.grabcut_outside_px)).astype(bool)
    labels = np.full(learned.shape, cv2.GC_BGD, np.uint8)
    labels[near] = cv2.GC_PR_BGD
    labels[learned] = cv2.GC_PR_FGD
    labels[cv2.erode(marked, _disc(settings.grabcut_inside_px)).astype(bool)] = cv2.GC_FGD
    if plate is not None:
        image, unlike, room = _plate_evidence(image, plate, learned, settings)
        _, patches = cv2.connectedComponents(unlike.astype(np.uint8), connectivity=8)
        touching = np.unique(patches[near & unlike])
        seeds = np.isin(patches, touching[touching > 0]) & ~learned
        band = cv2.dilate((learned | seeds).astype(np.uint8), _disc(settings.grabcut_outside_px))
        labels[band.astype(bool) & (labels == cv2.GC_BGD)] = cv2.GC_PR_BGD
        labels[seeds] = cv2.GC_PR_FGD
        labels[room] = cv2.GC_BGD
    rows, cols = np.nonzero(labels != cv2.GC_BGD)
    box = (slice(max(rows.min() - 1, 0), rows.max() + 2), slice(max(cols.min() - 1, 0), cols.max() + 2))
    boxed = np.ascontiguousarray(labels[box])
    beyond, loose = _head_zones(landmarks, np.arange(learned.shape[0])[box[0]],
                                np.arange(learned.shape[1])[box[1]], settings)
    boxed[loose & learned[box] & (boxed != cv2.GC_BGD)] = cv2.GC_PR_BGD
    boxed[beyond] = cv2.GC_BGD
    cv2.setRNGSeed(0)  # GrabCut's k-means starts from OpenCV's global generator
    cv2.grabCut(np.ascontiguousarray(image[box]), boxed, None, np.zeros((1, 65)),
                np.zeros((1, 65)), settings.grabcut_iterations, cv2.GC_INIT_WITH_MASK)
    cut = np.zeros(learned.shape, bool)
    cut[box] = (boxed == cv2.GC_FGD) | (boxed == cv2.GC_PR_FGD)
    return cut


def _backdrop_silhouette(image_bgr: np.ndarray, background: np.ndarray | None,
                         settings: SilhouetteSettings) -> np.ndarray:
    """(H, W) bool: steps 1-5 of the module docstring.

    Raises:
        _NotSurrounded: the border is no plain backdrop (or the plate does not match it),
            the person touches the frame's edge, or several person-sized regions.
        UserError: no person.
    """
    band = _border_band(image_bgr.shape[:2], settings.border_band_fraction)
    backdrop = _fit_backdrop(image_bgr, band) if background is None else background.astype(np.float32)
    brightness, chroma = _compare(image_bgr, backdrop)

    lit = band & (brightness >= settings.shadow_min_brightness) & (brightness <= settings.max_highlight_brightness)
    if not lit.any():
        raise _NotSurrounded(
            "the frame border shows no lit backdrop (it is black, or far darker or brighter than "
            f"the {'background plate' if background is not None else 'modelled backdrop'}); light "
            "a plain backdrop evenly and let it fill the whole frame"
        )
    lit_chroma = chroma[lit]
    chroma_threshold = max(settings.min_chroma_distortion, settings.noise_factor * float(np.median(lit_chroma)))
    foreground = (
        (chroma > chroma_threshold)
        | (brightness < settings.shadow_min_brightness)
        | (brightness > settings.max_highlight_brightness)
    )
    border_foreground = float(foreground[band].mean())
    chroma_spread = float(np.percentile(lit_chroma, 95))
    log.info(
        "backdrop: chroma spread %.1f, threshold %.1f grey levels, %.1f %% of the border unlike it",
        chroma_spread,
        chroma_threshold,
        100 * border_foreground,
    )
    if (
        chroma_spread > settings.max_backdrop_chroma_distortion
        or border_foreground > settings.max_border_foreground_fraction
    ):
        if background is not None:
            raise _NotSurrounded(
                "the background plate does not match the photo around the edges; keep the camera and "
                "the lights still between the plate and the photo"
            )
        raise _NotSurrounded(
            f"the backdrop is not plain ({border_foreground:.0%} of the frame border differs from it, colour "
            f"spread {chroma_spread:.0f} grey levels); use a single-colour backdrop filling the whole frame, "
            "or give a background plate (--background)"
        )
    region = _person_region(_clean(foreground, settings), settings)
    for _ in range(settings.outline_passes):
        region = _refine_outline(image_bgr, region, backdrop, settings)
    return _fill_small_holes(region, settings)


def load_mask(path: str | Path, settings: SilhouetteSettings = SilhouetteSettings()
              ) -> np.ndarray:
    """A user-made silhouette mask: (H, W) bool, the largest 8-connected region of the
    pixels brighter than mid-grey (a segmentation network's stray blobs dropped: a shoe
    beside the feet, a speck of the room).

    The mask must be of the undistorted, upright photo (e.g. drawn over the output of
    ``calib undistort``). Raises UserError when it cannot be read, is empty or all white,
    or holds a second region of at least ``settings.max_second_region_ratio`` of the
    largest's area (two people).
    """
    path = Path(path)
    pixels, _, _ = read_image_file(path, cv2.IMREAD_GRAYSCALE)
    mask = pixels > 127
    if not mask.any() or mask.all():
        raise UserError(
            f"{path}: the mask is all {'white' if mask.all() else 'black'}; the person must be white on black"
        )
    labels, stats = _components(mask)
    largest, similar = _largest_region(stats[:, cv2.CC_STAT_AREA], settings)
    if similar > 1:
        raise UserError(f"{path}: the mask holds {similar} person-sized regions; give a mask "
                        "of one person")
    return labels == largest + 1


def photo_silhouette(
    photo_path: str | Path,
    camera: Camera | None = None,
    background_path: str | Path | None = None,
    settings: SilhouetteSettings = SilhouetteSettings(),
    segmenter: str = "auto",
) -> np.ndarray:
    """Silhouette of the person in a photo file, as the fitter needs it.

    The silhouette is extracted from the photo as recorded (sensor frame, so the whole
    border is real backdrop), then undistorted with ``camera`` when given (bilinear,
    thresholded at one half: the outline keeps sub-pixel accuracy), then turned upright
    by the photo's EXIF orientation.

    Args:
        photo_path: the person's photo.
        camera: the calibrated camera, or None to skip undistortion.
        background_path: optional background plate photo (same spot, no person).
        settings: thresholds.
        segmenter: how the person is found (:func:`extract_silhouette`).

    Returns:
        (H', W') bool mask of the undistorted, upright photo.
    """
    photo = read_photo(photo_path)
    if camera is not None:
        camera.check_image(photo.pixels, str(photo_path))
    plate = None if background_path is None else read_photo(background_path).pixels
    mask = extract_silhouette(photo.pixels, plate, settings, segmenter)
    if camera is not None:
        mask = undistort_image(mask.astype(np.float32), camera, str(photo_path)) > 0.5
    log.info("%s: silhouette of %d pixels", photo_path, int(mask.sum()))
    return to_upright(mask.view(np.uint8), photo.orientation).astype(bool)
