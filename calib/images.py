"""Reading photos and video frames, and writing images, in one consistent pixel frame.

EXIF orientation: a phone stores every photo in its *sensor* pixel layout and records
how to turn it upright in the EXIF Orientation tag. The camera matrix describes the
sensor layout, so every image is read with ``cv2.IMREAD_IGNORE_ORIENTATION`` (and
videos with ``CAP_PROP_ORIENTATION_AUTO`` off): calibration, undistortion and
silhouette extraction all happen in the sensor frame, and portrait and landscape shots
of one phone share one camera.json. Only images made for people or for the fitter
(undistorted photos, masks) are turned upright at the end with :func:`to_upright`,
using the tag :func:`read_photo` returns.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import sys
import tempfile
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from PIL import ExifTags, Image

from bodyfit.calib.blur import edge_rise_px
from bodyfit.common.errors import UserError
from bodyfit.common.files import check_input_file, write_atomic

__all__ = [
    "FULL_FRAME_DIAGONAL_MM",
    "VIDEO_SUFFIXES",
    "Photo",
    "encode_image",
    "frame_name",
    "is_video",
    "native_messages_logged",
    "read_frames",
    "read_image_file",
    "read_photo",
    "sample_video_frames",
    "to_upright",
    "write_image",
]

log = logging.getLogger(__name__)

VIDEO_SUFFIXES = frozenset({".mp4", ".mov", ".m4v", ".avi", ".mkv", ".webm", ".mts", ".3gp"})

#: A full frame's (35 mm film) diagonal, mm: EXIF's FocalLengthIn35mmFilm is the focal
#: length that gives the same field of view across it.
FULL_FRAME_DIAGONAL_MM = 43.27
_RESOLUTION_UNIT_MM = {2: 25.4, 3: 10.0, 4: 1.0, 5: 0.001}  # EXIF: inch, cm, mm, micrometre
#: Fields of view (across the long side, degrees) an EXIF focal length may give; beyond,
#: the tag is taken as wrong.
_PLAUSIBLE_FOV_DEG = (15.0, 130.0)
# Frames are ranked for sharpness at this width; the ranking only compares frames of one clip.
_RANKING_WIDTH_PX = 640


@dataclass(frozen=True)
class Photo:
    """A photo as the sensor recorded it.

    Attributes:
        pixels: (H, W, 3) uint8, BGR, sensor frame (EXIF orientation not applied).
        orientation: EXIF Orientation tag, 1..8 (1 when the file has none).
        focal_px: the focal length EXIF states, in pixels of this photo (None: none stated).
        focal_source: which EXIF tags stated it ("" when none did).
    """

    pixels: np.ndarray
    orientation: int
    focal_px: float | None = None
    focal_source: str = ""


def _exif_fields(exif: bytes, size_px: tuple[int, int]) -> tuple[int, float | None, str]:
    """(orientation 1..8, focal length in sensor pixels or None, what stated it) of an EXIF
    block (Pillow's reading; a malformed block or tag counts as absent).

    The focal length, in the order a phone's JPEG states it: ``FocalLengthIn35mmFilm``
    (scaled from a full frame's diagonal, :data:`FULL_FRAME_DIAGONAL_MM`, to the photo's
    ``size_px`` (width, height) diagonal), else ``FocalLength`` with the sensor's size
    (``FocalPlaneXResolution`` in ``FocalPlaneResolutionUnit``). A value that gives a
    field of view outside :data:`_PLAUSIBLE_FOV_DEG` across the long side is ignored.
    """
    try:
        tags = Image.Exif()
        tags.load(exif)
        orientation = int(tags.get(ExifTags.Base.Orientation, 1))
        fields = tags.get_ifd(ExifTags.IFD.Exif)
    except Exception:  # Pillow raises many kinds on a malformed block  # noqa: BLE001
        return 1, None, ""
    orientation = orientation if 1 <= orientation <= 8 else 1
    focal, source = None, ""
    try:
        full_frame = float(fields.get(ExifTags.Base.FocalLengthIn35mmFilm, 0) or 0)
        focal_mm = float(fields.get(ExifTags.Base.FocalLength, 0) or 0)
        per_unit = float(fields.get(ExifTags.Base.FocalPlaneXResolution, 0) or 0)
        unit_mm = _RESOLUTION_UNIT_MM.get(int(fields.get(
            ExifTags.Base.FocalPlaneResolutionUnit, 2)), 0.0)
    except (TypeError, ValueError, ZeroDivisionError):
        return orientation, None, ""
    if full_frame > 0:
        focal = full_frame * math.hypot(*size_px) / FULL_FRAME_DIAGONAL_MM
        source = f"EXIF FocalLengthIn35mmFilm {full_frame:g} mm"
    elif focal_mm > 0 and per_unit > 0 and unit_mm > 0:
        focal = focal_mm * per_unit / unit_mm
        source = f"EXIF FocalLength {focal_mm:g} mm and the sensor's FocalPlaneXResolution"
    if focal is not None:
        fov = math.degrees(2 * math.atan(max(size_px) / 2 / focal))
        if not _PLAUSIBLE_FOV_DEG[0] <= fov <= _PLAUSIBLE_FOV_DEG[1]:
            log.warning("ignoring the photo's EXIF focal length (%s): %.0f degrees across "
                        "is no phone's", source, fov)
            focal, source = None, ""
    return orientation, focal, source


@contextlib.contextmanager
def native_messages_logged(source: str | Path):
    """Within it, what native libraries write to the process's standard error goes to the
    debug log instead, each line under ``source``: libjpeg's "Premature end of JPEG file"
    beside the one line a corrupt photo gets, LiteRT's note on its CPU delegate. It yields
    a list that holds those lines once the block has ended."""
    sys.stderr.flush()
    saved = os.dup(2)
    said: list[str] = []
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield said
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            said.extend(sink.read().decode(errors="replace").splitlines())
            for line in said:
                log.debug("%s: a native library said: %s", source, line)


def read_image_file(path: str | Path, flags: int) -> tuple[np.ndarray, list, list]:
    """``cv2.imreadWithMetadata(path, flags)``: (pixels, metadata kinds, metadata blocks).

    Raises UserError when the file is missing or OpenCV cannot decode it (corrupt,
    not an image, or declaring more pixels than OpenCV accepts), or when it is a JPEG cut
    short (libjpeg fills the missing rows in grey and says "Premature end of JPEG file").
    """
    path = Path(path)
    check_input_file(path)
    try:
        with native_messages_logged(path) as said:
            pixels, kinds, blocks = cv2.imreadWithMetadata(str(path), flags)
    except cv2.error:  # e.g. a header claiming a width above CV_IO_MAX_IMAGE_WIDTH
        pixels, kinds, blocks = None, [], []
    if pixels is None or pixels.size == 0:
        raise UserError(f"{path}: not a readable image (OpenCV cannot decode it)")
    if any("Premature end of JPEG file" in line for line in said):
        raise UserError(f"{path}: the file is cut short (its JPEG data ends early); copy "
                        "the photo from the phone again")
    return pixels, kinds, blocks


def read_photo(path: str | Path) -> Photo:
    """Read a photo in the sensor frame, with its EXIF orientation and focal length;
    UserError if unreadable."""
    pixels, kinds, blocks = read_image_file(path, cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION)
    for kind, block in zip(np.asarray(kinds).reshape(-1), blocks):
        if kind == cv2.IMAGE_METADATA_EXIF:
            size = (pixels.shape[1], pixels.shape[0])
            return Photo(pixels, *_exif_fields(np.asarray(block, np.uint8).tobytes(), size))
    return Photo(pixels, 1)


def to_upright(image: np.ndarray, orientation: int) -> np.ndarray:
    """Turn a sensor-frame image upright as its EXIF ``orientation`` (1..8) says.

    Works on any (H, W, ...) array (photos, masks); matches what ``cv2.imread`` does by
    default with the same tag.
    """
    if orientation == 1:
        return image
    if orientation == 2:
        return cv2.flip(image, 1)
    if orientation == 3:
        return cv2.rotate(image, cv2.ROTATE_180)
    if orientation == 4:
        return cv2.flip(image, 0)
    if orientation == 5:
        return cv2.transpose(image)
    if orientation == 6:
        return cv2.rotate(image, cv2.ROTATE_90_CLOCKWISE)
    if orientation == 7:
        return cv2.flip(cv2.transpose(image), -1)
    if orientation == 8:
        return cv2.rotate(image, cv2.ROTATE_90_COUNTERCLOCKWISE)
    raise ValueError(f"EXIF orientation must be 1..8, got {orientation}")


def is_video(path: str | Path) -> bool:
    """Whether ``path`` names a video (by its suffix, one of :data:`VIDEO_SUFFIXES`)."""
    return Path(path).suffix.lower() in VIDEO_SUFFIXES


def sample_video_frames(path: str | Path, max_frames: int) -> Iterator[tuple[int, np.ndarray]]:
    """The sharpest frame of each of about ``max_frames`` equal stretches of a video.

    Yields (frame_index, (H, W, 3) uint8 BGR sensor-frame frame) in time order. The
    stretches are the clip split evenly by frame count (one per second when the
    container does not say how many frames it holds). Raises UserError when the
    file cannot be opened as a video.
    """
    if max_frames < 1:
        raise ValueError(f"max_frames must be at least 1, got {max_frames}")
    path = Path(path)
    check_input_file(path)
    capture = cv2.VideoCapture(str(path))
    try:
        if not capture.isOpened():
            raise UserError(f"{path}: not a readable video (OpenCV cannot open it)")
        capture.set(cv2.CAP_PROP_ORIENTATION_AUTO, 0)
        frame_count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
        frames_per_second = capture.get(cv2.CAP_PROP_FPS)
        if frame_count > 0:
            stretch = max(1, math.ceil(frame_count / max_frames))
        else:
            stretch = max(1, round(frames_per_second)) if frames_per_second > 0 else 30
        best: tuple[float, int, np.ndarray] | None = None
        index = -1
        frames_read = 0
        while True:
            ok, frame = capture.read()
            if not ok:
                break
            index += 1
            frames_read += 1
            if best is not None and index // stretch != best[1] // stretch:
                yield best[1], best[2]
                best = None
            rise = _ranking_rise(frame)
            if best is None or rise < best[0]:
                best = (rise, index, frame)
        if best is not None:
            yield best[1], best[2]
        if frames_read == 0:
            raise UserError(f"{path}: the video holds no frame OpenCV can decode")
        log.info("%s: %d frames read, stretches of %d frames", path, frames_read, stretch)
    finally:
        capture.release()


def frame_name(source: str, frame_index: int | None) -> str:
    """How reports name an input image: ``photo.jpg``, or ``clip.mp4@frame 120`` for a video frame."""
    return source if frame_index is None else f"{source}@frame {frame_index}"


def read_frames(paths: Iterable[str], video_max_frames: int) -> Iterator[tuple[str, int | None, np.ndarray]]:
    """(source, frame_index, (H, W, 3) uint8 BGR sensor-frame image) for every input.

    A photo gives one image (frame_index None), a video its sampled frames
    (:func:`sample_video_frames`). All images must have one size: UserError names the
    first that differs.
    """
    first: tuple[tuple[int, int], str] | None = None
    for path in paths:
        frames = sample_video_frames(path, video_max_frames) if is_video(path) else [(None, read_photo(path).pixels)]
        for frame_index, image in frames:
            size = (image.shape[1], image.shape[0])
            if first is None:
                first = (size, path)
            elif size != first[0]:
                raise UserError(
                    f"{path} is {size[0]}x{size[1]} pixels but {first[1]} is {first[0][0]}x{first[0][1]}; "
                    "the images must all have one size (a phone's photos and videos often differ: "
                    "use them separately)"
                )
            yield path, frame_index, image


def _ranking_rise(frame: np.ndarray) -> float:
    gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    if gray.shape[1] > _RANKING_WIDTH_PX:
        height = round(gray.shape[0] * _RANKING_WIDTH_PX / gray.shape[1])
        gray = cv2.resize(gray, (_RANKING_WIDTH_PX, height), interpolation=cv2.INTER_AREA)
    return edge_rise_px(gray)


def encode_image(image: np.ndarray, suffix: str) -> bytes:
    """Encode ``image`` ((H, W) or (H, W, 3) uint8) in the format named by ``suffix`` (".png", ".jpg", ...).

    JPEG is written at quality 95.
    """
    params = [cv2.IMWRITE_JPEG_QUALITY, 95] if suffix.lower() in (".jpg", ".jpeg") else []
    try:
        ok, payload = cv2.imencode(suffix, image, params)
    except cv2.error:
        ok = False
    if not ok:
        raise UserError(f"cannot write a {suffix!r} image; use .png or .jpg")
    return payload.tobytes()


def write_image(path: str | Path, image: np.ndarray) -> None:
    """Encode ``image`` by the suffix of ``path`` and write it atomically."""
    write_atomic(path, encode_image(image, Path(path).suffix))
