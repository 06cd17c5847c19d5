"""Repeating a run: the inputs and settings of a previous run.json (`fitter run --config`).

run.json (:func:`bodyfit.fitter.run.results.run_record`) holds the person's inputs and the fit's
settings as plain JSON (dataclasses as objects, tuples as lists). :func:`run_config`
rebuilds them, type-checked field by field against the dataclasses, so that a repeated
run with the same seed gives the same body. Relative input paths are taken relative to
the working folder the run was started in (recorded as ``working_dir``). A run.json written
before the neck was a part of its own (nine part weights) weighs the neck as its head, as
those runs did.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from pathlib import Path

from bodyfit import kernels
from bodyfit.common.errors import UserError
from bodyfit.common.files import read_json_file
from bodyfit.fitter.fit.canvas import CanvasSettings
from bodyfit.fitter.fit.local_solver import SolverSettings
from bodyfit.fitter.fit.person import PersonInputs
from bodyfit.fitter.fit.person_fit import FitSettings
from bodyfit.fitter.fit.search import SearchSettings

__all__ = ["RunConfig", "run_config", "read_run_config"]

_PATH_FIELDS = ("front", "side", "camera", "mask_front", "mask_side", "background_front",
                "background_side")


@dataclasses.dataclass(frozen=True)
class RunConfig:
    """What a run.json says about how to repeat its run.

    Attributes:
        inputs: the person's inputs, relative paths made relative to the current folder.
        settings: the fit's settings.
        output: the run's output folder, or None when run.json does not record it.
    """

    inputs: PersonInputs
    settings: FitSettings
    output: Path | None


def _matches(value, hint) -> bool:
    """Whether a JSON ``value`` fits the type ``hint`` (lists stand for tuples)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (types.UnionType, typing.Union):
        return any(_matches(value, arg) for arg in args)
    if hint is type(None):
        return value is None
    if origin is tuple:
        return isinstance(value, list) and all(_matches(item, args[0]) for item in value)
    if hint is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if hint is int:
        return isinstance(value, int) and not isinstance(value, bool)
    return isinstance(value, hint)


def _build(cls, values, where: str, nested: dict[str, type] | None = None):
    """An instance of dataclass ``cls`` from its JSON object ``values``.

    Raises:
        UserError: not an object, a missing or unknown field, or a value of the wrong type.
    """
    if not isinstance(values, dict):
        raise UserError(f"{where} must be an object, got {type(values).__name__}")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - set(fields))
    if unknown:
        raise UserError(f"{where}: unknown field {unknown[0]!r}")
    hints = typing.get_type_hints(cls)
    kwargs = {}
    for name, field in fields.items():
        if name not in values:
            if field.default is dataclasses.MISSING:
                raise UserError(f"{where}: missing {name!r}")
            continue
        value = values[name]
        if nested and name in nested:
            kwargs[name] = _build(nested[name], value, f"{where}.{name}")
            continue
        if not _matches(value, hints[name]):
            raise UserError(f"{where}.{name}: {value!r} is not a {hints[name]}")
        kwargs[name] = tuple(value) if isinstance(value, list) else value
    try:
        return cls(**kwargs)
    except ValueError as exc:  # CostSettings checks its own values
        raise UserError(f"{where}: {exc}") from None


def _neck_as_head(settings):
    """run.json's ``settings`` object with a neck weight appended to a cost's part weights
    written before the neck was a part (one value short; the neck is the last part): the
    head's, which weighed the neck then (as
    :func:`bodyfit.fitter.fit.weights.settings_from_record` reads a weights record without a
    neck). Anything else is returned as it is, for :func:`_build` to check."""
    cost = settings.get("cost") if isinstance(settings, dict) else None
    weights = cost.get("part_weights") if isinstance(cost, dict) else None
    if not (isinstance(weights, list) and len(weights) == len(kernels.PART_NAMES) - 1):
        return settings
    neck_as_head = weights + [weights[kernels.PART_NAMES.index("head")]]
    return {**settings, "cost": {**cost, "part_weights": neck_as_head}}


def _canvas_without_limit(settings):
    """run.json's ``settings`` object without ``canvas.beta_limit``: a run from when the
    canvases held their own copy of the search's bound (always equal to it; the canvases'
    room now follows ``search.beta_limit``). Anything else is returned as it is."""
    canvas = settings.get("canvas") if isinstance(settings, dict) else None
    if not (isinstance(canvas, dict) and "beta_limit" in canvas):
        return settings
    return {**settings, "canvas": {k: v for k, v in canvas.items() if k != "beta_limit"}}


def _without_solver(settings):
    """run.json's ``settings`` object with the local solver off when it names none: a run
    from before the solver (docs/history.md), whose settings are the population search's
    alone. Anything else is returned as it is, for :func:`_build` to check."""
    if isinstance(settings, dict) and "solver" not in settings:
        return {**settings, "solver": {"iterations": 0}}
    return settings


def _without_prior(settings):
    """run.json's ``settings`` object with the measurements' prior, the mass scaling and
    the shape prior's share of the misfit off when it names none: a run from before them
    (docs/history.md). Anything else is returned as it is, for :func:`_build` to check."""
    if not isinstance(settings, dict):
        return settings
    if "measurement_prior" not in settings:
        settings = {**settings, "measurement_prior": "none"}
    if "mass_scaling" not in settings:  # a run from before it
        settings = {**settings, "mass_scaling": "none"}
    solver = settings.get("solver")
    if isinstance(solver, dict) and "prior_per_cost" not in solver:  # before the shape's
        settings = {**settings, "solver": {**solver, "prior_per_cost": 0.0}}
    return settings


def run_config(record: dict, where: str = "run.json") -> RunConfig:
    """The inputs, settings and output folder of a run.json payload.

    Raises:
        UserError: a missing or malformed part (one line, naming the field).
    """
    if not isinstance(record, dict):
        raise UserError(f"{where} must hold a JSON object")
    for key in ("inputs", "settings"):
        if key not in record:
            raise UserError(f"{where}: missing {key!r}; is it a fitter run's run.json?")
    inputs = _build(PersonInputs, record["inputs"], f"{where}: inputs")
    settings = _build(FitSettings,
                      _without_prior(_without_solver(_canvas_without_limit(
                          _neck_as_head(record["settings"])))),
                      f"{where}: settings",
                      {"search": SearchSettings, "solver": SolverSettings,
                       "canvas": CanvasSettings, "cost": kernels.CostSettings})
    base, output = record.get("working_dir"), record.get("output")
    for name, value in (("working_dir", base), ("output", output)):
        if value is not None and not isinstance(value, str):
            raise UserError(f"{where}: {name} must be a path, got {value!r}")
    base = Path(base or "")
    relative = {name: str(base / value) for name in _PATH_FIELDS
                if (value := getattr(inputs, name)) is not None and not Path(value).is_absolute()}
    return RunConfig(dataclasses.replace(inputs, **relative), settings,
                     None if output is None else base / output)


def read_run_config(path) -> RunConfig:
    """:func:`run_config` of the run.json file at ``path``.

    Raises:
        UserError: a missing, unreadable or non-JSON file, or a malformed record.
    """
    return run_config(read_json_file(path, str(path)), str(path))
