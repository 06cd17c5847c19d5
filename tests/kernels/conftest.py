"""Fixtures of the kernel tests: the real body model, loaded once."""

from __future__ import annotations

import pytest

from bodyfit.fitter.model_cache import load_model
from bodyfit.kernels.skinning import ModelArrays


@pytest.fixture(scope="session")
def body_model():
    """The cached body model (``$BODYFIT_CACHE_DIR``; built on first use)."""
    return load_model()


@pytest.fixture(scope="session")
def model_arrays(body_model):
    return ModelArrays.from_body_model(body_model, num_betas=20, device="cpu")
