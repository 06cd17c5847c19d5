"""Fixtures of the kernel tests (``body_model`` comes from tests/conftest.py)."""

from __future__ import annotations

import pytest

from bodyfit.kernels.skinning import ModelArrays


@pytest.fixture(scope="session")
def model_arrays(body_model):
    return ModelArrays.from_body_model(body_model, num_components=20, device="cpu")
