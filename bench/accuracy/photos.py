"""The accuracy benchmark's photos: a phone camera's record of a posed body.

Independent of the fitter's kernels: the body is painted by
:func:`bodyfit.fitter.demo.studio_photos.lens_photo` (OpenCV polygons far to near, the
person's outline from each pixel's sub-pixel coverage, through a pinhole and then the
lens's distortion), then
:func:`record` adds what a real sensor and a real room add (:class:`PhotoEffects`).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cv2
import numpy as np
from PIL import ExifTags, Image

from bench.accuracy.rooms import PLATE_EXPOSURE, RoomScene, room_photo
from bodyfit.calib.camera import Camera
from bodyfit.calib.images import FULL_FRAME_DIAGONAL_MM, encode_image
from bodyfit.common.files import write_atomic
from bodyfit.fitter.demo.studio_photos import lens_photo
from bodyfit.fitter.model.body_model import PART_NAMES, BodyModel

__all__ = ["PhotoEffects", "Shot", "exif_focal", "light_gain", "record", "write_photos"]

#: The phone sensor's diagonal assumed for EXIF's FocalLength, mm (a 1/1.7" sensor).
_SENSOR_DIAGONAL_MM = 9.5


@dataclasses.dataclass(frozen=True)
class Shot:
    """Where one photo was taken from: ``distance_m`` from the body's vertical axis,
    ``camera_height_m`` above the floor, pitched ``pitch_deg`` (positive looks down)."""

    distance_m: float
    camera_height_m: float
    pitch_deg: float = 0.0


@dataclasses.dataclass(frozen=True)
class PhotoEffects:
    """What the room and the sensor do to a photo (:func:`record`).

    Attributes:
        light_slope: the light falls off across the picture: a gain of 1 +- this at the
            left/right and top/bottom edges (each photo a random direction and size up to it).
        vignette: the gain drops by up to this much from the centre to the corners.
        noise_dn: sensor noise, standard deviation in grey levels (0-255), per channel.
        jpeg_quality: the photo is stored as a JPEG of this quality (OpenCV's 0-100).
    """

    light_slope: float = 0.15
    vignette: float = 0.25
    noise_dn: float = 3.0
    jpeg_quality: int = 90


def exif_focal(camera: Camera) -> bytes:
    """An EXIF block (``Exif\\0\\0`` and its TIFF structure) that says ``camera``'s focal
    length as a phone writes it: FocalLengthIn35mmFilm, the focal length scaled from the
    photo's diagonal to a full frame's and rounded to a millimetre, and FocalLength in mm
    on a sensor of :data:`_SENSOR_DIAGONAL_MM`."""
    width, height = camera.image_size_px
    full_frame_mm = camera.K[0, 0] * FULL_FRAME_DIAGONAL_MM / np.hypot(width, height)
    exif = Image.Exif()
    fields = exif.get_ifd(ExifTags.IFD.Exif)
    fields[ExifTags.Base.FocalLengthIn35mmFilm] = int(round(full_frame_mm))
    fields[ExifTags.Base.FocalLength] = round(
        full_frame_mm * _SENSOR_DIAGONAL_MM / FULL_FRAME_DIAGONAL_MM, 2)
    return exif.tobytes()


def light_gain(size_px: tuple[int, int], effects: PhotoEffects,
               rng: np.random.Generator) -> np.ndarray:
    """(H, W) float32 gain of uneven light on a photo of ``size_px`` (W, H): a random
    slope across the frame times a random vignette."""
    w, h = size_px
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    x, y = (x - w / 2) / (w / 2), (y - h / 2) / (h / 2)  # -1..1
    slope_x, slope_y = rng.uniform(-effects.light_slope, effects.light_slope, 2)
    fall = rng.uniform(0.5, 1.0) * effects.vignette
    return (1.0 + slope_x * x + slope_y * y) * (1.0 - fall * (x * x + y * y) / 2)


def record(image: np.ndarray, effects: PhotoEffects, rng: np.random.Generator,
           exif: bytes = b"", gain: np.ndarray | None = None) -> bytes:
    """JPEG bytes of ``image`` (H, W, 3) uint8 BGR after uneven light (``gain`` (H, W),
    else drawn by :func:`light_gain`) and sensor noise, with the EXIF block ``exif``
    (:func:`exif_focal`) if given."""
    if gain is None:
        gain = light_gain((image.shape[1], image.shape[0]), effects, rng)
    noisy = image * gain[..., None] + rng.normal(0.0, effects.noise_dn, image.shape)
    ok, data = cv2.imencode(".jpg", np.clip(np.rint(noisy), 0, 255).astype(np.uint8),
                            [cv2.IMWRITE_JPEG_QUALITY, effects.jpeg_quality])
    if not ok:
        raise RuntimeError("OpenCV could not encode a JPEG")
    data = data.tobytes()
    if exif:  # an APP1 segment right after the start-of-image marker
        data = data[:2] + b"\xff\xe1" + (len(exif) + 2).to_bytes(2, "big") + exif + data[2:]
    return data


def write_photos(folder: Path, model: BodyModel, posed: dict[str, np.ndarray],
                 camera: Camera, shots: dict[str, Shot], effects: PhotoEffects,
                 rng: np.random.Generator, exif: bytes = b"",
                 scene: RoomScene | None = None) -> None:
    """Write front.jpg and side.jpg of the posed bodies ``posed`` ("front", "side" ->
    (V, 3) metres) into ``folder``, each from its ``shots`` place, with ``exif``; on the
    plain backdrop, or dressed in ``scene``'s room with truth_front.png and
    truth_side.png beside them, and plate_front.jpg and plate_side.jpg: the room from
    the same place without the person, in the same light, with its own noise and an
    exposure up to ``PLATE_EXPOSURE`` off (:mod:`.rooms`)."""
    plate_rng = None if scene is None else np.random.default_rng(scene.plate_seed)
    for view in ("front", "side"):
        shot = shots[view]
        if scene is None:
            image = lens_photo(posed[view], model, view, PART_NAMES, camera, shot.distance_m,
                               shot.camera_height_m, (shot.pitch_deg, 0.0))
        else:
            image, truth, plate = room_photo(posed[view], model, view, camera, shot.distance_m,
                                             shot.camera_height_m, shot.pitch_deg, scene)
            write_atomic(Path(folder) / f"truth_{view}.png",
                         encode_image(truth.astype(np.uint8) * 255, ".png"))
        gain = light_gain((image.shape[1], image.shape[0]), effects, rng)
        write_atomic(Path(folder) / f"{view}.jpg", record(image, effects, rng, exif, gain))
        if scene is not None:
            exposure = plate_rng.uniform(1 - PLATE_EXPOSURE, 1 + PLATE_EXPOSURE)
            write_atomic(Path(folder) / f"plate_{view}.jpg",
                         record(plate, effects, plate_rng, exif, gain * exposure))
