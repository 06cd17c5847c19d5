"""Tape measures on analytic shapes and the 16 measurements on model bodies."""

import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull

from bodyfit.fitter.measure.measurements import MEASUREMENTS, SECTION_GIRTHS
from bodyfit.fitter.measure.sections import (hull_perimeter, mesh_edges, section_centre,
                                             section_points, tape_lengths)
from bodyfit.fitter.model_build.anny_source import SHAPE_PARAMETERS
from bodyfit.fitter.model_build.body_sample import SEXES, ReferenceStats

KEYS = list(MEASUREMENTS)


def ellipse_perimeter(a, b):
    """Ramanujan's second approximation (relative error ~1e-10 at these ratios)."""
    h = ((a - b) / (a + b)) ** 2
    return np.pi * (a + b) * (1 + 3 * h / (10 + np.sqrt(4 - 3 * h)))


def test_elliptic_cylinder_tape_is_the_ellipse_perimeter():
    cyl = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=720)
    vertices = cyl.vertices * [0.16, 0.11, 1.0]  # semi-axes 16 cm and 11 cm
    got = tape_lengths(vertices, mesh_edges(cyl.faces), [[0.0, 0.0, 0.1]], [0, 0, 1])[0]
    assert got == pytest.approx(ellipse_perimeter(0.16, 0.11), rel=2e-5)


def test_tilted_plane_through_a_cylinder_is_an_ellipse():
    cyl = trimesh.creation.cylinder(radius=0.05, height=2.0, sections=720)
    tilt = np.deg2rad(30)
    normal = [np.sin(tilt), 0.0, np.cos(tilt)]
    got = tape_lengths(cyl.vertices, mesh_edges(cyl.faces), [[0, 0, 0]], normal)[0]
    assert got == pytest.approx(ellipse_perimeter(0.05 / np.cos(tilt), 0.05), rel=2e-5)


def test_section_of_a_tilted_plane_is_turned_across_the_body():
    """A plane tilted forward about the x axis cuts an elliptic cylinder (semi-axes 8 cm
    across, 5 cm front to back) in an ellipse 16 cm across and 10 / cos(tilt) cm deep."""
    cyl = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=720)
    vertices = cyl.vertices * [0.08, 0.05, 1.0]
    tilt = np.deg2rad(25)
    points = section_points(vertices, mesh_edges(cyl.faces), [0.0, 0.0, 0.3],
                            [0.0, np.sin(tilt), np.cos(tilt)], [1.0, 0.0, 0.0])
    assert np.ptp(points[:, 0]) == pytest.approx(0.16, rel=1e-5)
    assert np.ptp(points[:, 1]) == pytest.approx(0.10 / np.cos(tilt), rel=1e-5)
    assert hull_perimeter(points) == pytest.approx(
        ellipse_perimeter(0.08, 0.05 / np.cos(tilt)), rel=2e-5)


def test_section_centre_of_a_tilted_plane_is_on_the_cylinders_axis():
    """A plane tilted about the x axis through (0, 0, 0.3) cuts a cylinder standing on
    (0.4, -0.2) where the axis meets it: at (0.4, -0.2, 0.3 + 0.2 tan(tilt))."""
    cyl = trimesh.creation.cylinder(radius=0.06, height=2.0, sections=720)
    vertices = cyl.vertices + [0.4, -0.2, 0.0]
    tilt = np.deg2rad(25)
    centre = section_centre(vertices, mesh_edges(cyl.faces), [0.0, 0.0, 0.3],
                            [0.0, np.sin(tilt), np.cos(tilt)])
    np.testing.assert_allclose(centre, [0.4, -0.2, 0.3 + 0.2 * np.tan(tilt)], atol=1e-5)


def test_tape_bridges_concavities_of_an_l_shaped_prism():
    """A tape around an L-shaped prism follows its convex hull, not its outline."""
    outline = np.array([[0, 0], [0.4, 0], [0.4, 0.1], [0.1, 0.1], [0.1, 0.3], [0, 0.3]])
    n = len(outline)
    vertices = np.vstack([np.c_[outline, np.zeros(n)], np.c_[outline, np.ones(n)]])
    sides = [[i, (i + 1) % n, n + i] for i in range(n)] + \
        [[(i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
    got = tape_lengths(vertices, mesh_edges(np.array(sides)), [[0, 0, 0.5]], [0, 0, 1])[0]
    hull = outline[ConvexHull(outline).vertices]
    expected = np.sum(np.linalg.norm(hull - np.roll(hull, 1, axis=0), axis=1))
    assert got == pytest.approx(expected, rel=1e-6)  # OpenCV hulls in float32
    assert got < 2 * (0.4 + 0.3)  # a box around it would be longer


def test_sections_agree_with_trimesh_mesh_plane():
    mesh = trimesh.creation.icosphere(subdivisions=3)
    rng = np.random.default_rng(0)
    mesh.vertices *= 1 + 0.1 * rng.standard_normal((len(mesh.vertices), 1))
    origin, normal = np.array([0.1, -0.05, 0.2]), np.array([0.3, 0.2, 1.0])
    segments = trimesh.intersections.mesh_plane(mesh, normal, origin)
    pts3 = segments.reshape(-1, 3)
    n = normal / np.linalg.norm(normal)
    u = np.cross(n, [1.0, 0, 0])
    u /= np.linalg.norm(u)
    pts2 = np.stack([pts3 @ u, pts3 @ np.cross(n, u)], axis=1)
    expected = ConvexHull(pts2).area
    got = tape_lengths(mesh.vertices, mesh_edges(mesh.faces), [origin], normal)[0]
    assert got == pytest.approx(expected, rel=1e-6)  # OpenCV hulls in float32


def test_a_plane_missing_the_mesh_gives_nan():
    box = trimesh.creation.box([1, 1, 1])
    assert np.isnan(tape_lengths(box.vertices, mesh_edges(box.faces), [[0, 0, 5]], [0, 0, 1])[0])


def test_stature_is_the_mesh_height_and_translation_does_not_matter(body_model, measurer):
    v = body_model.mean_vertices.astype(np.float64)
    got = measurer.measure(v)
    assert got["O"] == pytest.approx(np.ptp(v[:, 2]) * 1000, abs=1e-6)
    shifted = measurer.measure(v + [0.5, -2.0, 1.3])
    for key in KEYS:
        assert shifted[key] == pytest.approx(got[key], abs=1e-3), key


@pytest.mark.parametrize("key", SECTION_GIRTHS)
def test_girth_section_is_the_tape(measurer, body_model, key):
    """Each one-plane girth's section's hull is its circumference; a body twice as wide has
    a section twice as wide and as deep as before."""
    v = body_model.mean_vertices.astype(np.float64)
    points = measurer.girth_section(v, key)
    assert hull_perimeter(points) * 1000 == pytest.approx(measurer.measure(v)[key], rel=1e-6)
    wide = measurer.girth_section(v * [2.0, 1.0, 1.0], key)
    assert np.ptp(wide[:, 0]) == pytest.approx(2 * np.ptp(points[:, 0]), rel=1e-5)
    assert np.ptp(wide[:, 1]) == pytest.approx(np.ptp(points[:, 1]), rel=1e-5)


def test_all_measurements_are_plausible_on_the_mean_body(measurer, body_model):
    got = measurer.measure(body_model.mean_vertices)
    ranges = {"A": (500, 640), "B": (280, 450), "C": (450, 700), "D": (800, 1250),
              "E": (650, 1200), "F": (850, 1200), "G": (130, 200), "H": (220, 400),
              "I": (200, 330), "J": (480, 700), "K": (680, 950), "L": (480, 750),
              "M": (300, 450), "N": (180, 270), "O": (1500, 1900), "P": (320, 460)}
    for key, (lo, hi) in ranges.items():
        assert lo < got[key] < hi, (key, got[key])


def anny_bodies(anny_source, **local_changes):
    params = np.zeros((2, len(SHAPE_PARAMETERS)))
    params[:, :5] = [0.8, 0.5, 0.5, 0.5, 0.5]
    for name, values in local_changes.items():
        params[:, SHAPE_PARAMETERS.index(name)] = values
    return anny_source.rest_bodies(np.array([0.0, 0.0]), params)[0]


@pytest.mark.parametrize("change,key", [("measure-waist-circ-incr", "E"),
                                        ("measure-thigh-circ-incr", "L"),
                                        ("measure-neck-circ-incr", "B")])
def test_a_bigger_local_change_gives_a_bigger_girth(anny_source, measurer, change, key):
    small, big = anny_bodies(anny_source, **{change: [0.0, 0.8]})
    assert measurer.measure(big)[key] > measurer.measure(small)[key] + 10  # mm


@pytest.mark.parametrize("sex", SEXES)
def test_sample_resembles_ansur(body_model, sex):
    """The issue's realism bar: per sex, means and SDs within 10 % of ANSUR II for
    stature, chest, waist, hip, thigh, biacromial breadth and crotch height; the main
    correlations of the same sign and similar size."""
    ref = ReferenceStats.load()
    pop = body_model.sample_measurements[body_model.sample_sex == SEXES.index(sex)]
    for key in "ODEFLPK":
        col, r = pop[:, KEYS.index(key)], ref.keys.index(key)
        assert abs(col.mean() / ref.mean[sex][r] - 1) < 0.10, key
        assert abs(col.std() / ref.std[sex][r] - 1) < 0.10, key
    corr = np.corrcoef(pop, rowvar=False)
    for a, b in [("E", "D"), ("O", "K"), ("F", "L"), ("O", "P")]:
        got = corr[KEYS.index(a), KEYS.index(b)]
        want = ref.correlation[sex][ref.keys.index(a), ref.keys.index(b)]
        assert np.sign(got) == np.sign(want) and abs(got - want) < 0.2, (a, b, got, want)
