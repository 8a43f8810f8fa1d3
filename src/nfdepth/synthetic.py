"""Exactly anti-aliased synthetic scenes: the paper's pyramid (section 3.2, 3.3.1).

(At the end of the module, a scene of another kind: a textured plane seen by
a calibrated row of cameras that is not rectified, :func:`calibrated_plane_row`,
for :mod:`nfdepth.rectify`; its texture is evaluated exactly at each pixel's
ray, not area-averaged.)

A scene is a convex polyhedron with one constant intensity per face, seen by
a pinhole camera (``nfdepth.camera.PinholeCamera``) over a constant
background. Both the object and the camera move rigidly over time.

Rendering is *exact*: each pixel holds the area-average of the continuous
image over its unit square (pixel ``(r, c)`` covers columns ``c-0.5 .. c+0.5``
and rows ``r-0.5 .. r+0.5``). For a convex solid the faces turned toward the
camera project to convex polygons that tile the silhouette without overlap,
so::

    image = background + sum_f (intensity_f - background) * coverage_f

where ``coverage_f`` is the exact area of the projected face inside each
pixel, computed in closed form with Green's theorem (see
:func:`polygon_coverage`). There is no supersampling, so sub-pixel edge
displacements (0.1 px in the paper's experiments) are rendered faithfully.

Coordinates and signs follow docs/how-it-works.md, "Conventions": camera frame X right, Y down,
Z forward; ``col = cx + f X/Z``, ``row = cy + f Y/Z``; ``(V, Omega)`` is the
motion of the scene relative to the camera, ``dP/dt = V + Omega x P``.

World coordinates are those of the reference ("stationary") camera at
``t = 0``: a camera with no motion sits at the origin with its axes along the
world axes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from ._validate import as_vector3, check_finite, check_frame_size, check_int, check_nonnegative_finite, check_positive_finite, check_shape_rows_cols, float_dtype
from .camera import PinholeCamera, RigidMotion

__all__ = [
    "BACKGROUND_INTENSITY",
    "PAPER_EXPERIMENTS",
    "PAPER_FOCAL_PX",
    "PAPER_MOVING_CAMERA_VELOCITY",
    "PYRAMID_FACE_INTENSITIES",
    "CalibratedRowScene",
    "CameraMotion",
    "ConvexPolyhedron",
    "DynamicScene",
    "ObjectMotion",
    "PaperExperiment",
    "Rendering",
    "StaticScene",
    "VideoScene",
    "calibrated_plane_row",
    "dynamic_sequence",
    "example_calibrated_cameras",
    "paper_camera",
    "paper_dynamic_sequence",
    "paper_pyramid",
    "paper_static_sequence",
    "points_in_camera_frame",
    "polygon_coverage",
    "relative_motion",
    "render",
    "static_sequence",
    "surface_depth_at",
    "video_sequence",
]

#: Background intensity of the paper's synthetic images.
BACKGROUND_INTENSITY = 255.0

#: Focal length of the paper's synthetic cameras, in pixels.
PAPER_FOCAL_PX = 100.0

#: Velocity of the paper's moving camera (units per unit time, world frame).
PAPER_MOVING_CAMERA_VELOCITY = (2.0, 0.0, 0.0)

#: Intensity of each side face of :func:`paper_pyramid`, keyed by the
#: direction of the face's outward normal (image side it appears on). The
#: paper gives the four values but not their placement; this one is ours.
PYRAMID_FACE_INTENSITIES = {
    "-Y (top of the image)": 50.0,
    "+X (right)": 100.0,
    "+Y (bottom)": 150.0,
    "-X (left)": 200.0,
}


# ---------------------------------------------------------------------------
# Validation helpers (private)
# ---------------------------------------------------------------------------


def _check_time(name: str, value) -> float:
    return check_finite(name, value)


_MAX_NOISE_STD = 1e6  # grey levels: the renders span 0-255; far more would only overflow float32 downstream


def _check_noise(noise_std, rng) -> float:
    std = check_nonnegative_finite("noise_std", noise_std)
    if std > _MAX_NOISE_STD:
        msg = f"noise_std = {std:g} grey levels is beyond any image: expected at most {_MAX_NOISE_STD:g} (the renders span 0-255)"
        raise ValueError(msg)
    if std > 0 and rng is None:
        msg = f"noise_std={std} > 0 needs rng, a numpy.random.Generator (e.g. numpy.random.default_rng(0)); got rng=None"
        raise ValueError(msg)
    if rng is not None and not isinstance(rng, np.random.Generator):
        msg = f"rng must be a numpy.random.Generator, got {type(rng).__name__}"
        raise TypeError(msg)
    return std


def _check_camera(camera) -> PinholeCamera:
    if not isinstance(camera, PinholeCamera):
        msg = f"camera must be a nfdepth.camera.PinholeCamera, got {type(camera).__name__}"
        raise TypeError(msg)
    return camera


def _check_type(name: str, value, cls, *, allow_none: bool = True):
    if value is None and allow_none:
        return value
    if not isinstance(value, cls):
        msg = f"{name} must be a {cls.__name__}{' or None' if allow_none else ''}, got {type(value).__name__}"
        raise TypeError(msg)
    return value


# ---------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------


def _newell_normal(points: np.ndarray) -> np.ndarray:
    """Area-weighted normal of a polygon (Newell's method), right-hand rule."""
    nxt = np.roll(points, -1, axis=0)
    return 0.5 * np.cross(points, nxt).sum(axis=0)


@dataclass(frozen=True, eq=False)
class ConvexPolyhedron:
    """Convex solid with one constant intensity per planar face.

    Parameters
    ----------
    vertices : array_like, shape (N, 3)
        Vertex positions in object (world) coordinates, at time 0.
    faces : sequence of sequences of int
        One tuple of vertex indices per face; each face must be a planar
        convex polygon. Faces whose vertex order gives an *inward* normal by
        the right-hand rule are reversed, so that after construction every
        face's normal (right-hand rule) points out of the solid.
    intensities : array_like, shape (len(faces),)
        Intensity of each face (any linear unit). A face never turned toward
        the camera (e.g. the pyramid's base) may hold any value.

    Raises
    ------
    ValueError
        If a face is degenerate, not planar or not convex, or if the solid
        is not convex (a vertex lies outside a face plane).
    """

    vertices: np.ndarray
    faces: tuple
    intensities: np.ndarray
    normals: np.ndarray = field(init=False, repr=False)
    offsets: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        try:
            verts = np.array(self.vertices, dtype=float)
        except (TypeError, ValueError):
            msg = f"vertices must be an (N, 3) array of numbers, got {self.vertices!r}"
            raise TypeError(msg) from None
        if verts.ndim != 2 or verts.shape[1] != 3 or verts.shape[0] < 4:
            msg = f"vertices must have shape (N, 3) with N >= 4, got shape {verts.shape}"
            raise ValueError(msg)
        if not np.all(np.isfinite(verts)):
            msg = "vertices must be finite"
            raise ValueError(msg)
        n = verts.shape[0]
        try:
            faces = [tuple(int(i) for i in face) for face in self.faces]
        except (TypeError, ValueError):
            msg = f"faces must be a sequence of sequences of vertex indices, got {self.faces!r}"
            raise TypeError(msg) from None
        if len(faces) < 4:
            msg = f"faces must hold at least 4 faces for a closed solid, got {len(faces)}"
            raise ValueError(msg)
        try:
            intens = np.array(self.intensities, dtype=float)
        except (TypeError, ValueError):
            msg = f"intensities must be numbers, got {self.intensities!r}"
            raise TypeError(msg) from None
        if intens.shape != (len(faces),):
            msg = f"intensities must have shape ({len(faces)},) (one per face), got shape {intens.shape}"
            raise ValueError(msg)
        if not np.all(np.isfinite(intens)):
            msg = f"intensities must be finite, got {intens.tolist()}"
            raise ValueError(msg)

        scale = float(np.max(np.ptp(verts, axis=0)))
        if scale <= 0:
            msg = "vertices must not all coincide"
            raise ValueError(msg)
        tol = 1e-9 * scale
        centroid = verts.mean(axis=0)
        fixed, normals, offsets = [], [], []
        for k, face in enumerate(faces):
            if len(face) < 3 or len(set(face)) != len(face):
                msg = f"faces[{k}] must list at least 3 distinct vertex indices, got {face}"
                raise ValueError(msg)
            if min(face) < 0 or max(face) >= n:
                msg = f"faces[{k}] has a vertex index outside 0..{n - 1}: {face}"
                raise ValueError(msg)
            pts = verts[list(face)]
            normal = _newell_normal(pts)
            norm = float(np.linalg.norm(normal))
            if norm <= tol * scale:
                msg = f"faces[{k}] {face} is degenerate (zero area)"
                raise ValueError(msg)
            unit = normal / norm
            dist = (pts - pts.mean(axis=0)) @ unit
            if np.max(np.abs(dist)) > tol:
                msg = f"faces[{k}] {face} is not planar (a vertex is {np.max(np.abs(dist)):.3g} off its plane)"
                raise ValueError(msg)
            turns = np.cross(np.roll(pts, -1, axis=0) - pts, np.roll(pts, -2, axis=0) - np.roll(pts, -1, axis=0)) @ unit
            if np.any(turns < -tol * scale):
                msg = f"faces[{k}] {face} is not a convex polygon in the given vertex order"
                raise ValueError(msg)
            if unit @ (pts.mean(axis=0) - centroid) < 0:
                face = face[::-1]
                unit = -unit
            fixed.append(face)
            normals.append(unit)
            offsets.append(float(unit @ pts.mean(axis=0)))
        normals_arr = np.array(normals)
        offsets_arr = np.array(offsets)
        excess = verts @ normals_arr.T - offsets_arr
        if np.max(excess) > tol:
            k = int(np.argmax(np.max(excess, axis=0)))
            msg = f"the solid is not convex: a vertex lies {np.max(excess):.3g} outside the plane of faces[{k}]"
            raise ValueError(msg)
        verts.setflags(write=False)
        intens.setflags(write=False)
        normals_arr.setflags(write=False)
        offsets_arr.setflags(write=False)
        object.__setattr__(self, "vertices", verts)
        object.__setattr__(self, "faces", tuple(fixed))
        object.__setattr__(self, "intensities", intens)
        object.__setattr__(self, "normals", normals_arr)
        object.__setattr__(self, "offsets", offsets_arr)


def paper_pyramid() -> ConvexPolyhedron:
    """The paper's pyramid (section 3.2, Fig. 4).

    Base 600 x 600 in the plane ``Z = 400`` (corners ``(+-300, +-300, 400)``),
    apex ``(0, 0, 200)`` toward the camera, so the optical axis of a camera at
    the origin passes through the apex. Faces and intensities (the paper gives
    the values, not their placement; see :data:`PYRAMID_FACE_INTENSITIES`):

    ====  ========================================  =========
    face  outward normal side (image side)          intensity
    ====  ========================================  =========
    0     -Y (top of the image, rows < cy)          50
    1     +X (right, cols > cx)                     100
    2     +Y (bottom, rows > cy)                    150
    3     -X (left, cols < cx)                      200
    4     base, +Z (hidden from the camera)         255
    ====  ========================================  =========
    """
    v = np.array(
        [
            [-300.0, -300.0, 400.0],
            [300.0, -300.0, 400.0],
            [300.0, 300.0, 400.0],
            [-300.0, 300.0, 400.0],
            [0.0, 0.0, 200.0],
        ]
    )
    faces = ((4, 1, 0), (4, 2, 1), (4, 3, 2), (4, 0, 3), (0, 1, 2, 3))
    return ConvexPolyhedron(v, faces, (50.0, 100.0, 150.0, 200.0, BACKGROUND_INTENSITY))


# ---------------------------------------------------------------------------
# Motion
# ---------------------------------------------------------------------------


def _rotation_matrix(rotvec: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(rotvec).as_matrix()


@dataclass(frozen=True, eq=False)
class ObjectMotion:
    """Rigid motion of an object over time (world frame).

    ``P(t) = center + R(t * rotation_rad_per_t) (P0 - center) + t * translation_per_t``
    with ``R(theta)`` the rotation by ``|theta|`` about ``theta/|theta|``
    (right-hand rule).

    Parameters
    ----------
    rotation_rad_per_t : array_like, shape (3,)
        Angular velocity ``omega`` in radians per unit time.
    center : array_like, shape (3,)
        A point of the rotation axis, world units (at ``t = 0``).
    translation_per_t : array_like, shape (3,)
        Translational velocity ``V`` in world units per unit time.
    """

    rotation_rad_per_t: np.ndarray = field(default_factory=lambda: np.zeros(3))
    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    translation_per_t: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        for name in ("rotation_rad_per_t", "center", "translation_per_t"):
            object.__setattr__(self, name, as_vector3(name, getattr(self, name)))

    def apply(self, points, time: float) -> np.ndarray:
        """Positions at ``time`` of points given at time 0, shape ``(..., 3)``."""
        t = _check_time("time", time)
        p = np.asarray(points, dtype=float)
        rot = _rotation_matrix(t * self.rotation_rad_per_t)
        return self.center + (p - self.center) @ rot.T + t * self.translation_per_t


@dataclass(frozen=True, eq=False)
class CameraMotion:
    """Pose of a camera over time (world frame).

    Position ``c(t) = position + t * velocity_per_t``; the camera axes are the
    world axes at ``t = 0`` and rotate by ``R(t * rotation_rad_per_t)``. A
    world point maps to the camera frame as ``R(t w)^T (P - c(t))``.

    Parameters
    ----------
    position : array_like, shape (3,)
        Optical centre at ``t = 0`` (world units).
    velocity_per_t : array_like, shape (3,)
        Translational velocity ``T`` (world units per unit time).
    rotation_rad_per_t : array_like, shape (3,)
        Angular velocity of the camera axes (radians per unit time).
    """

    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    velocity_per_t: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation_rad_per_t: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        for name in ("position", "velocity_per_t", "rotation_rad_per_t"):
            object.__setattr__(self, name, as_vector3(name, getattr(self, name)))

    def position_at(self, time: float) -> np.ndarray:
        """Optical centre at ``time`` (world units)."""
        return self.position + _check_time("time", time) * self.velocity_per_t

    def rotation_at(self, time: float) -> np.ndarray:
        """Camera-to-world rotation matrix at ``time``."""
        return _rotation_matrix(_check_time("time", time) * self.rotation_rad_per_t)


_STILL_OBJECT = ObjectMotion()
_STILL_CAMERA = CameraMotion()


def points_in_camera_frame(points, *, object_motion=None, camera_motion=None, time=0.0) -> np.ndarray:
    """Camera-frame coordinates at ``time`` of object points given at time 0.

    Parameters
    ----------
    points : array_like, shape (..., 3)
        Points in object (world) coordinates at ``t = 0``.
    object_motion : ObjectMotion, optional
        Motion of the object (default: still).
    camera_motion : CameraMotion, optional
        Pose of the camera (default: at the origin, still).
    time : float
        Time in the same unit as the velocities.

    Returns
    -------
    ndarray, shape (..., 3)
        ``R_cam(t)^T (P_world(t) - c(t))``.
    """
    om = _check_type("object_motion", object_motion, ObjectMotion) or _STILL_OBJECT
    cm = _check_type("camera_motion", camera_motion, CameraMotion) or _STILL_CAMERA
    t = _check_time("time", time)
    p = np.asarray(points, dtype=float)
    if p.shape[-1:] != (3,):
        msg = f"points must have shape (..., 3), got {p.shape}"
        raise ValueError(msg)
    world = om.apply(p, t)
    # row-vector form of R^T (P - c): (P - c) @ R
    return (world - cm.position_at(t)) @ cm.rotation_at(t)


def relative_motion(object_motion=None, camera_motion=None, *, time=0.0) -> RigidMotion:
    """Instantaneous motion of the object relative to the camera (camera frame).

    At ``t = 0`` (camera axes = world axes, centre ``c0``) this is exactly::

        RigidMotion.about_center(rotation=w, center=center - c0, translation=V)
            - RigidMotion(translation=T, rotation=w_cam)

    i.e. ``V_rel = V - w x (center - c0) - T`` and ``Omega_rel = w - w_cam``,
    so that camera-frame points move as ``dP/dt = V_rel + Omega_rel x P``.
    At other times the same quantities are taken about the current centres
    and rotated into the current camera frame.

    Parameters
    ----------
    object_motion : ObjectMotion, optional
        Motion of the object (default: still).
    camera_motion : CameraMotion, optional
        Pose of the camera (default: at the origin, still).
    time : float, keyword-only
        Instant at which the motion is taken (default 0).

    Returns
    -------
    nfdepth.camera.RigidMotion
    """
    om = _check_type("object_motion", object_motion, ObjectMotion) or _STILL_OBJECT
    cm = _check_type("camera_motion", camera_motion, CameraMotion) or _STILL_CAMERA
    t = _check_time("time", time)
    w, v = om.rotation_rad_per_t, om.translation_per_t
    center_t = om.center + t * v  # the rotation axis travels with the translation
    c_t = cm.position_at(t)
    rot = cm.rotation_at(t)
    trans = v - np.cross(w, center_t - c_t) - cm.velocity_per_t
    omega = w - cm.rotation_rad_per_t
    return RigidMotion(trans @ rot, omega @ rot)  # R^T x as row vectors


# ---------------------------------------------------------------------------
# Exact pixel coverage of a polygon
# ---------------------------------------------------------------------------

_CHUNK_ELEMENTS = 1 << 21


def _coverage_rows(xa, ya, xb, yb, rows, cols) -> np.ndarray:
    """``sum over edges of  int g(y) dH(x)`` for the pixel boxes rows x cols.

    Edge arrays have shape (E,); returns shape (len(rows), len(cols)).
    Each edge's x-range, clipped to a column, is split where the line crosses
    the row's two boundaries; ``g`` is linear on each piece, so the midpoint
    rule is exact there.
    """
    e = xa.shape[0]
    xa = xa[:, None, None]
    ya = ya[:, None, None]
    dx = (xb - xa[:, 0, 0])[:, None, None]
    dy = (yb - ya[:, 0, 0])[:, None, None]
    x0 = (cols - 0.5)[None, None, :]
    x1 = (cols + 0.5)[None, None, :]
    y0 = (rows - 0.5)[None, :, None]
    u = np.clip(xa, x0, x1)
    w = np.clip(xa + dx, x0, x1)
    lo = np.minimum(u, w)
    hi = np.maximum(u, w)
    vertical = dx == 0
    slope = np.where(vertical, 0.0, dy / np.where(vertical, 1.0, dx))
    crossing = (dy != 0) & ~vertical
    inv = np.where(crossing, dx / np.where(crossing, dy, 1.0), 0.0)
    far = np.where(crossing, 0.0, -np.inf)  # no crossing: collapse to lo
    c0 = np.clip(xa + (y0 - ya) * inv + far, lo, hi)
    c1 = np.clip(xa + (y0 + 1.0 - ya) * inv + far, lo, hi)
    m1 = np.minimum(c0, c1)
    m2 = np.maximum(c0, c1)
    total = np.zeros((e, rows.size, cols.size))
    for a, b in ((lo, m1), (m1, m2), (m2, hi)):
        mid = 0.5 * (a + b)
        g = np.clip(ya + (mid - xa) * slope - y0, 0.0, 1.0)
        total += (b - a) * g
    return (np.sign(dx) * total).sum(axis=0)


def _coverage_block(vertices_px: np.ndarray, shape: tuple[int, int]):
    """Exact coverage of a polygon over its bounding box within the image.

    Returns ``(row0, col0, block)`` or ``None`` when the polygon misses the
    image.
    """
    cols_v = vertices_px[:, 0]
    rows_v = vertices_px[:, 1]
    h, w = shape
    r0 = max(int(np.floor(rows_v.min() + 0.5)), 0)
    r1 = min(int(np.ceil(rows_v.max() - 0.5)), h - 1)
    c0 = max(int(np.floor(cols_v.min() + 0.5)), 0)
    c1 = min(int(np.ceil(cols_v.max() - 0.5)), w - 1)
    if r1 < r0 or c1 < c0:
        return None
    # work relative to a local origin for accuracy
    oc, orow = float(c0), float(r0)
    xs = cols_v - oc
    ys = rows_v - orow
    signed = 0.5 * np.sum(xs * np.roll(ys, -1) - np.roll(xs, -1) * ys)
    if signed == 0:
        return None
    xa, ya = xs, ys
    xb, yb = np.roll(xs, -1), np.roll(ys, -1)
    cols = np.arange(c1 - c0 + 1, dtype=float)
    rows = np.arange(r1 - r0 + 1, dtype=float)
    per_chunk = max(1, _CHUNK_ELEMENTS // (xa.size * cols.size))
    block = np.empty((rows.size, cols.size))
    for start in range(0, rows.size, per_chunk):
        sl = slice(start, start + per_chunk)
        block[sl] = _coverage_rows(xa, ya, xb, yb, rows[sl], cols)
    # Green: area(P n box) = -(int_dP g dH) for a positively oriented P
    block *= -np.sign(signed)
    return r0, c0, block


def polygon_coverage(vertices_px, shape) -> np.ndarray:
    """Exact area of a polygon inside each pixel.

    Pixel ``(r, c)`` is the unit square ``[c-0.5, c+0.5] x [r-0.5, r+0.5]``.
    With ``H(x) = clamp(x, x0, x1)`` and ``g(y) = clamp(y, y0, y1) - y0`` for
    a pixel box ``[x0, x1] x [y0, y1]``, Green's theorem gives
    ``area(P n box) = -+ closed_integral_{dP} g(y) dH(x)`` (sign by the
    polygon's orientation). Each edge contributes the integral of the
    piecewise-linear ``g(y(x))`` over its x-range clipped to the column,
    evaluated exactly by splitting it where the edge crosses ``y0`` and
    ``y1``. The result is exact up to floating-point rounding and the
    computation is vectorised over the polygon's bounding box.

    Parameters
    ----------
    vertices_px : array_like, shape (M, 2)
        Polygon vertices as ``(col, row)`` pixel coordinates, in either
        orientation. Any simple (non-self-intersecting) polygon works.
    shape : tuple of int
        Image shape ``(rows, cols)``.

    Returns
    -------
    ndarray, shape ``shape``
        Covered area of each pixel, in ``[0, 1]``.
    """
    v = np.asarray(vertices_px, dtype=float)
    if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
        msg = f"vertices_px must have shape (M, 2) with M >= 3, got shape {v.shape}"
        raise ValueError(msg)
    if not np.all(np.isfinite(v)):
        msg = "vertices_px must be finite"
        raise ValueError(msg)
    h, w = check_shape_rows_cols(shape)
    out = np.zeros((h, w))
    res = _coverage_block(v, (h, w))
    if res is not None:
        r0, c0, block = res
        out[r0 : r0 + block.shape[0], c0 : c0 + block.shape[1]] = block
    return out


# ---------------------------------------------------------------------------
# Rendering
# ---------------------------------------------------------------------------


def _camera_frame_planes(polyhedron: ConvexPolyhedron, object_motion, camera_motion, time):
    verts = points_in_camera_frame(polyhedron.vertices, object_motion=object_motion, camera_motion=camera_motion, time=time)
    normals = np.array([_newell_normal(verts[list(f)]) for f in polyhedron.faces])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    offsets = np.array([normals[k] @ verts[list(f)].mean(axis=0) for k, f in enumerate(polyhedron.faces)])
    return verts, normals, offsets


def _entry_exit(normals, offsets, x, y):
    """Entry and exit depth of the rays ``(x, y, 1) * Z`` through the solid."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    entry = np.zeros(np.broadcast(x, y).shape)
    exit_ = np.full(entry.shape, np.inf)
    for n, h in zip(normals, offsets):
        nd = n[0] * x + n[1] * y + n[2]
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = h / nd
        if h < 0:  # front-facing plane: the camera is on its outer side
            entry = np.maximum(entry, np.where(nd < 0, lam, np.inf))
        else:  # back-facing (or through the camera): bounds the exit
            exit_ = np.minimum(exit_, np.where(nd > 0, lam, np.inf))
    return entry, exit_


def surface_depth_at(polyhedron, camera, rows, cols, *, object_motion=None, camera_motion=None, time=0.0) -> np.ndarray:
    """Depth ``Z`` of the solid along the rays through sub-pixel positions.

    Returns ``min(entry, exit)``: ``entry`` is the largest ray depth at which
    the ray crosses a front-facing face plane, ``exit`` the smallest at which
    it crosses a back-facing one. Inside the silhouette this is the depth of
    the visible surface. Outside it, it is the depth of the plane of the
    nearest silhouette edge's hidden face, continuous across the outline
    (for the paper's pyramid: 400 just outside the base outline). It is the
    ground truth for edge points that lie on the outline.

    Parameters
    ----------
    polyhedron : ConvexPolyhedron
    camera : nfdepth.camera.PinholeCamera
    rows, cols : array_like
        Sub-pixel positions (broadcast together).
    object_motion : ObjectMotion, optional
    camera_motion : CameraMotion, optional
    time : float, keyword-only

    Returns
    -------
    ndarray
        Depth ``Z`` (float64), ``inf`` only where no face plane bounds the ray.
    """
    _check_type("polyhedron", polyhedron, ConvexPolyhedron, allow_none=False)
    _check_camera(camera)
    x, y = camera.to_normalized(rows, cols)
    _, normals, offsets = _camera_frame_planes(polyhedron, object_motion, camera_motion, time)
    entry, exit_ = _entry_exit(normals, offsets, x, y)
    return np.minimum(entry, exit_)


@dataclass(frozen=True, eq=False)
class Rendering:
    """One rendered view.

    Attributes
    ----------
    image : ndarray, shape (H, W)
        Exactly area-averaged intensities, in the requested dtype.
    depth : ndarray, shape (H, W)
        Depth ``Z`` (float64) at pixel centres; ``inf`` where the ray misses.
    visible_faces : tuple of int
        Indices of the faces turned toward the camera.
    """

    image: np.ndarray
    depth: np.ndarray
    visible_faces: tuple


def render(
    polyhedron,
    camera,
    *,
    object_motion=None,
    camera_motion=None,
    time=0.0,
    background=BACKGROUND_INTENSITY,
    noise_std=0.0,
    rng=None,
    dtype=np.float64,
) -> Rendering:
    """Render a convex polyhedron, exactly anti-aliased.

    Parameters
    ----------
    polyhedron : ConvexPolyhedron
    camera : nfdepth.camera.PinholeCamera
    object_motion : ObjectMotion, optional
        Motion of the object (default: still).
    camera_motion : CameraMotion, optional
        Pose of the camera (default: at the origin, still).
    time : float
        Instant of the view.
    background : float
        Intensity where no face is seen (the paper: 255).
    noise_std : float
        Standard deviation of additive Gaussian noise (intensity units,
        >= 0; not clipped).
    rng : numpy.random.Generator, optional
        Required when ``noise_std > 0``.
    dtype : float32 or float64
        Dtype of ``image``.

    Returns
    -------
    Rendering

    Raises
    ------
    ValueError
        If a vertex of a face turned toward the camera is not in front of
        it (``Z <= 0``), or on bad options.
    """
    _check_type("polyhedron", polyhedron, ConvexPolyhedron, allow_none=False)
    _check_camera(camera)
    check_frame_size("camera image", camera.shape)
    std = _check_noise(noise_std, rng)
    bg = _check_time("background", background)
    dt = float_dtype(dtype)
    verts, normals, offsets = _camera_frame_planes(polyhedron, object_motion, camera_motion, time)
    shape = camera.shape
    image = np.full(shape, bg)
    visible = []
    for k, face in enumerate(polyhedron.faces):
        if not offsets[k] < 0:  # n . (P_face - camera) < 0: facing the camera
            continue
        pts = verts[list(face)]
        if np.any(pts[:, 2] <= 0):
            bad = float(pts[:, 2].min())
            msg = (
                f"face {k} of the polyhedron is turned toward the camera but has a vertex at depth Z={bad:.6g} <= 0 "
                f"(time={float(time)}); the visible part of the object must lie in front of the camera"
            )
            raise ValueError(msg)
        visible.append(k)
        rows_v, cols_v, _ = camera.project(pts)
        res = _coverage_block(np.stack([cols_v, rows_v], axis=1), shape)
        if res is None:
            continue
        r0, c0, block = res
        image[r0 : r0 + block.shape[0], c0 : c0 + block.shape[1]] += (polyhedron.intensities[k] - bg) * block
    rr, cc = np.mgrid[0 : shape[0], 0 : shape[1]]
    x, y = camera.to_normalized(rr, cc)
    entry, exit_ = _entry_exit(normals, offsets, x, y)
    depth = np.where((entry <= exit_) & (entry > 0), entry, np.inf)
    if std > 0:
        image = image + rng.normal(0.0, std, size=shape)
    return Rendering(image.astype(dt), depth, tuple(visible))


# ---------------------------------------------------------------------------
# Sequences
# ---------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class DynamicScene:
    """Dynamic stereo sequence I1..I5 (paper section 3.2, Fig. 3).

    Attributes
    ----------
    frames : ndarray, shape (5, H, W)
        I1..I5; frame ``k`` (1-based) is taken at ``times[k-1]``.
        I1, I3, I5 come from the moving camera, I2, I3, I4 from the
        stationary one; I3 (t = 0) is shared, the cameras coincide then.
    times : ndarray, shape (5,)
        ``(-2, -1, 0, 1, 2) * time_step``.
    frame_cameras : tuple of str
        ``("moving", "stationary", "both", "stationary", "moving")``.
    camera : PinholeCamera
        Intrinsics of both cameras.
    moving_camera, stationary_camera : CameraMotion
    motion_moving, motion_stationary : RigidMotion
        Scene motion relative to each camera at t = 0 (camera frame).
    relative_motion : RigidMotion
        ``motion_moving - motion_stationary`` (paper eq. 4); the object's
        own motion cancels.
    polyhedron : ConvexPolyhedron
    object_motion : ObjectMotion
    """

    frames: np.ndarray
    times: np.ndarray
    frame_cameras: tuple
    camera: PinholeCamera
    moving_camera: CameraMotion
    stationary_camera: CameraMotion
    motion_moving: RigidMotion
    motion_stationary: RigidMotion
    relative_motion: RigidMotion
    polyhedron: ConvexPolyhedron
    object_motion: ObjectMotion

    def depth_at(self, rows, cols) -> np.ndarray:
        """True depth at sub-pixel positions of I3 (see :func:`surface_depth_at`)."""
        return surface_depth_at(
            self.polyhedron, self.camera, rows, cols, object_motion=self.object_motion, camera_motion=self.stationary_camera, time=0.0
        )


@dataclass(frozen=True, eq=False)
class StaticScene:
    """Static stereo views of a still object (paper section 2.3, 3.3.1).

    Attributes
    ----------
    frames : ndarray, shape (n_views, H, W)
        View ``k`` from the camera at ``camera_positions[k]``.
    times : ndarray, shape (n_views,)
        ``k - reference_index``: the views as a sequence of unit time step.
    reference_index : int
        Index of the reference view (camera at the origin).
    camera : PinholeCamera
    camera_positions : ndarray, shape (n_views, 3)
    relative_motion : RigidMotion
        ``-step`` per unit time step (the stationary camera's flow is zero).
    polyhedron : ConvexPolyhedron
    """

    frames: np.ndarray
    times: np.ndarray
    reference_index: int
    camera: PinholeCamera
    camera_positions: np.ndarray
    relative_motion: RigidMotion
    polyhedron: ConvexPolyhedron

    def depth_at(self, rows, cols) -> np.ndarray:
        """True depth at sub-pixel positions of the reference view."""
        return surface_depth_at(self.polyhedron, self.camera, rows, cols)


def dynamic_sequence(
    polyhedron,
    camera,
    *,
    object_motion=None,
    moving_camera_velocity,
    moving_camera_rotation_rad_per_t=(0.0, 0.0, 0.0),
    time_step=1.0,
    background=BACKGROUND_INTENSITY,
    noise_std=0.0,
    rng=None,
    dtype=np.float64,
) -> DynamicScene:
    """Render a dynamic stereo sequence I1..I5 (paper Fig. 3).

    The stationary camera sits at the origin; the moving camera passes
    through the origin at ``t = 0`` with velocity ``moving_camera_velocity``
    (and optionally rotating). Frame ``k`` (1-based) is taken at
    ``t = (k - 3) * time_step``: I1, I3, I5 by the moving camera, I2, I4 by
    the stationary one, I3 shared.

    Parameters
    ----------
    polyhedron : ConvexPolyhedron
    camera : PinholeCamera
        Intrinsics of both cameras.
    object_motion : ObjectMotion, optional
        Motion of the object (default: still).
    moving_camera_velocity : array_like, shape (3,)
        ``T`` of the moving camera, world units per unit time.
    moving_camera_rotation_rad_per_t : array_like, shape (3,)
        Angular velocity of the moving camera (default none).
    time_step : float
        Time between consecutive frames (> 0).
    background, noise_std, rng, dtype
        As in :func:`render`; independent noise per frame (I3 is one frame).

    Returns
    -------
    DynamicScene
    """
    _check_type("polyhedron", polyhedron, ConvexPolyhedron, allow_none=False)
    _check_camera(camera)
    om = _check_type("object_motion", object_motion, ObjectMotion) or ObjectMotion()
    step = check_positive_finite("time_step", time_step)
    _check_noise(noise_std, rng)
    moving = CameraMotion(
        velocity_per_t=as_vector3("moving_camera_velocity", moving_camera_velocity),
        rotation_rad_per_t=as_vector3("moving_camera_rotation_rad_per_t", moving_camera_rotation_rad_per_t),
    )
    stationary = CameraMotion()
    roles = ("moving", "stationary", "both", "stationary", "moving")
    times = (np.arange(5) - 2.0) * step
    frames = []
    for t, role in zip(times, roles):
        cam_motion = moving if role == "moving" else stationary
        frames.append(
            render(
                polyhedron,
                camera,
                object_motion=om,
                camera_motion=cam_motion,
                time=t,
                background=background,
                noise_std=noise_std,
                rng=rng,
                dtype=dtype,
            ).image
        )
    m_moving = relative_motion(om, moving)
    m_stationary = relative_motion(om, stationary)
    return DynamicScene(
        frames=np.stack(frames),
        times=times,
        frame_cameras=roles,
        camera=camera,
        moving_camera=moving,
        stationary_camera=stationary,
        motion_moving=m_moving,
        motion_stationary=m_stationary,
        relative_motion=m_moving - m_stationary,
        polyhedron=polyhedron,
        object_motion=om,
    )


def _film(polyhedron, camera, motion: CameraMotion, n: int, reference_index, **render_options):
    """``n`` frames of ``motion`` at times ``k - reference_index`` (checked to index a frame): ``(times, frames)``."""
    ref = check_int("reference_index", reference_index, 0)
    if ref >= n:
        msg = f"reference_index must be in 0..{n - 1}, got {ref}"
        raise ValueError(msg)
    _check_noise(render_options["noise_std"], render_options["rng"])
    times = np.arange(n, dtype=float) - ref
    return times, np.stack([render(polyhedron, camera, camera_motion=motion, time=t, **render_options).image for t in times])


def static_sequence(
    polyhedron,
    camera,
    *,
    n_views=3,
    camera_step=(2.0, 0.0, 0.0),
    reference_index=None,
    background=BACKGROUND_INTENSITY,
    noise_std=0.0,
    rng=None,
    dtype=np.float64,
) -> StaticScene:
    """Render views of a still object from cameras spaced along a line.

    View ``k`` is taken from ``(k - reference_index) * camera_step`` (world
    units), all cameras aligned with the world axes.

    Parameters
    ----------
    polyhedron : ConvexPolyhedron
    camera : PinholeCamera
    n_views : int
        Number of views (>= 2).
    camera_step : array_like, shape (3,)
        Displacement between neighbouring views (world units).
    reference_index : int, optional
        Reference view, default the middle one ``(n_views - 1) // 2``.
    background, noise_std, rng, dtype
        As in :func:`render`.

    Returns
    -------
    StaticScene
    """
    _check_type("polyhedron", polyhedron, ConvexPolyhedron, allow_none=False)
    _check_camera(camera)
    n = check_int("n_views", n_views, 2)
    step = as_vector3("camera_step", camera_step)
    motion = CameraMotion(velocity_per_t=step)
    ref = (n - 1) // 2 if reference_index is None else reference_index
    times, frames = _film(polyhedron, camera, motion, n, ref, background=background, noise_std=noise_std, rng=rng, dtype=dtype)
    return StaticScene(
        frames=frames,
        times=times,
        reference_index=ref,
        camera=camera,
        camera_positions=times[:, None] * step,
        relative_motion=RigidMotion.camera_translation(step),
        polyhedron=polyhedron,
    )


@dataclass(frozen=True, eq=False)
class VideoScene:
    """A video of a still object from one camera in motion (translating and turning).

    Attributes
    ----------
    frames : ndarray, shape (n_frames, H, W)
        Frame ``k`` taken at ``times[k]``.
    times : ndarray, shape (n_frames,)
        ``k - reference_index``.
    camera : PinholeCamera
    camera_motion : CameraMotion
    positions : ndarray, shape (n_frames, 3)
        Optical centre of every frame (world units).
    orientations_rad : ndarray, shape (n_frames, 3)
        Camera-to-world orientation of every frame as a rotation vector
        (``times[k] * camera_motion.rotation_rad_per_t``), as
        :func:`nfdepth.video.depth_from_video` takes it.
    polyhedron : ConvexPolyhedron
    """

    frames: np.ndarray
    times: np.ndarray
    camera: PinholeCamera
    camera_motion: CameraMotion
    positions: np.ndarray
    orientations_rad: np.ndarray
    polyhedron: ConvexPolyhedron

    def depth_at(self, frame: int, rows, cols) -> np.ndarray:
        """True depth at sub-pixel positions of frame ``frame``."""
        t = float(self.times[check_int("frame", frame, 0)])
        return surface_depth_at(self.polyhedron, self.camera, rows, cols, camera_motion=self.camera_motion, time=t)


def video_sequence(
    polyhedron,
    camera,
    *,
    camera_motion,
    n_frames=5,
    reference_index=None,
    background=BACKGROUND_INTENSITY,
    noise_std=0.0,
    rng=None,
    dtype=np.float64,
) -> VideoScene:
    """Render a video of a still object from a camera moving as ``camera_motion`` says.

    Frame ``k`` is taken at time ``k - reference_index`` (default: the
    middle frame at ``t = 0``), one unit of time per frame.

    Parameters
    ----------
    polyhedron : ConvexPolyhedron
    camera : PinholeCamera
    camera_motion : CameraMotion
        Position and orientation over time (per frame).
    n_frames : int
        Number of frames (>= 1).
    reference_index : int, optional
        The frame taken at ``t = 0``; default ``n_frames // 2``.
    background, noise_std, rng, dtype
        As in :func:`render`.

    Returns
    -------
    VideoScene
    """
    _check_type("polyhedron", polyhedron, ConvexPolyhedron, allow_none=False)
    _check_camera(camera)
    motion = _check_type("camera_motion", camera_motion, CameraMotion, allow_none=False)
    n = check_int("n_frames", n_frames, 1)
    ref = n // 2 if reference_index is None else reference_index
    times, frames = _film(polyhedron, camera, motion, n, ref, background=background, noise_std=noise_std, rng=rng, dtype=dtype)
    return VideoScene(
        frames=frames,
        times=times,
        camera=camera,
        camera_motion=motion,
        positions=np.array([motion.position_at(t) for t in times]),
        orientations_rad=times[:, None] * motion.rotation_rad_per_t,
        polyhedron=polyhedron,
    )


# ---------------------------------------------------------------------------
# The paper's experiments
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class PaperExperiment:
    """One of the paper's dynamic-stereo experiments (section 3.2, Table 1).

    Angular velocity in degrees per unit time as the paper quotes it;
    :meth:`object_motion` converts to radians.
    """

    number: int
    rotation_axis: tuple
    rotation_deg_per_t: float
    center: tuple
    translation_per_t: tuple
    paper_max_flow_rel_error: float

    def object_motion(self) -> ObjectMotion:
        """The pyramid's motion as an :class:`ObjectMotion`."""
        axis = np.asarray(self.rotation_axis, dtype=float)
        axis = axis / np.linalg.norm(axis)
        return ObjectMotion(
            rotation_rad_per_t=np.deg2rad(self.rotation_deg_per_t) * axis,
            center=self.center,
            translation_per_t=self.translation_per_t,
        )


#: The paper's experiments 1-4. Rotations are about an axis through the
#: centre of the pyramid's base (0, 0, 400); for 1-3 that is the Z axis
#: through the apex. The paper does not say where experiment 4's axis
#: passes; we use the same point.
PAPER_EXPERIMENTS = {
    1: PaperExperiment(1, (0.0, 0.0, 1.0), 0.1, (0.0, 0.0, 400.0), (0.0, 0.0, 0.0), 0.01),
    2: PaperExperiment(2, (0.0, 0.0, 1.0), 0.5, (0.0, 0.0, 400.0), (0.0, 0.0, 0.0), 0.02),
    3: PaperExperiment(3, (0.0, 0.0, 1.0), 1.0, (0.0, 0.0, 400.0), (0.0, 0.0, 0.0), 0.12),
    4: PaperExperiment(4, (1.0, 1.0, 1.0), 0.5, (0.0, 0.0, 400.0), (0.5, 1.0, 1.5), 0.05),
}


def paper_camera(*, image_size_px=200) -> PinholeCamera:
    """The paper's camera: f = 100 px, square image, principal point at the centre."""
    n = check_int("image_size_px", image_size_px, 2)
    return PinholeCamera(PAPER_FOCAL_PX, n, n)


def paper_dynamic_sequence(experiment, *, noise_std=0.0, rng=None, image_size_px=200, dtype=np.float64) -> DynamicScene:
    """The paper's dynamic sequence for experiment 1, 2, 3 or 4 (section 3.2).

    Pyramid of :func:`paper_pyramid`, f = 100 px, image
    ``image_size_px`` square (principal point at its centre, 99.5 for 200),
    moving camera at ``(2 t, 0, 0)``, stationary camera at the origin; see
    :data:`PAPER_EXPERIMENTS` and :func:`dynamic_sequence`. The relative
    motion is ``V = (-2, 0, 0)``, ``Omega = 0``.
    """
    if isinstance(experiment, bool) or not isinstance(experiment, (int, np.integer)):
        msg = f"experiment must be one of {sorted(PAPER_EXPERIMENTS)}, got {experiment!r}"
        raise TypeError(msg)
    if int(experiment) not in PAPER_EXPERIMENTS:
        msg = f"experiment must be one of {sorted(PAPER_EXPERIMENTS)}, got {experiment!r}"
        raise ValueError(msg)
    spec = PAPER_EXPERIMENTS[int(experiment)]
    return dynamic_sequence(
        paper_pyramid(),
        paper_camera(image_size_px=image_size_px),
        object_motion=spec.object_motion(),
        moving_camera_velocity=PAPER_MOVING_CAMERA_VELOCITY,
        noise_std=noise_std,
        rng=rng,
        dtype=dtype,
    )


def paper_static_sequence(*, n_views=3, baseline=2.0, noise_std=0.0, rng=None, image_size_px=200, dtype=np.float64) -> StaticScene:
    """The paper's static stereo views of the still pyramid (section 3.3.1).

    Cameras at ``X = (k - ref) * baseline`` for ``k = 0 .. n_views-1``
    (moving toward +X), reference the middle view; relative motion
    ``V = (-baseline, 0, 0)`` per view step; disparity ``f * baseline / Z``.
    """
    b = check_positive_finite("baseline", baseline)
    return static_sequence(
        paper_pyramid(),
        paper_camera(image_size_px=image_size_px),
        n_views=n_views,
        camera_step=(b, 0.0, 0.0),
        noise_std=noise_std,
        rng=rng,
        dtype=dtype,
    )


# ---------------------------------------------------------------------------
# A calibrated row of cameras that is not rectified (nfdepth.rectify)
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class CalibratedRowScene:
    """Views of a textured plane by calibrated cameras (:func:`calibrated_plane_row`).

    ``views`` (float32), ``depths`` (float64: each camera's true depth along
    its own optical axis at each of its pixels), ``cameras``
    (:class:`nfdepth.rectify.CalibratedCamera`), ``reference_index``.
    """

    views: list
    depths: list
    cameras: list
    reference_index: int


def example_calibrated_cameras(*, image_size_px=(180, 120)) -> list:
    """Three cameras 0.1 scene units apart along world X, not rectified: focal lengths of 395-411 px, their own
    principal points, turns of 0.5-1.7 degrees, lens distortion on two (``examples/calibrated_row_cameras.toml``)."""
    from .rectify import CalibratedCamera

    w, h = (int(v) for v in image_size_px)
    check_frame_size("image_size_px", (h, w))
    sx, sy = w / 180.0, h / 120.0  # the intrinsics scale with the image
    spec = [  # fx, fy, cx, cy at 180 x 120 px; x; turn (deg); distortion
        (400.0, 400.0, 92.0, 58.0, -0.1, (0.8, -1.5, 0.6), (-0.08, 0.02, 0.0, 0.0)),
        (410.0, 411.0, 89.5, 60.5, 0.0, (-0.4, 0.7, -0.3), (0.05, 0.0, 0.001, -0.001, 0.0)),
        (395.0, 395.0, 90.0, 59.0, 0.1, (0.3, 1.2, 0.9), ()),
    ]
    cams = []
    for fx, fy, cx, cy, x, turn, dist in spec:
        k = np.array([[fx * sx, 0.0, (cx + 0.5) * sx - 0.5], [0.0, fy * sy, (cy + 0.5) * sy - 0.5], [0.0, 0.0, 1.0]])
        rotation = Rotation.from_rotvec(np.radians(turn)).as_matrix()
        cams.append(CalibratedCamera(matrix=k, width_px=w, height_px=h, position=np.array([x, 0.0, 0.0]), rotation=rotation, distortion=np.array(dist)))
    return cams


def calibrated_plane_row(cameras=None, *, depth=6.0, slope=0.15, noise_std=1.0, seed=4, reference_index=1) -> CalibratedRowScene:
    """A slanted plane ``Z = depth + slope X`` (world axes) with a sum-of-sinusoids texture in world ``X, Y``.

    Each camera's pixel ray (its lens distortion undone) meets the plane at a
    point whose texture is evaluated exactly: no resampling enters the
    images or the true depths. Wavelengths 0.11-0.45 scene units (7-30 px
    for the default cameras at the default depth). ``cameras`` default
    :func:`example_calibrated_cameras`.
    """
    from ._derotation import turn_rays

    cams = example_calibrated_cameras() if cameras is None else list(cameras)
    z0 = check_positive_finite("depth", depth)
    slope = check_finite("slope", slope)
    noise = check_nonnegative_finite("noise_std", noise_std)
    reference_index = check_int("reference_index", reference_index, 0)
    if reference_index >= len(cams):
        msg = f"reference_index must index one of the {len(cams)} cameras, got {reference_index}"
        raise ValueError(msg)
    rng = np.random.default_rng(seed)
    n = 40
    wavelength = rng.uniform(0.11, 0.45, n)
    angle = rng.uniform(0.0, np.pi, n)
    ky, kx = 2 * np.pi * np.sin(angle) / wavelength, 2 * np.pi * np.cos(angle) / wavelength
    phase = rng.uniform(0.0, 2 * np.pi, n)
    noise_rng = np.random.default_rng(seed + 1)
    views, depths = [], []
    for cam in cams:
        xy = cam.rays()
        rx, ry, rz = turn_rays(cam.rotation, xy[..., 0], xy[..., 1])  # the pixel's ray in world axes
        c = cam.position
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (z0 + slope * c[0] - c[2]) / (rz - slope * rx)
        px, py = c[0] + s * rx, c[1] + s * ry  # where it meets the plane
        texture = 100.0 + 40.0 / np.sqrt(n / 2) * np.sin(ky * py[..., None] + kx * px[..., None] + phase).sum(-1)
        views.append((texture + noise_rng.normal(0.0, noise, s.shape)).astype(np.float32))
        depths.append(s)  # the ray's z in camera axes is 1: s is the depth along the optical axis
    return CalibratedRowScene(views=views, depths=depths, cameras=cams, reference_index=reference_index)
