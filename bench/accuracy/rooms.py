"""The room benchmark's photos: the subjects dressed and photographed in ordinary rooms.

A set made with ``--rooms`` (:class:`~.subject_set.SetSettings`) photographs the same
bodies from the same camera places as the plain set of its kind, count and seed (each
room draw has its own random stream), so that its fits pair with the plain set's. What
changes:

- **the backdrop**: one of the room photos of ``bench/data/rooms/`` (README there),
  centre-cropped to the photo's aspect, scaled to its size, mirrored or not;
- **a contact shadow**: the room darkened under the feet, by up to
  ``SHADOW_DEPTH`` at the centre of a soft ellipse about the lowest rows of the body;
- **a background plate** per photo: the same room from the same place without the
  person (nor their shadow), as a user photographs it from a tripod for
  ``--background-front/--background-side``;
- **clothes**: each part painted as a person dresses it (:func:`dressed_colours`: skin,
  hair on the head's top and back, a top with long or short sleeves, trousers, shoes),
  shaded as :func:`bodyfit.fitter.output.render.render_pinhole` shades (by how squarely
  each face looks at the camera). An undressed, part-coloured body was found by
  MediaPipe's detector on a plain backdrop; dressed, the learned segmentation sees
  something like a person in a room.

Each subject folder also gets ``truth_front.png``/``truth_side.png``: the pixels the body
covers by more than half, through the same lens, for the silhouettes' wrong pixels
(:func:`.outlines.outline_errors`).
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import cv2
import numpy as np

from bodyfit.calib.camera import Camera
from bodyfit.calib.synthetic import distort_image
from bodyfit.fitter.demo.studio_photos import pinhole_layers
from bodyfit.fitter.model.body_model import PART_NAMES, BodyModel

__all__ = ["PLATE_EXPOSURE", "ROOMS_FOLDER", "SHADOW_DEPTH", "RoomScene", "draw_scene",
           "dressed_colours", "room_photo"]

ROOMS_FOLDER = Path(__file__).parents[1] / "data" / "rooms"
#: The contact shadow darkens the floor by this share at its centre.
SHADOW_DEPTH = 0.45
#: A background plate's exposure differs from its photo's by up to this share (a phone
#: meters the empty room a little differently).
PLATE_EXPOSURE = 0.03
# BGR palettes the clothes and the skin are drawn from
_SKIN = ((180, 200, 235), (140, 170, 215), (110, 145, 190), (70, 100, 145), (45, 65, 100))
_HAIR = ((25, 25, 30), (30, 45, 70), (45, 75, 115), (120, 170, 205), (150, 150, 155))
_TROUSERS = ((90, 50, 30), (35, 35, 35), (115, 150, 170), (110, 110, 110), (150, 105, 60))
_SHOES = ((25, 25, 25), (225, 225, 225), (40, 60, 95))
_TOP_PARTS = ("chest", "waist", "arm")
_HAIR_ABOVE = 0.55  # share of the head's height above which its faces are hair (and behind)


@dataclasses.dataclass(frozen=True)
class RoomScene:
    """One subject's room and clothes (the same for both photos).

    Attributes:
        room: the room photo's file name in ``ROOMS_FOLDER``; mirrored: flipped left-right.
        part_colours: (10, 3) uint8 BGR, ``PART_NAMES`` order.
        hair: (3,) uint8 BGR.
        plate_seed: the seed of the background plates' noise and exposure.
    """

    room: str
    mirrored: bool
    part_colours: np.ndarray
    hair: np.ndarray
    plate_seed: int


def draw_scene(rng: np.random.Generator) -> RoomScene:
    """A room and clothes, drawn from ``rng``."""
    rooms = sorted(path.name for path in ROOMS_FOLDER.glob("*.jpg"))
    skin = np.array(_SKIN[rng.integers(len(_SKIN))])
    hue, saturation, value = rng.integers(0, 180), rng.uniform(0.2, 0.8), rng.uniform(0.3, 0.9)
    top = cv2.cvtColor(np.uint8([[[hue, 255 * saturation, 255 * value]]]), cv2.COLOR_HSV2BGR)[0, 0]
    trousers = np.array(_TROUSERS[rng.integers(len(_TROUSERS))])
    colours = {"head": skin, "neck": skin, "hand": skin, "hip": trousers, "leg": trousers,
               "foot": np.array(_SHOES[rng.integers(len(_SHOES))]),
               "elbow": top if rng.random() < 0.6 else skin}  # long or short sleeves
    colours |= {part: top for part in _TOP_PARTS}
    part_colours = np.array([colours[name] for name in PART_NAMES], np.uint8)
    return RoomScene(rooms[rng.integers(len(rooms))], bool(rng.random() < 0.5), part_colours,
                     np.array(_HAIR[rng.integers(len(_HAIR))], np.uint8),
                     int(rng.integers(2**31)))


def dressed_colours(model: BodyModel, vertices: np.ndarray, scene: RoomScene) -> np.ndarray:
    """(F, 3) uint8 BGR per face of ``model`` posed as ``vertices`` (V, 3) metres: its
    part's colour, and the hair's on the head's faces in its top ``1 - _HAIR_ABOVE`` or
    behind its centre above the ears."""
    colours = scene.part_colours[model.face_parts].copy()
    head = model.face_parts == PART_NAMES.index("head")
    centres = vertices[model.faces[head]].mean(axis=1)
    low, high = centres[:, 2].min(), centres[:, 2].max()
    height = (centres[:, 2] - low) / max(high - low, 1e-9)
    behind = centres[:, 1] > centres[:, 1].mean()  # -y is forward
    colours[np.flatnonzero(head)[(height > _HAIR_ABOVE) | (behind & (height > 0.3))]] = scene.hair
    return colours


@functools.cache
def _room(name: str, size_px: tuple[int, int]) -> np.ndarray:
    """(H, W, 3) uint8 BGR: room ``name`` centre-cropped to ``size_px``'s aspect and scaled
    to it."""
    image = cv2.imread(str(ROOMS_FOLDER / name))
    height, width = image.shape[:2]
    aspect = size_px[0] / size_px[1]
    if width / height > aspect:
        crop = round(height * aspect)
        image = image[:, (width - crop) // 2:(width - crop) // 2 + crop]
    else:
        crop = round(width / aspect)
        image = image[(height - crop) // 2:(height - crop) // 2 + crop]
    return cv2.resize(image, size_px, interpolation=cv2.INTER_AREA)


def _shadowed(room: np.ndarray, body: np.ndarray) -> np.ndarray:
    """``room`` darkened under the feet of the ``body`` mask (H, W) bool: a soft ellipse
    about its lowest rows (the bottom 3 % of its height), twice as wide as they are."""
    rows, _ = np.nonzero(body)
    low = body[rows.max() - max(2, (rows.max() - rows.min()) * 3 // 100):rows.max() + 1]
    cols = np.flatnonzero(low.any(axis=0))
    centre = (int(cols.mean()), int(rows.max()))
    axes = (int(0.7 * np.ptp(cols)) + 10, int(0.12 * np.ptp(cols)) + 6)
    shade = np.zeros(body.shape, np.float32)
    cv2.ellipse(shade, centre, axes, 0, 0, 360, 1.0, -1)
    shade = cv2.GaussianBlur(shade, (0, 0), axes[1])
    return (room * (1 - SHADOW_DEPTH * shade)[..., None]).astype(np.uint8)


def room_photo(vertices: np.ndarray, model: BodyModel, view: str, camera: Camera,
               distance_m: float, camera_height_m: float, pitch_deg: float,
               scene: RoomScene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(photo (H, W, 3) uint8 BGR, truth (H, W) bool, plate (H, W, 3) uint8 BGR) of the
    posed body ``vertices`` (V, 3) metres, dressed, in ``scene``'s room, through
    ``camera`` from its place, as :func:`bodyfit.fitter.demo.studio_photos.lens_photo`
    photographs it on the plain backdrop; truth: the pixels it covers by more than half,
    through the same lens; plate: the room alone, through the same lens."""
    size = tuple(camera.image_size_px)
    image, body = pinhole_layers(np.asarray(vertices, np.float64), model, view, PART_NAMES,
                                 camera.K, size, distance_m, camera_height_m, (pitch_deg, 0.0),
                                 dressed_colours(model, vertices, scene))
    room = _room(scene.room, size)
    plate = np.ascontiguousarray(room[:, ::-1]) if scene.mirrored else room.copy()
    canvas = _shadowed(plate, body)
    canvas[body] = image[body]
    truth = body.astype(np.uint8) * 255
    if np.any(camera.dist):
        # beyond the pinhole picture's edge the lens sees the photo's mean colour
        fill = tuple(float(v) for v in canvas.reshape(-1, 3).mean(axis=0))
        canvas, plate = (distort_image(picture, camera.K, camera.dist, fill)
                         for picture in (canvas, plate))
        truth = distort_image(truth, camera.K, camera.dist)
    return canvas, truth > 127, plate

