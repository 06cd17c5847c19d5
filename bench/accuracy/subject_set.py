"""A set of benchmark subjects on disk, as a user would have them for ``fitter batch``.

Layout of a set's folder::

    set.json        what was drawn: kind, count, seed, the camera, the photo effects
    bodies.npz      the rest bodies (vertices as int16 offsets from the model's mean,
                    0.02 mm steps; joints; sex; poses; standing: Anny parameters and
                    stances) - the truth's meshes
    board/          chessboard photos of the same camera (calib capture's input)
    subjects.csv    fitter batch's table: id, front, side, height_cm, sex (and camera
                    when some subjects have none: camera.json or empty)
    <id>/           front.jpg, side.jpg, truth.json (16 measurements, mm; stature; sex;
                    the cameras' distance, height and pitch; standing: the stance, the
                    side photo's side, calibrated or EXIF)

The ``standing`` kind photographs each view from its own hand-held place (distance,
height, pitch; redrawn until the person is in the frame), and ``exif_share`` of its
subjects with no calibration: the phone's own JPEG (no lens distortion left: phones
correct it) with its focal length in EXIF (``FocalLength`` and
``FocalLengthIn35mmFilm``, the latter by the diagonal, rounded to a millimetre as phones
write it), their subjects.csv camera cell empty; the others name the set's camera.json,
which the benchmark's ``fit`` calibrates from board/.

:func:`write_bodies` draws and stores the bodies (out-of-space needs Anny);
:func:`write_photos_of_set` photographs them, skipping subjects done already (a subject
is done when its truth.json exists), so a set can be made in steps and resumed.
"""

from __future__ import annotations

import csv
import dataclasses
import functools
import io
import json
from pathlib import Path

import numpy as np

from bench.accuracy.bodies import Bodies, draw_bodies, pose_bodies
from bench.accuracy.photos import PhotoEffects, Shot, exif_focal, write_photos
from bench.accuracy.rooms import draw_scene
from bench.accuracy.stances import StanceSettings, posed_bodies
from bodyfit.calib.boards import parse_board
from bodyfit.calib.camera import Camera, camera_fields
from bodyfit.calib.synthetic import write_board_photos
from bodyfit.common.files import write_atomic
from bodyfit.fitter.demo.example import demo_camera
from bodyfit.fitter.fit.pinhole_canvas import Placement
from bodyfit.fitter.measure.measurements import MEASUREMENTS, Measurer
from bodyfit.fitter.model_build.body_sample import ANNY_GENDER
from bodyfit.fitter.model.body_model import BodyModel
from bodyfit.fitter.output.render import pinhole_pixels
from bodyfit.fitter.output.result_files import write_json

__all__ = ["SetSettings", "BOARD", "SQUARE_MM", "CAMERA_FILE", "write_bodies", "read_bodies",
           "write_photos_of_set", "subject_ids", "read_truth"]

#: The printed board of every set (``calib capture --board``, ``--square-mm``).
BOARD, SQUARE_MM = "chessboard:9x6", 25.0
#: The set's calibrated camera (``fit`` writes it with ``calib capture`` on board/).
CAMERA_FILE = "camera.json"
_STEP_M = 2e-5  # bodies.npz: vertex offsets from the mean body in 0.02 mm steps


@dataclasses.dataclass(frozen=True)
class SetSettings:
    """What a set is drawn with (recorded in set.json).

    Attributes:
        kind: ``"in-space"``, ``"out-of-space"`` or ``"standing"`` (:mod:`.bodies`).
        count: subjects, even (half women, half men).
        seed: draws bodies, poses, camera places, light and noise.
        size_px: (width, height) of the photos; the camera is ``fitter demo``'s phone
            (:func:`bodyfit.fitter.demo.example.demo_camera`: 66 degrees across, k1 -0.11, k2 0.21).
        distance_m, camera_height_m: ranges of the camera's place for each subject.
        board_views: sharp board photos (one blurred and one of a bent board besides).
        pool_per_sex: Anny's kinds only (:func:`.bodies.draw_bodies`).
        effects: :class:`~.photos.PhotoEffects`.
        pitch_deg: each photo's camera pitched by up to this (standing only).
        exif_share: standing only: the share of subjects photographed without calibration
            (module docstring).
        stance: standing only: the poses' ranges.
        rooms: the subjects dressed and photographed in rooms (:mod:`.rooms`), the bodies
            and camera places those of the plain set of the same kind, count and seed.
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
    pitch_deg: float = 0.0
    exif_share: float = 0.0
    stance: StanceSettings = StanceSettings()
    rooms: bool = False

    @property
    def per_row_camera(self) -> bool:
        """subjects.csv names each subject's camera (some have none: ``exif_share``)."""
        return self.exif_share > 0

    @classmethod
    def standing(cls, count: int, seed: int, **overrides) -> "SetSettings":
        """The ``standing`` set's protocol (issue 58): cameras 2-4 m away, 0.8-1.6 m high,
        pitched up to 5 degrees, half the subjects with EXIF and no calibration."""
        return cls(kind="standing", count=count, seed=seed, distance_m=(2.0, 4.0),
                   camera_height_m=(0.8, 1.6), pitch_deg=5.0, exif_share=0.5, **overrides)

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
                         pool_per_sex=settings.pool_per_sex, stance=settings.stance,
                         progress=progress)
    offsets = np.rint((bodies.vertices - model.mean_vertices) / _STEP_M)
    if np.abs(offsets).max() > np.iinfo(np.int16).max:
        raise ValueError("a body lies more than 0.65 m from the mean body")
    buffer = io.BytesIO()
    np.savez_compressed(buffer, offsets=offsets.astype(np.int16), joints=bodies.joints,
                        sex=bodies.sex, hard=bodies.hard, abduction_deg=bodies.abduction_deg,
                        flexion_deg=bodies.flexion_deg, anny_params=bodies.anny_params,
                        **{f"stance_{name}": value for name, value in bodies.stances.items()})
    write_atomic(folder / "bodies.npz", buffer.getvalue())
    write_json(folder / "set.json", {"settings": dataclasses.asdict(settings),
                                     "camera": camera_fields(settings.camera)})
    return read_bodies(model, folder)


def read_bodies(model: BodyModel, folder: Path) -> Bodies:
    """The bodies :func:`write_bodies` stored in ``folder``."""
    with np.load(Path(folder) / "bodies.npz") as npz:
        vertices = (model.mean_vertices + npz["offsets"] * np.float32(_STEP_M)).astype(np.float32)
        count = len(vertices)
        params = npz["anny_params"] if "anny_params" in npz else np.zeros((count, 0))
        stances = {name.removeprefix("stance_"): npz[name] for name in npz.files
                   if name.startswith("stance_")}
        return Bodies(npz["sex"], npz["hard"], vertices, npz["joints"], npz["abduction_deg"],
                      npz["flexion_deg"], params, stances)


def read_settings(folder: Path) -> SetSettings:
    """The settings of the set in ``folder`` (its set.json)."""
    recorded = json.loads((Path(folder) / "set.json").read_text())["settings"]
    recorded["effects"] = PhotoEffects(**recorded["effects"])
    if "stance" in recorded:
        recorded["stance"] = StanceSettings(**{
            name: tuple(value) if isinstance(value, list) else value
            for name, value in recorded["stance"].items()})
    for name in ("size_px", "distance_m", "camera_height_m"):
        recorded[name] = tuple(recorded[name])
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
    per_row_camera = settings.per_row_camera
    writer.writerow(["id", "front", "side", "height_cm", "sex"]
                    + (["camera"] if per_row_camera else []))
    for subject, sex in zip(ids, bodies.sex):
        if (folder / subject / "truth.json").exists():
            record = json.loads((folder / subject / "truth.json").read_text())
            calibrated = record.get("standing", {}).get("camera") == "calibrated"
            writer.writerow([subject, f"{subject}/front.jpg", f"{subject}/side.jpg",
                             f"{record['measurements']['O'] / 10:.2f}", sex]
                            + ([CAMERA_FILE if calibrated else ""] if per_row_camera else []))
    write_atomic(folder / "subjects.csv", table.getvalue().encode())
    return folder / "subjects.csv"


def _write_subject(out: Path, model: BodyModel, bodies: Bodies, index: int,
                   settings: SetSettings, measurer: Measurer) -> None:
    rng = np.random.default_rng([settings.seed, index, 7])
    out.mkdir(parents=True, exist_ok=True)
    record = {"sex": str(bodies.sex[index]), "hard": bool(bodies.hard[index])}
    if settings.kind == "standing":
        camera, exif, posed, shots, record["standing"] = _standing_photos(
            model, bodies, index, settings, rng)
    else:
        shot = Shot(rng.uniform(*settings.distance_m), rng.uniform(*settings.camera_height_m))
        camera, exif, shots = settings.camera, b"", {"front": shot, "side": shot}
        posed = dict(zip(("front", "side"), pose_bodies(model, bodies, index)))
        record |= {"camera_distance_m": round(shot.distance_m, 4),
                   "camera_height_m": round(shot.camera_height_m, 4)}
    scene = draw_scene(np.random.default_rng([settings.seed, index, 11])) if settings.rooms \
        else None
    write_photos(out, model, posed, camera, shots, settings.effects, rng, exif, scene)
    truth = measurer.measure(bodies.vertices[index])
    write_json(out / "truth.json", {
        "units": "mm",
        "measurements": {key: round(float(truth[key]), 3) for key in MEASUREMENTS}} | record)


@functools.cache
def _anny():
    """Anny's skeleton source, loaded once per process (standing sets only)."""
    from bodyfit.fitter.model_build.anny_source import AnnySource
    source = AnnySource()
    return source, source.skeleton()


def _standing_photos(model: BodyModel, bodies: Bodies, index: int, settings: SetSettings,
                     rng: np.random.Generator):
    """(camera, EXIF block, posed bodies, shots, what truth.json records) of a
    ``standing`` subject: posed by Anny's skeleton (:mod:`.stances`), each view from its
    own hand-held place, with or without calibration (module docstring)."""
    source, skeleton = _anny()
    gender = np.array([ANNY_GENDER[bodies.sex[index]]])
    rest, heads = source.rest_bodies(gender, bodies.anny_params[index][None], all_bones=True)
    if np.abs(rest[0] - bodies.vertices[index]).max() > 1e-4:
        raise ValueError("bodies.npz's Anny parameters do not make its bodies: another "
                         "Anny version? Draw the set again")
    stance = {name: value[index] for name, value in bodies.stances.items()}
    front, side = posed_bodies(skeleton, rest[0].astype(float), heads[0].astype(float), stance)
    exif = rng.random() < settings.exif_share
    camera = settings.camera
    if exif:  # the phone's own JPEG: its lens corrected in the phone
        camera = Camera(camera.image_size_px, camera.K, np.zeros(5))
    posed = {"front": front, "side": side}
    shots = {view: _framing_shot(vertices, view, camera, settings, rng)
             for view, vertices in posed.items()}
    record = {"camera": "exif" if exif else "calibrated",
              "side_from": "right" if stance["side_from_right"] else "left",
              "shots": {view: {key: round(value, 4) for key, value in
                               dataclasses.asdict(shot).items()}
                        for view, shot in shots.items()},
              "stance": {name: np.round(value, 3).tolist() for name, value in stance.items()}}
    return camera, exif_focal(camera) if exif else b"", posed, shots, record


def _framing_shot(vertices: np.ndarray, view: str, camera: Camera, settings: SetSettings,
                  rng: np.random.Generator, margin: float = 0.03) -> Shot:
    """A random hand-held place (``settings``' ranges) from which the whole body
    (V, 3) metres lies inside the photo, ``margin`` of its height from every edge, as a
    user frames a photo; ValueError after 50 tries."""
    width, height = camera.image_size_px
    edge = margin * height
    floor = float(vertices[:, 2].min())
    for _ in range(50):
        shot = Shot(rng.uniform(*settings.distance_m), rng.uniform(*settings.camera_height_m),
                    rng.uniform(-settings.pitch_deg, settings.pitch_deg))
        placement = Placement(shot.distance_m, shot.camera_height_m, 0.0, -floor,
                              shot.pitch_deg)
        px, _ = pinhole_pixels(vertices.astype(float), camera.K, *placement.extrinsics(view))
        if (px.min() >= edge and px[:, 0].max() <= width - 1 - edge
                and px[:, 1].max() <= height - 1 - edge):
            return shot
    raise ValueError(f"no camera place of the set's ranges frames the {view} photo's body")


def read_truth(subject_folder: Path) -> dict[str, float]:
    """key ("A".."P") -> true measurement, mm, of a subject's truth.json."""
    return json.loads((Path(subject_folder) / "truth.json").read_text())["measurements"]
