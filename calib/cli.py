"""The ``calib`` command: calibrate a phone camera, undistort photos, extract silhouettes.

Units: board sizes in millimetres, image measurements in pixels. Bad input ends with one
line ``calib: error: ...`` on stderr and exit code 2; outputs are written atomically, so
a failed command leaves no half-written file.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

import cv2
import numpy as np

from bodyfit.calib.boards import BoardDetector, BoardSpec, parse_board, render_board
from bodyfit.calib.camera import load_camera
from bodyfit.calib.camera_capture import capture_camera
from bodyfit.calib.capture import (DISTORTION_MODELS, INTRINSIC_NAMES, CaptureSettings,
                                   describe_views)
from bodyfit.calib.check import CheckedView, check_calibration, rms_px
from bodyfit.calib.images import encode_image, read_photo, to_upright, write_image
from bodyfit.calib.segmenters import SEGMENTER_HELP, SEGMENTERS
from bodyfit.calib.silhouette import SilhouetteSettings, photo_silhouette
from bodyfit.calib.undistort import undistort_image
from bodyfit.common.command_line import OneLineArgumentParser, bodyfit_version
from bodyfit.common.errors import UserError
from bodyfit.common.files import check_writable_dir, write_atomic

__all__ = ["main"]

_DEFAULTS = CaptureSettings()


def _add_board_arguments(parser: argparse.ArgumentParser, required: bool) -> None:
    parser.add_argument(
        "--board",
        required=required,
        metavar="KIND:COLSxROWS",
        help="chessboard:COLSxROWS counts inner corners (e.g. chessboard:9x6); "
        "charuco:COLSxROWS counts squares (e.g. charuco:11x8)",
    )
    parser.add_argument("--square-mm", type=float, metavar="MM", help="side of one square as printed, millimetres")
    parser.add_argument("--marker-mm", type=float, metavar="MM", help="charuco only: side of one marker, millimetres")
    parser.add_argument(
        "--dict", dest="dictionary", metavar="NAME", help="charuco only: ArUco dictionary, e.g. DICT_5X5_100"
    )


def _board(args: argparse.Namespace) -> BoardSpec:
    if args.square_mm is None:
        raise UserError("--board needs --square-mm (the printed square's side in millimetres)")
    return parse_board(args.board, args.square_mm, args.marker_mm, args.dictionary)


def _build_parser() -> argparse.ArgumentParser:
    parser = OneLineArgumentParser(
        prog="calib",
        description="Calibrate a phone camera, undistort photos, extract silhouettes. "
        "Board sizes in millimetres, image measures in pixels.",
    )
    parser.add_argument("--version", action="version", version=f"bodyfit {bodyfit_version()}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log every step to stderr")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    capture = commands.add_parser(
        "capture",
        help="calibrate a camera from board photos and/or videos",
        description="Calibrate a camera from photos and/or videos of a printed board; writes camera.json "
        "and a coverage picture. Board sizes in millimetres, errors in pixels.",
    )
    capture.add_argument("inputs", nargs="+", metavar="INPUT", help="board photos and/or videos (.mp4, .mov, ...)")
    _add_board_arguments(capture, required=True)
    capture.add_argument("-o", "--output", required=True, metavar="camera.json", help="camera file to write")
    capture.add_argument("--coverage", metavar="PNG", help="coverage picture (default: <output stem>_coverage.png)")
    capture.add_argument(
        "--model",
        choices=list(DISTORTION_MODELS),
        default=_DEFAULTS.model,
        help=f"distortion coefficients to estimate (default {_DEFAULTS.model}: radial k1, k2, as in the paper)",
    )
    capture.add_argument(
        "--max-blur-px",
        type=float,
        default=_DEFAULTS.max_edge_rise_px,
        metavar="PX",
        help="reject views whose board edges take more than PX pixels to rise from 10%% to 90%% "
        f"(default {_DEFAULTS.max_edge_rise_px})",
    )
    capture.add_argument(
        "--min-views",
        type=int,
        default=_DEFAULTS.min_views,
        metavar="N",
        help=f"fewest usable views to accept (default {_DEFAULTS.min_views}; 10-20 make a good calibration)",
    )
    capture.add_argument(
        "--video-frames",
        type=int,
        default=_DEFAULTS.video_max_frames,
        metavar="N",
        help="frames to sample from each video, the sharpest of N equal stretches "
        f"(default {_DEFAULTS.video_max_frames})",
    )

    check = commands.add_parser(
        "check",
        help="reprojection error of a calibration on held-out board photos",
        description="Reprojection error (pixels) of camera.json on board photos it was not solved from; "
        "photos it was solved from (recognised by content) are reported apart. "
        "Uses the board recorded in camera.json unless --board is given.",
    )
    check.add_argument("camera", metavar="camera.json")
    check.add_argument("inputs", nargs="+", metavar="IMAGE", help="held-out board photos and/or videos")
    _add_board_arguments(check, required=False)

    undistort = commands.add_parser(
        "undistort",
        help="remove lens distortion from photos",
        description="Undistort photos with camera.json (kornia); writes upright images of the same name into DIR.",
    )
    undistort.add_argument("camera", metavar="camera.json")
    undistort.add_argument("inputs", nargs="+", metavar="IMAGE")
    undistort.add_argument("-o", "--output-dir", required=True, metavar="DIR", help="folder for the undistorted photos")

    silhouette = commands.add_parser(
        "silhouette",
        help="the person's mask in a photo",
        description="Extract the person's silhouette from a photo (on a plain backdrop, or in a room "
        "through the learned segmentation); writes a black/white PNG of the undistorted (with --camera), "
        "upright photo.",
    )
    silhouette.add_argument("photo", metavar="PHOTO")
    silhouette.add_argument("--camera", metavar="camera.json", help="undistort the silhouette with this camera")
    silhouette.add_argument("--background", metavar="PLATE", help="background plate: the same view without the person")
    silhouette.add_argument("-o", "--output", required=True, metavar="mask.png")
    silhouette.add_argument("--segmenter", choices=SEGMENTERS, default="auto", help=SEGMENTER_HELP)

    board = commands.add_parser(
        "board",
        help="draw a board to print",
        description="Draw a calibration board as a PNG. Print it at 100%% scale at --dpi, glue it flat, "
        "and measure a square: pass the measured side as --square-mm.",
    )
    _add_board_arguments(board, required=True)
    board.add_argument("--dpi", type=float, default=300.0, help="print resolution, dots per inch (default 300)")
    board.add_argument("-o", "--output", required=True, metavar="board.png")
    return parser


def _capture(args: argparse.Namespace, argv: list[str]) -> None:
    spec = _board(args)
    settings = CaptureSettings(
        model=args.model,
        max_edge_rise_px=args.max_blur_px,
        min_views=args.min_views,
        video_max_frames=args.video_frames,
    )
    output = Path(args.output)
    coverage_path = Path(args.coverage) if args.coverage else output.with_name(f"{output.stem}_coverage.png")
    calibration, covered = capture_camera(list(args.inputs), spec, settings, output, coverage_path, argv)
    width, height = calibration.camera.image_size_px
    print(f"board: {spec.describe()}; images {width}x{height} px")
    for view in calibration.views:
        detail = view.status.value
        if view.error_px is not None:
            detail += f"  error {view.error_px:.3f} px"
        if view.edge_rise_px is not None:
            detail += f"  edge rise {view.edge_rise_px:.1f} px"
        print(f"  {view.name}: {detail}")
    worst = calibration.worst_view
    print(f"views: {describe_views(calibration.views)}")
    print(f"RMS reprojection error {calibration.rms_px:.3f} px; worst view {worst.name} {worst.error_px:.3f} px")
    print(f"coverage: corners in {covered:.0%} of the frame's grid cells (see {coverage_path})")
    print(f"intrinsics, model {settings.model} (value ± standard deviation):")
    K, dist = calibration.camera.K, calibration.camera.dist
    values = dict(zip(INTRINSIC_NAMES, (K[0, 0], K[1, 1], K[0, 2], K[1, 2], *dist)))
    for name, std in calibration.std.items():
        unit = " px" if name in ("fx", "fy", "cx", "cy") else ""
        digits = 2 if unit else 4
        print(f"  {name} = {values[name]:.{digits}f} ± {std:.{digits}f}{unit}")
    print(f"wrote {output}")
    print(f"wrote {coverage_path}")


def _check(args: argparse.Namespace) -> None:
    camera = load_camera(args.camera)
    if args.board is not None:
        spec = _board(args)
    elif camera.board is not None:
        spec = camera.board
    else:
        raise UserError(f"{args.camera} records no board; give --board and --square-mm")
    views = check_calibration(camera, args.inputs, BoardDetector(spec))
    for view in views:
        seen = ", calibrated on it" if view.calibrated_on else ""
        if view.error_px is not None:
            print(f"  {view.name}: error {view.error_px:.3f} px ({view.corners} corners){seen}")
        else:
            print(f"  {view.name}: {'no board' if view.corners == 0 else 'pose not found'}{seen}")
    held_out = [view for view in views if not view.calibrated_on]
    calibrated_on = [view for view in views if view.calibrated_on]
    if held_out:
        print(f"held-out RMS reprojection error {_group_error(held_out)}")
    if calibrated_on:
        print(
            f"RMS reprojection error on {len(calibrated_on)} photo{'s' if len(calibrated_on) != 1 else ''} "
            "the camera was calibrated on "
            f"(not held out): {_group_error(calibrated_on)}"
        )
    if camera.rms_px is not None:
        print(f"calibration RMS reprojection error {camera.rms_px:.3f} px")


def _group_error(views: list[CheckedView]) -> str:
    """``0.045 px over 3 of 4 views``, or ``not measured: no board found in 4 views``."""
    rms = rms_px(views)
    if rms is None:
        return f"not measured: no board found in {len(views)} views"
    found = sum(view.error_px is not None for view in views)
    return f"{rms:.3f} px over {found} of {len(views)} views"


def _undistort(args: argparse.Namespace) -> None:
    camera = load_camera(args.camera)
    folder = check_writable_dir(args.output_dir)
    targets = [folder / Path(path).name for path in args.inputs]
    if len(set(targets)) < len(targets):
        raise UserError("two inputs share a file name; they would overwrite each other in the output folder")
    for path, target in zip(args.inputs, targets):
        if target.exists() and target.resolve() == Path(path).resolve():
            raise UserError(f"{path} would be overwritten; choose another output folder")
    # Undistort everything before writing anything: a bad input fails the whole command cleanly.
    payloads = []
    for path, target in zip(args.inputs, targets):
        photo = read_photo(path)
        undistorted = to_upright(undistort_image(photo.pixels, camera, path), photo.orientation)
        payloads.append((target, encode_image(undistorted, target.suffix)))
    for target, payload in payloads:
        write_atomic(target, payload)
        print(f"wrote {target}")


def _silhouette(args: argparse.Namespace) -> None:
    output = Path(args.output)
    check_writable_dir(output.parent)
    camera = load_camera(args.camera) if args.camera else None
    mask = photo_silhouette(args.photo, camera, args.background, SilhouetteSettings(),
                            args.segmenter)
    rows = np.flatnonzero(mask.any(axis=1))
    write_image(output, mask.astype(np.uint8) * 255)
    print(
        f"silhouette: {int(mask.sum())} pixels, {rows[-1] - rows[0] + 1} px tall, in a "
        f"{mask.shape[1]}x{mask.shape[0]} image{' (undistorted)' if camera else ''}"
    )
    print(f"wrote {output}")


def _draw_board(args: argparse.Namespace) -> None:
    spec = _board(args)
    if not args.dpi > 0:
        raise UserError(f"--dpi must be positive, got {args.dpi}")
    pixels_per_square = round(spec.square_mm / 25.4 * args.dpi)
    picture = render_board(spec, pixels_per_square)
    write_image(args.output, picture.image)
    height, width = picture.image.shape
    print(
        f"{spec.describe()}: {width}x{height} px; printed at {args.dpi:g} dpi and 100 % scale it is "
        f"{width / args.dpi * 25.4:.0f} x {height / args.dpi * 25.4:.0f} mm with "
        f"{pixels_per_square / args.dpi * 25.4:.2f} mm squares"
    )
    print(f"wrote {args.output}")


def main(argv: list[str] | None = None) -> int:
    """Run ``calib`` with ``argv`` (default: the process's arguments); returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args = _build_parser().parse_args(argv)
    except SystemExit as stop:  # --help, --version, usage errors: argparse has printed its message
        return int(stop.code or 0)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, format="%(name)s: %(message)s")
    # OpenCV logs decoder complaints (a corrupt TIFF, ...) on stderr; the one-line error says it.
    cv2.utils.logging.setLogLevel(
        cv2.utils.logging.LOG_LEVEL_INFO if args.verbose else cv2.utils.logging.LOG_LEVEL_SILENT
    )
    try:
        if args.command == "capture":
            _capture(args, ["calib", *argv])
        elif args.command == "check":
            _check(args)
        elif args.command == "undistort":
            _undistort(args)
        elif args.command == "silhouette":
            _silhouette(args)
        else:
            _draw_board(args)
    except UserError as error:
        print(f"calib: error: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
