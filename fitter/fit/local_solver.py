"""The local solver: Levenberg-Marquardt on a smooth, sub-pixel silhouette cost.

Where the population search (:mod:`bodyfit.fitter.fit.search`) scores whole candidates by
their raster and needs tens of thousands of them, the local solver follows the cost's
gradient from a start and needs tens of renders.

The parameters ``x``: the genes (betas 2..K, standard deviations; the four abduction
angles, degrees) and, per view, a move of the camera (3 metres, camera frame, within
``_CAMERA_REACH_M`` of where the placement put it). The cost of a body:

    cost = sum over views v:  (1 - p) * sum_e W_e rho(mm_v * sd_v(x_e))
                            +      p  * sum_z W_z rho(mm_v * n_e(z) . (z - x_e(z)))
                            + lambda * |betas 2..K|^2
    lambda = prior + prior_per_cost * (the silhouette terms' cost where the iteration starts)
    W_e  = view weight(v) * part weight(e) * length_e / (the view's outline length)
    W_z  = view weight(v) * part weight(e(z)) / (the person's edge points in v)

- model -> person: each outline sample x_e of the body
  (:mod:`bodyfit.fitter.fit.outline`) at the person's signed distance sd_v (pixels,
  negative inside, :func:`signed_distance`), sampled bilinearly;
- person -> model: each point z of the person's sub-pixel edge (:func:`silhouette_edge`)
  to the line of its nearest sample e(z) (normal n_e), which sees what the first cannot:
  a gap between the legs the body fills, a hand it does not reach;
- ``p`` is ``person_to_model``, mm_v the view's millimetres per pixel, the part and view
  weights the fit's cost settings' (Table 2's, as the search's), rho Huber's loss
  (quadratic within the knee, linear beyond), the prior a Gaussian one at the mean body:
  a fixed weak part keeps the directions the silhouettes cannot see at the mean, and a
  part that grows with the silhouettes' misfit (read at ``huber_mm``) treats that misfit
  as the outline's noise: it is the variance of a Gaussian likelihood's residuals, whose
  weight against the prior falls as it grows. On clean synthetic photos the answer costs
  are about 9 mm^2 and the prior stays weak; on real people's masks (BodyM, 400-4000
  mm^2) without it half of the 39 free components ended at their +-3 sigma bounds, a
  shape no person has, bought for outline pixels of hair, clothes and segmentation.

The knee falls from ``huber_start_mm`` to ``huber_mm`` over the first iterations: far from
the person the body's largest misfits (legs at another angle) carry the information; near
it they are a mask's stray pixels, which must not pull the whole body.

The stature is held as the search holds it: the first beta is solved from the others
(:class:`~bodyfit.fitter.fit.stature.StatureConditioner`), its slope with respect to them
entering the Jacobian. The pinhole cameras are solved with the body, and may be placed
anew from the body so far (``placements`` times, evenly through the first
``placements_within`` iterations) as the search places them.

The Jacobian is analytic (:meth:`~bodyfit.fitter.fit.outline.ViewOutline.jacobian`); the
steps are Gauss-Newton's on the Huber-reweighted residuals, damped by Levenberg-Marquardt,
each accepted only if it lowers the cost.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import scipy.ndimage as ndi
from scipy.spatial import cKDTree

from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.elbows import elbow_forward, elbow_rig, view_twist
from bodyfit.fitter.fit.outline import OutlineSamples, ViewOutline, moved_camera
from bodyfit.fitter.fit.pitch import PITCHES
from bodyfit.fitter.model.body_model import BodyModel
from bodyfit import kernels

#: The blur (pixels) through which a silhouette's sub-pixel edge is read.
_EDGE_SIGMA_PX = 1.0
#: Pixels within this many of the boundary get their distance from the sub-pixel edge.
_EDGE_BAND_PX = 4.0
#: The Huber knee's fall per iteration (``SolverSettings.huber_start_mm``).
_KNEE_FALL = 0.8
#: Where the local solver starts (``SolverSettings.start``); the first is the default.
SOLVER_STARTS = ("mean", "learned")
#: How the solver treats the elbows: ``"fitted"``, one flexion for both arms and both
#: photos solved with the body (:mod:`bodyfit.fitter.fit.elbows`); ``"rest"``, the rest
#: pose's (the model's rig alone).
ELBOWS = ("fitted", "rest")
#: The bounds of a fitted elbow flexion, degrees.
ELBOW_RANGE_DEG = (0.0, 60.0)
#: How the solver treats the hands in the front photo: ``"fitted"``, each hand's twist
#: about its forearm solved with the body (:mod:`bodyfit.fitter.fit.elbows`);
#: ``"rest"``, the rest pose's (palms facing in).
HANDS = ("fitted", "rest")
#: The bounds of a fitted hand's twist, degrees (0: palm in, 90: palm forward), and
#: where it starts: the middle of the turns people stand with.
TWIST_RANGE_DEG = (-15.0, 120.0)
TWIST_START_DEG = 45.0
#: How far (metres, each axis) the solver may move a view's camera from where it was placed.
_CAMERA_REACH_M = 0.5

__all__ = ["SOLVER_STARTS", "ELBOWS", "HANDS", "SolverSettings", "SolverTrace", "Residuals",
           "silhouette_edge", "signed_distance", "sample_bilinear", "LocalProblem", "solve", "placement_iterations",
           "moved_view"]


@dataclasses.dataclass(frozen=True)
class SolverSettings:
    """The local solver's settings.

    Attributes:
        iterations: Levenberg-Marquardt iterations at most (0: no local solver).
        components: K, the shape components it solves for (up to those stored).
        prior: mm^2 of cost per sigma^2 of every beta (a Gaussian prior at the mean).
        prior_per_cost: the prior's weight grows by this share of the silhouette terms'
            cost (mm^2), read at each iteration's start (module docstring): 1/800, chosen
            on BodyM's choice rows (1/2000 did no better; a fixed weight of 1, as good
            there, cost the in-space set 1.15 -> 1.68 mm); 0: the fixed part alone (the
            default before).
        huber_mm: the Huber loss's knee, millimetres at the person.
        huber_start_mm: the knee of the first iteration; it falls geometrically by
            ``_KNEE_FALL`` an iteration to ``huber_mm`` (far from the person, a body's
            largest misfits, such as legs at another angle, carry the information; near
            it, they are a mask's stray pixels).
        placements: how often the pinhole cameras are placed anew from the body so far,
            evenly through the first ``placements_within`` iterations.
        placements_within: the iterations the placements are spread over (0: all of
            them); a placement moves the cameras off the cost's minimum, so the last one
            leaves the solver the rest of its iterations to come back.
        person_to_model: the share of the person -> model term in each view's cost (the
            rest is the model -> person term's).
        tolerance: stop when an accepted step lowers the cost by less than this share.
        start: where it starts without a population search: ``"mean"``, the mean body
            (its angles 0), or ``"learned"``, the body and angles the learned start reads
            off the silhouettes (:mod:`bodyfit.fitter.fit.learned_start`; with 0
            iterations, that body is the answer).
        elbows: one of ``ELBOWS``; a fitted flexion starts at the rest pose's.
        hands: one of ``HANDS``; fitted twists start at ``TWIST_START_DEG`` (or at an
            earlier solve's).
        pitch: the pinhole cameras' pitch, one of ``pitch.PITCHES``: ``"searched"``, the
            solver run again with each view's camera pitched
            (:mod:`bodyfit.fitter.fit.pitch`), or ``"level"``.
    """

    iterations: int = 0
    components: int = 40
    prior: float = 1e-3
    prior_per_cost: float = 0.00125
    huber_mm: float = 3.0
    huber_start_mm: float = 30.0
    placements: int = 3
    placements_within: int = 0
    person_to_model: float = 0.5
    tolerance: float = 1e-5
    start: str = "mean"
    elbows: str = "rest"
    hands: str = "rest"
    pitch: str = "level"

    def validate(self, stored_components: int) -> None:
        if self.iterations < 0:
            raise UserError(f"--iterations must be >= 0, got {self.iterations}")
        if self.iterations and not 2 <= self.components <= stored_components:
            raise UserError(f"the local solver's components must be 2-{stored_components}, "
                            f"got {self.components}")
        if self.prior_per_cost < 0:
            raise UserError(f"--shape-prior must be >= 0, got {self.prior_per_cost:g}")
        if (self.prior < 0 or self.huber_mm <= 0 or self.placements < 0
                or self.placements_within < 0 or self.huber_start_mm < self.huber_mm):
            raise UserError("the solver's prior and placements must be >= 0 and its "
                            "Huber knees > 0, the first at least the last")
        if not 0 <= self.person_to_model <= 1:
            raise UserError(f"person_to_model must be in [0, 1], got {self.person_to_model}")
        if self.start not in SOLVER_STARTS:
            raise UserError(f"--start must be one of {', '.join(SOLVER_STARTS)}, "
                            f"got {self.start!r}")
        if self.elbows not in ELBOWS:
            raise UserError(f"--elbows must be one of {', '.join(ELBOWS)}, got {self.elbows!r}")
        if self.hands not in HANDS:
            raise UserError(f"--hands must be one of {', '.join(HANDS)}, got {self.hands!r}")
        if self.pitch not in PITCHES:
            raise UserError(f"--pitch must be one of {', '.join(PITCHES)}, got {self.pitch!r}")


def silhouette_edge(mask: np.ndarray) -> np.ndarray:
    """(N, 2) float64 the edge of a (H, W) bool silhouette, sub-pixel, pixels (column, row):
    where the mask, blurred by a Gaussian of ``_EDGE_SIGMA_PX``, crosses one half between
    two neighbouring pixel centres of a row or a column (marching squares' edge points).
    The blur reads an oblique edge's staircase as the line it samples: the binary mask's
    own half-way points read it up to a tenth of a pixel outward, and a fit on them
    answers with a body too large."""
    level = cv2.GaussianBlur(np.asarray(mask, np.float64), (0, 0), _EDGE_SIGMA_PX,
                             borderType=cv2.BORDER_REPLICATE) - 0.5
    rows, cols = np.nonzero((level[:, :-1] > 0) != (level[:, 1:] > 0))  # along rows
    t = level[rows, cols] / (level[rows, cols] - level[rows, cols + 1])
    points = [np.stack([cols + t, rows], axis=1)]
    rows, cols = np.nonzero((level[:-1] > 0) != (level[1:] > 0))  # along columns
    t = level[rows, cols] / (level[rows, cols] - level[rows + 1, cols])
    points.append(np.stack([cols, rows + t], axis=1))
    return np.concatenate(points)


def signed_distance(mask: np.ndarray, edge: np.ndarray) -> np.ndarray:
    """(H, W) float64 signed distance from each pixel centre to a silhouette's edge, pixels,
    negative inside: within ``_EDGE_BAND_PX`` of the (H, W) bool ``mask``'s boundary the
    distance to the nearest of the sub-pixel ``edge`` points (:func:`silhouette_edge`),
    farther out the exact distance to the nearest pixel centre across the boundary less
    one half (the two differ by a fraction of a pixel, where no fit ends)."""
    mask = np.asarray(mask, bool)
    far = np.where(mask, 0.5 - ndi.distance_transform_edt(mask),
                   ndi.distance_transform_edt(~mask) - 0.5)
    rows, cols = np.nonzero(np.abs(far) < _EDGE_BAND_PX)
    near, _ = cKDTree(edge).query(np.stack([cols, rows], axis=1).astype(np.float64))
    far[rows, cols] = np.where(far[rows, cols] < 0, -near, near)
    return far


def sample_bilinear(field: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """((N,) values, (N, 2) gradients d/d(column, row)) of a (H, W) field at (N, 2) pixel
    points (column, row), bilinearly interpolated; points off the field read its edge."""
    height, width = field.shape
    u = np.clip(points[:, 0], 0.0, width - 1.000001)
    v = np.clip(points[:, 1], 0.0, height - 1.000001)
    c, r = np.floor(u).astype(int), np.floor(v).astype(int)
    fu, fv = u - c, v - r
    f00, f01 = field[r, c], field[r, c + 1]
    f10, f11 = field[r + 1, c], field[r + 1, c + 1]
    top = f00 + fu * (f01 - f00)
    bottom = f10 + fu * (f11 - f10)
    values = top + fv * (bottom - top)
    du = (1 - fv) * (f01 - f00) + fv * (f11 - f10)
    return values, np.stack([du, bottom - top], axis=1)


@dataclasses.dataclass
class SolverTrace:
    """What the solver did, per iteration.

    Attributes:
        costs: the cost after each iteration (mm^2, the module docstring's).
        genes: (iterations, K - 1 + 4) the solved genes after each.
        evaluations: the bodies whose outlines were read (one render a view each).
        stop_reason: why it stopped.
    """

    costs: list[float] = dataclasses.field(default_factory=list)
    genes: list[np.ndarray] = dataclasses.field(default_factory=list)
    evaluations: int = 0
    stop_reason: str = ""


@dataclasses.dataclass
class _ViewReading:
    """What a view's residuals were read from: the body's outline samples, the camera
    that saw them, and per term the sampled gradients of the person's signed distance
    ((S, 2), model -> person) or each person edge point's nearest sample ((N,) indices,
    person -> model); None where the term has no weight."""

    samples: OutlineSamples
    camera: kernels.ViewCamera
    gradients: np.ndarray | None = None
    nearest: np.ndarray | None = None


@dataclasses.dataclass(frozen=True)
class Residuals:
    """A body's residuals: (S,) weights W and distances d (mm), every view's terms in
    turn (model -> person, then person -> model), and the views' readings."""

    weights: np.ndarray
    distances: np.ndarray
    readings: list[_ViewReading]


class LocalProblem:
    """One person's smooth cost (the module docstring) over the genes (betas 2..K, the
    four angles), the elbows' flexion when ``settings.elbows`` fits it, the front
    photo's hands' twists (left, right) when ``settings.hands`` fits them, and a camera
    move per view, in that order.

    Args:
        model: the render model (:func:`~bodyfit.fitter.fit.render_mesh.render_model`).
        views: view name -> the kernels' target (its canvas, camera, parts, fixed angles);
            replace entries with :meth:`replace_view` when the cameras are placed anew.
        cost: the fit's cost settings (part and view weights).
        conditioner: the :class:`~bodyfit.fitter.fit.stature.StatureConditioner` over
            ``components`` betas.
        components: K.
        pose_lower_deg, pose_upper_deg: (4,) the angles' bounds; beta_limit: the betas'.
        settings: the solver's.
    """

    def __init__(self, model: BodyModel, views: dict[str, kernels.ViewTarget],
                 cost: kernels.CostSettings, conditioner, components: int,
                 pose_lower_deg, pose_upper_deg, beta_limit: float, settings: SolverSettings):
        self.model, self.conditioner, self.settings = model, conditioner, settings
        self.k = components
        self.outlines = {name: ViewOutline(model, view) for name, view in views.items()}
        self.person_edges = {name: silhouette_edge(view.silhouette)
                             for name, view in views.items()}
        self.distance = {name: signed_distance(view.silhouette, self.person_edges[name])
                         for name, view in views.items()}
        self.part_weights = np.asarray(cost.part_weights, np.float64)
        self.view_weights = {"front": cost.front_weight, "side": cost.side_weight}
        self.names = list(views)
        self.num_genes = self.k - 1 + 4
        self.rig = elbow_rig(model) if settings.elbows == "fitted" else None
        self.fits_twist = settings.hands == "fitted"
        #: where the cameras' moves start in the parameters (after the elbows and the
        #: hands, if fitted)
        self.camera_start = self.num_genes + (self.rig is not None) + 2 * self.fits_twist
        turns = np.array([ELBOW_RANGE_DEG] * (self.rig is not None)
                         + [TWIST_RANGE_DEG] * 2 * self.fits_twist).reshape(-1, 2)
        self.lower = np.r_[np.full(self.k - 1, -beta_limit), pose_lower_deg,
                           turns[:, 0], np.full(3 * len(views), -_CAMERA_REACH_M)]
        self.upper = np.r_[np.full(self.k - 1, beta_limit), pose_upper_deg,
                           turns[:, 1], np.full(3 * len(views), _CAMERA_REACH_M)]

    def start(self, genes: np.ndarray, flexion_deg: float | None = None,
              twist_deg: np.ndarray | None = None) -> np.ndarray:
        """The parameters of ``genes`` (K - 1 + 4,): the elbows at ``flexion_deg`` (None:
        the rest pose's), the hands at ``twist_deg`` ((2,); None: ``TWIST_START_DEG``),
        the cameras where they stand."""
        elbow = ([self.rig.rest_deg if flexion_deg is None else flexion_deg]
                 if self.rig is not None else [])
        twist = (np.broadcast_to(TWIST_START_DEG if twist_deg is None else twist_deg, 2)
                 if self.fits_twist else [])
        return np.clip(np.r_[genes, elbow, twist, np.zeros(3 * len(self.names))],
                       self.lower, self.upper)

    def camera_moves(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """View name -> (3,) metres, the move of its camera in the parameters ``x``."""
        return {name: x[self.camera_start + 3 * i:self.camera_start + 3 * i + 3]
                for i, name in enumerate(self.names)}

    def replace_view(self, view: kernels.ViewTarget) -> None:
        """Score against ``view`` (the view of its name with its camera placed anew)."""
        self.outlines[view.name].view = view

    def body(self, x: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, float | None, np.ndarray | None]:
        """(betas (K,), pose (4,) degrees, the elbows' flexion and the front photo's
        hands' twists (2,) in degrees, each None for the rest pose's) of the parameters
        ``x``."""
        genes = x[:self.num_genes]
        betas = self.conditioner.complete(genes[None, :self.k - 1], genes[None, self.k - 1:])[0]
        flexion = float(x[self.num_genes]) if self.rig is not None else None
        twist = x[self.camera_start - 2:self.camera_start].copy() if self.fits_twist else None
        return betas, genes[self.k - 1:], flexion, twist

    def _first_beta_slope(self, x: np.ndarray) -> np.ndarray:
        """(K - 1,) d first beta / d betas 2..K (the stature held), by differences (the
        solved beta is piecewise linear in the others)."""
        genes = x[:self.num_genes]
        others, pose = genes[:self.k - 1], genes[self.k - 1:]
        step = 1e-3
        rows = np.vstack([others[None], others[None] + step * np.eye(self.k - 1)])
        first = self.conditioner.complete(rows, np.repeat(pose[None], len(rows), 0))[:, 0]
        return (first[1:] - first[0]) / step

    def residuals(self, x: np.ndarray) -> "Residuals":
        """The residuals of the parameters ``x`` over every view's outline samples (one
        render a view), with what :meth:`jacobian` needs of them."""
        betas, pose, flexion, twist = self.body(x)
        weights, distances, readings = [], [], []
        share = 1.0 - self.settings.person_to_model
        for name, move in self.camera_moves(x).items():
            outline = self.outlines[name]
            view = outline.view
            posed = elbow_forward(self.model, betas[None], view.view_pose(pose[None]), flexion,
                                  view_twist(name, twist))[0]
            camera = moved_camera(view.camera, move)
            samples = outline.samples(posed.astype(np.float64), camera)
            mm, view_weight = view.millimetres_per_pixel, self.view_weights[name]
            part_weights = self.part_weights[samples.parts]
            reading = _ViewReading(samples, camera)
            if share > 0:  # model -> person: the person's signed distance at each sample
                sd, reading.gradients = sample_bilinear(self.distance[name], samples.points)
                lengths = samples.lengths / max(samples.lengths.sum(), 1e-9)
                weights.append(share * view_weight * part_weights * lengths)
                distances.append(mm * sd)
            if share < 1:  # person -> model: each edge point to its nearest sample's edge
                person = self.person_edges[name]
                _, reading.nearest = cKDTree(samples.points).query(person)
                gap = np.einsum("si,si->s", person - samples.points[reading.nearest],
                                samples.normals[reading.nearest])
                weights.append((1.0 - share) * view_weight * part_weights[reading.nearest]
                               / len(person))
                distances.append(mm * gap)
            readings.append(reading)
        return Residuals(np.concatenate(weights), np.concatenate(distances), readings)

    def jacobian(self, x: np.ndarray, residuals: "Residuals") -> np.ndarray:
        """(S, len(x)) d distances (mm) / d ``x`` of ``residuals`` (:meth:`residuals` of
        ``x``), rows in their order; no render."""
        betas, pose, flexion, twist = self.body(x)
        slope = self._first_beta_slope(x)
        rows = []
        for i, (name, reading) in enumerate(zip(self.names, residuals.readings)):
            outline = self.outlines[name]
            mm = outline.view.millimetres_per_pixel
            first = self.camera_start + 3 * i
            seen_twist = view_twist(name, twist)
            d_pixels = outline.jacobian(reading.samples, betas, pose, reading.camera, flexion,
                                        seen_twist)
            d_points = np.zeros((len(reading.samples.points), 2, len(x)))
            # columns of d_pixels: K betas, 4 angles, the flexion if fitted, the twists if
            # fitted and this view's hands turn with them, 3 camera (a view's hands that do
            # not turn: the twists' columns stay zero)
            turns = self.camera_start - 2 * (self.fits_twist and seen_twist is None)
            d_points[:, :, :turns] = np.concatenate(
                [d_pixels[:, :, 1:self.k] + d_pixels[:, :, :1] * slope[None, None],
                 d_pixels[:, :, self.k:-3]], axis=2)
            d_points[:, :, first:first + 3] = d_pixels[:, :, -3:]
            if reading.gradients is not None:
                rows.append(mm * np.einsum("si,sik->sk", reading.gradients, d_points))
            if reading.nearest is not None:
                normals = reading.samples.normals[reading.nearest]
                rows.append(-mm * np.einsum("si,sik->sk", normals,
                                            d_points[reading.nearest]))
        return np.concatenate(rows)

    def silhouette_cost(self, residuals: Residuals, knee: float) -> float:
        """The silhouette terms of the cost of ``residuals`` (Huber's loss with its
        ``knee``, mm), mm^2."""
        a = np.abs(residuals.distances)
        rho = np.where(a <= knee, a * a, 2 * knee * a - knee * knee)
        return float(residuals.weights @ rho)

    def prior_weight(self, residuals: Residuals) -> float:
        """The prior's weight (mm^2 per sigma^2) where the silhouettes left ``residuals``."""
        s = self.settings
        return s.prior + s.prior_per_cost * self.silhouette_cost(residuals, s.huber_mm)

    def cost(self, residuals: Residuals, x: np.ndarray, knee: float, prior: float) -> float:
        """The cost of ``x``'s residuals (Huber's loss with its ``knee``, mm) plus the
        prior of weight ``prior`` (:meth:`prior_weight`), mm^2."""
        betas = x[:self.k - 1]
        return self.silhouette_cost(residuals, knee) + prior * float(betas @ betas)

    def cost_of(self, x: np.ndarray) -> float:
        """The cost (mm^2) of the parameters ``x`` at the last knee, its prior weighed
        where ``x`` leaves the silhouettes (one render a view)."""
        residuals = self.residuals(x)
        return self.cost(residuals, x, self.settings.huber_mm, self.prior_weight(residuals))


def solve(problem: LocalProblem, start: np.ndarray, place=None,
          flexion_deg: float | None = None, twist_deg: np.ndarray | None = None
          ) -> tuple[np.ndarray, SolverTrace]:
    """Levenberg-Marquardt from ``start`` (genes (K - 1 + 4,); the cameras where they stand).

    Args:
        problem: the person's cost.
        start: the genes to start from.
        flexion_deg: the fitted elbows' flexion to start from (None: the rest pose's).
        twist_deg: the fitted hands' twists (2,) to start from (None: ``TWIST_START_DEG``).
        place: None, or called with :meth:`LocalProblem.body`'s (betas (K,), pose (4,),
            flexion, twist) to place the cameras anew (it calls ``problem.replace_view``),
            ``settings.placements`` times.

    Returns:
        (the solved parameters (:class:`LocalProblem`'s order), the trace).
    """
    s = problem.settings
    x = problem.start(start, flexion_deg, twist_deg)
    trace = SolverTrace()
    at = placement_iterations(s)
    damping = 1e-3
    prior = np.zeros(len(x))
    residuals = problem.residuals(x)
    jacobian = problem.jacobian(x, residuals)
    trace.evaluations += 1
    for iteration in range(s.iterations):
        if place is not None and iteration in at:
            place(*problem.body(x))
            x[problem.camera_start:] = 0.0  # the cameras stand where the placement put them
            residuals = problem.residuals(x)
            jacobian = problem.jacobian(x, residuals)
            trace.evaluations += 1
        knee = max(s.huber_mm, s.huber_start_mm * _KNEE_FALL ** iteration)
        weight = problem.prior_weight(residuals)
        prior[:problem.k - 1] = weight
        cost = problem.cost(residuals, x, knee, weight)
        a = np.abs(residuals.distances)
        reweight = residuals.weights * np.where(a <= knee, 1.0, knee / np.maximum(a, 1e-12))
        normal = (jacobian * reweight[:, None]).T @ jacobian + np.diag(prior)
        gradient = jacobian.T @ (reweight * residuals.distances) + prior * x
        improved = False
        for _ in range(8):
            step = np.linalg.solve(normal + damping * np.diag(np.diag(normal) + 1e-9),
                                   -gradient)
            trial = np.clip(x + step, problem.lower, problem.upper)
            tried = problem.residuals(trial)
            trace.evaluations += 1
            t_cost = problem.cost(tried, trial, knee, weight)
            if t_cost < cost:
                improved = True
                damping = max(damping / 3, 1e-7)
                break
            damping *= 4
        if not improved:
            trace.stop_reason = "no step lowers the cost"
            break
        x, residuals = trial, tried
        jacobian = problem.jacobian(x, residuals)  # of the outline the trial already read
        trace.costs.append(problem.cost(residuals, x, s.huber_mm, weight))
        trace.genes.append(x[:problem.num_genes].copy())
        if ((cost - t_cost) < s.tolerance * cost and knee == s.huber_mm
                and iteration + 1 not in at):
            trace.stop_reason = "the cost stopped falling"
            break
    else:
        trace.stop_reason = "iterations"
    return x, trace


def placement_iterations(settings: SolverSettings) -> set[int]:
    """The iterations (0-based) before which the cameras are placed anew: ``placements`` of
    them, evenly within the first ``placements_within`` iterations (all, when 0)."""
    span = min(settings.iterations, settings.placements_within or settings.iterations)
    return {round(span * (i + 1) / (settings.placements + 1)) for i in range(settings.placements)}


def moved_view(view: kernels.ViewTarget, translation_m: np.ndarray) -> kernels.ViewTarget:
    """``view`` with its camera moved as the solver moved it (``translation_m`` (3,)
    metres added to the camera's translation, :func:`~bodyfit.fitter.fit.outline.
    moved_camera`), its millimetres per pixel scaled with the model origin's depth."""
    depth = float(np.array(view.camera.translation)[2])
    return dataclasses.replace(
        view, camera=moved_camera(view.camera, translation_m),
        millimetres_per_pixel=view.millimetres_per_pixel * (depth + translation_m[2]) / depth)
