"""The packages' layering (docs/architecture.md, "Layers"): dependencies run one way.

``kernels`` and ``common`` are the bottom layer and import no other bodyfit package;
``calib`` imports ``common`` only; ``fitter``'s sub-packages each import only those below
them in :data:`FITTER_LAYERS`; nothing installed imports the benchmarks (``bench``).
Imports are read with ``ast`` from every module's source, including imports inside
functions and ``if TYPE_CHECKING:`` blocks, so a late import cannot hide a dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: The fitter's sub-packages, lowest first: each may import those before it, not after.
FITTER_LAYERS = ("model", "measure", "model_build", "check", "fit", "output", "training", "run",
                 "batch", "serve", "demo", "cli")

#: The other top-level packages -> the bodyfit packages they may import.
ALLOWED = {
    "bodyfit.kernels": (),
    "bodyfit.common": (),
    "bodyfit.calib": ("bodyfit.common",),
}
for _rank, _layer in enumerate(FITTER_LAYERS):
    ALLOWED[f"bodyfit.fitter.{_layer}"] = ("bodyfit.common", "bodyfit.kernels", "bodyfit.calib",
                                           *(f"bodyfit.fitter.{below}"
                                             for below in FITTER_LAYERS[:_rank]))
# The package's own module: the short Python API over the sub-packages.
ALLOWED["bodyfit.fitter"] = tuple(f"bodyfit.fitter.{layer}" for layer in FITTER_LAYERS) + (
    "bodyfit.common", "bodyfit.kernels", "bodyfit.calib")


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


def _folder(package: str) -> Path:
    """The source folder of a dotted bodyfit package (pyproject's package-dir)."""
    return ROOT.joinpath(*package.split(".")[1:])


def _owner(module: str) -> str | None:
    """The package of :data:`ALLOWED` that holds ``module`` (the most specific), or None
    for a module outside bodyfit."""
    owners = [package for package in ALLOWED if _is_under(module, package)]
    if not owners and module.startswith("bodyfit."):
        return module  # a bodyfit package the layering does not know: always a violation
    return max(owners, key=len) if owners else None


def test_import_finder_sees_every_form():
    source = ("import bodyfit.fitter.cli.main\n"
              "from bodyfit import calib\n"
              "def late():\n"
              "    from bodyfit.fitter.model.body_model import PART_NAMES\n"
              "    from ..calib import errors\n")
    modules = [m for _, m in imported_modules(source, "bodyfit.kernels")]
    assert "bodyfit.fitter.cli.main" in modules
    assert "bodyfit.calib" in modules
    assert "bodyfit.fitter.model.body_model" in modules
    assert "bodyfit.calib.errors" in modules


def test_every_fitter_sub_package_has_a_layer_and_a_docstring():
    found = {path.parent.name for path in (ROOT / "fitter").glob("*/__init__.py")}
    assert found - {"data"} == set(FITTER_LAYERS)
    for package in ALLOWED:
        init = _folder(package) / "__init__.py"
        assert ast.get_docstring(ast.parse(init.read_text(encoding="utf-8"))), \
            f"{init.relative_to(ROOT)} says nothing of what the package holds"


@pytest.mark.parametrize("package", sorted(ALLOWED))
def test_package_imports_only_lower_layers(package):
    folder = _folder(package)
    files = sorted(folder.glob("*.py")) if package == "bodyfit.fitter" else \
        sorted(folder.rglob("*.py"))
    assert files, f"no modules found under {folder.relative_to(ROOT)}/"
    violations = {}  # one line per offending import statement
    for path in files:
        dotted = ".".join((package, *path.relative_to(folder).parent.parts))
        for line, module in imported_modules(path.read_text(encoding="utf-8"), dotted):
            owner = _owner(module)
            if module.split(".")[0] == "bench" or (
                    owner is not None and owner != package and owner not in ALLOWED[package]):
                violations.setdefault((path, line),
                                      f"{path.relative_to(ROOT)}:{line} imports {module}")
    violations = list(violations.values())
    assert not violations, "layering broken:\n" + "\n".join(violations)


def test_a_forbidden_import_is_caught(tmp_path):
    """The check itself can fail: calib importing the fitter is a violation."""
    source = "from bodyfit.fitter.model.body_model import BodyModel\n"
    modules = [m for _, m in imported_modules(source, "bodyfit.calib")]
    owners = {_owner(m) for m in modules} - {None}
    assert owners and not owners <= set(ALLOWED["bodyfit.calib"])
