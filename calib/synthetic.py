"""Synthetic photos through a known lens: the ground truth for tests and benchmarks.

A real lens maps an ideal (pinhole) image point to a distorted one by OpenCV's model
(``cv2.projectPoints``). To *render* through it, every recorded pixel looks up where it
came from: its centre is undistorted with ``cv2.undistortPoints`` (iterated to
convergence) and the scene is sampled there. Boards are rendered at ``supersampling``
times the resolution and box-filtered down, so edges are anti-aliased like a sensor's.

Units: pixels for images, millimetres for board poses (``tvec_mm``), radians for
rotation vectors (``rvec``), the board in front of the camera along +z.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from bodyfit.calib.boards import BoardPicture, BoardSpec, render_board

__all__ = [
    "BoardPhotoRenderer",
    "BoardPhotoSet",
    "bend_photo",
    "distort_image",
    "random_board_poses",
    "source_coordinates",
    "write_board_photos",
]

_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)


def source_coordinates(
    K: np.ndarray, dist: np.ndarray, image_size_px: tuple[int, int], supersampling: int = 1, to_pixels: bool = False
) -> np.ndarray:
    """Where each recorded pixel's light came from.

    Args:
        K: (3, 3) float, camera matrix, pixels.
        dist: (n,) float, distortion coefficients in OpenCV order.
        image_size_px: (width, height) of the recorded image.
        supersampling: s; the grid has s x s samples per recorded pixel, centred in it.
        to_pixels: False: normalised ideal coordinates (x/z, y/z); True: ideal pixels (K applied).

    Returns:
        (H*s, W*s, 2) float64: for every sample, its undistorted coordinates.
    """
    width, height = image_size_px
    offsets = (np.arange(supersampling) + 0.5) / supersampling - 0.5
    xs = (np.arange(width)[:, None] + offsets[None, :]).reshape(-1)
    ys = (np.arange(height)[:, None] + offsets[None, :]).reshape(-1)
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 1, 2)
    projection = np.asarray(K, np.float64) if to_pixels else None
    ideal = cv2.undistortPoints(grid, K, dist, R=None, P=projection, criteria=_UNDISTORT_CRITERIA)
    return ideal.reshape(height * supersampling, width * supersampling, 2)


def distort_image(
    ideal_image: np.ndarray, K: np.ndarray, dist: np.ndarray, outside: float | tuple[float, ...] = 0
) -> np.ndarray:
    """The image a distorting lens records of a scene whose pinhole image is ``ideal_image``.

    Args:
        ideal_image: (H, W) or (H, W, C) uint8, undistorted (pinhole) image.
        K, dist: the lens, as in :func:`source_coordinates`.
        outside: the value (a grey level, or one per channel) of pixels whose source falls
            outside the ideal image: black by default; a plain backdrop's colour continues it.

    Returns:
        Same shape and dtype, the distorted image. ``cv2.undistort`` (or kornia's) takes it back.
    """
    height, width = ideal_image.shape[:2]
    source = source_coordinates(K, dist, (width, height), to_pixels=True).astype(np.float32)
    return cv2.remap(
        ideal_image,
        source[..., 0],
        source[..., 1],
        cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=outside,
    )


class BoardPhotoRenderer:
    """Renders grey photos of a printed board through one camera; reuse it for many poses.

    Args:
        picture: the board as printed (:func:`bodyfit.calib.boards.render_board`).
        K: (3, 3) float, camera matrix, pixels.
        dist: (n,) float, distortion coefficients, OpenCV order.
        image_size_px: (width, height) of the photos.
        supersampling: samples per pixel along each axis.
    """

    def __init__(
        self,
        picture: BoardPicture,
        K: np.ndarray,
        dist: np.ndarray,
        image_size_px: tuple[int, int],
        supersampling: int = 2,
    ) -> None:
        self.picture = picture
        self.image_size_px = image_size_px
        rays = source_coordinates(K, dist, image_size_px, supersampling)
        self._rays = np.concatenate([rays, np.ones(rays.shape[:2] + (1,))], axis=-1)  # (H*s, W*s, 3)
        # Paper grey levels as a camera sees them: white is not 255, black is not 0.
        self._texture = (25 + picture.image.astype(np.float32) * (205 / 255)).astype(np.float32)

    def render(
        self,
        rvec: np.ndarray,
        tvec_mm: np.ndarray,
        noise_sigma: float = 2.0,
        rng: np.random.Generator | None = None,
        background: float = 110.0,
    ) -> np.ndarray:
        """Photo of the board at pose (rvec, tvec_mm): (H, W) uint8, with Gaussian noise.

        Args:
            rvec: (3,) rotation vector, board to camera, radians.
            tvec_mm: (3,) board origin in the camera frame, millimetres.
            noise_sigma: standard deviation of the sensor noise, grey levels.
            rng: noise source (a fixed seed gives the same photo).
            background: grey level around the board.
        """
        rotation, _ = cv2.Rodrigues(np.asarray(rvec, np.float64))
        plane_to_rays = np.column_stack([rotation[:, 0], rotation[:, 1], np.asarray(tvec_mm, np.float64)])
        board = self._rays @ np.linalg.inv(plane_to_rays).T  # (X, Y, 1) / depth per sample
        in_front = board[..., 2] > 0
        scale = self.picture.pixels_per_mm
        origin = np.asarray(self.picture.origin_px)
        # Board millimetres -> picture pixel-centre coordinates.
        texel = board[..., :2] / board[..., 2:3] * scale + origin - 0.5
        texel[~in_front] = -1e6
        texel = texel.astype(np.float32)
        fine = cv2.remap(
            self._texture,
            texel[..., 0],
            texel[..., 1],
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_CONSTANT,
            borderValue=background,
        )
        width, height = self.image_size_px
        photo = cv2.resize(fine, (width, height), interpolation=cv2.INTER_AREA)
        if noise_sigma > 0:
            rng = rng if rng is not None else np.random.default_rng(0)
            photo = photo + rng.normal(0.0, noise_sigma, photo.shape)
        return np.clip(np.rint(photo), 0, 255).astype(np.uint8)


def _rotation(tilt_x: float, tilt_y: float, roll: float) -> np.ndarray:
    rx, _ = cv2.Rodrigues(np.array([tilt_x, 0.0, 0.0]))
    ry, _ = cv2.Rodrigues(np.array([0.0, tilt_y, 0.0]))
    rz, _ = cv2.Rodrigues(np.array([0.0, 0.0, roll]))
    return rz @ ry @ rx


def random_board_poses(
    picture: BoardPicture,
    K: np.ndarray,
    dist: np.ndarray,
    image_size_px: tuple[int, int],
    count: int,
    rng: np.random.Generator,
    max_tilt_deg: float = 40.0,
    fill_range: tuple[float, float] = (0.35, 0.65),
    margin_px: float = 8.0,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """``count`` varied board poses (rvec, tvec_mm) that keep the whole picture in frame.

    The board is tilted up to ``max_tilt_deg`` about both in-plane axes, rolled up to
    30 degrees, placed so that it spans ``fill_range`` of the image width, and centred
    anywhere that keeps its printed margin ``margin_px`` inside the frame.
    """
    width, height = image_size_px
    picture_h, picture_w = picture.image.shape
    left, top = -np.asarray(picture.origin_px) / picture.pixels_per_mm
    right, bottom = left + picture_w / picture.pixels_per_mm, top + picture_h / picture.pixels_per_mm
    steps = np.linspace(0.0, 1.0, 9)
    outline = np.concatenate(
        [
            np.column_stack([left + (right - left) * steps, np.full(9, top)]),
            np.column_stack([np.full(9, right), top + (bottom - top) * steps]),
            np.column_stack([left + (right - left) * steps, np.full(9, bottom)]),
            np.column_stack([np.full(9, left), top + (bottom - top) * steps]),
        ]
    )
    outline = np.hstack([outline, np.zeros((len(outline), 1))])
    centre = np.array([(left + right) / 2, (top + bottom) / 2, 0.0])
    max_tilt = math.radians(max_tilt_deg)
    poses: list[tuple[np.ndarray, np.ndarray]] = []
    for _ in range(1000 * count):
        if len(poses) == count:
            break
        rotation = _rotation(*rng.uniform(-max_tilt, max_tilt, 2), rng.uniform(-math.pi / 6, math.pi / 6))
        depth = K[0, 0] * (right - left) / (rng.uniform(*fill_range) * width)
        target = np.array([rng.uniform(0.2, 0.8) * width, rng.uniform(0.2, 0.8) * height, 1.0])
        ray = np.linalg.solve(K, target)
        tvec = depth * ray - rotation @ centre
        rvec, _ = cv2.Rodrigues(rotation)
        camera_points = outline @ rotation.T + tvec
        if np.any(camera_points[:, 2] <= 0):
            continue
        projected, _ = cv2.projectPoints(outline, rvec, tvec, K, dist)
        projected = projected.reshape(-1, 2)
        inside = (
            (projected >= margin_px).all()
            and (projected[:, 0] <= width - 1 - margin_px).all()
            and (projected[:, 1] <= height - 1 - margin_px).all()
        )
        if inside:
            poses.append((rvec.reshape(3), tvec))
    if len(poses) < count:
        raise ValueError(f"found only {len(poses)} of {count} board poses that fit the frame")
    return poses


def bend_photo(
    photo: np.ndarray, amplitude_px: float = 2.0, wavelengths_px: tuple[float, float] = (180.0, 240.0)
) -> np.ndarray:
    """The photo of a board that is not flat: content shifted in a wave.

    x moves by ``amplitude_px * sin(2 pi y / wavelengths_px[0])`` and y by
    ``amplitude_px * sin(2 pi x / wavelengths_px[1])``. The detector still finds the
    board, but its corners fit no pinhole camera: a calibration outlier.
    """
    height, width = photo.shape[:2]
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    map_x = xs + amplitude_px * np.sin(2 * np.pi * ys / wavelengths_px[0])
    map_y = ys + amplitude_px * np.sin(2 * np.pi * xs / wavelengths_px[1])
    return cv2.remap(photo, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


@dataclass(frozen=True)
class BoardPhotoSet:
    """Grey PNG photos of one board through one camera, written by :func:`write_board_photos`.

    Attributes:
        spec: the board.
        sharp: the usable photos, ``view00.png`` ...
        blurred: the first photo blurred by a 2.5 px Gaussian (edge rise about 6.5 px): too blurry.
        bent: the second photo through :func:`bend_photo`: corners that fit no camera, an outlier.
    """

    spec: BoardSpec
    sharp: list[Path]
    blurred: Path
    bent: Path


def write_board_photos(
    folder: Path,
    spec: BoardSpec,
    K: np.ndarray,
    dist: np.ndarray,
    image_size_px: tuple[int, int],
    count: int,
    seed: int,
    fill_range: tuple[float, float] = (0.3, 0.6),
) -> BoardPhotoSet:
    """Photograph ``spec`` from ``count`` random poses (:func:`random_board_poses`) into ``folder``.

    The board is printed at 60 pixels per square; the camera noise is 2 grey levels; the
    same ``seed`` gives the same photos.
    """
    picture = render_board(spec, 60)
    renderer = BoardPhotoRenderer(picture, K, dist, image_size_px)
    rng = np.random.default_rng(seed)
    sharp = []
    for index, (rvec, tvec) in enumerate(
        random_board_poses(picture, K, dist, image_size_px, count, rng, fill_range=fill_range)
    ):
        path = Path(folder) / f"view{index:02d}.png"
        cv2.imwrite(str(path), renderer.render(rvec, tvec, rng=rng))
        sharp.append(path)
    blurred, bent = Path(folder) / "blurred.png", Path(folder) / "bent.png"
    cv2.imwrite(str(blurred), cv2.GaussianBlur(cv2.imread(str(sharp[0]), cv2.IMREAD_GRAYSCALE), (0, 0), 2.5))
    cv2.imwrite(str(bent), bend_photo(cv2.imread(str(sharp[1]), cv2.IMREAD_GRAYSCALE)))
    return BoardPhotoSet(spec, sharp, blurred, bent)
