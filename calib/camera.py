"""The calibrated camera and its file, camera.json.

camera.json is a readable JSON object. :func:`load_camera` needs only these fields:

- ``image_size_px``: [width, height] of the sensor-frame images it was calibrated on.
- ``K``: 3x3 camera matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], pixels.
- ``dist``: distortion coefficients in OpenCV order (k1, k2, p1, p2[, k3[, k4, k5, k6
  [, s1, s2, s3, s4[, tx, ty]]]]), 4, 5, 8, 12 or 14 numbers, unitless.

``calib capture`` adds ``format``, ``board``, ``rms_px`` and the calibration report
(standard deviations, per-view errors, settings, provenance); see docs/calib.md. Of the
provenance, :func:`load_camera` reads ``inputs`` (the paths given to ``calib capture``)
and ``input_sha256`` (their contents' SHA-256, parallel to ``inputs``; absent in older
files), so that ``calib check`` can tell held-out photos from calibration photos.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bodyfit.calib.boards import BoardSpec
from bodyfit.common.errors import UserError
from bodyfit.common.files import read_json_file

__all__ = ["CAMERA_FORMAT", "DIST_LENGTHS", "CalibrationInput", "Camera", "camera_fields", "load_camera"]

CAMERA_FORMAT = "bodyfit.camera/1"
DIST_LENGTHS = (4, 5, 8, 12, 14)
MAX_IMAGE_SIDE_PX = 100_000  # larger than any camera's; guards against absurd sizes


@dataclass(frozen=True)
class CalibrationInput:
    """A photo or video the camera was calibrated from.

    Attributes:
        path: as given to ``calib capture`` (relative to the folder it ran in).
        sha256: hex SHA-256 of the file's bytes; None in files that did not record it.
    """

    path: str
    sha256: str | None


@dataclass(frozen=True)
class Camera:
    """A pinhole camera with lens distortion (OpenCV's model).

    Attributes:
        image_size_px: (width, height) of the images it applies to, sensor frame.
        K: (3, 3) float64 camera matrix, pixels.
        dist: (n,) float64 distortion coefficients, OpenCV order, n in 4, 5, 8, 12, 14.
        board: the board it was calibrated with, if known (``calib check`` reuses it).
        rms_px: RMS reprojection error of the calibration, pixels, if known.
        inputs: the inputs it was calibrated from, if known (from camera.json's provenance).
    """

    image_size_px: tuple[int, int]
    K: np.ndarray
    dist: np.ndarray
    board: BoardSpec | None = None
    rms_px: float | None = None
    inputs: tuple[CalibrationInput, ...] = ()

    def check_image(self, image: np.ndarray, name: str) -> None:
        """Raise UserError unless ``image`` ((H, W, ...) array) has this camera's size."""
        height, width = image.shape[:2]
        if (width, height) == tuple(self.image_size_px):
            return
        hint = ""
        if (height, width) == tuple(self.image_size_px):
            hint = " (the same size turned 90 degrees: was the photo rotated by an editor before saving?)"
        raise UserError(
            f"{name} is {width}x{height} pixels but the camera was calibrated on "
            f"{self.image_size_px[0]}x{self.image_size_px[1]} images{hint}; use photos straight "
            "from the calibrated camera, same resolution setting"
        )


def camera_fields(camera: Camera) -> dict:
    """The JSON fields :func:`load_camera` reads, for ``camera``."""
    fields = {
        "format": CAMERA_FORMAT,
        "image_size_px": [int(camera.image_size_px[0]), int(camera.image_size_px[1])],
        "K": np.asarray(camera.K, float).tolist(),
        "dist": np.asarray(camera.dist, float).reshape(-1).tolist(),
    }
    if camera.board is not None:
        fields["board"] = camera.board.to_dict()
    if camera.rms_px is not None:
        fields["rms_px"] = float(camera.rms_px)
    return fields


def _is_number(value: object) -> bool:
    """A JSON number that fits a float (not a bool, not an integer beyond float range)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        float(value)
    except OverflowError:
        return False
    return True


def _is_whole(value: object, lowest: int, highest: int) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and lowest <= value <= highest


_ADVICE = "; run `calib capture` again to make a new one"


def _fail(path: Path, problem: str) -> UserError:
    return UserError(f"camera file {path}: {problem}{_ADVICE}")


def load_camera(path: str | Path) -> Camera:
    """Read and validate camera.json; raises UserError saying what is wrong with it."""
    path = Path(path)
    record = read_json_file(path, f"camera file {path}", _ADVICE)
    if not isinstance(record, dict):
        raise _fail(path, "not a JSON object")
    missing = [key for key in ("image_size_px", "K", "dist") if key not in record]
    if missing:
        raise _fail(path, f"missing {', '.join(missing)}")

    size = record["image_size_px"]
    if not (isinstance(size, list) and len(size) == 2 and all(_is_whole(v, 1, MAX_IMAGE_SIDE_PX) for v in size)):
        raise _fail(path, f"image_size_px must be [width, height] in whole pixels (1 to {MAX_IMAGE_SIDE_PX})")
    try:
        K = np.array(record["K"], dtype=np.float64)
        dist = np.array(record["dist"], dtype=np.float64)
    except (TypeError, ValueError, OverflowError):  # OverflowError: integers beyond float range
        raise _fail(path, "K and dist must hold numbers only") from None
    if K.shape != (3, 3) or not np.isfinite(K).all():
        raise _fail(path, f"K must be a 3x3 matrix of finite numbers, got shape {K.shape}")
    if not (K[0, 0] > 0 and K[1, 1] > 0) or not np.allclose(K[2], [0, 0, 1]) or K[1, 0] != 0:
        raise _fail(path, "K must be [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with positive focal lengths")
    if dist.ndim != 1 or len(dist) not in DIST_LENGTHS or not np.isfinite(dist).all():
        raise _fail(
            path, f"dist must be a list of {', '.join(map(str, DIST_LENGTHS))} finite numbers, got {dist.shape}"
        )

    board = None
    if record.get("board") is not None:
        if not isinstance(record["board"], dict):
            raise _fail(path, "board must be an object")
        try:
            board = BoardSpec.from_dict(record["board"])
        except UserError as error:
            raise _fail(path, f"board: {error}") from None
    rms = record.get("rms_px")
    if rms is not None and not (_is_number(rms) and math.isfinite(rms) and rms >= 0):
        raise _fail(path, "rms_px must be a non-negative number")
    inputs = _calibration_inputs(path, record.get("provenance"))
    return Camera((size[0], size[1]), K, dist, board, None if rms is None else float(rms), inputs)


def _calibration_inputs(path: Path, provenance: object) -> tuple[CalibrationInput, ...]:
    """The provenance's ``inputs`` with their ``input_sha256``; () without a provenance."""
    if provenance is None:
        return ()
    if not isinstance(provenance, dict):
        raise _fail(path, "provenance must be an object")
    inputs = provenance.get("inputs", [])
    if not (isinstance(inputs, list) and all(isinstance(item, str) for item in inputs)):
        raise _fail(path, "provenance.inputs must be a list of paths")
    hashes = provenance.get("input_sha256", [None] * len(inputs))
    if not (
        isinstance(hashes, list)
        and len(hashes) == len(inputs)
        and all(item is None or isinstance(item, str) for item in hashes)
    ):
        raise _fail(path, "provenance.input_sha256 must list one hash per input")
    return tuple(CalibrationInput(item, digest) for item, digest in zip(inputs, hashes))
