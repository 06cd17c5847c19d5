"""The benchmarks' shared fixtures: small accuracy runs made once for every command's test.

4 in-space subjects (seed 2) photographed by ``make``, fitted by ``fit`` through the
user's pipeline (calib capture, then fitter batch --camera): ``small_run`` with bodyfit's
default method (the local solver, about a minute on two cores), ``small_thorough_run``
with the population search of ``--method thorough`` on a small budget (60 generations,
refinements of 20: about two minutes), for the probes that read a search's generations
and averaged answers.
"""

from __future__ import annotations

import pytest
from accuracy_runs import SmallRun

from bodyfit.fitter.model.cache import CACHE_ENV_VAR


@pytest.fixture(scope="session")
def small_set(tmp_path_factory):
    """The 4 subjects' set folder (the shipped model, not a user's build in the cache)."""
    from bench.accuracy.cli import main

    folder = tmp_path_factory.mktemp("accuracy")
    patch = pytest.MonkeyPatch()
    patch.setenv(CACHE_ENV_VAR, str(folder / "cache"))
    subject_set = folder / "set"
    main(["make", str(subject_set), "--kind", "in-space", "--count", "4", "--seed", "2",
          "--workers", "2"])
    yield subject_set
    patch.undo()


@pytest.fixture(scope="session")
def small_run(small_set) -> SmallRun:
    from bench.accuracy.cli import main

    main(["fit", str(small_set), "small"])
    return SmallRun(small_set, "small")


@pytest.fixture(scope="session")
def small_thorough_run(small_set) -> SmallRun:
    from bench.accuracy.cli import main

    main(["fit", str(small_set), "small-thorough", "--", "--method", "thorough",
          "--generations", "60", "--refine-generations", "20"])
    return SmallRun(small_set, "small-thorough")
