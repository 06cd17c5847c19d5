"""The search: an optimiser asks for candidate bodies, the kernels score them, repeat.

A candidate is a vector of genes: the K shape coefficients (betas, in standard
deviations, within +-``SearchSettings.beta_limit``; the first one left out and solved
from the stature when ``condition_stature``) and the four abduction angles of
``POSE_NAMES`` in degrees, within the pose bounds. Any optimiser of
:mod:`bodyfit.fitter.fit.optimizers` drives it through ask/tell; the kernels'
:class:`~bodyfit.kernels.PopulationEvaluator` scores each population in one call.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from tqdm import tqdm

from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.optimizers import OPTIMIZER_NAMES, make_optimizer
from bodyfit.fitter.model.body_model import POSE_NAMES

__all__ = ["SearchSettings", "SearchResult", "search", "searches_together", "averaged", "refined",
           "REFINE_SIGMA0"]

#: The refinement's initial step (``SearchSettings.refine_components``), a fraction of every
#: gene's range: 0.5 sd of a beta, 3 degrees of an angle (on the first 20 out-of-space
#: subjects, 0.05 for 100 generations gained 0.2 mm, 0.08 for 250 gained 2.0:
#: docs/history.md, [14]; two refinements at 0.04 against 0.08 on the first 40 of each
#: set: -0.42 mm in-space, +0.15 out-of-space, [16]).
REFINE_SIGMA0 = 0.08


@dataclasses.dataclass(frozen=True)
class SearchSettings:
    """How the body space is searched.

    Attributes:
        optimizer: one of ``OPTIMIZER_NAMES`` (``"ga"``: the paper's genetic algorithm;
            default ``"cmaes"``, chosen by measured error: docs/fitter.md).
        population: candidates per generation (None: the optimiser's default, the GA's
            is the paper's 30).
        generations: generations at most (None: the optimiser's default, the GA's is the
            paper's 25).
        components: K, shape components searched (the paper: 20; up to those stored).
        beta_limit: betas lie within +-this many standard deviations (the paper: 3).
        pose_lower_deg, pose_upper_deg: bounds of the four abduction angles, degrees
            (the paper: 0-30; people also hold their limbs a little closer than the
            model's A-pose, hence -10 by default).
        sigma0: CMA-ES's initial step, a fraction of every gene's range (0.1: 0.6 sd of
            a beta, 4 degrees of an angle; chosen by measured error, docs/fitter.md);
            the GA has none.
        seed: the optimiser's random seed; the same seed gives the same search.
        condition_stature: solve each candidate's first beta so that it stands as tall as
            the person (:mod:`bodyfit.fitter.fit.stature`) instead of searching it (the paper
            searches it).
        searches: independent searches of each person (seeds ``seed``, ``seed + 1``, ...),
            whose answers the fit averages (:func:`averaged`; the paper: 1); 0: no
            population search (the fit's local solver starts from the mean body). One search's
            answer varies with its seed by about as much as its error (its cost's noise
            floor is flat across millimetres of shape), so the mean of two is nearer the
            truth (docs/history.md, [13]).
        refine_components: K' > K: after the searches, ``refinements`` more searches
            (CMA-ES's, seeds ``seed``, ``seed + 1``, ...) over the first K' components and
            the angles, each started from the searches' answer (the components past K at
            0) with a step of ``REFINE_SIGMA0``, for ``refine_generations`` generations of
            ``population``, their answers averaged; the components past K carry the shape K
            cannot (with K = 20, 7.1 mm of the 7 important measurements of real bodies).
            One refinement alone varies with its seed by about its error; two averaged
            gained 2.0 mm out-of-space and lost 0.6 in-space (200 subjects of each set),
            four gained 0.4 mm more in each set (the first 40; docs/history.md, [14-16]).
            0: none (the paper).
        refine_generations: each refinement's generations. 500 against 250: -0.25 mm
            in-space and -0.67 out-of-space on 20 subjects of each set, for 1.6x the
            time; the refinements converge (cma stops) by about 900, 750 gained 0.1 mm
            more out-of-space only (docs/history.md, [19]).
        refinements: how many refinements are averaged. Their answers scatter about the
            body the silhouettes fix, each by about its error (the cost is flat across
            millimetres of shape), so their mean is nearer: four against two, -0.42 mm
            in-space and -0.40 out-of-space on the first 40 subjects of each set
            (docs/history.md, [16]); six against four, -0.18 +- 0.11 mm over 54
            subjects of both sets, each subject's own fits, for 1.43x the candidates
            ([24]-[27]).
    """

    optimizer: str = "cmaes"
    population: int | None = 30
    generations: int | None = 150
    components: int = 20
    beta_limit: float = 3.0
    pose_lower_deg: tuple[float, ...] = (-10.0,) * len(POSE_NAMES)
    pose_upper_deg: tuple[float, ...] = (30.0,) * len(POSE_NAMES)
    sigma0: float = 0.1
    seed: int = 0
    condition_stature: bool = True
    searches: int = 2
    refine_components: int = 40
    refine_generations: int = 500
    refinements: int = 6

    def validate(self, stored_components: int) -> None:
        if self.optimizer not in OPTIMIZER_NAMES:
            raise UserError(f"--optimizer must be one of {', '.join(OPTIMIZER_NAMES)}, "
                            f"got {self.optimizer!r}")
        if not 1 <= self.components <= stored_components:
            raise UserError(f"--components must be 1-{stored_components} (the components "
                            f"the body model stores), got {self.components}")
        if self.refine_components and not (self.components < self.refine_components
                                           <= stored_components):
            raise UserError(f"--refine-components must be 0 or {self.components + 1}-"
                            f"{stored_components} (more than --components, at most those "
                            f"the body model stores), got {self.refine_components}")
        for name, value, least in (("--population", self.population, 4),
                                   ("--generations", self.generations, 1),
                                   ("--searches", self.searches, 0),
                                   ("--refine-generations", self.refine_generations, 1),
                                   ("--refinements", self.refinements, 1)):
            if value is not None and value < least:
                raise UserError(f"{name} must be at least {least}, got {value}")
        if self.refine_components and not self.searches:
            raise UserError("--refine-components refines the searches' answer: it needs "
                            "--searches 1 or more")
        if not all(lo < hi for lo, hi in zip(self.pose_lower_deg, self.pose_upper_deg)):
            raise UserError("every pose lower bound must lie below its upper bound")
        if not self.beta_limit > 0:
            raise UserError(f"--beta-limit must be above 0, got {self.beta_limit}")
        if not 0 < self.sigma0 <= 1:
            raise UserError(f"sigma0 must be in (0, 1], a fraction of each gene's range, "
                            f"got {self.sigma0}")

    def refinement(self) -> "SearchSettings":
        """The settings of the refinement search (``refine_components``)."""
        return dataclasses.replace(self, optimizer="cmaes", components=self.refine_components,
                                   generations=self.refine_generations, sigma0=REFINE_SIGMA0,
                                   searches=self.refinements, refine_components=0)

    @property
    def searched_betas(self) -> int:
        """Betas among the genes: K, or K - 1 when the first is solved from the stature."""
        return self.components - int(self.condition_stature)

    @property
    def lower(self) -> np.ndarray:
        """(searched betas + 4,) float64 lower bounds of the genes."""
        return np.r_[np.full(self.searched_betas, -self.beta_limit), self.pose_lower_deg]

    @property
    def upper(self) -> np.ndarray:
        """(searched betas + 4,) float64 upper bounds of the genes."""
        return np.r_[np.full(self.searched_betas, self.beta_limit), self.pose_upper_deg]


@dataclasses.dataclass(frozen=True)
class SearchResult:
    """The outcome of :func:`search`.

    Attributes:
        betas: (K,) float64 the search's answer, standard deviations: the centre of the
            optimiser's distribution at the end where it keeps one (CMA-ES's mean: it
            averages the last generations' best candidates, where the best candidate
            ever scored is partly chosen by the raster's noise), else the best candidate.
        pose_deg: (4,) float64 the answer's pose, degrees, ``POSE_NAMES`` order.
        cost: the answer's cost, weighted millimetres.
        part_costs: (12,) float32, the answer's terms (``kernels.TERM_NAMES``).
        best_costs, mean_costs: (G,) per generation, the best so far and the mean of the
            finite costs of that generation.
        best_betas: (G, K) per generation, the betas the search would have answered with
            had it stopped there: the optimiser's centre (CMA-ES), else the best candidate
            so far (the first candidate until one is scored); the last is the answer's.
        final_genes: (P, K + 4) float64 the last population (all K betas, then the pose),
            ``final_costs`` (P,) its costs.
        evaluations: candidates scored; generations: G; seconds: wall time.
        stop_reasons: the optimiser's reasons for stopping.
        averaged_from: the results whose answers were averaged into this one
            (:func:`averaged`; after :func:`refined`, the refinements'); () for one search.
        elbow_deg: the elbows' flexion of the answer, degrees (the local solver's
            ``elbows="fitted"``); None: the rest pose's.
        hand_twist_deg: (2,) the front photo's left and right hands' twists of the answer,
            degrees (the local solver's ``hands="fitted"``; 0 palm in, 90 palm forward);
            None: the rest pose's.
    """

    betas: np.ndarray
    pose_deg: np.ndarray
    cost: float
    part_costs: np.ndarray
    best_costs: np.ndarray
    mean_costs: np.ndarray
    best_betas: np.ndarray
    final_genes: np.ndarray
    final_costs: np.ndarray
    evaluations: int
    generations: int
    seconds: float
    stop_reasons: dict
    averaged_from: tuple["SearchResult", ...] = ()
    elbow_deg: float | None = None
    hand_twist_deg: np.ndarray | None = None


class _Search:
    """One search between generations: its optimiser and its per-generation records
    (:func:`search` runs one, :func:`searches_together` several in one population)."""

    def __init__(self, settings: SearchSettings, conditioner, start: np.ndarray | None):
        if settings.condition_stature and conditioner is None:
            raise ValueError("condition_stature needs a StatureConditioner")
        options = {} if settings.generations is None else {"generations": settings.generations}
        if settings.optimizer == "cmaes":
            options["sigma0"] = settings.sigma0
            if start is not None:
                options["x0"] = tuple(np.clip(start, settings.lower, settings.upper))
        elif start is not None:
            raise ValueError("only CMA-ES starts from given genes")
        self.settings, self.conditioner = settings, conditioner
        self.k = settings.searched_betas
        self.optimizer = make_optimizer(settings.optimizer, settings.lower, settings.upper,
                                        population=settings.population, seed=settings.seed,
                                        **options)
        self.best_costs, self.mean_costs, self.answers = [], [], []
        self.running = (np.inf, None)  # the best cost and genes scored so far

    def betas_of(self, genes: np.ndarray) -> np.ndarray:
        """(P, K) betas of (P, genes) candidates."""
        if not self.settings.condition_stature:
            return genes[:, :self.k]
        return self.conditioner.complete(genes[:, :self.k], genes[:, self.k:])

    def ask(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The next population: its genes (P, searched betas + 4), betas (P, K) and pose
        (P, 4), degrees."""
        genes = self.optimizer.ask()
        return genes, self.betas_of(genes), genes[:, self.k:]

    def tell(self, genes: np.ndarray, costs: np.ndarray) -> None:
        """Take back the asked ``genes`` with their (P,) costs; record the generation."""
        costs = np.asarray(costs, np.float64)
        self.optimizer.tell(genes, costs)
        finite = costs[np.isfinite(costs)]
        if finite.size and finite.min() < self.running[0]:
            self.running = (finite.min(), genes[np.flatnonzero(costs == finite.min())[0]])
        centre = self.optimizer.centre  # the answer had the search stopped here
        self.answers.append(centre if centre is not None else
                            genes[0] if self.running[1] is None else self.running[1])
        self.best_costs.append(self.optimizer.best_cost)
        self.mean_costs.append(float(finite.mean()) if finite.size else np.inf)

    def forget_best(self) -> None:
        """The costs from now on are not comparable with the earlier ones."""
        self.optimizer.forget_best()
        self.running = (np.inf, None)

    def result(self, evaluator, seconds: float) -> SearchResult:
        """The search's :class:`SearchResult`, its answer scored by ``evaluator``."""
        result, k = self.optimizer.result, self.k
        if not np.isfinite(result.best_cost):
            raise UserError("no candidate body produced a silhouette; check the photos and "
                            "masks")
        # the centre, unless it draws no silhouette; the best candidate ever scored did
        for answer in (c for c in (result.centre, result.best_candidate) if c is not None):
            answer_betas = self.betas_of(answer[None])
            scored = evaluator.evaluate(answer_betas, answer[None, k:])  # cost and terms
            if np.isfinite(scored.costs[0]):
                break
        return SearchResult(
            betas=answer_betas[0], pose_deg=answer[k:], cost=float(scored.costs[0]),
            part_costs=scored.part_costs[0], best_costs=np.array(self.best_costs),
            best_betas=self.betas_of(np.array(self.answers)),
            mean_costs=np.array(self.mean_costs),
            final_genes=np.concatenate([self.betas_of(result.population),
                                        result.population[:, k:]], axis=1),
            final_costs=result.population_costs, evaluations=result.evaluations,
            generations=result.generations, seconds=seconds,
            stop_reasons=result.stop_reasons)


def _progress_bar(description: str, progress: bool | None) -> tqdm:
    return tqdm(desc=description, unit="gen", dynamic_ncols=True,
                disable=None if progress is None else not progress)


def search(evaluator, settings: SearchSettings, conditioner=None,
           progress: bool | None = None, on_generation=None,
           start: np.ndarray | None = None) -> SearchResult:
    """Search the body space against the evaluator's views.

    Args:
        evaluator: a :class:`bodyfit.kernels.PopulationEvaluator` over the person's views,
            built for ``settings.components`` betas.
        settings: the optimiser and the space.
        conditioner: a :class:`bodyfit.fitter.fit.stature.StatureConditioner`, required when
            ``settings.condition_stature``: it turns the searched genes into full betas.
        progress: a progress bar with the best cost per generation on stderr (None: only
            when stderr is a terminal).
        on_generation: None, or called after each generation with (generations done, the
            best candidate's betas (K,), its pose (4,)); when it returns True, the costs
            from the next generation on are not comparable with the earlier ones (it moved
            the evaluator's cameras), and the best so far is forgotten.
        start: None, or (searched betas + 4,) genes CMA-ES's distribution starts from
            (clipped to the bounds); None: the middle of the bounds (the mean body).
    """
    run = _Search(settings, conditioner, start)
    began = time.perf_counter()
    with _progress_bar(f"search ({settings.optimizer})", progress) as bar:
        while not run.optimizer.stop():
            genes, betas, pose = run.ask()
            run.tell(genes, evaluator.evaluate(betas, pose).costs)
            bar.update(1)
            bar.set_postfix(best=f"{run.best_costs[-1]:.1f}")
            best = run.running[1]
            if on_generation is not None and best is not None and on_generation(
                    len(run.best_costs), run.betas_of(best[None])[0], best[run.k:]):
                run.forget_best()
    return run.result(evaluator, time.perf_counter() - began)


def searches_together(evaluator, settings: list[SearchSettings], conditioner=None,
                      progress: bool | None = None,
                      start: np.ndarray | None = None) -> list[SearchResult]:
    """Several searches (one per ``settings``, e.g. other seeds) run side by side: each
    generation, their populations are scored in one call of the evaluator, so a GPU gets
    one launch of S x P candidates instead of S of P. Every candidate is scored on its
    own, so each result equals :func:`search`'s with the same arguments (its ``seconds``:
    the wall time divided among the searches). Arguments as :func:`search`'s, without
    ``on_generation`` (the searches share the evaluator's cameras)."""
    runs = [_Search(s, conditioner, start) for s in settings]
    began = time.perf_counter()
    names = ", ".join(sorted({s.optimizer for s in settings}))
    with _progress_bar(f"{len(runs)} searches ({names})", progress) as bar:
        while active := [run for run in runs if not run.optimizer.stop()]:
            asked = [run.ask() for run in active]
            costs = evaluator.evaluate(np.concatenate([betas for _, betas, _ in asked]),
                                       np.concatenate([pose for _, _, pose in asked])).costs
            ends = np.cumsum([len(genes) for genes, _, _ in asked])
            for run, (genes, _, _), part in zip(active, asked, np.split(costs, ends[:-1])):
                run.tell(genes, part)
            bar.update(1)
            bar.set_postfix(best=f"{min(run.best_costs[-1] for run in runs):.1f}")
    seconds = (time.perf_counter() - began) / len(runs)
    return [run.result(evaluator, seconds) for run in runs]


def _padded(curves: list[np.ndarray]) -> np.ndarray:
    """(S, G, ...) of S per-generation curves of up to G generations, each padded with its
    last value (a search that stopped early stays where it ended)."""
    length = max(len(c) for c in curves)
    return np.stack([np.concatenate([c, np.repeat(c[-1:], length - len(c), axis=0)])
                     for c in curves])


def averaged(results: list[SearchResult], betas: np.ndarray, pose_deg: np.ndarray,
             cost: float, part_costs: np.ndarray) -> SearchResult:
    """One result for several searches of a person whose answers were averaged into
    (``betas`` (K,), ``pose_deg`` (4,)), scored ``cost`` with ``part_costs`` (12,).

    The per-generation curves are the searches' means (``best_betas``: the mean of their
    answers had they stopped there, as the averaged answer is formed); the final
    population is all of theirs; evaluations and seconds add up.
    """
    return SearchResult(
        betas=betas, pose_deg=pose_deg, cost=cost, part_costs=part_costs,
        best_costs=_padded([r.best_costs for r in results]).mean(axis=0),
        mean_costs=_padded([r.mean_costs for r in results]).mean(axis=0),
        best_betas=_padded([r.best_betas for r in results]).mean(axis=0),
        final_genes=np.concatenate([r.final_genes for r in results]),
        final_costs=np.concatenate([r.final_costs for r in results]),
        evaluations=sum(r.evaluations for r in results),
        generations=max(r.generations for r in results),
        seconds=sum(r.seconds for r in results),
        stop_reasons={k: v for r in results for k, v in r.stop_reasons.items()},
        averaged_from=tuple(results))


def refined(first: SearchResult, refinement: SearchResult) -> SearchResult:
    """One result for a search (or searches averaged) ``first`` over K components followed
    by its ``refinement`` over K' > K: the refinement's answer; the per-generation curves
    one after the other (``first``'s betas padded with zeros to K'); both final
    populations (for the spreads); evaluations, generations and seconds added up."""
    def padded(betas: np.ndarray) -> np.ndarray:
        width = [(0, 0)] * (betas.ndim - 1) + [(0, len(refinement.betas) - betas.shape[-1])]
        return np.pad(betas, width)

    k = len(first.betas)
    first_genes = np.concatenate([padded(first.final_genes[:, :k]), first.final_genes[:, k:]],
                                 axis=1)
    return dataclasses.replace(
        refinement,
        best_costs=np.concatenate([first.best_costs, refinement.best_costs]),
        mean_costs=np.concatenate([first.mean_costs, refinement.mean_costs]),
        best_betas=np.concatenate([padded(first.best_betas), refinement.best_betas]),
        final_genes=np.concatenate([first_genes, refinement.final_genes]),
        final_costs=np.concatenate([first.final_costs, refinement.final_costs]),
        evaluations=first.evaluations + refinement.evaluations,
        generations=first.generations + refinement.generations,
        seconds=first.seconds + refinement.seconds,
        stop_reasons={**first.stop_reasons, **{f"refinement {reason}": value for reason, value
                                               in refinement.stop_reasons.items()}})
