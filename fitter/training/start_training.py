"""Training the learned start (:mod:`bodyfit.fitter.fit.learned_start`): bodies the project
draws and photographs itself, posed and photographed with more variation than the
fitter's own poses, and a ridge regression from their silhouettes to their shapes.

The bodies (:func:`training_bodies`): half from the model's own sample (Anny bodies with
measurements like ANSUR II's, projected into its space, ``BodyModel.sample_betas``), half
drawn from a normal distribution with each sex's mean and covariance of that sample
(the in-space kind); each clipped at +-3 sigma, the fitter's space
(``SearchSettings.beta_limit``). Random numbers come from
``numpy.random.default_rng([seed, TRAINING_STREAM])``, a stream the accuracy benchmark
never draws from (it draws from ``[seed, kind]`` with kind 0 or 1, and Anny from seeds
above 1,000,000).

Each body is photographed twice (:func:`photographed_masks`):

- **front**: each limb abducted by a random angle of ``front_arms_deg`` /
  ``front_legs_deg`` and swung forward or back by up to ``flexion_deg`` (a motion the
  rig cannot make, :mod:`bodyfit.fitter.model.limb_bends`);
- **side**: the arms hanging at the body's own arms-down angle +- ``side_arms_deg``,
  swung by up to ``flexion_deg``, the legs as in the front photo;
- **cameras**: a phone's pinhole (:func:`~bodyfit.fitter.fit.pinhole_canvas.phone_intrinsics`,
  the focal length scaled by up to ``focal_spread``) at a random distance, height and
  sideways offset, pitched and rolled as a hand holds it; a photo that cuts the body
  off is drawn again. The person's pixels are those whose centre the body covers
  (:func:`bodyfit.fitter.output.render.centre_samples`).

The ridge's strength is chosen on a tenth of the bodies held out, and its errors there
are recorded in the weights' metadata: the components and angles, and the 7 important
measurements (mm) of the start's body made the stature tall (its first component solved,
:mod:`bodyfit.fitter.fit.stature`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.canvas import extreme_bodies
from bodyfit.fitter.fit.learned_start import (SEX_CODES, LearnedStart, model_fingerprint,
                                              start_inputs)
from bodyfit.fitter.fit.pinhole_canvas import Placement, phone_intrinsics
from bodyfit.fitter.fit.search import SearchSettings
from bodyfit.fitter.fit.side_arms import arms_down_angle
from bodyfit.fitter.fit.stature import StatureConditioner
from bodyfit.fitter.measure.measurements import IMPORTANT, Measurer
from bodyfit.fitter.model.body_model import BodyModel, rest_shape
from bodyfit.fitter.model.limb_bends import bent_bodies
from bodyfit.fitter.output.render import centre_samples, pinhole_pixels

__all__ = ["TRAINING_STREAM", "TrainingSettings", "TrainingBodies", "training_bodies",
           "photographed_masks", "train_start"]

#: The random stream of the training draws (module docstring).
TRAINING_STREAM = 0x57A27
#: Ridge strengths tried (on standardised inputs).
_ALPHAS = (1e-3, 1e-2, 0.1, 1.0, 10.0)
#: The components' bound, sigma (the search's and the solver's).
_BETA_LIMIT = SearchSettings().beta_limit
#: Pixels the body must stay clear of the photo's edges.
_EDGE_PX = 4


@dataclasses.dataclass(frozen=True)
class TrainingSettings:
    """What ``fitter model train-start`` draws and photographs (module docstring).

    Attributes:
        bodies: bodies photographed, front and side (a tenth held out).
        seed: random seed.
        components: K, the components the start predicts (the solver's).
        unknown_sex_share: the share of bodies whose sex the regression is not told.
        front_arms_deg, front_legs_deg: the front photo's abduction ranges, degrees.
        side_arms_deg: the side photo's arms off their arms-down angle by up to this.
        flexion_deg: each limb swung forward or back by up to this, both photos.
        distance_m, camera_height_m: ranges of the camera's distance and height, metres.
        lateral_m: the body up to this far beside the camera's axis, metres.
        pitch_deg, roll_deg: the camera tilted by up to these, degrees.
        focal_spread: the phone's focal length times 1 +- up to this.
        image_px: (height, width) of the photos.
    """

    bodies: int = 6000
    seed: int = 0
    components: int = 40
    unknown_sex_share: float = 1 / 3
    front_arms_deg: tuple[float, float] = (-6.0, 16.0)
    front_legs_deg: tuple[float, float] = (-4.0, 12.0)
    side_arms_deg: float = 4.0
    flexion_deg: float = 6.0
    distance_m: tuple[float, float] = (2.2, 3.8)
    camera_height_m: tuple[float, float] = (0.8, 1.7)
    lateral_m: float = 0.25
    pitch_deg: float = 6.0
    roll_deg: float = 2.0
    focal_spread: float = 0.15
    image_px: tuple[int, int] = (960, 720)

    def validate(self, model: BodyModel) -> None:
        if self.bodies < 100:
            raise UserError(f"--bodies must be at least 100, got {self.bodies}")
        if not 2 <= self.components <= model.num_components:
            raise UserError(f"--components must be 2-{model.num_components}, "
                            f"got {self.components}")


@dataclasses.dataclass(frozen=True)
class TrainingBodies:
    """N drawn bodies, row-aligned.

    Attributes:
        betas: (N, K) sigma; sex: (N,) "female" or "male"; told: (N,) bool, the sex is
            given to the regression.
        front_deg, side_deg: (N, 4) abduction angles of the two photos, ``POSE_NAMES`` order.
        front_flexion_deg, side_flexion_deg: (N, 4) each limb's swing in the two photos.
    """

    betas: np.ndarray
    sex: np.ndarray
    told: np.ndarray
    front_deg: np.ndarray
    side_deg: np.ndarray
    front_flexion_deg: np.ndarray
    side_flexion_deg: np.ndarray


def training_bodies(model: BodyModel, settings: TrainingSettings,
                    rng: np.random.Generator) -> TrainingBodies:
    """``settings.bodies`` bodies and their photos' poses (module docstring); the side
    photo's arms-down angle is each body's own."""
    n, k = settings.bodies, settings.components
    sample = model.sample_betas[:, :k].astype(np.float64)
    sample_sex = np.where(model.sample_sex == 1, "female", "male")  # sample_sex 1: a woman
    from_sample = rng.random(n) < 0.5
    picks = rng.integers(0, len(sample), n)
    sex = np.where(from_sample, sample_sex[picks], rng.choice(["female", "male"], n))
    betas = np.where(from_sample[:, None], sample[picks], 0.0)
    for name in ("female", "male"):
        pool = sample[sample_sex == name]
        drawn = (sex == name) & ~from_sample
        betas[drawn] = rng.multivariate_normal(pool.mean(axis=0), np.cov(pool.T), drawn.sum())
    betas = np.clip(betas, -_BETA_LIMIT, _BETA_LIMIT)
    front = np.c_[rng.uniform(*settings.front_arms_deg, (n, 2)),
                  rng.uniform(*settings.front_legs_deg, (n, 2))]
    rest, joints = rest_shape(model, betas)
    side = front.copy()
    side[:, :2] = np.array([arms_down_angle(model, r, j) for r, j in zip(rest, joints)])[:, None] \
        + rng.uniform(-settings.side_arms_deg, settings.side_arms_deg, (n, 2))
    flexion = rng.uniform(-settings.flexion_deg, settings.flexion_deg, (2, n, 4))
    flexion[1, :, 2:] = 0.0  # the side photo's legs as the front photo's abduction shows
    return TrainingBodies(betas, sex, rng.random(n) >= settings.unknown_sex_share, front, side,
                          flexion[0], flexion[1])


def _camera(settings: TrainingSettings, view: str, floor_m: float,
            rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(K (3, 3), R (3, 3), t (3,) metres) of a random hand-held phone (module docstring)."""
    height, width = settings.image_px
    intrinsics = phone_intrinsics((height, width))
    intrinsics[:2, :2] *= 1.0 + rng.uniform(-settings.focal_spread, settings.focal_spread)
    distance, height = rng.uniform(*settings.distance_m), rng.uniform(*settings.camera_height_m)
    lateral = rng.uniform(-settings.lateral_m, settings.lateral_m)
    pitch, roll = rng.uniform(-1, 1, 2) * (settings.pitch_deg, settings.roll_deg)
    placement = Placement(distance, height, lateral, -floor_m, pitch, roll)
    return (intrinsics,) + placement.extrinsics(view)


def photographed_masks(model: BodyModel, posed: dict[str, np.ndarray],
                       settings: TrainingSettings,
                       rng: np.random.Generator) -> dict[str, np.ndarray]:
    """{"front": (H, W) bool, "side": ...}: the person's pixels of each posed body
    (V, 3) metres, each through its own random camera; redrawn until the body is inside
    the photo (ValueError after 20 tries)."""
    height, width = settings.image_px
    masks = {}
    for view, vertices in posed.items():
        for _ in range(20):
            intrinsics, rotation, translation = _camera(settings, view,
                                                        float(vertices[:, 2].min()), rng)
            px = pinhole_pixels(vertices.astype(np.float64), intrinsics, rotation,
                                translation)[0]
            if (px.min() >= _EDGE_PX and px[:, 0].max() <= width - 1 - _EDGE_PX
                    and px[:, 1].max() <= height - 1 - _EDGE_PX):
                masks[view] = centre_samples(px, model.faces, (width, height))
                break
        else:
            raise ValueError(f"no camera of the settings kept the body in the {view} photo")
    return masks


def _inputs_of(model: BodyModel, bodies: TrainingBodies, settings: TrainingSettings,
               rng: np.random.Generator, progress) -> np.ndarray:
    """(N, F) :func:`~bodyfit.fitter.fit.learned_start.start_inputs` of every body's photos."""
    rest, joints = rest_shape(model, bodies.betas)
    rows = []
    for i in range(len(bodies.betas)):
        posed = bent_bodies(model, rest[i], joints[i],
                            np.stack([bodies.front_deg[i], bodies.side_deg[i]]),
                            np.stack([bodies.front_flexion_deg[i], bodies.side_flexion_deg[i]]))
        masks = photographed_masks(model, {"front": posed[0], "side": posed[1]}, settings, rng)
        stature = float(np.ptp(rest[i][:, 2]))
        rows.append(start_inputs(masks, stature, bodies.sex[i] if bodies.told[i] else "unknown"))
        if progress is not None:
            progress.update(1)
    return np.array(rows)


def _ridge(z: np.ndarray, targets: np.ndarray, alpha: float) -> np.ndarray:
    """(F + 1, T) weights of standardised inputs ``z`` (N, F) and a 1, the 1 unpenalised."""
    design = np.c_[z, np.ones(len(z))]
    penalty = np.diag(np.r_[np.full(z.shape[1], alpha * len(z)), 0.0])
    return np.linalg.solve(design.T @ design + penalty, design.T @ targets)


def _measurement_errors(model: BodyModel, betas: np.ndarray, true_betas: np.ndarray,
                        statures: np.ndarray, k: int) -> np.ndarray:
    """(N, 7) mm: the important measurements of the predicted bodies (components 1..K-1,
    the first solved for the true stature) minus the true bodies'."""
    measurer = Measurer.from_model(model)
    search = SearchSettings()
    extremes = extreme_bodies(model, k, search.pose_lower_deg, search.pose_upper_deg,
                              search.beta_limit)
    errors = []
    for predicted, truth, stature in zip(betas, true_betas, statures):
        conditioner = StatureConditioner(model, k, stature, search.beta_limit, extremes)
        full = conditioner.complete(predicted[None], np.zeros((1, 4)))
        got = measurer.measure(rest_shape(model, full)[0][0])
        want = measurer.measure(rest_shape(model, truth[None])[0][0])
        errors.append([got[key] - want[key] for key in IMPORTANT])
    return np.array(errors)


def train_start(model: BodyModel, settings: TrainingSettings = TrainingSettings(),
                progress=None) -> LearnedStart:
    """Draw, photograph and fit the learned start (module docstring); ``progress``: a tqdm
    bar over the bodies, or None."""
    settings.validate(model)
    k = settings.components
    rng = np.random.default_rng([settings.seed, TRAINING_STREAM])
    bodies = training_bodies(model, settings, rng)
    inputs = _inputs_of(model, bodies, settings, rng, progress)
    targets = np.c_[bodies.betas[:, 1:], bodies.front_deg]
    held = np.arange(len(inputs)) % 10 == 0
    mean, scale = inputs[~held].mean(axis=0), inputs[~held].std(axis=0) + 1e-9
    z = (inputs - mean) / scale
    best = None
    for alpha in _ALPHAS:
        weights = _ridge(z[~held], targets[~held], alpha)
        error = float(np.sqrt(np.mean((np.c_[z[held], np.ones(held.sum())] @ weights
                                       - targets[held])[:, :k - 1] ** 2)))
        if best is None or error < best[0]:
            best = (error, alpha, weights)
    _, alpha, weights = best
    start = LearnedStart(mean, scale, weights, k, model_fingerprint(model, k), {})
    betas, pose = start.predict(inputs[held])
    statures = inputs[held, -2]
    measured = _measurement_errors(model, betas, bodies.betas[held], statures, k)
    held_out = {
        "bodies": int(held.sum()),
        "components_rms_sigma": float(np.sqrt(np.mean((betas - targets[held, :k - 1]) ** 2))),
        "angles_rms_deg": float(np.sqrt(np.mean((pose - targets[held, k - 1:]) ** 2))),
        "important_mean_abs_mm": float(np.abs(measured).mean()),
        "important_mean_abs_mm_each": dict(zip(IMPORTANT, np.abs(measured).mean(axis=0)
                                               .round(2).tolist())),
    }
    return dataclasses.replace(start, metadata={"settings": dataclasses.asdict(settings),
                                                "alpha": alpha,
                                                "held_out": held_out,
                                                "sex_codes": SEX_CODES})
