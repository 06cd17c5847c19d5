"""The elbows the local solver bends and the hands it turns (fitter/fit/elbows.py): the
turns and their derivatives."""

import numpy as np
import pytest

from bodyfit.fitter.fit.elbows import (bend_derivative, bent, elbow_forward, elbow_rig,
                                      wrist_rig)
from bodyfit.fitter.fit.outline import posed_with_jacobian
from bodyfit.fitter.model.body_model import forward, rest_shape


def _flexion(model, vertices, side="L"):
    ring = {name: vertices[model.landmarks[f"ring:{name}.{side}"]].mean(axis=0)
            for name in ("shoulder", "elbow", "wrist")}
    upper, fore = ring["elbow"] - ring["shoulder"], ring["wrist"] - ring["elbow"]
    return np.degrees(np.arccos(upper @ fore / np.linalg.norm(upper) / np.linalg.norm(fore)))


def test_the_rest_flexion_leaves_the_body_and_others_bend_it(body_model):
    rig = elbow_rig(body_model)
    rest = rest_shape(body_model, np.array([[0.5, -1.0, 0.3]]))[0][0].astype(float)
    assert rig.rest_deg == pytest.approx(_flexion(body_model, rest), abs=2.0)
    np.testing.assert_array_equal(bent(rig, rest, rig.rest_deg), rest)
    for side in ("L", "R"):  # the rings' axes: within a degree and a half of the asked
        for target in (0.0, 10.0, 25.0):
            assert _flexion(body_model, bent(rig, rest, target), side) == pytest.approx(
                target, abs=1.5)
    untouched = rig.weights.sum(axis=0) == 0  # the torso, the head, the legs
    np.testing.assert_array_equal(bent(rig, rest, 5.0)[untouched], rest[untouched])


def test_the_bend_is_linear_in_the_body(body_model):
    rig = elbow_rig(body_model)
    a = body_model.mean_vertices.astype(float)
    b = np.random.default_rng(1).normal(0, 0.01, a.shape)
    np.testing.assert_allclose(bent(rig, a + 2 * b, 9.0),
                               bent(rig, a, 9.0) + 2 * bent(rig, b, 9.0), atol=1e-12)


def test_elbow_forward_without_a_flexion_is_forward(body_model):
    betas, pose = np.array([[0.3, 0.2]]), np.array([[-30.0, -30.0, 4.0, 4.0]])
    np.testing.assert_array_equal(elbow_forward(body_model, betas, pose, None),
                                  forward(body_model, betas, pose))


def test_posed_derivatives_match_differences(body_model):
    """The flexion's and a beta's columns of posed_with_jacobian, against central
    differences of elbow_forward (the posed body is linear in the betas)."""
    betas = np.array([0.4, -0.6, 0.2, 0.8])
    pose, flexion = np.array([-35.0, -35.0, 3.0, 3.0]), 12.0
    vertices = np.arange(0, body_model.num_vertices, 11)
    posed, jacobian = posed_with_jacobian(body_model, betas, pose, vertices, flexion)
    assert jacobian.shape == (len(vertices), 3, 4 + 4 + 1)
    np.testing.assert_allclose(posed, elbow_forward(body_model, betas[None], pose[None],
                                                    flexion)[0][vertices], atol=1e-6)

    def at(b, f):
        return elbow_forward(body_model, b[None], pose[None], f)[0][vertices].astype(float)

    step = np.eye(4)[2] * 0.05
    np.testing.assert_allclose((at(betas + step, flexion) - at(betas - step, flexion)) / 0.1,
                               jacobian[:, :, 2], atol=5e-6)
    np.testing.assert_allclose((at(betas, flexion + 0.5) - at(betas, flexion - 0.5)) / 1.0,
                               jacobian[:, :, -1], atol=5e-6)
    rig = elbow_rig(body_model)
    rest = rest_shape(body_model, betas[None])[0][0]
    np.testing.assert_allclose((bent(rig, rest, 7.0) - bent(rig, rest, 5.0)) / 2.0,
                               bend_derivative(rig, rest, 6.0), atol=1e-6)


def test_the_twist_turns_each_hand_about_its_forearm(body_model):
    """The hands' twist: each hand's core (weight 1) turned rigidly about its forearm's
    axis through the wrist ring's centroid (distances to the axis kept, a quarter turn
    about it), the rest of the body left."""
    rig = wrist_rig(body_model)
    rest = rest_shape(body_model, np.array([[0.5, -1.0, 0.3]]))[0][0].astype(float)
    np.testing.assert_array_equal(bent(rig, rest, 0.0), rest)
    turned = bent(rig, rest, 90.0)
    for weights, ring, axis in zip(rig.weights, rig.rings, rig.axes):
        core = weights > 1.0 - 1e-9
        centre = rest[ring].mean(axis=0)

        def radial(v):  # the vertices' offsets from the axis
            offsets = v[core] - centre
            return offsets - np.outer(offsets @ axis, axis)

        before, after = radial(rest), radial(turned)
        np.testing.assert_allclose(np.linalg.norm(after, axis=1),
                                   np.linalg.norm(before, axis=1), atol=1e-9)
        cosines = np.einsum("ij,ij->i", before, after) / np.maximum(
            np.linalg.norm(before, axis=1) ** 2, 1e-12)
        far = np.linalg.norm(before, axis=1) > 0.01
        np.testing.assert_allclose(cosines[far], 0.0, atol=1e-6)  # a quarter turn
        np.testing.assert_allclose(np.cross(before[far], after[far]) @ axis,
                                   np.linalg.norm(before[far], axis=1) ** 2, rtol=1e-6)
    untouched = rig.weights.sum(axis=0) == 0
    np.testing.assert_array_equal(turned[untouched], rest[untouched])


def test_the_twists_derivative_matches_differences(body_model):
    """posed_with_jacobian's twists' columns (the hands turned, then the elbows bent, then
    the rig), against central differences of elbow_forward."""
    betas = np.array([0.4, -0.6, 0.2, 0.8])
    pose, flexion, twist = np.array([-35.0, -35.0, 3.0, 3.0]), 12.0, np.array([50.0, 20.0])
    vertices = np.arange(0, body_model.num_vertices, 11)
    posed, jacobian = posed_with_jacobian(body_model, betas, pose, vertices, flexion, twist)
    assert jacobian.shape == (len(vertices), 3, 4 + 4 + 1 + 2)

    def at(b, t):
        return elbow_forward(body_model, b[None], pose[None], flexion, t)[0][vertices]

    np.testing.assert_allclose(posed, at(betas, twist), atol=1e-6)
    for side in (0, 1):
        step = np.eye(2)[side] * 0.5
        np.testing.assert_allclose((at(betas, twist + step) - at(betas, twist - step)) / 1.0,
                                   jacobian[:, :, 9 + side], atol=5e-6)
    step = np.eye(4)[1] * 0.05
    np.testing.assert_allclose((at(betas + step, twist) - at(betas - step, twist)) / 0.1,
                               jacobian[:, :, 1], atol=5e-6)
    for side, sign in ((0, 1.0), (1, -1.0)):  # each twist moves its own hand alone (+x: left)
        column = np.abs(jacobian[:, :, 9 + side]).max(axis=1)
        assert column.max() > 1e-4
        assert not column[sign * body_model.mean_vertices[vertices, 0] < 0].any()
