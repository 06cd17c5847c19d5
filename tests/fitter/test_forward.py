"""The NumPy reference forward: shape blend + 4-DOF linear blend skinning."""

import numpy as np
import pytest

from bodyfit.fitter.model.body_model import (PART_NAMES, POSE_NAMES, abduction_rotations, forward,
                                             rest_shape)


@pytest.fixture(scope="module")
def betas():
    return np.random.default_rng(3).uniform(-2, 2, (3, 20))


def test_zero_pose_is_the_rest_shape(body_model, betas):
    rest, _ = rest_shape(body_model, betas)
    posed = forward(body_model, betas, np.zeros((3, 4)))
    np.testing.assert_allclose(posed, rest, atol=1e-6)


def test_rotations_are_proper_and_abduct_outwards():
    rot = abduction_rotations(np.array([[20.0, 20.0, 20.0, 20.0]]))[0]
    for r in rot:
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
        assert np.isclose(np.linalg.det(r), 1.0)
    down = np.array([0.0, 0.0, -1.0])
    s = np.sin(np.deg2rad(20))
    np.testing.assert_allclose(rot[0] @ down, [s, 0, -np.cos(np.deg2rad(20))], atol=1e-12)
    np.testing.assert_allclose(rot[1] @ down, [-s, 0, -np.cos(np.deg2rad(20))], atol=1e-12)


def test_shoulder_abduction_moves_the_hand_analytically(body_model, betas):
    """20 degrees of left shoulder abduction: a left-hand vertex skinned wholly to the
    arm chain turns rigidly about the joint: its displacement is 2 r sin(10 deg), r its
    distance from the joint's y axis; the feet do not move."""
    pose = np.zeros((3, 4))
    pose[:, POSE_NAMES.index("shoulder_abduction_left")] = 20.0
    rest, joints = rest_shape(body_model, betas)
    posed = forward(body_model, betas, pose)
    parts = body_model.vertex_parts
    w = body_model.chain_weights[:, 0]
    hand = np.flatnonzero((parts == PART_NAMES.index("hand")) & (w > 0.999)
                          & (body_model.mean_vertices[:, 0] > 0))
    assert len(hand) > 100
    offset = rest[:, hand] - joints[:, None, 0]
    r = np.linalg.norm(offset[..., [0, 2]], axis=-1)
    moved = np.linalg.norm(posed[:, hand] - rest[:, hand], axis=-1)
    np.testing.assert_allclose(moved, 2 * r * np.sin(np.deg2rad(10)), atol=2e-6)
    assert np.all(posed[:, hand, 0] > rest[:, hand, 0])  # outwards (+x, the left)
    assert np.all(posed[:, hand, 1] == pytest.approx(rest[:, hand, 1], abs=1e-6))
    feet = parts == PART_NAMES.index("foot")
    np.testing.assert_allclose(posed[:, feet], rest[:, feet], atol=1e-7)  # metres
    right_hand = (parts == PART_NAMES.index("hand")) & (body_model.mean_vertices[:, 0] < 0)
    np.testing.assert_allclose(posed[:, right_hand], rest[:, right_hand], atol=1e-7)


def test_hip_abduction_moves_the_right_foot_outwards(body_model, betas):
    pose = np.zeros((3, 4))
    pose[:, POSE_NAMES.index("hip_abduction_right")] = 10.0
    rest, _ = rest_shape(body_model, betas)
    posed = forward(body_model, betas, pose)
    foot = (body_model.vertex_parts == PART_NAMES.index("foot")) & (body_model.mean_vertices[:, 0] < 0)
    assert np.all(posed[:, foot, 0] < rest[:, foot, 0] - 0.05)  # metres, towards -x


def test_bad_shapes_are_rejected(body_model):
    with pytest.raises(ValueError, match="pose"):
        forward(body_model, np.zeros((2, 20)), np.zeros((3, 4)))
