"""Population optimisers behind one ask/tell interface (pycma's shape).

The optimiser never evaluates a cost: the caller asks for a population, evaluates all of
it at once (on the GPU, for thousands of bodies), and tells the costs back::

    opt = make_optimizer("ga", lower, upper, seed=0)
    while not opt.stop():
        candidates = opt.ask()                 # (P, D) float64, inside [lower, upper]
        opt.tell(candidates, cost(candidates))  # (P,) float, lower is better
    opt.result.best_candidate                  # (D,) float64

The search space (paper Section 3.2): a candidate holds D = K + 4 genes, K shape
coefficients (betas, in standard deviations, bounded to +-3) followed by the 4 pose
angles in degrees (shoulder abduction left/right, hip abduction left/right, bounds given
by the caller; the paper uses 0-30). :func:`search_bounds` builds those bounds; the
optimisers themselves take any box ``lower < upper``.

Implementations (``OPTIMIZER_NAMES``):

- ``ga``: :class:`GeneticAlgorithm`, the paper's genetic algorithm (Section 3.4).
- ``cmaes``: :class:`CmaEvolutionStrategy`, CMA-ES from the ``cma`` package, in
  coordinates where every gene's range is [0, 1], with optional IPOP restarts.
"""

from __future__ import annotations

import abc
import dataclasses
import functools
import logging
import typing
import warnings

import numpy as np

if typing.TYPE_CHECKING:
    import cma

@functools.cache
def _cma():
    """The ``cma`` package, imported on first use: with scipy.stats it takes 0.3-0.7 s to
    import, which a fit without a population search (bodyfit's default) never needs."""
    with warnings.catch_warnings():  # cma warns on import when matplotlib is missing
        warnings.filterwarnings("ignore", message="Could not import matplotlib")
        import cma
    return cma


__all__ = [
    "OPTIMIZER_NAMES",
    "BETA_LIMIT_SD",
    "NUM_POSE_ANGLES",
    "PAPER_POSE_RANGE_DEG",
    "search_bounds",
    "OptimizerResult",
    "Optimizer",
    "GeneticSettings",
    "GeneticAlgorithm",
    "draw_parents",
    "draw_cut_points",
    "crossover",
    "mutate",
    "CmaSettings",
    "CmaEvolutionStrategy",
    "make_optimizer",
]

logger = logging.getLogger(__name__)

OPTIMIZER_NAMES = ("ga", "cmaes")
#: Betas are bounded to +-3 standard deviations (paper Section 3.4, initialisation).
BETA_LIMIT_SD = 3.0
#: Pose genes after the betas, in ``bodyfit.fitter.model.body_model.POSE_NAMES`` order.
NUM_POSE_ANGLES = 4
#: The paper's range of the 4 abduction angles, degrees.
PAPER_POSE_RANGE_DEG = (0.0, 30.0)

#: The paper's GA removes "one-third of them, or ten" of 30 chromosomes each generation.
CULLED_FRACTION = 1.0 / 3.0
#: The paper mutates 3 of 30 chromosomes ...
MUTATED_CHROMOSOME_FRACTION = 3.0 / 30.0
#: ... and 5 of the 24 genes of each.
MUTATED_GENE_FRACTION = 5.0 / 24.0


def search_bounds(num_components: int = 20,
                  pose_range_deg: tuple[float, float] = PAPER_POSE_RANGE_DEG,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Box of the fitting search space: ``num_components`` betas in +-3 sd, then 4 angles.

    Returns:
        lower, upper: (num_components + 4,) float64; sd for the betas, degrees for the angles.

    Example:
        >>> lower, upper = search_bounds(2, (-10.0, 30.0))
        >>> lower.tolist(), upper.tolist()
        ([-3.0, -3.0, -10.0, -10.0, -10.0, -10.0], [3.0, 3.0, 30.0, 30.0, 30.0, 30.0])
    """
    lo_deg, hi_deg = pose_range_deg
    lower = np.concatenate([np.full(num_components, -BETA_LIMIT_SD),
                            np.full(NUM_POSE_ANGLES, lo_deg)])
    upper = np.concatenate([np.full(num_components, BETA_LIMIT_SD),
                            np.full(NUM_POSE_ANGLES, hi_deg)])
    return lower, upper


@dataclasses.dataclass(frozen=True, eq=False)
class OptimizerResult:
    """Where a run stands after its last ``tell``.

    Attributes:
        best_candidate: (D,) float64; the best candidate ever told (genes' units).
        best_cost: its cost; +inf when every candidate failed.
        evaluations: candidates told so far, all generations together.
        generations: tells so far.
        population: (P, D) float64; the last generation told, as told.
        population_costs: (P,) float64; its costs (+inf for failed candidates).
        stop_reasons: ``Optimizer.stop()`` at the time; empty while running.
        centre: (D,) float64, the centre of the optimiser's search distribution (CMA-ES:
            its mean, cma's ``xfavorite``), or None where it keeps none (the GA).
    """

    best_candidate: np.ndarray
    best_cost: float
    evaluations: int
    generations: int
    population: np.ndarray
    population_costs: np.ndarray
    stop_reasons: dict[str, object]
    centre: np.ndarray | None = None


class Optimizer(abc.ABC):
    """The ask/tell loop shared by every optimiser (see the module docstring).

    ``ask()`` returns the next population; ``tell()`` takes it back with its costs and
    must follow an ``ask()``. The base class checks what is told (shapes, bounds, costs),
    counts generations and evaluations, and keeps the best candidate; subclasses
    implement ``_ask``, ``_tell`` and ``_stop_reasons``.

    Attributes:
        lower, upper: (D,) float64; bounds of the genes, ``lower < upper``.
        generations: budget of generations; ``stop()`` reports it when reached.
        generation: tells so far.
    """

    def __init__(self, lower: np.ndarray, upper: np.ndarray, generations: int):
        self.lower, self.upper = _checked_bounds(lower, upper)
        if generations < 1:
            raise ValueError(f"generations must be at least 1, got {generations}")
        self.generations = int(generations)
        self.generation = 0
        self._evaluations = 0
        self._asked: np.ndarray | None = None
        self._best_candidate: np.ndarray | None = None
        self._best_cost = np.inf
        self._population: np.ndarray | None = None
        self._population_costs: np.ndarray | None = None

    @property
    def num_genes(self) -> int:
        return self.lower.size

    @property
    def best_cost(self) -> float:
        """The best cost told so far (+inf before the first tell); cheaper than ``result``."""
        return self._best_cost

    def forget_best(self) -> None:
        """Forget the best candidate told so far: the costs told from now on are not
        comparable with the earlier ones (the views' cameras moved, say)."""
        self._best_candidate, self._best_cost = None, np.inf

    @property
    @abc.abstractmethod
    def population_size(self) -> int:
        """P, the number of candidates the next ``ask()`` returns."""

    def ask(self) -> np.ndarray:
        """The next population: (P, D) float64, every gene inside its bounds.

        Raises:
            RuntimeError: the run has stopped (read ``result``).
        """
        reasons = self.stop()
        if reasons:
            raise RuntimeError(f"the optimiser has stopped ({reasons}); read its result")
        self._asked = self._ask()
        return self._asked.copy()

    def tell(self, candidates: np.ndarray, costs: np.ndarray) -> None:
        """Take back the asked population with its costs.

        Args:
            candidates: (P, D) float; the population ``ask()`` returned (the GA also
                accepts other candidates of that shape inside the bounds).
            costs: (P,) float, lower is better; +inf marks a failed candidate.

        Raises:
            RuntimeError: no ``ask()`` is waiting for its ``tell()``.
            ValueError: wrong shapes, candidates outside the bounds, NaN or -inf costs.
        """
        if self._asked is None:
            raise RuntimeError("tell() must follow an ask()")
        candidates = np.asarray(candidates, dtype=np.float64)
        costs = np.asarray(costs, dtype=np.float64)
        if candidates.shape != self._asked.shape:
            raise ValueError(f"candidates must have shape {self._asked.shape} (P, D) like the "
                             f"asked population, got {candidates.shape}")
        if costs.shape != (len(candidates),):
            raise ValueError(f"costs must have shape ({len(candidates)},), got {costs.shape}")
        if np.isnan(costs).any() or (costs == -np.inf).any():
            raise ValueError("costs must be numbers or +inf (failed candidate); got NaN or -inf")
        if not np.all((candidates >= self.lower) & (candidates <= self.upper)):
            raise ValueError("candidates must lie inside [lower, upper]")
        best = int(np.argmin(costs))
        if self._best_candidate is None or costs[best] < self._best_cost:
            self._best_candidate, self._best_cost = candidates[best].copy(), float(costs[best])
        self._population, self._population_costs = candidates.copy(), costs.copy()
        self._evaluations += len(costs)
        self.generation += 1
        self._tell(candidates, costs)
        self._asked = None

    def stop(self) -> dict[str, object]:
        """Why the run has stopped: {} while it runs, else e.g. {"generations": 25}."""
        if self.generation >= self.generations:
            return {"generations": self.generations}
        return self._stop_reasons()

    @property
    def result(self) -> OptimizerResult:
        """The run so far (see :class:`OptimizerResult`).

        Raises:
            RuntimeError: nothing has been told yet.
        """
        if self._best_candidate is None:
            raise RuntimeError("no population has been told yet")
        return OptimizerResult(
            best_candidate=self._best_candidate.copy(), best_cost=self._best_cost,
            evaluations=self._evaluations, generations=self.generation,
            population=self._population.copy(), population_costs=self._population_costs.copy(),
            stop_reasons=self.stop(), centre=self.centre)

    @property
    def centre(self) -> np.ndarray | None:
        """(D,) the search distribution's centre in genes' units, or None where the
        optimiser keeps none (the default)."""
        return None

    @abc.abstractmethod
    def _ask(self) -> np.ndarray:
        """(P, D) float64 inside the bounds."""

    @abc.abstractmethod
    def _tell(self, candidates: np.ndarray, costs: np.ndarray) -> None:
        """Update from checked (P, D) candidates and (P,) costs (may hold +inf)."""

    @abc.abstractmethod
    def _stop_reasons(self) -> dict[str, object]:
        """Reasons to stop other than the generation budget."""


def _checked_bounds(lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    lower = np.array(lower, dtype=np.float64)
    upper = np.array(upper, dtype=np.float64)
    if lower.ndim != 1 or lower.shape != upper.shape or lower.size == 0:
        raise ValueError(f"lower and upper must be (D,) vectors of one length, got shapes "
                         f"{lower.shape} and {upper.shape}")
    if not (np.isfinite(lower).all() and np.isfinite(upper).all() and (lower < upper).all()):
        raise ValueError("bounds must be finite with lower < upper for every gene")
    return lower, upper


# ------------------------------------------------------------------ genetic algorithm
@dataclasses.dataclass(frozen=True)
class GeneticSettings:
    """The GA's sizes; defaults are the paper's (Section 3.4).

    Counts left at None scale with the population P and the genes D like the paper's
    30 x 24 run: ``culled = round(P / 3)`` (10 of 30), ``mutated_chromosomes =
    max(1, round(P / 10))`` (3 of 30), ``mutated_genes = max(1, round(5 D / 24))``
    (5 of 24). So 3000 chromosomes cull 1000 and mutate 300 per generation.

    Attributes:
        population: chromosomes per generation, P >= 3.
        generations: generations evaluated.
        culled: worst chromosomes removed each generation, 1 <= culled <= P - 2 (so
            at least two parents survive), replaced by crossover children.
        mutated_chromosomes: chromosomes mutated each generation, <= P - 1 (the best
            one is never mutated).
        mutated_genes: genes redrawn in each mutated chromosome, 1 <= n <= D.
    """

    population: int = 30
    generations: int = 25
    culled: int | None = None
    mutated_chromosomes: int | None = None
    mutated_genes: int | None = None

    def counts(self, num_genes: int) -> tuple[int, int, int]:
        """(culled, mutated_chromosomes, mutated_genes) for D = ``num_genes``, checked."""
        p = self.population
        if p < 3:
            raise ValueError(f"the GA needs a population of at least 3, got {p}")
        culled = round(p * CULLED_FRACTION) if self.culled is None else self.culled
        chromosomes = (max(1, round(p * MUTATED_CHROMOSOME_FRACTION))
                       if self.mutated_chromosomes is None else self.mutated_chromosomes)
        genes = (max(1, round(num_genes * MUTATED_GENE_FRACTION))
                 if self.mutated_genes is None else self.mutated_genes)
        if not 1 <= culled <= p - 2:
            raise ValueError(f"culled must be 1..{p - 2} for a population of {p}, got {culled}")
        if not 0 <= chromosomes <= p - 1:
            raise ValueError(f"mutated_chromosomes must be 0..{p - 1}, got {chromosomes}")
        if not 1 <= genes <= num_genes:
            raise ValueError(f"mutated_genes must be 1..{num_genes}, got {genes}")
        return culled, chromosomes, genes


class GeneticAlgorithm(Optimizer):
    """The paper's genetic algorithm (Section 3.4), with explicit elitism.

    What the paper specifies, with its defaults:

    - initialisation: 30 chromosomes of 24 genes, every gene uniform in its bounds
      (betas in +-3 sd, angles in 0-30 degrees there; here the caller's bounds);
    - each generation: evaluate, sort by cost, remove the worst third (10);
    - "one-point and two-point crossover randomly apply on the remaining chromosomes"
      to bring the population back to 30;
    - mutation of 5 of the 24 genes in 3 randomly chosen of the 30 chromosomes, "by
      mutation values";
    - 25 generations (Section 4).

    What the paper leaves open, and the choices made here:

    - the 20 survivors stay in the next generation and 10 children fill it up (the
      paper's "generate the next 30 chromosomes" could also read as 30 children);
    - each child comes from its own pair of distinct survivors, drawn uniformly
      (:func:`draw_parents`), and its own operator: one-point or two-point with
      probability 1/2 each, cut points uniform (:func:`draw_cut_points`,
      :func:`crossover`);
    - a mutated gene is redrawn uniformly in its bounds (:func:`mutate`), as at
      initialisation, since the paper gives no distribution for its "mutation values";
      the 5 genes of a chromosome are distinct;
    - elitism: the paper does not say. Here the best chromosome of a generation is row 0
      of the next one, and mutation picks its chromosomes among the other P - 1, so the
      best chromosome is never lost and, with a deterministic cost, the best cost of a
      generation never rises. Any survivor or child may be mutated.

    Stops only on the generation budget, like the paper. Seeded with a
    ``numpy.random.Generator``: one seed, one run.
    """

    def __init__(self, lower: np.ndarray, upper: np.ndarray,
                 settings: GeneticSettings = GeneticSettings(), seed: int = 0):
        super().__init__(lower, upper, settings.generations)
        if self.num_genes < 3:
            raise ValueError(f"two-point crossover needs at least 3 genes, got {self.num_genes}")
        self.settings = settings
        self.culled, self.mutated_chromosomes, self.mutated_genes = settings.counts(self.num_genes)
        self._rng = np.random.default_rng(seed)
        self._population_next = self._rng.uniform(
            self.lower, self.upper, size=(settings.population, self.num_genes))

    @property
    def population_size(self) -> int:
        return self.settings.population

    def _ask(self) -> np.ndarray:
        return self._population_next

    def _tell(self, candidates: np.ndarray, costs: np.ndarray) -> None:
        ranked = candidates[np.argsort(costs, kind="stable")]
        survivors = ranked[: len(ranked) - self.culled]
        first, second = draw_parents(self._rng, len(survivors), self.culled)
        cut_start, cut_end = draw_cut_points(self._rng, self.culled, self.num_genes)
        children = crossover(survivors[first], survivors[second], cut_start, cut_end)
        population = np.concatenate([survivors, children])
        rows = 1 + self._rng.choice(len(population) - 1, size=self.mutated_chromosomes,
                                    replace=False)  # row 0, the elite, is never mutated
        self._population_next = mutate(population, rows, self.mutated_genes,
                                       self.lower, self.upper, self._rng)

    def _stop_reasons(self) -> dict[str, object]:
        return {}


def draw_parents(rng: np.random.Generator, num_survivors: int,
                 num_children: int) -> tuple[np.ndarray, np.ndarray]:
    """Parent pairs for ``num_children`` children: uniform pairs of distinct survivors.

    Returns:
        first, second: (num_children,) int64 row indices into the survivors, first != second.
    """
    first = rng.integers(num_survivors, size=num_children)
    second = (first + rng.integers(1, num_survivors, size=num_children)) % num_survivors
    return first, second


def draw_cut_points(rng: np.random.Generator, num_children: int,
                    num_genes: int) -> tuple[np.ndarray, np.ndarray]:
    """Crossover cut points: half the children one-point, half two-point, on average.

    A one-point child has one cut c uniform in 1..D-1, returned as (c, D); a two-point
    child two distinct cuts uniform in 1..D-1, returned sorted. Every cut falls between
    genes, so both parents give at least one gene.

    Returns:
        cut_start, cut_end: (num_children,) int64, 1 <= cut_start < cut_end <= D.
    """
    two_point = rng.random(num_children) < 0.5
    a = rng.integers(1, num_genes, size=num_children)
    b = rng.integers(1, num_genes - 1, size=num_children)
    b = b + (b >= a)  # uniform over 1..D-1 without a
    cut_start = np.where(two_point, np.minimum(a, b), a)
    cut_end = np.where(two_point, np.maximum(a, b), num_genes)
    return cut_start, cut_end


def crossover(parents_a: np.ndarray, parents_b: np.ndarray, cut_start: np.ndarray,
              cut_end: np.ndarray) -> np.ndarray:
    """Children with genes [cut_start, cut_end) of parent B and the rest of parent A.

    One-point crossover at c is ``cut_end = D``: ``A[:c] + B[c:]``; two-point at
    c1 < c2 is ``A[:c1] + B[c1:c2] + A[c2:]``.

    Args:
        parents_a, parents_b: (n, D) float64.
        cut_start, cut_end: (n,) int, 0 <= cut_start <= cut_end <= D.

    Returns:
        (n, D) float64 children.

    Example:
        >>> a, b = np.zeros((1, 5)), np.ones((1, 5))
        >>> crossover(a, b, np.array([1]), np.array([3])).tolist()
        [[0.0, 1.0, 1.0, 0.0, 0.0]]
    """
    gene = np.arange(parents_a.shape[1])
    from_b = (gene >= np.asarray(cut_start)[:, None]) & (gene < np.asarray(cut_end)[:, None])
    return np.where(from_b, parents_b, parents_a)


def mutate(population: np.ndarray, rows: np.ndarray, genes_per_row: int, lower: np.ndarray,
           upper: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Redraw ``genes_per_row`` distinct genes of each chromosome in ``rows``.

    A redrawn gene is uniform in its bounds [lower, upper).

    Args:
        population: (P, D) float64; not modified.
        rows: (m,) int, distinct rows to mutate.
        genes_per_row: genes redrawn per mutated row, <= D.
        lower, upper: (D,) float64 bounds.

    Returns:
        (P, D) float64, the population with those genes redrawn.
    """
    mutated = population.copy()
    rows = np.asarray(rows, dtype=np.int64)
    genes = np.argsort(rng.random((len(rows), population.shape[1])), axis=1)[:, :genes_per_row]
    mutated[rows[:, None], genes] = rng.uniform(lower[genes], upper[genes])
    return mutated


# ---------------------------------------------------------------------------- CMA-ES
@dataclasses.dataclass(frozen=True)
class CmaSettings:
    """CMA-ES settings. Genes are searched in normalised coordinates
    ``u = (x - lower) / (upper - lower)`` in [0, 1], so a step of 0.1 is 0.6 sd of a
    beta in +-3 sd and 4 degrees of an angle in -10..30: betas and degrees move alike.

    Attributes:
        population: candidates per generation (cma's ``popsize``); None: cma's default
            4 + floor(3 ln D), 13 for D = 24.
        generations: budget of generations, restarts included.
        sigma0: initial step size in normalised units (a quarter of every gene's range).
        x0: (D,) start mean in genes' units, inside the bounds; None: the middle of the
            bounds (betas 0 for symmetric beta bounds).
        restarts: IPOP restarts allowed: when cma stops before the generation budget,
            it starts again from the best candidate so far with twice the population
            and ``sigma0``. 0: no restarts.
    """

    population: int | None = None
    generations: int = 25
    sigma0: float = 0.25
    x0: tuple[float, ...] | None = None
    restarts: int = 0


def _finite_costs(costs: np.ndarray) -> np.ndarray:
    """Costs cma can take, (P,) float64: cma needs finite values, and ranks them.

    A failed (+inf) candidate is told as the worst finite cost of its generation plus
    max(1, |worst|), so it ranks below every finite one. A generation without any
    finite cost is not told to cma at all (see ``CmaEvolutionStrategy._tell``).
    """
    finite = np.isfinite(costs)
    worst = costs[finite].max()
    return np.where(finite, costs, worst + max(1.0, abs(worst)))


class CmaEvolutionStrategy(Optimizer):
    """CMA-ES (``cma.CMAEvolutionStrategy``) in the ask/tell interface.

    cma searches the normalised coordinates of :class:`CmaSettings`, bounded to
    [0, 1] by cma's ``BoundTransform`` (its ``bounds`` option), so every candidate is
    inside the bounds. Its Gaussian samples come from a ``numpy.random.Generator``
    seeded with ``seed`` (cma's ``randn`` option), not numpy's global state: one seed,
    one run, whatever else draws random numbers meanwhile.

    ``stop()`` returns cma's own reasons under cma's names (e.g. ``{"tolfun": 1e-11}``,
    ``{"tolstagnation": ...}``, ``{"tolflatfitness": 1}``) once no restart is left,
    and ``{"generations": n}`` at the budget (restarts share it). A generation where every
    candidate failed (+inf) counts against the budget but leaves cma as it was: an
    all-equal generation would end cma at once ("tolfun"); other +inf costs are ranked
    last (``_finite_costs``); ``result`` keeps the true costs. After a restart
    ``population_size`` doubles.
    """

    def __init__(self, lower: np.ndarray, upper: np.ndarray,
                 settings: CmaSettings = CmaSettings(), seed: int = 0):
        super().__init__(lower, upper, settings.generations)
        if settings.sigma0 <= 0 or settings.restarts < 0:
            raise ValueError(f"sigma0 must be > 0 and restarts >= 0, got {settings.sigma0} "
                             f"and {settings.restarts}")
        if settings.population is not None and settings.population < 2:
            raise ValueError(f"CMA-ES needs a population of at least 2, got {settings.population}")
        x0 = (self.lower + self.upper) / 2 if settings.x0 is None else np.asarray(settings.x0,
                                                                                 dtype=np.float64)
        if x0.shape != self.lower.shape or not np.all((x0 >= self.lower) & (x0 <= self.upper)):
            raise ValueError(f"x0 must be a ({self.num_genes},) vector inside the bounds")
        self.settings = settings
        self.restarts_left = settings.restarts
        self._rng = np.random.default_rng(seed)
        self._asked_normalised: list[np.ndarray] = []
        self._es = self._start(self._normalise(x0), settings.population)

    def _start(self, mean: np.ndarray, population: int | None) -> "cma.CMAEvolutionStrategy":
        options = {"bounds": [0.0, 1.0], "seed": np.nan,  # nan: cma leaves np.random alone
                   "randn": lambda *shape: self._rng.standard_normal(shape),
                   "verbose": -9, "verb_log": 0, "verb_disp": 0}
        if population is not None:
            options["popsize"] = population
        return _cma().CMAEvolutionStrategy(mean, self.settings.sigma0, options)

    def _normalise(self, x: np.ndarray) -> np.ndarray:
        return (x - self.lower) / (self.upper - self.lower)

    def _genes(self, normalised) -> np.ndarray:
        """Genes' units of normalised coordinates, clipped to the bounds (rounding only)."""
        x = self.lower + np.asarray(normalised) * (self.upper - self.lower)
        return np.clip(x, self.lower, self.upper)

    @property
    def population_size(self) -> int:
        return int(self._es.popsize)

    def _ask(self) -> np.ndarray:
        self._asked_normalised = self._es.ask()
        return self._genes(self._asked_normalised)

    def _tell(self, candidates: np.ndarray, costs: np.ndarray) -> None:
        if not np.isfinite(costs).any():
            return  # all failed: cma keeps its state and samples anew at the next ask
        if np.array_equal(candidates, self._asked):  # cma recognises its own solutions
            normalised = self._asked_normalised
        else:
            normalised = list(self._normalise(candidates))
        self._es.tell(normalised, _finite_costs(costs).tolist())
        reasons = self._es.stop()
        if reasons and self.restarts_left and self.generation < self.generations:
            self.restarts_left -= 1
            population = 2 * self.population_size
            logger.info("CMA-ES stopped (%s) at generation %d; restarting with population %d",
                        dict(reasons), self.generation, population)
            self._es = self._start(self._normalise(self._best_candidate), population)

    def _stop_reasons(self) -> dict[str, object]:
        return dict(self._es.stop())

    @property
    def centre(self) -> np.ndarray:
        return self._genes(self._es.result.xfavorite)


# --------------------------------------------------------------------------- factory
def make_optimizer(name: str, lower: np.ndarray, upper: np.ndarray,
                   population: int | None = None, generations: int = 25, seed: int = 0,
                   **options) -> Optimizer:
    """An optimiser by name (``OPTIMIZER_NAMES``) over the box [lower, upper].

    Args:
        name: "ga" or "cmaes".
        lower, upper: (D,) float bounds of the genes.
        population: candidates per generation; None: the optimiser's default (the
            paper's 30 for "ga", cma's 4 + floor(3 ln D) for "cmaes").
        generations: budget of generations.
        seed: seed of the optimiser's random generator.
        **options: further fields of :class:`GeneticSettings` ("ga") or
            :class:`CmaSettings` ("cmaes").

    Raises:
        ValueError: unknown name or option, or values out of range.

    Example:
        >>> lower, upper = search_bounds(20)
        >>> opt = make_optimizer("ga", lower, upper, seed=1)
        >>> while not opt.stop():
        ...     x = opt.ask()
        ...     opt.tell(x, np.sum((x[:, :20] - 1.0) ** 2, axis=1))
        >>> opt.stop(), opt.result.evaluations, opt.result.best_candidate.shape
        ({'generations': 25}, 750, (24,))
    """
    kinds = {"ga": (GeneticAlgorithm, GeneticSettings),
             "cmaes": (CmaEvolutionStrategy, CmaSettings)}
    if name not in kinds:
        raise ValueError(f"unknown optimiser {name!r}; choose one of {OPTIMIZER_NAMES}")
    optimizer, settings_type = kinds[name]
    fields = {f.name for f in dataclasses.fields(settings_type)} - {"population", "generations"}
    unknown = set(options) - fields
    if unknown:
        raise ValueError(f"unknown options {sorted(unknown)} for {name!r}; known: {sorted(fields)}")
    if population is not None:
        options["population"] = population
    settings = settings_type(generations=generations, **options)
    return optimizer(lower, upper, settings, seed)
