"""Limbs bent outside the model's rig: each chain turned about its joint before the
abduction, such as a forward or backward swing (flexion) in the sagittal plane.

The rig (:mod:`bodyfit.fitter.model.body_model`) abducts each limb in the frontal plane
only; people's limbs also swing forward or back. These bodies are for photographing
subjects and training data the fitter did not shape (the accuracy benchmark's
out-of-space bodies, :mod:`bodyfit.fitter.training.start_training`).

Units: metres, model frame (z up, -y forward); degrees.
"""

from __future__ import annotations

import numpy as np

from bodyfit.fitter.model.body_model import BodyModel, abduction_rotations
from bodyfit.kernels.body_forward import blend_skinning

__all__ = ["flexion_rotations", "turned_bodies", "bent_bodies"]


def flexion_rotations(flexion_deg: np.ndarray) -> np.ndarray:
    """(P, 4, 3, 3) rotations about each chain's x axis (the sagittal plane): a positive
    angle swings a hanging limb forward (towards -y)."""
    phi = np.deg2rad(np.asarray(flexion_deg, dtype=np.float64))
    c, s = np.cos(phi), np.sin(phi)
    rot = np.zeros(phi.shape + (3, 3))
    rot[..., 0, 0] = 1.0
    rot[..., 1, 1] = c
    rot[..., 1, 2] = s
    rot[..., 2, 1] = -s
    rot[..., 2, 2] = c
    return rot


def turned_bodies(model: BodyModel, rest: np.ndarray, joints: np.ndarray,
                  pose_deg: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """(P, V, 3) float32 metres: the rest body (V, 3), its rig joints (4, 3), posed by each
    row of ``pose_deg`` (P, 4) abduction angles after the same row's ``turns``
    (P, 4, 3, 3) rotations of each chain about its joint, ``POSE_NAMES`` order."""
    count = len(pose_deg)
    return blend_skinning(model.chain_weights, np.repeat(rest[None], count, 0),
                          np.repeat(joints[None], count, 0),
                          abduction_rotations(pose_deg) @ turns)


def bent_bodies(model: BodyModel, rest: np.ndarray, joints: np.ndarray, pose_deg: np.ndarray,
                flexion_deg: np.ndarray) -> np.ndarray:
    """:func:`turned_bodies` turned by the (P, 4) ``flexion_deg`` bends
    (:func:`flexion_rotations`)."""
    return turned_bodies(model, rest, joints, pose_deg, flexion_rotations(flexion_deg))
