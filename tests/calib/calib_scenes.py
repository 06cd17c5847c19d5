"""Synthetic studio photos for the silhouette tests: a person drawn from ellipses and
polygons (A-pose) on a coloured backdrop with a lighting gradient, a soft shadow and
sensor noise. The drawing is not anti-aliased, so the person's pixels are known exactly.
Also the EXIF block with which a phone marks a photo stored sideways."""

from __future__ import annotations

import struct

import cv2
import numpy as np

SKIN = (120, 150, 205)  # BGR
SHIRT = (60, 60, 200)
TROUSERS = (90, 70, 50)
SHOES = (30, 30, 30)
BACKDROP = (175, 150, 70)  # a teal-blue studio backdrop, BGR


def exif_with_orientation(orientation: int, byte_order: str) -> np.ndarray:
    """A minimal TIFF-structured EXIF block holding only the Orientation tag."""
    mark = b"II" if byte_order == "<" else b"MM"
    block = mark + struct.pack(byte_order + "HI", 42, 8) + struct.pack(byte_order + "H", 1)
    block += struct.pack(byte_order + "HHIHH", 0x0112, 3, 1, orientation, 0) + struct.pack(byte_order + "I", 0)
    return np.frombuffer(block, np.uint8)


def _limb(start, end, width: float) -> np.ndarray:
    """Quadrilateral of ``width`` pixels around the segment start -> end, (4, 2) int32."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    direction = (end - start) / np.linalg.norm(end - start)
    normal = np.array([-direction[1], direction[0]]) * width / 2
    return np.rint([start + normal, end + normal, end - normal, start - normal]).astype(np.int32)


def draw_person(canvas: np.ndarray, centre_x: float, top_y: float, height: float, colours: bool = True) -> None:
    """Paint an A-pose person ``height`` pixels tall onto ``canvas`` in place.

    With ``colours`` False every part is painted 255 (for a truth mask on a uint8 canvas).
    """
    h, x = height, centre_x

    def paint(colour):
        return colour if colours else 255

    def point(dx, dy):
        return (x + dx * h, top_y + dy * h)

    # Legs and shoes.
    for side in (-1, 1):
        cv2.fillConvexPoly(
            canvas, _limb(point(side * 0.055, 0.50), point(side * 0.09, 0.95), 0.085 * h), paint(TROUSERS)
        )
        foot = tuple(int(round(v)) for v in point(side * 0.10, 0.965))
        cv2.ellipse(canvas, foot, (int(0.045 * h), int(0.022 * h)), 0, 0, 360, paint(SHOES), cv2.FILLED)
    # Arms (A-pose, apart from the torso) and hands.
    for side in (-1, 1):
        shoulder, hand = point(side * 0.115, 0.19), point(side * 0.26, 0.50)
        cv2.fillConvexPoly(canvas, _limb(shoulder, hand, 0.05 * h), paint(SKIN))
        centre = tuple(int(round(v)) for v in point(side * 0.265, 0.52))
        cv2.ellipse(canvas, centre, (int(0.022 * h), int(0.035 * h)), side * 20, 0, 360, paint(SKIN), cv2.FILLED)
    # Torso: shoulders, waist, hips.
    torso = np.rint(
        [
            point(-0.125, 0.17),
            point(0.125, 0.17),
            point(0.10, 0.32),
            point(0.085, 0.42),
            point(0.105, 0.52),
            point(-0.105, 0.52),
            point(-0.085, 0.42),
            point(-0.10, 0.32),
        ]
    ).astype(np.int32)
    cv2.fillPoly(canvas, [torso], paint(SHIRT))
    # Neck and head.
    cv2.fillConvexPoly(canvas, _limb(point(0, 0.10), point(0, 0.18), 0.05 * h), paint(SKIN))
    head = tuple(int(round(v)) for v in point(0, 0.065))
    cv2.ellipse(canvas, head, (int(0.048 * h), int(0.063 * h)), 0, 0, 360, paint(SKIN), cv2.FILLED)


def studio_photo(
    size_px: tuple[int, int],
    people: list[tuple[float, float, float]],
    rng: np.random.Generator,
    noise_sigma: float = 4.0,
    shadow: bool = True,
    backdrop: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """A photo of ``people`` ((centre_x, top_y, height) each) and the truth mask.

    Returns:
        ((H, W, 3) uint8 BGR photo, (H, W) bool truth mask).
    """
    width, height = size_px
    truth = np.zeros((height, width), np.uint8)
    for person in people:
        draw_person(truth, *person, colours=False)
    truth = truth > 0
    if backdrop is None:
        ys, xs = np.mgrid[0:height, 0:width]
        light = 1.1 - 0.25 * (((xs - width / 2) / width) ** 2 + ((ys - height / 3) / height) ** 2)
        scene = np.asarray(BACKDROP, np.float32) * light[..., None]
    else:
        scene = backdrop.astype(np.float32)
    if shadow:
        shifted = np.roll(truth, (12, 45), axis=(0, 1)).astype(np.float32)
        penumbra = cv2.GaussianBlur(shifted, (0, 0), 12)
        scene *= (1.0 - 0.4 * penumbra)[..., None]
    people_layer = np.zeros((height, width, 3), np.uint8)
    for person in people:
        draw_person(people_layer, *person)
    scene[truth] = people_layer[truth]
    scene += rng.normal(0.0, noise_sigma, scene.shape)
    return np.clip(np.rint(scene), 0, 255).astype(np.uint8), truth


def clutter(size_px: tuple[int, int], rng: np.random.Generator, count: int = 60) -> np.ndarray:
    """A busy room: ``count`` random coloured rectangles, (H, W, 3) uint8 BGR.

    No rectangle has a colour within 60 grey levels of the person's clothes or skin:
    nothing tells a person from an object of their colour right behind them.
    """
    width, height = size_px
    room = np.full((height, width, 3), 128, np.uint8)
    person_colours = np.array([SKIN, SHIRT, TROUSERS, SHOES], float)
    drawn = 0
    while drawn < count:
        colour = rng.integers(0, 256, 3)
        if np.linalg.norm(person_colours - colour, axis=1).min() < 60:
            continue
        x0, y0 = int(rng.integers(0, width)), int(rng.integers(0, height))
        x1, y1 = x0 + int(rng.integers(20, width // 3)), y0 + int(rng.integers(20, height // 3))
        cv2.rectangle(room, (x0, y0), (x1, y1), tuple(int(v) for v in colour), cv2.FILLED)
        drawn += 1
    return room


def iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two bool masks."""
    return float((a & b).sum() / (a | b).sum())
