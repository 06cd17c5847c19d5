"""Fitting the body model to a person's photos: the `fitter` command's package, and a short
Python API.

Fit a person in three lines (the default method; a few minutes on a CPU)::

    from bodyfit.fitter import PersonInputs, fit_photos
    fit = fit_photos(PersonInputs("front.jpg", "side.jpg", height_cm=178, camera="camera.json"))
    print(fit.measurements["E"], fit.spreads["E"])   # the waist and its ±, mm

``fit.measurements`` maps the 16 measurements' letters (``MEASUREMENTS``: "A" the head
circumference ... "P" the shoulder breadth) to millimetres; ``fit.posed`` and
``fit.rest`` are the fitted body's vertices (metres, z up, facing -y) in the photos' pose
and in the rest A-pose, ``load_model().faces`` its triangles. :func:`run_person` also
writes every file of `fitter run` (meshes, measurements, overlays, report) to a folder.

The sub-packages, lowest first (docs/architecture.md): ``model`` (the body model),
``measure`` (the 16 measurements), ``model_build`` (the model built from Anny), ``fit`` (one
person's fit), ``output`` (meshes, pictures, report), ``run`` (one `fitter run`),
``batch`` (`fitter batch`), ``demo`` (`fitter demo`), ``cli`` (the command line).
Importing this package imports none of them; each name below loads on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

#: Public name -> the module that defines it.
_EXPORTS = {
    "PersonInputs": "bodyfit.fitter.fit.person",
    "FitSettings": "bodyfit.fitter.fit.person_fit",
    "METHODS": "bodyfit.fitter.fit.person_fit",
    "Fit": "bodyfit.fitter.fit.person_fit",
    "MEASUREMENTS": "bodyfit.fitter.measure.measurements",
    "load_model": "bodyfit.fitter.model.cache",
    "run_person": "bodyfit.fitter.run.results",
}

__all__ = ["fit_photos", *_EXPORTS]

if TYPE_CHECKING:
    from bodyfit.fitter.fit.person import PersonInputs
    from bodyfit.fitter.fit.person_fit import METHODS, Fit, FitSettings
    from bodyfit.fitter.measure.measurements import MEASUREMENTS
    from bodyfit.fitter.model.cache import load_model
    from bodyfit.fitter.run.results import run_person


def fit_photos(person: PersonInputs, settings: FitSettings | None = None,
               progress: bool | None = False) -> Fit:
    """Fit the body model (:func:`load_model`'s) to a person's photos, as `fitter run` does,
    without writing files.

    Args:
        person: the photos (front in an A-pose, side with the arms down), the stature in
            centimetres, and optionally camera.json, the user's own masks or background
            plates.
        settings: how to fit (default: ``METHODS["bodyfit"]``; ``METHODS["paper"]`` is the
            paper's method exactly, in seconds).
        progress: show the search's progress bar (None: when stderr is a terminal).

    Raises:
        bodyfit.common.errors.UserError: unreadable photos, no person or several, a person
            cut off by the frame, a stature outside 100-250 cm, front and side swapped.

    Example (the mean body photographed on a plain backdrop by the demo's orthographic
    studio camera, fitted by the default method through that camera: seconds):

    >>> import dataclasses, pathlib, tempfile, numpy as np, warp
    >>> from bodyfit.fitter import METHODS, PersonInputs, fit_photos, load_model
    >>> from bodyfit.fitter.demo.studio_photos import write_subject
    >>> warp.config.log_level = warp.LOG_ERROR   # no Warp start-up messages
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> truth = write_subject(folder, load_model(), np.zeros(20), np.full(4, 10.0))
    >>> person = PersonInputs(str(folder / "front.png"), str(folder / "side.png"),
    ...                       height_cm=truth["O"] / 10)
    >>> studio = dataclasses.replace(METHODS["bodyfit"], projection="orthographic")
    >>> fit = fit_photos(person, studio)
    >>> [bool(abs(fit.measurements[key] - truth[key]) < 5) for key in "DEF"]  # chest, waist, hip
    [True, True, True]
    >>> bool(abs(fit.measurements["O"] - truth["O"]) < 0.1)  # the stature, given
    True
    """
    from bodyfit.fitter.fit.person_fit import METHODS, fit_inputs
    from bodyfit.fitter.model.cache import load_model

    return fit_inputs(load_model(), person, METHODS["bodyfit"] if settings is None else settings,
                      progress)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
