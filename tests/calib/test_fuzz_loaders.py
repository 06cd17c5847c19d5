"""Fuzzed loaders: whatever a user's file holds, calib answers with one-line UserError.

Every reader of a user's file (camera.json, photos, masks) is fed random, truncated,
mutated and oddly shaped files. Each must return a valid result or raise UserError with
a single-line message, never another exception; the CLI commands that write outputs
must then write nothing. Settings (derandomized, no deadline) come from the "bodyfit"
hypothesis profile in tests/conftest.py.
"""

import contextlib
import io
import json
import struct
import tempfile
import zlib
from pathlib import Path

import cv2
import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bodyfit.calib.camera import Camera, camera_fields, load_camera
from bodyfit.calib.cli import main
from bodyfit.calib.images import read_photo
from bodyfit.calib.silhouette import load_mask
from bodyfit.common.errors import UserError

from calib_true_camera import TRUE_DIST, TRUE_K

VALID_CAMERA = camera_fields(Camera((64, 48), TRUE_K * 0.05 + np.diag([0, 0, 0.95]), TRUE_DIST))
VALID_CAMERA["provenance"] = {"inputs": ["a.png", "b.png"], "input_sha256": ["0" * 64, "1" * 64]}
VALID_CAMERA_TEXT = json.dumps(VALID_CAMERA, indent=2)

json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=8), inner, max_size=5),
    max_leaves=20,
)


def _loaded_or_user_error(load, path):
    """load(path), or None after a UserError, which must be a single non-empty line."""
    try:
        return load(path)
    except UserError as error:
        message = str(error)
        assert message and "\n" not in message, repr(message)
        return None


def _mutated(payload: bytes, cut: int, flips: list[tuple[int, int]]) -> bytes:
    """``payload`` cut to ``cut`` bytes, then some bytes replaced: (position, value) pairs."""
    data = bytearray(payload[:cut])
    for position, value in flips:
        if data:
            data[position % len(data)] = value
    return bytes(data)


mutations = st.tuples(
    st.integers(0, 10**6), st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), max_size=4)
)


def _with_file(suffix: str, payload: bytes, check) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"input{suffix}"
        path.write_bytes(payload)
        check(path)


# --- camera.json -------------------------------------------------------------------------


def _check_camera(path):
    camera = _loaded_or_user_error(load_camera, path)
    if camera is not None:  # accepted: it must be a camera the rest of calib can use
        assert camera.K.shape == (3, 3) and np.isfinite(camera.K).all() and camera.K[0, 0] > 0
        assert all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in camera.image_size_px)
        assert np.isfinite(camera.dist).all()


@given(st.binary(max_size=300))
def test_camera_file_of_random_bytes(payload):
    _with_file(".json", payload, _check_camera)


@given(json_values)
def test_camera_file_of_random_json(value):
    _with_file(".json", json.dumps(value).encode(), _check_camera)


@given(mutations)
def test_camera_file_truncated_or_mutated(mutation):
    _with_file(".json", _mutated(VALID_CAMERA_TEXT.encode(), *mutation), _check_camera)


@given(
    st.sampled_from(sorted(VALID_CAMERA) + ["board"]),
    st.one_of(
        json_values,
        st.just("missing"),
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(min_value=-(10**400), max_value=10**400),
    ),
)
def test_camera_file_with_a_field_of_the_wrong_type(key, value):
    record = json.loads(VALID_CAMERA_TEXT)
    if value == "missing":
        record.pop(key, None)
    else:
        record[key] = value
    _with_file(".json", json.dumps(record).encode(), _check_camera)


@given(
    st.tuples(st.integers(0, 2), st.integers(0, 2)),
    st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-(10**30), 10**30), json_values),
)
def test_camera_matrix_with_odd_entries(entry, value):
    record = json.loads(VALID_CAMERA_TEXT)
    record["K"][entry[0]][entry[1]] = value  # NaN, negative focal lengths, huge numbers, lists...
    _with_file(".json", json.dumps(record).encode(), _check_camera)


# --- photos and masks ----------------------------------------------------------------------


def _check_image_readers(path):
    photo = _loaded_or_user_error(read_photo, path)
    if photo is not None:
        assert photo.pixels.ndim == 3 and photo.pixels.shape[2] == 3 and photo.pixels.dtype == np.uint8
        assert 1 <= photo.orientation <= 8
    mask = _loaded_or_user_error(load_mask, path)
    if mask is not None:
        assert mask.ndim == 2 and mask.dtype == bool


@st.composite
def small_images(draw):
    """(suffix, encoded bytes) of a small random image of 1, 3 or 4 channels, 8 or 16 bits."""
    suffix = draw(st.sampled_from([".png", ".jpg", ".bmp", ".tiff", ".webp"]))
    channels = draw(st.sampled_from([1, 3, 4]))  # OpenCV writes no 2-channel files
    depth = np.uint16 if suffix in (".png", ".tiff") and draw(st.booleans()) else np.uint8
    height, width = draw(st.integers(1, 24)), draw(st.integers(1, 24))
    seed = draw(st.integers(0, 2**32 - 1))
    pixels = np.random.default_rng(seed).integers(0, np.iinfo(depth).max, (height, width, channels), dtype=depth)
    ok, payload = cv2.imencode(suffix, pixels)
    assert ok
    return suffix, payload.tobytes()


def _png_claiming(width: int, height: int, bit_depth: int, colour_type: int) -> bytes:
    """A PNG whose header declares ``width`` x ``height`` pixels but holds almost no data."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + chunk(
        b"IEND", b""
    )


def _jpeg_with_exif(exif: bytes) -> bytes:
    """A small JPEG whose APP1 segment holds ``exif`` after the Exif marker."""
    ok, jpeg = cv2.imencode(".jpg", np.full((16, 16, 3), 128, np.uint8))
    segment = b"Exif\x00\x00" + exif
    return b"\xff\xd8\xff\xe1" + struct.pack(">H", len(segment) + 2) + segment + jpeg.tobytes()[2:]


@given(st.binary(max_size=400), st.sampled_from([".png", ".jpg", ".tiff", ".bmp"]))
def test_photo_of_random_bytes(payload, suffix):
    _with_file(suffix, payload, _check_image_readers)


@given(small_images(), mutations)
def test_photo_truncated_or_mutated(image, mutation):
    suffix, payload = image
    _with_file(suffix, _mutated(payload, *mutation), _check_image_readers)


@given(small_images())
def test_photo_of_any_depth_and_channel_count(image):
    suffix, payload = image
    _with_file(suffix, payload, _check_image_readers)


@given(
    st.integers(1, 2**31 - 1), st.integers(1, 2**31 - 1), st.sampled_from([(8, 0), (8, 2), (16, 2), (8, 6), (16, 0)])
)
def test_photo_claiming_huge_dimensions(width, height, depth_and_type):
    _with_file(".png", _png_claiming(width, height, *depth_and_type), _check_image_readers)


def test_photo_claiming_100000_by_100000_pixels():
    _with_file(".png", _png_claiming(100000, 100000, 8, 2), _check_image_readers)


@given(
    st.one_of(
        st.binary(max_size=200),
        st.tuples(st.sampled_from([b"II*\x00", b"MM\x00*"]), st.binary(max_size=200)).map(lambda t: t[0] + t[1]),
    )
)
def test_photo_with_junk_exif(exif):
    _with_file(".jpg", _jpeg_with_exif(exif), _check_image_readers)


def test_zero_size_photo_and_camera_file():
    _with_file(".jpg", b"", _check_image_readers)
    _with_file(".json", b"", _check_camera)


# --- through the CLI: one line, exit 2, nothing written ------------------------------------


def _run_cli(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(arg) for arg in argv])
    return code, err.getvalue()


def _bad_photos():
    return st.one_of(
        st.binary(max_size=300).map(lambda payload: (".jpg", payload)),
        st.tuples(small_images(), mutations).map(lambda t: (t[0][0], _mutated(t[0][1], *t[1]))),
        small_images(),
        st.tuples(st.integers(1, 2**31 - 1), st.integers(1, 2**31 - 1)).map(
            lambda size: (".png", _png_claiming(size[0], size[1], 8, 2))
        ),
    )


@settings(max_examples=100, suppress_health_check=[HealthCheck.too_slow])
@given(_bad_photos(), st.booleans())
def test_cli_writes_nothing_for_a_bad_photo(photo, with_camera):
    suffix, payload = photo
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        photo_path = folder / f"photo{suffix}"
        photo_path.write_bytes(payload)
        camera_path = folder / "camera.json"
        camera_path.write_text(VALID_CAMERA_TEXT)
        outputs = folder / "outputs"
        camera_option = ["--camera", camera_path] if with_camera else []
        for argv in (
            ["silhouette", photo_path, *camera_option, "-o", outputs / "mask.png"],
            ["undistort", camera_path, photo_path, "-o", outputs / "undistorted"],
        ):
            code, stderr = _run_cli(argv)
            assert code == 2, argv  # a 64x48 camera; none of these photos holds a person
            assert stderr.startswith("calib: error: ") and stderr.count("\n") == 1, stderr
            assert not outputs.exists()


@settings(max_examples=100)
@given(st.one_of(json_values.map(lambda v: json.dumps(v).encode()), mutations.map(
    lambda m: _mutated(VALID_CAMERA_TEXT.encode(), *m))))
def test_cli_writes_nothing_for_a_bad_camera_file(payload):
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        photo_path = folder / "photo.png"
        cv2.imwrite(str(photo_path), np.full((48, 64, 3), 128, np.uint8))
        camera_path = folder / "camera.json"
        camera_path.write_bytes(payload)
        outputs = folder / "outputs"
        for argv in (
            ["silhouette", photo_path, "--camera", camera_path, "-o", outputs / "mask.png"],
            ["undistort", camera_path, photo_path, "-o", outputs / "undistorted"],
        ):
            code, stderr = _run_cli(argv)
            if code == 0:  # a mutation that left a valid camera: undistort may succeed
                continue
            assert code == 2 and stderr.startswith("calib: error: ") and stderr.count("\n") == 1, stderr
            assert not outputs.exists()
