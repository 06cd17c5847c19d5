"""Calibration boards: their specification, a printable picture, and their detection.

Two kinds of planar board are supported:

- ``chessboard:COLSxROWS`` -- a plain chessboard; COLS x ROWS counts the *inner corners*
  (where four squares meet), as OpenCV does. The whole board must be visible in a view.
  Found with ``cv2.findChessboardCornersSB`` and refined with ``cv2.cornerSubPix`` (on
  rendered boards the refinement halves SB's corner error, and costs ~1 ms). When SB
  misses the board (a white board on a white wall, steep views, uneven light), detection
  falls back through :data:`CHESSBOARD_ATTEMPTS` before it gives up. The detectors number
  the corners from either end, so the grid is put in one canonical order
  (:func:`canonical_chessboard_order`) whichever detector found it.
- ``charuco:COLSxROWS`` -- a ChArUco board; COLS x ROWS counts the *squares*. ArUco
  markers in the white squares identify every corner, so a partly visible board still
  gives a view. Found with OpenCV 5's ``cv2.aruco.CharucoDetector``, refined with
  ``cv2.cornerSubPix`` in a window that stops short of the markers.

Board coordinates are millimetres in the board plane (z = 0); image coordinates are
pixels with OpenCV's convention (the centre of the top-left pixel is (0, 0)).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.spatial.distance import pdist

from bodyfit.common.errors import UserError

__all__ = [
    "BOARD_KINDS",
    "CHESSBOARD_ATTEMPTS",
    "BoardDetection",
    "BoardDetector",
    "BoardPicture",
    "BoardSpec",
    "canonical_chessboard_order",
    "parse_board",
    "render_board",
]

BOARD_KINDS = ("chessboard", "charuco")

# A ChArUco view with fewer corners than this is too weak to constrain its own pose.
MIN_CHARUCO_CORNERS = 6

# (detector, flags) tried in turn until one finds the chessboard; the later ones run only
# when the earlier fail. SB without NORMALIZE_IMAGE finds boards whose white margin merges
# with a light background; the classic detector finds steep views SB misses. (Both occur
# on OpenCV's own sample photos.) CALIB_CB_ACCURACY would triple SB's detection time for a
# worse result than cornerSubPix.
CHESSBOARD_ATTEMPTS = (
    ("SB", cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE),
    ("SB", cv2.CALIB_CB_EXHAUSTIVE),
    ("classic", cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE),
)
_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 100, 1e-4)


@dataclass(frozen=True)
class BoardSpec:
    """A calibration board as printed.

    Attributes:
        kind: ``"chessboard"`` or ``"charuco"``.
        columns: chessboard: inner corners across; charuco: squares across.
        rows: chessboard: inner corners down; charuco: squares down.
        square_mm: side of one square, millimetres, as measured on the print.
        marker_mm: side of one ArUco marker, millimetres (charuco only, else None).
        dictionary: ArUco dictionary name such as ``"DICT_5X5_100"`` (charuco only, else None).
    """

    kind: str
    columns: int
    rows: int
    square_mm: float
    marker_mm: float | None = None
    dictionary: str | None = None

    def __post_init__(self) -> None:
        _validate(self)

    @property
    def corner_count(self) -> int:
        """Number of corners the board has (all of them are detected in a full view)."""
        if self.kind == "chessboard":
            return self.columns * self.rows
        return (self.columns - 1) * (self.rows - 1)

    @property
    def size_mm(self) -> tuple[float, float]:
        """(width, height) of the squared area, millimetres (margins not included)."""
        squares = (self.columns + 1, self.rows + 1) if self.kind == "chessboard" else (self.columns, self.rows)
        return squares[0] * self.square_mm, squares[1] * self.square_mm

    def describe(self) -> str:
        """One line for summaries, e.g. ``chessboard 9x6 inner corners, 25 mm squares``."""
        if self.kind == "chessboard":
            return f"chessboard {self.columns}x{self.rows} inner corners, {self.square_mm:g} mm squares"
        return (
            f"charuco {self.columns}x{self.rows} squares, {self.square_mm:g} mm squares, "
            f"{self.marker_mm:g} mm markers, {self.dictionary}"
        )

    def to_dict(self) -> dict:
        """JSON-ready dictionary; :meth:`from_dict` reads it back."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, fields: dict) -> BoardSpec:
        """Board from :meth:`to_dict`'s output; raises UserError when it is not one."""
        try:
            return cls(**fields)
        except TypeError as error:
            raise UserError(f"board record {fields!r} is not a board: {error}") from None


def _validate(spec: BoardSpec) -> None:
    if spec.kind not in BOARD_KINDS:
        raise UserError(f"unknown board kind {spec.kind!r}; use one of {', '.join(BOARD_KINDS)}")
    minimum = 2 if spec.kind == "chessboard" else 3
    if not (isinstance(spec.columns, int) and isinstance(spec.rows, int)) or min(spec.columns, spec.rows) < minimum:
        unit = "inner corners" if spec.kind == "chessboard" else "squares"
        raise UserError(f"a {spec.kind} needs at least {minimum}x{minimum} {unit}, got {spec.columns}x{spec.rows}")
    if not spec.square_mm > 0:
        raise UserError(f"--square-mm must be a positive length in millimetres, got {spec.square_mm}")
    if spec.kind == "chessboard":
        if spec.marker_mm is not None or spec.dictionary is not None:
            raise UserError("--marker-mm and --dict belong to charuco boards, not to a chessboard")
        return
    if spec.marker_mm is None or spec.dictionary is None:
        raise UserError("a charuco board needs --marker-mm (marker side, mm) and --dict (e.g. DICT_5X5_100)")
    if not 0 < spec.marker_mm < spec.square_mm:
        raise UserError(
            f"--marker-mm ({spec.marker_mm}) must be positive and smaller than --square-mm ({spec.square_mm})"
        )
    if not spec.dictionary.startswith("DICT_") or not hasattr(cv2.aruco, spec.dictionary):
        names = sorted(name for name in dir(cv2.aruco) if name.startswith("DICT_"))
        raise UserError(f"unknown ArUco dictionary {spec.dictionary!r}; use one of {', '.join(names)}")
    markers_needed = spec.columns * spec.rows // 2
    markers_available = len(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, spec.dictionary)).bytesList)
    if markers_needed > markers_available:
        raise UserError(
            f"a {spec.columns}x{spec.rows} charuco board needs {markers_needed} markers but "
            f"{spec.dictionary} has {markers_available}; pick a larger dictionary"
        )


def parse_board(
    text: str, square_mm: float, marker_mm: float | None = None, dictionary: str | None = None
) -> BoardSpec:
    """Board from the command line's ``--board KIND:COLSxROWS`` and its sizes.

    Example: ``parse_board("chessboard:9x6", 25.0)``. Raises UserError on anything else.
    """
    match = re.fullmatch(r"\s*([a-z]+)\s*:\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if match is None:
        raise UserError(f"--board {text!r} is not KIND:COLSxROWS, e.g. chessboard:9x6 or charuco:11x8")
    kind, columns, rows = match.group(1), int(match.group(2)), int(match.group(3))
    return BoardSpec(kind, columns, rows, float(square_mm), marker_mm, dictionary)


def _charuco_board(spec: BoardSpec) -> cv2.aruco.CharucoBoard:
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, spec.dictionary))
    return cv2.aruco.CharucoBoard((spec.columns, spec.rows), spec.square_mm, spec.marker_mm, dictionary)


@dataclass(frozen=True)
class BoardPicture:
    """A printable image of a board and where the board's coordinates lie on it.

    Attributes:
        image: (H, W) uint8, black 0 and white 255, a white margin of one square around
            the squared area (detectors need that quiet zone).
        pixels_per_mm: image pixels per board millimetre.
        origin_px: (x, y) of board point (0, 0, 0) on the image, in pixel-edge
            coordinates (the top-left image corner is (0, 0); pixel centres lie at
            half-integers). Board point (X, Y) mm lies at ``origin_px + (X, Y) * pixels_per_mm``.
    """

    image: np.ndarray
    pixels_per_mm: float
    origin_px: tuple[float, float]


def render_board(spec: BoardSpec, pixels_per_square: int) -> BoardPicture:
    """Draw ``spec`` with ``pixels_per_square`` pixels per square side (an integer).

    Print it at 100 % scale and measure a square with a ruler: the measured size, not the
    nominal one, is what ``--square-mm`` must say.
    """
    if pixels_per_square < 8:
        raise UserError(f"a board needs at least 8 pixels per square to print, got {pixels_per_square}")
    margin = pixels_per_square
    pixels_per_mm = pixels_per_square / spec.square_mm
    if spec.kind == "chessboard":
        squares_x, squares_y = spec.columns + 1, spec.rows + 1
        cells = (np.add.outer(np.arange(squares_y), np.arange(squares_x)) % 2 == 0).astype(np.uint8)
        squares = np.kron(1 - cells, np.ones((pixels_per_square, pixels_per_square), np.uint8)) * 255
        image = cv2.copyMakeBorder(squares, margin, margin, margin, margin, cv2.BORDER_CONSTANT, value=255)
        # The board's origin is its first inner corner, one square in from the squared area.
        origin = float(margin + pixels_per_square)
        return BoardPicture(image, pixels_per_mm, (origin, origin))
    size = (spec.columns * pixels_per_square + 2 * margin, spec.rows * pixels_per_square + 2 * margin)
    image = _charuco_board(spec).generateImage(size, marginSize=margin)
    # ChArUco board coordinates start at the outer corner of the squared area.
    return BoardPicture(image, pixels_per_mm, (float(margin), float(margin)))


@dataclass(frozen=True)
class BoardDetection:
    """The board corners found in one view.

    Attributes:
        image_points: (N, 2) float32, pixels, image frame.
        object_points: (N, 3) float32, millimetres, board frame (z = 0).
        corner_ids: (N,) int32, index of each corner on the board (0 .. corner_count - 1),
            so detections of the same board can be compared corner by corner.
    """

    image_points: np.ndarray
    object_points: np.ndarray
    corner_ids: np.ndarray


class BoardDetector:
    """Finds one board in grey images; build it once per board and reuse it."""

    def __init__(self, spec: BoardSpec) -> None:
        self.spec = spec
        if spec.kind == "chessboard":
            grid = np.mgrid[0 : spec.columns, 0 : spec.rows].T.reshape(-1, 2) * spec.square_mm
            self._object_points = np.hstack([grid, np.zeros((len(grid), 1))]).astype(np.float32)
        else:
            self._board = _charuco_board(spec)
            self._charuco = cv2.aruco.CharucoDetector(self._board)
            self._object_points = np.asarray(self._board.getChessboardCorners(), np.float32).reshape(-1, 3)

    def _refine(self, gray: np.ndarray, corners: np.ndarray) -> np.ndarray:
        """cornerSubPix with the widest window that sees no other edge, (N, 2) float32.

        A chessboard corner's window may span a quarter of the corner spacing; a ChArUco
        corner's must stop short of the markers, 0.8 of the gap between square and
        marker (on rendered boards this beats CharucoDetector's own refinement 2-3x).
        """
        spacing = float(pdist(corners.reshape(-1, 2)).min())
        if self.spec.kind == "chessboard":
            half = 0.25 * spacing
        else:
            half = 0.8 * spacing * (self.spec.square_mm - self.spec.marker_mm) / (2 * self.spec.square_mm)
        window = int(np.clip(round(half), 2, 15))
        refined = cv2.cornerSubPix(
            gray, corners.reshape(-1, 1, 2).astype(np.float32), (window, window), (-1, -1), _SUBPIX_CRITERIA
        )
        return refined.reshape(-1, 2)

    def detect(self, gray: np.ndarray) -> BoardDetection | None:
        """Board corners in ``gray`` ((H, W) uint8), or None when no usable board is seen."""
        if gray.ndim != 2 or gray.dtype != np.uint8:
            raise ValueError(f"detect() takes an (H, W) uint8 image, got {gray.shape} {gray.dtype}")
        if self.spec.kind == "chessboard":
            corners = _find_chessboard(gray, (self.spec.columns, self.spec.rows))
            if corners is None:
                return None
            ids = np.arange(self.spec.corner_count, dtype=np.int32)
            ordered = canonical_chessboard_order(gray, corners, self.spec.columns, self.spec.rows)
            return BoardDetection(self._refine(gray, ordered), self._object_points, ids)
        corners, ids, _, _ = self._charuco.detectBoard(gray)
        if ids is None or len(ids) < MIN_CHARUCO_CORNERS or self._board.checkCharucoCornersCollinear(ids):
            return None
        ids = ids.reshape(-1).astype(np.int32)
        return BoardDetection(self._refine(gray, corners), self._object_points[ids], ids)


def _find_chessboard(gray: np.ndarray, pattern: tuple[int, int]) -> np.ndarray | None:
    """(N, 2) float32 corners, pixels, from the first of :data:`CHESSBOARD_ATTEMPTS` that finds
    the board (``pattern`` = (columns, rows) inner corners), or None when none does."""
    for detector, flags in CHESSBOARD_ATTEMPTS:
        find = cv2.findChessboardCornersSB if detector == "SB" else cv2.findChessboardCorners
        found, corners = find(gray, pattern, flags=flags)
        if found:
            return corners.reshape(-1, 2)
    return None


def _first_cell_is_dark(gray: np.ndarray, grid: np.ndarray) -> bool:
    """Whether the squares of the first square's colour (cells (i, j) with i + j even) are
    darker than the others; ``grid`` is (rows, columns, 2) corners, pixels."""
    centres = (grid[:-1, :-1] + grid[1:, :-1] + grid[:-1, 1:] + grid[1:, 1:]) / 4
    height, width = gray.shape
    xs = np.clip(np.rint(centres[..., 0]).astype(int), 0, width - 1)
    ys = np.clip(np.rint(centres[..., 1]).astype(int), 0, height - 1)
    levels = cv2.blur(gray, (3, 3))[ys, xs].astype(np.float64)
    even = np.add.outer(np.arange(levels.shape[0]), np.arange(levels.shape[1])) % 2 == 0
    return bool(levels[even].mean() < levels[~even].mean())


def canonical_chessboard_order(gray: np.ndarray, corners: np.ndarray, columns: int, rows: int) -> np.ndarray:
    """The detected corners renumbered in the order of the printed board's object points.

    OpenCV's detectors return the grid row by row, but starting from either end (SB and
    the classic detector often disagree on the same photo), possibly mirrored. The
    canonical order, as :func:`render_board` draws it: seen from the front, the board's
    x axis (along a row) turned clockwise gives its y axis (down the columns), and the
    square between the first four corners is black. When the board looks the same turned
    half round (columns + rows even) or a quarter round (square boards), the candidate
    whose first corner lies nearest the image's top-left corner is taken.

    Args:
        gray: (H, W) uint8, the image the corners were found in.
        corners: (columns * rows, 2) corners, pixels, row by row.

    Returns:
        (columns * rows, 2) float32, the same corners in canonical order.
    """
    grid = np.asarray(corners, np.float32).reshape(rows, columns, 2)
    along_x = (grid[:, -1] - grid[:, 0]).mean(axis=0)
    along_y = (grid[-1] - grid[0]).mean(axis=0)
    if along_x[0] * along_y[1] - along_x[1] * along_y[0] < 0:  # mirrored: the y axis turns the other way
        grid = grid[::-1]
    turns = (0, 1, 2, 3) if columns == rows else (0, 2)
    candidates = [np.rot90(grid, turn) for turn in turns]
    best = min(candidates, key=lambda g: (not _first_cell_is_dark(gray, g), float(g[0, 0].sum())))
    return np.ascontiguousarray(best.reshape(-1, 2))
