"""Shared fixtures: board photos rendered through a known camera, and a CLI runner."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pytest
from bodyfit.calib.boards import BoardSpec, parse_board, render_board
from bodyfit.calib.cli import main
from bodyfit.calib.synthetic import BoardPhotoRenderer, bend_photo, random_board_poses

# A phone-like camera: 1280x720, about 63 degrees across, off-centre principal point,
# fx != fy, and the paper's radial model (k1, k2) with phone-like values.
TRUE_K = np.array([[1050.0, 0.0, 648.5], [0.0, 1046.0, 352.3], [0.0, 0.0, 1.0]])
TRUE_DIST = np.array([-0.11, 0.21, 0.0, 0.0, 0.0])
IMAGE_SIZE = (1280, 720)
VIEW_COUNT = 12


@dataclass(frozen=True)
class BoardShots:
    """Photos of one board through the true camera.

    Attributes:
        spec: the board.
        paths: the sharp photos (PNG, grey).
        blurred: a Gaussian-blurred copy of the first photo (sigma 2.5 px).
        warped: the second photo of a bent board (``bend_photo``): corners that fit no camera.
    """

    spec: BoardSpec
    paths: list[Path]
    blurred: Path
    warped: Path


def _shoot(folder: Path, spec: BoardSpec, seed: int) -> BoardShots:
    picture = render_board(spec, 60)
    renderer = BoardPhotoRenderer(picture, TRUE_K, TRUE_DIST, IMAGE_SIZE)
    rng = np.random.default_rng(seed)
    poses = random_board_poses(picture, TRUE_K, TRUE_DIST, IMAGE_SIZE, VIEW_COUNT, rng, fill_range=(0.3, 0.55))
    paths = []
    for index, (rvec, tvec) in enumerate(poses):
        path = folder / f"view{index:02d}.png"
        cv2.imwrite(str(path), renderer.render(rvec, tvec, rng=rng))
        paths.append(path)
    first = cv2.imread(str(paths[0]), cv2.IMREAD_GRAYSCALE)
    blurred = folder / "blurred.png"
    cv2.imwrite(str(blurred), cv2.GaussianBlur(first, (0, 0), 2.5))
    warped = folder / "warped.png"
    cv2.imwrite(str(warped), bend_photo(cv2.imread(str(paths[1]), cv2.IMREAD_GRAYSCALE)))
    return BoardShots(spec, paths, blurred, warped)


@pytest.fixture(scope="session")
def chessboard_shots(tmp_path_factory) -> BoardShots:
    return _shoot(tmp_path_factory.mktemp("chessboard"), parse_board("chessboard:9x6", 25.0), seed=1)


@pytest.fixture(scope="session")
def charuco_shots(tmp_path_factory) -> BoardShots:
    spec = parse_board("charuco:11x8", 20.0, 15.0, "DICT_5X5_100")
    return _shoot(tmp_path_factory.mktemp("charuco"), spec, seed=2)


@dataclass(frozen=True)
class CliResult:
    code: int
    stdout: str
    stderr: str


@pytest.fixture
def run_calib(capsys):
    """Run ``calib`` in-process: ``run_calib("capture", ...)`` -> CliResult."""

    def run(*argv: str | Path) -> CliResult:
        code = main([str(arg) for arg in argv])
        captured = capsys.readouterr()
        return CliResult(code, captured.out, captured.err)

    return run
