"""The paper's 16 body measurements (its Fig. 10), taken on a body in the model's topology.

Every measurement is taken on the rest (A-pose) body, standing on the floor (its lowest
vertex), in millimetres. Circumferences are tape measures: the perimeter of the convex
hull of a plane section (:mod:`bodyfit.fitter.measure.sections`), restricted to the body part
being measured; limbs are cut perpendicular to the limb's axis (the line between the
centroids of its two joint rings), the trunk and the head horizontally. Limb values are
the mean of the left and right sides. Lengths are straight lines between landmarks (the
paper: "straight lines represent the Euclidean distance").

Definitions, with the ISO 8559-1:2017 clause where one exists and ANSUR II's procedure
(the reference population the body model is matched to) otherwise. The clause numbers
are those cited in public sizing literature; the standard's text is not freely available
to check them against.

=====  ======================  ============================================================
key    name                    definition
=====  ======================  ============================================================
A      head circumference      maximum horizontal girth of the skull above the brow: planes
                               from 50 % to 80 % of the way from the neck-top ring to the
                               vertex (ISO 8559-1 5.3.1 head girth)
B      neck circumference      perpendicular to the neck axis, midway between the neck's
                               base and top rings, just below the larynx (ISO 5.3.2)
C      shoulder-crotch length  vertical distance from the acromion height (mean of both
                               sides) down to the crotch point (no ISO clause)
D      chest circumference     horizontal girth of the trunk at the height of the bust
                               points (ISO 5.3.4 chest girth; ANSUR: at nipple level)
E      waist circumference     horizontal girth of the trunk at the navel (omphalion), as
                               ANSUR II takes it (ISO 5.3.10 uses the natural waist)
F      pelvis circumference    horizontal girth of trunk and thighs at the height of the
                               greatest posterior protrusion of the buttocks (ISO 5.3.13
                               hip girth; ANSUR buttock circumference)
G      wrist circumference     perpendicular to the forearm at the wrist ring (ISO 5.3.19)
H      bicep circumference     perpendicular to the upper arm, midway between acromion and
                               elbow ring, arm relaxed (ISO 5.3.16 upper arm girth; ANSUR
                               measures it flexed, about 2-3 cm larger)
I      forearm circumference   maximum girth perpendicular to the forearm, 10-40 % of the way
                               from elbow to wrist (ANSUR forearm circumference, relaxed here)
J      arm length              acromion to radiale (outer elbow) plus radiale to stylion
                               (outer wrist) (ANSUR acromion-radiale + radiale-stylion length)
K      inside leg length       height of the crotch point above the floor (ISO 5.1.15; ANSUR
                               crotch height)
L      thigh circumference     perpendicular to the thigh axis, 2 % of stature below the
                               crotch: the gluteal fold (ISO 5.3.20; ANSUR thigh circ.)
M      calf circumference      maximum girth perpendicular to the shank, 20-50 % of the way
                               from knee to ankle (ISO 5.3.24)
N      ankle circumference     minimum girth perpendicular to the shank, 75-92 % of the way
                               from knee to ankle, above the malleoli (ANSUR ankle circ.)
O      stature                 top of the head to the floor (ISO 5.1.1 body height)
P      shoulder breadth        straight distance between the two acromion landmarks
                               (ANSUR biacromial breadth)
=====  ======================  ============================================================
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bodyfit.fitter.measure.sections import (mesh_edges, region_edges, section_axes, section_centre,
                                             section_points, tape_lengths)
from bodyfit.fitter.model.body_model import PART_NAMES, BodyModel

__all__ = ["MEASUREMENTS", "IMPORTANT", "SECTION_GIRTHS", "LIMB_SECTIONS", "ACROSS",
           "Measurer"]

#: key -> (snake_case name, human name), in the paper's Fig. 10 order.
MEASUREMENTS = {
    "A": ("head_circumference", "head circumference"),
    "B": ("neck_circumference", "neck circumference"),
    "C": ("shoulder_crotch_length", "shoulder to crotch length"),
    "D": ("chest_circumference", "chest circumference"),
    "E": ("waist_circumference", "waist circumference"),
    "F": ("pelvis_circumference", "pelvis (hip) circumference"),
    "G": ("wrist_circumference", "wrist circumference"),
    "H": ("bicep_circumference", "bicep circumference"),
    "I": ("forearm_circumference", "forearm circumference"),
    "J": ("arm_length", "arm length"),
    "K": ("inside_leg_length", "inside leg length"),
    "L": ("thigh_circumference", "thigh circumference"),
    "M": ("calf_circumference", "calf circumference"),
    "N": ("ankle_circumference", "ankle circumference"),
    "O": ("stature", "stature"),
    "P": ("shoulder_breadth", "shoulder breadth"),
}
#: The paper's 7 "visually important" measurements (its Table 4).
IMPORTANT = ("B", "C", "D", "E", "F", "L", "P")

#: The head's, the neck's and the trunk's girths: one plane section each (the head's the
#: largest of several horizontal planes; the limbs' girths: ``LIMB_SECTIONS``).
SECTION_GIRTHS = ("A", "B", "D", "E", "F")
#: Where the head's candidate planes lie, from the neck-top ring's height (0) to the
#: vertex (1): the largest girth is the tape.
_HEAD_FRACTIONS = np.linspace(0.5, 0.8, 7)
#: The limbs' girths (wrist, bicep, forearm, thigh, calf, ankle) -> their two tapes, left
#: and right (the girth is their mean): plane sections too (:meth:`Measurer.girth_plane`
#: and the rest take these keys).
LIMB_SECTIONS = {key: (f"{key}.L", f"{key}.R") for key in "GHILMN"}
#: limb girth -> its limb (``_LIMBS``)
_GIRTH_LIMBS = {"G": "wrist", "H": "upperarm", "I": "forearm", "L": "thigh", "M": "shank",
                "N": "shank"}
#: limb girth -> where its candidate planes cross the limb's axis (0 at the proximal ring,
#: 1 at the distal) and which of their girths is the tape (the others: one plane,
#: :meth:`Measurer.girth_plane`)
_GIRTH_SPANS = {"I": (np.linspace(0.1, 0.4, 7), np.nanargmax),
                "M": (np.linspace(0.2, 0.5, 7), np.nanargmax),
                "N": (np.linspace(0.75, 0.92, 6), np.nanargmin)}
#: limb tape -> (its girth's key, its side)
_LIMB_TAPES = {tape: (key, tape[-1]) for key, tapes in LIMB_SECTIONS.items() for tape in tapes}
_SECTION_REGIONS = {"A": "skull", "B": "neck", "D": "trunk", "E": "trunk",
                    "F": "trunk_thighs"} | {
    tape: f"{_GIRTH_LIMBS[key]}.{side}" for tape, (key, side) in _LIMB_TAPES.items()}

_UP = np.array([0.0, 0.0, 1.0])
#: Across the body (the model's x): a girth section's first axis, as a front photo shows it.
ACROSS = np.array([1.0, 0.0, 0.0])
_SIDES = ("L", "R")


@dataclasses.dataclass(frozen=True)
class _Limb:
    upper_ring: str  # ring at the proximal joint
    lower_ring: str  # ring at the distal joint
    region: tuple[str, ...]  # bone groups whose edges the tape may touch


_LIMBS = {
    "upperarm": _Limb("shoulder", "elbow", ("upperarm",)),
    "forearm": _Limb("elbow", "wrist", ("forearm",)),
    "wrist": _Limb("elbow", "wrist", ("forearm", "hand")),
    "thigh": _Limb("hip", "knee", ("thigh",)),
    "shank": _Limb("knee", "ankle", ("shank",)),
}


class Measurer:
    """Takes the 16 measurements on bodies of one model's topology.

    Precomputes the edges of every region once; :meth:`measure` then costs a few
    milliseconds per body.
    """

    def __init__(self, faces: np.ndarray, landmarks: dict[str, np.ndarray],
                 vertex_parts: np.ndarray) -> None:
        """
        Args:
            faces: (F, 3) int triangles of the topology.
            landmarks: the model's landmarks (:func:`bodyfit.fitter.model_build.parts.landmarks`).
            vertex_parts: (V,) int part labels (``PART_NAMES`` indices).
        """
        self.landmarks = landmarks
        v = len(vertex_parts)
        edges = mesh_edges(faces)

        def groups(names):
            m = np.zeros(v, bool)
            m[np.concatenate([landmarks[f"region:{n}"] for n in names])] = True
            return m

        self._edges = {
            "trunk": region_edges(edges, groups(["torso"])),
            "trunk_thighs": region_edges(edges, groups(["torso", "thigh.L", "thigh.R"])),
            "neck": region_edges(edges, groups(["neck"])),
            "skull": region_edges(edges, groups(["skull"])),
        }
        for limb, spec in _LIMBS.items():
            for side in _SIDES:
                self._edges[f"{limb}.{side}"] = region_edges(
                    edges, groups([f"{g}.{side}" for g in spec.region]))
        self._buttock_vertices = np.flatnonzero(vertex_parts == PART_NAMES.index("hip"))

    @classmethod
    def from_model(cls, model: BodyModel) -> "Measurer":
        return cls(model.faces, model.landmarks, model.vertex_parts)

    def _point(self, vertices: np.ndarray, name: str) -> np.ndarray:
        return vertices[self.landmarks[name]].astype(np.float64)

    def _ring(self, vertices: np.ndarray, joint: str, side: str = "") -> np.ndarray:
        key = f"ring:{joint}.{side}" if side else f"ring:{joint}"
        return vertices[self.landmarks[key]].astype(np.float64).mean(axis=0)

    def _horizontal_girth(self, vertices: np.ndarray, region: str, heights) -> np.ndarray:
        heights = np.atleast_1d(heights)
        origins = np.zeros((len(heights), 3))
        origins[:, 2] = heights
        return tape_lengths(vertices, self._edges[region], origins, _UP)

    def _limb_fraction(self, v: np.ndarray, girth: str, side: str, top: np.ndarray,
                       bottom: np.ndarray) -> float:
        """Where the one plane of limb girth ``girth`` ("G", "H" or "L") crosses its limb's
        axis from ``top`` (3,) to ``bottom`` (3,) on ``side``, 0 at ``top``, 1 at
        ``bottom``: the wrist at the wrist ring, the bicep where the point midway between
        acromion and elbow ring projects, the thigh where the axis passes 2 % of stature
        below the crotch."""
        if girth == "G":
            return 1.0
        axis = bottom - top
        if girth == "H":
            midway = 0.5 * (self.acromions(v)[_SIDES.index(side)] + bottom)
            return float(np.dot(midway - top, axis) / np.sum(axis ** 2))
        fold = self._point(v, "crotch")[0, 2] - 0.02 * (v[:, 2].max() - v[:, 2].min())
        return float((top[2] - fold) / (top[2] - bottom[2]))

    def girth_plane(self, vertices: np.ndarray, key: str) -> tuple[np.ndarray, np.ndarray]:
        """(3,) a point of girth ``key``'s plane (one of ``SECTION_GIRTHS`` or a limb tape
        of ``LIMB_SECTIONS``) and (3,) its normal, on ``vertices`` (V, 3) metres, rest
        A-pose or posed (the head, neck and trunk do not move with the pose's four angles,
        a limb tape's plane follows its limb). The head's: horizontal, at the largest of
        the girths 50-80 % of the way from the neck-top ring up to the vertex
        (``_HEAD_FRACTIONS``); the neck's: midway between the neck's base and top rings,
        perpendicular to the line joining them; the trunk's: horizontal; a limb tape's:
        perpendicular to its limb's axis (the proximal ring's centre to the distal's), for
        the forearm and the calf at the largest, for the ankle at the smallest of the
        girths over their spans (``_GIRTH_SPANS``), for the others where
        :meth:`_limb_fraction` says."""
        v = np.asarray(vertices, np.float64)
        if key in _LIMB_TAPES:
            girth, side = _LIMB_TAPES[key]
            spec = _LIMBS[_GIRTH_LIMBS[girth]]
            top = self._ring(v, spec.upper_ring, side)
            bottom = self._ring(v, spec.lower_ring, side)
            axis = bottom - top
            if girth in _GIRTH_SPANS:
                fractions, pick = _GIRTH_SPANS[girth]
                girths = tape_lengths(v, self._edges[_SECTION_REGIONS[key]],
                                      top + np.outer(fractions, axis), axis)
                chosen = pick(girths) if np.isfinite(girths).any() else 0
                return top + fractions[chosen] * axis, axis
            return top + self._limb_fraction(v, girth, side, top, bottom) * axis, axis
        if key == "B":
            base, top = self._ring(v, "neck_base"), self._ring(v, "neck_top")
            return 0.5 * (base + top), top - base
        if key == "A":
            neck_top = self._ring(v, "neck_top")[2]
            heights = neck_top + (v[:, 2].max() - neck_top) * _HEAD_FRACTIONS
            girths = self._horizontal_girth(v, "skull", heights)
            height = heights[np.nanargmax(girths) if np.isfinite(girths).any() else 0]
        elif key == "D":
            height = self._point(v, "bust")[:, 2].mean()
        elif key == "E":
            height = self._point(v, "navel")[0, 2]
        elif key == "F":
            buttocks = v[self._buttock_vertices]
            height = buttocks[np.argmax(buttocks[:, 1]), 2]
        else:
            raise KeyError(f"{key!r} is neither one of {SECTION_GIRTHS} nor a limb tape")
        return np.array([0.0, 0.0, height]), _UP

    def _plane_girth(self, vertices: np.ndarray, key: str) -> float:
        """Metres: girth ``key``'s tape (:meth:`girth_plane`'s section of its region);
        NaN where the plane misses it."""
        return tape_lengths(vertices, self._edges[_SECTION_REGIONS[key]],
                            *self.girth_plane(vertices, key))[0]

    def girth_section(self, vertices: np.ndarray, key: str) -> np.ndarray:
        """(n, 2) float64, metres: the points where girth ``key``'s plane
        (:meth:`girth_plane`) cuts its region (whose convex hull is the tape), across the
        body (the model's x, as a front photo shows it) then front to back (as a side
        photo does); ``vertices``: (V, 3) metres."""
        v = np.asarray(vertices, np.float64)
        origin, normal = self.girth_plane(v, key)
        return section_points(v, self._edges[_SECTION_REGIONS[key]], origin, normal, ACROSS)

    def girth_axes(self, vertices: np.ndarray, key: str) -> np.ndarray:
        """(2, 3) float64: the unit axes of :meth:`girth_section`'s frame (across the body,
        then front to back, in girth ``key``'s plane) in the body's frame; ``vertices``:
        (V, 3) metres."""
        return section_axes(self.girth_plane(vertices, key)[1], ACROSS)

    def acromions(self, vertices: np.ndarray) -> np.ndarray:
        """(2, 3) float64, metres: the left and right acromion landmarks of ``vertices``
        (V, 3) metres (the shoulder breadth is their distance)."""
        return self._point(np.asarray(vertices, np.float64), "acromion")

    def girth_centre(self, vertices: np.ndarray, key: str) -> np.ndarray:
        """(3,) float64, metres: the mean of girth ``key``'s section points
        (:meth:`girth_section`) in the body's frame; ``vertices``: (V, 3) metres."""
        v = np.asarray(vertices, np.float64)
        return section_centre(v, self._edges[_SECTION_REGIONS[key]], *self.girth_plane(v, key))

    def measure(self, vertices: np.ndarray) -> dict[str, float]:
        """The 16 measurements of one body.

        Args:
            vertices: (V, 3) float, metres, model frame, rest A-pose.

        Returns:
            key ("A".."P") -> value in millimetres; NaN where a section misses the body
            (a mesh far outside the model's shape space).
        """
        v = np.asarray(vertices, np.float64)
        floor, top = v[:, 2].min(), v[:, 2].max()
        stature = top - floor
        crotch = self._point(v, "crotch")[0]
        acromion = self.acromions(v)
        out = {}

        for key in SECTION_GIRTHS:
            out[key] = self._plane_girth(v, key)
        out["C"] = acromion[:, 2].mean() - crotch[2]
        for key, tapes in LIMB_SECTIONS.items():
            out[key] = np.mean([self._plane_girth(v, tape) for tape in tapes])
        radiale, stylion = self._point(v, "radiale"), self._point(v, "stylion")
        out["J"] = float(np.mean(np.linalg.norm(acromion - radiale, axis=1)
                                 + np.linalg.norm(radiale - stylion, axis=1)))
        out["K"] = crotch[2] - floor
        out["O"] = stature
        out["P"] = float(np.linalg.norm(acromion[0] - acromion[1]))
        return {k: float(out[k]) * 1000.0 for k in MEASUREMENTS}

    def measure_many(self, vertices: np.ndarray) -> np.ndarray:
        """(N, 16) float64 measurements in mm, columns in ``MEASUREMENTS`` order, of
        ``vertices`` (N, V, 3) metres."""
        return np.array([[m[k] for k in MEASUREMENTS] for m in map(self.measure, vertices)])
