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

from bodyfit.calib.camera import Camera
from bodyfit.common.files import write_atomic
from bodyfit.fitter.demo.studio_photos import lens_photo
from bodyfit.fitter.model.body_model import PART_NAMES, BodyModel

__all__ = ["PhotoEffects", "record", "write_photos"]


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


def record(image: np.ndarray, effects: PhotoEffects, rng: np.random.Generator) -> bytes:
    """JPEG bytes of ``image`` (H, W, 3) uint8 BGR after uneven light and sensor noise."""
    h, w = image.shape[:2]
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    x, y = (x - w / 2) / (w / 2), (y - h / 2) / (h / 2)  # -1..1
    slope_x, slope_y = rng.uniform(-effects.light_slope, effects.light_slope, 2)
    fall = rng.uniform(0.5, 1.0) * effects.vignette
    gain = (1.0 + slope_x * x + slope_y * y) * (1.0 - fall * (x * x + y * y) / 2)
    noisy = image * gain[..., None] + rng.normal(0.0, effects.noise_dn, image.shape)
    ok, data = cv2.imencode(".jpg", np.clip(np.rint(noisy), 0, 255).astype(np.uint8),
                            [cv2.IMWRITE_JPEG_QUALITY, effects.jpeg_quality])
    if not ok:
        raise RuntimeError("OpenCV could not encode a JPEG")
    return data.tobytes()


def write_photos(folder: Path, model: BodyModel, front: np.ndarray, side: np.ndarray,
                 camera: Camera, distance_m: float, camera_height_m: float,
                 effects: PhotoEffects, rng: np.random.Generator) -> tuple[Path, Path]:
    """Write front.jpg and side.jpg of the posed bodies ``front`` and ``side`` (V, 3)
    metres into ``folder``, both from ``distance_m`` and ``camera_height_m``; return
    their paths."""
    paths = []
    for view, vertices in (("front", front), ("side", side)):
        image = lens_photo(vertices, model, view, PART_NAMES, camera, distance_m,
                           camera_height_m)
        path = Path(folder) / f"{view}.jpg"
        write_atomic(path, record(image, effects, rng))
        paths.append(path)
    return paths[0], paths[1]
