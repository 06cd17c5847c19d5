"""Building the body model from Anny: topology, parts, landmarks, the sample, PCA.

Steps (docs/model.md):

1. Anny's mesh (main component), skinning weights aggregated per bone group and per
   moving chain (:mod:`bodyfit.fitter.model_build.anny_source`);
2. part labels and measurement landmarks on a neutral template body
   (:mod:`bodyfit.fitter.model_build.parts`);
3. a seeded sample of adults, half men and half women, whose measurements follow
   ANSUR II's (:mod:`bodyfit.fitter.model_build.body_sample`);
4. PCA over each body's rest vertices and rig joints stacked into one vector, so the
   joints are linear in the shape coefficients too (``x = mean + A @ beta``).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from bodyfit.fitter.measure.measurements import Measurer
from bodyfit.fitter.model.body_model import BodyModel
from bodyfit.fitter.model.cache import model_path
from bodyfit.fitter.model_build import parts
from bodyfit.fitter.model_build.anny_source import SHAPE_PARAMETERS, AnnySource
from bodyfit.fitter.model_build.body_sample import SEXES, BodySampler, SamplingSettings

__all__ = ["ModelBuildSettings", "build_model", "build_and_save", "template_body",
           "principal_components"]

logger = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class ModelBuildSettings:
    """What ``fitter model build`` takes; written into the model's metadata."""

    components: int = 60  # PCA components stored (the fitter uses 20 by default)
    samples: int = 3000  # bodies in the sample, half men, half women
    seed: int = 0
    sampling: SamplingSettings = SamplingSettings()

    @classmethod
    def of(cls, model: BodyModel) -> "ModelBuildSettings":
        """The settings a model was built with (from its metadata)."""
        recorded = dict(model.metadata["settings"])
        recorded["sampling"] = SamplingSettings(**recorded["sampling"])
        return cls(**recorded)

    def validate(self) -> None:
        from bodyfit.common.errors import UserError

        if self.samples < 100 or self.samples % 2:
            raise UserError(f"--samples must be an even number >= 100, got {self.samples}")
        if not 1 <= self.components < self.samples:
            raise UserError(f"--components must be between 1 and the number of samples "
                            f"({self.samples}), got {self.components}")
        if not self.sampling.girth_spread > 0:
            raise UserError(f"--girth-spread must be above 0, got {self.sampling.girth_spread}")


def template_body(source: AnnySource) -> tuple[np.ndarray, np.ndarray]:
    """Anny's neutral adult (gender 0.5, mid phenotypes, no local changes).

    Returns:
        vertices: (V, 3) float32, metres; joints: (4, 3) float32, metres.
    """
    params = np.zeros((1, len(SHAPE_PARAMETERS)))
    for i, name in enumerate(SHAPE_PARAMETERS[:5]):
        params[0, i] = 0.8 if name == "age" else 0.5
    vertices, joints = source.rest_bodies(np.array([0.5]), params)
    return vertices[0], joints[0]


def principal_components(shapes: np.ndarray, count: int, chunk: int = 4096):
    """PCA of row vectors through the Gram matrix (cheap when rows << columns).

    Accumulates in float64 over column chunks, so the small trailing components stay
    orthonormal without holding a float64 copy of the data.

    Args:
        shapes: (N, D) float32 data, one body per row.
        count: components to keep.

    Returns:
        mean: (D,) float64; components: (count, D) float32 orthonormal rows;
        eigenvalues: (count,) float64, variance along each component (unbiased);
        scores: (N, count) float64, each row's coefficients in units of standard
        deviation (the Gram eigenvectors scaled by sqrt(N - 1)).
    """
    n, d = shapes.shape
    mean = shapes.mean(axis=0, dtype=np.float64)
    gram = np.zeros((n, n))
    for start in range(0, d, chunk):
        block = shapes[:, start:start + chunk] - mean[start:start + chunk]
        gram += block @ block.T
    eigval, eigvec = np.linalg.eigh(gram)
    order = np.argsort(eigval)[::-1][:count]
    eigval, eigvec = np.maximum(eigval[order], 1e-30), eigvec[:, order]
    components = np.empty((count, d))
    for start in range(0, d, chunk):
        block = shapes[:, start:start + chunk] - mean[start:start + chunk]
        components[:, start:start + chunk] = eigvec.T @ block
    components /= np.sqrt(eigval)[:, None]
    return mean, components.astype(np.float32), eigval / (n - 1), eigvec * np.sqrt(n - 1)


def build_model(settings: ModelBuildSettings = ModelBuildSettings(),
                progress: bool | None = None) -> BodyModel:
    """Build the body model (about four minutes on two CPU cores for the defaults).

    ``progress``: show a progress bar with the time left on stderr (None: only when
    stderr is a terminal)."""
    settings.validate()
    t0 = time.perf_counter()
    logger.info("loading Anny (a first build fills its data cache, about 1.1 GB)")
    source = AnnySource()
    topo = source.topology
    template, template_joints = template_body(source)
    marks = parts.landmarks(template, topo.group_weights, template_joints[:2])
    labels = parts.part_labels(template, topo.group_weights, marks)
    measurer = Measurer(topo.faces, marks, labels)
    t_setup = time.perf_counter()

    sampler = BodySampler(source, measurer, settings.sampling)
    half = settings.samples // 2
    counts = {"male": half, "female": half}
    with tqdm(total=sampler.work_units(counts), desc="sample: bodies made, measured, fitted",
              unit="step", disable=None if progress is None else not progress,
              dynamic_ncols=True) as bar:
        sample = sampler.sample(counts, seed=settings.seed, progress=bar)
    t_sample = time.perf_counter()
    logger.info("principal components of %d bodies", settings.samples)

    n, v = sample.vertices.shape[:2]
    shapes = np.concatenate([sample.vertices.reshape(n, -1),
                             sample.joints.reshape(n, -1)], axis=1)
    mean, components, eigenvalues, betas = principal_components(shapes, settings.components)
    t_pca = time.perf_counter()

    c = settings.components
    metadata = {
        "builder": "bodyfit.fitter.model_build.builder",
        "anny_version": source.anny_version,
        "settings": dataclasses.asdict(settings),
        "shape_parameters": list(SHAPE_PARAMETERS),
        "explained_variance": float(eigenvalues.sum() / (shapes.var(axis=0, ddof=1).sum())),
        "timings_s": {"setup": round(t_setup - t0, 2),
                      "sample": round(t_sample - t_setup, 2),
                      "pca": round(t_pca - t_sample, 2),
                      "total": round(t_pca - t0, 2)},
    }
    model = BodyModel(
        mean_vertices=mean[: v * 3].reshape(v, 3).astype(np.float32),
        mean_joints=mean[v * 3:].reshape(4, 3).astype(np.float32),
        vertex_components=np.ascontiguousarray(components[:, : v * 3].reshape(c, v, 3)),
        joint_components=np.ascontiguousarray(components[:, v * 3:].reshape(c, 4, 3)),
        eigenvalues=eigenvalues,
        faces=topo.faces,
        vertex_parts=labels,
        chain_weights=topo.chain_weights,
        landmarks=marks,
        sample_betas=betas.astype(np.float32),
        sample_sex=np.array([SEXES.index(s) for s in sample.sex], np.int8),
        sample_measurements=sample.measurements.astype(np.float32),
        metadata=metadata,
    )
    model.validate()
    return model


def build_and_save(settings: ModelBuildSettings = ModelBuildSettings(),
                   path: Path | None = None, progress: bool | None = None) -> BodyModel:
    """Build the model and write it to ``path`` (default: the cache, where
    :func:`~bodyfit.fitter.model.cache.load_model` prefers it to the shipped one);
    ``progress`` as in :func:`build_model`."""
    path = Path(path) if path is not None else model_path()
    model = build_model(settings, progress=progress)
    model.save(path)
    return model
