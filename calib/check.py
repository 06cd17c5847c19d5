"""Checking a calibration on held-out board photos.

A calibration's own RMS error measures how well it fits the photos it was solved
from; photos it has not seen tell whether it generalises. For each held-out view the
board's pose is solved with the calibrated K and distortion held fixed
(``cv2.solvePnP``), the board corners are reprojected (``cv2.projectPoints``), and the
RMS distance to the detected corners is reported: close to the calibration's RMS
means the camera model holds; much larger means too few or too similar calibration
views, or a changed camera (zoom, focus, resolution).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import cv2
import numpy as np

from bodyfit.calib.boards import BoardDetector
from bodyfit.calib.camera import Camera
from bodyfit.calib.errors import UserError
from bodyfit.calib.images import frame_name, read_frames

__all__ = ["CheckedView", "check_calibration"]


@dataclass(frozen=True)
class CheckedView:
    """One held-out view.

    Attributes:
        name: the photo's path (``clip.mp4@frame N`` for a video frame).
        corners: board corners detected (0 when none).
        error_px: RMS reprojection error, pixels; None when no board was found.
    """

    name: str
    corners: int
    error_px: float | None


def check_calibration(
    camera: Camera, paths: Iterable[str], detector: BoardDetector, video_max_frames: int = 30
) -> tuple[list[CheckedView], float]:
    """Reprojection error of ``camera`` on board photos it was not solved from.

    Returns:
        (views, rms_px): every view, and the RMS error over all their corners, pixels.

    Raises:
        UserError: unreadable photos, photos not of the camera's size, no board in any.
    """
    views: list[CheckedView] = []
    squared_sum, corner_total = 0.0, 0
    for source, frame_index, image in read_frames(paths, video_max_frames):
        name = frame_name(source, frame_index)
        camera.check_image(image, name)
        detection = detector.detect(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))
        if detection is None:
            views.append(CheckedView(name, 0, None))
            continue
        ok, rvec, tvec = cv2.solvePnP(detection.object_points, detection.image_points, camera.K, camera.dist)
        if not ok:
            views.append(CheckedView(name, len(detection.corner_ids), None))
            continue
        projected, _ = cv2.projectPoints(detection.object_points, rvec, tvec, camera.K, camera.dist)
        squared = np.sum((projected.reshape(-1, 2) - detection.image_points) ** 2, axis=1)
        views.append(CheckedView(name, len(squared), float(np.sqrt(squared.mean()))))
        squared_sum += float(squared.sum())
        corner_total += len(squared)
    if corner_total == 0:
        raise UserError(
            f"no board found in any of the {len(views)} photos; check that they show the board "
            f"{camera.board.describe() if camera.board else '(give --board)'} whole"
        )
    return views, float(np.sqrt(squared_sum / corner_total))
