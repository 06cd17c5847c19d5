"""Shared fixtures: the body model shipped with bodyfit, and Anny."""

import pytest


@pytest.fixture(scope="session")
def body_model():
    """The default body model shipped in the package (a user-built model in the cache,
    if any, is not used, so the tests see what every install sees)."""
    from bodyfit.fitter.model.body_model import BodyModel
    from bodyfit.fitter.model.cache import shipped_model_path

    return BodyModel.load(shipped_model_path())


@pytest.fixture(scope="session")
def anny_source():
    from bodyfit.fitter.model_build.anny_source import AnnySource

    return AnnySource()


@pytest.fixture(scope="session")
def measurer(body_model):
    from bodyfit.fitter.measure.measurements import Measurer

    return Measurer.from_model(body_model)


# Property-based tests (hypothesis): derandomized, so CI runs the same cases every time, and
# no per-example deadline (image decoding times vary between machines).
from hypothesis import settings  # noqa: E402

settings.register_profile("bodyfit", derandomize=True, deadline=None, max_examples=150)
settings.load_profile("bodyfit")
