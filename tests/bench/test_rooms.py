"""The room benchmark's photos (bench/accuracy/rooms.py): the same subjects and camera
places as the plain set, dressed, in a room, with their truth masks."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from bench.accuracy.outlines import height_error, outline_errors
from bench.accuracy.rooms import (PLATE_EXPOSURE, SHADOW_DEPTH, RoomScene, _room, draw_scene,
                                  dressed_colours, room_photo)
from bench.accuracy.subject_set import SetSettings, write_bodies, write_photos_of_set
from bodyfit.calib.camera import Camera
from bodyfit.calib.silhouette import extract_silhouette
from bodyfit.fitter.demo.example import demo_camera
from bodyfit.fitter.demo.studio_photos import pinhole_layers
from bodyfit.fitter.model.body_model import PART_NAMES


def test_height_error_of_a_grown_and_a_cut_silhouette():
    exact = np.zeros((100, 40), bool)
    exact[10:90, 10:30] = True  # 80 rows
    grown, cut = exact.copy(), exact.copy()
    grown[2:10, 18:22] = True     # a lamp merged above: 88 rows
    cut[84:90] = False            # the feet lost: 74 rows
    assert height_error(grown, exact) == pytest.approx(8 / 80)
    assert height_error(cut, exact) == pytest.approx(-6 / 80)
    assert height_error(np.roll(exact, 3, axis=0), exact) == 0.0


def test_outline_errors_of_a_shifted_and_a_grown_square():
    """A 10 x 10 square's outline is its 36 border pixels; shifted by a column, the mask
    is wrong on 20 pixels and no further out; grown by a pixel all round, 44 pixels out."""
    truth = np.zeros((20, 20), bool)
    truth[5:15, 5:15] = True
    assert outline_errors(truth, truth) == (0.0, 0.0)
    assert outline_errors(np.roll(truth, 1, axis=1), truth) == pytest.approx((0.0, 20 / 36))
    grown = np.zeros_like(truth)
    grown[4:16, 4:16] = True
    assert outline_errors(grown, truth) == pytest.approx((44 / 36, 44 / 36))


def test_a_scene_is_drawn_from_its_stream_and_dresses_by_part(body_model):
    """The same stream gives the same scene; the head's top is hair, its face skin, the
    hands skin and the legs the trousers (the hip's colour)."""
    scene = draw_scene(np.random.default_rng(5))
    again = draw_scene(np.random.default_rng(5))
    assert scene.room == again.room and np.array_equal(scene.part_colours, again.part_colours)
    vertices = body_model.mean_vertices
    colours = dressed_colours(body_model, vertices, scene)
    head = np.flatnonzero(body_model.face_parts == PART_NAMES.index("head"))
    heights = vertices[body_model.faces[head]].mean(axis=1)[:, 2]
    assert np.all(colours[head[np.argmax(heights)]] == scene.hair)
    front = head[np.argmin(vertices[body_model.faces[head]].mean(axis=1)[:, 1])]  # the nose
    assert np.all(colours[front] == scene.part_colours[PART_NAMES.index("head")])
    for part, same_as in (("hand", "head"), ("leg", "hip")):
        faces = body_model.face_parts == PART_NAMES.index(part)
        assert np.all(colours[faces] == scene.part_colours[PART_NAMES.index(same_as)])


def test_room_photo_puts_the_body_on_the_room_with_a_shadow_at_its_feet(body_model):
    """Through a lens without distortion: the truth is the body's coverage, the photo is
    the room outside it, darker just under the feet by up to SHADOW_DEPTH, and the plate
    is the room alone."""
    camera = demo_camera((600, 800))
    camera = Camera(camera.image_size_px, camera.K, np.zeros(5))
    scene = RoomScene("white-room.jpg", False, draw_scene(np.random.default_rng(1)).part_colours,
                      np.array([30, 30, 30], np.uint8), 0)
    vertices = body_model.mean_vertices.astype(np.float64)
    photo, truth, plate = room_photo(vertices, body_model, "front", camera, 3.0, 1.1, 0.0,
                                     scene)
    _, covered = pinhole_layers(vertices, body_model, "front", PART_NAMES, camera.K, (600, 800),
                                3.0, 1.1)
    assert np.array_equal(truth, covered)
    room = _room("white-room.jpg", (600, 800)).astype(float)
    rows, cols = np.nonzero(truth)
    below = (rows.max() + 3, int(cols.mean()))
    ratio = photo[below].astype(float).sum() / room[below].sum()
    assert 1 - SHADOW_DEPTH - 0.05 < ratio < 0.9
    far = ~cv2.dilate(truth.astype(np.uint8), np.ones((61, 61), np.uint8)).astype(bool)
    far[rows.max() - 150:, :] = False  # the shadow's reach
    assert np.abs(photo[far].astype(float) - room[far]).max() <= 1
    assert np.array_equal(plate, room.astype(np.uint8))


def test_a_room_set_photographs_the_plain_sets_bodies_from_the_same_places(body_model, tmp_path):
    """Its subject's truth.json (measurements, camera place) is the plain set's, and its
    truth mask is the plain photo's silhouette (the backdrop's colour model's, within the
    JPEG's and the lens's blur). Its plate is the photo's room: away from the body and its
    shadow the two differ by the exposure (up to PLATE_EXPOSURE) and noise; against it
    the backdrop's colour model finds the body (but the shadow between the feet and a
    shoe of the floor's colour), and the learned segmentation finds more of it than
    without it."""
    truths, masks = {}, {}
    for rooms in (False, True):
        folder = tmp_path / ("room" if rooms else "plain")
        folder.mkdir()
        write_bodies(body_model, folder, SetSettings(kind="in-space", count=2, seed=3,
                                                     size_px=(600, 800), board_views=3,
                                                     rooms=rooms))
        write_photos_of_set(body_model, folder, [0])
        subject = next(p for p in folder.iterdir() if p.name.startswith("s0000"))
        truths[rooms] = json.loads((subject / "truth.json").read_text())
        masks[rooms] = subject
    assert truths[False] == truths[True]
    truth = cv2.imread(str(masks[True] / "truth_front.png"), cv2.IMREAD_GRAYSCALE) > 127
    backdrop = extract_silhouette(cv2.imread(str(masks[False] / "front.jpg")),
                                  segmenter="backdrop")

    def iou(mask: np.ndarray) -> float:
        return (mask & truth).sum() / (mask | truth).sum()

    assert iou(backdrop) > 0.98
    photo, plate = (cv2.imread(str(masks[True] / name)) for name in ("front.jpg",
                                                                      "plate_front.jpg"))
    rows, _ = np.nonzero(truth)
    far = ~cv2.dilate(truth.astype(np.uint8), np.ones((61, 61), np.uint8)).astype(bool)
    far[rows.max() - 150:, :] = False  # the shadow's reach
    exposure = np.median(photo[far].sum(axis=1) / np.maximum(plate[far].sum(axis=1), 1))
    assert abs(exposure - 1) <= PLATE_EXPOSURE + 0.01
    assert np.percentile(np.abs(photo[far] - exposure * plate[far].astype(float)), 99) < 15
    assert iou(extract_silhouette(photo, plate, segmenter="backdrop")) > 0.92
    assert iou(extract_silhouette(photo, plate)) > iou(extract_silhouette(photo,
                                                                          segmenter="learned"))
