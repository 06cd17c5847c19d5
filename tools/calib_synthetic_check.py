"""Calibrate from synthetic board photos and compare with the camera that took them.

Renders chessboard and ChArUco photos through a known phone-like camera with real
radial distortion (bodyfit.calib.synthetic), adds one blurred and one warped (bent
board) photo to each set, runs the real `calib capture` command on them, and prints a
Markdown table of true vs recovered parameters with the reported standard deviations,
the rejected views, and the wall time. Usage:

    python tools/calib_synthetic_check.py [--views 15] [--size 1920x1080] [--seed 7]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from bodyfit.calib.boards import parse_board
from bodyfit.calib.cli import main as calib
from bodyfit.calib.synthetic import write_board_photos

BOARDS = {
    "chessboard": (parse_board("chessboard:9x6", 25.0), ["--board", "chessboard:9x6", "--square-mm", "25"]),
    "charuco": (
        parse_board("charuco:11x8", 20.0, 15.0, "DICT_5X5_100"),
        ["--board", "charuco:11x8", "--square-mm", "20", "--marker-mm", "15", "--dict", "DICT_5X5_100"],
    ),
}


def true_camera(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """A phone-like camera: 66 degrees across, principal point off centre, fx != fy, k1 k2 radial."""
    fx = 0.77 * width
    K = np.array([[fx, 0.0, 0.503 * width + 0.3], [0.0, 0.996 * fx, 0.491 * height - 0.2], [0.0, 0.0, 1.0]])
    return K, np.array([-0.11, 0.21, 0.0, 0.0, 0.0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--views", type=int, default=15, help="sharp views per board (default 15)")
    parser.add_argument("--size", default="1920x1080", help="photo size WIDTHxHEIGHT, pixels (default 1920x1080)")
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.lower().split("x"))
    K, dist = true_camera(width, height)
    truth = {"fx": K[0, 0], "fy": K[1, 1], "cx": K[0, 2], "cy": K[1, 2], "k1": dist[0], "k2": dist[1]}

    print(f"{args.views} sharp + 1 blurred + 1 bent-board photos per board, {width}x{height} px, seed {args.seed}\n")
    print("| board | parameter | true | recovered | std | error / std | error % |")
    print("|---|---|---|---|---|---|---|")
    summaries = []
    for name, (spec, board_args) in BOARDS.items():
        with tempfile.TemporaryDirectory() as folder:
            folder = Path(folder)
            start = time.perf_counter()
            photos = write_board_photos(folder, spec, K, dist, (width, height), args.views, args.seed)
            render_s = time.perf_counter() - start
            paths = [str(path) for path in (*photos.sharp, photos.blurred, photos.bent)]
            output = folder / "camera.json"
            start = time.perf_counter()
            with contextlib.redirect_stdout(io.StringIO()):  # keep the command's summary out of the table
                code = calib(["capture", *paths, *board_args, "-o", str(output)])
            capture_s = time.perf_counter() - start
            if code != 0:
                raise SystemExit(f"calib capture failed on the {name} photos")
            record = json.loads(output.read_text())
        recovered = dict(
            zip(("fx", "fy", "cx", "cy"), (record["K"][0][0], record["K"][1][1], record["K"][0][2], record["K"][1][2]))
        )
        recovered.update(k1=record["dist"][0], k2=record["dist"][1])
        for parameter, true_value in truth.items():
            estimate, std = recovered[parameter], record["std"][parameter]
            error = estimate - true_value
            digits = 2 if parameter in ("fx", "fy", "cx", "cy") else 4
            print(
                f"| {name} | {parameter} | {true_value:.{digits}f} | {estimate:.{digits}f} | {std:.{digits}f} | "
                f"{error / std:+.2f} | {100 * error / abs(true_value):+.3f} |"
            )
        rejected = {
            view["name"].rsplit("/", 1)[-1]: view["status"] for view in record["views"] if view["status"] != "used"
        }
        summaries.append(
            f"- {name}: RMS {record['rms_px']:.3f} px, rejected {rejected}, coverage "
            f"{record['coverage_fraction']:.0%}; rendering {render_s:.1f} s, `calib capture` {capture_s:.1f} s "
            f"({len(paths)} photos)"
        )
    print()
    print("\n".join(summaries))


if __name__ == "__main__":
    main()
