"""`fitter demo`: the main job on a synthetic person, measured against the truth.

One synthetic phone camera (:func:`demo_camera`: a pinhole with radial distortion k1, k2)
photographs a body drawn from the model's space, front (A-pose) and side (arms hanging
down), 2.5-3.5 m away (:func:`bodyfit.fitter.demo.studio_photos.write_pinhole_photos`, a
painter's renderer, not the kernels), and a printed chessboard from varied angles
(:func:`bodyfit.calib.synthetic.write_board_photos`). The demo then does what a user
does: calibrates the camera from the board photos as ``calib capture`` does
(:func:`calibrate_scene`) and fits the person with ``fitter run --camera camera.json``
(the command line builds that run, ``fitter/cli/main.py``); :func:`measurement_table` sets the
fitted measurements against the true ones.

Files in the demo's folder: ``front.png``, ``side.png`` (the person), ``board/`` (the
board photos: ``view00.png`` ..., one too blurry, ``blurred.png``, and one of a bent
board, ``bent.png``), ``camera.json`` and ``camera_coverage.png`` (the calibration),
``truth.json`` (the true measurements, mm, the body, the true camera and where it
stood), and the fit's folder ``fit/``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from bodyfit.calib.boards import parse_board
from bodyfit.calib.camera import Camera, camera_fields
from bodyfit.calib.camera_capture import capture_camera
from bodyfit.calib.capture import Calibration, CaptureSettings
from bodyfit.calib.synthetic import write_board_photos
from bodyfit.common.files import check_writable_dir
from bodyfit.fitter.demo.studio_photos import write_pinhole_photos
from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS
from bodyfit.fitter.model.body_model import POSE_NAMES, BodyModel
from bodyfit.fitter.output.result_files import write_json

__all__ = ["DemoScene", "DemoSettings", "calibrate_scene", "demo_camera", "measurement_table",
           "write_scene"]


@dataclasses.dataclass(frozen=True)
class DemoSettings:
    """The synthetic scene.

    Attributes:
        seed: draws the body, the camera's place and the board poses.
        size_px: (width, height) of every photo, pixels (portrait).
        board: the printed board, ``calib``'s ``--board`` form; square_mm its square's side.
        board_views: sharp board photos (besides one blurred and one of a bent board).
        components: shape components drawn, as the fit searches them.
        beta_limit_sigma: every |beta| clipped here.
        pose_deg: range of the four abduction angles of the front photo, degrees.
        distance_m: range of the camera's distance from the person, metres.
        camera_height_m: range of the camera's height above the floor, metres.
    """

    seed: int = 0
    size_px: tuple[int, int] = (900, 1200)
    board: str = "chessboard:9x6"
    square_mm: float = 25.0
    board_views: int = 12
    components: int = 20
    beta_limit_sigma: float = 2.0
    pose_deg: tuple[float, float] = (2.0, 8.0)
    distance_m: tuple[float, float] = (2.5, 3.5)
    camera_height_m: tuple[float, float] = (1.0, 1.3)


def demo_camera(size_px: tuple[int, int]) -> Camera:
    """A phone's main camera for photos of ``size_px`` (width, height): 66 degrees across
    the long side (28 mm equivalent), square pixels, principal point 6 px right of and
    9 px above the centre, radial distortion k1 = -0.11, k2 = 0.21 (a phone lens's)."""
    width, height = size_px
    focal = max(size_px) / 2 / np.tan(np.deg2rad(66.0) / 2)
    K = np.array([[focal, 0.0, (width - 1) / 2 + 6.0], [0.0, focal, (height - 1) / 2 - 9.0],
                  [0.0, 0.0, 1.0]])
    return Camera(tuple(size_px), K, np.array([-0.11, 0.21, 0.0, 0.0, 0.0]))


@dataclasses.dataclass(frozen=True)
class DemoScene:
    """What :func:`write_scene` wrote.

    Attributes:
        folder: the demo's folder.
        settings: the scene's settings.
        camera: the true camera.
        truth: key ("A".."P") -> the body's true measurement, mm.
        front, side: the person's photos.
        board_photos: every board photo, sharp ones first.
        truth_file: truth.json.
    """

    folder: Path
    settings: DemoSettings
    camera: Camera
    truth: dict[str, float]
    front: Path
    side: Path
    board_photos: tuple[Path, ...]
    truth_file: Path


def write_scene(model: BodyModel, folder: Path, settings: DemoSettings = DemoSettings()
                ) -> DemoScene:
    """Draw a body and the camera's place from ``settings.seed``; write the person's
    photos, the board photos and truth.json into ``folder`` (created; files of an earlier
    demo there are replaced)."""
    folder = Path(folder)
    check_writable_dir(folder)
    (folder / "board").mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(settings.seed)
    betas = np.clip(rng.standard_normal(settings.components), -settings.beta_limit_sigma,
                    settings.beta_limit_sigma)
    pose_deg = rng.uniform(*settings.pose_deg, len(POSE_NAMES))
    distance_m = rng.uniform(*settings.distance_m)
    camera_height_m = rng.uniform(*settings.camera_height_m)
    camera = demo_camera(settings.size_px)
    truth = write_pinhole_photos(folder, model, betas, pose_deg, camera, distance_m,
                                 camera_height_m)
    board = parse_board(settings.board, settings.square_mm)
    photos = write_board_photos(folder / "board", board, camera.K, camera.dist,
                                camera.image_size_px, settings.board_views, settings.seed)
    write_json(folder / "truth.json", {
        "units": "mm",
        "measurements": {name: {"letter": key, "label": label, "value_mm": round(truth[key], 2)}
                         for key, (name, label) in MEASUREMENTS.items()},
        "body": {"betas_sigma": betas.round(4).tolist(),
                 "pose_deg": dict(zip(POSE_NAMES, pose_deg.round(2).tolist()))},
        "camera": camera_fields(camera),
        "camera_distance_m": round(distance_m, 3),
        "camera_height_m": round(camera_height_m, 3),
        "settings": dataclasses.asdict(settings),
    })
    return DemoScene(folder, settings, camera, truth, folder / "front.png", folder / "side.png",
                     (*photos.sharp, photos.blurred, photos.bent), folder / "truth.json")


def calibrate_scene(scene: DemoScene) -> tuple[Calibration, Path, Path]:
    """Calibrate the camera from the scene's board photos as ``calib capture`` does (its
    default settings); write camera.json and camera_coverage.png beside the photos.

    Returns:
        (the calibration, camera.json's path, the coverage picture's path).
    """
    settings = scene.settings
    output, coverage = scene.folder / "camera.json", scene.folder / "camera_coverage.png"
    inputs = [str(path) for path in scene.board_photos]
    argv = ["calib", "capture", *inputs, "--board", settings.board,
            "--square-mm", f"{settings.square_mm:g}", "-o", str(output)]
    calibration, _ = capture_camera(inputs, parse_board(settings.board, settings.square_mm),
                                    CaptureSettings(), output, coverage, argv)
    return calibration, output, coverage


def measurement_table(measured: dict[str, float], spreads: dict[str, float],
                      truth: dict[str, float]) -> list[str]:
    """Lines of the fitted against the true measurements (mm, key -> value): a header, one
    row per measurement (value, its ±, truth, error), and the mean absolute error of the
    paper's seven important ones (``IMPORTANT``)."""
    lines = [f"  {'measurement':<30} {'fitted':>8} {'±':>6} {'true':>8} {'error':>7}  (mm)"]
    for key, (_, label) in MEASUREMENTS.items():
        lines.append(f"  {key} {label:<28} {measured[key]:8.1f} {spreads[key]:6.1f} "
                     f"{truth[key]:8.1f} {measured[key] - truth[key]:+7.1f}")
    mae = np.mean([abs(measured[key] - truth[key]) for key in IMPORTANT])
    lines.append(f"  mean absolute error of the 7 important ({', '.join(IMPORTANT)}): "
                 f"{mae:.1f} mm")
    return lines
