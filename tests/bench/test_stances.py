"""The standing set's poses (bench/accuracy/stances.py): Anny's skeleton posed as people
stand, checked on its own bones."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from bench.accuracy.stances import (StanceSettings, arm_turns, bone_transforms, draw_stances,
                                    posed_bodies, posed_vertices)
from bodyfit.fitter.model_build.anny_source import PHENOTYPES, SHAPE_PARAMETERS


@pytest.fixture(scope="module")
def body(anny_source):
    """(skeleton, rest (V, 3), every bone's head (B, 3), name -> head) of one Anny man
    (phenotypes at the middle of their ranges but a younger age, no local change)."""
    params = np.array([[{"age": 0.35}.get(name, 0.5) if name in PHENOTYPES else 0.0
                        for name in SHAPE_PARAMETERS]])
    rest, heads = anny_source.rest_bodies(np.array([0.0]), params, all_bones=True)
    skeleton = anny_source.skeleton()
    rest, heads = rest[0].astype(float), heads[0].astype(float)
    return skeleton, rest, heads, dict(zip(skeleton.labels, heads))


def _posed_head(skeleton, heads, turns, bone):
    b = skeleton.labels.index(bone)
    return (bone_transforms(skeleton, heads, turns)[b] @ np.append(heads[b], 1.0))[:3]


def test_no_turns_leave_the_rest_body(body):
    skeleton, rest, heads, _ = body
    np.testing.assert_allclose(posed_vertices(skeleton, rest, heads, {}), rest, atol=1e-9)


def test_a_straight_hanging_arm_puts_the_wrist_below_the_shoulder(body):
    skeleton, _, heads, at = body
    for side in ("L", "R"):
        shoulder, elbow = at[f"upperarm01.{side}"], at[f"lowerarm01.{side}"]
        length = (np.linalg.norm(elbow - shoulder)
                  + np.linalg.norm(at[f"wrist.{side}"] - elbow))
        turns = arm_turns(at, side, 0.0, 0.0, 0.0, 25.0)  # the twist leaves the wrist put
        wrist = _posed_head(skeleton, heads, turns, f"wrist.{side}")
        np.testing.assert_allclose(wrist, shoulder - [0.0, 0.0, length], atol=1e-9)


def test_arm_angles_out_swing_and_elbow(body):
    """The upper arm points out_deg from straight down in the frontal plane after a
    swing_deg forward; the forearm bends elbow_deg from it."""
    skeleton, _, heads, at = body
    turns = arm_turns(at, "L", 30.0, 10.0, 12.0, 0.0)
    shoulder = at["upperarm01.L"]
    elbow = _posed_head(skeleton, heads, turns, "lowerarm01.L")
    wrist = _posed_head(skeleton, heads, turns, "wrist.L")
    upper = (elbow - shoulder) / np.linalg.norm(elbow - shoulder)
    out, swing = np.deg2rad(30.0), np.deg2rad(10.0)
    np.testing.assert_allclose(upper, [np.sin(out) * np.cos(swing), -np.sin(swing),
                                       -np.cos(out) * np.cos(swing)], atol=1e-9)
    fore = (wrist - elbow) / np.linalg.norm(wrist - elbow)
    assert np.degrees(np.arccos(upper @ fore)) == pytest.approx(12.0, abs=1e-6)


def test_side_photo_from_the_right_is_the_body_turned_round(body):
    skeleton, rest, heads, _ = body
    stance = {name: value[0] for name, value in
              draw_stances(StanceSettings(), 1, np.random.default_rng(3)).items()}
    left = posed_bodies(skeleton, rest, heads, stance | {"side_from_right": 0.0})
    right = posed_bodies(skeleton, rest, heads, stance | {"side_from_right": 1.0})
    np.testing.assert_array_equal(left[0], right[0])
    half_turn = Rotation.from_euler("z", 180, degrees=True).as_matrix()
    np.testing.assert_allclose(right[1], left[1] @ half_turn.T, atol=1e-6)


def _photographed(body, body_model, measurer, folder, shots, twist_deg=20.0):
    """(PersonInputs, truth measurements) of ``body`` standing with straight arms (elbows 5
    degrees, the front photo's hands ``twist_deg`` from palm in) photographed by the
    benchmark's renderer through the demo's lens from ``shots`` (view name ->
    bench.accuracy.photos.Shot)."""
    from bench.accuracy.photos import PhotoEffects, write_photos
    from bodyfit.calib.camera import Camera, camera_fields
    from bodyfit.fitter.demo.example import demo_camera
    from bodyfit.fitter.fit.person import PersonInputs
    from bodyfit.fitter.output.result_files import write_json

    skeleton, rest, heads, _ = body
    stance = {name: value[0] for name, value in
              draw_stances(StanceSettings(), 1, np.random.default_rng(5)).items()}
    stance |= {"front_arm_deg": np.full(2, 35.0), "front_elbow_deg": np.full(2, 5.0),
               "front_twist_deg": np.full(2, twist_deg), "side_out_deg": np.full(2, 5.0),
               "side_swing_deg": np.zeros(2), "side_elbow_deg": np.full(2, 5.0),
               "side_from_right": 0.0}
    front, side = posed_bodies(skeleton, rest, heads, stance)
    lens = demo_camera((900, 1200))
    camera = Camera(lens.image_size_px, lens.K, np.zeros(5))
    write_photos(folder, body_model, {"front": front, "side": side}, camera, shots,
                 PhotoEffects(), np.random.default_rng(0))
    write_json(folder / "camera.json", camera_fields(camera))
    truth = measurer.measure(rest)
    return PersonInputs(str(folder / "front.jpg"), str(folder / "side.jpg"), truth["O"] / 10,
                        str(folder / "camera.json")), truth


def test_straight_hanging_arms_are_fitted_with_their_length(body, body_model, measurer,
                                                             tmp_path):
    """A body standing with straight arms (elbows 5 degrees) photographed by the
    benchmark's renderer. Fitted with the elbows fitted: the flexion within 10 degrees,
    the arm length within 50 mm (today's tolerance, not ISO's 5: this body, Anny's middle
    phenotype, measures 42.7 mm long, 27.6 with the shape prior's fixed part alone; the
    standing set's 72 choice subjects 6.9 mm on average, 8.7 with it alone), the 7
    important within 15 mm on average and under 0.7 of what the rest
    pose's elbows give (about 43 degrees: the side view's hands in front of the belly;
    measured 10.5 against 17.3 mm)."""
    import dataclasses

    from bench.accuracy.photos import Shot
    from bodyfit.fitter.fit.person_fit import FitSettings, fit_inputs
    from bodyfit.fitter.measure.measurements import IMPORTANT

    shot = Shot(3.0, 1.1)
    inputs, truth = _photographed(body, body_model, measurer, tmp_path,
                                  {"front": shot, "side": shot})
    settings = FitSettings(measurement_prior="none")  # the fits' own measurements
    fits = {elbows: fit_inputs(body_model, inputs, dataclasses.replace(
        settings, solver=dataclasses.replace(settings.solver, elbows=elbows)), progress=False)
        for elbows in ("fitted", "rest")}
    important = {name: np.mean([abs(fit.measurements[k] - truth[k]) for k in IMPORTANT])
                 for name, fit in fits.items()}
    assert fits["fitted"].search.elbow_deg == pytest.approx(5.0, abs=10.0)
    assert fits["rest"].search.elbow_deg is None
    assert abs(fits["fitted"].measurements["J"] - truth["J"]) < 50.0
    assert important["fitted"] < 15.0 and important["fitted"] < 0.7 * important["rest"]


def test_a_pitched_side_photo_is_fitted_through_its_pitch(body, body_model, measurer,
                                                          tmp_path):
    """The same body, its side photo taken from 1.5 m high with the phone pitched 7 degrees
    down (the front level). The default search answers the side camera pitched one step
    (4 degrees) down and the front camera level; the 7 important come nearer the truth
    than the level cameras' fit (`--pitch level`) puts them (measured: 7.4 against 10.0
    mm; the inside leg, nearer before the shape prior grew with the misfit, 4.0 against
    1.5 mm now). At 5 degrees the side's pitched solve
    won by less than the prior on one machine and more on another (costs 44.3 + 3.2 against
    the level fit's 46.1: the search kept level); at 7: 41.8 + 3.2 against 47.3."""
    import dataclasses

    from bench.accuracy.photos import Shot
    from bodyfit.fitter.fit.person_fit import FitSettings, fit_inputs
    from bodyfit.fitter.measure.measurements import IMPORTANT

    inputs, truth = _photographed(body, body_model, measurer, tmp_path,
                                  {"front": Shot(3.0, 1.1), "side": Shot(3.0, 1.5, 7.0)})
    settings = FitSettings()
    fits = {pitch: fit_inputs(body_model, inputs, dataclasses.replace(
        settings, solver=dataclasses.replace(settings.solver, pitch=pitch)), progress=False)
        for pitch in ("searched", "level")}
    assert fits["searched"].photos["pitch_deg"]["side"] == 4.0
    assert fits["searched"].photos["pitch_deg"]["front"] == 0.0
    assert fits["level"].photos["pitch_deg"] == {"front": 0.0, "side": 0.0}
    errors = {pitch: np.mean([abs(fit.measurements[k] - truth[k]) for k in IMPORTANT])
              for pitch, fit in fits.items()}
    assert errors["searched"] < 0.9 * errors["level"], errors


def test_the_front_photos_hands_are_fitted_with_their_turn(body, body_model, measurer,
                                                          tmp_path):
    """The same body, its front photo's palms turned 20 and 80 degrees from palm in
    towards the camera, fitted with the cameras level (`--pitch level`, for time): each
    hand's fitted twist follows the photo's, by more than 15 degrees (measured: 3.4 and
    5.0 degrees at 20, 33.2 and 27.7 at 80: this body's fit reads the turn short; on the
    standing set's choice rows the fitted twists follow the truth with r = 0.73, 10.8
    degrees off on average)."""
    import dataclasses

    from bench.accuracy.photos import Shot
    from bodyfit.fitter.fit.person_fit import FitSettings, fit_inputs

    settings = FitSettings()
    settings = dataclasses.replace(settings, solver=dataclasses.replace(settings.solver,
                                                                        pitch="level"))
    twists = {}
    for twist in (20.0, 80.0):  # the truth's stance is the same, but for the hands
        folder = tmp_path / str(twist)
        folder.mkdir()
        inputs, _ = _photographed(body, body_model, measurer, folder,
                                  {"front": Shot(3.0, 1.1), "side": Shot(3.0, 1.1)},
                                  twist_deg=twist)
        twists[twist] = fit_inputs(body_model, inputs, settings, progress=False
                                   ).search.hand_twist_deg
    assert np.all(twists[80.0] - twists[20.0] > 15.0), twists
