"""Optimisers: the GA's operators against the paper's counts, the ask/tell contract of
both optimisers, reproducibility, and the analytic case of a shifted sphere (the minimum
is known). No body model: the costs are written here."""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bodyfit.fitter.fit.optimizers import (CmaEvolutionStrategy, CmaSettings, GeneticAlgorithm,
                                           GeneticSettings, crossover, draw_cut_points,
                                           draw_parents, make_optimizer, mutate, search_bounds,)

LOWER, UPPER = search_bounds(20, (-10.0, 30.0))  # D = 24: 20 betas (sd), 4 angles (deg)
SPAN = UPPER - LOWER
D = LOWER.size


def sphere(target):
    """Squared distance to ``target`` in units of each gene's range: (P, D) -> (P,)."""
    return lambda x: np.sum(((x - target) / SPAN) ** 2, axis=1)


def inner_target(seed):
    """A minimum inside the box, at least 10 % of each range from its bounds (from a
    stream no optimiser seeded with ``seed`` draws)."""
    rng = np.random.default_rng([seed, 999])
    return rng.uniform(LOWER + 0.1 * SPAN, UPPER - 0.1 * SPAN)


def run(opt, cost):
    """Ask/tell until stop; the populations asked, in order."""
    asked = []
    while not opt.stop():
        x = opt.ask()
        asked.append(x)
        opt.tell(x, cost(x))
    return asked


# ------------------------------------------------------------------------ GA operators
def test_one_point_child_is_prefix_of_a_and_suffix_of_b():
    a, b = np.arange(24.0)[None], 100 + np.arange(24.0)[None]
    child = crossover(a, b, np.array([7]), np.array([24]))
    assert child.tolist() == [list(range(7)) + list(range(107, 124))]


def test_two_point_child_takes_the_middle_from_b():
    a, b = np.arange(24.0)[None], 100 + np.arange(24.0)[None]
    child = crossover(a, b, np.array([5]), np.array([12]))
    assert child.tolist() == [list(range(5)) + list(range(105, 112)) + list(range(12, 24))]


def test_cut_points_lie_between_genes_half_one_point_half_two_point():
    start, end = draw_cut_points(np.random.default_rng(0), 20_000, D)
    assert np.all((1 <= start) & (start < end) & (end <= D))
    one_point = end == D
    assert 0.48 < one_point.mean() < 0.52
    assert set(start[one_point]) == set(range(1, D))
    assert set(start[~one_point]) == set(range(1, D - 1))  # two distinct cuts in 1..D-1
    assert set(end[~one_point]) == set(range(2, D))


def test_parents_are_two_distinct_survivors_drawn_uniformly():
    first, second = draw_parents(np.random.default_rng(0), 20, 20_000)
    assert np.all(first != second)
    for parent in (first, second):
        counts = np.bincount(parent, minlength=20)
        assert counts.size == 20 and np.all(np.abs(counts / 1000 - 1) < 0.1)


def test_mutation_redraws_exactly_the_asked_genes_within_bounds():
    rng = np.random.default_rng(0)
    population = rng.uniform(LOWER, UPPER, size=(30, D))
    before = population.copy()
    mutated = mutate(population, np.array([2, 9, 17]), 5, LOWER, UPPER, rng)
    assert np.array_equal(population, before)  # input untouched
    changed = mutated != population
    assert changed.sum(axis=1).tolist() == [5 if i in (2, 9, 17) else 0 for i in range(30)]
    assert np.all((mutated >= LOWER) & (mutated < UPPER))


def test_counts_are_the_papers_and_scale_with_the_population():
    assert GeneticSettings().counts(24) == (10, 3, 5)
    assert GeneticSettings(population=3000).counts(24) == (1000, 300, 5)
    assert GeneticSettings(population=4).counts(14) == (1, 1, 3)
    assert GeneticSettings(culled=5, mutated_chromosomes=0, mutated_genes=24).counts(24) == (5, 0, 24)
    for bad in (dict(culled=29), dict(culled=0), dict(mutated_chromosomes=30),
                dict(mutated_genes=25), dict(population=2)):
        with pytest.raises(ValueError):
            GeneticSettings(**bad).counts(24)


def source_rows(children, survivors):
    """(n, D) index of the survivor each child gene came from (-1: from none)."""
    match = children[:, None, :] == survivors[None, :, :]  # (n, S, D)
    return np.where(match.any(axis=1), match.argmax(axis=1), -1)


def test_ga_keeps_the_best_20_in_order_and_breeds_10_crossover_children():
    ga = GeneticAlgorithm(LOWER, UPPER, GeneticSettings(mutated_chromosomes=0), seed=3)
    told = ga.ask()
    costs = np.random.default_rng(1).permutation(30).astype(float)
    ga.tell(told, costs)
    nxt = ga.ask()
    ranked = told[np.argsort(costs)]
    assert np.array_equal(nxt[:20], ranked[:20])
    sources = source_rows(nxt[20:], ranked[:20])
    assert np.all(sources >= 0)  # every child gene comes from a survivor, none from the culled
    for row in sources:
        runs = row[np.r_[True, row[1:] != row[:-1]]]  # the parent of each stretch
        assert len(runs) in (2, 3) and runs[0] != runs[1]  # one-point: A B; two-point: A B A
        assert len(runs) == 2 or runs[2] == runs[0]


def test_ga_mutates_exactly_5_genes_in_3_chromosomes_never_the_elite():
    ga = GeneticAlgorithm(LOWER, UPPER, seed=4)
    cost = sphere(inner_target(0))
    for _ in range(10):
        told = ga.ask()
        costs = cost(told)
        ga.tell(told, costs)
        nxt = ga.ask()
        survivors = told[np.argsort(costs)][:20]
        fresh = source_rows(nxt, survivors) < 0  # genes no survivor holds: the mutated ones
        assert fresh.sum() == 15
        assert sorted(fresh.sum(axis=1))[-3:] == [5, 5, 5] and fresh.any(axis=1).sum() == 3
        assert np.array_equal(nxt[0], survivors[0])


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), name=st.sampled_from(["ga", "cmaes"]),
       failed_share=st.floats(0.0, 1.0))
def test_candidates_stay_inside_the_bounds(seed, name, failed_share):
    rng = np.random.default_rng(seed)
    lower = rng.uniform(-5, 0, size=6)
    upper = lower + rng.uniform(0.01, 5, size=6)
    opt = make_optimizer(name, lower, upper, generations=8, seed=seed)
    # costs pushing towards a corner outside the box, some candidates failing
    cost = lambda x: np.where(rng.random(len(x)) < failed_share, np.inf, -x.sum(axis=1))
    for x in run(opt, cost):
        assert np.all((x >= lower) & (x <= upper))


@pytest.mark.parametrize("seed", range(5))
def test_ga_best_cost_never_rises_and_the_elite_leads_the_next_generation(seed):
    ga = GeneticAlgorithm(LOWER, UPPER, seed=seed)
    cost = sphere(inner_target(seed))
    best = []
    for x in run(ga, cost):
        if best:
            assert cost(x[:1])[0] == best[-1]  # row 0 is the previous generation's best
        best.append(cost(x).min())
    assert len(best) == 25
    assert np.all(np.diff(best) <= 0) and best[-1] < best[0]


# -------------------------------------------------------------- the ask/tell contract
def make(name, **options):
    return make_optimizer(name, LOWER, UPPER, seed=0, **options)


@pytest.mark.parametrize("name, size", [("ga", 30), ("cmaes", 13)])
def test_ask_gives_the_population_and_tell_counts_it(name, size):
    opt = make(name, generations=3)
    with pytest.raises(RuntimeError):
        opt.result
    x = opt.ask()
    assert x.shape == (size, D) and x.dtype == np.float64 and opt.population_size == size
    costs = np.arange(size, dtype=float)
    opt.tell(x, costs)
    result = opt.result
    assert (result.generations, result.evaluations, result.best_cost) == (1, size, 0.0)
    assert np.array_equal(result.best_candidate, x[0]) and result.stop_reasons == {}
    assert np.array_equal(result.population, x) and np.array_equal(result.population_costs, costs)
    assert opt.generation == 1 and opt.stop() == {}


@pytest.mark.parametrize("name", ["ga", "cmaes"])
def test_tell_rejects_what_was_not_asked(name):
    opt = make(name)
    with pytest.raises(RuntimeError):
        opt.tell(np.zeros((opt.population_size, D)), np.zeros(opt.population_size))
    x = opt.ask()
    p = len(x)
    bad = [(x[:-1], np.zeros(p - 1)), (np.hstack([x, x[:, :1]]), np.zeros(p)),
           (x, np.zeros(p + 1)), (x, np.zeros((p, 1))), (x, np.r_[np.nan, np.zeros(p - 1)]),
           (x, np.r_[-np.inf, np.zeros(p - 1)]), (np.vstack([UPPER + 1, x[1:]]), np.zeros(p))]
    for candidates, costs in bad:
        with pytest.raises(ValueError):
            opt.tell(candidates, costs)
    opt.tell(x, np.zeros(p))  # the rejected tells left the optimiser as it was
    assert opt.generation == 1


@pytest.mark.parametrize("name", ["ga", "cmaes"])
def test_stop_at_the_generation_budget_then_ask_raises(name):
    opt = make(name, generations=4)
    asked = run(opt, sphere(inner_target(0)))
    assert len(asked) == 4 and opt.stop() == {"generations": 4}
    assert opt.result.evaluations == 4 * opt.population_size
    assert opt.result.stop_reasons == {"generations": 4}
    with pytest.raises(RuntimeError, match="stopped"):
        opt.ask()


@pytest.mark.parametrize("name", ["ga", "cmaes"])
def test_infinite_costs_rank_last_and_break_nothing(name):
    opt = make(name, generations=60)
    target = inner_target(1)
    target[0] = LOWER[0] + 0.3 * SPAN[0]
    cost = sphere(target)
    # candidates in the upper half of gene 0 fail; the first generation fails entirely
    failing = lambda x: np.where(x[:, 0] > (LOWER[0] + UPPER[0]) / 2, np.inf, cost(x))
    x = opt.ask()
    opt.tell(x, np.full(len(x), np.inf))
    assert opt.result.best_cost == np.inf and opt.stop() == {}
    asked = run(opt, failing)
    result = opt.result
    assert np.isfinite(result.best_cost) and result.best_candidate[0] <= 0.0
    assert result.best_cost == pytest.approx(cost(result.best_candidate[None])[0])
    assert result.best_cost < 0.8 * failing(asked[0]).min()  # it improved on its start


@pytest.mark.parametrize("name", ["ga", "cmaes"])
def test_same_seed_same_run_other_seed_other_run(name):
    cost = sphere(inner_target(2))

    def history(seed):
        opt = make_optimizer(name, LOWER, UPPER, generations=10, seed=seed)
        asked = []
        while not opt.stop():
            np.random.seed(len(asked))  # the global RNG must not matter
            np.random.rand(7)
            x = opt.ask()
            asked.append(x)
            opt.tell(x, cost(x))
        return np.stack(asked), opt.result

    (a, ra), (b, rb), (c, _) = history(11), history(11), history(12)
    assert np.array_equal(a, b) and np.array_equal(ra.best_candidate, rb.best_candidate)
    assert ra.best_cost == rb.best_cost
    assert not np.any(a[0] == c[0])


# ---------------------------------------------------------------------------- CMA-ES
def test_cmaes_starts_at_x0_with_steps_in_units_of_each_range():
    x0 = LOWER + 0.25 * SPAN
    for start, expected in ((None, (LOWER + UPPER) / 2), (tuple(x0), x0)):
        opt = CmaEvolutionStrategy(LOWER, UPPER, CmaSettings(population=4000, sigma0=0.01,
                                                             x0=start), seed=0)
        x = opt.ask()
        assert np.allclose(x.mean(axis=0), expected, atol=0.002 * SPAN)
        assert np.allclose(x.std(axis=0) / SPAN, 0.01, rtol=0.1)  # 0.06 sd, 0.4 degrees
    with pytest.raises(ValueError):
        CmaEvolutionStrategy(LOWER, UPPER, CmaSettings(x0=tuple(UPPER + 1)))


def test_cmaes_restarts_with_twice_the_population_then_stops_with_cmas_reason():
    opt = make("cmaes", generations=100, restarts=2)
    sizes = [len(x) for x in run(opt, lambda x: np.zeros(len(x)))]  # flat: cma gives up
    assert sorted(set(sizes)) == [13, 26, 52] and sizes == sorted(sizes)
    assert len(sizes) < 100 and "tolfun" in opt.stop()
    assert opt.result.evaluations == sum(sizes)


# ------------------------------------------------- the analytic case: a shifted sphere
def test_ga_paper_defaults_beat_random_search_of_the_same_budget():
    ratios = []
    for seed in range(8):
        cost = sphere(inner_target(seed))
        ga = make_optimizer("ga", LOWER, UPPER, seed=seed)
        run(ga, cost)
        uniform = np.random.default_rng(seed + 100).uniform(LOWER, UPPER, size=(750, D))
        assert ga.result.evaluations == 750
        ratios.append(ga.result.best_cost / cost(uniform).min())
    # measured: 0.34-1.02 per seed (one seed no better than chance), 0.51 on average
    assert np.mean(ratios) < 0.65, ratios


@pytest.mark.parametrize("seed", range(3))
def test_ga_finds_the_sphere_minimum(seed):
    target = inner_target(seed)
    ga = make_optimizer("ga", LOWER, UPPER, population=300, generations=100, seed=seed)
    run(ga, sphere(target))
    # the GA only recombines and redraws genes: it gets near, not onto, the minimum
    assert ga.result.best_cost < 0.1  # RMS gene error < 6.5 % of its range
    assert np.all(np.abs(ga.result.best_candidate - target) < 0.25 * SPAN)


@pytest.mark.parametrize("seed", range(3))
def test_cmaes_finds_the_sphere_minimum(seed):
    target = inner_target(seed)
    opt = make_optimizer("cmaes", LOWER, UPPER, generations=250, seed=seed)
    run(opt, sphere(target))
    assert opt.result.best_cost < 1e-8
    assert np.all(np.abs(opt.result.best_candidate - target) < 1e-3 * SPAN)


def test_factory_names_and_options():
    assert make_optimizer("ga", LOWER, UPPER, population=60).population_size == 60
    assert make_optimizer("cmaes", LOWER, UPPER, population=20).population_size == 20
    assert isinstance(make_optimizer("ga", LOWER, UPPER, culled=5), GeneticAlgorithm)
    with pytest.raises(ValueError, match="unknown optimiser"):
        make_optimizer("pso", LOWER, UPPER)
    with pytest.raises(ValueError, match="sigma0"):
        make_optimizer("ga", LOWER, UPPER, sigma0=0.1)
    with pytest.raises(ValueError):
        make_optimizer("ga", LOWER, UPPER[:-1])
    with pytest.raises(ValueError):
        make_optimizer("cmaes", UPPER, LOWER)


@pytest.mark.parametrize("name", ["ga", "cmaes"])
def test_best_cost_is_the_results(name):
    lower, upper = search_bounds(4)
    opt = make_optimizer(name, lower, upper, population=8, generations=3, seed=2)
    assert opt.best_cost == np.inf
    while not opt.stop():
        x = opt.ask()
        opt.tell(x, np.sum(x ** 2, axis=1))
        assert opt.best_cost == opt.result.best_cost


def test_search_forgets_the_best_when_the_costs_change_meaning():
    """on_generation sees every generation's best so far; once it says the costs changed
    (True), the best so far restarts from the next generation's costs."""
    from types import SimpleNamespace

    from bodyfit.fitter.fit.search import SearchSettings, search

    offset = {"value": 0.0}

    class Evaluator:
        def evaluate(self, betas, pose_deg):
            return SimpleNamespace(costs=np.sum(betas ** 2, axis=1) + offset["value"],
                                   part_costs=np.zeros((len(betas), 11)))

    seen = []

    def on_generation(done, betas, pose_deg):
        seen.append(done)
        assert betas.shape == (3,) and pose_deg.shape == (4,)
        if done == 4:
            offset["value"] = 100.0  # every cost from now on is 100 higher
            return True
        return False

    settings = SearchSettings(optimizer="cmaes", population=6, generations=8, components=3,
                              condition_stature=False, seed=1)
    result = search(Evaluator(), settings, on_generation=on_generation, progress=False)
    assert seen == list(range(1, 9))
    assert np.all(result.best_costs[:4] < 100) and np.all(result.best_costs[4:] >= 100)
    assert result.cost >= 100 and len(result.best_betas) == 8


def noisy_sphere(target, seed, noise=0.01):
    """``sphere`` plus Gaussian noise of ``noise`` per candidate, like the raster's on a
    body's cost: the best candidate ever told is partly the luckiest draw."""
    rng = np.random.default_rng([seed, 123])
    exact = sphere(target)
    return lambda x: exact(x) + rng.normal(0.0, noise, len(x))


@pytest.mark.parametrize("seed", range(3))
def test_cmaes_centre_is_nearer_a_noisy_minimum_than_the_best_candidate(seed):
    target = inner_target(seed)
    opt = make_optimizer("cmaes", LOWER, UPPER, population=30, generations=150, seed=seed)
    run(opt, noisy_sphere(target, seed))
    result = opt.result
    assert np.all((result.centre >= LOWER) & (result.centre <= UPPER))
    error = {name: np.sqrt(sphere(target)(x[None])[0])
             for name, x in (("centre", result.centre), ("best", result.best_candidate))}
    assert error["centre"] < error["best"], error


def test_ga_keeps_no_centre():
    opt = make_optimizer("ga", LOWER, UPPER, population=10, generations=2, seed=0)
    run(opt, sphere(inner_target(0)))
    assert opt.result.centre is None


def test_search_answers_with_the_cmaes_centre_scored():
    """The search's answer is CMA-ES's final mean, with its own cost and terms, and the last
    of the per-generation answers; on a noisy cost it lies nearer the minimum than the
    best candidate scored."""
    from types import SimpleNamespace

    from bodyfit.fitter.fit.search import SearchSettings, search

    target = np.array([0.5, -1.0, 0.8])
    rng = np.random.default_rng(5)
    scored = []

    class Evaluator:
        def evaluate(self, betas, pose_deg):
            costs = np.sum((betas - target) ** 2, axis=1) + rng.normal(0, 0.05, len(betas))
            scored.extend(zip(costs, betas.copy()))
            return SimpleNamespace(costs=costs, part_costs=np.tile(costs[:, None], (1, 11)))

    settings = SearchSettings(optimizer="cmaes", population=12, generations=80, components=3,
                              condition_stature=False, seed=3)
    result = search(Evaluator(), settings, progress=False)
    best = min(scored[:-1], key=lambda pair: pair[0])[1]  # the last scored is the answer
    assert np.linalg.norm(result.betas - target) < np.linalg.norm(best - target)
    np.testing.assert_array_equal(scored[-1][1], result.betas)
    np.testing.assert_array_equal(result.best_betas[-1], result.betas)
    assert result.part_costs[0] == pytest.approx(result.cost)


def test_averaged_searches_pad_average_and_add_up():
    from bodyfit.fitter.fit.search import SearchResult, averaged

    def result(best_costs, betas, evaluations, population):
        g = len(best_costs)
        return SearchResult(
            betas=np.zeros(2), pose_deg=np.zeros(4), cost=1.0, part_costs=np.zeros(11),
            best_costs=np.array(best_costs, float), mean_costs=np.array(best_costs) + 1.0,
            best_betas=np.tile(betas, (g, 1)), final_genes=np.full((population, 6), g, float),
            final_costs=np.arange(population, dtype=float), evaluations=evaluations,
            generations=g, seconds=2.0, stop_reasons={"generations": g})

    one = result([5.0, 4.0, 3.0], [1.0, 2.0], 30, 3)
    two = result([7.0, 5.0], [3.0, 0.0], 20, 2)  # stopped a generation early
    both = averaged([one, two], np.array([2.0, 1.0]), np.ones(4), 9.0, np.full(11, 0.5))
    np.testing.assert_allclose(both.best_costs, [6.0, 4.5, 4.0])
    np.testing.assert_allclose(both.mean_costs, [7.0, 5.5, 5.0])
    np.testing.assert_allclose(both.best_betas, [[2.0, 1.0]] * 3)
    assert both.final_genes.shape == (5, 6) and len(both.final_costs) == 5
    assert (both.evaluations, both.generations, both.seconds) == (50, 3, 4.0)
    assert both.cost == 9.0 and both.betas.tolist() == [2.0, 1.0]


def test_refined_search_joins_the_curves_and_pads_the_first_betas():
    from bodyfit.fitter.fit.search import SearchResult, refined

    def result(k, generations, population, value):
        return SearchResult(
            betas=np.full(k, value), pose_deg=np.full(4, value), cost=value,
            part_costs=np.zeros(11), best_costs=np.full(generations, value),
            mean_costs=np.full(generations, value + 1.0),
            best_betas=np.full((generations, k), value),
            final_genes=np.full((population, k + 4), value),
            final_costs=np.full(population, value), evaluations=generations * population,
            generations=generations, seconds=value, stop_reasons={"generations": generations})

    first, refinement = result(2, 3, 4, 1.0), result(5, 2, 6, 2.0)
    joined = refined(first, refinement)
    assert joined.betas.tolist() == [2.0] * 5 and joined.cost == 2.0
    assert joined.best_costs.tolist() == [1.0, 1.0, 1.0, 2.0, 2.0]
    np.testing.assert_array_equal(joined.best_betas[:3], [[1.0, 1.0, 0.0, 0.0, 0.0]] * 3)
    np.testing.assert_array_equal(joined.best_betas[3:], np.full((2, 5), 2.0))
    # the first's final genes: its betas padded with zero components, then its angles
    np.testing.assert_array_equal(joined.final_genes[:4], [[1, 1, 0, 0, 0, 1, 1, 1, 1]] * 4)
    assert joined.final_genes.shape == (10, 9) and len(joined.final_costs) == 10
    assert (joined.evaluations, joined.generations, joined.seconds) == (24, 5, 3.0)
    assert joined.stop_reasons == {"generations": 3, "refinement generations": 2}


def test_search_starts_cmaes_from_the_given_genes():
    """A start far from the middle of the bounds: the first generation is drawn around it
    (sigma0 0.01 of the ranges), and a GA, which keeps no distribution, refuses one."""
    from types import SimpleNamespace

    from bodyfit.fitter.fit.search import SearchSettings, search

    asked = []

    class Evaluator:
        def evaluate(self, betas, pose_deg):
            asked.append(np.concatenate([betas, pose_deg], axis=1))
            costs = np.sum(betas ** 2, axis=1)
            return SimpleNamespace(costs=costs, part_costs=np.tile(costs[:, None], (1, 11)))

    start = np.array([2.0, -1.5, 0.5, 20.0, 25.0, -5.0, 10.0])
    settings = SearchSettings(population=20, generations=1, components=3,
                              condition_stature=False, sigma0=0.01)
    search(Evaluator(), settings, progress=False, start=start)
    ranges = settings.upper - settings.lower
    np.testing.assert_allclose(asked[0].mean(axis=0), start, atol=0.02 * ranges.max())
    assert np.all(np.abs(asked[0] - start) < 0.05 * ranges)
    with pytest.raises(ValueError, match="only CMA-ES"):
        search(Evaluator(), dataclasses.replace(settings, optimizer="ga"), progress=False,
               start=start)


def test_searches_together_score_one_population_and_equal_searches_alone():
    """Three CMA-ES searches (one stopping earlier) side by side: each generation one call
    of the evaluator with every running search's population, and each result equal to
    its search run alone."""
    from types import SimpleNamespace

    from bodyfit.fitter.fit.search import SearchSettings, search, searches_together

    target = np.array([0.5, -1.0, 0.8])
    sizes = []

    class Evaluator:  # a rugged cost, each candidate's its own (no shared noise stream)
        def evaluate(self, betas, pose_deg):
            sizes.append(len(betas))
            costs = (np.sum((betas - target) ** 2, axis=1) + 0.05 * np.sin(40 * betas[:, 0])
                     + 0.01 * np.sum(pose_deg ** 2, axis=1))
            return SimpleNamespace(costs=costs, part_costs=np.tile(costs[:, None], (1, 11)))

    base = SearchSettings(population=8, generations=12, components=3, condition_stature=False)
    settings = [dataclasses.replace(base, seed=0), dataclasses.replace(base, seed=1),
                dataclasses.replace(base, seed=2, generations=5)]
    start = np.array([0.2, 0.1, -0.3, 5.0, 5.0, 5.0, 5.0])
    together = searches_together(Evaluator(), settings, progress=False, start=start)
    assert sizes == [24] * 5 + [16] * 7 + [1] * 3  # then each answer scored alone
    for alone_settings, joint in zip(settings, together):
        alone = search(Evaluator(), alone_settings, progress=False, start=start)
        for field in ("betas", "pose_deg", "best_costs", "mean_costs", "best_betas",
                      "final_genes", "final_costs"):
            np.testing.assert_array_equal(getattr(joint, field), getattr(alone, field))
        assert (joint.cost, joint.evaluations, joint.generations) == (
            alone.cost, alone.evaluations, alone.generations)
