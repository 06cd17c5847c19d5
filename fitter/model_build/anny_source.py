"""Anny, the body model bodyfit's shape space is learned from: loading and sampling bodies.

Anny (NAVER, Apache-2.0 code, CC0 MakeHuman assets) generates a body from phenotypes
(gender, age, muscle, weight, height, proportions in [0, 1]) and local changes (named
blend shapes such as ``measure-waist-circ-incr`` in [-1, 1]). bodyfit uses its rest
(A-pose) bodies, its triangle topology and its skinning weights. Only the body's main
connected component is kept (Anny adds eyes and teeth as separate closed meshes inside
the head, invisible in a silhouette).

Anny's frame is bodyfit's model frame: metres, z up, -y forward, +x the body's left.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from bodyfit.fitter.measure.sections import mesh_edges

__all__ = [
    "BONE_GROUPS",
    "RIG_JOINT_BONES",
    "CHAIN_ROOT_BONES",
    "SHAPE_PARAMETERS",
    "AnnySource",
    "Skeleton",
]

logger = logging.getLogger(__name__)

#: Rig joints of bodyfit's 4 pose DOF, ``POSE_NAMES`` order: the head of the first bone
#: of each moving chain (glenohumeral joint; hip joint).
RIG_JOINT_BONES = ("upperarm01.L", "upperarm01.R", "upperleg01.L", "upperleg01.R")
#: Each moving chain is the subtree of Anny's skeleton rooted at this bone.
CHAIN_ROOT_BONES = RIG_JOINT_BONES

#: Bone groups (each the subtree under its root bones, minus the subtrees of the other
#: groups' roots) from which part labels and landmark rings are derived.
BONE_GROUPS = {
    "torso": ("root",),
    "neck": ("neck01",),
    "skull": ("head",),
    "upperarm.L": ("upperarm01.L",),
    "upperarm.R": ("upperarm01.R",),
    "forearm.L": ("lowerarm01.L",),
    "forearm.R": ("lowerarm01.R",),
    "hand.L": ("wrist.L",),
    "hand.R": ("wrist.R",),
    "thigh.L": ("upperleg01.L",),
    "thigh.R": ("upperleg01.R",),
    "shank.L": ("lowerleg01.L",),
    "shank.R": ("lowerleg01.R",),
    "foot.L": ("foot.L",),
    "foot.R": ("foot.R",),
}

#: Anny parameters varied across the model's sample. A name without an ``l-``/``r-`` prefix
#: that Anny only has sided (``upperarm-fat-incr``) drives both sides together, so bodies
#: stay left-right symmetric. Phenotypes are in [0, 1]; local changes in [-1, 1].
SHAPE_PARAMETERS = (
    # phenotypes
    "age", "muscle", "weight", "height", "proportions",
    # torso
    "measure-bust-circ-incr", "measure-underbust-circ-incr", "measure-waist-circ-incr",
    "measure-hips-circ-incr", "measure-shoulder-dist-incr", "measure-napetowaist-dist-incr",
    "measure-waisttohip-dist-incr", "measure-frontchest-dist-incr",
    "torso-scale-depth-incr", "torso-scale-horiz-incr", "torso-vshape-incr",
    "torso-muscle-pectoral-incr", "torso-muscle-dorsi-incr", "stomach-pregnant-incr",
    "buttocks-volume-incr", "hip-scale-horiz-incr", "hip-scale-depth-incr",
    # neck and head
    "measure-neck-circ-incr", "measure-neck-height-incr",
    "head-scale-horiz-incr", "head-scale-depth-incr", "head-scale-vert-incr", "head-fat-incr",
    # arms
    "measure-upperarm-circ-incr", "measure-upperarm-length-incr",
    "measure-lowerarm-length-incr", "measure-wrist-circ-incr",
    "upperarm-fat-incr", "upperarm-muscle-incr", "lowerarm-fat-incr", "lowerarm-muscle-incr",
    # legs
    "measure-thigh-circ-incr", "measure-knee-circ-incr", "measure-calf-circ-incr",
    "measure-ankle-circ-incr", "measure-upperleg-height-incr", "measure-lowerleg-height-incr",
    "upperleg-fat-incr", "upperleg-muscle-incr", "lowerleg-fat-incr", "lowerleg-muscle-incr",
)
PHENOTYPES = ("age", "muscle", "weight", "height", "proportions")


@dataclasses.dataclass(frozen=True, eq=False)
class Skeleton:
    """Anny's whole skeleton on the kept vertices, for posing a body by any bone.

    Attributes:
        labels: (B,) bone names; parents: (B,) int, each bone's parent (-1: the root),
            every parent before its children.
        vertex_bones: (V, k) int64 bones of each kept vertex; vertex_weights: (V, k)
            float64 their skinning weights (rows sum to 1).
    """

    labels: tuple[str, ...]
    parents: np.ndarray
    vertex_bones: np.ndarray
    vertex_weights: np.ndarray


@dataclasses.dataclass(frozen=True, eq=False)
class Topology:
    """The kept part of Anny's mesh and its rig data.

    Attributes:
        faces: (F, 3) int32, indices into the kept vertices.
        kept_vertices: (V,) int64, Anny vertex index of each kept vertex.
        group_weights: (V, G) float32, skinning weight summed per ``BONE_GROUPS`` entry.
        chain_weights: (V, 4) float32, skinning weight summed per moving chain.
    """

    faces: np.ndarray
    kept_vertices: np.ndarray
    group_weights: np.ndarray
    chain_weights: np.ndarray


class AnnySource:
    """An Anny model restricted to bodyfit's shape parameters, sampling rest bodies.

    Loading Anny the first time builds its own data cache (about a minute); later loads
    take well under a second.
    """

    def __init__(self) -> None:
        import anny  # heavy import (torch, warp): only when a model is built

        self.anny_version = anny.__version__
        # All local changes: one Anny data cache to build; the unused ones stay at 0.
        self.model = anny.Anny(local_changes="all")
        self._local_names = self._resolve_sided(set(self.model.local_change_labels))
        self.topology = self._make_topology()

    @staticmethod
    def _resolve_sided(available: set[str]) -> dict[str, tuple[str, ...]]:
        """Map each local-change parameter to the Anny local changes it drives."""
        resolved = {}
        for name in SHAPE_PARAMETERS:
            if name in PHENOTYPES:
                continue
            if name in available:
                resolved[name] = (name,)
            elif f"l-{name}" in available and f"r-{name}" in available:
                resolved[name] = (f"l-{name}", f"r-{name}")
            else:
                raise RuntimeError(f"this Anny version has no local change {name!r}")
        return resolved

    def _make_topology(self) -> Topology:
        import scipy.sparse
        import scipy.sparse.csgraph

        m = self.model
        faces = m.faces.cpu().numpy().astype(np.int64)
        n = m.template_vertices.shape[0]
        edges = mesh_edges(faces)
        graph = scipy.sparse.coo_matrix((np.ones(len(edges)), edges.T), shape=(n, n))
        _, comp = scipy.sparse.csgraph.connected_components(graph, directed=False)
        main = np.argmax(np.bincount(comp))
        kept = np.flatnonzero(comp == main)
        remap = np.full(n, -1, np.int64)
        remap[kept] = np.arange(len(kept))
        kept_faces = remap[faces[np.all(comp[faces] == main, axis=1)]].astype(np.int32)

        labels = list(m.bone_labels)
        parents = list(m.bone_parents)
        owner = self._bone_owner(labels, parents, BONE_GROUPS)
        chain_owner = self._bone_owner(
            labels, parents, {c: (c,) for c in CHAIN_ROOT_BONES}, default=-1)
        bone_idx = m.vertex_bone_indices.cpu().numpy()[kept]
        bone_w = m.vertex_bone_weights.cpu().numpy()[kept].astype(np.float64)
        group_w = np.zeros((len(kept), len(BONE_GROUPS)))
        chain_w = np.zeros((len(kept), len(CHAIN_ROOT_BONES)))
        rows = np.repeat(np.arange(len(kept))[:, None], bone_idx.shape[1], axis=1)
        np.add.at(group_w, (rows, owner[bone_idx]), bone_w)
        in_chain = chain_owner[bone_idx] >= 0
        np.add.at(chain_w, (rows[in_chain], chain_owner[bone_idx][in_chain]), bone_w[in_chain])
        return Topology(kept_faces, kept, group_w.astype(np.float32), chain_w.astype(np.float32))

    def skeleton(self) -> Skeleton:
        """The whole skeleton and its skinning of the kept vertices (:class:`Skeleton`)."""
        m = self.model
        kept = self.topology.kept_vertices
        parents = np.asarray(list(m.bone_parents), np.int64)
        if np.any(parents >= np.arange(len(parents))):
            raise RuntimeError("this Anny version lists a bone before its parent")
        return Skeleton(tuple(m.bone_labels), parents,
                        m.vertex_bone_indices.cpu().numpy()[kept].astype(np.int64),
                        m.vertex_bone_weights.cpu().numpy()[kept].astype(np.float64))

    @staticmethod
    def _bone_owner(labels, parents, groups: dict[str, tuple[str, ...]],
                    default: int | None = None) -> np.ndarray:
        """(bones,) int: index of the group whose root is each bone's nearest ancestor-or-self.

        Bones under no group root get ``default`` (an error when it is None).
        """
        roots = {labels.index(bone): g for g, bones in enumerate(groups.values())
                 for bone in bones}
        owner = np.empty(len(labels), np.int64)
        for b in range(len(labels)):
            a = b
            while a >= 0 and a not in roots:
                a = parents[a]
            if a < 0:
                if default is None:
                    raise RuntimeError(f"bone {labels[b]} belongs to no group")
                owner[b] = default
            else:
                owner[b] = roots[a]
        return owner

    def rest_bodies(self, gender: np.ndarray, params: np.ndarray, batch_size: int = 128,
                    all_bones: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Rest-pose (A-pose) bodies for parameter rows.

        Args:
            gender: (N,) float in [0, 1]; 0 male, 1 female (Anny's convention).
            params: (N, len(SHAPE_PARAMETERS)) float; phenotypes in [0, 1], local changes
                in [-1, 1], in ``SHAPE_PARAMETERS`` order.

        Returns:
            vertices: (N, V, 3) float32, metres, model frame (kept vertices only).
            joints: (N, 4, 3) float32, metres; heads of ``RIG_JOINT_BONES`` (``all_bones``:
                (N, B, 3), the head of every bone of :meth:`skeleton`).
        """
        import torch

        m = self.model
        joint_ids = (list(range(len(m.bone_labels))) if all_bones
                     else [m.bone_labels.index(b) for b in RIG_JOINT_BONES])
        kept = torch.as_tensor(self.topology.kept_vertices)
        verts, joints = [], []
        for start in range(0, len(params), batch_size):
            p = torch.as_tensor(params[start:start + batch_size], dtype=m.dtype)
            phen = {"gender": torch.as_tensor(gender[start:start + batch_size], dtype=m.dtype)}
            local = {}
            for i, name in enumerate(SHAPE_PARAMETERS):
                if name in PHENOTYPES:
                    phen[name] = p[:, i]
                else:
                    for anny_name in self._local_names[name]:
                        local[anny_name] = p[:, i]
            with torch.no_grad():
                out = m(phenotype_kwargs=phen, local_changes_kwargs=local)
            verts.append(out["rest_vertices"][:, kept].float().numpy())
            joints.append(out["rest_bone_heads"][:, joint_ids].float().numpy())
        return np.concatenate(verts), np.concatenate(joints)
