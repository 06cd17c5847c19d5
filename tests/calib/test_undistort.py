"""kornia undistortion: a round trip through a synthetic lens, and agreement with OpenCV."""

import cv2
import numpy as np
import pytest
from scipy.spatial import cKDTree

from bodyfit.calib.camera import Camera
from bodyfit.calib.synthetic import distort_image
from bodyfit.calib.undistort import undistort_image
from bodyfit.common.errors import UserError

from calib_true_camera import IMAGE_SIZE, TRUE_DIST, TRUE_K

CAMERA = Camera(IMAGE_SIZE, TRUE_K, TRUE_DIST)
WIDTH, HEIGHT = IMAGE_SIZE


def dot_grid() -> tuple[np.ndarray, np.ndarray]:
    """A grid of soft dots, (H, W) uint8, and their centres (N, 2), pixels."""
    centres = np.stack(np.meshgrid(np.arange(60, WIDTH - 40, 80), np.arange(50, HEIGHT - 30, 70)), -1).reshape(-1, 2)
    ys, xs = np.mgrid[0:HEIGHT, 0:WIDTH]
    image = np.zeros((HEIGHT, WIDTH), np.float32)
    for x, y in centres:
        image += np.exp(-((xs - x) ** 2 + (ys - y) ** 2) / (2 * 6.0**2))
    return np.clip(image * 230, 0, 255).astype(np.uint8), centres.astype(np.float64)


def dot_centres(image: np.ndarray) -> np.ndarray:
    """Intensity-weighted centroids of the dots, (N, 2), pixels."""
    count, labels = cv2.connectedComponents((image > 40).astype(np.uint8))
    ys, xs = np.mgrid[0 : image.shape[0], 0 : image.shape[1]]
    weights = image.astype(np.float64)
    centres = []
    for label in range(1, count):
        inside = labels == label
        total = weights[inside].sum()
        centres.append(((xs[inside] * weights[inside]).sum() / total, (ys[inside] * weights[inside]).sum() / total))
    return np.array(centres)


def offsets(found: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """Distance from every expected dot to the nearest found one, (N,) pixels."""
    assert len(found) == len(expected)
    return cKDTree(found).query(expected)[0]


@pytest.fixture(scope="module")
def dots():
    ideal, centres = dot_grid()
    return ideal, centres, distort_image(ideal, TRUE_K, TRUE_DIST)


def test_distort_image_moves_the_dots_where_project_points_says(dots):
    _, centres, distorted = dots
    rays = np.hstack([(centres - TRUE_K[:2, 2]) / np.diag(TRUE_K)[:2], np.ones((len(centres), 1))])
    expected, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), TRUE_K, TRUE_DIST)
    expected = expected.reshape(-1, 2)
    assert np.linalg.norm(expected - centres, axis=1).max() > 5  # a real lens effect
    assert offsets(dot_centres(distorted), expected).max() < 0.15


def test_undistort_of_distort_returns_the_image(dots):
    ideal, centres, distorted = dots
    restored = undistort_image(distorted, CAMERA)
    assert restored.shape == ideal.shape and restored.dtype == np.uint8
    assert offsets(dot_centres(restored), centres).max() < 0.1
    difference = np.abs(restored.astype(int) - ideal.astype(int))
    assert difference.mean() < 0.5 and difference.max() <= 12


def test_kornia_agrees_with_cv2_undistort(dots):
    _, _, distorted = dots
    ours = undistort_image(distorted, CAMERA)
    reference = cv2.undistort(distorted, TRUE_K, TRUE_DIST)
    assert offsets(dot_centres(ours), dot_centres(reference)).max() < 0.05
    assert np.abs(ours.astype(int) - reference.astype(int)).mean() < 0.2


def test_colour_and_float_images_keep_their_layout(dots):
    _, _, distorted = dots
    colour = np.dstack([distorted, distorted // 2, 255 - distorted])
    result = undistort_image(colour, CAMERA)
    assert result.shape == colour.shape
    np.testing.assert_array_equal(result[..., 0], undistort_image(distorted, CAMERA))
    as_float = undistort_image(distorted.astype(np.float32) / 255, CAMERA)
    assert as_float.dtype == np.float32
    np.testing.assert_allclose(as_float * 255, undistort_image(distorted, CAMERA), atol=0.51)


def test_wrong_size_is_a_user_error():
    with pytest.raises(UserError, match="calibrated on 1280x720"):
        undistort_image(np.zeros((480, 640), np.uint8), CAMERA, "small.png")
