"""The matched-contour overlays of a fit (the paper's Fig. 6 and 8), for people to judge.

The fitted body is rendered by the kernels (:func:`bodyfit.kernels.rasterize`) with the
view's camera onto the view's canvas, as a part-label map. Then the paper's path of
:mod:`bodyfit.fitter.fit.contour`: both outer boundaries are traced and normalised, the
person's contour is registered onto the body's by rigid ICP, and every person point is
paired with its nearest body point; each pair takes the body part of its body point.

The overlay draws, in the body's canvas frame, the person's silhouette (grey, moved by the
registration: normalised to the body's RMS radius, as the paper matches them), the
fitted body's silhouette (tinted by part) and the matched pairs as short lines coloured
by part, upscaled, with a legend. Points are (column, row) pixels.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from bodyfit import kernels
from bodyfit.fitter.fit.contour import RigidFit, contour_points, normalise_contour, rigid_icp
from bodyfit.fitter.model.body_model import PART_NAMES, BodyModel
from bodyfit.fitter.output.render import PART_COLOURS_BGR, parts_legend
from bodyfit.kernels.target import visible_faces

__all__ = ["MatchedContours", "match_contours", "overlay_image", "fitted_outline_image",
           "outline_in_photo", "photo_outline_image", "OVERLAY_SCALE", "PHOTO_HEIGHT_PX"]

#: Upscaling of the overlays over the canvas, for legibility.
OVERLAY_SCALE = 2
_PAIR_STEP = 3  # draw every third pair: all of them blur into a band
_PERSON_BGR = (212, 212, 212)
_PERSON_EDGE_BGR = (40, 40, 40)
_TINT = 0.35
_FONT = cv2.FONT_HERSHEY_SIMPLEX
#: The height of the photo with the fitted outline, pixels (the person's box and a margin).
PHOTO_HEIGHT_PX = 720
_MASK_EDGE_BGR = (255, 255, 255)


@dataclasses.dataclass(frozen=True)
class MatchedContours:
    """One view's registration of the person's contour onto the fitted body's.

    Attributes:
        view: "front" or "side".
        labels: (H, W) int8 part label of the fitted body on the canvas, -1 background.
        silhouette: (H, W) bool, the person's canvas mask.
        body: (M, 2) float64 the body's contour, canvas pixels.
        body_parts: (M,) int, part index (``PART_NAMES``) of each body point.
        person: (N, 2) float64 the person's contour, canvas pixels.
        registration: the rigid fit of the normalised person contour onto the normalised
            body contour (its ``matches`` index ``body``).
        person_frame: (centre (2,), scale) that normalised the person's contour.
        body_frame: (centre (2,), scale) that normalised the body's contour.
        millimetres_per_pixel: canvas scale.
    """

    view: str
    labels: np.ndarray
    silhouette: np.ndarray
    body: np.ndarray
    body_parts: np.ndarray
    person: np.ndarray
    registration: RigidFit
    person_frame: tuple[np.ndarray, float]
    body_frame: tuple[np.ndarray, float]
    millimetres_per_pixel: float

    def person_on_body(self, points: np.ndarray) -> np.ndarray:
        """(N, 2) person-canvas points moved into the body's frame by the registration."""
        centre, scale = self.person_frame
        body_centre, body_scale = self.body_frame
        return self.registration.apply((points - centre) / scale) * body_scale + body_centre

    def body_on_person(self, points: np.ndarray) -> np.ndarray:
        """(M, 2) body-canvas points moved into the person's frame (the inverse)."""
        centre, scale = self.person_frame
        body_centre, body_scale = self.body_frame
        fit = self.registration
        normalised = ((points - body_centre) / body_scale - fit.translation) @ fit.rotation
        return normalised * scale + centre

    @property
    def mean_distance_mm(self) -> float:
        """Mean distance of the matched pairs, millimetres (in the body's frame)."""
        return float(self.registration.distances.mean() * self.body_frame[1]
                     * self.millimetres_per_pixel)


def match_contours(model: BodyModel, posed: np.ndarray, view: kernels.ViewTarget,
                   device: str = "cpu") -> MatchedContours:
    """Render the fitted body into ``view``'s canvas and match the two contours.

    Args:
        model: the body model (faces and their parts).
        posed: (V, 3) float metres, the fitted body as the view's canvas shows it
            (``Fit.view_bodies``).
        view: the view's kernel target (camera, canvas size, person's mask, visible parts).
        device: where the kernels run.
    """
    faces, face_parts = visible_faces(model.faces, model.face_parts, view.visible_parts)
    labels = kernels.rasterize(np.asarray(posed, np.float32)[None], faces, face_parts,
                               view.camera, view.height, view.width, device).numpy()[0]
    body = contour_points(labels >= 0)
    person = contour_points(view.silhouette)
    body_n, body_centre, body_scale = normalise_contour(body)
    person_n, person_centre, person_scale = normalise_contour(person)
    registration = rigid_icp(person_n, body_n)
    columns, rows = body.astype(int).T
    return MatchedContours(view.name, labels, np.asarray(view.silhouette, bool), body,
                           labels[rows, columns].astype(int), person, registration,
                           (person_centre, person_scale), (body_centre, body_scale),
                           view.millimetres_per_pixel)


def _px(points: np.ndarray) -> np.ndarray:
    """(N, 2) canvas points -> (N, 1, 2) int32 pixels of the upscaled picture."""
    return np.round((points + 0.5) * OVERLAY_SCALE - 0.5).astype(np.int32)[:, None, :]


def _upscaled_canvas(shape: tuple[int, int]) -> np.ndarray:
    return np.full((shape[0] * OVERLAY_SCALE, shape[1] * OVERLAY_SCALE, 3), 255, np.uint8)


def _tint(colour: np.ndarray) -> tuple[int, ...]:
    """A part colour as the fitted body's tint over white."""
    return tuple(int(round(_TINT * c + (1 - _TINT) * 255)) for c in colour)


def _tinted_body(image: np.ndarray, labels: np.ndarray) -> None:
    """Tint ``image`` (upscaled canvas) by part where the body's ``labels`` (canvas) are."""
    big = cv2.resize(labels, image.shape[1::-1], interpolation=cv2.INTER_NEAREST).astype(int)
    inside = big >= 0
    colours = PART_COLOURS_BGR[big[inside]].astype(np.float64)
    image[inside] = np.round(_TINT * colours + (1 - _TINT) * image[inside]).astype(np.uint8)


def _cropped(image: np.ndarray, margin_px: int = 16) -> np.ndarray:
    """``image`` cut to its drawn (non-white) pixels plus a margin: the canvas leaves room
    for every candidate of the search, mostly empty around the fitted one."""
    rows, cols = np.nonzero((image < 255).any(axis=2))
    top, left = max(0, rows.min() - margin_px), max(0, cols.min() - margin_px)
    return image[top:rows.max() + margin_px + 1, left:cols.max() + margin_px + 1]


def _draw_part_outline(image: np.ndarray, outline: np.ndarray, parts: np.ndarray) -> None:
    """Draw the closed ``outline`` ((N, 1, 2) int32 pixels) on ``image``, each segment 2 px
    wide in the colour of its first point's part (``parts``: (N,) ``PART_NAMES`` indices)."""
    for i in range(len(outline)):
        colour = PART_COLOURS_BGR[parts[i]].tolist()
        cv2.line(image, tuple(outline[i, 0]), tuple(outline[(i + 1) % len(outline), 0]), colour,
                 2, cv2.LINE_AA)


def _with_legend(image: np.ndarray, title: str, entries: list[tuple[tuple, str]]) -> np.ndarray:
    """``image``, cropped, under a title band, with the parts legend and ``entries`` to
    its right."""
    image = _cropped(image)
    legend = parts_legend(20 + 24 * (len(PART_NAMES) + len(entries)))
    for i, (colour, text) in enumerate(entries):
        y = 20 + 24 * (len(PART_NAMES) + i)
        cv2.rectangle(legend, (8, y - 12), (26, y + 4), colour, -1)
        cv2.rectangle(legend, (8, y - 12), (26, y + 4), (0, 0, 0), 1)
        cv2.putText(legend, text, (34, y + 2), _FONT, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    band = 30
    height = max(image.shape[0], legend.shape[0]) + band
    picture = np.full((height, image.shape[1] + legend.shape[1], 3), 255, np.uint8)
    cv2.putText(picture, title, (8, 21), _FONT, 0.6, (0, 0, 0), 1, cv2.LINE_AA)
    picture[band:band + image.shape[0], :image.shape[1]] = image
    picture[band:band + legend.shape[0], image.shape[1]:] = legend
    return picture


def overlay_image(matched: MatchedContours) -> np.ndarray:
    """(H', W', 3) uint8 BGR overlay: person (grey) and fitted body (tinted by part) in the
    body's frame, every third matched pair a line coloured by its body point's part,
    ``OVERLAY_SCALE`` times the canvas, a title and a legend at the right."""
    image = _upscaled_canvas(matched.labels.shape)
    person = _px(matched.person_on_body(matched.person))
    cv2.fillPoly(image, [person], _PERSON_BGR, cv2.LINE_AA)
    _tinted_body(image, matched.labels)
    cv2.polylines(image, [person], True, _PERSON_EDGE_BGR, 1, cv2.LINE_AA)
    targets = _px(matched.body[matched.registration.matches])
    parts = matched.body_parts[matched.registration.matches]
    for i in range(0, len(person), _PAIR_STEP):
        colour = PART_COLOURS_BGR[parts[i]].tolist()
        cv2.line(image, tuple(person[i, 0]), tuple(targets[i, 0]), colour, 2, cv2.LINE_AA)
        cv2.circle(image, tuple(person[i, 0]), 2, colour, -1, cv2.LINE_AA)
    title = f"{matched.view}: matched pairs, mean {matched.mean_distance_mm:.1f} mm"
    return _with_legend(image, title, [(_PERSON_BGR, "person"),
                                       (_tint(PART_COLOURS_BGR[1]), "fitted body")])


def fitted_outline_image(matched: MatchedContours) -> np.ndarray:
    """(H', W', 3) uint8 BGR: the person's canvas silhouette (dark grey, as it is) with the
    fitted body's outline drawn over it, coloured by part and moved onto the person by the
    inverse registration; upscaled, titled, with a legend."""
    image = _upscaled_canvas(matched.silhouette.shape)
    big = cv2.resize(matched.silhouette.astype(np.uint8), image.shape[1::-1],
                     interpolation=cv2.INTER_NEAREST).astype(bool)
    image[big] = (110, 110, 110)
    _draw_part_outline(image, _px(matched.body_on_person(matched.body)), matched.body_parts)
    return _with_legend(image, f"{matched.view}: person and fitted outline",
                        [((110, 110, 110), "person")])


def _canvas_to_photo(canvas_mask: np.ndarray, photo_mask: np.ndarray, points: np.ndarray
                     ) -> np.ndarray:
    """(N, 2) canvas points -> photo pixels. The canvas holds the photo's silhouette moved
    and scaled alike along both axes (:mod:`bodyfit.fitter.fit.canvas`,
    :mod:`bodyfit.fitter.fit.pinhole_canvas`), so the map is the one that takes the canvas
    silhouette's area and centroid onto the photo's."""
    def centroid(mask):
        rows, cols = np.nonzero(mask)
        return np.array([cols.mean(), rows.mean()])

    scale = np.sqrt(photo_mask.sum() / canvas_mask.sum())
    return centroid(photo_mask) + scale * (points - centroid(canvas_mask))


def outline_in_photo(matched: MatchedContours, mask: np.ndarray, mirrored: bool = False
                     ) -> np.ndarray:
    """(M, 2) float64 the fitted body's outline (``matched.body``, its parts
    ``matched.body_parts``) in the pixels of the person's photo: moved onto the person by
    the inverse registration, then from the canvas into the photo.

    Args:
        matched: the view's matched contours.
        mask: (H, W) bool, the photo's silhouette as fitted (mirrored when ``mirrored``).
        mirrored: the fit saw the photo mirrored (a side photo from the person's right):
            the outline is mirrored back onto the photo as taken.
    """
    outline = _canvas_to_photo(matched.silhouette, mask, matched.body_on_person(matched.body))
    if mirrored:
        outline[:, 0] = mask.shape[1] - 1 - outline[:, 0]
    return outline


def photo_outline_image(matched: MatchedContours, photo: np.ndarray, mask: np.ndarray,
                        mirrored: bool = False) -> np.ndarray:
    """(H', W', 3) uint8 BGR: the person's own photo, cut to the person with a margin, the
    silhouette's outline in white and the fitted body's (:func:`outline_in_photo`) over it
    coloured by part, ``PHOTO_HEIGHT_PX`` tall, titled, with a legend.

    Args:
        matched, mask, mirrored: as :func:`outline_in_photo`.
        photo: (H, W, 3) uint8 BGR, the photo upright (and undistorted), as the user gave it.
    """
    outline = outline_in_photo(matched, mask, mirrored)
    if mirrored:
        mask = mask[:, ::-1]
    edge = contour_points(mask)
    rows, cols = np.nonzero(mask)
    margin = 0.06 * (rows.max() - rows.min() + 1)
    top, bottom = max(0, int(rows.min() - margin)), min(mask.shape[0], int(rows.max() + margin) + 1)
    left, right = max(0, int(cols.min() - margin)), min(mask.shape[1], int(cols.max() + margin) + 1)
    scale = PHOTO_HEIGHT_PX / (bottom - top)
    image = cv2.resize(photo[top:bottom, left:right], None, fx=scale, fy=scale,
                       interpolation=cv2.INTER_AREA)

    def pixels(points):
        return np.round((points - [left, top] + 0.5) * scale - 0.5).astype(np.int32)[:, None, :]

    cv2.polylines(image, [pixels(edge)], True, (0, 0, 0), 3, cv2.LINE_AA)
    cv2.polylines(image, [pixels(edge)], True, _MASK_EDGE_BGR, 1, cv2.LINE_AA)
    _draw_part_outline(image, pixels(outline), matched.body_parts)
    return _with_legend(image, f"{matched.view}: the photo and the fitted outline",
                        [(_MASK_EDGE_BGR, "silhouette")])
