"""Skinning kernel against the NumPy reference forward of the body model."""

from __future__ import annotations

import re

import numpy as np
import pytest
import warp as wp

from bodyfit.fitter.model.body_model import forward
from bodyfit.kernels.device import resolve_device
from bodyfit.kernels.skinning import ModelArrays, skin

from kernel_scenes import DEVICES, random_bodies


@pytest.mark.parametrize("device", DEVICES)
def test_skin_matches_numpy_forward(body_model, device):
    model = ModelArrays.from_body_model(body_model, num_components=20, device=device)
    betas, pose = random_bodies(6, seed=1, spread=3.0)
    pose[0] = [30.0, 0.0, -10.0, 45.0]  # outside the GA's range too
    posed = skin(model, betas, pose).numpy()
    expected = forward(body_model, betas, pose)
    assert posed.shape == expected.shape == (6, body_model.num_vertices, 3)
    assert np.abs(posed - expected).max() < 1e-5


def test_skin_moves_only_the_posed_chain(body_model, model_arrays):
    betas = np.zeros((2, 20), np.float32)
    pose = np.array([[0, 0, 0, 0], [20, 0, 0, 0]], np.float32)  # left shoulder only
    rest, raised = skin(model_arrays, betas, pose).numpy()
    moved = np.linalg.norm(raised - rest, axis=1) > 1e-6
    assert np.array_equal(moved, body_model.chain_weights[:, 0] > 0)


def test_skin_accepts_warp_arrays(model_arrays):
    betas, pose = random_bodies(3, seed=2)
    expected = skin(model_arrays, betas, pose).numpy()
    got = skin(model_arrays, wp.array(betas, dtype=wp.float32), wp.array(pose, dtype=wp.float32))
    assert np.array_equal(got.numpy(), expected)


@pytest.mark.parametrize("betas_shape, pose_shape, name, expected", [
    ((4, 19), (4, 4), "betas", "(P=4, K=20)"),
    ((4, 20), (4, 3), "pose_deg", "(P=4, 4)"),
    ((4, 20), (5, 4), "pose_deg", "(P=4, 4)"),
    ((20,), (4, 4), "betas", "(P, K=20)"),
])
def test_skin_rejects_wrong_shapes(model_arrays, betas_shape, pose_shape, name, expected):
    with pytest.raises(ValueError, match=re.escape(f"{name} must have shape {expected}")):
        skin(model_arrays, np.zeros(betas_shape), np.zeros(pose_shape))


def test_skin_rejects_wrong_dtypes(model_arrays):
    with pytest.raises(ValueError, match="betas must be a float array"):
        skin(model_arrays, np.zeros((2, 20), complex), np.zeros((2, 4)))
    with pytest.raises(ValueError, match="pose_deg must be a Warp array of dtype float32"):
        skin(model_arrays, np.zeros((2, 20)), wp.zeros((2, 4), dtype=wp.float64))


def test_unavailable_device_is_a_clear_error(body_model):
    with pytest.raises(ValueError, match="'tpu:0' is not available"):
        resolve_device("tpu:0")
    if not wp.is_cuda_available():
        with pytest.raises(ValueError, match="use --device cpu"):
            ModelArrays.from_body_model(body_model, device="cuda:0")


def test_too_many_betas_is_a_value_error(body_model):
    with pytest.raises(ValueError, match="stores"):
        ModelArrays.from_body_model(body_model, num_components=body_model.num_components + 1)
