"""How `fitter run`'s options become a fit's settings.

Shared by `fitter run` (one person) and `fitter batch` (every subject of a table, with the
same options): the settings start from a method's (``--method``, default ``bodyfit``) or a
previous run's run.json (``--config``), and every option given overrides one setting.
Options are passed as a mapping from their argparse names (``"height_cm"``,
``"vertical_anchor"``) to their values, None meaning "not given".
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path

from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.person_fit import METHODS, FitSettings
from bodyfit.fitter.fit.weights import (cost_settings, parse_override, settings_from_record,
                                        weights_record)
from bodyfit.fitter.run.config import RunConfig, read_run_config

__all__ = ["INPUT_OPTIONS", "SEARCH_OPTIONS", "base_settings", "fit_settings"]

#: `fitter run`'s options that are fields of PersonInputs, and of SearchSettings.
INPUT_OPTIONS = ("front", "side", "height_cm", "camera", "mask_front", "mask_side",
                 "background_front", "background_side", "sex", "segmenter", "check",
                 "mass_kg", "side_from")
SEARCH_OPTIONS = ("optimizer", "population", "generations", "components", "seed",
                  "searches", "refine_components", "refine_generations", "refinements")


def base_settings(method: str | None, config: Path | None
                  ) -> tuple[FitSettings, RunConfig | None]:
    """The settings the options override: ``--method``'s (default ``bodyfit``), or with
    ``--config`` the run.json's (returned too, with its inputs and output folder).

    Raises:
        UserError: both given, or an unreadable or malformed run.json.
    """
    if config is None:
        return METHODS[method or "bodyfit"], None
    if method is not None:
        raise UserError("--method and --config cannot go together: the run.json holds the "
                        "method's settings")
    recorded = read_run_config(config)
    return recorded.settings, recorded


def fit_settings(base: FitSettings, options: Mapping[str, object]) -> FitSettings:
    """``base`` with every fit option of ``options`` that is not None applied: the search's
    (``SEARCH_OPTIONS``, ``free_stature``, ``beta_limit`` (the canvases' room follows it);
    ``components`` at or above the base's ``refine_components``, that not given, turns the
    refinement off), the cost's
    (``matching``, ``vertical_anchor``, ``weights`` (a preset or a .toml file, replacing
    the weights) and ``weight`` (a list of ``NAME=VALUE`` overrides on top)), ``device``,
    ``threads``, ``side_arms``, ``projection``, ``placement_rounds``, ``arms_lower_deg``
    (both shoulders' lowest abduction) and the local solver's
    ``iterations``, ``start``, ``elbows``, ``hands``, ``placements_within``, ``pitch`` and
    ``shape_prior`` (its ``prior_per_cost``), ``measurement_prior`` and ``mass_scaling``.

    Raises:
        UserError: a bad weights preset, file or override.
        ValueError: a bad matching or vertical anchor (the kernels' CostSettings check).
    """
    given = {k: v for k, v in options.items() if v is not None}
    if ("components" in given and "refine_components" not in given
            and given["components"] >= base.search.refine_components):
        given["refine_components"] = 0  # the base's refinement adds no component to these
    search = dataclasses.replace(base.search, **{k: given[k] for k in SEARCH_OPTIONS
                                                 if k in given})
    if given.get("free_stature"):
        search = dataclasses.replace(search, condition_stature=False)
    if "beta_limit" in given:
        search = dataclasses.replace(search, beta_limit=float(given["beta_limit"]))
    if "arms_lower_deg" in given:
        search = dataclasses.replace(search, pose_lower_deg=(
            (float(given["arms_lower_deg"]),) * 2 + tuple(search.pose_lower_deg[2:])))
    cost = dataclasses.replace(base.cost, **{k: given[k] for k in ("matching", "vertical_anchor")
                                             if k in given})
    if "weights" in given:
        cost = cost_settings(given["weights"], given.get("weight", []), cost)
    elif "weight" in given:  # on top of the method's or the recorded weights
        record = weights_record(cost) | dict(map(parse_override, given["weight"]))
        cost = settings_from_record(record, cost)
    solver = dataclasses.replace(base.solver, **{k: given[k] for k in
                                                 ("iterations", "start", "elbows", "hands",
                                                  "placements_within", "pitch")
                                                 if k in given})
    if "shape_prior" in given:
        solver = dataclasses.replace(solver, prior_per_cost=float(given["shape_prior"]))
    return dataclasses.replace(base, search=search, solver=solver, cost=cost,
                               device=given.get("device", base.device),
                               threads=given.get("threads", base.threads),
                               side_arms=given.get("side_arms", base.side_arms),
                               projection=given.get("projection", base.projection),
                               placement_rounds=given.get("placement_rounds",
                                                          base.placement_rounds),
                               measurement_prior=given.get("measurement_prior",
                                                           base.measurement_prior),
                               mass_scaling=given.get("mass_scaling", base.mass_scaling))
