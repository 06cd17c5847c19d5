"""Board specifications, printable pictures and detection against projected truth."""

import cv2
import numpy as np
import pytest

from bodyfit.calib.boards import BoardDetector, BoardSpec, parse_board, render_board
from bodyfit.calib.errors import UserError
from bodyfit.calib.synthetic import BoardPhotoRenderer

K = np.array([[900.0, 0.0, 480.0], [0.0, 900.0, 270.0], [0.0, 0.0, 1.0]])
NO_DIST = np.zeros(5)
SIZE = (960, 540)


def test_parse_board_reads_kind_counts_and_sizes():
    spec = parse_board("chessboard:9x6", 24.5)
    assert (spec.kind, spec.columns, spec.rows, spec.square_mm) == ("chessboard", 9, 6, 24.5)
    assert spec.corner_count == 54
    assert spec.size_mm == (245.0, 171.5)
    charuco = parse_board("charuco:11X8", 20, 15, "DICT_5X5_100")
    assert charuco.corner_count == 10 * 7
    assert BoardSpec.from_dict(charuco.to_dict()) == charuco


@pytest.mark.parametrize(
    "text, square, marker, dictionary, complaint",
    [
        ("chessboard-9x6", 25, None, None, "KIND:COLSxROWS"),
        ("circles:9x6", 25, None, None, "unknown board kind"),
        ("chessboard:1x6", 25, None, None, "at least"),
        ("chessboard:9x6", 0, None, None, "positive"),
        ("chessboard:9x6", 25, 15, None, "charuco"),
        ("charuco:11x8", 20, None, None, "--marker-mm"),
        ("charuco:11x8", 20, 25, "DICT_5X5_100", "smaller"),
        ("charuco:11x8", 20, 15, "DICT_9X9_1", "unknown ArUco dictionary"),
        ("charuco:20x20", 20, 15, "DICT_4X4_50", "needs 200 markers"),
    ],
)
def test_parse_board_rejects_bad_specs(text, square, marker, dictionary, complaint):
    with pytest.raises(UserError, match=complaint):
        parse_board(text, square, marker, dictionary)


def test_render_board_places_the_origin_where_it_says():
    spec = parse_board("chessboard:5x4", 10.0)
    picture = render_board(spec, 20)
    assert picture.image.shape == ((4 + 1 + 2) * 20, (5 + 1 + 2) * 20)
    x0, y0 = (int(v) for v in picture.origin_px)
    # The first inner corner: black square up-left of it, white to its right.
    assert picture.image[y0 - 5, x0 - 5] == 0 and picture.image[y0 - 5, x0 + 5] == 255
    assert picture.image[y0 + 5, x0 + 5] == 0


def _frontal_photo(spec):
    picture = render_board(spec, 40)
    renderer = BoardPhotoRenderer(picture, K, NO_DIST, SIZE)
    rvec, tvec = np.array([0.25, -0.3, 0.1]), np.array([-100.0, -70.0, 500.0])
    return renderer.render(rvec, tvec, noise_sigma=1.0), rvec, tvec


def test_chessboard_corners_land_on_the_projected_corners():
    spec = parse_board("chessboard:7x5", 25.0)
    photo, rvec, tvec = _frontal_photo(spec)
    detection = BoardDetector(spec).detect(photo)
    assert detection is not None and detection.image_points.shape == (35, 2)
    truth, _ = cv2.projectPoints(detection.object_points, rvec, tvec, K, NO_DIST)
    truth = truth.reshape(-1, 2)
    # A chessboard's numbering may start from either end (the board is symmetric under 180 degrees).
    error = min(np.abs(detection.image_points - truth).max(), np.abs(detection.image_points[::-1] - truth).max())
    assert error < 0.25


def test_charuco_corners_carry_their_ids():
    spec = parse_board("charuco:7x5", 25.0, 18.0, "DICT_4X4_50")
    photo, rvec, tvec = _frontal_photo(spec)
    detection = BoardDetector(spec).detect(photo)
    assert detection is not None and len(detection.corner_ids) == 24
    truth, _ = cv2.projectPoints(detection.object_points, rvec, tvec, K, NO_DIST)
    assert np.abs(detection.image_points - truth.reshape(-1, 2)).max() < 0.25


def test_detect_returns_none_without_a_board():
    blank = np.full((SIZE[1], SIZE[0]), 128, np.uint8)
    assert BoardDetector(parse_board("chessboard:7x5", 25.0)).detect(blank) is None
    assert BoardDetector(parse_board("charuco:7x5", 25.0, 18.0, "DICT_4X4_50")).detect(blank) is None
