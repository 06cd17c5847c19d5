"""Calibration from rendered board photos recovers the camera that took them."""

import dataclasses

import cv2
import numpy as np
import pytest

from bodyfit.calib.boards import BoardDetector, render_board
from bodyfit.calib.capture import (DISTORTION_MODELS, CaptureSettings, BoardViewStatus, calibrate,
                                   collect_views, describe_views,)
from bodyfit.calib.synthetic import BoardPhotoRenderer, random_board_poses
from bodyfit.common.errors import UserError

from calib_true_camera import IMAGE_SIZE, TRUE_DIST, TRUE_K

SETTINGS = CaptureSettings()


def solve(shots, paths, settings=SETTINGS):
    views, size = collect_views([str(p) for p in paths], BoardDetector(shots.spec), settings)
    return calibrate(views, size, settings, shots.spec)


def assert_recovers_true_camera(calibration):
    K, dist, std = calibration.camera.K, calibration.camera.dist, calibration.std
    for name, estimate, truth in (
        ("fx", K[0, 0], TRUE_K[0, 0]),
        ("fy", K[1, 1], TRUE_K[1, 1]),
        ("cx", K[0, 2], TRUE_K[0, 2]),
        ("cy", K[1, 2], TRUE_K[1, 2]),
    ):
        assert estimate == pytest.approx(truth, rel=0.005), name
    for index, name in enumerate(("k1", "k2")):
        assert abs(dist[index] - TRUE_DIST[index]) <= 3 * std[name], (name, dist[index], std[name])
    # The paper's model: tangential terms and k3 are held at zero, only k1, k2 estimated.
    np.testing.assert_array_equal(dist[2:], 0.0)
    assert set(std) == {"fx", "fy", "cx", "cy", "k1", "k2"}
    assert 0 < std["k1"] < 0.01 and 0 < std["fx"] < 5


@pytest.mark.parametrize("board", ["chessboard_shots", "charuco_shots"])
def test_recovers_the_camera_from_rendered_photos(request, board):
    shots = request.getfixturevalue(board)
    calibration = solve(shots, shots.sharp)
    assert len(calibration.used_views) == len(shots.sharp)
    assert calibration.rms_px < 0.15
    assert_recovers_true_camera(calibration)
    assert calibration.camera.board == shots.spec and calibration.camera.image_size_px == IMAGE_SIZE


def test_rejects_a_blurred_view_and_an_outlier_and_still_recovers(chessboard_shots):
    shots = chessboard_shots
    calibration = solve(shots, [*shots.sharp, shots.blurred, shots.bent])
    status = {view.source: view for view in calibration.views}
    assert status[str(shots.blurred)].status is BoardViewStatus.BLURRY
    assert status[str(shots.blurred)].edge_rise_px > SETTINGS.max_edge_rise_px
    assert status[str(shots.bent)].status is BoardViewStatus.OUTLIER
    assert status[str(shots.bent)].error_px > 1.0
    assert describe_views(calibration.views) == f"{len(shots.sharp)} used, 2 rejected (1 too blurry, 1 outlier)"
    assert calibration.worst_view.error_px < 0.2
    assert_recovers_true_camera(calibration)


def test_a_richer_model_reports_its_extra_coefficients(charuco_shots):
    calibration = solve(charuco_shots, charuco_shots.sharp, CaptureSettings(model="k1k2p1p2k3"))
    assert set(calibration.std) == {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"}
    p1, p2 = calibration.camera.dist[2:4]
    assert abs(p1) < 3 * calibration.std["p1"] + 1e-4 and abs(p2) < 3 * calibration.std["p2"] + 1e-4


def test_too_few_usable_views_is_a_user_error(chessboard_shots):
    shots = chessboard_shots
    with pytest.raises(
        UserError, match=r"only 2 usable views, the solve needs at least 3 \(2 used, 1 rejected \(1 too blurry\)\)"
    ):
        solve(shots, [shots.sharp[2], shots.sharp[3], shots.blurred])


def test_no_board_anywhere_is_a_user_error(tmp_path, chessboard_shots):
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((IMAGE_SIZE[1], IMAGE_SIZE[0]), 128, np.uint8))
    with pytest.raises(UserError, match="no board found in any of the 2 views"):
        solve(chessboard_shots, [blank, blank])


def test_no_model_enables_the_tilted_sensor():
    # In OpenCV 5.0.0.93 CALIB_DISABLE_SCHUR_COMPLEMENT == CALIB_TILTED_MODEL: passing it adds tilt terms.
    for flags, _ in DISTORTION_MODELS.values():
        assert not flags & cv2.CALIB_TILTED_MODEL


def test_unknown_model_is_a_user_error():
    with pytest.raises(UserError, match="unknown --model"):
        CaptureSettings(model="fisheye")


def test_video_frames_are_sampled_and_repeated_positions_skipped(tmp_path, charuco_shots):
    # Eight board positions held for 6 frames each, sampled 16 times: two frames of every
    # position come out, and the second of each pair adds nothing.
    spec = charuco_shots.spec
    picture = render_board(spec, 60)
    small_k = TRUE_K * np.array([[0.5], [0.5], [1.0]])
    size = (640, 360)
    renderer = BoardPhotoRenderer(picture, small_k, TRUE_DIST, size)
    rng = np.random.default_rng(12)  # poses at least 47 px (median corner motion) apart
    poses = random_board_poses(picture, small_k, TRUE_DIST, size, 8, rng, fill_range=(0.45, 0.7))
    path = tmp_path / "sweep.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 30, size)
    for rvec, tvec in poses:
        frame = cv2.cvtColor(renderer.render(rvec, tvec, rng=rng), cv2.COLOR_GRAY2BGR)
        for _ in range(6):
            writer.write(frame)
    writer.release()
    settings = dataclasses.replace(SETTINGS, video_max_frames=16)
    views, size_found = collect_views([str(path)], BoardDetector(spec), settings)
    assert size_found == size and len(views) == 16
    assert [view.frame_index // 3 for view in views] == list(range(16))  # one frame from each stretch
    statuses = [view.status for view in views]
    assert statuses == [BoardViewStatus.USED, BoardViewStatus.DUPLICATE] * 8
    calibration = calibrate(views, size, settings, spec)
    assert calibration.camera.K[0, 0] == pytest.approx(small_k[0, 0], rel=0.01)


def test_the_same_views_give_the_same_camera_to_the_last_bit(chessboard_shots):
    """The solve runs single-threaded: OpenCV's threaded solve differed in the last bits
    from run to run, and the fit downstream amplifies such differences (docs/fitter.md)."""
    views, size = collect_views([str(p) for p in chessboard_shots.sharp], BoardDetector(chessboard_shots.spec),
                                SETTINGS)
    threads = cv2.getNumThreads()
    cameras = [calibrate(views, size, SETTINGS, chessboard_shots.spec).camera for _ in range(4)]
    for camera in cameras[1:]:
        np.testing.assert_array_equal(camera.K, cameras[0].K)
        np.testing.assert_array_equal(camera.dist, cameras[0].dist)
    assert cv2.getNumThreads() == threads  # restored for the rest of the program
