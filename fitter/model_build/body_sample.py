"""The model's sample: realistic adult Anny bodies, measured like ANSUR II.

The paper's S-SCAPE space was learned from thousands of real scans. Sampling Anny's
parameters independently spreads variance over combinations no human has, and then 20
PCA components miss much of it. So every body here is *fitted to a real-looking set of
measurements*:

1. targets: a draw from a multivariate normal with ANSUR II's per-sex means, standard
   deviations and correlations (``data/ansur2_stats.json``, z-scores clipped at +-3) of
   13 measurements (all of the paper's 16 but C, which ANSUR lacks, and the bicep and
   forearm girths, which ANSUR takes flexed); with ``SamplingSettings.girth_spread``
   (``fitter model build --girth-spread``) the circumferences' z-scores are multiplied by
   it, for bodies beyond the soldiers' range (at 1.5 BodyM's real people were fitted no
   better: docs/accuracy.md, "Reach");
2. a random start in Anny's parameters (phenotypes near the middle of their range,
   local changes near 0: the variation of what ANSUR does not constrain);
3. quasi-Newton steps that move the parameters the least (in units of their scale)
   to hit the targets, within the parameters' bounds: a linear map parameters
   -> measurements per sex, fitted by least squares on a pool of bodies, refined per
   body by Broyden updates; each body keeps its best evaluated parameters.

A body is thus an Anny body whose measurements follow ANSUR II's joint distribution.
"""

from __future__ import annotations

import dataclasses
import json
import logging
from importlib import resources

import numpy as np
from scipy.optimize import lsq_linear

from bodyfit.fitter.measure.measurements import MEASUREMENTS, Measurer
from bodyfit.fitter.model_build.anny_source import PHENOTYPES, SHAPE_PARAMETERS, AnnySource

__all__ = ["SEXES", "TARGET_KEYS", "GIRTH_TARGETS", "ReferenceStats", "SamplingSettings",
           "BodySample", "BodySampler", "ANNY_GENDER"]

logger = logging.getLogger(__name__)

SEXES = ("male", "female")
#: Anny's gender phenotype of each sex.
ANNY_GENDER = {"male": 0.0, "female": 1.0}
#: Measurements the sample's bodies are fitted to (see the module docstring).
TARGET_KEYS = ("A", "B", "D", "E", "F", "G", "J", "K", "L", "M", "N", "O", "P")
#: The targets' circumferences (all but the head's): what a body's build widens.
GIRTH_TARGETS = ("B", "D", "E", "F", "G", "L", "M", "N")
_KEYS = list(MEASUREMENTS)

#: Centre, scale and bounds of each Anny parameter. Start values are drawn around the
#: centre with this scale (local changes: ``SamplingSettings.local_change_spread``), and
#: fitting steps are measured in it. Anny's age 0.77-0.83 spans 18 to 64 years.
_PRIOR = {"age": (0.80, 0.015, 0.77, 0.83)} | {
    p: (0.5, 0.15, 0.0, 1.0) for p in PHENOTYPES if p != "age"}
_LOCAL_PRIOR = (0.0, 0.2, -1.0, 1.0)


def _prior_table() -> np.ndarray:
    """(4, D) rows centre, scale, lower bound, upper bound per ``SHAPE_PARAMETERS``."""
    return np.array([_PRIOR.get(p, _LOCAL_PRIOR) for p in SHAPE_PARAMETERS]).T


@dataclasses.dataclass(frozen=True)
class ReferenceStats:
    """Per-sex statistics of real adults (ANSUR II), millimetres.

    Attributes:
        keys: measurement keys of the columns.
        mean, std: sex -> (k,) float64.
        correlation: sex -> (k, k) float64.
        n: sex -> subjects.
    """

    keys: tuple[str, ...]
    mean: dict[str, np.ndarray]
    std: dict[str, np.ndarray]
    correlation: dict[str, np.ndarray]
    n: dict[str, int]

    @classmethod
    def load(cls) -> "ReferenceStats":
        """The ANSUR II table shipped in ``bodyfit.fitter.data``."""
        text = resources.files("bodyfit.fitter.data").joinpath("ansur2_stats.json").read_text()
        table = json.loads(text)
        sexes = table["sexes"]
        return cls(
            keys=tuple(table["keys"]),
            mean={s: np.array(sexes[s]["mean"]) for s in SEXES},
            std={s: np.array(sexes[s]["std"]) for s in SEXES},
            correlation={s: np.array(sexes[s]["correlation"]) for s in SEXES},
            n={s: int(sexes[s]["n"]) for s in SEXES},
        )

    def subset(self, keys) -> "ReferenceStats":
        idx = [self.keys.index(k) for k in keys]
        return ReferenceStats(tuple(keys), {s: m[idx] for s, m in self.mean.items()},
                              {s: m[idx] for s, m in self.std.items()},
                              {s: c[np.ix_(idx, idx)] for s, c in self.correlation.items()},
                              dict(self.n))

    def covariance(self, sex: str) -> np.ndarray:
        """(k, k) float64: the covariance of ``sex``'s columns, mm^2 (kg^2 for a mass)."""
        return self.correlation[sex] * np.outer(self.std[sex], self.std[sex])

    def sample(self, sex: str, n: int, rng: np.random.Generator,
               widen: np.ndarray | float = 1.0) -> np.ndarray:
        """(n, k) float64 mm: multivariate normal draws, z-scores clipped at +-3, then
        multiplied by ``widen`` ((k,) or one factor; 1: each column as wide as the table's)."""
        z = rng.multivariate_normal(np.zeros(len(self.keys)), self.correlation[sex], size=n)
        return self.mean[sex] + np.clip(z, -3.0, 3.0) * widen * self.std[sex]


@dataclasses.dataclass(frozen=True)
class SamplingSettings:
    """How the sample is drawn (recorded in the model's metadata)."""

    iterations: int = 4  # Gauss-Newton steps per body
    pool_per_sex: int = 400  # bodies for the linear map parameters -> measurements
    measurement_weight_sd: float = 0.05  # a miss of this many ANSUR SDs costs as much as
    # moving one parameter by its scale
    local_change_spread: float = 0.1  # SD of the local changes' start values: the
    # variation the fitted measurements leave free (0.2 doubles the K=20 floor, docs/model.md)
    girth_spread: float = 1.0  # the targets' circumferences (GIRTH_TARGETS) spread this
    # many times ANSUR II's soldiers' (their z-scores multiplied): bodies beyond them


@dataclasses.dataclass(frozen=True)
class BodySample:
    """Bodies drawn by :class:`BodySampler`, all arrays row-aligned.

    Attributes:
        sex: (N,) str, "male" or "female".
        params: (N, D) float64 Anny parameters, ``SHAPE_PARAMETERS`` order.
        vertices: (N, V, 3) float32, metres, rest A-pose.
        joints: (N, 4, 3) float32, metres, rig joints.
        measurements: (N, 16) float64 mm, ``MEASUREMENTS`` order.
    """

    sex: np.ndarray
    params: np.ndarray
    vertices: np.ndarray
    joints: np.ndarray
    measurements: np.ndarray


class BodySampler:
    """Draws ANSUR-like Anny bodies (see the module docstring)."""

    def __init__(self, source: AnnySource, measurer: Measurer,
                 settings: SamplingSettings = SamplingSettings()) -> None:
        self.source = source
        self.measurer = measurer
        self.settings = settings
        self.stats = ReferenceStats.load().subset(TARGET_KEYS)
        self._prior = _prior_table()
        is_local = np.array([p not in PHENOTYPES for p in SHAPE_PARAMETERS])
        self._start_spread = np.where(is_local, settings.local_change_spread, self._prior[1])
        self._target_cols = [_KEYS.index(k) for k in TARGET_KEYS]

    def _start(self, n: int, rng: np.random.Generator, widen: float = 1.0) -> np.ndarray:
        """(n, D) draws of the start distribution, its spread multiplied by ``widen``."""
        centre, _, lo, hi = self._prior
        noise = rng.standard_normal((n, len(centre))) * self._start_spread * widen
        return np.clip(centre + noise, lo, hi)

    def _bodies(self, sex: str, params: np.ndarray, progress=None):
        gender = np.full(len(params), ANNY_GENDER[sex])
        vertices, joints = self.source.rest_bodies(gender, params)
        measured = self.measurer.measure_many(vertices)
        if progress is not None:
            progress.update(len(params))
        return vertices, joints, measured

    @staticmethod
    def _regress(params: np.ndarray, measured: np.ndarray) -> np.ndarray:
        """(k, D) least-squares slopes of ``measured`` (n, k) on ``params`` (n, D)."""
        keep = np.all(np.isfinite(measured), axis=1)
        design = np.hstack([np.ones((keep.sum(), 1)), params[keep]])
        coef, *_ = np.linalg.lstsq(design, measured[keep], rcond=None)
        return coef[1:].T

    def work_units(self, counts: dict[str, int]) -> int:
        """How many units :meth:`sample` reports to its ``progress``: one per body built
        and measured and one per fitting step solved."""
        iterations = self.settings.iterations
        return sum(self.settings.pool_per_sex + (2 * iterations + 1) * n
                   for n in counts.values() if n > 0)

    def sample(self, counts: dict[str, int], seed: int, progress=None) -> BodySample:
        """Draw ``counts[sex]`` bodies of each sex, reproducibly from ``seed``.

        ``progress``, if given, is told of the work done by ``progress.update(units)``
        (a tqdm bar; :meth:`work_units` units in all)."""
        parts = []
        for i, sex in enumerate(SEXES):
            if counts.get(sex, 0) > 0:
                rng = np.random.default_rng([seed, i])
                parts.append(self._sample_sex(sex, counts[sex], rng, progress))
        return BodySample(*(np.concatenate([getattr(p, f.name) for p in parts])
                            for f in dataclasses.fields(BodySample)))

    def _sample_sex(self, sex: str, n: int, rng: np.random.Generator,
                    progress=None) -> BodySample:
        # One linear map from a pool spread wider than the start distribution, then
        # refined per body by Broyden's rank-one updates along the steps it takes.
        pool = self._start(self.settings.pool_per_sex, rng, widen=2.0)
        jac = self._regress(pool, self._bodies(sex, pool, progress)[2][:, self._target_cols])
        jacobians = np.repeat(jac[None], n, axis=0)  # (n, k, D) mm per parameter unit
        widen = np.where(np.isin(TARGET_KEYS, GIRTH_TARGETS), self.settings.girth_spread, 1.0)
        targets = self.stats.sample(sex, n, rng, widen)
        start = self._start(n, rng)
        _, scale, lo, hi = self._prior
        # whitened least squares: rows scaled by 1 / (w * ANSUR SD), columns by the scale
        row_scale = 1.0 / (self.settings.measurement_weight_sd * self.stats.std[sex])
        params = start.copy()
        previous = None
        best = None  # per body, the evaluated parameters with the lowest objective so far
        for it in range(self.settings.iterations + 1):
            vertices, joints, meas = self._bodies(sex, params, progress)
            measured = meas[:, self._target_cols]
            residual = targets - measured
            objective = (np.sum(np.nan_to_num(row_scale * residual, nan=1e6) ** 2, axis=1)
                         + np.sum(((params - start) / scale) ** 2, axis=1))
            if best is None:
                best = [objective, params.copy(), vertices, joints, meas]
            else:
                better = objective < best[0]
                for store, new in zip(best, (objective, params, vertices, joints, meas)):
                    store[better] = new[better]
            miss = np.nanmean(np.abs(targets - best[4][:, self._target_cols]), axis=0)
            logger.info("%s bodies, step %d of %d: mean miss of the ANSUR targets (mm): %s",
                        sex, it, self.settings.iterations,
                        ", ".join(f"{MEASUREMENTS[k][0].removesuffix('_circumference')} {m:.1f}"
                                  for k, m in zip(TARGET_KEYS, miss)))
            if it == self.settings.iterations:
                break
            if previous is not None:
                self._broyden(jacobians, params - previous[0], measured - previous[1])
            previous = (params.copy(), measured)
            residual = np.nan_to_num(residual)
            for b in range(n):
                # the step u (in parameter scales) minimising |a u - r|^2 + |u + offset|^2
                # inside the parameter bounds
                a = row_scale[:, None] * jacobians[b] * scale[None, :]
                offset = (params[b] - start[b]) / scale
                step = lsq_linear(np.vstack([a, np.eye(len(scale))]),
                                  np.concatenate([row_scale * residual[b], -offset]),
                                  bounds=((lo - params[b]) / scale,
                                          (hi - params[b]) / scale)).x
                params[b] = np.clip(params[b] + step * scale, lo, hi)
                if progress is not None:
                    progress.update(1)
        _, params, vertices, joints, meas = best
        return BodySample(np.full(n, sex), params, vertices, joints, meas)

    @staticmethod
    def _broyden(jacobians: np.ndarray, dx: np.ndarray, dm: np.ndarray) -> None:
        """Rank-one update J += (dm - J dx) dx^T / |dx|^2 of each body's Jacobian, in place,
        where a body moved (``dx`` (n, D)) and its measurements are finite (``dm`` (n, k))."""
        norm2 = np.einsum("nd,nd->n", dx, dx)
        ok = (norm2 > 1e-12) & np.all(np.isfinite(dm), axis=1)
        pred = np.einsum("nkd,nd->nk", jacobians[ok], dx[ok])
        jacobians[ok] += np.einsum("nk,nd->nkd", dm[ok] - pred, dx[ok]) / norm2[ok, None, None]
