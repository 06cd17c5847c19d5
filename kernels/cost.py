"""The paper's weighted silhouette cost (Eq. 17-18, Table 2), for every candidate.

For one view, with the person's boundary points z_1..z_n and the candidate's aligned
boundary, the paper's direction (``"person_to_model"``) is

    f_view = (1/n) sum_i w_part(x_i) |z_i - x_i| + w_top dis(z_top, x_top) + w_bottom dis(z_bottom, x_bottom)

where x_i is the candidate's boundary pixel nearest to z_i and part(x_i) its part. The
reverse direction (``"model_to_person"``) sums over the candidate's m boundary pixels x_j,
each weighted by its own part, the distance to the person's boundary (the person's exact
distance transform, bilinearly interpolated): (1/m) sum_j w_part(x_j) d(x_j, Z).
``"symmetric"`` averages the two sums. Then f = w_front f_front + w_side f_side (Eq. 17).

The highest and lowest points are those of the silhouettes' top and bottom rows, and
dis() is their vertical distance after the alignment: the soles are flat, so which heel
or toe reaches the lowest row (and so a point's column) jumps between similar bodies,
while the rows, the stature, do not.

Distances are measured in pixels and reported in millimetres at the person
(``ViewTarget.millimetres_per_pixel``), so costs read as weighted millimetres. Each
candidate's per-term breakdown (P, 12) holds the ten parts of ``PART_NAMES``, then the
top and bottom terms, summed over the views with the view weights; its rows sum to the
costs. A candidate with an empty silhouette in a view costs +inf.
"""

from __future__ import annotations

import dataclasses

import warp as wp

from bodyfit.kernels.body_layout import PART_NAMES
from bodyfit.kernels.alignment import WarpSilhouetteMoments, anchors_on_extremes
from bodyfit.kernels.boundary import run_end, run_part, run_start, transform_point

__all__ = [
    "MATCHING_DIRECTIONS",
    "MATCHING_WEIGHTS",
    "TERM_NAMES",
    "CostSettings",
    "CostParams",
    "PartVector",
    "cost_params",
    "launch_model_to_person",
    "launch_view_cost",
]

NUM_PARTS = len(PART_NAMES)
#: Columns of the per-term breakdown.
TERM_NAMES = PART_NAMES + ("top", "bottom")
#: Matching direction -> weights of the (person -> model, model -> person) means.
MATCHING_WEIGHTS = {"person_to_model": (1.0, 0.0), "model_to_person": (0.0, 1.0),
                    "symmetric": (0.5, 0.5)}
MATCHING_DIRECTIONS = tuple(MATCHING_WEIGHTS)


PartVector = wp.types.vector(length=NUM_PARTS, dtype=wp.float32)


@dataclasses.dataclass(frozen=True)
class CostSettings:
    """Weights of the paper's Table 2 and the matching choices (weights are unitless).

    Attributes:
        part_weights: one weight per part, in ``PART_NAMES`` order (head 2, chest 5,
            waist 5, hip 5, leg 2, foot 1, arm 3, elbow 2, hand 1; neck 2, the weight of
            Table 2's head part, which holds the neck).
        top_weight, bottom_weight: the highest- and lowest-point terms (5 and 5).
        front_weight, side_weight: the view weights of Eq. 17 (2 and 3).
        matching: one of ``MATCHING_DIRECTIONS``; the paper's is ``"person_to_model"``.
        align_rotation: rotate as well as translate each candidate onto the person.
        vertical_anchor: how the vertical shift is found: ``"centroid"`` (the paper's
            normalisation by the silhouettes' moments) or ``"extremes"`` (the middle of the
            top and bottom rows; :func:`bodyfit.kernels.alignment.launch_alignment`).
    """

    part_weights: tuple[float, ...] = (2.0, 5.0, 5.0, 5.0, 2.0, 1.0, 3.0, 2.0, 1.0, 2.0)
    top_weight: float = 5.0
    bottom_weight: float = 5.0
    front_weight: float = 2.0
    side_weight: float = 3.0
    matching: str = "person_to_model"
    align_rotation: bool = True
    vertical_anchor: str = "centroid"

    def __post_init__(self):
        if len(self.part_weights) != NUM_PARTS:
            raise ValueError(f"part_weights needs {NUM_PARTS} values ({', '.join(PART_NAMES)}), "
                             f"got {len(self.part_weights)}")
        weights = (*self.part_weights, self.top_weight, self.bottom_weight, self.front_weight,
                   self.side_weight)
        if any(not w >= 0 for w in weights):
            raise ValueError("cost weights must be >= 0")
        anchors_on_extremes(self.vertical_anchor)  # ValueError for an unknown one
        if self.matching not in MATCHING_DIRECTIONS:
            raise ValueError(f"matching must be one of {MATCHING_DIRECTIONS}, "
                             f"got {self.matching!r}")

    def view_weight(self, view_name: str) -> float:
        return {"front": self.front_weight, "side": self.side_weight}[view_name]


@wp.struct
class CostParams:
    """The constants of one view's cost.

    Attributes:
        part_weights: per ``PART_NAMES``.
        top_weight, bottom_weight: the extreme-point terms.
        scale: view weight x millimetres per pixel.
        person_to_model, model_to_person: weights of the two directions' means (1 and 0,
            0 and 1, or 0.5 and 0.5).
    """

    part_weights: PartVector
    top_weight: float
    bottom_weight: float
    scale: float
    person_to_model: float
    model_to_person: float


def cost_params(settings: CostSettings, view_name: str,
                millimetres_per_pixel: float) -> CostParams:
    """The :class:`CostParams` of one view."""
    params = CostParams()
    params.part_weights = PartVector(*settings.part_weights)
    params.top_weight = settings.top_weight
    params.bottom_weight = settings.bottom_weight
    params.scale = settings.view_weight(view_name) * millimetres_per_pixel
    params.person_to_model, params.model_to_person = MATCHING_WEIGHTS[settings.matching]
    return params


@wp.func
def _interpolate_distance(distance: wp.array2d(dtype=wp.float32), q: wp.vec2):
    """Bilinear value of a distance map at q = (column, row); outside the image, the value
    at the nearest image point plus the distance to it."""
    height = distance.shape[0]
    width = distance.shape[1]
    cx = wp.clamp(q[0], 0.0, float(width - 1))
    cy = wp.clamp(q[1], 0.0, float(height - 1))
    outside = wp.length(q - wp.vec2(cx, cy))
    x0 = int(cx)
    y0 = int(cy)
    x1 = wp.min(x0 + 1, width - 1)
    y1 = wp.min(y0 + 1, height - 1)
    fx = cx - float(x0)
    fy = cy - float(y0)
    upper = (1.0 - fx) * distance[y0, x0] + fx * distance[y0, x1]
    lower = (1.0 - fx) * distance[y1, x0] + fx * distance[y1, x1]
    return (1.0 - fy) * upper + fy * lower + outside


@wp.kernel(enable_backward=False)
def _model_to_person_kernel(runs: wp.array3d(dtype=wp.int32),
                            run_counts: wp.array2d(dtype=wp.int32),
                            transforms: wp.array(dtype=wp.mat33),
                            person_distance: wp.array2d(dtype=wp.float32),
                            row_sums: wp.array2d(dtype=PartVector),
                            row_pixels: wp.array2d(dtype=wp.int32)):
    p, y = wp.tid()
    to_person = wp.inverse(transforms[p])
    sums = PartVector()
    pixels = int(0)
    for i in range(run_counts[p, y]):
        packed = runs[p, y, i]
        part = run_part(packed)
        for x in range(run_start(packed), run_end(packed) + 1):
            q = transform_point(to_person, wp.vec2(float(x), float(y)))
            sums[part] = sums[part] + _interpolate_distance(person_distance, q)
            pixels = pixels + 1
    row_sums[p, y] = sums
    row_pixels[p, y] = pixels


@wp.kernel(enable_backward=False)
def _view_cost_kernel(params: CostParams, target: WarpSilhouetteMoments,
                      distances: wp.array2d(dtype=wp.float32), parts: wp.array2d(dtype=wp.int32),
                      row_sums: wp.array2d(dtype=PartVector),
                      row_pixels: wp.array2d(dtype=wp.int32),
                      transforms: wp.array(dtype=wp.mat33), extremes: wp.array2d(dtype=wp.vec2),
                      areas: wp.array(dtype=wp.float32), term_costs: wp.array2d(dtype=wp.float32),
                      costs: wp.array(dtype=wp.float32)):
    p = wp.tid()
    if areas[p] == 0.0:
        for k in range(NUM_PARTS + 2):
            term_costs[p, k] = wp.inf
        costs[p] = wp.inf
        return
    terms = PartVector()
    if params.person_to_model > 0.0:
        sums = PartVector()
        num = distances.shape[1]
        for i in range(num):
            sums[parts[p, i]] = sums[parts[p, i]] + distances[p, i]
        terms = terms + (params.person_to_model / float(num)) * sums
    if params.model_to_person > 0.0:
        sums = PartVector()
        pixels = int(0)
        for y in range(row_sums.shape[1]):
            sums = sums + row_sums[p, y]
            pixels = pixels + row_pixels[p, y]
        terms = terms + (params.model_to_person / float(pixels)) * sums
    to_person = wp.inverse(transforms[p])
    top = wp.abs(transform_point(to_person, extremes[p, 0])[1] - target.top[1])
    bottom = wp.abs(transform_point(to_person, extremes[p, 1])[1] - target.bottom[1])
    total = float(0.0)
    for k in range(NUM_PARTS):
        term = params.scale * params.part_weights[k] * terms[k]
        term_costs[p, k] = term_costs[p, k] + term
        total = total + term
    top_term = params.scale * params.top_weight * top
    bottom_term = params.scale * params.bottom_weight * bottom
    term_costs[p, NUM_PARTS] = term_costs[p, NUM_PARTS] + top_term
    term_costs[p, NUM_PARTS + 1] = term_costs[p, NUM_PARTS + 1] + bottom_term
    costs[p] = costs[p] + total + top_term + bottom_term


def launch_model_to_person(runs: wp.array, run_counts: wp.array, transforms: wp.array,
                           person_distance: wp.array, row_sums: wp.array,
                           row_pixels: wp.array) -> None:
    """Per row of every candidate: the part sums of its boundary pixels' distances to the
    person's boundary (row_sums (P, H) PartVector) and their count (row_pixels (P, H))."""
    wp.launch(_model_to_person_kernel, dim=run_counts.shape, device=runs.device,
              inputs=[runs, run_counts, transforms, person_distance],
              outputs=[row_sums, row_pixels])


def launch_view_cost(params: CostParams, target: WarpSilhouetteMoments, distances: wp.array,
                     parts: wp.array, row_sums: wp.array, row_pixels: wp.array,
                     transforms: wp.array, extremes: wp.array, areas: wp.array,
                     term_costs: wp.array, costs: wp.array) -> None:
    """Add one view's weighted terms to (P, 12) ``term_costs`` and (P,) ``costs``.

    Reads the person -> model matches (``distances``, ``parts``: (P, N)) when
    ``params.person_to_model`` > 0 and the model -> person row sums when
    ``params.model_to_person`` > 0; the alignment's transforms, extremes and areas.
    """
    wp.launch(_view_cost_kernel, dim=costs.shape[0], device=costs.device,
              inputs=[params, target, distances, parts, row_sums, row_pixels, transforms,
                      extremes, areas], outputs=[term_costs, costs])
