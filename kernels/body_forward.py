"""The body model's forward map in NumPy (the paper's Eq. 1-3): shape blend, then skinning.

The reference the Warp skinning kernels are checked against, and the host-side forward of
the fitter (:mod:`bodyfit.fitter.model.body_model` re-exports it). Typed on
:class:`bodyfit.kernels.skinning.SkinnableModel`'s attributes; no Warp, so importing it
initialises nothing.
"""

from __future__ import annotations

import numpy as np

from bodyfit.kernels.body_layout import POSE_NAMES, POSE_SIDES

__all__ = ["rest_shape", "abduction_rotations", "blend_skinning", "forward"]


def rest_shape(model, betas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 1: rest-pose vertices and rig joints of each body.

    Args:
        model: the body model (the attributes of
            :class:`bodyfit.kernels.skinning.SkinnableModel`).
        betas: (P, K) float, shape coefficients in units of standard deviation, K <= C.

    Returns:
        vertices: (P, V, 3) float32, metres, model frame.
        joints: (P, 4, 3) float32, metres.
    """
    betas = np.asarray(betas, dtype=np.float32)
    if betas.ndim != 2:
        raise ValueError(f"betas must have shape (P, K), got {betas.shape}")
    vertex_dirs, joint_dirs = model.shape_directions(betas.shape[1])
    num = betas.shape[0]
    vertices = model.mean_vertices + (betas @ vertex_dirs.reshape(len(vertex_dirs), -1)
                                      ).reshape(num, *model.mean_vertices.shape)
    joints = model.mean_joints + (betas @ joint_dirs.reshape(len(joint_dirs), -1)
                                  ).reshape(num, *model.mean_joints.shape)
    return vertices.astype(np.float32), joints.astype(np.float32)


def abduction_rotations(pose_deg: np.ndarray) -> np.ndarray:
    """Rotation matrices of the four chains, in the frontal (x-z) plane about the y axis.

    A positive angle moves the limb away from the midline: the left chains (+x side) turn
    a downward vector (0, 0, -1) towards +x, the right chains towards -x.

    Args:
        pose_deg: (P, 4) float, degrees, in ``POSE_NAMES`` order.

    Returns:
        (P, 4, 3, 3) float64 rotation matrices acting on column vectors (x, y, z).
    """
    theta = np.deg2rad(np.asarray(pose_deg, dtype=np.float64)) * POSE_SIDES
    c, s = np.cos(theta), np.sin(theta)
    rot = np.zeros(theta.shape + (3, 3))
    rot[..., 0, 0] = c
    rot[..., 0, 2] = -s
    rot[..., 1, 1] = 1.0
    rot[..., 2, 0] = s
    rot[..., 2, 2] = c
    return rot


def forward(model, betas: np.ndarray, pose_deg: np.ndarray) -> np.ndarray:
    """NumPy reference forward (Eq. 1-3): shape blend, then linear blend skinning.

    The Warp kernels of :mod:`bodyfit.kernels` are checked against this function.

    Args:
        model: the body model, as for :func:`rest_shape`.
        betas: (P, K) float, shape coefficients in units of standard deviation.
        pose_deg: (P, 4) float, abduction angles in degrees, ``POSE_NAMES`` order.

    Returns:
        (P, V, 3) float32 posed vertices, metres, model frame.
    """
    pose_deg = np.asarray(pose_deg, dtype=np.float64)
    betas = np.asarray(betas)
    if betas.ndim != 2 or pose_deg.shape != (betas.shape[0], len(POSE_NAMES)):
        raise ValueError(f"betas must be (P, K) and pose (P, 4); got {betas.shape} "
                         f"and {pose_deg.shape}")
    rest, joints = rest_shape(model, betas)
    return blend_skinning(model.chain_weights, rest, joints, abduction_rotations(pose_deg))


def blend_skinning(chain_weights: np.ndarray, rest: np.ndarray, joints: np.ndarray,
                   rotations: np.ndarray) -> np.ndarray:
    """Eq. 2, linear blend skinning of rest bodies by any rotation of each chain.

    Args:
        chain_weights: (V, 4) float, each vertex's weight on each moving chain.
        rest: (P, V, 3) float, metres, rest vertices; joints: (P, 4, 3) float, metres.
        rotations: (P, 4, 3, 3) float, each chain's rotation about its joint (acting on
            column vectors).

    Returns:
        (P, V, 3) float32 posed vertices, metres.
    """
    rot_t = np.asarray(rotations, dtype=np.float64).transpose(0, 1, 3, 2)  # R^T
    weights = np.asarray(chain_weights, dtype=np.float64)  # (V, 4)
    # posed = (1 - sum_c w_c) v + sum_c w_c (R_c (v - j_c) + j_c), rows as row vectors
    posed = rest * (1.0 - weights.sum(axis=1))[:, None]
    for c in range(weights.shape[1]):
        pivot = joints[:, c, None, :]  # (P, 1, 3)
        moved = (rest - pivot) @ rot_t[:, c] + pivot  # (P, V, 3)
        posed += weights[:, c, None] * moved
    return posed.astype(np.float32)
