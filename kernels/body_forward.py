"""The body model's forward map in NumPy (the paper's Eq. 1-3): shape blend, then skinning.

The reference the Warp skinning kernels are checked against, and the host-side forward of
the fitter (:mod:`bodyfit.fitter.body_model` re-exports it). Typed on
:class:`bodyfit.kernels.skinning.SkinnableModel`'s attributes; no Warp, so importing it
initialises nothing.
"""

from __future__ import annotations

import numpy as np

from bodyfit.kernels.body_layout import POSE_NAMES, POSE_SIDES

__all__ = ["rest_shape", "abduction_rotations", "forward"]


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
    vertices = model.mean_vertices + np.einsum("pk,kvd->pvd", betas, vertex_dirs)
    joints = model.mean_joints + np.einsum("pk,kjd->pjd", betas, joint_dirs)
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
    rot = abduction_rotations(pose_deg)  # (P, 4, 3, 3)
    offset = rest[:, None, :, :] - joints[:, :, None, :]  # (P, 4, V, 3)
    moved = np.einsum("pcij,pcvj->pcvi", rot, offset) + joints[:, :, None, :]
    delta = moved - rest[:, None, :, :]  # (P, 4, V, 3)
    posed = rest + np.einsum("vc,pcvd->pvd", model.chain_weights, delta)
    return posed.astype(np.float32)
