"""The photography check: silhouette measures on a drawn mask, its verdicts on rendered
bodies posed wrong in each way it catches, on the real photos, and `fitter check`."""

import re
import tempfile
from pathlib import Path

import cv2
import numpy as np
import pytest

from bodyfit.calib.images import write_image
from bodyfit.calib.silhouette import photo_silhouette
from bodyfit.fitter.check.photos import check_view
from bodyfit.fitter.check.shape import silhouette_shape
from bodyfit.fitter.cli.main import main
from bodyfit.fitter.demo.studio_photos import BACKDROP_BGR, photo, write_subject
from bodyfit.fitter.model.body_model import PART_NAMES, forward

REAL = "tests/data/real-photos"
TRUE_BETAS = np.array([0.8, -0.6, 0.5, 0.3, -0.4] + [0.0] * 15)
TRUE_POSE = np.array([6.0, 6.0, 3.0, 3.0])


def test_shape_of_a_drawn_person():
    mask = np.zeros((200, 200), bool)
    mask[20:100, 80:120] = True   # head and torso: rows 20-99
    mask[100:180, 80:95] = True   # legs, 10 columns apart, to the soles at row 179
    mask[100:180, 105:120] = True
    mask[40:91, 60:70] = True     # arms, 10 columns clear of the torso
    mask[40:91, 130:140] = True
    shape = silhouette_shape(mask)
    assert (shape.height_px, shape.width_px) == (160, 80)
    np.testing.assert_allclose(shape.margins, np.array([20, 20, 60, 60]) / 160)
    assert shape.feet_gap == pytest.approx(10 / 160)
    assert shape.leg_split == pytest.approx(80 / 160)
    np.testing.assert_allclose(shape.arm_gaps, [10 / 160, 10 / 160])
    mask[160:180, 95:105] = True  # the ankles and feet together
    together = silhouette_shape(mask)
    assert (together.feet_gap, together.leg_split) == (0.0, 0.0)


def _body(model, pose=TRUE_POSE, turn_deg=0.0):
    vertices = forward(model, TRUE_BETAS[None], np.asarray(pose, float)[None])[0]
    turn = np.deg2rad(turn_deg)
    about_z = np.array([[np.cos(turn), -np.sin(turn), 0], [np.sin(turn), np.cos(turn), 0],
                        [0, 0, 1]])
    return vertices @ about_z.T


def _verdict(view, image):
    """The check of an image, on the silhouette `fitter run` takes of it."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "photo.png"
        write_image(path, image)
        return check_view(view, image, photo_silhouette(path))


def _padded(image, top=0, bottom=0):
    return cv2.copyMakeBorder(image, top, bottom, 0, 0, cv2.BORDER_CONSTANT, value=BACKDROP_BGR)


@pytest.fixture(scope="module")
def front(body_model):
    return photo(_body(body_model), body_model, "front", PART_NAMES)


@pytest.fixture(scope="module")
def side(body_model, tmp_path_factory):
    folder = tmp_path_factory.mktemp("subject")
    write_subject(folder, body_model, TRUE_BETAS, TRUE_POSE)
    return cv2.imread(str(folder / "side.png"))


def test_a_well_taken_pair_passes(front, side):
    for view, image in (("front", front), ("side", side)):
        verdict = _verdict(view, image)
        assert verdict.problems == () and verdict.warnings == (), verdict.summary()
    assert _verdict("front", front).readings["shoulders"] > 0.5


@pytest.mark.parametrize("wrong, message", [
    ("arms down", r"an arm is close to the body \(\d+ degrees out\); raise both arms"),
    ("feet together", "the feet are together; stand with them apart"),
    ("a hand raised", "a hand is raised above the shoulders"),
    ("turned away", "the person is turned from the camera"),
    ("small", "the person is only 300 pixels tall; come closer"),
    ("cut at the feet", "the feet reach the frame's edge; step back"),
    ("lying down", "the person is not upright"),
    ("camera high", r"the camera is too high or tilted down \(the photo's middle passes "
                    r"1\d\d% of the way up the body\)"),
    ("camera low", "the camera is too low or tilted up"),
])
def test_each_wrong_front_photo_is_told_what_to_do(body_model, front, wrong, message):
    image = {
        "arms down": lambda: photo(_body(body_model, [-45, -45, 3, 3]), body_model, "front",
                                   PART_NAMES),
        "feet together": lambda: photo(_body(body_model, [6, 6, -12, -12]), body_model, "front",
                                       PART_NAMES),
        "a hand raised": lambda: photo(_body(body_model, [110, 6, 3, 3]), body_model, "front",
                                       PART_NAMES, size_px=(900, 800)),
        "turned away": lambda: photo(_body(body_model, turn_deg=70), body_model, "front",
                                     PART_NAMES),
        "small": lambda: photo(_body(body_model), body_model, "front", PART_NAMES, body_px=300),
        "cut at the feet": lambda: front[:-46],
        "lying down": lambda: np.ascontiguousarray(np.rot90(front)),
        "camera high": lambda: _padded(front, top=1000),
        "camera low": lambda: _padded(front, bottom=700),
    }[wrong]()
    verdict = _verdict("front", image)
    assert any(re.search(message, line) for line in verdict.problems), verdict.problems


def test_a_front_photo_given_as_the_side_is_not_side_on(front):
    verdict = _verdict("side", front)
    assert any("the side photo: the person is not side-on" in line for line in verdict.problems)


@pytest.mark.parametrize("name, arms_down, loose", [
    ("ramzan1", True, True), ("saif1", True, False),
    ("ramzan2", False, True), ("saif2", False, False),
])
def test_real_front_photos(name, arms_down, loose):
    """The men with their arms hanging are told to raise them; those in an A-pose pass;
    ramzan's knee-long tunic is flagged (a warning, not a problem)."""
    path = f"{REAL}/{name}.jpeg"
    verdict = check_view("front", cv2.imread(path), photo_silhouette(path))
    told = [line for line in verdict.problems if "an arm is close to the body" in line]
    assert bool(told) == arms_down and len(verdict.problems) == int(arms_down), verdict.problems
    assert bool(verdict.warnings) == loose and all("legs part only" in line
                                                   for line in verdict.warnings)


def test_fitter_check_prints_the_verdicts_and_exits_2_on_a_problem(front, side, tmp_path,
                                                                   capsys):
    write_image(tmp_path / "front.png", front)
    write_image(tmp_path / "side.png", side)
    assert main(["check", str(tmp_path / "front.png"), str(tmp_path / "side.png")]) == 0
    out, err = capsys.readouterr()
    assert out.splitlines()[0].startswith("the front photo: ") and "pass the check" in out
    assert err == ""
    code = main(["check", str(tmp_path / "front.png"), str(tmp_path / "front.png")])
    out, err = capsys.readouterr()
    assert code == 2
    assert err.strip().splitlines() == [
        line for line in err.strip().splitlines() if line.startswith("fitter: error: the side")]
    assert "not side-on" in err


def test_no_check_reaches_a_run_and_every_batch_subject(tmp_path):
    """`--no-check` sets the inputs' check off in `fitter run`'s options and in each of
    `fitter batch`'s subjects; without it the check runs."""
    from bodyfit.fitter.batch.job import subject_job
    from bodyfit.fitter.batch.subjects import SubjectRow
    from bodyfit.fitter.cli.main import _build_parser, _run_settings
    from bodyfit.fitter.fit.person import PersonInputs
    from bodyfit.fitter.fit.person_fit import METHODS

    for extra, check in (([], True), (["--no-check"], False)):
        args = _build_parser().parse_args(["run", "--front", "f.png", "--side", "s.png",
                                           "--height-cm", "175", "-o", str(tmp_path), *extra])
        assert _run_settings(args)[0].check is check
        batch = _build_parser().parse_args(["batch", "t.csv", "-o", str(tmp_path), *extra])
        row = SubjectRow("s1", PersonInputs("front.png", "side.png", 175.0), None, 2)
        assert subject_job(row, METHODS["bodyfit"], vars(batch), tmp_path).inputs.check is check


def test_two_bodies_side_by_side_are_two_people(front, side, tmp_path, capsys):
    """Two of the part-coloured bodies side by side, which the detector scores under
    SECOND_PERSON_SCORE each: the second counts by its share of the first's score."""
    write_image(tmp_path / "two.png", np.hstack([front, front]))
    write_image(tmp_path / "side.png", side)
    assert main(["check", str(tmp_path / "two.png"), str(tmp_path / "side.png")]) == 2
    assert capsys.readouterr().err.strip() == (
        "fitter: error: 2 people found in the photo; photograph one person at a time")
