"""What a fit reads of the photos besides their silhouettes: which side the side photo
shows (a photo from the right fitted as its mirror image), and EXIF's focal length."""

import dataclasses
import math

import cv2
import numpy as np
import pytest
from PIL import ExifTags, Image

from bodyfit.calib.images import FULL_FRAME_DIAGONAL_MM, read_photo
from bodyfit.common.errors import UserError
from bodyfit.fitter.demo.studio_photos import pinhole_photo, write_pinhole_subject
from bodyfit.fitter.fit.facing import FACING_MARGIN, facing_reach, side_seen, side_text
from bodyfit.fitter.fit import person
from bodyfit.fitter.fit.person import PersonInputs, person_silhouettes, view_intrinsics
from bodyfit.fitter.fit.person_fit import FitSettings, fit_inputs
from bodyfit.fitter.fit.side_arms import side_photo_pose
from bodyfit.fitter.measure.measurements import IMPORTANT
from bodyfit.fitter.model.body_model import PART_NAMES, forward

BETAS = np.array([0.6, -0.4, 0.5, 0.2, -0.3] + [0.0] * 15)
POSE = np.array([5.0, 5.0, 4.0, 4.0])
SIZE = (900, 1200)  # width, height
K = np.array([[1000.0, 0.0, (SIZE[0] - 1) / 2], [0.0, 1000.0, (SIZE[1] - 1) / 2],
              [0.0, 0.0, 1.0]])
DISTANCE_M, HEIGHT_M = 3.0, 1.1


@pytest.fixture(scope="module")
def subject(body_model, tmp_path_factory):
    """A pinhole subject (camera.json with a centred principal point) and a side photo of
    the same body taken from its right (the body turned half round: right.png)."""
    folder = tmp_path_factory.mktemp("sides")
    truth = write_pinhole_subject(folder, body_model, BETAS, POSE, K, SIZE, DISTANCE_M,
                                  HEIGHT_M)
    side = forward(body_model, BETAS[None], side_photo_pose(body_model, BETAS, POSE)[None])[0]
    turned = side * np.array([-1.0, -1.0, 1.0], np.float32)
    cv2.imwrite(str(folder / "right.png"), pinhole_photo(turned, body_model, "side", PART_NAMES,
                                                         K, SIZE, DISTANCE_M, HEIGHT_M))
    cv2.imwrite(str(folder / "mirrored.png"), cv2.imread(str(folder / "right.png"))[:, ::-1])
    return folder, truth


def _inputs(folder, truth, side="side.png", camera=True, front="front.png"):
    return PersonInputs(str(folder / front), str(folder / side), truth["O"] / 10,
                        str(folder / "camera.json") if camera else None)


def test_side_seen_from_the_feet_of_a_drawn_profile():
    """A drawn profile: a leg column and feet reaching forward nearly 3x as far as back; the
    far foot seen higher than the near one, as from a camera above the floor."""
    mask = np.zeros((400, 300), bool)
    mask[50:390, 140:160] = True  # body and leg, 340 px tall, centre column 149.5
    mask[382:390, 100:168] = True  # the foot: toes 49.5 px left of the centre, heel 17.5 right
    mask[368:376, 104:168] = True  # the far foot, 14 px (4 % of the height) higher
    assert facing_reach(mask) == pytest.approx((49.5 - 17.5) / 340)
    assert side_seen(mask) == "left" and side_seen(mask[:, ::-1]) == "right"
    mask[382:390, 100:200] = True  # toes and heel alike: the feet do not tell
    assert abs(facing_reach(mask)) < FACING_MARGIN and side_seen(mask) is None


def test_side_photo_from_the_right_is_fitted_as_its_mirror_image(body_model, subject,
                                                                 monkeypatch):
    folder, truth = subject
    fits = {name: fit_inputs(body_model, _inputs(folder, truth, f"{name}.png"), FitSettings(),
                             progress=False)
            for name in ("side", "right", "mirrored")}
    assert fits["right"].photos["side_from"] == "right"
    assert fits["mirrored"].photos["side_from"] == "left"
    assert fits["side"].photos["side_from"] == "left"
    for key in truth:
        assert fits["right"].measurements[key] == pytest.approx(
            fits["mirrored"].measurements[key], abs=0.3), key
    # the model's bodies are left-right symmetric: the right side's photo says what the
    # left's does
    gap = np.mean([abs(fits["right"].measurements[k] - fits["side"].measurements[k])
                   for k in IMPORTANT])
    assert gap < 1.5
    # feet that do not tell: both ways fitted, the photo from the right's lower cost kept,
    # and that fit is the one told by the feet
    monkeypatch.setattr(person, "side_seen", lambda mask: None)
    untold = fit_inputs(body_model, _inputs(folder, truth, "right.png"), FitSettings(),
                        progress=False)
    costs = untold.photos["side_costs"]
    assert untold.photos["side_from"] == "right" and costs["right"] < costs["left"] - 5
    assert untold.measurements == fits["right"].measurements
    assert untold.seconds["search"] > fits["right"].seconds["search"]
    assert side_text(untold.photos) == (
        f"the person's right side (the feet do not tell; fitted both ways, its cost "
        f"{costs['right']:.1f} against {costs['left']:.1f})")


def test_side_from_given_overrides_the_feet(subject):
    folder, truth = subject
    told = person_silhouettes(_inputs(folder, truth), "pinhole")
    given = person_silhouettes(dataclasses.replace(_inputs(folder, truth), side_from="right"),
                               "pinhole")
    assert told.side_from == "left" and given.side_from == "right"
    np.testing.assert_array_equal(given.masks["side"], told.masks["side"][:, ::-1])
    cx = told.intrinsics["side"][0, 2]
    assert given.intrinsics["side"][0, 2] == pytest.approx(SIZE[0] - 1 - cx)
    with pytest.raises(UserError, match="--side-from must be one of auto, left, right"):
        person_silhouettes(dataclasses.replace(_inputs(folder, truth), side_from="front"),
                           "pinhole")


def _with_focal_exif(source, target, full_frame_mm: int):
    exif = Image.Exif()
    fields = exif.get_ifd(ExifTags.IFD.Exif)
    fields[ExifTags.Base.FocalLengthIn35mmFilm] = full_frame_mm
    fields[ExifTags.Base.FocalLength] = 4.2
    rgb = cv2.cvtColor(cv2.imread(str(source)), cv2.COLOR_BGR2RGB)
    Image.fromarray(rgb).save(target, quality=95, exif=exif)


def test_exif_focal_length_is_the_fitted_camera(body_model, subject, tmp_path):
    """No camera.json: the photos' FocalLengthIn35mmFilm gives K (the diagonal's ratio to a
    full frame's), and the placed canvas camera is that K scaled with the canvas."""
    folder, truth = subject
    for view in ("front", "side"):
        _with_focal_exif(folder / f"{view}.png", tmp_path / f"{view}.jpg", 35)
    focal = 35 * math.hypot(*SIZE) / FULL_FRAME_DIAGONAL_MM
    assert read_photo(tmp_path / "front.jpg").focal_px == pytest.approx(focal)
    inputs = PersonInputs(str(tmp_path / "front.jpg"), str(tmp_path / "side.jpg"),
                          truth["O"] / 10)
    photos = person_silhouettes(inputs, "pinhole")
    assert photos.camera_source == "EXIF FocalLengthIn35mmFilm 35 mm"
    for view in ("front", "side"):
        np.testing.assert_allclose(photos.intrinsics[view],
                                   [[focal, 0, (SIZE[0] - 1) / 2], [0, focal, (SIZE[1] - 1) / 2],
                                    [0, 0, 1]])
    settings = FitSettings()
    fit = fit_inputs(body_model, inputs, settings, progress=False)
    assert fit.photos["camera"] == photos.camera_source
    rows = np.flatnonzero(photos.masks["front"].any(axis=1))
    scale = settings.canvas.body_height_px / (rows[-1] - rows[0] + 1)
    # the canvas's scale, up to its size's rounding to whole pixels (about 1e-3)
    assert fit.views["front"].camera.fx / scale == pytest.approx(focal, rel=2e-3)
    # without EXIF: the assumed phone's, and it says so
    _, source = view_intrinsics(_inputs(folder, truth, camera=False),
                                person_silhouettes(_inputs(folder, truth), "pinhole").masks)
    assert source.startswith("assumed")
