"""The packages' layering (DESIGN.md, "Layout"): dependencies run one way.

``kernels`` is the bottom layer and imports no other bodyfit package; ``calib`` imports
no other bodyfit package; ``fitter`` may use both. Imports are read with ``ast`` from
every module's source, including imports inside functions and ``if TYPE_CHECKING:``
blocks, so a late import cannot hide a dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Package folder -> the bodyfit packages its modules must not import.
FORBIDDEN = {
    "kernels": ("bodyfit.fitter", "bodyfit.calib"),
    "calib": ("bodyfit.fitter", "bodyfit.kernels"),
}


def imported_modules(source: str, package: str) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in a module of the dotted ``package``
    (e.g. ``"bodyfit.kernels"``); ``from bodyfit import fitter`` counts as importing
    ``bodyfit.fitter``, and relative imports are resolved against ``package``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                parts = parts[:max(0, len(parts) - node.level + 1)]
                base = ".".join(parts + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            found.append((node.lineno, base))
            found += [(node.lineno, f"{base}.{alias.name}") for alias in node.names]
    return found


def _is_under(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def test_import_finder_sees_every_form():
    source = ("import bodyfit.fitter.cli\n"
              "from bodyfit import calib\n"
              "def late():\n"
              "    from bodyfit.fitter.body_model import PART_NAMES\n"
              "    from ..calib import errors\n")
    modules = [m for _, m in imported_modules(source, "bodyfit.kernels")]
    assert "bodyfit.fitter.cli" in modules
    assert "bodyfit.calib" in modules
    assert "bodyfit.fitter.body_model" in modules
    assert "bodyfit.calib.errors" in modules


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_imports_only_lower_layers(package):
    files = sorted((ROOT / package).rglob("*.py"))
    assert files, f"no modules found under {package}/"
    violations = {}  # one line per offending import statement
    for path in files:
        dotted = ".".join(("bodyfit", package, *path.relative_to(ROOT / package).parent.parts))
        for line, module in imported_modules(path.read_text(encoding="utf-8"), dotted):
            if any(_is_under(module, forbidden) for forbidden in FORBIDDEN[package]):
                violations.setdefault((path, line),
                                      f"{path.relative_to(ROOT)}:{line} imports {module}")
    violations = list(violations.values())
    assert not violations, "layering broken:\n" + "\n".join(violations)
