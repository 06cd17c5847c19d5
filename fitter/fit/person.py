"""The person's inputs: two photos (or the user's own masks), the stature, the camera.

Photos go through calib: read in the sensor frame, silhouette on the plain backdrop
(optionally against a background plate), undistorted with the camera when one is given,
turned upright by EXIF (:func:`bodyfit.calib.silhouette.photo_silhouette`). A user's
mask replaces the extraction; it must be of the undistorted, upright photo.

The side photo may show either side of the person: one taken from the person's right
(given, or told by :func:`bodyfit.fitter.fit.facing.side_seen`) is mirrored, mask and
camera, into the photo from the left the fit expects (:func:`mirrored_side`). The camera:
camera.json when given; else the focal length the photos' EXIF states; else a typical
phone's (:class:`PersonPhotos` records which).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bodyfit.calib.camera import load_camera
from bodyfit.calib.images import read_photo, to_upright
from bodyfit.calib.segmenters import check_segmenter
from bodyfit.calib.silhouette import SilhouetteSettings, load_mask, photo_silhouette
from bodyfit.calib.undistort import undistort_image
from bodyfit.common.errors import UserError
from bodyfit.common.files import check_input_file
from bodyfit.fitter.check.photos import PhotoCheckFailed, ViewVerdict, check_view, failed_lines
from bodyfit.fitter.fit.facing import SIDE_FROM, side_seen
from bodyfit.fitter.fit.pinhole_canvas import (PHONE_HFOV_DEG, phone_intrinsics,
                                               upright_intrinsics)

__all__ = ["PersonInputs", "PersonPhotos", "STATURE_RANGE_CM", "MASS_RANGE_KG",
           "checked_photo", "checked_photos", "mirrored_side", "person_masks", "upright_photo",
           "view_intrinsics", "person_silhouettes"]

#: Statures bodyfit accepts, centimetres (adults and teenagers; a value outside is
#: most likely given in other units).
STATURE_RANGE_CM = (100.0, 250.0)
#: The body masses ``--mass-kg`` accepts, kilograms (another unit, pounds, is refused
#: where it falls outside).
MASS_RANGE_KG = (25.0, 300.0)
SEXES = ("female", "male", "unknown")
#: The narrowest front silhouette accepted, as its width over its height: the arms held
#: out from the body. The mean body at the search's lowest arm abduction
#: (``person_fit.ARMS_LOWER_DEG``) is 0.40 wide (0.37-0.44 with any one shape component
#: at +-3 sigma); with its arms hanging down, 0.25. The standing set's front photos:
#: 0.55-0.86.
FRONT_MIN_ASPECT = 0.32
#: The widest side silhouette accepted, as a share of the front one's aspect. The standing
#: set's: 0.20-0.35; the widest-bellied model body's side (0.32) against its front at the
#: lowest arms (0.43): 0.75. A second front photo given as the side: about 1; a broad
#: body's front with the arms hanging against it: 0.86 (tests/fitter/test_run.py).
SIDE_MAX_SHARE = 0.8


@dataclasses.dataclass(frozen=True)
class PersonInputs:
    """What the user gives about one person (paths as given).

    Attributes:
        front, side: the photos: front in an A-pose, side with the arms hanging down.
        height_cm: stature, centimetres.
        camera: camera.json from ``calib capture``, or None.
        mask_front, mask_side: the user's own silhouettes (white person on black), or None.
        background_front, background_side: background plates, or None.
        sex: "female", "male" or "unknown" (read by the learned start,
            :mod:`bodyfit.fitter.fit.learned_start`).
        segmenter: how the photos' silhouettes are taken, one of
            :data:`bodyfit.calib.segmenters.SEGMENTERS`.
        check: run the photography check (:mod:`bodyfit.fitter.check.photos`) before
            the fit (``--no-check``: False).
        mass_kg: the body's mass, kilograms, or None (the girths are scaled to it,
            :mod:`bodyfit.fitter.fit.mass_volume`, and the measurements' prior reads it,
            :mod:`bodyfit.fitter.fit.measurement_prior`).
        side_from: which side of the person the side photo shows, one of
            :data:`~bodyfit.fitter.fit.facing.SIDE_FROM`.
    """

    front: str
    side: str
    height_cm: float
    camera: str | None = None
    mask_front: str | None = None
    mask_side: str | None = None
    background_front: str | None = None
    background_side: str | None = None
    sex: str = "unknown"
    segmenter: str = "auto"
    check: bool = True
    mass_kg: float | None = None
    side_from: str = "auto"

    def validate(self) -> None:
        lo, hi = STATURE_RANGE_CM
        if not lo <= self.height_cm <= hi:
            raise UserError(f"--height-cm must be a stature in centimetres, {lo:.0f}-{hi:.0f}; "
                            f"got {self.height_cm:g}")
        lo, hi = MASS_RANGE_KG
        if self.mass_kg is not None and not lo <= self.mass_kg <= hi:
            raise UserError(f"--mass-kg must be a body mass in kilograms, {lo:.0f}-{hi:.0f}; "
                            f"got {self.mass_kg:g}")
        if self.sex not in SEXES:
            raise UserError(f"--sex must be one of {', '.join(SEXES)}, got {self.sex!r}")
        if self.side_from not in SIDE_FROM:
            raise UserError(f"--side-from must be one of {', '.join(SIDE_FROM)}, "
                            f"got {self.side_from!r}")
        self.validate_photos()

    def validate_photos(self) -> None:
        """The segmenter and the files (what the photography check reads)."""
        check_segmenter(self.segmenter)
        for path in (self.front, self.side, self.camera, self.mask_front, self.mask_side,
                     self.background_front, self.background_side):
            if path is not None:
                check_input_file(path)


def _view_mask(photo: str, mask: str | None, background: str | None, camera,
               segmenter: str) -> np.ndarray:
    if mask is not None:
        return load_mask(mask)
    return photo_silhouette(photo, camera, background, SilhouetteSettings(), segmenter)


def _masks(inputs: PersonInputs, camera) -> dict[str, np.ndarray]:
    return {"front": _view_mask(inputs.front, inputs.mask_front, inputs.background_front,
                                camera, inputs.segmenter),
            "side": _view_mask(inputs.side, inputs.mask_side, inputs.background_side, camera,
                               inputs.segmenter)}


def upright_photo(path: str, camera) -> np.ndarray:
    """(H, W, 3) uint8 BGR, the photo undistorted (with a camera) and turned upright, as
    its silhouette is."""
    photo = read_photo(path)
    pixels = photo.pixels if camera is None else undistort_image(photo.pixels, camera, path)
    return to_upright(pixels, photo.orientation)


def _upright_photos(inputs: PersonInputs, camera) -> dict[str, np.ndarray]:
    return {view: upright_photo(getattr(inputs, view), camera) for view in ("front", "side")}


def _camera(inputs: PersonInputs):
    """The calibrated camera of ``inputs``, or None."""
    return load_camera(inputs.camera) if inputs.camera else None


def _verdicts(masks: dict[str, np.ndarray], photos: dict[str, np.ndarray]
              ) -> list[ViewVerdict]:
    """The photography check of each view, front then side
    (:func:`bodyfit.fitter.check.photos.check_view`)."""
    return [check_view(view, photos[view], masks[view]) for view in ("front", "side")]


def checked_photos(inputs: PersonInputs) -> list[ViewVerdict]:
    """The photography check of the person's photos, front then side
    (:func:`checked_photo`)."""
    return [checked_photo(inputs, view) for view in ("front", "side")]


def checked_photo(inputs: PersonInputs, view: str) -> ViewVerdict:
    """The photography check of the person's ``view`` photo ("front" or "side") on its
    silhouette (without :func:`person_masks`' own refusals) and its :func:`upright_photo`.
    Of ``inputs`` it reads that photo, mask and background plate, the camera and the
    segmenter only.

    Raises:
        UserError: unreadable files, no person, several people, a person cut by the frame.
    """
    inputs.validate_photos()
    camera = _camera(inputs)
    photo = getattr(inputs, view)
    mask = _view_mask(photo, getattr(inputs, f"mask_{view}"),
                      getattr(inputs, f"background_{view}"), camera, inputs.segmenter)
    return check_view(view, upright_photo(photo, camera), mask)


def person_masks(inputs: PersonInputs) -> dict[str, np.ndarray]:
    """{"front": mask, "side": mask}: (H, W) bool silhouettes of the upright photos, as
    they are (the side one not mirrored).

    Raises:
        UserError: unreadable files, no person, several people, a person cut by the frame,
            photos of another size than the camera's, front and side swapped, two front
            photos, or a front photo with the arms against the body.
    """
    inputs.validate()
    return _framed(_masks(inputs, _camera(inputs)))


def _framed(masks: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``masks``, or UserError where they show a person cut by the frame, front and side
    swapped, two front photos, or a front photo with the arms against the body."""
    aspect = {}
    for view, mask in masks.items():
        rows, cols = np.nonzero(mask)
        for edge, touching in (("top", rows.min() == 0), ("bottom", rows.max() == mask.shape[0] - 1),
                               ("left", cols.min() == 0), ("right", cols.max() == mask.shape[1] - 1)):
            if touching:
                raise UserError(f"the person in the {view} silhouette touches the {edge} edge of "
                                "the frame: the whole body must be in the photo")
        aspect[view] = np.ptp(cols) / max(1, np.ptp(rows))
    if aspect["side"] > aspect["front"]:
        raise UserError(f"the side silhouette is wider than the front one ({aspect['side']:.2f} "
                        f"vs {aspect['front']:.2f} of the height): are --front and --side swapped?")
    if aspect["front"] < FRONT_MIN_ASPECT or aspect["side"] > SIDE_MAX_SHARE * aspect["front"]:
        raise UserError(f"the front silhouette is {aspect['front']:.2f} of its height wide and "
                        f"the side one {aspect['side']:.2f}: photograph the front with the arms "
                        "held out from the body (an A-pose), the side from the person's left or "
                        "right (README, 'How to photograph')")
    return masks


def view_intrinsics(inputs: PersonInputs, masks: dict[str, np.ndarray]
                    ) -> tuple[dict[str, np.ndarray], str]:
    """({"front": K, "side": K}: (3, 3) pixels, the camera matrix of each upright photo;
    where it came from, in a few words).

    camera.json's K turned as the photo's EXIF orientation turns it upright; without
    camera.json, the focal length the photo's EXIF states (principal point at the
    centre), else a typical phone's
    (:func:`bodyfit.fitter.fit.pinhole_canvas.phone_intrinsics`).

    Raises:
        UserError: a mirrored photo, or a mask of another size than the upright photo.
    """
    if inputs.camera is None:
        found, stated = {}, {}
        for view, mask in masks.items():
            photo = read_photo(getattr(inputs, view))
            found[view] = phone_intrinsics(mask.shape)
            if photo.focal_px is not None:
                found[view][0, 0] = found[view][1, 1] = photo.focal_px
            stated[view] = photo.focal_source or (
                f"assumed: a phone's main camera, {PHONE_HFOV_DEG:g} degrees across")
        if len(set(stated.values())) == 1:
            return found, stated["front"]
        return found, "; ".join(f"{view}: {source}" for view, source in stated.items())
    camera = load_camera(inputs.camera)
    found = {}
    for view, mask in masks.items():
        orientation = read_photo(getattr(inputs, view)).orientation
        k = upright_intrinsics(camera.K, camera.image_size_px, orientation)
        width, height = camera.image_size_px
        size = (height, width) if orientation in (1, 3) else (width, height)
        if mask.shape != size:
            raise UserError(f"the {view} silhouette is {mask.shape[1]}x{mask.shape[0]} pixels but "
                            f"the upright photo of the camera is {size[1]}x{size[0]}")
        found[view] = k
    return found, f"calibrated: {inputs.camera}"


@dataclasses.dataclass(frozen=True)
class PersonPhotos:
    """What a fit takes of the person's photos.

    Attributes:
        masks: view name -> (H, W) bool, the upright silhouettes; the side one as seen from
            the person's left (mirrored when the photo shows the right).
        intrinsics: view name -> (3, 3) K of those masks (None: orthographic views).
        camera_source: where K came from (:func:`view_intrinsics`; "" orthographic).
        side_from: which side of the person the side photo shows: "left" or "right" as
            given or told by the feet; "unknown" when the feet do not tell (the fit tries
            both).
        check: the photography check's warnings, one line each; None where it was not run.
        images: view name -> (H, W, 3) uint8 BGR, the photos undistorted and upright
            (:func:`upright_photo`), as taken (the side one not mirrored).
    """

    masks: dict[str, np.ndarray]
    intrinsics: dict[str, np.ndarray] | None
    camera_source: str
    side_from: str
    check: tuple[str, ...] | None
    images: dict[str, np.ndarray]


def person_silhouettes(inputs: PersonInputs, projection: str) -> PersonPhotos:
    """What a fit takes of the person's photos (:class:`PersonPhotos`): their masks
    (:func:`person_masks`), when ``inputs.check`` the photography check
    (:func:`checked_photos`; its problems stop the fit, its warnings are kept), and, for
    the ``"pinhole"`` projection, their cameras (:func:`view_intrinsics`); a side photo
    from the person's right mirrored.

    Raises:
        UserError: as :func:`person_masks` and :func:`view_intrinsics`.
        PhotoCheckFailed: the check's problems, one line each (after the masks' own
            refusals, each a single line that names the problem of the pair).
    """
    inputs.validate()
    camera = _camera(inputs)
    masks = _framed(_masks(inputs, camera))
    images = _upright_photos(inputs, camera)
    warnings = None
    if inputs.check:
        verdicts = _verdicts(masks, images)
        problems = failed_lines(verdicts)
        if problems:
            raise PhotoCheckFailed("\n".join(problems))
        warnings = tuple(line for verdict in verdicts for line in verdict.warnings)
    intrinsics, source = (view_intrinsics(inputs, masks) if projection == "pinhole"
                          else (None, ""))
    seen = (inputs.side_from if inputs.side_from != "auto" else side_seen(masks["side"])
            or "unknown")
    photos = PersonPhotos(masks, intrinsics, source, seen, warnings, images)
    return mirrored_side(photos) if seen == "right" else photos


def mirrored_side(photos: PersonPhotos) -> PersonPhotos:
    """``photos`` with the side mask and its camera mirrored left to right: a side photo
    from the person's right seen as the one from the left the fit expects (the model's
    bodies are left-right symmetric)."""
    masks = photos.masks | {"side": np.ascontiguousarray(photos.masks["side"][:, ::-1])}
    intrinsics = photos.intrinsics
    if intrinsics is not None:
        mirrored = intrinsics["side"].copy()
        mirrored[0, 2] = masks["side"].shape[1] - 1 - mirrored[0, 2]
        intrinsics = intrinsics | {"side": mirrored}
    return dataclasses.replace(photos, masks=masks, intrinsics=intrinsics)
