"""The statistical body model: PCA shape space, 4-DOF skinning rig, part labels, landmarks.

bodyfit's equivalent of the paper's S-SCAPE model (Section 3.2, Eq. 1-3), built from the
Anny body model by :mod:`bodyfit.fitter.model_build.builder`. A body is

    rest = mean + sum_k betas[k] * sqrt(eigenvalues[k]) * components[k]      (Eq. 1)
    posed_i = rest_i + sum_c w_ic * (R_c(pose_c) (rest_i - j_c) + j_c - rest_i)  (Eq. 2)

where the shape vector stacks the rest vertices *and* the four rig joints, so the joints
follow the shape linearly; ``betas`` are in units of standard deviation (the paper draws
them in +-3); ``w_ic`` is the skinning weight of vertex i on moving chain c (Anny's bone
weights summed over the chain); ``R_c`` rotates about the model's y axis (the frontal
plane) by the chain's abduction angle.

Frame and units everywhere: metres, model frame, z up, -y forward (the body faces -y),
+x is the body's left.
"""

from __future__ import annotations

import dataclasses
import functools
import io
import json
from pathlib import Path

import numpy as np

from bodyfit.common.errors import UserError
from bodyfit.common.files import write_atomic
from bodyfit.kernels.body_forward import abduction_rotations, forward, rest_shape  # re-exported
from bodyfit.kernels.body_layout import PART_NAMES, POSE_NAMES  # re-exported

__all__ = [
    "PART_NAMES",
    "POSE_NAMES",
    "FORMAT_VERSION",
    "BodyModel",
    "abduction_rotations",
    "forward",
    "rest_shape",
    "project_shape",
]

#: Bumped whenever the file layout or the build changes meaning; older caches are rebuilt.
FORMAT_VERSION = 2  # 2: the neck part (labels 0-9)


@dataclasses.dataclass(frozen=True, eq=False)
class BodyModel:
    """Model data, loaded once. Shapes: V vertices, F faces, C stored components, J=4.

    Attributes:
        mean_vertices: (V, 3) float32, metres, model frame; rest (A-pose) mean body.
        mean_joints: (4, 3) float32, metres; rig joints (shoulders, hips) of the mean body,
            in ``POSE_NAMES`` order.
        vertex_components: (C, V, 3) float32; orthonormal PCA directions (vertex part),
            sorted by decreasing eigenvalue.
        joint_components: (C, 4, 3) float32; the joint part of the same directions.
        eigenvalues: (C,) float64, m^2; variance of the model's sample along each direction.
        faces: (F, 3) int32; triangles, counter-clockwise seen from outside.
        vertex_parts: (V,) int8; index into ``PART_NAMES``.
        chain_weights: (V, 4) float32 in [0, 1]; skinning weight of each vertex on each
            moving chain (left arm, right arm, left leg, right leg); rows sum to <= 1.
        landmarks: name -> (n,) int32 vertex indices used by the measurements.
        sample_betas: (N, C) float32; the shape coefficients (in sigma) of the N
            bodies the space was learned from.
        sample_sex: (N,) int8; 0 man, 1 woman.
        sample_measurements: (N, 16) float32, mm; their measurements, keys A..P.
        metadata: how the model was built (anny version, seed, samples, timings).
    """

    mean_vertices: np.ndarray
    mean_joints: np.ndarray
    vertex_components: np.ndarray
    joint_components: np.ndarray
    eigenvalues: np.ndarray
    faces: np.ndarray
    vertex_parts: np.ndarray
    chain_weights: np.ndarray
    landmarks: dict[str, np.ndarray]
    sample_betas: np.ndarray
    sample_sex: np.ndarray
    sample_measurements: np.ndarray
    metadata: dict

    @property
    def num_vertices(self) -> int:
        return self.mean_vertices.shape[0]

    @property
    def num_components(self) -> int:
        return self.eigenvalues.shape[0]

    @property
    def face_parts(self) -> np.ndarray:
        """(F,) int8: part of each face, the part most of its three vertices carry
        (the first vertex's part on a three-way tie)."""
        p = self.vertex_parts[self.faces]
        return np.where(p[:, 1] == p[:, 2], p[:, 1], p[:, 0]).astype(np.int8)

    def shape_directions(self, num_components: int) -> tuple[np.ndarray, np.ndarray]:
        """Components scaled by their standard deviation, for betas in units of sigma.

        Returns:
            vertex_dirs: (K, V, 3) float32, metres per sigma.
            joint_dirs: (K, 4, 3) float32, metres per sigma.
        """
        if not 1 <= num_components <= self.num_components:
            raise UserError(
                f"the body model stores {self.num_components} shape components; "
                f"asked for {num_components}. Rebuild it with `fitter model build --components N`."
            )
        return _scaled_directions(self, num_components)

    # ----------------------------------------------------------------- file I/O
    def save(self, path: Path) -> None:
        """Write a compressed .npz atomically (a temporary file, then a rename)."""
        path = Path(path)
        arrays = {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if f.name not in ("landmarks", "metadata")
        }
        arrays.update({f"landmark:{k}": v for k, v in self.landmarks.items()})
        meta = dict(self.metadata, format_version=FORMAT_VERSION)
        arrays["metadata_json"] = np.array(json.dumps(meta))
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **arrays)
        write_atomic(path, buffer.getvalue())

    @classmethod
    def load(cls, path: Path) -> "BodyModel":
        """Read a model written by :meth:`save`.

        Raises:
            UserError: the file is missing, unreadable, of another format version, or
                its arrays are inconsistent.
        """
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as npz:
                files = dict(npz.items())
        except FileNotFoundError:
            raise UserError(f"no body model at {path}; run `fitter model build`") from None
        except IsADirectoryError:
            raise UserError(f"body model path {path} is a folder, not a model file") from None
        except Exception:  # zip, pickle and value errors: all mean "corrupt". numpy's own
            # message may advise allow_pickle=True, which must never be followed here.
            raise UserError(f"body model file {path} is corrupt (not a model .npz); "
                            "run `fitter model build` to rebuild it") from None
        try:
            meta = json.loads(str(files.pop("metadata_json")))
            if meta.get("format_version") != FORMAT_VERSION:
                raise UserError(
                    f"body model {path} has format {meta.get('format_version')}, this "
                    f"bodyfit reads {FORMAT_VERSION}; run `fitter model build`")
            landmarks = {k.split(":", 1)[1]: files.pop(k)
                         for k in list(files) if k.startswith("landmark:")}
            files, meta = _today_names(files, meta)
            model = cls(**files, landmarks=landmarks, metadata=meta)
        except (KeyError, TypeError, ValueError) as exc:
            raise UserError(f"body model file {path} is incomplete ({exc}); "
                            "run `fitter model build` to rebuild it") from None
        model.validate()
        return model

    def validate(self) -> None:
        """Check that the arrays agree in shape; raise UserError naming the first that doesn't."""
        v, c = self.num_vertices, self.num_components
        expected = {
            "mean_vertices": (v, 3),
            "mean_joints": (4, 3),
            "vertex_components": (c, v, 3),
            "joint_components": (c, 4, 3),
            "eigenvalues": (c,),
            "vertex_parts": (v,),
            "chain_weights": (v, 4),
            "sample_betas": (len(self.sample_sex), c),
            "sample_measurements": (len(self.sample_sex), 16),
        }
        for name, shape in expected.items():
            if getattr(self, name).shape != shape:
                raise UserError(f"body model array {name} has shape "
                                f"{getattr(self, name).shape}, expected {shape}; "
                                "run `fitter model build` to rebuild it")
        if self.faces.ndim != 2 or self.faces.shape[1] != 3 or self.faces.max() >= v:
            raise UserError("body model faces are inconsistent; run `fitter model build`")


@functools.lru_cache(maxsize=8)
def _scaled_directions(model: BodyModel, num_components: int) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`BodyModel.shape_directions`, computed once per model and K (read-only
    arrays): a fit's forward passes ask for them hundreds of times (the local solver's
    each iteration, the stature conditioner's each candidate), and scaling 40 components
    of the mesh costs a few milliseconds each time. A model is hashed by its identity
    (``eq=False``)."""
    std = np.sqrt(model.eigenvalues[:num_components]).astype(np.float32)[:, None, None]
    vertex_dirs = model.vertex_components[:num_components] * std
    joint_dirs = model.joint_components[:num_components] * std
    vertex_dirs.setflags(write=False)
    joint_dirs.setflags(write=False)
    return vertex_dirs, joint_dirs


def _today_names(files: dict[str, np.ndarray], meta: dict) -> tuple[dict, dict]:
    """A model file's arrays and metadata under today's names: files written before the
    bodies the model is built from were called its sample (the shipped model among them)
    name them its population (the optimisers' word for their candidates)."""
    files = {name.replace("population_", "sample_", 1) if name.startswith("population_")
             else name: array for name, array in files.items()}
    if "population" in meta.get("settings", {}):
        settings = dict(meta["settings"])
        settings["sampling"] = settings.pop("population")
        meta = dict(meta, settings=settings)
    if "population" in meta.get("timings_s", {}):
        timings = dict(meta["timings_s"])
        timings["sample"] = timings.pop("population")
        meta = dict(meta, timings_s=timings)
    return files, meta


def project_shape(model: BodyModel, vertices: np.ndarray, joints: np.ndarray,
                  num_components: int) -> np.ndarray:
    """The inverse of :func:`rest_shape`: betas of the closest bodies of the space.

    Orthogonal projection onto the first ``num_components`` components (least squares over
    vertices and joints together), i.e. the best reconstruction the space allows.

    Args:
        vertices: (N, V, 3) float, metres, rest pose, model frame.
        joints: (N, 4, 3) float, metres, rig joints.

    Returns:
        (N, num_components) float64 betas in units of standard deviation.
    """
    k = num_components
    x = np.concatenate([(vertices - model.mean_vertices).reshape(len(vertices), -1),
                        (joints - model.mean_joints).reshape(len(joints), -1)], axis=1)
    comps = np.concatenate([model.vertex_components[:k].reshape(k, -1),
                            model.joint_components[:k].reshape(k, -1)], axis=1)
    return (x.astype(np.float64) @ comps.T.astype(np.float64)) / np.sqrt(model.eigenvalues[:k])
