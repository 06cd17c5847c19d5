"""One person's fit: silhouettes -> canvases -> search -> body and measurements with spreads.

The ± of each measurement: :mod:`bodyfit.fitter.fit.spreads` (calibrated on the accuracy
benchmark for the default method, the search's own scatter for other settings).
"""

from __future__ import annotations

import dataclasses
import functools
import time

import numpy as np
from threadpoolctl import threadpool_limits

from bodyfit import kernels
from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.canvas import (PAPER_CANVAS, CanvasSettings, extreme_bodies,
                                       orthographic_view)
from bodyfit.fitter.fit.elbows import elbow_forward, view_twist
from bodyfit.fitter.fit.learned_start import active_start
from bodyfit.fitter.fit.local_solver import LocalProblem, SolverSettings, moved_view, solve
from bodyfit.fitter.fit.mass_volume import MASS_SCALINGS, mass_scale, mass_scaled
from bodyfit.fitter.fit.measurement_prior import PRIORS, MeasurementPrior, combined
from bodyfit.fitter.fit.person import PersonInputs, mirrored_side, person_silhouettes
from bodyfit.fitter.fit.photo_extents import ViewPhoto, photo_scaled_measurements
from bodyfit.fitter.fit.pinhole_canvas import pinhole_view, placed_anew, view_pitch_deg
from bodyfit.fitter.fit.pitch import PITCH_ITERATIONS, searched_pitches
from bodyfit.fitter.fit.render_mesh import render_model
from bodyfit.fitter.fit.search import (SearchResult, SearchSettings, averaged, refined, search,
                                       searches_together)
from bodyfit.fitter.fit.side_arms import side_view_options
from bodyfit.fitter.fit.spreads import (answer_cost, bodyfit_calibration, calibration_applies,
                                        match_warning, population_spreads)
from bodyfit.fitter.fit.stature import StatureConditioner, stature_scale
from bodyfit.fitter.fit.weights import cost_settings
from bodyfit.fitter.measure.measurements import Measurer
from bodyfit.fitter.model.body_model import POSE_NAMES, BodyModel, forward, rest_shape
from bodyfit.kernels.target import visible_vertices

__all__ = ["FitSettings", "METHODS", "Fit", "fit_person", "fit_inputs", "fit_work",
           "fitted_bodies", "fitted_measurements", "reported_measurements",
           "check_learned_start", "learned_genes",
           "person_views", "place_cameras", "placement_body", "refinement_scoring",
           "stature_conditioner", "view_photos"]

#: The default's lowest abduction angles, degrees (``POSE_NAMES`` order): the arms down to
#: 17 degrees from hanging (the rest pose's are 43 out), as people hold them in a front
#: photo; the searches' range (thorough, paper) stays -10.
ARMS_LOWER_DEG = (-25.0, -25.0, -10.0, -10.0)


@dataclasses.dataclass(frozen=True)
class FitSettings:
    """Everything about a fit but the person.

    Attributes:
        search: the population search (optimiser and space); ``searches`` 0: none, the
            local solver starts from the mean body.
        solver: the local solver (:mod:`bodyfit.fitter.fit.local_solver`), run after the
            search from its answer (``iterations`` 0: none).
        canvas: canvas geometry.
        cost: the kernels' weights, matching and alignment (default: the ``bodyfit``
            weights preset, model -> person matching, the vertical anchor on the
            extremes; docs/accuracy.md measured the matching directions).
        device: where the kernels run, "cpu" or "cuda:0".
        threads: CPU threads evaluating each population side by side (None: one per core
            this process may use; ignored on a GPU). The result does not depend on it.
        render_cell_mm: the candidates are rendered with the parts of
            ``render_mesh.CLUSTERED_PARTS`` clustered to cubes of this size
            (:mod:`bodyfit.fitter.fit.render_mesh`; 0: the full mesh).
        side_arms: how the side view treats the person's arms, one of
            ``bodyfit.fitter.fit.side_arms.SIDE_ARMS`` ("down": candidates rendered with their
            arms hanging down; "hidden": without arms).
        projection: "pinhole" (the photos' camera, or a typical phone's without one,
            :mod:`bodyfit.fitter.fit.pinhole_canvas`; the default) or "orthographic" (the
            paper's, each view scaled from the stature).
        placement_rounds: pinhole only: how often the search places the cameras anew
            from its best body so far (evenly spaced through the generations;
            :func:`~bodyfit.fitter.fit.pinhole_canvas.placed_anew`); 0: only from the mean
            body, before the search.
        photo_extents: pinhole only: the girths and the shoulder breadth of
            :data:`~bodyfit.fitter.fit.photo_extents.SCALED` take their extents from the
            photos (:mod:`bodyfit.fitter.fit.photo_extents`); False: every
            measurement is the fitted mesh's.
        measurement_prior: one of :data:`~bodyfit.fitter.fit.measurement_prior.PRIORS`:
            "ansur", the measurements weighed against what ANSUR II's adults of the
            person's stature, sex (and mass) measure, each by its ± (the module
            :mod:`bodyfit.fitter.fit.measurement_prior`); "none": the fit's own.
        mass_scaling: one of :data:`~bodyfit.fitter.fit.mass_volume.MASS_SCALINGS`:
            with a mass given, "girths" scales the circumferences so that the fitted
            body's volume matches it (:mod:`bodyfit.fitter.fit.mass_volume`), before the
            prior; "none": the mass is read by the prior alone.
    """

    search: SearchSettings = SearchSettings(searches=0, refine_components=0,
                                            pose_lower_deg=ARMS_LOWER_DEG)
    solver: SolverSettings = SolverSettings(iterations=40, start="learned", elbows="fitted",
                                            hands="fitted",
                                            placements_within=10, pitch="searched")
    canvas: CanvasSettings = CanvasSettings()
    cost: kernels.CostSettings = cost_settings(
        "bodyfit", base=kernels.CostSettings(matching="model_to_person",
                                             vertical_anchor="extremes"))
    device: str = "cpu"
    threads: int | None = None
    render_cell_mm: float = 8.0
    side_arms: str = "down"
    projection: str = "pinhole"
    placement_rounds: int = 2
    photo_extents: bool = True
    measurement_prior: str = "ansur"
    mass_scaling: str = "girths"

    @property
    def learned_start(self) -> bool:
        """The fit starts from the learned start (no search)."""
        return self.solver.start == "learned"

    @property
    def searches_pitch(self) -> bool:
        """The local solver searches the pinhole cameras' pitch
        (:mod:`bodyfit.fitter.fit.pitch`)."""
        return (self.solver.pitch == "searched" and bool(self.solver.iterations)
                and self.projection == "pinhole")

    @property
    def solves(self) -> bool:
        """The local solver runs: its iterations, or the learned start's body alone."""
        return bool(self.solver.iterations) or self.learned_start

    def validate(self, stored_components: int) -> None:
        """Raise UserError for settings no person could be fitted with (one line, naming
        the option)."""
        self.search.validate(stored_components)
        self.solver.validate(stored_components)
        if not (self.search.searches or self.solves):
            raise UserError("--searches 0 needs the local solver (--iterations 1 or more) "
                            "or --start learned")
        if self.search.searches and self.learned_start:
            raise UserError("--start learned needs --searches 0: after a search the solver "
                            "starts from the search's answer")
        if self.solves and not self.search.condition_stature:
            raise UserError("the local solver holds the stature: --free-stature needs "
                            "--iterations 0 (a population search alone)")
        self.canvas.validate()
        if self.threads is not None and self.threads < 1:
            raise UserError(f"--threads must be at least 1, got {self.threads}")
        if self.render_cell_mm < 0:
            raise UserError(f"render_cell_mm must be >= 0, got {self.render_cell_mm}")
        if self.projection not in ("orthographic", "pinhole"):
            raise UserError(f"--projection must be orthographic or pinhole, got "
                            f"{self.projection!r}")
        if self.placement_rounds < 0:
            raise UserError(f"placement_rounds must be >= 0, got {self.placement_rounds}")
        if self.measurement_prior not in PRIORS:
            raise UserError(f"--measurement-prior must be one of {', '.join(PRIORS)}, got "
                            f"{self.measurement_prior!r}")
        if self.mass_scaling not in MASS_SCALINGS:
            raise UserError(f"--mass-scaling must be one of {', '.join(MASS_SCALINGS)}, got "
                            f"{self.mass_scaling!r}")


#: The methods of ``fitter run --method``: bodyfit's default (the local solver from the
#: mean body, chosen by measured error against time: docs/fitter.md "Choosing the
#: defaults"); ``thorough``, the population search that was the default before it (two
#: CMA-ES searches of 30 x 150 over 20 components, six refinements of 30 x 500 over 40,
#: averaged: 99,000 candidates); and the paper's method exactly (Sections 3.3-3.4): one
#: search, its GA at 30 x 25 over all 20 betas and the 4 angles, no refinement, Table 2's
#: weights, the person -> model matching, the moments' alignment, its 512 px canvases,
#: every measurement the fitted mesh's.
METHODS = {
    "bodyfit": FitSettings(),
    "thorough": FitSettings(search=SearchSettings(), solver=SolverSettings(),
                            measurement_prior="none", mass_scaling="none"),
    "paper": FitSettings(search=SearchSettings(optimizer="ga", population=None,
                                               generations=None, condition_stature=False,
                                               searches=1, refine_components=0),
                         solver=SolverSettings(),
                         canvas=PAPER_CANVAS, cost=kernels.CostSettings(),
                         projection="orthographic",
                         render_cell_mm=0.0, placement_rounds=0, photo_extents=False,
                         measurement_prior="none", mass_scaling="none"),
}


@dataclasses.dataclass(frozen=True)
class Fit:
    """A fitted body.

    Attributes:
        search: the search's outcome (best parameters, convergence, final population).
        posed: (V, 3) float32 metres, the best body in its fitted pose.
        rest: (V, 3) float32 metres, the same body in the rest A-pose.
        measurements: key ("A".."P") -> mm, of ``rest``.
        spreads: key -> mm, the ± of each measurement (:mod:`bodyfit.fitter.fit.spreads`).
        spread_basis: which ± ``spreads`` holds, one of ``spreads.SPREAD_BASES``.
        views: the kernels' targets (canvas silhouettes and cameras), by view name.
        seconds: stage -> wall seconds ("canvas", "search", "measure").
        view_bodies: view name -> (V, 3) float32 metres, the best candidate as the search
            scored it in that view (its pose with the view's fixed angles, e.g. the side
            view's arms down; not rescaled to the stature): what the view's canvas shows.
        photos: what was read of the photos besides their masks (:func:`fit_inputs`):
            ``camera`` (where K came from), ``side_from`` (which side the side photo
            shows), ``side_costs`` where the fit tried both sides (each one's answer
            cost), where the photography check ran ``check_warnings`` (its warnings,
            one line each), and ``fit_warning`` for a fit that matched its silhouettes
            poorly (:func:`~bodyfit.fitter.fit.spreads.match_warning`); empty for a fit
            of masks.
        masks: view name -> (H, W) bool, the silhouettes of the upright photos as fitted
            (:attr:`~bodyfit.fitter.fit.person.PersonPhotos.masks`); empty for a fit of
            masks.
        mass_scale: the scale the circumferences took from the mass
            (:func:`~bodyfit.fitter.fit.mass_volume.mass_scale`), or None (no mass, or
            ``mass_scaling`` "none").
        images: view name -> (H, W, 3) uint8 BGR, the photos undistorted and upright, as
            taken (:attr:`~bodyfit.fitter.fit.person.PersonPhotos.images`); empty for a
            fit of masks.
    """

    search: SearchResult
    posed: np.ndarray
    rest: np.ndarray
    measurements: dict[str, float]
    spreads: dict[str, float]
    spread_basis: str
    views: dict[str, kernels.ViewTarget]
    seconds: dict[str, float]
    view_bodies: dict[str, np.ndarray]
    photos: dict[str, object] = dataclasses.field(default_factory=dict)
    masks: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    images: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    mass_scale: float | None = None


def _view(name, mask, intrinsics, stature_m, extent, mean_body, model, settings,
          view_options: dict) -> kernels.ViewTarget:
    """One view's target with ``settings.projection`` (``intrinsics``: (3, 3) K for pinhole;
    ``view_options``: the side view's arms,
    :func:`~bodyfit.fitter.fit.side_arms.side_view_options`)."""
    if settings.projection == "pinhole":
        # placed from the mean body as the view renders it (the side view's arms hanging
        # down: the hands reach in front of the body, and the placement's horizontal
        # centre must see them as the photo does)
        pose = np.zeros((1, len(POSE_NAMES)))
        for joint, degrees in (view_options.get("fixed_pose_deg") or {}).items():
            pose[0, POSE_NAMES.index(joint)] = degrees
        posed_mean = forward(model, np.zeros((1, settings.search.components)), pose)[0]
        return pinhole_view(name, mask, intrinsics, stature_m, extent, posed_mean,
                            model.vertex_parts, settings.canvas, settings.device,
                            **view_options)
    return orthographic_view(name, mask, stature_m, extent, mean_body, settings.canvas,
                             settings.device, **view_options)


def person_views(model: BodyModel, masks: dict[str, np.ndarray], stature_m: float,
                 settings: FitSettings, intrinsics: dict[str, np.ndarray] | None,
                 bodies: np.ndarray) -> dict[str, kernels.ViewTarget]:
    """{"front": view, "side": view}: the targets a fit's search starts on (pinhole cameras
    placed from the mean body), of :func:`fit_person`'s arguments; ``bodies``: the search's
    extreme bodies (:func:`~bodyfit.fitter.fit.canvas.extreme_bodies` over
    ``settings.search.components``), whose extent the canvases cover."""
    s = settings.search
    mean_body = forward(model, np.zeros((1, s.components)), np.zeros((1, 4)))[0]
    # arms turned down in the frontal plane keep their side-view width and stay above
    # the feet, so the extent of the search's pose range covers them
    options = {"front": {}, "side": side_view_options(model, settings.side_arms)}
    return {name: _view(name, masks[name], (intrinsics or {}).get(name), stature_m,
                        bodies.reshape(-1, 3), mean_body, model, settings, options[name])
            for name in ("front", "side")}


def stature_conditioner(model: BodyModel, settings: FitSettings, stature_m: float,
                        bodies: np.ndarray) -> StatureConditioner | None:
    """The fit's :class:`~bodyfit.fitter.fit.stature.StatureConditioner` (None without
    ``condition_stature``): on the rest stature, on the posed height for orthographic
    canvases (scaled so that the person's silhouette is the stature tall). ``bodies``: the
    search's extreme bodies (:func:`~bodyfit.fitter.fit.canvas.extreme_bodies`)."""
    s = settings.search
    if not s.condition_stature:
        return None
    return StatureConditioner(model, s.components, stature_m, s.beta_limit, bodies,
                              posed=settings.projection == "orthographic")


def _scoring(model: BodyModel, views: dict[str, kernels.ViewTarget], settings: FitSettings,
             stature_m: float, bodies: np.ndarray):
    """(the kernels' evaluator over ``views``, the stature conditioner or None) for the
    ``settings.search.components`` of a candidate; ``bodies``: the search's extreme bodies
    over those components."""
    arrays = kernels.ModelArrays.from_body_model(render_model(model, settings.render_cell_mm),
                                                 settings.search.components, settings.device)
    evaluator = kernels.PopulationEvaluator(arrays, list(views.values()), settings.cost,
                                           workers=settings.threads)
    return evaluator, stature_conditioner(model, settings, stature_m, bodies)


def placement_body(model: BodyModel, betas: np.ndarray, pose_deg: np.ndarray,
                   view: kernels.ViewTarget, stature_m: float,
                   condition_stature: bool, flexion_deg: float | None = None,
                   twist_deg: np.ndarray | None = None) -> np.ndarray:
    """(V', 3) float64 metres: the body a pinhole view's camera is placed from
    (:func:`~bodyfit.fitter.fit.pinhole_canvas.placed_anew`) for a candidate (betas (K,), pose
    (4,) degrees, its elbows' flexion and front hands' twist, each None for the rest
    pose's): the parts the view shows, in the view's pose, as the kernels (or the local
    solver) render it.

    A candidate conditioned on the stature (:mod:`bodyfit.fitter.fit.stature`) is taken as it
    is: on the rest stature (pinhole views) it is the person's size. (Conditioned on the
    posed height, it stands the stature tall with its legs apart, where the person stands a
    few millimetres lower, so it is the person scaled by stature / (stature - delta) and
    its camera must stand as much farther: scaled to the rest stature instead, the camera
    stood at the person's distance and showed every candidate 0.2-0.7 % too tall, and the
    search answered with bodies as much too thin; docs/history.md, [11].) Without the
    conditioning a candidate has its own height, and the camera is placed for it scaled to
    the person's stature.
    """
    body = elbow_forward(model, betas[None], view.view_pose(pose_deg[None]), flexion_deg,
                         view_twist(view.name, twist_deg))[0]
    if not condition_stature:
        body = body * stature_scale(rest_shape(model, betas[None])[0][0], stature_m)
    shown = visible_vertices(model.vertex_parts, view.visible_parts)
    return body[shown].astype(np.float64)


def place_cameras(model, views, masks, intrinsics, stature_m, evaluator, settings,
                  betas: np.ndarray, pose_deg: np.ndarray, flexion_deg: float | None = None,
                  twist_deg: np.ndarray | None = None,
                  pitches: dict[str, float] | None = None) -> None:
    """Place every view's pinhole camera anew from the candidate (betas (K,), pose (4,)
    degrees, elbows' flexion and hands' twist or None) as it is rendered
    (:func:`placement_body`,
    :func:`~bodyfit.fitter.fit.pinhole_canvas.placed_anew`), pitched by ``pitches`` (view
    name -> degrees; None: each camera keeps its pitch); updates ``views`` and the
    evaluator."""
    for name, view in views.items():
        body = placement_body(model, betas, pose_deg, view, stature_m,
                              settings.search.condition_stature, flexion_deg, twist_deg)
        views[name] = placed_anew(view, masks[name], intrinsics[name], body,
                                  None if pitches is None else pitches[name])
        evaluator.replace_view(views[name])


def _placement_rounds(model, views, masks, intrinsics, stature_m, evaluator, settings):
    """The search's ``on_generation`` that places the pinhole cameras anew from the best
    body so far (:func:`place_cameras`) after each of ``settings.placement_rounds``
    evenly spaced generations."""
    generations = settings.search.generations or 1
    rounds = settings.placement_rounds
    # never after the last generation: its best must be scored with the cameras it ends with
    at = {g for g in (round(generations * (i + 1) / (rounds + 1)) for i in range(rounds))
          if 1 <= g < generations}

    def place(done: int, betas: np.ndarray, pose_deg: np.ndarray) -> bool:
        if done not in at:
            return False
        place_cameras(model, views, masks, intrinsics, stature_m, evaluator, settings,
                      betas, pose_deg)
        return True

    return place


def _searched(model, views, masks, intrinsics, stature_m, evaluator, conditioner, settings,
              progress) -> SearchResult:
    """``settings.search.searches`` searches of the person (seeds ``seed``, ``seed + 1``,
    ...), each from the views as ``views`` holds them (the cameras placed from the mean
    body) with its own placement rounds; one search's result as it is, several averaged
    (:func:`~bodyfit.fitter.fit.search.averaged`): the mean of their genes (the first beta
    solved anew from the stature), scored with the cameras placed from that body. Updates
    ``views`` (and the evaluator) to the cameras the answer is scored with."""
    s = settings.search
    placing = settings.projection == "pinhole" and settings.placement_rounds > 0
    replace = (_placement_rounds(model, views, masks, intrinsics, stature_m, evaluator,
                                 settings) if placing else None)
    first_views = dict(views)
    results = []
    for i in range(s.searches):
        views.update(first_views)  # each search starts from the mean body's cameras
        for view in views.values():
            evaluator.replace_view(view)
        results.append(search(evaluator, dataclasses.replace(s, seed=s.seed + i), conditioner,
                              progress, replace))
    if len(results) == 1:
        return results[0]
    place = (functools.partial(place_cameras, model, views, masks, intrinsics, stature_m,
                               evaluator, settings) if placing else None)
    return _mean_of(results, evaluator, conditioner, place)


def _mean_of(results: list[SearchResult], evaluator, conditioner, place=None) -> SearchResult:
    """Several searches' results as one (:func:`~bodyfit.fitter.fit.search.averaged`): the mean
    of their genes (the first beta solved anew from the stature when ``conditioner`` is
    given), scored by ``evaluator`` after ``place(betas, pose)`` (None: the cameras as
    they are) has placed its cameras from that body."""
    pose = np.mean([r.pose_deg for r in results], axis=0)
    betas = np.mean([r.betas for r in results], axis=0)
    if conditioner is not None:
        betas = conditioner.complete(betas[None, 1:], pose[None])[0]
    if place is not None:
        place(betas, pose)
    scored = evaluator.evaluate(betas[None], pose[None])
    return averaged(results, betas, pose, float(scored.costs[0]), scored.part_costs[0])


def refinement_scoring(model: BodyModel, views: dict[str, kernels.ViewTarget],
                       stature_m: float, settings: FitSettings):
    """(evaluator, stature conditioner or None) of the refinement
    (``settings.search.refinement()``: its ``refine_components``) over ``views``."""
    s = settings.search
    refinement = s.refinement()
    bodies = extreme_bodies(model, refinement.components, s.pose_lower_deg, s.pose_upper_deg,
                            s.beta_limit)
    return _scoring(model, views, dataclasses.replace(settings, search=refinement), stature_m,
                    bodies)


def _refined(model, views, stature_m, first: SearchResult, settings, progress) -> SearchResult:
    """The refinement (``SearchSettings.refine_components``) of ``first``'s answer:
    ``refinements`` searches (seeds ``seed``, ``seed + 1``, ...), each started from that
    answer, with the cameras ``first`` left in ``views``, side by side
    (:func:`~bodyfit.fitter.fit.search.searches_together`); several averaged by
    :func:`_mean_of` (the cameras kept); joined to ``first`` by
    :func:`~bodyfit.fitter.fit.search.refined`."""
    refinement = settings.search.refinement()
    evaluator, conditioner = refinement_scoring(model, views, stature_m, settings)
    betas = np.r_[first.betas, np.zeros(refinement.components - len(first.betas))]
    start = np.r_[betas[len(betas) - refinement.searched_betas:], first.pose_deg]
    seeds = [dataclasses.replace(refinement, seed=refinement.seed + i)
             for i in range(refinement.searches)]
    results = searches_together(evaluator, seeds, conditioner, progress, start=start)
    return refined(first, results[0] if len(results) == 1
                   else _mean_of(results, evaluator, conditioner))


def _canvas_components(settings: FitSettings) -> int:
    """The components whose extreme bodies the canvases cover: the search's, or the local
    solver's when it solves for more."""
    return max(settings.search.components if settings.search.searches else 1,
               settings.solver.components if settings.solves else 1)


def check_learned_start(model: BodyModel, settings: FitSettings) -> None:
    """Raise UserError (one line) if ``settings`` start from the learned start and its
    weights are missing, corrupt or of another body model: checked before any work."""
    if settings.learned_start:
        active_start(model)


def learned_genes(model: BodyModel, masks: dict[str, np.ndarray], stature_m: float, sex: str,
                  components: int) -> np.ndarray:
    """(K - 1 + 4,) the local solver's genes (components 2..K, the four angles, degrees) as
    the learned start reads them off the person
    (:mod:`bodyfit.fitter.fit.learned_start`); components it does not predict are 0.

    Raises:
        UserError: its weights are missing, corrupt, or of another body model.
    """
    betas, pose = active_start(model).start(masks, stature_m, sex)
    return np.r_[np.r_[betas, np.zeros(components)][:components - 1], pose]


def _solved(model, views, masks, intrinsics, stature_m, sex: str, settings: FitSettings,
            first: SearchResult | None, canvas_bodies: np.ndarray,
            warm: SearchResult | None = None,
            pitches: dict[str, float] | None = None) -> SearchResult:
    """The local solver's answer (:mod:`bodyfit.fitter.fit.local_solver`), started from
    ``warm``'s body (an earlier solve's, the cameras placed for it first with ``pitches``,
    view name -> degrees, None: as they are), else from ``first``'s (the searches' answer),
    else from the mean body or the learned start (:func:`learned_genes`, the cameras
    placed for it first; ``sex``: the person's, or "unknown"), the pinhole cameras placed
    anew from its body ``solver.placements`` times; joined to ``first`` by
    :func:`~bodyfit.fitter.fit.search.refined`. Updates ``views`` to the cameras as
    solved, and scores the answer with the search's cost there (its ``cost``, from which
    the calibrated ± is read). ``canvas_bodies``: the extreme bodies the canvases cover
    (:func:`_canvas_components`'), the solver's own when it sets their components."""
    solver, s = settings.solver, settings.search
    began = time.perf_counter()
    at_k = dataclasses.replace(settings,
                               search=dataclasses.replace(s, components=solver.components))
    bodies = canvas_bodies if _canvas_components(settings) == solver.components else \
        extreme_bodies(model, solver.components, s.pose_lower_deg, s.pose_upper_deg,
                       s.beta_limit)
    evaluator, conditioner = _scoring(model, views, at_k, stature_m, bodies)
    problem = LocalProblem(render_model(model, settings.render_cell_mm), views, settings.cost,
                           conditioner, solver.components, s.pose_lower_deg, s.pose_upper_deg,
                           s.beta_limit, solver)
    start = np.zeros(problem.num_genes)
    if warm is not None:
        start = np.r_[np.r_[warm.betas, np.zeros(solver.components)][1:solver.components],
                      warm.pose_deg]
    elif first is not None:
        betas = np.r_[first.betas, np.zeros(solver.components)][:solver.components]
        start = np.r_[betas[1:], first.pose_deg]
    elif settings.learned_start:
        start = np.clip(learned_genes(model, masks, stature_m, sex, solver.components),
                        problem.lower[:problem.num_genes], problem.upper[:problem.num_genes])

    def place(betas: np.ndarray, pose_deg: np.ndarray, flexion_deg: float | None,
              twist_deg: np.ndarray | None, turned: dict[str, float] | None = None) -> None:
        place_cameras(model, views, masks, intrinsics, stature_m, evaluator, at_k, betas,
                      pose_deg, flexion_deg, twist_deg, turned)
        for view in views.values():
            problem.replace_view(view)

    pinhole = settings.projection == "pinhole"
    start_flexion = None if warm is None else warm.elbow_deg
    start_twist = None if warm is None else warm.hand_twist_deg
    if (warm is not None or settings.learned_start) and pinhole:  # placed for the start
        place(*problem.body(problem.start(start, start_flexion, start_twist)), pitches)
    solved, trace = solve(problem, start, place if pinhole else None, start_flexion,
                          start_twist)
    betas, pose, flexion, twist = problem.body(solved)
    for name, move in problem.camera_moves(solved).items():
        views[name] = moved_view(views[name], move)
        evaluator.replace_view(views[name])
    if flexion is None and twist is None:
        scored = evaluator.evaluate(betas[None], pose[None])
    else:  # the kernels' rig has no elbows or hands: the bodies as the solver posed them
        scored = evaluator.evaluate_posed({
            name: elbow_forward(problem.model, betas[None], view.view_pose(pose[None]), flexion,
                                view_twist(name, twist))
            for name, view in views.items()})
    genes = np.array(trace.genes) if trace.genes else start[None]
    # the solver's cost per iteration; with none (the learned start alone), the start's
    costs = np.array(trace.costs or [problem.cost_of(solved)])
    per_iteration = conditioner.complete(genes[:, :solver.components - 1],
                                         genes[:, solver.components - 1:])
    result = SearchResult(
        betas=betas, pose_deg=pose, cost=float(scored.costs[0]),
        part_costs=scored.part_costs[0], best_costs=costs, mean_costs=costs,
        best_betas=per_iteration,
        final_genes=np.r_[betas, pose][None], final_costs=scored.costs[:1].astype(np.float64),
        evaluations=trace.evaluations, generations=len(trace.costs),
        seconds=time.perf_counter() - began, stop_reasons={"solver": trace.stop_reason},
        elbow_deg=flexion, hand_twist_deg=twist)
    return result if first is None else refined(first, result)


def _pitch_searched(model, views, masks, intrinsics, stature_m, sex: str,
                    settings: FitSettings, level: SearchResult,
                    canvas_bodies: np.ndarray) -> SearchResult:
    """The answer of the cameras' pitch search (:mod:`bodyfit.fitter.fit.pitch`) from
    ``level``, the local solver's answer with both cameras level (arguments as
    :func:`_solved`'s); its ``evaluations`` count every solve's renders. Updates ``views``
    to the cameras the answer was solved with."""
    short = dataclasses.replace(settings, solver=dataclasses.replace(
        settings.solver, iterations=min(PITCH_ITERATIONS, settings.solver.iterations)))
    evaluations = [level.evaluations]

    def solve_at(pitches: dict[str, float], start):
        tried = dict(views)
        result = _solved(model, tried, masks, intrinsics, stature_m, sex, short, None,
                         canvas_bodies, start[0], pitches)
        evaluations.append(result.evaluations)
        return result.cost, (result, tried)

    (answer, answer_views), _ = searched_pitches(solve_at, (level.cost, (level, dict(views))))
    views.update(answer_views)
    return dataclasses.replace(answer, evaluations=sum(evaluations))


def fitted_bodies(model: BodyModel, betas: np.ndarray, pose_deg: np.ndarray,
                  views: dict[str, kernels.ViewTarget], stature_m: float,
                  condition_stature: bool, flexion_deg: float | None = None,
                  twist_deg: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
    """The fit's bodies of its answer (betas (K,), pose (4,) degrees, elbows' flexion and
    the front photo's hands' twist, each None for the rest pose's; the posed body has the
    front photo's hands, the rest body the rest pose's), float32 metres:
    (posed (V, 3), rest (V, 3), view name -> (V, 3) in that view's pose), the posed and
    rest bodies rescaled to the stature when the search conditioned it (a posed height
    conditioned, or a first beta at its limit), the view bodies as the search scored them."""
    posed = elbow_forward(model, betas[None], pose_deg[None], flexion_deg, twist_deg)[0]
    view_bodies = {name: elbow_forward(model, betas[None], view.view_pose(pose_deg[None]),
                                       flexion_deg, view_twist(name, twist_deg))[0]
                   for name, view in views.items()}
    rest = rest_shape(model, betas[None])[0][0]
    if condition_stature:
        scale = stature_scale(rest, stature_m)
        posed, rest = posed * scale, rest * scale
    return posed, rest, view_bodies


def view_photos(settings: FitSettings, views: dict[str, kernels.ViewTarget],
                view_bodies: dict[str, np.ndarray], masks: dict[str, np.ndarray],
                intrinsics: dict[str, np.ndarray] | None) -> dict[str, ViewPhoto] | None:
    """The photos the measurements take extents from (:mod:`bodyfit.fitter.fit.photo_extents`),
    by view name, with the fitted body in each view's pose; None when the settings take
    none (``photo_extents`` off, or orthographic views). Arguments as
    :func:`fitted_measurements`'."""
    if not (settings.photo_extents and settings.projection == "pinhole"):
        return None
    return {name: ViewPhoto(name, masks[name], intrinsics[name], view_bodies[name],
                            view.visible_parts, pitch_deg=view_pitch_deg(view))
            for name, view in views.items()}


def fitted_measurements(model: BodyModel, measurer: Measurer, settings: FitSettings,
                        rest: np.ndarray, view_bodies: dict[str, np.ndarray],
                        views: dict[str, kernels.ViewTarget], masks: dict[str, np.ndarray],
                        intrinsics: dict[str, np.ndarray] | None) -> dict[str, float]:
    """key -> mm: the 16 measurements of the fitted ``rest`` body, those of
    ``photo_extents.SCALED`` scaled to the photos (:func:`view_photos`); the other arguments as
    :func:`fit_person`'s and :func:`fitted_bodies`' answers."""
    measurements = measurer.measure(rest)
    photos = view_photos(settings, views, view_bodies, masks, intrinsics)
    if photos is not None:
        measurements |= photo_scaled_measurements(model, measurer, rest, photos)
    return measurements


def reported_measurements(settings: FitSettings, measurements: dict[str, float],
                          spreads: dict[str, float], sex: str, stature_m: float,
                          mass_kg: float | None) -> tuple[dict[str, float], dict[str, float]]:
    """(key -> mm, key -> mm): the measurements and ± a fit reports, from the fitted
    body's ``measurements`` (:func:`fitted_measurements`) and their ``spreads``: weighed
    against the measurements' prior for the person's sex, stature (metres) and mass (kg or
    None) when ``settings.measurement_prior`` is "ansur"
    (:mod:`bodyfit.fitter.fit.measurement_prior`), else as they are."""
    if settings.measurement_prior == "none":
        return measurements, spreads
    return combined(measurements, spreads,
                    *MeasurementPrior.load().predict(sex, 1000.0 * stature_m, mass_kg))


# One BLAS thread for the whole fit: its matrices are small (CMA-ES's 24 x 24, the
# conditioner's, the forward's), and OpenBLAS's idle threads spin on the cores the
# kernels' threads evaluate the population on (one fit: 22.5 -> 14.9 s with the search
# alone limited; fitter batch, 2 workers: 17.6 -> 16.8 s with the whole fit limited).
@threadpool_limits.wrap(limits=1, user_api="blas")
def fit_person(model: BodyModel, masks: dict[str, np.ndarray], stature_m: float,
               settings: FitSettings = FitSettings(), progress: bool | None = None,
               intrinsics: dict[str, np.ndarray] | None = None, sex: str = "unknown",
               mass_kg: float | None = None) -> Fit:
    """Fit the body model to a person's front and side silhouettes.

    Args:
        model: the body model.
        masks: {"front": (H, W) bool, "side": (H', W') bool} silhouettes of the photos.
        stature_m: the person's stature, metres (scales each view, Section 3.3).
        settings: search, canvas, cost, device.
        progress: show the search's progress bar (None: when stderr is a terminal).
        intrinsics: {"front": K, "side": K}, (3, 3) pixels, of the upright photos the masks
            are of; needed by the pinhole projection
            (:func:`bodyfit.fitter.fit.person.view_intrinsics`).
        sex: "female", "male" or "unknown": read by the learned start and the
            measurements' prior.
        mass_kg: the body's mass, kilograms, or None: the circumferences scaled to it
            (``settings.mass_scaling``), and read by the measurements' prior.
    """
    settings.validate(model.num_components)
    if settings.projection == "pinhole" and intrinsics is None:
        raise ValueError("the pinhole projection needs the photos' intrinsics")
    s = settings.search
    t0 = time.perf_counter()
    bodies = extreme_bodies(model, _canvas_components(settings), s.pose_lower_deg,
                            s.pose_upper_deg, s.beta_limit)
    views = person_views(model, masks, stature_m, settings, intrinsics, bodies)
    t1 = time.perf_counter()
    result = None
    if s.searches:
        evaluator, conditioner = _scoring(model, views, settings, stature_m, bodies)
        result = _searched(model, views, masks, intrinsics, stature_m, evaluator, conditioner,
                           settings, progress)
        if s.refine_components:
            result = _refined(model, views, stature_m, result, settings, progress)
    if settings.solves:
        result = _solved(model, views, masks, intrinsics, stature_m, sex, settings, result,
                         bodies)
        if settings.searches_pitch:
            result = _pitch_searched(model, views, masks, intrinsics, stature_m, sex,
                                     settings, result, bodies)
    t2 = time.perf_counter()
    posed, rest, view_bodies = fitted_bodies(model, result.betas, result.pose_deg, views,
                                             stature_m, s.condition_stature,
                                             result.elbow_deg, result.hand_twist_deg)
    measurer = Measurer.from_model(model)
    measurements = fitted_measurements(model, measurer, settings, rest, view_bodies, views,
                                       masks, intrinsics)
    scale = None
    if mass_kg is not None:
        across = mass_scale(mass_kg, rest, model.faces)  # refuses another body's mass
        if settings.mass_scaling == "girths":
            scale = across
            measurements = mass_scaled(measurements, scale)
    calibrated = calibration_applies(settings, METHODS["bodyfit"])
    if calibrated or not s.searches:  # the solver alone has no population to measure
        spreads = bodyfit_calibration().spreads(answer_cost(result))
        basis = "calibrated" if calibrated else "solver"
    else:
        spreads, basis = population_spreads(model, measurer, result, stature_m
                                            if s.condition_stature else None), "population"
    measurements, spreads = reported_measurements(settings, measurements, spreads, sex,
                                                  stature_m, mass_kg)
    t3 = time.perf_counter()
    return Fit(result, posed, rest, measurements, spreads, basis, views,
               {"canvas": t1 - t0, "search": t2 - t1, "measure": t3 - t2}, view_bodies,
               mass_scale=scale)


def fit_work(settings: FitSettings, result: SearchResult) -> str:
    """The work a fit did, in a few words (for the command line and the convergence plot)."""
    s = settings.search
    if not s.searches:
        start = " from the learned start" if settings.learned_start else ""
        pitch = ", then the cameras' pitch searched" if settings.searches_pitch else ""
        return (f"local solver{start}, {result.generations} iterations{pitch} "
                f"({result.evaluations} bodies rendered)")
    text = (f"{s.optimizer}: {result.evaluations} candidates"
            + (f", {s.searches} searches' mean" if s.searches > 1 else "")
            + (f", refined at K={s.refine_components}" if s.refine_components else ""))
    return text + (", then the local solver" if settings.solver.iterations else "")


def fit_inputs(model: BodyModel, inputs: PersonInputs, settings: FitSettings = FitSettings(),
               progress: bool | None = None) -> Fit:
    """:func:`fit_person` of a person's inputs: their photos' silhouettes (or their own
    masks; a side photo from the right mirrored) and, through a pinhole camera, the
    photos' intrinsics; ``Fit.photos`` says what was read (and, through a pinhole camera,
    ``pitch_deg``: each camera's pitch as fitted, degrees).

    Where neither the user nor the feet tell which side the side photo shows, the person
    is fitted both ways and the fit with the lower answer cost kept; ``Fit.photos``
    then holds ``side_costs``, each way's answer cost, and ``Fit.seconds`` both fits'.

    Raises:
        UserError: the inputs' problems
            (:func:`~bodyfit.fitter.fit.person.person_silhouettes`).
    """
    photos = person_silhouettes(inputs, settings.projection)

    def fitted(photos):
        return fit_person(model, photos.masks, inputs.height_cm / 100.0, settings, progress,
                          photos.intrinsics, inputs.sex, inputs.mass_kg)

    read = {}
    if photos.side_from == "unknown":
        ways = {"left": photos, "right": mirrored_side(photos)}
        fits = {side: fitted(way) for side, way in ways.items()}
        costs = {side: answer_cost(f.search) for side, f in fits.items()}
        side = min(costs, key=costs.get)
        photos = dataclasses.replace(ways[side], side_from=side)
        fit = dataclasses.replace(fits[side], seconds={
            stage: sum(f.seconds[stage] for f in fits.values()) for stage in fits[side].seconds})
        read["side_costs"] = {side: round(cost, 2) for side, cost in costs.items()}
    else:
        fit = fitted(photos)
    read = {"camera": photos.camera_source or "orthographic", "side_from": photos.side_from,
            **read}
    if photos.check is not None:
        read["check_warnings"] = list(photos.check)
    poor = match_warning(answer_cost(fit.search), fit.spread_basis)
    if poor is not None:
        read["fit_warning"] = poor
    if settings.projection == "pinhole":
        read["pitch_deg"] = {name: round(view_pitch_deg(view), 2) + 0.0  # not -0.0
                             for name, view in fit.views.items()}
    return dataclasses.replace(fit, photos=read, masks=photos.masks, images=photos.images)
