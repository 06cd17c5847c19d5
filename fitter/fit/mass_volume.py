"""The body's mass against its volume: the girths of a fit scaled so that the fitted
body's volume matches the mass given (``--mass-kg``).

A body of mass ``m`` (kg) has the volume ``m / rho``; the whole body with the air in its
lungs is about as dense as water (people barely float), so ``rho`` = 1.0 kg/L
(:data:`DENSITY_KG_PER_L`). A fitted body of volume ``V`` (its rest mesh, litres) that
is too thin or too stout for the mass is off across, not in height (the stature is
given): scaled across by ``s = sqrt(m / (rho V))`` its volume would be ``m / rho``, and
every circumference scales by ``s`` with it. :data:`SCALED` are the circumferences that
follow the body's mass (all but the head's). The fitted mesh itself is left as fitted (it
matches the photos).

A density from the build (body fat from the BMI, Deurenberg's formula at an age of 35;
Siri's tissue density; 1.2 L of residual lung air) did no better on BodyM's choice rows
than the constant (docs/accuracy.md, "Real people").
"""

from __future__ import annotations

import numpy as np

from bodyfit.common.errors import UserError

__all__ = ["DENSITY_KG_PER_L", "MASS_SCALINGS", "MASS_MISMATCH", "SCALED", "mesh_volume_l",
           "mass_scale", "mass_scaled"]

#: The whole body's density with the air in its lungs, kilograms per litre.
DENSITY_KG_PER_L = 1.0
#: ``FitSettings.mass_scaling``: "girths", the circumferences scaled to the mass (with
#: ``--mass-kg``; the default), or "none": the mass read by the measurements' prior only.
MASS_SCALINGS = ("girths", "none")
#: A mass given more than this many times, or less than its inverse, the mass the fitted
#: body holds is refused: pounds given as kilograms are 2.2 times. The stated weights of
#: 300 real people (BodyM) were 0.50-1.23 times what their fits held, the lowest a stated
#: BMI of 10.6 (no living adult's); loose clothes and hair add volume to a silhouette.
MASS_MISMATCH = 1.75
#: The measurements scaled: every circumference but the head's (its size does not follow
#: the body's mass).
SCALED = ("B", "D", "E", "F", "G", "H", "I", "L", "M", "N")


def mesh_volume_l(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The volume (litres) a closed mesh encloses: ``vertices`` (V, 3) metres, ``faces``
    (F, 3) counter-clockwise seen from outside (trimesh's, imported here: this module's
    names are read by ``fitter --help``).

    Example:
        >>> cube = np.array([[x, y, z] for x in (0, .1) for y in (0, .1) for z in (0, .1)])
        >>> faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5],
        ...                   [0, 5, 1], [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4],
        ...                   [1, 5, 7], [1, 7, 3]])
        >>> round(mesh_volume_l(cube, faces), 6)  # a 10 cm cube
        1.0
    """
    import trimesh

    mesh = trimesh.Trimesh(np.asarray(vertices, np.float64), np.asarray(faces), process=False)
    return float(mesh.volume * 1000.0)


def mass_scale(mass_kg: float, vertices: np.ndarray, faces: np.ndarray) -> float:
    """``sqrt(m / (rho V))``: the scale across that gives the body (``vertices`` (V, 3)
    metres, ``faces`` (F, 3)) the volume of ``mass_kg``.

    Raises:
        UserError: the mass is more than :data:`MASS_MISMATCH` times, or less than its
            inverse, the mass the body holds (``rho V``): not this body's in kilograms.
    """
    held_kg = DENSITY_KG_PER_L * mesh_volume_l(vertices, faces)
    ratio = mass_kg / held_kg
    if not 1.0 / MASS_MISMATCH <= ratio <= MASS_MISMATCH:
        raise UserError(f"--mass-kg {mass_kg:g} is {ratio:.1f} times what the body in the "
                        f"photos weighs (about {held_kg:.0f} kg): give this person's mass in "
                        f"kilograms, or leave it out")
    return float(np.sqrt(ratio))


def mass_scaled(measurements: dict[str, float], scale: float) -> dict[str, float]:
    """``measurements`` (key -> mm) with those of :data:`SCALED` times ``scale``."""
    return {key: value * scale if key in SCALED else value
            for key, value in measurements.items()}
