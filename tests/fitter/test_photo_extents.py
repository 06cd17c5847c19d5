"""Girths and the shoulder breadth scaled to the photos' extents: a person whose neck is
wider (or deeper), whose chest is deeper, or whose shoulders are broader, than the fitted
body's, photographed through a known camera, gives back that girth or those shoulders'
breadth."""

import cv2
import numpy as np
import pytest

from bodyfit import kernels
from bodyfit.fitter.fit import photo_extents
from bodyfit.fitter.fit.photo_extents import (MAX_CHANGE, WHOLE_SECTION, ViewPhoto, extent_ratio,
                                              outline_width, person_width,
                                              photo_scaled_measurements, placed_camera,
                                              silhouette_axis, turned_to_tape)
from bodyfit.fitter.fit.pinhole_canvas import Placement
from bodyfit.fitter.fit.side_arms import side_photo_pose
from bodyfit.fitter.measure.measurements import LIMB_SECTIONS
from bodyfit.fitter.model.body_model import PART_NAMES, POSE_NAMES, forward, rest_shape

PHOTO_SHAPE = (1600, 1200)
K = np.array([[1500.0, 0, 599.5], [0, 1500.0, 799.5], [0, 0, 1]])


def test_outline_width_takes_the_run_at_or_nearest_the_column():
    row = np.zeros(20, bool)
    row[2:6] = True
    row[9:15] = True
    assert outline_width(row, 10.0) == (9, 14)
    assert outline_width(row, 16.5) == (9, 14)
    assert outline_width(row, 6.5) == (2, 5)  # 0.5 from the first run, 2.5 from the second
    assert outline_width(np.zeros(5, bool), 2.0) == (0, -1)


def test_person_width_sums_the_shares_of_its_run_and_its_edges():
    """Shares beyond the run count up to SHARE_REACH_PX (2) pixels out, another run's
    pixels not; without shares the width is the run's length."""
    share = np.array([[0.9, 0.0, 0.2, 0.6, 1.0, 1.0, 0.7, 0.3, 0.1, 0.9]], np.float32)
    photo = ViewPhoto("side", share > 0.5, np.eye(3), np.zeros((1, 3)), (), share)
    assert outline_width(photo.mask[0], 4.5) == (3, 6)
    assert person_width(photo, 0, range(10), (3, 6)) == pytest.approx(0.2 + 3.3 + 0.3 + 0.1)
    # the first pixel belongs to another run, the last lies 3 px beyond the run
    inner = ViewPhoto("side", photo.mask, np.eye(3), np.zeros((1, 3)), ())
    assert person_width(inner, 0, range(10), (3, 6)) == 4.0
    # a crop of the row: its columns start at 2
    assert person_width(photo, 0, range(2, 9), (1, 4)) == pytest.approx(3.9)


@pytest.mark.parametrize("tilt_deg", [10.0, 15.0])
def test_summed_shares_of_a_turned_strip_read_its_width_finer_than_whole_pixels(tilt_deg):
    """A strip 45.7 px wide tilted ``tilt_deg`` from upright, its mask the pixels whose
    centre it holds, turned upright by a bilinear warp (as turned_to_tape turns a photo):
    along the rows the thresholded mask's runs are off by about half a pixel (sd) and
    the summed shares by under 0.6 of that (the side photo's neck tape is tilted 8-15
    degrees), both unbiased (7 sub-pixel offsets, 21 rows each)."""
    size, width = 200, 45.7
    thresholded, summed = [], []
    for offset in np.linspace(0.0, 1.0, 7, endpoint=False):
        y, x = np.mgrid[0:size, 0:size].astype(float)
        centre = size / 2 + offset
        tilt = np.radians(tilt_deg)
        across = (x - centre) * np.cos(tilt) + (y - centre) * np.sin(tilt)
        mask = (np.abs(across) <= width / 2).astype(np.float32)
        turn = cv2.getRotationMatrix2D((centre, centre), tilt_deg, 1.0)
        share = cv2.warpAffine(mask, turn, (size, size), flags=cv2.INTER_LINEAR)
        photo = ViewPhoto("side", share > 0.5, np.eye(3), np.zeros((1, 3)), (), share)
        for row in range(90, 111):
            run = outline_width(photo.mask[row], centre)
            thresholded.append(run[1] - run[0] + 1 - width)
            summed.append(person_width(photo, row, range(size), run) - width)
    assert abs(np.mean(thresholded)) < 0.1 and abs(np.mean(summed)) < 0.02
    assert np.std(thresholded) > 0.4
    assert np.std(summed) < 0.6 * np.std(thresholded)


def _neck_widened(body_model, measurer, vertices: np.ndarray, factor: float,
                  slope: float = 0.0) -> np.ndarray:
    """``vertices`` (V, 3) with the neck region's x scaled about its centre by ``factor``
    plus ``slope`` per metre of height above the neck tape's centre (a positive slope
    widens the outline upwards, as the jaw's underside does; a negative one flares it
    downwards, as the neck's base into the shoulders does)."""
    out = vertices.astype(np.float64).copy()
    neck = measurer.landmarks["region:neck"]
    centre = out[neck, 0].mean()
    scale = factor + slope * (out[neck, 2] - measurer.girth_centre(out, "B")[2])
    out[neck, 0] = centre + scale * (out[neck, 0] - centre)
    return out


def _deepened(measurer, vertices: np.ndarray, key: str, factor: float,
              reach: float) -> np.ndarray:
    """``vertices`` (V, 3) with the body ``factor`` times as deep front to back at girth
    ``key``'s tape (the neck's: the throat's front, the head's part, with it): each
    vertex's y scaled about the tape's centre, fully on its plane, less with the distance
    from it, not at all ``reach`` metres away."""
    out = vertices.astype(np.float64).copy()
    origin, normal = measurer.girth_plane(out, key)
    distance = np.abs((out - origin) @ normal) / np.linalg.norm(normal)
    weight = np.clip(1 - distance / reach, 0, 1)
    centre = measurer.girth_centre(out, key)[1]
    out[:, 1] = centre + (1 + (factor - 1) * weight) * (out[:, 1] - centre)
    return out


def _head_scaled(measurer, vertices: np.ndarray, factor: float, axis: int) -> np.ndarray:
    """``vertices`` (V, 3) with the head ``factor`` times as wide (``axis`` 0) or as deep
    (1) about its tape's centre: fully from 3 cm above the neck-top ring up, not at all
    below the ring, evenly between."""
    out = vertices.astype(np.float64).copy()
    neck_top = out[measurer.landmarks["ring:neck_top"], 2].mean()
    weight = np.clip((out[:, 2] - neck_top) / 0.03, 0, 1)
    centre = measurer.girth_centre(out, "A")[axis]
    out[:, axis] = centre + (1 + (factor - 1) * weight) * (out[:, axis] - centre)
    return out


def _labels(body_model, body: np.ndarray, k: np.ndarray, camera) -> np.ndarray:
    """(H, W) int8 part labels of ``body`` (V, 3) through K ``k`` and (R, t) ``camera``."""
    return kernels.rasterize(body[None].astype(np.float32), body_model.faces,
                             body_model.face_parts, kernels.pinhole_camera(k, *camera),
                             *PHOTO_SHAPE).numpy()[0]


def _photo_of(body_model, body: np.ndarray, view: str = "front") -> np.ndarray:
    """(H, W) bool: ``body`` (V, 3) standing on the floor 3 m from a camera K held 1 m
    high, seen from the ``view``'s side."""
    placement = Placement(3.0, 1.0, 0.0, -body[:, 2].min())
    return _labels(body_model, body, K, placement.extrinsics(view)) >= 0


@pytest.fixture(scope="module")
def mean_body(body_model):
    betas = np.zeros((1, 20))
    posed = forward(body_model, betas, np.zeros((1, len(POSE_NAMES))))[0].astype(np.float64)
    rest = rest_shape(body_model, betas)[0][0].astype(np.float64)
    return posed, rest


@pytest.fixture(scope="module")
def mean_body_arms_down(body_model, mean_body):
    """(posed, rest) as ``mean_body``, posed as a side photo's person stands: the arms
    hanging down."""
    betas = np.zeros(20)
    pose = side_photo_pose(body_model, betas, np.zeros(len(POSE_NAMES)))
    posed = forward(body_model, betas[None], pose[None])[0].astype(np.float64)
    return posed, mean_body[1]


def _follows(body_model, measurer, mean_body, key: str, view: str, deform, factor: float,
             share: float) -> tuple[float, float]:
    """The fitted body is the mean body, the person the mean body deformed by ``deform``
    (vertices (V, 3), ``factor``) -> vertices, photographed from the ``view``. Scaled to the
    photo, measurement ``key`` moves at least ``share`` of the way to the person's; for
    the same body (``factor`` 1) it stays within 0.5 % (the camera is placed from the
    silhouette's rows, to a fraction of a pixel). Returns (fitted, true), mm."""
    posed, rest = mean_body
    photo = ViewPhoto(view, _photo_of(body_model, deform(posed, factor), view), K, posed,
                      PART_NAMES)
    got = photo_scaled_measurements(body_model, measurer, rest, {view: photo})[key]
    fitted = measurer.measure(rest)[key]
    true = measurer.measure(deform(rest, factor))[key]
    if factor == 1.0:
        assert got == pytest.approx(fitted, rel=0.005)
    else:
        assert abs(got - true) < (1 - share) * abs(true - fitted)
    return fitted, true


@pytest.mark.parametrize("factor", [1.0, 1.08, 0.93])
def test_the_neck_girth_follows_the_photo(body_model, measurer, mean_body, factor):
    """The person's neck ``factor`` times as wide, photographed with the neck 60 px wide:
    the girth moves at least 80 % of the way (:func:`_follows`)."""
    _follows(body_model, measurer, mean_body, "B", "front",
             lambda v, f: _neck_widened(body_model, measurer, v, f), factor, 0.8)


@pytest.mark.parametrize("factor", [1.0, 1.08, 0.93])
def test_the_neck_girth_follows_the_side_photo(body_model, measurer, mean_body, factor):
    """The neck ``factor`` times as deep, seen from the side (the neck some 45 px deep,
    its tape tilted in the photo): the girth moves at least two thirds of the way (the
    band's rows either side of the tape see less of the deepening)."""
    _follows(body_model, measurer, mean_body, "B", "side",
             lambda v, f: _deepened(measurer, v, "B", f, 0.03), factor, 2 / 3)


@pytest.mark.parametrize("key", ["D", "E"])
@pytest.mark.parametrize("factor", [1.0, 1.06, 0.95])
def test_the_chest_and_waist_girths_follow_the_side_photo(body_model, measurer,
                                                          mean_body_arms_down, key, factor):
    """The trunk ``factor`` times as deep at the chest's or the waist's tape, fully there
    and less over 10 cm up and down, seen from the side with the arms hanging down (as
    people stand for it; the trunk some 125-135 px deep): the girth moves at least 80 %
    of the way."""
    _follows(body_model, measurer, mean_body_arms_down, key, "side",
             lambda v, f: _deepened(measurer, v, key, f, 0.1), factor, 0.8)


@pytest.mark.parametrize("view", ["front", "side"])
@pytest.mark.parametrize("factor", [1.0, 1.06, 0.95])
def test_the_head_girth_follows_the_photo(body_model, measurer, mean_body, view, factor):
    """The head ``factor`` times as wide, seen from the front, or as deep, seen from the
    side: the girth moves at least 80 % of the way."""
    _follows(body_model, measurer, mean_body, "A", view,
             lambda v, f: _head_scaled(measurer, v, f, 0 if view == "front" else 1), factor,
             0.8)


def _shoulders_widened(measurer, vertices: np.ndarray, factor: float) -> np.ndarray:
    """``vertices`` (V, 3) with the body's x scaled by ``factor`` about its middle from 5
    cm below the acromions up (the shoulders, neck and head), not at all from 15 cm below,
    evenly between."""
    out = vertices.astype(np.float64).copy()
    top = measurer.acromions(out)[:, 2].mean()
    weight = np.clip((out[:, 2] - (top - 0.15)) / 0.1, 0, 1)
    middle = measurer.acromions(out)[:, 0].mean()
    out[:, 0] = middle + (1 + (factor - 1) * weight) * (out[:, 0] - middle)
    return out


@pytest.mark.parametrize("factor", [1.0, 1.05, 0.96])
def test_the_shoulder_breadth_follows_the_photo(body_model, measurer, mean_body, factor):
    """The shoulders ``factor`` times as broad: the shoulder breadth moves at least 80 %
    of the way (the arms' outline 2 cm below the acromions, about 200 px across)."""
    fitted, true = _follows(body_model, measurer, mean_body, "P", "front",
                            lambda v, f: _shoulders_widened(measurer, v, f), factor, 0.8)
    assert true == pytest.approx(fitted * factor)


def test_the_silhouette_axis_lies_in_the_tape_across_the_line_of_sight(measurer, mean_body):
    """The trunk's tapes are horizontal: the front photo sees their extent across the body
    (x), the side photo front to back (y). The A-pose's forearm reaches forward: its axis
    lies in the tape's plane, across the front camera's line of sight (y), and some
    degrees off the section's first axis."""
    posed, _ = mean_body
    for view, expected in (("front", [1.0, 0.0, 0.0]), ("side", [0.0, 1.0, 0.0])):
        assert abs(silhouette_axis(measurer, posed, "D", view) @ expected) == pytest.approx(1.0)
    axis = silhouette_axis(measurer, posed, "I.L", "front")
    normal = measurer.girth_plane(posed, "I.L")[1]
    assert axis @ normal == pytest.approx(0.0, abs=1e-9)
    assert axis[1] == pytest.approx(0.0, abs=1e-9)
    assert np.linalg.norm(axis) == pytest.approx(1.0)
    assert abs(axis @ measurer.girth_axes(posed, "I.L")[0]) < np.cos(np.radians(10))


#: a limb girth -> the regions its tapes widen (each side's) and how far from the tape's
#: plane the widening is full (metres; it then falls to none over 4 cm more): the
#: wrist's photo width is read 3 cm up the forearm (``WRIST_RISE_M``), so the person's
#: whole lower forearm is wider there
_LIMB_REGIONS = {"G": (("forearm", "hand"), 0.05), "H": (("upperarm",), 0.0),
                 "I": (("forearm",), 0.0), "M": (("shank",), 0.0), "N": (("shank",), 0.0)}
#: a limb girth -> the least share of the way it must move (``_follows``)
_LIMB_SHARES = {"G": 0.8, "H": 0.8, "I": 0.6, "M": 0.5, "N": 0.7}


def _limbs_widened(measurer, vertices: np.ndarray, key: str, factor: float) -> np.ndarray:
    """``vertices`` (V, 3) with each limb ``factor`` times as wide across girth ``key``'s
    tape as the front photo sees it (along its silhouette axis, about the limb's axis
    through the section's centre; for the tapes of ``WHOLE_SECTION`` as thick every way
    in the tape's plane), fully near the tape's plane (``_LIMB_REGIONS``), less farther,
    not at all 4 cm beyond."""
    out = vertices.astype(np.float64).copy()
    regions, full = _LIMB_REGIONS[key]
    for tape, side in zip(LIMB_SECTIONS[key], ("L", "R")):
        limb = np.concatenate([measurer.landmarks[f"region:{region}.{side}"]
                               for region in regions])
        origin, normal = measurer.girth_plane(out, tape)
        centre = measurer.girth_centre(out, tape)
        distance = np.abs((out[limb] - origin) @ normal) / np.linalg.norm(normal)
        weight = np.clip(1 - (distance - full) / 0.04, 0, 1)
        if tape in WHOLE_SECTION:  # thicker both ways in the tape's plane
            offsets = out[limb] - centre
            offsets -= np.outer(offsets @ normal, normal) / (normal @ normal)
            out[limb] += (factor - 1) * weight[:, None] * offsets
        else:
            across = silhouette_axis(measurer, out, tape, "front")
            offset = (out[limb] - centre) @ across
            out[limb] += ((factor - 1) * weight * offset)[:, None] * across
    return out


@pytest.mark.parametrize("key", ["G", "H", "I", "M", "N"])
@pytest.mark.parametrize("factor", [1.0, 1.08, 0.93])
def test_the_limb_girths_follow_the_photo(body_model, measurer, mean_body, key, factor):
    """Both limbs ``factor`` times as wide across the wrist's, the bicep's (as thick every
    way: its photo's ratio scales the whole section), the forearm's,
    the calf's or the ankle's tapes as the front photo sees them (tilted
    with the A-pose's limbs, some 25-45 px across for the arm's; the forearm reaches
    forward, out of the photo's plane): the girth moves at least 80 % of the way, the
    forearm's 60 %, the calf's 50 % and the ankle's 70 % (their girth is the largest or
    the smallest of 6-7 planes: changed at the tape, another plane's may become it, and
    the truth moves less than the section)."""
    _follows(body_model, measurer, mean_body, key, "front",
             lambda v, f: _limbs_widened(measurer, v, key, f), factor, _LIMB_SHARES[key])


def test_the_turned_view_is_the_photo_of_a_turned_camera(body_model, measurer, mean_body):
    """turned_to_tape's mask is the body's photo through its turned camera (a round trip
    through the renderer, to the warp's rounding at the outline), the neck's tape line
    lies along a row of it, and the side photo's neck tape is tilted some degrees."""
    posed, _ = mean_body
    photo = ViewPhoto("side", _photo_of(body_model, posed, "side"), K, posed, PART_NAMES)
    camera = placed_camera(body_model, photo)
    turned, (rotation, translation) = turned_to_tape(measurer, "B", photo, camera)
    rendered = _labels(body_model, posed, turned.intrinsics, (rotation, translation)) >= 0
    contours, _ = cv2.findContours(rendered.astype(np.uint8), cv2.RETR_EXTERNAL,
                                   cv2.CHAIN_APPROX_NONE)
    outline = sum(len(contour) for contour in contours)
    # the warp re-decides outline pixels (23 % here), without moving the outline
    assert np.sum(rendered ^ turned.mask) < 0.4 * outline
    assert abs(int(rendered.sum()) - int(turned.mask.sum())) < 0.05 * outline
    centre = measurer.girth_centre(posed, "B")
    ends = np.stack([centre, centre + 0.05 * measurer.girth_axes(posed, "B")[1]])
    rows = (ends @ rotation.T + translation) @ turned.intrinsics.T
    assert rows[0, 1] / rows[0, 2] == pytest.approx(rows[1, 1] / rows[1, 2], abs=1e-6)
    assert np.sum(turned.mask ^ photo.mask) > outline  # not the photo as it was


def test_a_change_beyond_the_bound_keeps_the_fitted_girth(body_model, measurer, mean_body):
    posed, rest = mean_body
    wide = 1.0 + 2 * MAX_CHANGE
    person = _photo_of(body_model, _neck_widened(body_model, measurer, posed, wide))
    photo = ViewPhoto("front", person, K, posed, PART_NAMES)
    got = photo_scaled_measurements(body_model, measurer, rest, {"front": photo})["B"]
    assert got == pytest.approx(measurer.measure(rest)["B"], abs=1e-6)


def test_a_neck_outline_widening_across_its_band_keeps_the_fitted_neck(body_model, measurer,
                                                                       mean_body):
    """A person whose neck widens by 2.5 % per mm of height (some 20 % over the band's 5
    rows of 2 mm, its mean ratio still about 1) gives no neck ratio; widened evenly by 8 %,
    the same neck gives one of 1.08."""
    posed, _ = mean_body
    ratios = {}
    for name, body in (("flared", _neck_widened(body_model, measurer, posed, 1.0, slope=25.0)),
                       ("even", _neck_widened(body_model, measurer, posed, 1.08))):
        photo = ViewPhoto("front", _photo_of(body_model, body), K, posed, PART_NAMES)
        ratios[name] = extent_ratio(body_model, measurer, "B", photo,
                                    placed_camera(body_model, photo))
    assert ratios["flared"] is None
    assert ratios["even"] == pytest.approx(1.08, abs=0.02)


def test_a_neck_band_on_a_slope_keeps_the_fitted_neck(body_model, measurer, mean_body,
                                                    monkeypatch):
    """A fitted body whose neck narrows by 2.5 % per mm of height at its tape (its
    outline's sides over 45 degrees from upright across the band), photographed 8 % wider
    all over: no neck ratio; with the lean guard off, one of 1.10 (on the slope a row's
    width reads more than the 8 %)."""
    posed, _ = mean_body
    sloped = _neck_widened(body_model, measurer, posed, 1.0, slope=-25.0)
    photo = ViewPhoto("front", _photo_of(body_model, _neck_widened(body_model, measurer,
                                                                   sloped, 1.08)),
                      K, sloped, PART_NAMES)
    camera = placed_camera(body_model, photo)
    assert extent_ratio(body_model, measurer, "B", photo, camera) is None
    monkeypatch.setattr(photo_extents, "MAX_OUTLINE_LEAN_DEG", {})
    assert extent_ratio(body_model, measurer, "B", photo, camera) == pytest.approx(1.10, abs=0.02)


def test_a_person_whose_arms_touch_the_chest_keeps_the_fitted_chest(body_model, measurer,
                                                                    mean_body):
    """The fitted body's arms hang clear of its chest; a person whose outline joins arm and
    chest at the tape (every row's first two runs merged) gives no chest ratio, where the
    body's own photo gives one of about 1."""
    posed, _ = mean_body
    person = _photo_of(body_model, posed)
    joined = person.copy()
    for row in joined:
        cols = np.flatnonzero(row)
        gaps = np.flatnonzero(np.diff(cols) > 1)
        if len(gaps):
            row[cols[gaps[0]]:cols[gaps[0] + 1]] = True
    apart = ViewPhoto("front", person, K, posed, PART_NAMES)
    camera = placed_camera(body_model, apart)
    assert extent_ratio(body_model, measurer, "D", apart, camera) == pytest.approx(1, abs=0.01)
    touching = ViewPhoto("front", joined, K, posed, PART_NAMES)
    assert extent_ratio(body_model, measurer, "D", touching,
                        placed_camera(body_model, touching)) is None
