"""Every runnable example in a docstring of the installed packages (kornia's ``Example:``
blocks), run as doctest runs them: the module's examples pass as written."""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"common": "bodyfit.common", "kernels": "bodyfit.kernels", "calib": "bodyfit.calib",
            "fitter": "bodyfit.fitter"}


def _modules_with_examples() -> list[str]:
    found = []
    for folder, package in PACKAGES.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            if ">>> " in path.read_text(encoding="utf-8"):
                parts = path.relative_to(ROOT / folder).with_suffix("").parts
                parts = parts[:-1] if parts[-1] == "__init__" else parts
                found.append(".".join((package, *parts)))
    return found


def test_the_short_api_has_its_example():
    assert "bodyfit.fitter" in _modules_with_examples()


@pytest.mark.parametrize("name", _modules_with_examples())
def test_examples_run_as_written(name):
    module = importlib.import_module(name)
    results = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert results.attempted > 0 and results.failed == 0
