"""camera.json: writing and reading back, and every way it can be broken."""

import json

import numpy as np
import pytest

from bodyfit.calib.boards import parse_board
from bodyfit.calib.camera import Camera, camera_fields, load_camera
from bodyfit.common.errors import UserError

CAMERA = Camera(
    (1280, 720),
    np.array([[1050.0, 0.0, 648.5], [0.0, 1046.0, 352.3], [0.0, 0.0, 1.0]]),
    np.array([-0.11, 0.21, 0.0, 0.0, 0.0]),
    parse_board("chessboard:9x6", 25.0),
    0.06,
)


def write(tmp_path, record) -> str:
    path = tmp_path / "camera.json"
    path.write_text(record if isinstance(record, str) else json.dumps(record))
    return str(path)


def test_camera_round_trips_through_json(tmp_path):
    loaded = load_camera(write(tmp_path, camera_fields(CAMERA)))
    assert loaded.image_size_px == (1280, 720)
    np.testing.assert_array_equal(loaded.K, CAMERA.K)
    np.testing.assert_array_equal(loaded.dist, CAMERA.dist)
    assert loaded.board == CAMERA.board and loaded.rms_px == 0.06


def broken(**changes):
    record = camera_fields(CAMERA)
    for key, value in changes.items():
        if value is None:
            del record[key]
        else:
            record[key] = value
    return record


@pytest.mark.parametrize(
    "record, complaint",
    [
        ("{ not json", "not valid JSON"),
        ("[1, 2, 3]", "not a JSON object"),
        (broken(K=None), "missing K"),
        (broken(dist=None, image_size_px=None), "missing image_size_px, dist"),
        (broken(image_size_px=[1280]), "image_size_px"),
        (broken(image_size_px=[1280.5, 720]), "image_size_px"),
        (broken(K=[[1, 0, 0], [0, 1, 0]]), "3x3"),
        (broken(K=[[-5, 0, 1], [0, 5, 1], [0, 0, 1]]), "positive focal"),
        (broken(K=[["a", 0, 1], [0, 5, 1], [0, 0, 1]]), "numbers only"),
        (broken(dist=[0.1, 0.2, 0.3]), "dist must be"),
        (broken(dist=[0.1, float("nan"), 0, 0]), "dist must be"),
        (broken(board={"kind": "chessboard", "columns": 9}), "board"),
        (broken(rms_px=-1), "rms_px"),
    ],
)
def test_corrupt_or_incomplete_camera_files_are_user_errors(tmp_path, record, complaint):
    with pytest.raises(UserError, match=complaint):
        load_camera(write(tmp_path, record))


def test_missing_camera_file_is_a_user_error(tmp_path):
    with pytest.raises(UserError, match="no such file"):
        load_camera(tmp_path / "nowhere.json")


def test_check_image_names_the_size_and_spots_a_rotation():
    CAMERA.check_image(np.zeros((720, 1280, 3), np.uint8), "ok.jpg")
    with pytest.raises(UserError, match="turned 90 degrees"):
        CAMERA.check_image(np.zeros((1280, 720, 3), np.uint8), "portrait.jpg")
    with pytest.raises(UserError, match="small.jpg is 640x360 pixels"):
        CAMERA.check_image(np.zeros((360, 640), np.uint8), "small.jpg")
