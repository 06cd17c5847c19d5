"""Reading photos in the sensor frame, EXIF orientation, video sampling, atomic writes."""

import cv2
import numpy as np
import pytest

from bodyfit.calib.images import (read_frames, read_photo, sample_video_frames, to_upright,
                                  write_image,)
from bodyfit.common.errors import UserError

from calib_scenes import exif_with_orientation


@pytest.fixture(scope="module")
def asymmetric_image():
    image = np.zeros((48, 80, 3), np.uint8)
    image[:16, :24] = (0, 0, 255)
    image[32:, 56:] = (255, 0, 0)
    image[:, 40:44] = (0, 255, 0)
    return image


@pytest.mark.parametrize("orientation", range(1, 9))
def test_orientation_is_read_and_applied_like_opencv(tmp_path, asymmetric_image, orientation):
    path = tmp_path / f"o{orientation}.jpg"
    order = "<" if orientation % 2 else ">"
    assert cv2.imwriteWithMetadata(
        str(path), asymmetric_image, [cv2.IMAGE_METADATA_EXIF], [exif_with_orientation(orientation, order)]
    )
    photo = read_photo(path)
    assert photo.orientation == orientation
    # Sensor frame: exactly what OpenCV decodes when told to ignore the tag.
    assert np.array_equal(photo.pixels, cv2.imread(str(path), cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION))
    # Upright: exactly what OpenCV decodes when it applies the tag itself.
    assert np.array_equal(to_upright(photo.pixels, photo.orientation), cv2.imread(str(path)))


def test_photo_without_exif_has_orientation_one(tmp_path, asymmetric_image):
    path = tmp_path / "plain.png"
    cv2.imwrite(str(path), asymmetric_image)
    assert read_photo(path).orientation == 1


def test_unreadable_and_missing_files_are_user_errors(tmp_path):
    junk = tmp_path / "junk.jpg"
    junk.write_bytes(b"not an image at all")
    with pytest.raises(UserError, match="not a readable image"):
        read_photo(junk)
    with pytest.raises(UserError, match="no such file"):
        read_photo(tmp_path / "missing.jpg")
    with pytest.raises(UserError, match="not a readable video"):
        list(sample_video_frames(junk.rename(tmp_path / "junk.mp4"), 5))


def test_a_truncated_jpeg_is_one_user_error_and_nothing_on_stderr(tmp_path, capfd):
    """The decoder's own complaint (libjpeg's "Premature end of JPEG file", written to the
    process's standard error) stays off the terminal: the UserError is the one line. A JPEG
    cut short is refused (libjpeg would fill its missing rows in grey); the whole one reads."""
    photo = np.random.default_rng(0).integers(0, 256, (300, 200, 3), np.uint8)
    whole = cv2.imencode(".jpg", photo)[1].tobytes()
    truncated = tmp_path / "cut.jpg"
    truncated.write_bytes(whole[:len(whole) // 2])  # half the rows' data
    capfd.readouterr()
    with pytest.raises(UserError, match="cut.jpg: the file is cut short"):
        read_photo(truncated)
    truncated.write_bytes(whole)
    assert read_photo(truncated).pixels.shape == photo.shape
    corrupt = tmp_path / "corrupt.jpg"
    corrupt.write_bytes(b"\xff\xd8\xff\xe0garbage")
    with pytest.raises(UserError, match="not a readable image"):
        read_photo(corrupt)
    assert capfd.readouterr().err == ""


def test_images_of_different_sizes_are_refused(tmp_path):
    for name, shape in (("a.png", (40, 60, 3)), ("b.png", (60, 40, 3))):
        cv2.imwrite(str(tmp_path / name), np.zeros(shape, np.uint8))
    with pytest.raises(UserError, match="b.png is 40x60 pixels but .*a.png is 60x40"):
        list(read_frames([str(tmp_path / "a.png"), str(tmp_path / "b.png")], 5))


def test_video_sampling_picks_the_sharpest_frame_of_each_stretch(tmp_path):
    # Three stretches of 6 frames; in each, one frame is sharp and the others blurred.
    rng = np.random.default_rng(5)
    path = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10, (320, 240))
    sharp_frames = {2, 9, 13}
    for index in range(18):
        scene = np.kron(rng.integers(0, 2, (12, 16)), np.ones((20, 20))).astype(np.uint8) * 200
        if index not in sharp_frames:
            scene = cv2.GaussianBlur(scene, (0, 0), 3.0)
        writer.write(cv2.cvtColor(scene, cv2.COLOR_GRAY2BGR))
    writer.release()
    sampled = list(sample_video_frames(path, 3))
    assert [index for index, _ in sampled] == sorted(sharp_frames)
    assert all(frame.shape == (240, 320, 3) for _, frame in sampled)


def test_write_image_refuses_unknown_formats(tmp_path):
    with pytest.raises(UserError, match="cannot write"):
        write_image(tmp_path / "mask.xyz", np.zeros((4, 4), np.uint8))
    assert list(tmp_path.iterdir()) == []
