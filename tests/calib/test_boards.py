"""Board specifications, printable pictures and detection against projected truth."""

import cv2
import numpy as np
import pytest

from bodyfit.calib.boards import (CHESSBOARD_ATTEMPTS, BoardDetector, BoardSpec,
                                  canonical_chessboard_order, parse_board, render_board,)
from bodyfit.calib.synthetic import BoardPhotoRenderer
from bodyfit.common.errors import UserError

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


# --- boards the first detector misses: a white board on a white wall, steep views ---------

# Like OpenCV's sample photos left01..14.jpg: 640x480 grey, a 9x6 board printed with a white
# margin, here hung on a wall as light as the paper, seen 50-60 degrees off its axis.
WALL_K = np.array([[540.0, 0.0, 320.0], [0.0, 540.0, 240.0], [0.0, 0.0, 1.0]])
WALL_SIZE = (640, 480)
WALL_SPEC = parse_board("chessboard:9x6", 25.0)
STEEP_POSES = {
    # SB without NORMALIZE_IMAGE finds it (and numbers it from the far end).
    "second SB attempt": (np.array([0.744, -0.783, 0.524]), np.array([99.1, -44.37, 355.18])),
    # Only the classic detector finds it.
    "classic detector": (np.array([-0.893, 0.364, 0.307]), np.array([13.39, -176.23, 584.41])),
}


def _board_on_a_white_wall(pose):
    """(photo (480, 640) uint8, true corners (54, 2) in the detector's object-point order, pixels)."""
    rvec, tvec = pose
    renderer = BoardPhotoRenderer(render_board(WALL_SPEC, 40), WALL_K, NO_DIST, WALL_SIZE)
    photo = renderer.render(rvec, tvec, noise_sigma=2.0, rng=np.random.default_rng(5), background=235.0)
    object_points = BoardDetector(WALL_SPEC).detect(photo).object_points
    truth, _ = cv2.projectPoints(object_points, rvec, tvec, WALL_K, NO_DIST)
    return photo, truth.reshape(-1, 2)


def _first_attempt_finds(photo):
    _, flags = CHESSBOARD_ATTEMPTS[0]
    return cv2.findChessboardCornersSB(photo, (WALL_SPEC.columns, WALL_SPEC.rows), flags=flags)[0]


@pytest.mark.parametrize("case", list(STEEP_POSES))
def test_a_board_the_first_detector_misses_is_found_by_a_fallback(case):
    photo, truth = _board_on_a_white_wall(STEEP_POSES[case])
    assert not _first_attempt_finds(photo)  # the case really needs a fallback
    detection = BoardDetector(WALL_SPEC).detect(photo)
    assert detection is not None
    # Canonical order: the corners match the object points' projections one by one.
    assert np.abs(detection.image_points - truth).max() < 0.5


def test_sb_and_the_classic_detector_give_one_corner_order():
    photo, truth = _board_on_a_white_wall(STEEP_POSES["second SB attempt"])
    pattern = (WALL_SPEC.columns, WALL_SPEC.rows)
    found_sb, sb = cv2.findChessboardCornersSB(photo, pattern, flags=cv2.CALIB_CB_EXHAUSTIVE)
    found_classic, classic = cv2.findChessboardCorners(photo, pattern, flags=CHESSBOARD_ATTEMPTS[2][1])
    assert found_sb and found_classic
    sb, classic = sb.reshape(-1, 2), classic.reshape(-1, 2)
    assert np.abs(sb[::-1] - classic).max() < 3  # the two detectors start from opposite ends here
    for corners in (sb, classic):
        ordered = canonical_chessboard_order(photo, corners, *pattern)
        assert np.abs(ordered - truth).max() < 3  # unrefined corners, but the same order as the truth


@pytest.mark.parametrize("spec_text", ["chessboard:9x6", "chessboard:7x5", "chessboard:6x6"])
def test_canonical_order_undoes_any_numbering_of_the_grid(spec_text):
    spec = parse_board(spec_text, 25.0)
    photo, rvec, tvec = _frontal_photo(spec)
    truth, _ = cv2.projectPoints(BoardDetector(spec).detect(photo).object_points, rvec, tvec, K, NO_DIST)
    grid = truth.reshape(spec.rows, spec.columns, 2)
    canonical = canonical_chessboard_order(photo, grid.reshape(-1, 2), spec.columns, spec.rows)
    numberings = [grid[::-1, ::-1], grid[::-1], grid[:, ::-1]]
    if spec.columns == spec.rows:
        numberings += [np.rot90(grid), np.rot90(grid, 3), np.swapaxes(grid, 0, 1)]
    for numbering in numberings:
        reordered = canonical_chessboard_order(photo, numbering.reshape(-1, 2), spec.columns, spec.rows)
        np.testing.assert_array_equal(reordered, canonical)
    if (spec.columns + spec.rows) % 2:  # not symmetric: the colours fix the order to the truth's
        np.testing.assert_array_equal(canonical, truth.reshape(-1, 2).astype(np.float32))
