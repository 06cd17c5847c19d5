"""A posed body's projected outline, sub-pixel, with its derivatives: the local solver's view.

The population search scores a candidate by its rasterised boundary pixels, which move in
whole pixels: its cost is flat across millimetres of shape. The local solver
(:mod:`bodyfit.fitter.fit.local_solver`) needs a cost that moves smoothly with the body,
so it reads the outline off the mesh itself:

- **Silhouette edges**: the mesh edges between a triangle facing the camera and one
  facing away. Their projections trace every contour of the body, the outer one and the
  inner ones (an arm in front of the torso) alike.
- **Visibility from the raster**: the candidate is rasterised once
  (:func:`bodyfit.kernels.rasterize`, the search's own renderer), and an edge is kept
  when the pixel of its midpoint has pixels inside and outside the rendered silhouette
  in its 3 x 3 neighbourhood: the outer outline and the holes (the gap between the
  legs). Contours inside the silhouette are left out, as the raster's boundary leaves
  them out.
- **Samples**: one per kept edge, at its midpoint, weighted by its projected length, so
  that the outline counts by its length as the boundary pixels do, however finely the
  mesh is cut there.

The samples move with the body's parameters: the shape blend is linear in the betas, the
skinning rotates each chain by its angle, the camera projects. :meth:`ViewOutline.jacobian`
is that chain of derivatives, analytic, at the samples.

Units: model frame metres (z up, -y forward); canvas pixels (column, row), OpenCV's
centre convention; angles in degrees.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import warp as wp
from scipy.spatial import cKDTree

from bodyfit import kernels
from bodyfit.fitter.fit.elbows import bend_derivative, bent, elbow_rig, wrist_rig
from bodyfit.fitter.model.body_model import POSE_NAMES, BodyModel, rest_shape
from bodyfit.kernels.body_forward import abduction_rotations, blend_skinning
from bodyfit.kernels.body_layout import POSE_SIDES
from bodyfit.kernels.raster import BACKGROUND, launch_projection, launch_raster
from bodyfit.kernels.target import visible_faces
from bodyfit.kernels.view_camera import camera_matrices

__all__ = ["MeshEdges", "OutlineSamples", "ViewOutline", "project_with_jacobian",
           "moved_camera", "posed_with_jacobian"]

#: The envelope test (:func:`_on_envelope`): neighbours within this many pixels...
_ENVELOPE_REACH_PX = 2.0
_ENVELOPE_NEIGHBOURS = 8
#: ... that stand out by more than this many pixels along a sample's normal drop it.
_ENVELOPE_SLACK_PX = 0.05
_SQUARE = cv2.getStructuringElement(cv2.MORPH_RECT, (3, 3))


@dataclasses.dataclass(frozen=True)
class MeshEdges:
    """The edges of a triangle mesh with the faces on either side.

    Attributes:
        vertices: (E, 2) int, each edge's two vertex indices.
        faces: (E, 2) int, the two faces sharing the edge (index into the mesh's faces);
            an edge of one face only (an open mesh's border) has -1 second.
    """

    vertices: np.ndarray
    faces: np.ndarray

    @classmethod
    def of(cls, faces: np.ndarray) -> "MeshEdges":
        """The edges of (F, 3) ``faces``; edges of more than two faces are left out (a
        closed mesh has none)."""
        faces = np.asarray(faces)
        pairs = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        owner = np.tile(np.arange(len(faces)), 3)
        keys = np.sort(pairs, axis=1)
        order = np.lexsort((keys[:, 1], keys[:, 0]))
        keys, owner = keys[order], owner[order]
        starts = np.flatnonzero(np.r_[True, np.any(keys[1:] != keys[:-1], axis=1)])
        counts = np.diff(np.r_[starts, len(keys)])
        single, double = starts[counts == 1], starts[counts == 2]
        first = np.r_[owner[double], owner[single]]
        second = np.r_[owner[double + 1], np.full(len(single), -1)]
        return cls(np.r_[keys[double], keys[single]], np.stack([first, second], axis=1))


@dataclasses.dataclass(frozen=True)
class OutlineSamples:
    """A body's outline in one view, one sample per visible silhouette edge.

    Attributes:
        edges: (S, 2) int, the two vertices of each sample's edge (the sample is their
            midpoint).
        points: (S, 2) float64, canvas pixels (column, row).
        lengths: (S,) float64, the edge's projected length, pixels (the sample's share of
            the outline).
        parts: (S,) int, the part (index into ``PART_NAMES``) of the edge's first vertex.
        normals: (S, 2) float64, unit normals of the projected edges, pointing out of the
            body.
    """

    edges: np.ndarray
    points: np.ndarray
    lengths: np.ndarray
    parts: np.ndarray
    normals: np.ndarray


def project_with_jacobian(camera: kernels.ViewCamera, points: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Pinhole or orthographic projection of (N, 3) model-frame points, metres: ((N, 2)
    pixels, (N, 2, 3) d pixels / d camera-frame point, pixels per metre: the derivative
    with respect to the camera's translation; times the rotation, with respect to the
    model-frame point)."""
    k, r, t = camera_matrices(camera)
    cam = points @ r.T + t
    if not camera.pinhole:
        uv = cam[:, :2] @ k[:2, :2].T + k[:2, 2]
        return uv, np.broadcast_to(np.c_[k[:2, :2], np.zeros(2)], (len(points), 2, 3)).copy()
    x, y, z = cam[:, 0], cam[:, 1], cam[:, 2]
    inv = 1.0 / z
    uv = np.stack([(k[0, 0] * x + k[0, 1] * y) * inv + k[0, 2], k[1, 1] * y * inv + k[1, 2]],
                  axis=1)
    d_cam = np.zeros((len(points), 2, 3))
    d_cam[:, 0, 0] = k[0, 0] * inv
    d_cam[:, 0, 1] = k[0, 1] * inv
    d_cam[:, 0, 2] = -(k[0, 0] * x + k[0, 1] * y) * inv * inv
    d_cam[:, 1, 1] = k[1, 1] * inv
    d_cam[:, 1, 2] = -k[1, 1] * y * inv * inv
    return uv, d_cam


def moved_camera(camera: kernels.ViewCamera, translation_m: np.ndarray) -> kernels.ViewCamera:
    """A copy of ``camera`` with (3,) ``translation_m`` metres added to its translation
    (camera frame): the camera moved by minus that much."""
    moved = kernels.ViewCamera()
    for field in ("rotation", "fx", "fy", "cx", "cy", "skew", "pinhole"):
        setattr(moved, field, getattr(camera, field))
    moved.translation = wp.vec3(*(np.array(camera.translation, np.float64)
                                  + np.asarray(translation_m, np.float64)))
    return moved


def posed_with_jacobian(model: BodyModel, betas: np.ndarray, pose_deg: np.ndarray,
                        vertices: np.ndarray, flexion_deg: float | None = None,
                        twist_deg: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Posed vertices of one body and their derivatives, float64.

    Args:
        model: the body model.
        betas: (K,) shape coefficients, standard deviations.
        pose_deg: (4,) the pose the body is posed in, degrees, ``POSE_NAMES`` order.
        vertices: (N,) int, the vertices wanted.
        flexion_deg: both elbows bent to this before the skinning
            (:mod:`bodyfit.fitter.fit.elbows`), or None (the rest pose's).
        twist_deg: (2,) the left and right hands turned by these before the elbows'
            bend, or None (the rest pose's).

    Returns:
        posed: (N, 3) metres.
        jacobian: (N, 3, K + 4 (+ 1) (+ 2)): d posed / d (betas, then the four angles,
            then the flexion when given, then the two twists when given), metres per standard
            deviation and per degree. For a fixed pose the posed vertices are linear in
            the betas (the skinning applied to the shape directions); each chain's angle
            turns its share of the vertex about its joint; the flexion turns the forearms
            before, and the twist the hands before that.
    """
    k = len(betas)
    rest, joints = rest_shape(model, np.asarray(betas)[None])
    rest = rest[0].astype(np.float64)
    joints = joints[0].astype(np.float64)
    vertex_dirs, joint_dirs = model.shape_directions(k)
    turned = []  # d rest / d (flexion, twists), as given: (N, 3) each
    if twist_deg is not None:  # the whole bodies turned: the elbow rings' centroids whole
        hands = wrist_rig(model)
        d_twist = [bend_derivative(hands, rest, twist_deg, side=side) for side in (0, 1)]
        rest = bent(hands, rest, twist_deg)
        vertex_dirs = bent(hands, vertex_dirs, twist_deg)
    if flexion_deg is None:
        rest = rest[vertices]
        dirs = vertex_dirs[:, vertices].astype(np.float64)
        if twist_deg is not None:
            turned += [d[vertices] for d in d_twist]
    else:
        rig = elbow_rig(model)  # only the wanted vertices bent (the rings' centroids whole)
        turned.append(bend_derivative(rig, rest, flexion_deg, vertices))
        if twist_deg is not None:  # the bend is linear: it maps the twists' motions too
            turned += [bent(rig, d, flexion_deg, vertices) for d in d_twist]
        rest = bent(rig, rest, flexion_deg, vertices)
        dirs = bent(rig, vertex_dirs, flexion_deg, vertices)
    dirs = dirs.transpose(1, 2, 0)  # (N, 3, K)
    rotations = abduction_rotations(np.asarray(pose_deg, np.float64)[None])[0]  # (4, 3, 3)
    weights = model.chain_weights[vertices].astype(np.float64)  # (N, 4)
    posed = blend_skinning(weights, rest[None], joints[None], rotations[None])[0]
    # d posed / d beta_k: the skinning of the shape direction (vertex and joint parts)
    jdirs = joint_dirs.astype(np.float64).transpose(1, 2, 0)  # (4, 3, K)
    d_betas = dirs * (1.0 - weights.sum(axis=1))[:, None, None]
    for c in range(len(POSE_NAMES)):
        moved = np.einsum("ij,njk->nik", rotations[c], dirs - jdirs[c]) + jdirs[c]
        d_betas += weights[:, c, None, None] * moved
    # d posed / d angle_c: R_c'(theta) (rest - j_c), theta = side * radians(angle)
    theta = np.deg2rad(np.asarray(pose_deg, np.float64)) * POSE_SIDES
    d_angles = np.zeros((len(vertices), 3, len(POSE_NAMES)))
    for c in range(len(POSE_NAMES)):
        cos, sin = np.cos(theta[c]), np.sin(theta[c])
        d_rot = np.array([[-sin, 0, -cos], [0, 0, 0], [cos, 0, -sin]]) \
            * POSE_SIDES[c] * np.pi / 180.0
        d_angles[:, :, c] = weights[:, c, None] * ((rest - joints[c]) @ d_rot.T)
    columns = [d_betas, d_angles]
    for d_rest in turned:  # the skinning is linear in the rest body, joints held
        skinned = d_rest * (1.0 - weights.sum(axis=1))[:, None]
        for c in range(len(POSE_NAMES)):
            skinned += weights[:, c, None] * (d_rest @ rotations[c].T)
        columns.append(skinned[:, :, None])
    return posed.astype(np.float64), np.concatenate(columns, axis=2)


def _on_envelope(points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(S,) bool: the samples (points (S, 2), outward unit normals (S, 2), pixels) that no
    other sample beside them (within ``_ENVELOPE_REACH_PX``) lies outside of by more than
    ``_ENVELOPE_SLACK_PX`` along their normal: the outline's outer envelope. Where the
    front- and back-facing triangles of a polygonal mesh meet in a zig-zag, some
    silhouette edges lie a fraction of a pixel inside the outline; kept, they read the
    body smaller than it is, and the fit answers with a body too large (in girths, about
    1 mm per 0.1 px)."""
    if len(points) < 2:
        return np.ones(len(points), bool)
    count = min(_ENVELOPE_NEIGHBOURS + 1, len(points))
    distance, index = cKDTree(points).query(points, k=count,
                                            distance_upper_bound=_ENVELOPE_REACH_PX)
    found = np.isfinite(distance)
    index = np.where(found, index, 0)
    offsets = np.einsum("snk,sk->sn", points[index] - points[:, None], normals)
    return ~np.any(found & (offsets > _ENVELOPE_SLACK_PX), axis=1)


class ViewOutline:
    """The outline of bodies in one view of the person (its camera, canvas and parts).

    Args:
        model: the body model the bodies are of (the fit's render model).
        view: the kernels' target of the view (camera, canvas size, visible parts, fixed
            pose angles).
    """

    def __init__(self, model: BodyModel, view: kernels.ViewTarget):
        self.model = model
        self.view = view
        self.faces, face_parts = visible_faces(model.faces, model.face_parts,
                                               view.visible_parts)
        self.edges = MeshEdges.of(self.faces)
        # the raster's inputs and buffers on the CPU, made once: every iteration renders
        self._raster_faces = wp.array(self.faces.astype(np.int32), dtype=wp.vec3i, device="cpu")
        self._raster_parts = wp.array(face_parts.astype(np.int32), dtype=wp.int32, device="cpu")
        self._screen = wp.empty((1, model.num_vertices), dtype=wp.vec3, device="cpu")
        self._keys = wp.empty((1, view.height, view.width), dtype=wp.int32, device="cpu")

    def samples(self, posed: np.ndarray, camera: kernels.ViewCamera) -> OutlineSamples:
        """The outline of a body posed as this view renders it, (V, 3) metres, seen by
        ``camera`` (the view's, or :func:`moved_camera` of it)."""
        edges, ends = self._silhouette_edges(posed, camera)
        points = ends[:, :2].mean(axis=1)
        inside = self._inside(posed, camera)
        near = cv2.dilate(inside, _SQUARE) != cv2.erode(inside, _SQUARE)
        kept = near[self._pixel(points)]
        points, ends, edges = points[kept], ends[kept], edges[kept]
        step = ends[:, 1] - ends[:, 0]
        lengths = np.hypot(step[:, 0], step[:, 1])
        normals = np.stack([-step[:, 1], step[:, 0]], axis=1) / np.maximum(lengths, 1e-9)[:, None]
        inward = np.einsum("si,si->s", normals, ends[:, 2] - points) > 0
        normals[inward] *= -1.0
        # a pixel beyond the edge covered: the edge is hidden (by an arm before the torso)
        outer = ~inside[self._pixel(points + normals)].astype(bool) & _on_envelope(points, normals)
        return OutlineSamples(edges[outer], points[outer], lengths[outer],
                              self.model.vertex_parts[edges[outer, 0]].astype(int),
                              normals[outer])

    def _silhouette_edges(self, posed: np.ndarray, camera: kernels.ViewCamera
                          ) -> tuple[np.ndarray, np.ndarray]:
        """The edges between a face turned to the camera and one turned away: their (E, 2)
        vertices and (E, 3, 2) pixels of their two ends and of a third vertex of a face at
        the edge (both faces of a fold lie on the edge's inner side)."""
        uv, _ = project_with_jacobian(camera, posed[self.faces.ravel()])
        tri = uv.reshape(-1, 3, 2)
        area = ((tri[:, 1, 0] - tri[:, 0, 0]) * (tri[:, 2, 1] - tri[:, 0, 1])
                - (tri[:, 2, 0] - tri[:, 0, 0]) * (tri[:, 1, 1] - tri[:, 0, 1]))
        facing = area > 0
        first, second = self.edges.faces[:, 0], self.edges.faces[:, 1]
        silhouette = np.where(second < 0, True, facing[first] != facing[np.maximum(second, 0)])
        edges = self.edges.vertices[silhouette]
        third = self.faces[first[silhouette]].sum(axis=1) - edges.sum(axis=1)
        ends, _ = project_with_jacobian(camera, posed[np.c_[edges, third].ravel()])
        return edges, ends.reshape(-1, 3, 2)

    def _inside(self, posed: np.ndarray, camera: kernels.ViewCamera) -> np.ndarray:
        """(H, W) uint8: 1 where the body's raster covers the pixel (the search's renderer,
        :func:`bodyfit.kernels.rasterize`'s kernels on buffers kept from call to call)."""
        vertices = wp.array(posed[None].astype(np.float32), dtype=wp.vec3, device="cpu")
        launch_projection(camera, vertices, self._screen)
        launch_raster(camera, self._screen, self._raster_faces, self._raster_parts, self._keys)
        return (self._keys.numpy()[0] != BACKGROUND).astype(np.uint8)

    def _pixel(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rows, columns) of the canvas pixels nearest (N, 2) points, clipped to it."""
        col = np.clip(np.rint(points[:, 0]).astype(int), 0, self.view.width - 1)
        row = np.clip(np.rint(points[:, 1]).astype(int), 0, self.view.height - 1)
        return row, col

    def jacobian(self, samples: OutlineSamples, betas: np.ndarray, pose_deg: np.ndarray,
                 camera: kernels.ViewCamera, flexion_deg: float | None = None,
                 twist_deg: np.ndarray | None = None) -> np.ndarray:
        """(S, 2, K + 4 (+ 1) (+ 2) + 3) d sample pixels / d (betas, the four angles, the
        elbows' flexion when given, the hands' twists when given, the camera's
        translation) of a body (betas (K,), its own pose (4,) degrees, its elbows' flexion
        and hands' twist or None) seen by ``camera``: the view's fixed angles (the side
        view's arms) do not move with the body's, so their columns are zero."""
        view_pose = self.view.view_pose(np.asarray(pose_deg, np.float64)[None])[0]
        wanted, index = np.unique(samples.edges.ravel(), return_inverse=True)
        posed, d_posed = posed_with_jacobian(self.model, betas, view_pose, wanted,
                                             flexion_deg, twist_deg)
        _, d_camera = project_with_jacobian(camera, posed)
        rotation = camera_matrices(camera)[1]
        d = np.concatenate([np.einsum("nij,njk->nik", d_camera @ rotation, d_posed), d_camera],
                           axis=2)
        d = d[index].reshape(len(samples.edges), 2, 2, -1).mean(axis=1)
        for column, _ in self.view.fixed_pose_deg:
            d[:, :, len(betas) + column] = 0.0
        return d
