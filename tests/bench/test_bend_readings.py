"""The front photo's limb-bend probes: the bicep's width under a swing against the turn it
makes about the arm's own axis, and the arms' swing read back from a photo of it."""

import numpy as np
import pytest

from bench.probes import bend_readings
from bench.accuracy.bodies import Bodies, bent_bodies
from bodyfit import kernels
from bodyfit.fitter.fit.photo_extents import ViewPhoto, silhouette_axis
from bodyfit.fitter.fit.pinhole_canvas import Placement
from bodyfit.fitter.model.body_model import PART_NAMES, rest_shape

POSE_DEG = np.array([5.0, 5.0, 4.0, 4.0])


@pytest.fixture(scope="module")
def mean_rest(body_model):
    """(rest (V, 3), joints (4, 3)) of the model's mean body, metres."""
    rest, joints = rest_shape(body_model, np.zeros((1, 20)))
    return rest[0].astype(np.float64), joints[0].astype(np.float64)


def test_a_swing_turns_the_bicep_about_its_arm_and_a_tilt_does_not(body_model, measurer,
                                                                    mean_rest):
    """The swing about the model's x axis changes the bicep's front width as much as its
    section turned in its plane by the swing times the arm's direction's x component (the
    share of the swing that turns the arm about its own axis) does; a tilt towards the
    camera changes it by under a tenth of that."""
    rest, joints = mean_rest
    bodies = Bodies(np.array(["female"]), np.array([False]), rest[None], joints[None],
                    POSE_DEG[None], np.zeros((1, 4)), np.zeros((1, 0)), {})
    swing, tilt = bend_readings.twist_width_change(body_model, measurer, bodies, 0)
    body = bent_bodies(body_model, rest, joints, POSE_DEG[None], np.zeros(4)[None])[0]
    section = measurer.girth_section(body, "H.L")
    across = measurer.girth_axes(body, "H.L") @ silhouette_axis(measurer, body, "H.L", "front")
    arm = measurer.girth_plane(body, "H.L")[1]
    turn_per_deg = abs(arm[0]) / np.linalg.norm(arm)
    widths = []
    for degrees in (-4.0, 4.0):
        psi = np.deg2rad(turn_per_deg * degrees)
        turned = section @ np.array([[np.cos(psi), -np.sin(psi)], [np.sin(psi), np.cos(psi)]]).T
        widths.append(np.ptp(turned @ across))
    turned_change = 100.0 * (widths[1] - widths[0]) / 8.0 / np.mean(widths)
    assert abs(swing) > 0.1  # % per degree: the mean body's section is not round
    assert abs(swing) == pytest.approx(abs(turned_change), rel=0.2)
    assert abs(tilt) < 0.1 * abs(swing)


def test_the_arms_swing_is_read_back_from_a_photo_of_it(body_model, mean_rest):
    """The mean body photographed 3 m away with its left arm swung 5 degrees forward, its
    right arm 3 degrees back: the estimate on the unswung body finds those grid points, and
    no change of abduction. (A changed abduction moves the hands, which set the
    silhouette's horizontal extent and so the placed camera's sideways offset: the
    estimate then trades swing against abduction.)"""
    rest, joints = mean_rest
    k = np.array([[750.0, 0, 299.5], [0, 750.0, 399.5], [0, 0, 1]])
    person = bent_bodies(body_model, rest, joints, POSE_DEG[None],
                         np.array([[5.0, -3.0, 0.0, 0.0]]))[0]
    camera = Placement(3.0, 1.0, 0.0, -person[:, 2].min()).extrinsics("front")
    mask = kernels.rasterize(person[None].astype(np.float32), body_model.faces,
                             body_model.face_parts, kernels.pinhole_camera(k, *camera),
                             800, 600).numpy()[0] >= 0
    fitted = bent_bodies(body_model, rest, joints, POSE_DEG[None], np.zeros(4)[None])[0]
    photo = ViewPhoto("front", mask, k, fitted, PART_NAMES)
    estimate = bend_readings.estimate_arm_swing(body_model, photo, rest, joints, POSE_DEG)
    np.testing.assert_allclose(estimate, [5.0, -3.0, 0.0, 0.0])
