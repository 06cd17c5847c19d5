"""Weight presets, files and overrides (bodyfit.fitter.fit.weights), down to the kernels' cost."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.weights import (PRESETS, WEIGHT_NAMES, cost_settings, load_weights_file,
                                        parse_override, resolve_weights, settings_from_record,
                                        weights_record)
from bodyfit.fitter.model.body_model import PART_NAMES, forward
from bodyfit.kernels import (FRONT_VIEW_DEG, SIDE_VIEW_DEG, SIDE_VIEW_PARTS, TERM_NAMES,
                             CostSettings, ModelArrays, PopulationEvaluator, orthographic_camera,
                             prepare_view_target, rasterize)
from bodyfit.kernels.target import visible_faces

#: Table 2 of the paper, its "height" row carried by top and bottom.
#: The neck, split from Table 2's head part, weighs as the head.
TABLE_2 = {"head": 2, "chest": 5, "waist": 5, "hip": 5, "leg": 2, "foot": 1, "arm": 3,
           "elbow": 2, "hand": 1, "neck": 2, "top": 5, "bottom": 5, "view.front": 2,
           "view.side": 3}


def _one_line_error(call, *match):
    with pytest.raises(UserError) as info:
        call()
    message = str(info.value)
    assert message and "\n" not in message
    for text in match:
        assert text in message
    return message


def test_presets_have_the_documented_values():
    assert PRESETS["paper"] == TABLE_2
    assert PRESETS["bodyfit"] == {**TABLE_2, "head": 4, "neck": 4, "top": 0, "bottom": 0}
    assert PRESETS["uniform"] == dict.fromkeys(WEIGHT_NAMES, 1.0)
    assert PRESETS["lower-body"] == {
        "head": 1, "chest": 2, "waist": 5, "hip": 8, "leg": 6, "foot": 2, "arm": 1, "elbow": 1,
        "hand": 1, "neck": 1, "top": 5, "bottom": 5, "view.front": 2, "view.side": 3}
    assert list(PRESETS["paper"]) == list(WEIGHT_NAMES)


def test_paper_preset_is_the_kernels_default_and_bodyfit_the_fitters():
    from bodyfit.fitter.fit.person_fit import FitSettings

    assert cost_settings("paper") == CostSettings()
    assert weights_record(CostSettings()) == TABLE_2
    assert weights_record(FitSettings().cost) == PRESETS["bodyfit"]


def test_preset_settings_put_each_weight_in_its_field():
    settings = cost_settings("lower-body")
    assert settings.part_weights == (1, 2, 5, 8, 6, 2, 1, 1, 1, 1)
    assert (settings.top_weight, settings.bottom_weight) == (5, 5)
    assert (settings.front_weight, settings.side_weight) == (2, 3)


@pytest.mark.parametrize("name", WEIGHT_NAMES)
def test_an_override_changes_exactly_the_named_weight(name):
    record = weights_record(cost_settings("paper", [f"{name}=7.5"]))
    assert record == {**TABLE_2, name: 7.5}


def test_overrides_apply_in_order_after_the_preset():
    assert resolve_weights("uniform", ["waist=8", " waist = 3 ", "view.side=0"]) == {
        **PRESETS["uniform"], "waist": 3.0, "view.side": 0.0}


@pytest.mark.parametrize("text, match", [
    ("waist", "expected NAME=VALUE"),
    ("waist=", "empty"),
    ("waist=eight", "must be a number"),
    ("waist=-1", ">= 0"),
    ("waist=nan", ">= 0"),
    ("waist=inf", ">= 0"),
    ("=3", "unknown weight"),
    ("height=5", "unknown weight"),
    ("view=3", "unknown weight"),
])
def test_bad_overrides_are_one_line_user_errors(text, match):
    _one_line_error(lambda: parse_override(text), match, repr(text))


def test_unknown_names_list_the_valid_ones():
    message = _one_line_error(lambda: resolve_weights("paper", ["wasit=2"]), "'wasit'")
    assert all(name in message for name in WEIGHT_NAMES)


def test_degenerate_weights_are_errors():
    no_parts = [f"{name}=0" for name in PART_NAMES]
    _one_line_error(lambda: resolve_weights("paper", no_parts), "every part weight is 0")
    _one_line_error(lambda: resolve_weights("paper", ["view.front=0", "view.side=0"]),
                    "both view weights are 0")
    assert resolve_weights("paper", no_parts[1:])["head"] == 2.0


def test_unknown_weights_choice_is_an_error():
    _one_line_error(lambda: resolve_weights("papers"), "paper, bodyfit, uniform, lower-body",
                    "'papers'")


def test_weights_file_overrides_its_preset(tmp_path):
    path = tmp_path / "trousers.toml"
    path.write_text('preset = "lower-body"\nwaist = 8\nfoot = 3.5\nview.side = 4\n')
    assert load_weights_file(path) == {**PRESETS["lower-body"], "waist": 8, "foot": 3.5,
                                       "view.side": 4}
    settings = cost_settings(str(path), ["foot=1"])
    assert weights_record(settings) == {**PRESETS["lower-body"], "waist": 8, "foot": 1,
                                        "view.side": 4}


def test_weights_file_without_preset_starts_from_paper(tmp_path):
    path = tmp_path / "w.toml"
    path.write_text("top = 1\n[view]\nfront = 0.5\n")
    assert load_weights_file(path) == {**TABLE_2, "top": 1, "view.front": 0.5}


@pytest.mark.parametrize("text, match", [
    ("", "is empty"),
    ("# nothing but a comment\n", "is empty"),
    ("waist = \n", "not valid TOML"),
    ("waist = 1\nwaist = 2\n", "not valid TOML"),
    ('waist = "8"\n', "must be a number"),
    ("waist = true\n", "must be a number"),
    ("waist = [1, 2]\n", "must be a number"),
    ("waist = -2\n", ">= 0"),
    ("waist = nan\n", ">= 0"),
    ("wasit = 2\n", "unknown weight 'wasit'"),
    ("[parts]\nwaist = 2\n", "unknown weight 'parts'"),
    ("view.back = 2\n", "unknown weight 'view.back'"),
    ("view = 2\n", "view must be a table"),
    ('preset = "trousers"\n', "unknown preset 'trousers'"),
    ("preset = 1\n", "preset must be a string"),
])
def test_bad_weights_files_are_one_line_user_errors(tmp_path, text, match):
    path = tmp_path / "w.toml"
    path.write_text(text)
    _one_line_error(lambda: cost_settings(str(path)), str(path), match)


def test_missing_weights_file_is_an_error(tmp_path):
    path = tmp_path / "none.toml"
    _one_line_error(lambda: cost_settings(str(path)), str(path), "does not exist")


@pytest.mark.parametrize("choice, overrides", [
    ("paper", []), ("uniform", []), ("lower-body", []),
    ("paper", ["waist=8", "view.side=0", "top=0.25", "hand=0"]),
])
def test_record_round_trips_through_json(choice, overrides):
    base = CostSettings(matching="symmetric", align_rotation=False)
    settings = cost_settings(choice, overrides, base)
    record = json.loads(json.dumps(weights_record(settings)))
    assert list(record) == list(WEIGHT_NAMES)
    assert all(type(value) is float for value in record.values())
    assert settings_from_record(record, base) == settings
    assert settings.matching == "symmetric" and settings.align_rotation is False


def test_record_must_name_every_weight_once():
    record = weights_record(CostSettings())
    del record["hip"]
    _one_line_error(lambda: settings_from_record(record), "missing hip")
    _one_line_error(lambda: settings_from_record({**TABLE_2, "height": 5}), "'height'")
    _one_line_error(lambda: settings_from_record({**TABLE_2, "arm": -1}), ">= 0")


def test_record_from_before_the_neck_part_weighs_the_neck_as_the_head():
    old_record = {name: value for name, value in TABLE_2.items() if name != "neck"} | {"head": 4}
    settings = settings_from_record(old_record)
    assert settings.part_weights[PART_NAMES.index("neck")] == 4.0
    assert weights_record(settings) == {**TABLE_2, "head": 4, "neck": 4}


# --- the weights reach the kernels' cost ----------------------------------------------------

HEIGHT = 192
PIXELS_PER_METRE = 100.0
#: view -> (canvas width, parts rendered)
VIEWS = {"front": (128, PART_NAMES), "side": (64, SIDE_VIEW_PARTS)}
ANGLES = {"front": FRONT_VIEW_DEG, "side": SIDE_VIEW_DEG}


def _camera(view: str):
    width = VIEWS[view][0]
    return orthographic_camera(ANGLES[view], PIXELS_PER_METRE, (width / 2, HEIGHT / 2))


@pytest.fixture(scope="module")
def scene(body_model):
    """(model arrays, {view: ViewTarget}, betas, pose) of a person who is the mean body with
    limbs abducted 10 degrees, and two candidates: the person with the arms 12 degrees
    further out (wrong in the arms) and with the legs 4 degrees further out (wrong in the
    legs and the stature)."""
    betas = np.zeros((1, 20), np.float32)
    pose = np.full((1, 4), 10.0, np.float32)
    views = {}
    for name, (width, parts) in VIEWS.items():
        faces, face_parts = visible_faces(body_model.faces, body_model.face_parts, parts)
        labels = rasterize(forward(body_model, betas, pose), faces, face_parts, _camera(name),
                           HEIGHT, width).numpy()[0]
        views[name] = prepare_view_target(name, labels >= 0, _camera(name),
                                          1000.0 / PIXELS_PER_METRE, parts)
    model = ModelArrays.from_body_model(body_model, num_components=20, device="cpu")
    candidates_pose = np.repeat(pose, 2, axis=0)
    candidates_pose[0, :2] += 12.0
    candidates_pose[1, 2:] += 4.0
    return model, views, np.repeat(betas, 2, axis=0), candidates_pose


def _evaluate(scene, settings, views=("front", "side")):
    model, targets, betas, pose = scene
    return PopulationEvaluator(model, [targets[v] for v in views], settings).evaluate(betas, pose)


def test_an_override_changes_which_candidate_ranks_better(scene):
    arms_wrong, legs_wrong = 0, 1
    uniform = _evaluate(scene, cost_settings("uniform")).costs
    more_arm = _evaluate(scene, cost_settings("uniform", ["arm=20"])).costs
    more_leg = _evaluate(scene, cost_settings("uniform", ["leg=20"])).costs
    assert uniform[arms_wrong] < uniform[legs_wrong]
    assert more_leg[arms_wrong] < more_leg[legs_wrong]
    assert more_arm[legs_wrong] < more_arm[arms_wrong]


def test_an_override_scales_only_its_own_term(scene):
    uniform = _evaluate(scene, cost_settings("uniform")).part_costs
    for name, column in (("waist", TERM_NAMES.index("waist")), ("bottom", len(PART_NAMES) + 1)):
        weighted = _evaluate(scene, cost_settings("uniform", [f"{name}=8"])).part_costs
        expected = uniform.copy()
        expected[:, column] *= 8.0
        assert np.allclose(weighted, expected, rtol=1e-5)
        assert (weighted[:, column] > 0).all()


@pytest.mark.parametrize("view, other", [("front", "side"), ("side", "front")])
def test_view_weights_weigh_their_own_view(scene, view, other):
    alone = _evaluate(scene, cost_settings("uniform"), views=(view,)).costs
    both = _evaluate(scene, cost_settings("uniform", [f"view.{other}=0", f"view.{view}=3"]))
    assert np.allclose(both.costs, 3.0 * alone, rtol=1e-5)
