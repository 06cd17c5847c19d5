"""The user's weight choices -> the kernels' cost settings (the paper's Eq. 17-18, Table 2).

What ``fitter run --weights paper|uniform|lower-body|FILE.toml`` and the repeatable
``--weight NAME=VALUE`` will pass here. Weights are unitless multipliers of the cost's
millimetre distances (see :mod:`bodyfit.kernels.cost`); each is a finite number >= 0.

Names (``WEIGHT_NAMES``):

- the ten parts ``head``, ``chest``, ``waist``, ``hip``, ``leg``, ``foot``, ``arm``,
  ``elbow``, ``hand``, ``neck``: each weighs the distances of the person's boundary points
  matched to that part of the candidate. The first nine are Table 2's; ``neck`` is split
  from its head part (:mod:`bodyfit.fitter.model_build.parts`) and every preset gives it the head's
  weight, so a preset weighs the skull and neck as Table 2's head part does;
- ``top``, ``bottom``: the highest- and lowest-point terms of Eq. 18. Table 2 also lists
  a "height" weight (5), but Eq. 18 has no separate height term: the stature is what the
  top and bottom terms measure, so the height weight is carried by them;
- ``view.front``, ``view.side``: the view weights of Eq. 17.

At least one part and one view must keep a weight > 0 (otherwise the boundaries, or
everything, would cost nothing).

Presets (``PRESETS``):

- ``paper``: Table 2 exactly (head 2, chest 5, waist 5, hip 5, leg 2, foot 1, arm 3,
  elbow 2, hand 1, top 5, bottom 5, view.front 2, view.side 3; neck 2, the head's), the
  kernels' default.
- ``bodyfit``: Table 2's part and view weights with ``top`` and ``bottom`` 0 and the
  head and neck 4 instead of 2, the default of ``fitter run``. Its candidates are
  conditioned on the stature (:mod:`bodyfit.fitter.fit.stature`), so every candidate is as
  tall as the person and the two terms measure only which pixel row a silhouette's top
  and bottom fall in, steps of 4-5 mm weighted by 5 (docs/fitter.md, "Choosing the
  defaults"). The head and neck at 4, paired with 2 on 23 out-of-space subjects: the
  head circumference's error 5.3 -> 2.8 mm (-2.4 +- 1.7, better for 18), the 7 important
  measurements' mean -0.15 +- 0.57 mm; in-space (19 subjects) no change shown
  (docs/history.md, [22-23]).
- ``uniform``: every name 1: the paper's equal-coefficients run of Fig. 17, which it
  shows to be less accurate than Table 2's (Fig. 16).
- ``lower-body``: for trousers: hip 8, leg 6, waist 5, foot 2, top 5, bottom 5 (the
  lowest point fixes leg length), chest 2, head 1, neck 1, arm 1, elbow 1, hand 1,
  view.front 2, view.side 3. A trouser fit is set by the waistband, the seat (hip), the thighs and
  inseam (leg) and the hem (foot), so those outweigh Table 2's torso; the upper body keeps
  small weights so that it still steers the shape rather than being free to go wrong.

A weights file (``--weights FILE.toml``, read with :mod:`tomllib`) uses the same names
as ``--weight``, at the top level; ``preset`` names the preset it starts from (default
``paper``) and every name it gives overrides that preset's value::

    # trousers.toml
    preset = "lower-body"
    waist = 8
    foot = 3
    view.side = 4      # TOML's dotted key; a [view] table with side = 4 is the same

Then the ``--weight`` overrides apply, left to right. The final weights are recorded in
run.json as a plain dict (:func:`weights_record`), which rebuilds the same
:class:`~bodyfit.kernels.cost.CostSettings` (:func:`settings_from_record`).

Every problem is a one-line :class:`~bodyfit.common.errors.UserError`.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path
from types import MappingProxyType
from typing import Iterable, Mapping

from bodyfit.common.errors import UserError
from bodyfit.fitter.model.body_model import PART_NAMES
from bodyfit.kernels.cost import CostSettings

__all__ = ["WEIGHT_NAMES", "PRESETS", "parse_override", "load_weights_file", "resolve_weights",
           "cost_settings", "weights_record", "settings_from_record"]

EXTREME_NAMES = ("top", "bottom")
VIEW_WEIGHT_NAMES = ("view.front", "view.side")
#: Every weight's name, in the order of a record.
WEIGHT_NAMES = PART_NAMES + EXTREME_NAMES + VIEW_WEIGHT_NAMES


def _preset(*values: float) -> Mapping[str, float]:
    return MappingProxyType(dict(zip(WEIGHT_NAMES, map(float, values), strict=True)))


#: Preset name -> a weight for every name (see the module docstring).
PRESETS: Mapping[str, Mapping[str, float]] = MappingProxyType({
    #                head chest waist hip leg foot arm elbow hand neck top bottom front side
    "paper": _preset(2, 5, 5, 5, 2, 1, 3, 2, 1, 2, 5, 5, 2, 3),
    "bodyfit": _preset(4, 5, 5, 5, 2, 1, 3, 2, 1, 4, 0, 0, 2, 3),
    "uniform": _preset(1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1),
    "lower-body": _preset(1, 2, 5, 8, 6, 2, 1, 1, 1, 1, 5, 5, 2, 3),
})


def _valid_names() -> str:
    return ", ".join(WEIGHT_NAMES)


def _check_name(name: str, where: str) -> None:
    if name not in WEIGHT_NAMES:
        raise UserError(f"{where}: unknown weight {name!r}; valid names: {_valid_names()}")


def _check_value(name: str, value, where: str) -> float:
    """``value`` as a float, if it is a finite number >= 0 (bool is not a number here)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise UserError(f"{where}: weight {name} must be a number, got {value!r}")
    if not (math.isfinite(value) and value >= 0):
        raise UserError(f"{where}: weight {name} must be a finite number >= 0, got {value!r}")
    return float(value)


def parse_override(text: str) -> tuple[str, float]:
    """``"NAME=VALUE"`` (one ``--weight``) -> (name, value).

    Raises:
        UserError: no '=', an unknown name, an empty value, or a value that is not a
            finite number >= 0.
    """
    where = f"--weight {text!r}"
    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep:
        raise UserError(f"{where}: expected NAME=VALUE, e.g. waist=8")
    _check_name(name, where)
    if not value:
        raise UserError(f"{where}: the value is empty")
    try:
        number = float(value)
    except ValueError:
        raise UserError(f"{where}: weight {name} must be a number, got {value!r}") from None
    return name, _check_value(name, number, where)


def _preset_weights(name, where: str) -> dict[str, float]:
    if name not in PRESETS:
        raise UserError(f"{where}: unknown preset {name!r}; presets: {', '.join(PRESETS)}")
    return dict(PRESETS[name])


def load_weights_file(path) -> dict[str, float]:
    """Every weight of a weights file (see the module docstring): its preset's values
    with the file's own on top.

    Raises:
        UserError: a missing, unreadable, empty or malformed file; an unknown key or
            preset; a value of the wrong type or out of range.
    """
    path = Path(path)
    where = f"weights file {path}"
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UserError(f"{where} does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"{where} cannot be read: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"{where} is not valid TOML: {exc}") from None
    if not data:
        raise UserError(f"{where} is empty; give a preset and/or NAME = VALUE lines")
    preset = data.pop("preset", "paper")
    if not isinstance(preset, str):
        raise UserError(f"{where}: preset must be a string, got {preset!r}")
    weights = _preset_weights(preset, where)
    views = data.pop("view", {})
    if not isinstance(views, dict):
        raise UserError(f"{where}: view must be a table (view.front = ..., view.side = ...)")
    entries = {**data, **{f"view.{key}": value for key, value in views.items()}}
    for name, value in entries.items():
        _check_name(name, where)
        weights[name] = _check_value(name, value, where)
    return weights


def resolve_weights(choice: str = "paper", overrides: Iterable[str] = ()) -> dict[str, float]:
    """The final weights (a record, see :func:`weights_record`) of ``--weights choice``
    (a preset name or a ``.toml`` file) and the ``--weight`` overrides, in order.

    Raises:
        UserError: an unknown preset, a bad file or override, or no part or no view with
            a weight > 0.
    """
    if choice in PRESETS:
        weights = dict(PRESETS[choice])
    elif choice.endswith(".toml"):
        weights = load_weights_file(choice)
    else:
        raise UserError(f"--weights takes {', '.join(PRESETS)} or a .toml file, got {choice!r}")
    for text in overrides:
        name, value = parse_override(text)
        weights[name] = value
    _check_not_degenerate(weights, "weights")
    return weights


def _check_not_degenerate(weights: Mapping[str, float], where: str) -> None:
    if all(weights[name] == 0 for name in PART_NAMES):
        raise UserError(f"{where}: every part weight is 0; give at least one part a weight > 0")
    if all(weights[name] == 0 for name in VIEW_WEIGHT_NAMES):
        raise UserError(f"{where}: both view weights are 0; give a view a weight > 0")


def settings_from_record(record: Mapping[str, float],
                         base: CostSettings = CostSettings()) -> CostSettings:
    """The cost settings of a weights record: ``base``'s matching choices with the record's
    weights. A record without ``neck`` (run.json files from before bodyfit split the neck
    from the head part) weighs the neck as its head, as those runs did.

    Raises:
        UserError: a missing or unknown name, a bad value, or no part or view weight > 0.
    """
    where = "weights record"
    for name in record:
        _check_name(name, where)
    if "neck" not in record and "head" in record:
        record = {**record, "neck": record["head"]}  # written before the neck was a part
    missing = [name for name in WEIGHT_NAMES if name not in record]
    if missing:
        raise UserError(f"{where}: missing {', '.join(missing)}")
    weights = {name: _check_value(name, record[name], where) for name in WEIGHT_NAMES}
    _check_not_degenerate(weights, where)
    return dataclasses.replace(
        base, part_weights=tuple(weights[name] for name in PART_NAMES),
        top_weight=weights["top"], bottom_weight=weights["bottom"],
        front_weight=weights["view.front"], side_weight=weights["view.side"])


def cost_settings(choice: str = "paper", overrides: Iterable[str] = (),
                  base: CostSettings = CostSettings()) -> CostSettings:
    """The cost settings of ``--weights choice`` and ``--weight`` overrides, with
    ``base``'s matching choices (see :func:`resolve_weights`)."""
    return settings_from_record(resolve_weights(choice, overrides), base)


def weights_record(settings: CostSettings) -> dict[str, float]:
    """The weights of ``settings`` as a plain dict, name -> value in ``WEIGHT_NAMES``
    order (for run.json)."""
    values = (*settings.part_weights, settings.top_weight, settings.bottom_weight,
              settings.front_weight, settings.side_weight)
    return {name: float(value) for name, value in zip(WEIGHT_NAMES, values, strict=True)}
