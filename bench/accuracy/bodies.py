"""The accuracy benchmark's bodies, half women and half men, and their poses.

Two kinds (``KINDS``):

- ``"in-space"``: bodies of the fitter's own K-component space, as the paper draws its
  subjects from S-SCAPE: betas from a normal distribution with the mean and covariance of
  the model's sample of each sex (its first K coefficients), each clipped at +-3
  sigma. The fit can reproduce them exactly.
- ``"out-of-space"``: full Anny bodies (every phenotype and local change), drawn as the
  model's sample was (:class:`~bodyfit.fitter.model_build.body_sample.BodySampler`:
  measurements like ANSUR II's) with another seed; a share of them (``hard_share``) drawn
  from a start distribution three times wider (phenotypes near the ends of their ranges,
  local changes three times larger) before the same fit to ANSUR-like measurements.
  The K-component space reproduces none of them exactly. Needs the ``anny`` package and
  its data cache (about 1.1 GB, built on first use).
- ``"standing"``: out-of-space bodies of another draw, posed as people stand by Anny's
  whole skeleton (:mod:`.stances`): their Anny parameters are kept, for the photos.

Poses of the first two kinds: the front photo's four abduction angles are drawn uniformly from ``abduction_deg``;
out-of-space bodies also bend each limb forward or back by up to ``flexion_deg`` in the
front photo, a motion the model's rig cannot make. The side photo hangs the arms down
(shoulders at the body's own arms-down angle,
:func:`~bodyfit.fitter.fit.side_arms.arms_down_angle`), the legs at the front photo's
abduction, no flexion (the issue's protocol: angles varied in the front photo, the arms
down in the side photo; legs bent differently in a side photo would show as thicker
calves and thighs).

Units: metres, model frame (z up, -y forward); degrees.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bench.accuracy.stances import StanceSettings, draw_stances
from bodyfit.fitter.fit.side_arms import arms_down_angle
from bodyfit.fitter.model.body_model import BodyModel, rest_shape
from bodyfit.fitter.model.limb_bends import bent_bodies, flexion_rotations, turned_bodies
from bodyfit.fitter.model_build.body_sample import BodySampler, SamplingSettings

__all__ = ["KINDS", "SEXES", "Bodies", "bent_bodies", "draw_bodies", "flexion_rotations",
           "pose_bodies", "turned_bodies"]  # the bends re-exported from the model

KINDS = ("in-space", "out-of-space", "standing")
#: + the set's seed: seeds the model's own sample never used, so that none of these bodies
#: was learned from, and the two kinds' bodies differ
_ANNY_SEED = {"out-of-space": 1_000_003, "standing": 2_000_003}
SEXES = ("female", "male")
#: How much wider the out-of-space hard share's start distribution is.
HARD_WIDEN = 3.0


@dataclasses.dataclass(frozen=True)
class Bodies:
    """N rest bodies with their photo poses, row-aligned.

    Attributes:
        sex: (N,) str, ``SEXES``.
        hard: (N,) bool, drawn from the wider start distribution (out-of-space only).
        vertices: (N, V, 3) float32, rest A-pose; joints: (N, 4, 3) float32, rig joints.
        abduction_deg: (N, 4) front photo's abduction angles, ``POSE_NAMES`` order.
        flexion_deg: (N, 4) each chain's forward (+) or backward bend, both photos.
        anny_params: (N, D) float64 each body's Anny parameters (``SHAPE_PARAMETERS``
            order; ``standing`` only, else (N, 0)).
        stances: ``standing`` only, :func:`.stances.draw_stances`' arrays (else empty).
    """

    sex: np.ndarray
    hard: np.ndarray
    vertices: np.ndarray
    joints: np.ndarray
    abduction_deg: np.ndarray
    flexion_deg: np.ndarray
    anny_params: np.ndarray
    stances: dict[str, np.ndarray]


def draw_bodies(model: BodyModel, kind: str, count: int, seed: int, *, num_components: int = 20,
                hard_share: float = 0.2, abduction_deg: tuple[float, float] = (2.0, 8.0),
                flexion_deg: float = 4.0, pool_per_sex: int = 400,
                stance: StanceSettings = StanceSettings(), progress=None) -> Bodies:
    """``count`` bodies of ``kind`` (even: women and men alternately), reproducibly from
    ``seed``. Anny's kinds only: ``pool_per_sex``, the bodies the sampler's
    first linear map is fitted on (``SamplingSettings.pool_per_sex``; fewer is quicker
    and fits the ANSUR targets less closely); ``progress``, a tqdm bar or None.
    ``standing`` only: ``stance``, its poses' ranges."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    if count < 2 or count % 2:
        raise ValueError(f"count must be an even number >= 2, got {count}")
    rng = np.random.default_rng([seed, KINDS.index(kind)])
    per_sex = count // 2
    sex = np.repeat(SEXES, per_sex)  # drawn women first, then interleaved (below)
    hard = np.zeros(count, bool)
    params = np.zeros((count, 0))
    if kind == "in-space":
        vertices, joints = rest_shape(model, _in_space_betas(model, sex, num_components, rng))
        flexion = np.zeros((count, 4))
    else:
        hard_per_sex = int(round(per_sex * hard_share))
        hard[:hard_per_sex] = hard[per_sex:per_sex + hard_per_sex] = True
        vertices, joints, anny_params = _anny_bodies(
            model, per_sex, hard_per_sex, _ANNY_SEED[kind] + seed,
            SamplingSettings(pool_per_sex=pool_per_sex), progress)
        flexion = rng.uniform(-flexion_deg, flexion_deg, (count, 4))
        if kind == "standing":
            params = anny_params
    abduction = rng.uniform(*abduction_deg, (count, 4))
    # woman, man, woman, ... each sex in random order: any first 2n subjects are n women
    # and n men, with the hard share spread among them
    order = np.stack([rng.permutation(per_sex), per_sex + rng.permutation(per_sex)],
                     axis=1).ravel()
    stances = draw_stances(stance, count, rng) if kind == "standing" else {}
    return Bodies(sex[order], hard[order], vertices[order], joints[order], abduction[order],
                  flexion[order], params[order], stances)


def _in_space_betas(model: BodyModel, sex: np.ndarray, num_components: int,
                    rng: np.random.Generator) -> np.ndarray:
    betas = np.zeros((len(sex), num_components))
    for code, name in ((0, "male"), (1, "female")):  # sample_sex: 0 man, 1 woman
        pool = model.sample_betas[model.sample_sex == code, :num_components].astype(float)
        pick = sex == name
        betas[pick] = rng.multivariate_normal(pool.mean(axis=0), np.cov(pool.T), pick.sum())
    return np.clip(betas, -3.0, 3.0)


def _anny_bodies(model: BodyModel, per_sex: int, hard_per_sex: int, base: int,
                 settings: SamplingSettings, progress):
    """(vertices, joints, Anny parameters) of full Anny bodies, women then men, each sex's
    hard share first (module docstring), drawn from seeds ``base``, ``base + 1``."""
    from bodyfit.fitter.measure.measurements import Measurer
    from bodyfit.fitter.model_build.anny_source import AnnySource
    class WideSampler(BodySampler):
        def _start(self, n, rng, widen=1.0):
            return super()._start(n, rng, widen * HARD_WIDEN)

    source = AnnySource()
    if not np.array_equal(source.topology.faces, model.faces):
        raise ValueError("the body model's mesh is not this Anny version's: rebuild it with "
                         "`fitter model build`")
    measurer = Measurer.from_model(model)
    drawn = {}
    for name, sampler_class, counts in (
            ("hard", WideSampler, hard_per_sex),
            ("usual", BodySampler, per_sex - hard_per_sex)):
        if counts:
            sampler = sampler_class(source, measurer, settings)
            drawn[name] = sampler.sample({"male": counts, "female": counts},
                                         seed=base + len(drawn), progress=progress)
    parts = [(drawn[name], drawn[name].sex == sex) for sex in SEXES
             for name in ("hard", "usual") if name in drawn]
    return tuple(np.concatenate([getattr(sample, field)[pick] for sample, pick in parts])
                 for field in ("vertices", "joints", "params"))


def pose_bodies(model: BodyModel, bodies: Bodies, index: int) -> tuple[np.ndarray, np.ndarray]:
    """(front, side) posed vertices (V, 3) float32 of body ``index``: the front photo's
    pose (abduction and flexion), and the side photo's (arms hanging down, no flexion)."""
    rest, joints = bodies.vertices[index], bodies.joints[index]
    front = bodies.abduction_deg[index].astype(float)
    side = front.copy()
    side[:2] = arms_down_angle(model, rest, joints)
    posed = bent_bodies(model, rest, joints, np.stack([front, side]),
                        np.stack([bodies.flexion_deg[index], np.zeros(4)]))
    return posed[0], posed[1]
