"""A set of benchmark subjects on disk, as a user would have them for ``fitter batch``.

Layout of a set's folder::

    set.json        what was drawn: kind, count, seed, the camera, the photo effects
    bodies.npz      the rest bodies (vertices as int16 offsets from the model's mean,
                    0.02 mm steps; joints; sex; poses) - the truth's meshes
    board/          chessboard photos of the same camera (calib capture's input)
    subjects.csv    fitter batch's table: id, front, side, height_cm, sex
    <id>/           front.jpg, side.jpg, truth.json (16 measurements, mm; stature; sex;
                    the camera's distance and height)

:func:`write_bodies` draws and stores the bodies (out-of-space needs Anny);
:func:`write_photos_of_set` photographs them, skipping subjects done already (a subject
is done when its truth.json exists), so a set can be made in steps and resumed.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
from pathlib import Path

import numpy as np

from bench.accuracy.bodies import Bodies, draw_bodies, pose_bodies
from bench.accuracy.photos import PhotoEffects, write_photos
from bodyfit.calib.boards import parse_board
from bodyfit.calib.camera import Camera, camera_fields
from bodyfit.calib.synthetic import write_board_photos
from bodyfit.common.files import write_atomic
from bodyfit.fitter.demo.example import demo_camera
from bodyfit.fitter.measure.measurements import MEASUREMENTS, Measurer
from bodyfit.fitter.model.body_model import BodyModel
from bodyfit.fitter.output.result_files import write_json

__all__ = ["SetSettings", "BOARD", "SQUARE_MM", "write_bodies", "read_bodies",
           "write_photos_of_set", "subject_ids", "read_truth"]

#: The printed board of every set (``calib capture --board``, ``--square-mm``).
BOARD, SQUARE_MM = "chessboard:9x6", 25.0
_STEP_M = 2e-5  # bodies.npz: vertex offsets from the mean body in 0.02 mm steps


@dataclasses.dataclass(frozen=True)
class SetSettings:
    """What a set is drawn with (recorded in set.json).

    Attributes:
        kind: ``"in-space"`` or ``"out-of-space"`` (:mod:`.bodies`).
        count: subjects, even (half women, half men).
        seed: draws bodies, poses, camera places, light and noise.
        size_px: (width, height) of the photos; the camera is ``fitter demo``'s phone
            (:func:`bodyfit.fitter.demo.example.demo_camera`: 66 degrees across, k1 -0.11, k2 0.21).
        distance_m, camera_height_m: ranges of the camera's place for each subject.
        board_views: sharp board photos (one blurred and one of a bent board besides).
        pool_per_sex: out-of-space only (:func:`.bodies.draw_bodies`).
        effects: :class:`~.photos.PhotoEffects`.
    """

    kind: str = "in-space"
    count: int = 200
    seed: int = 0
    size_px: tuple[int, int] = (1200, 1600)
    distance_m: tuple[float, float] = (2.5, 3.5)
    camera_height_m: tuple[float, float] = (1.0, 1.3)
    board_views: int = 12
    pool_per_sex: int = 400
    effects: PhotoEffects = PhotoEffects()

    @property
    def camera(self) -> Camera:
        return demo_camera(self.size_px)


def subject_ids(count: int, sex: np.ndarray) -> list[str]:
    """The subjects' ids: ``s0000-female`` ..."""
    return [f"s{i:04d}-{sex[i]}" for i in range(count)]


def write_bodies(model: BodyModel, folder: Path, settings: SetSettings,
                 progress=None) -> Bodies:
    """Draw the set's bodies and write set.json and bodies.npz into ``folder``."""
    folder = Path(folder)
    bodies = draw_bodies(model, settings.kind, settings.count, settings.seed,
                         pool_per_sex=settings.pool_per_sex, progress=progress)
    offsets = np.rint((bodies.vertices - model.mean_vertices) / _STEP_M)
    if np.abs(offsets).max() > np.iinfo(np.int16).max:
        raise ValueError("a body lies more than 0.65 m from the mean body")
    buffer = io.BytesIO()
    np.savez_compressed(buffer, offsets=offsets.astype(np.int16), joints=bodies.joints,
                        sex=bodies.sex, hard=bodies.hard, abduction_deg=bodies.abduction_deg,
                        flexion_deg=bodies.flexion_deg)
    write_atomic(folder / "bodies.npz", buffer.getvalue())
    write_json(folder / "set.json", {"settings": dataclasses.asdict(settings),
                                     "camera": camera_fields(settings.camera)})
    return read_bodies(model, folder)


def read_bodies(model: BodyModel, folder: Path) -> Bodies:
    """The bodies :func:`write_bodies` stored in ``folder``."""
    with np.load(Path(folder) / "bodies.npz") as npz:
        vertices = (model.mean_vertices + npz["offsets"] * np.float32(_STEP_M)).astype(np.float32)
        return Bodies(npz["sex"], npz["hard"], vertices, npz["joints"], npz["abduction_deg"],
                      npz["flexion_deg"])


def read_settings(folder: Path) -> SetSettings:
    """The settings of the set in ``folder`` (its set.json)."""
    recorded = json.loads((Path(folder) / "set.json").read_text())["settings"]
    recorded["effects"] = PhotoEffects(**recorded["effects"])
    recorded["size_px"] = tuple(recorded["size_px"])
    recorded["distance_m"] = tuple(recorded["distance_m"])
    recorded["camera_height_m"] = tuple(recorded["camera_height_m"])
    return SetSettings(**recorded)


def write_photos_of_set(model: BodyModel, folder: Path, subjects: list[int] | None = None,
                        progress=None) -> Path:
    """Photograph the set's bodies (all, or the indices ``subjects``) and its board, and
    write subjects.csv; subjects with a truth.json are skipped. Returns subjects.csv."""
    folder = Path(folder)
    settings = read_settings(folder)
    bodies = read_bodies(model, folder)
    camera = settings.camera
    if not (folder / "board").is_dir():
        board = folder / "board.partial"
        board.mkdir(exist_ok=True)
        write_board_photos(board, parse_board(BOARD, SQUARE_MM), camera.K, camera.dist,
                           camera.image_size_px, settings.board_views, settings.seed)
        board.rename(folder / "board")
    measurer = Measurer.from_model(model)
    ids = subject_ids(len(bodies.sex), bodies.sex)
    for index in range(len(ids)) if subjects is None else subjects:
        out = folder / ids[index]
        if not (out / "truth.json").exists():
            _write_subject(out, model, bodies, index, settings, measurer)
        if progress is not None:
            progress.update(1)
    table = io.StringIO()
    writer = csv.writer(table, lineterminator="\n")
    writer.writerow(["id", "front", "side", "height_cm", "sex"])
    for subject, sex in zip(ids, bodies.sex):
        if (folder / subject / "truth.json").exists():
            truth = read_truth(folder / subject)
            writer.writerow([subject, f"{subject}/front.jpg", f"{subject}/side.jpg",
                             f"{truth['O'] / 10:.2f}", sex])
    write_atomic(folder / "subjects.csv", table.getvalue().encode())
    return folder / "subjects.csv"


def _write_subject(out: Path, model: BodyModel, bodies: Bodies, index: int,
                   settings: SetSettings, measurer: Measurer) -> None:
    rng = np.random.default_rng([settings.seed, index, 7])
    distance = rng.uniform(*settings.distance_m)
    height = rng.uniform(*settings.camera_height_m)
    out.mkdir(parents=True, exist_ok=True)
    front, side = pose_bodies(model, bodies, index)
    write_photos(out, model, front, side, settings.camera, distance, height, settings.effects,
                 rng)
    truth = measurer.measure(bodies.vertices[index])
    write_json(out / "truth.json", {
        "units": "mm",
        "measurements": {key: round(float(truth[key]), 3) for key in MEASUREMENTS},
        "sex": str(bodies.sex[index]), "hard": bool(bodies.hard[index]),
        "camera_distance_m": round(distance, 4), "camera_height_m": round(height, 4)})


def read_truth(subject_folder: Path) -> dict[str, float]:
    """key ("A".."P") -> true measurement, mm, of a subject's truth.json."""
    return json.loads((Path(subject_folder) / "truth.json").read_text())["measurements"]
