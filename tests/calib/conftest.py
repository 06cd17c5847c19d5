"""Shared fixtures: board photos rendered through the true camera, and a CLI runner."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

from bodyfit.calib.boards import parse_board
from bodyfit.calib.cli import main
from bodyfit.calib.synthetic import BoardPhotoSet, write_board_photos

from calib_true_camera import IMAGE_SIZE, TRUE_DIST, TRUE_K

VIEW_COUNT = 12


@pytest.fixture(scope="session")
def chessboard_shots(tmp_path_factory) -> BoardPhotoSet:
    spec = parse_board("chessboard:9x6", 25.0)
    folder = tmp_path_factory.mktemp("chessboard")
    return write_board_photos(folder, spec, TRUE_K, TRUE_DIST, IMAGE_SIZE, VIEW_COUNT, seed=1, fill_range=(0.3, 0.55))


@pytest.fixture(scope="session")
def charuco_shots(tmp_path_factory) -> BoardPhotoSet:
    spec = parse_board("charuco:11x8", 20.0, 15.0, "DICT_5X5_100")
    folder = tmp_path_factory.mktemp("charuco")
    return write_board_photos(folder, spec, TRUE_K, TRUE_DIST, IMAGE_SIZE, VIEW_COUNT, seed=2, fill_range=(0.3, 0.55))


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
