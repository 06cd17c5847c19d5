"""The body model on a device, and skinning: (P, K) betas + (P, 4) pose -> (P, V, 3) vertices.

The same maths as the body model's NumPy forward (:func:`bodyfit.kernels.body_forward.forward`,
re-exported as ``bodyfit.fitter.model.body_model.forward``; the paper's Eq. 1-3):

    rest_i  = mean_i + sum_k betas[k] * vertex_dirs[k, i]                 (shape blend)
    joint_c = mean_joint_c + sum_k betas[k] * joint_dirs[k, c]
    posed_i = rest_i + sum_c w_ic * (R_c (rest_i - joint_c) + joint_c - rest_i)   (LBS)

One thread per (candidate, chain) computes the joints and rotations, then one thread per
(candidate, vertex) blends and skins. The shape directions are stored vertex-major,
(V, K) vec3, so that a vertex thread reads one contiguous row.
"""

from __future__ import annotations

import dataclasses
from typing import Protocol

import numpy as np
import warp as wp

from bodyfit.kernels.body_layout import PART_NAMES, POSE_NAMES, POSE_SIDES
from bodyfit.kernels.device import device_array, resolve_device

__all__ = ["SkinnableModel", "ShapeSpace", "ModelArrays", "skin", "launch_skinning"]

NUM_CHAINS = len(POSE_NAMES)


class SkinnableModel(Protocol):
    """What the kernels read from a body model (duck-typed; the kernels import no model).

    :class:`bodyfit.fitter.model.body_model.BodyModel` is one. V vertices, F faces, C stored
    shape components, 4 rig chains (``POSE_NAMES`` order).

    Attributes:
        mean_vertices: (V, 3) float, metres, model frame; rest (A-pose) mean body.
        mean_joints: (4, 3) float, metres; rig joints of the mean body.
        chain_weights: (V, 4) float in [0, 1]; skinning weight of each vertex per chain.
        faces: (F, 3) int triangles, counter-clockwise seen from outside.
        face_parts: (F,) int8 index into ``PART_NAMES``.
        num_vertices: V.
        num_components: C.
    """

    mean_vertices: np.ndarray
    mean_joints: np.ndarray
    chain_weights: np.ndarray
    faces: np.ndarray
    face_parts: np.ndarray
    num_vertices: int
    num_components: int

    def shape_directions(self, num_components: int) -> tuple[np.ndarray, np.ndarray]:
        """(K, V, 3) vertex and (K, 4, 3) joint directions scaled by their standard
        deviation (metres per sigma), K = ``num_components`` <= C."""


@wp.struct
class ShapeSpace:
    """The model's shape space and rig on a device (V vertices, K betas, 4 chains).

    Attributes:
        mean_vertices: (V,) vec3, metres, model frame; rest (A-pose) mean body.
        vertex_dirs: (V, K) vec3, metres per sigma; PCA directions scaled by their std.
        mean_joints: (4,) vec3, metres; rig joints of the mean body (``POSE_NAMES`` order).
        joint_dirs: (4, K) vec3, metres per sigma.
        chain_weights: (V, 4) float32 in [0, 1]; skinning weight of each vertex per chain.
        chain_sides: (4,) float32; +1 for the body's left chains, -1 for the right ones.
    """

    mean_vertices: wp.array(dtype=wp.vec3)
    vertex_dirs: wp.array2d(dtype=wp.vec3)
    mean_joints: wp.array(dtype=wp.vec3)
    joint_dirs: wp.array2d(dtype=wp.vec3)
    chain_weights: wp.array2d(dtype=wp.float32)
    chain_sides: wp.array(dtype=wp.float32)


@wp.func
def _shape_blend(mean: wp.vec3, dirs: wp.array2d(dtype=wp.vec3), row: int,
                 betas: wp.array2d(dtype=wp.float32), p: int):
    """mean + sum_k betas[p, k] * dirs[row, k], summed in four interleaved accumulators
    (four independent dependency chains: about 2.5x faster on a CPU core)."""
    acc0 = wp.vec3()
    acc1 = wp.vec3()
    acc2 = wp.vec3()
    acc3 = wp.vec3()
    num = betas.shape[1]
    k = int(0)
    while k + 3 < num:
        acc0 = acc0 + betas[p, k] * dirs[row, k]
        acc1 = acc1 + betas[p, k + 1] * dirs[row, k + 1]
        acc2 = acc2 + betas[p, k + 2] * dirs[row, k + 2]
        acc3 = acc3 + betas[p, k + 3] * dirs[row, k + 3]
        k = k + 4
    while k < num:
        acc0 = acc0 + betas[p, k] * dirs[row, k]
        k = k + 1
    return mean + ((acc0 + acc1) + (acc2 + acc3))


@wp.kernel(enable_backward=False)
def _joints_kernel(space: ShapeSpace, betas: wp.array2d(dtype=wp.float32),
                   pose_deg: wp.array2d(dtype=wp.float32), fixed_deg: wp.vec4,
                   is_fixed: wp.vec4, joints: wp.array2d(dtype=wp.vec3),
                   rotations: wp.array2d(dtype=wp.mat33)):
    p, c = wp.tid()
    joints[p, c] = _shape_blend(space.mean_joints[c], space.joint_dirs, c, betas, p)
    angle = pose_deg[p, c]
    if is_fixed[c] > 0.0:
        angle = fixed_deg[c]
    theta = wp.radians(angle) * space.chain_sides[c]
    cs = wp.cos(theta)
    sn = wp.sin(theta)
    rotations[p, c] = wp.mat33(cs, 0.0, -sn, 0.0, 1.0, 0.0, sn, 0.0, cs)


@wp.kernel(enable_backward=False)
def _skin_kernel(space: ShapeSpace, betas: wp.array2d(dtype=wp.float32),
                 joints: wp.array2d(dtype=wp.vec3), rotations: wp.array2d(dtype=wp.mat33),
                 vertices: wp.array2d(dtype=wp.vec3)):
    p, v = wp.tid()
    rest = _shape_blend(space.mean_vertices[v], space.vertex_dirs, v, betas, p)
    posed = rest
    for c in range(NUM_CHAINS):
        w = space.chain_weights[v, c]
        if w > 0.0:
            j = joints[p, c]
            posed = posed + w * (rotations[p, c] * (rest - j) + j - rest)
    vertices[p, v] = posed


@dataclasses.dataclass(frozen=True, eq=False)
class ModelArrays:
    """A body model (:class:`SkinnableModel`) prepared for the kernels on one device, with K betas.

    Attributes:
        space: the shape space and rig (see :class:`ShapeSpace`).
        faces: (F, 3) int32 triangles, counter-clockwise seen from outside (NumPy, host).
        face_parts: (F,) int8 index into ``PART_NAMES`` (NumPy, host).
        num_components: K.
        num_vertices: V.
        device: the Warp device holding ``space``.
    """

    space: ShapeSpace
    faces: np.ndarray
    face_parts: np.ndarray
    num_components: int
    num_vertices: int
    device: wp.Device

    @classmethod
    def from_body_model(cls, model: SkinnableModel, num_components: int = 20,
                        device: str = "cpu") -> "ModelArrays":
        """Copy the model's first ``num_components`` shape directions and its rig to ``device``.

        Args:
            model: any object with the attributes of :class:`SkinnableModel` (a
                :class:`bodyfit.fitter.model.body_model.BodyModel`).

        Raises:
            ValueError: the model stores fewer than ``num_components`` components, its part
                labels exceed ``PART_NAMES``, or the device is unavailable.
        """
        dev = resolve_device(device)
        if not 1 <= num_components <= model.num_components:
            raise ValueError(f"the body model stores {model.num_components} shape components; "
                             f"asked for {num_components}")
        if model.face_parts.max() >= len(PART_NAMES):
            raise ValueError("the model's part labels exceed PART_NAMES")
        vertex_dirs, joint_dirs = model.shape_directions(num_components)
        space = ShapeSpace()
        space.mean_vertices = wp.array(model.mean_vertices, dtype=wp.vec3, device=dev)
        space.vertex_dirs = wp.array(np.ascontiguousarray(vertex_dirs.transpose(1, 0, 2)),
                                     dtype=wp.vec3, device=dev)
        space.mean_joints = wp.array(model.mean_joints, dtype=wp.vec3, device=dev)
        space.joint_dirs = wp.array(np.ascontiguousarray(joint_dirs.transpose(1, 0, 2)),
                                    dtype=wp.vec3, device=dev)
        space.chain_weights = wp.array(model.chain_weights, dtype=wp.float32, device=dev)
        space.chain_sides = wp.array(POSE_SIDES.astype(np.float32), dtype=wp.float32, device=dev)
        return cls(space, model.faces.astype(np.int32), model.face_parts, num_components,
                   model.num_vertices, dev)


def launch_skinning(model: ModelArrays, betas: wp.array, pose_deg: wp.array,
                    joints: wp.array, rotations: wp.array, vertices: wp.array,
                    fixed_pose_deg: tuple[tuple[int, float], ...] = ()) -> None:
    """Launch the skinning kernels on checked arrays (no allocation, no checks).

    Args:
        betas: (P, K) float32, units of sigma.
        pose_deg: (P, 4) float32, degrees, ``POSE_NAMES`` order.
        joints: (P, 4) vec3 scratch, metres.
        rotations: (P, 4) mat33 scratch.
        vertices: (P, V) vec3 output, metres, model frame.
        fixed_pose_deg: ((pose column, degrees), ...): angles every candidate takes instead
            of its own (``ViewTarget.fixed_pose_deg``, e.g. a side view's arms down).
    """
    num = betas.shape[0]
    fixed_deg, is_fixed = [0.0] * NUM_CHAINS, [0.0] * NUM_CHAINS
    for column, degrees in fixed_pose_deg:
        fixed_deg[column], is_fixed[column] = degrees, 1.0
    wp.launch(_joints_kernel, dim=(num, NUM_CHAINS), device=model.device,
              inputs=[model.space, betas, pose_deg, wp.vec4(*fixed_deg), wp.vec4(*is_fixed)],
              outputs=[joints, rotations])
    wp.launch(_skin_kernel, dim=(num, model.num_vertices), device=model.device,
              inputs=[model.space, betas, joints, rotations], outputs=[vertices])


def skin(model: ModelArrays, betas, pose_deg) -> wp.array:
    """Posed vertices of a population (shape blend + linear blend skinning).

    Args:
        model: the model on its device.
        betas: (P, K) float, shape coefficients in units of standard deviation.
        pose_deg: (P, 4) float, abduction angles in degrees, ``POSE_NAMES`` order.

    Returns:
        (P, V) vec3 Warp array on ``model.device``, metres, model frame
        (``.numpy()`` gives (P, V, 3) float32).

    Raises:
        ValueError: wrong shapes or dtypes.
    """
    dims = {"K": model.num_components}
    betas = device_array("betas", betas, ("P", "K"), dims, "float", wp.float32, model.device)
    pose_deg = device_array("pose_deg", pose_deg, ("P", NUM_CHAINS), dims, "float", wp.float32,
                            model.device)
    num = dims["P"]
    joints = wp.empty((num, NUM_CHAINS), dtype=wp.vec3, device=model.device)
    rotations = wp.empty((num, NUM_CHAINS), dtype=wp.mat33, device=model.device)
    vertices = wp.empty((num, model.num_vertices), dtype=wp.vec3, device=model.device)
    launch_skinning(model, betas, pose_deg, joints, rotations, vertices)
    return vertices
