"""The edge-rise sharpness measure against OpenCV's chessboard sharpness and optics."""

import math

import cv2
import numpy as np
import pytest

from bodyfit.calib.blur import edge_rise_px


@pytest.fixture(scope="module")
def board_photo(chessboard_shots):
    photo = cv2.imread(str(chessboard_shots.sharp[3]), cv2.IMREAD_GRAYSCALE)
    found, corners = cv2.findChessboardCornersSB(photo, (9, 6), flags=cv2.CALIB_CB_NORMALIZE_IMAGE)
    assert found
    return photo, corners


@pytest.mark.parametrize("sigma_px", [1.0, 2.0, 3.0])
def test_edge_rise_matches_opencv_chessboard_sharpness(board_photo, sigma_px):
    photo, corners = board_photo
    blurred = cv2.GaussianBlur(photo, (0, 0), sigma_px)
    opencv_rise = cv2.estimateChessboardSharpness(blurred, (9, 6), corners)[0][0]
    assert edge_rise_px(blurred) == pytest.approx(opencv_rise, abs=0.5)


def test_edge_rise_follows_a_gaussian_blur():
    # A vertical step blurred by sigma rises from 10 % to 90 % over 2.563 sigma pixels.
    step = np.zeros((64, 256), np.uint8)
    step[:, 128:] = 200
    for sigma_px in (2.0, 3.0, 4.0):
        rise = edge_rise_px(cv2.GaussianBlur(step, (0, 0), sigma_px))
        assert rise == pytest.approx(2.563 * sigma_px, rel=0.1)


def test_edge_rise_uses_only_the_region():
    image = np.zeros((100, 200), np.uint8)
    image[:, 50:] = 200
    image[:, 150:] = 0
    image[:, :100] = cv2.GaussianBlur(image, (0, 0), 4.0)[:, :100]
    left = np.zeros(image.shape, bool)
    left[:, :100] = True
    assert edge_rise_px(image, left) > 2 * edge_rise_px(image, ~left)


def test_edge_rise_of_a_flat_image_is_infinite():
    assert math.isinf(edge_rise_px(np.full((50, 50), 90, np.uint8)))
