"""Checking a calibration on held-out board photos.

A calibration's own RMS error measures how well it fits the photos it was solved
from; photos it has not seen tell whether it generalises. For each held-out view the
board's pose is solved with the calibrated K and distortion held fixed
(``cv2.solvePnP``), the board corners are reprojected (``cv2.projectPoints``), and the
RMS distance to the detected corners is reported: close to the calibration's RMS
means the camera model holds; much larger means too few or too similar calibration
views, or a changed camera (zoom, focus, resolution).

A photo the camera was calibrated from is not held out: its error is the calibration's
own fit. Such photos are recognised by their content (the SHA-256 camera.json records
for each input, however the path is spelled) or, in camera files without hashes, by
their resolved path, and reported apart (:attr:`CheckedView.calibrated_on`).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from bodyfit.calib.boards import BoardDetection, BoardDetector
from bodyfit.calib.camera import Camera
from bodyfit.calib.images import frame_name, read_frames
from bodyfit.common.errors import UserError
from bodyfit.common.files import file_sha256

__all__ = ["CheckedView", "check_calibration", "is_calibration_input", "rms_px"]


@dataclass(frozen=True)
class CheckedView:
    """One checked view.

    Attributes:
        name: the photo's path (``clip.mp4@frame N`` for a video frame).
        corners: board corners detected (0 when none).
        error_px: RMS reprojection error, pixels; None when no board was found.
        calibrated_on: whether the photo (or video) is one the camera was calibrated from,
            so not held out.
    """

    name: str
    corners: int
    error_px: float | None
    calibrated_on: bool = False


def is_calibration_input(path: str, camera: Camera) -> bool:
    """Whether the file at ``path`` is one of the inputs ``camera`` was calibrated from.

    The same bytes as an input whose SHA-256 camera.json records, or, for an input
    recorded without a hash, the same resolved path (resolved from the current folder).
    """
    hashes = {item.sha256 for item in camera.inputs if item.sha256 is not None}
    if hashes and file_sha256(path) in hashes:
        return True
    resolved = Path(path).resolve()
    return any(item.sha256 is None and Path(item.path).resolve() == resolved for item in camera.inputs)


def rms_px(views: Iterable[CheckedView]) -> float | None:
    """RMS reprojection error over all corners of ``views``, pixels; None when none has a board."""
    found = [view for view in views if view.error_px is not None]
    corners = sum(view.corners for view in found)
    if corners == 0:
        return None
    return float(np.sqrt(sum(view.error_px**2 * view.corners for view in found) / corners))


def _view_error_px(camera: Camera, detection: BoardDetection) -> float | None:
    """RMS reprojection error of one view with the camera held fixed, pixels; None if no pose."""
    ok, rvec, tvec = cv2.solvePnP(detection.object_points, detection.image_points, camera.K, camera.dist)
    if not ok:
        return None
    projected, _ = cv2.projectPoints(detection.object_points, rvec, tvec, camera.K, camera.dist)
    return float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - detection.image_points) ** 2, axis=1))))


def check_calibration(
    camera: Camera, paths: Iterable[str], detector: BoardDetector, video_max_frames: int = 30
) -> list[CheckedView]:
    """Reprojection error of ``camera`` on board photos, each marked held out or not.

    Returns:
        Every view; :func:`rms_px` gives the RMS error of any group of them.

    Raises:
        UserError: unreadable photos, photos not of the camera's size, no board in any.
    """
    views: list[CheckedView] = []
    calibrated_on: dict[str, bool] = {}
    for source, frame_index, image in read_frames(paths, video_max_frames):
        name = frame_name(source, frame_index)
        camera.check_image(image, name)
        if source not in calibrated_on:
            calibrated_on[source] = is_calibration_input(source, camera)
        detection = detector.detect(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))
        corners = 0 if detection is None else len(detection.corner_ids)
        error = None if detection is None else _view_error_px(camera, detection)
        views.append(CheckedView(name, corners, error, calibrated_on[source]))
    if rms_px(views) is None:
        raise UserError(
            f"no board found in any of the {len(views)} photos; check that they show the board "
            f"{camera.board.describe() if camera.board else '(give --board)'} whole"
        )
    return views
