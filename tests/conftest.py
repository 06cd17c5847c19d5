"""Shared fixtures: the body model (built into the cache on first use) and Anny."""

import pytest


@pytest.fixture(scope="session")
def body_model():
    """The cached default body model; the first run builds it (a few minutes)."""
    from bodyfit.fitter.model_cache import load_model

    return load_model()


@pytest.fixture(scope="session")
def anny_source():
    from bodyfit.fitter.anny_source import AnnySource

    return AnnySource()


@pytest.fixture(scope="session")
def measurer(body_model):
    from bodyfit.fitter.measurements import Measurer

    return Measurer.from_model(body_model)


# Property-based tests (hypothesis): derandomized, so CI runs the same cases every time, and
# no per-example deadline (image decoding times vary between machines).
from hypothesis import settings  # noqa: E402

settings.register_profile("bodyfit", derandomize=True, deadline=None, max_examples=150)
settings.load_profile("bodyfit")
