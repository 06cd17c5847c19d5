"""The benchmarks' shared fixture: a small accuracy run made once for every command's test.

4 in-space subjects (seed 2) photographed by ``make``, fitted by ``fit`` through the
user's pipeline (calib capture, then fitter batch --camera) with a small budget (60
generations, refinements of 20): about two minutes on two cores.
"""

from __future__ import annotations

import pytest
from accuracy_runs import SmallRun

from bodyfit.fitter.model.cache import CACHE_ENV_VAR


@pytest.fixture(scope="session")
def small_run(tmp_path_factory) -> SmallRun:
    from bench.accuracy.cli import main

    folder = tmp_path_factory.mktemp("accuracy")
    patch = pytest.MonkeyPatch()  # the shipped model, not a user's build in the cache
    patch.setenv(CACHE_ENV_VAR, str(folder / "cache"))
    subject_set = folder / "set"
    main(["make", str(subject_set), "--kind", "in-space", "--count", "4", "--seed", "2",
          "--workers", "2"])
    main(["fit", str(subject_set), "small", "--", "--generations", "60",
          "--refine-generations", "20"])
    yield SmallRun(subject_set, "small")
    patch.undo()
