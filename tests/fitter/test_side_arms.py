"""The side photo's arms: the arms-down angle, the side view's options, studio photos
with the arms down and a fit of them."""

import cv2
import numpy as np
import pytest

from bodyfit import kernels
from bodyfit.common.errors import UserError
from bodyfit.fitter.demo.studio_photos import write_subject
from bodyfit.fitter.fit.local_solver import SolverSettings
from bodyfit.fitter.fit.person import PersonInputs, person_masks
from bodyfit.fitter.fit.person_fit import FitSettings, fit_person
from bodyfit.fitter.fit.search import SearchSettings
from bodyfit.fitter.fit.side_arms import arms_down_deg, side_photo_pose, side_view_options
from bodyfit.fitter.model.body_model import PART_NAMES, POSE_NAMES, forward, rest_shape

BETAS = np.array([0.8, -0.6, 0.5, 0.3, -0.4] + [0.0] * 15)
POSE = np.array([6.0, 6.0, 3.0, 3.0])


@pytest.mark.parametrize("betas", [None, BETAS, -1.5 * BETAS])
def test_arms_down_angle_hangs_the_hands_below_the_shoulders(body_model, betas):
    angle = arms_down_deg(body_model, betas)
    assert -45.0 < angle < -36.0
    b = np.zeros((1, 20)) if betas is None else betas[None]
    posed = forward(body_model, b, side_photo_pose(body_model, b[0], POSE)[None])[0]
    joints = rest_shape(body_model, b)[1][0]
    hand = body_model.vertex_parts == PART_NAMES.index("hand")
    for side, chain in ((1.0, 0), (-1.0, 1)):
        centroid = posed[hand & (side * body_model.mean_vertices[:, 0] > 0)].mean(axis=0)
        assert abs(centroid[0] - joints[chain, 0]) < 1e-3  # metres
        assert centroid[2] < joints[chain, 2] - 0.4


def test_side_view_options(body_model):
    down = side_view_options(body_model, "down")
    assert down["visible_parts"] == PART_NAMES
    assert down["fixed_pose_deg"] == {POSE_NAMES[0]: pytest.approx(arms_down_deg(body_model)),
                                      POSE_NAMES[1]: pytest.approx(arms_down_deg(body_model))}
    hidden = side_view_options(body_model, "hidden")
    assert hidden == {"visible_parts": kernels.SIDE_VIEW_PARTS, "fixed_pose_deg": None}
    with pytest.raises(UserError, match="--side-arms must be one of down, hidden"):
        side_view_options(body_model, "up")


@pytest.fixture(scope="module")
def photos(body_model, tmp_path_factory):
    """Folders of one subject photographed with the side arms down and hidden."""
    folders = {}
    for arms in ("down", "hidden"):
        folders[arms] = tmp_path_factory.mktemp(arms)
        truth = write_subject(folders[arms], body_model, BETAS, POSE, side_arms=arms)
    return folders, truth


def test_studio_side_photo_shows_the_arms_hanging_forward(photos):
    folders, _ = photos
    read = {arms: {view: cv2.imread(str(folder / f"{view}.png")) for view in ("front", "side")}
            for arms, folder in folders.items()}
    assert np.array_equal(read["down"]["front"], read["hidden"]["front"])
    backdrop = {arms: (read[arms]["side"] == read[arms]["side"][0, 0]).all(axis=2)
                for arms in read}
    assert (~backdrop["down"] | backdrop["hidden"]).all()  # the arms add to the torso
    width = {arms: np.ptp(np.flatnonzero((~b).any(axis=0))) for arms, b in backdrop.items()}
    assert width["down"] > 1.3 * width["hidden"]  # the forearms hang forward
    with pytest.raises(ValueError, match="side_arms must be one of"):
        write_subject(folders["down"], None, BETAS, POSE, side_arms="up")


def test_a_side_photo_with_the_arms_down_costs_the_true_body_little_only_with_arms_down(
        body_model, photos):
    """On a side photo with the arms hanging down, the true body's outline (its shape and
    front pose; the nine part terms) scored with the candidates' arms down costs a few
    weighted mm in the side view; scored
    without arms (``side_arms="hidden"``), its side view costs over ten times as much: the
    person's arms would be matched to a torso, the thicker-torso bias."""
    folders, truth = photos
    inputs = PersonInputs(str(folders["down"] / "front.png"), str(folders["down"] / "side.png"),
                          truth["O"] / 10)
    masks = person_masks(inputs)
    search = SearchSettings(optimizer="ga", population=4, generations=1,
                            condition_stature=False, refine_components=0)
    side_cost = {}
    for arms in ("down", "hidden"):
        fit = fit_person(body_model, masks, truth["O"] / 1000,
                         FitSettings(search=search, solver=SolverSettings(), side_arms=arms,
                                     projection="orthographic"), progress=False)
        arrays = kernels.ModelArrays.from_body_model(body_model, 20)
        evaluator = kernels.PopulationEvaluator(arrays, [fit.views["side"]])
        part_costs = evaluator.evaluate(BETAS[None], POSE[None]).part_costs[0]
        side_cost[arms] = part_costs[:len(PART_NAMES)].sum()  # the outline, not top/bottom
    assert side_cost["down"] < 20.0
    assert side_cost["hidden"] > 10 * side_cost["down"]