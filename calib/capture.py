"""Camera calibration from board photos and videos: views, the solve, outlier rejection.

Every input image becomes a :class:`BoardView` with a status: ``used``, or rejected with a
reason -- no board found, too blurry (10-90 % edge rise over the board wider than
``max_edge_rise_px``), the same board position as an earlier video frame, or an outlier
(its RMS reprojection error above ``outlier_factor`` times the median view's and above
``outlier_floor_px``; removed one at a time, worst first, and the camera re-solved).

The solve is ``cv2.calibrateCameraExtended`` (sparse bundle adjustment), which also
returns standard deviations of the intrinsics. The distortion model defaults to the
paper's k1, k2 (tangential and k3 held at zero).
"""

from __future__ import annotations

import dataclasses
import enum
import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass

import cv2
import numpy as np
from tqdm import tqdm

from bodyfit.calib.blur import edge_rise_px
from bodyfit.calib.boards import BoardDetection, BoardDetector, BoardSpec
from bodyfit.calib.camera import Camera, camera_fields
from bodyfit.calib.images import frame_name, is_video, read_frames
from bodyfit.common.errors import UserError

__all__ = [
    "DISTORTION_MODELS",
    "INTRINSIC_NAMES",
    "Calibration",
    "CaptureSettings",
    "BoardView",
    "BoardViewStatus",
    "calibrate",
    "collect_views",
    "describe_views",
]

log = logging.getLogger(__name__)

# --model name -> (calibrateCamera flags, coefficients estimated). CALIB_DISABLE_SCHUR_COMPLEMENT
# is never used: in OpenCV 5.0.0.93 it has CALIB_TILTED_MODEL's value.
DISTORTION_MODELS: dict[str, tuple[int, tuple[str, ...]]] = {
    "k1": (cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3, ("k1",)),
    "k1k2": (cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K3, ("k1", "k2")),
    "k1k2k3": (cv2.CALIB_ZERO_TANGENT_DIST, ("k1", "k2", "k3")),
    "k1k2p1p2": (cv2.CALIB_FIX_K3, ("k1", "k2", "p1", "p2")),
    "k1k2p1p2k3": (0, ("k1", "k2", "p1", "p2", "k3")),
    "rational": (cv2.CALIB_RATIONAL_MODEL, ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")),
}

# Order of calibrateCameraExtended's stdDeviationsIntrinsics.
INTRINSIC_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")

_SOLVE_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)


@dataclass(frozen=True)
class CaptureSettings:
    """How views are chosen and the camera solved; written into camera.json.

    Attributes:
        model: distortion model, a key of :data:`DISTORTION_MODELS`.
        max_edge_rise_px: views whose board edges take longer than this to rise from
            10 % to 90 % (pixels) are too blurry.
        outlier_factor: a view whose RMS reprojection error exceeds this many times the
            median view's is an outlier ...
        outlier_floor_px: ... provided it also exceeds this many pixels.
        min_views: fewest usable views the solve accepts.
        video_max_frames: frames sampled from each video (the sharpest of equal stretches).
        video_min_motion_px: a video frame whose board corners moved less than this
            (median, pixels) from an earlier kept frame adds nothing and is skipped.
    """

    model: str = "k1k2"
    max_edge_rise_px: float = 4.0
    outlier_factor: float = 3.0
    outlier_floor_px: float = 0.5
    min_views: int = 3
    video_max_frames: int = 30
    video_min_motion_px: float = 20.0

    def __post_init__(self) -> None:
        if self.model not in DISTORTION_MODELS:
            raise UserError(f"unknown --model {self.model!r}; use one of {', '.join(DISTORTION_MODELS)}")
        if self.min_views < 3:
            raise UserError(f"the solve needs at least 3 views, min_views={self.min_views}")
        if not (self.max_edge_rise_px > 0 and self.outlier_factor > 1 and self.outlier_floor_px >= 0):
            raise UserError("blur and outlier thresholds must be positive (outlier factor above 1)")
        if self.video_max_frames < 1:
            raise UserError(f"--video-frames must be at least 1, got {self.video_max_frames}")


class BoardViewStatus(str, enum.Enum):
    """What became of a view."""

    USED = "used"
    NO_BOARD = "no board"
    BLURRY = "too blurry"
    DUPLICATE = "same board position as an earlier frame"
    OUTLIER = "outlier"


@dataclass(frozen=True)
class BoardView:
    """One photo or video frame offered to the calibration.

    Attributes:
        source: the input path as given.
        frame_index: the frame's index in a video, None for a photo.
        status: used, or why not.
        detection: the board corners found, None when none were.
        edge_rise_px: 10-90 % edge rise over the board, pixels (None without a board).
        error_px: RMS reprojection error of the view, pixels, from the last solve it
            took part in (None if it never did).
    """

    source: str
    frame_index: int | None
    status: BoardViewStatus
    detection: BoardDetection | None = None
    edge_rise_px: float | None = None
    error_px: float | None = None

    @property
    def name(self) -> str:
        """``photo.jpg``, or ``clip.mp4@frame 120`` for a video frame."""
        return frame_name(self.source, self.frame_index)

    def to_dict(self) -> dict:
        """JSON-ready record of the view (the corners themselves are left out)."""
        return {
            "name": self.name,
            "source": self.source,
            "frame_index": self.frame_index,
            "status": self.status.value,
            "corners": 0 if self.detection is None else len(self.detection.corner_ids),
            # A board region without a strong edge measures inf, which JSON cannot hold.
            "edge_rise_px": self.edge_rise_px
            if self.edge_rise_px is None or math.isfinite(self.edge_rise_px)
            else None,
            "error_px": self.error_px,
        }


def _board_region(shape: tuple[int, int], detection: BoardDetection) -> np.ndarray:
    hull = cv2.convexHull(detection.image_points.reshape(-1, 1, 2)).round().astype(np.int32)
    region = np.zeros(shape, np.uint8)
    cv2.fillConvexPoly(region, hull, 1)
    return region.astype(bool)


def _moved_px(a: BoardDetection, b: BoardDetection) -> float:
    """Median displacement of the corners two detections share, pixels (inf if none)."""
    shared, in_a, in_b = np.intersect1d(a.corner_ids, b.corner_ids, return_indices=True)
    if len(shared) == 0:
        return float("inf")
    return float(np.median(np.linalg.norm(a.image_points[in_a] - b.image_points[in_b], axis=1)))


def collect_views(
    paths: Iterable[str], detector: BoardDetector, settings: CaptureSettings
) -> tuple[list[BoardView], tuple[int, int]]:
    """Find the board in every input image and sort out the views to use (with a
    progress bar on stderr when it is a terminal).

    Returns:
        (views, image_size_px): every view with its status (``used`` ones still face
        outlier rejection in :func:`calibrate`), and (width, height) of the images.
    """
    paths = list(paths)
    views: list[BoardView] = []
    image_size: tuple[int, int] | None = None
    frames = tqdm(read_frames(paths, settings.video_max_frames), desc="finding the board",
                  unit="view", disable=None, leave=False,
                  total=sum(settings.video_max_frames if is_video(p) else 1 for p in paths))
    for source, frame_index, image in frames:
        image_size = (image.shape[1], image.shape[0])
        gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        detection = detector.detect(gray)
        if detection is None:
            views.append(BoardView(source, frame_index, BoardViewStatus.NO_BOARD))
            log.info("%s: no board", views[-1].name)
            continue
        rise = edge_rise_px(gray, _board_region(gray.shape, detection))
        status = BoardViewStatus.USED
        if rise > settings.max_edge_rise_px:
            status = BoardViewStatus.BLURRY
        elif frame_index is not None and any(
            view.status is BoardViewStatus.USED
            and view.source == source
            and _moved_px(view.detection, detection) < settings.video_min_motion_px
            for view in views
        ):
            status = BoardViewStatus.DUPLICATE
        views.append(BoardView(source, frame_index, status, detection, rise))
        log.info(
            "%s: %s (%d corners, edge rise %.2f px)", views[-1].name, status.value, len(detection.corner_ids), rise
        )
    if image_size is None:
        raise UserError("no input images given")
    return views, image_size


@dataclass(frozen=True)
class Calibration:
    """The result of :func:`calibrate`.

    Attributes:
        camera: the calibrated camera (K, dist in OpenCV order, image size, board, RMS).
        std: standard deviation of every estimated intrinsic (``fx`` ... ``k2`` ...), in
            the parameter's unit (pixels for fx, fy, cx, cy; unitless for distortion).
        rms_px: RMS reprojection error over all corners of the used views, pixels.
        views: every view offered, with final status and reprojection error.
        settings: the settings used.
    """

    camera: Camera
    std: dict[str, float]
    rms_px: float
    views: tuple[BoardView, ...]
    settings: CaptureSettings

    @property
    def used_views(self) -> list[BoardView]:
        """The views the final solve used."""
        return [view for view in self.views if view.status is BoardViewStatus.USED]

    @property
    def worst_view(self) -> BoardView:
        """The used view with the largest reprojection error."""
        return max(self.used_views, key=lambda view: view.error_px)

    def to_record(self) -> dict:
        """camera.json's content: the camera's fields, the model, standard deviations,
        every view's status and error, and the settings (provenance is the caller's)."""
        record = camera_fields(self.camera)
        record["model"] = self.settings.model
        record["std"] = dict(self.std)
        record["views"] = [view.to_dict() for view in self.views]
        record["settings"] = dataclasses.asdict(self.settings)
        return record


def _solve(
    views: list[BoardView], image_size: tuple[int, int], flags: int
) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(rms_px, K (3, 3), dist (n,), intrinsic std (18,), per-view RMS (views,)) from OpenCV."""
    object_points = [view.detection.object_points for view in views]
    image_points = [view.detection.image_points for view in views]
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)  # OpenCV's threaded solve differs in the last bits from run to run
    try:
        rms, K, dist, _, _, std, _, errors = cv2.calibrateCameraExtended(
            object_points, image_points, image_size, None, None, flags=flags, criteria=_SOLVE_CRITERIA
        )
    except cv2.error as error:
        raise UserError(
            f"the calibration solve failed ({str(error).strip().splitlines()[-1]}); "
            "photograph the board from more varied angles (tilted 20-45 degrees)"
        ) from None
    finally:
        cv2.setNumThreads(threads)
    if not np.isfinite(rms) or not np.isfinite(K).all() or not np.isfinite(dist).all():
        raise UserError("the calibration solve diverged; photograph the board from more varied angles")
    return rms, K, dist.reshape(-1), std.reshape(-1), errors.reshape(-1)


def calibrate(
    views: list[BoardView], image_size: tuple[int, int], settings: CaptureSettings, board: BoardSpec | None = None
) -> Calibration:
    """Solve the camera from the ``used`` views, rejecting outliers one at a time.

    Args:
        views: from :func:`collect_views`.
        image_size: (width, height), pixels.
        settings: model and thresholds.
        board: the BoardSpec, recorded in the camera.

    Raises:
        UserError: no view shows the board, or fewer than ``settings.min_views`` usable
            views remain.
    """
    flags, estimated = DISTORTION_MODELS[settings.model]
    views = list(views)
    if not any(view.detection is not None for view in views):
        raise UserError(
            f"no board found in any of the {len(views)} views; check --board (a chessboard counts inner "
            "corners, a charuco board squares) and that the whole board is in the picture"
        )
    while True:
        active = [index for index, view in enumerate(views) if view.status is BoardViewStatus.USED]
        if len(active) < settings.min_views:
            raise UserError(
                f"only {len(active)} usable view{'s' if len(active) != 1 else ''}, "
                f"the solve needs at least {settings.min_views} "
                f"({describe_views(views)}); take more sharp photos of the whole board from varied angles"
            )
        rms, K, dist, std, errors = _solve([views[i] for i in active], image_size, flags)
        for index, error in zip(active, errors):
            views[index] = dataclasses.replace(views[index], error_px=float(error))
        threshold = max(settings.outlier_factor * float(np.median(errors)), settings.outlier_floor_px)
        worst = int(np.argmax(errors))
        if errors[worst] <= threshold:
            break
        views[active[worst]] = dataclasses.replace(views[active[worst]], status=BoardViewStatus.OUTLIER)
        log.info("%s: outlier (%.3f px > %.3f px), solving again", views[active[worst]].name, errors[worst], threshold)
    names = ("fx", "fy", "cx", "cy") + estimated
    deviations = {name: float(std[INTRINSIC_NAMES.index(name)]) for name in names}
    camera = Camera(image_size, K, dist, board, float(rms))
    return Calibration(camera, deviations, float(rms), tuple(views), settings)


def describe_views(views: Iterable[BoardView]) -> str:
    """``12 used, 3 rejected (1 no board, 2 too blurry)`` for summaries."""
    views = list(views)
    used = sum(view.status is BoardViewStatus.USED for view in views)
    rejected = {
        status: sum(view.status is status for view in views) for status in BoardViewStatus if status is not BoardViewStatus.USED
    }
    detail = ", ".join(f"{n} {status.value}" for status, n in rejected.items() if n)
    return f"{used} used, {len(views) - used} rejected" + (f" ({detail})" if detail else "")
