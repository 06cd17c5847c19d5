"""The benchmarks' shared fixture: a small accuracy run made once for every command's test.

4 in-space subjects (seed 2) photographed by ``make``, fitted by ``fit`` through the
user's pipeline (calib capture, then fitter batch --camera) with bodyfit's default method
(the local solver): about a minute on two cores.
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
    main(["fit", str(subject_set), "small"])
    yield SmallRun(subject_set, "small")
    patch.undo()
