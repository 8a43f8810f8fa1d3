"""Pinhole camera and rigid-motion model (paper eq. 1, 3, 4).

Conventions (see ``docs/how-it-works.md``, "Conventions"): image arrays are ``I[row, col]``;
``col`` grows to the right, ``row`` downward; camera frame X right, Y down,
Z forward. A point ``(X, Y, Z)`` projects to normalised ``x = X/Z``,
``y = Y/Z`` and to pixel ``col = cx + f x``, ``row = cy + f y``.

``(V, Omega)`` is the motion of the *scene relative to the camera*, in camera
coordinates: a scene point moves as ``dP/dt = V + Omega x P``. A camera that
translates by ``T`` per unit time through a static scene sees ``V = -T``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._validate import (
    UNIT_SCALE_RANGE,
    as_real,
    as_vector3,
    check_finite,
    check_image_size,
    check_positive_finite,
    check_within,
)

__all__ = [
    "PinholeCamera",
    "RigidMotion",
    "image_flow",
    "image_flow_px",
    "normal_flow_px",
    "relative_normal_flow_coefficients",
]

#: A principal point may lie at most this many image sizes (the larger of width
#: and height) from the image centre, and at least :data:`PRINCIPAL_POINT_MIN_REACH_PX`
#: px: lens shifts and crops of any real sensor stay far inside it, so a value
#: beyond is in the wrong unit or a typo (and overflows the flow arithmetic).
PRINCIPAL_POINT_REACH_SIZES = 100

#: The smallest reach of the principal point, in px (a small crop of a large sensor).
PRINCIPAL_POINT_MIN_REACH_PX = 1e6


def _principal_point_reach(width_px: int, height_px: int) -> float:
    """Largest distance (px) of the principal point from the image centre :class:`PinholeCamera` accepts."""
    return max(PRINCIPAL_POINT_MIN_REACH_PX, PRINCIPAL_POINT_REACH_SIZES * float(max(width_px, height_px)))


def _principal_point_expected(centre: float, reach: float) -> str:
    """What a principal point coordinate is expected to be (the end of the messages refusing one)."""
    return (
        f"a principal point within {reach:g} px of the image centre {centre:g} (the larger of {PRINCIPAL_POINT_MIN_REACH_PX:g} px"
        f" and {PRINCIPAL_POINT_REACH_SIZES} image sizes: lens shifts and crops stay far inside it; a value beyond is in"
        " another unit or a typo)"
    )


#: Largest rotation between two consecutive frames accepted, in degrees (a rig's
#: ``motion.rotation_deg`` times ``motion.frame_interval``): the moving camera's
#: images are two frame intervals apart, and a turn of 180 degrees or more
#: between two images cannot be told from a smaller one the other way; the
#: small-motion method needs a few degrees per frame at most.
MAX_ROTATION_PER_FRAME_DEG = 90.0


def _motion(name: str, motion) -> RigidMotion:
    if not isinstance(motion, RigidMotion):
        msg = f"{name} must be a nfdepth.RigidMotion (e.g. RigidMotion.camera_translation((1, 0, 0))), got {type(motion).__name__}"
        raise TypeError(msg)
    return motion


def _camera(name: str, camera) -> PinholeCamera:
    if not isinstance(camera, PinholeCamera):
        msg = f"{name} must be a nfdepth.PinholeCamera, got {type(camera).__name__}"
        raise TypeError(msg)
    return camera


def _magnitude(vec) -> float:
    """Euclidean norm of a finite vector without overflow or underflow (inf where it exceeds the float range).

    ``np.linalg.norm`` itself for components between 1e-100 and 1e100 (its
    squares are safe there); beyond, the vector is scaled by its largest
    component first.
    """
    vec = np.asarray(vec, dtype=float)
    m = float(np.max(np.abs(vec))) if vec.size else 0.0
    if 1e-100 < m < 1e100 or m == 0:
        return float(np.linalg.norm(vec))
    return m * float(np.linalg.norm(vec / m))


@dataclass(frozen=True)
class PinholeCamera:
    """Pinhole camera with focal length and principal point in pixels.

    Parameters
    ----------
    focal_px : float
        Focal length ``f`` in pixels (> 0).
    width_px, height_px : int
        Image size in pixels.
    cx_px, cy_px : float, optional
        Principal point (column, row) in pixels; default the image centre
        ``((W-1)/2, (H-1)/2)``.

    Examples
    --------
    >>> cam = PinholeCamera(focal_px=100.0, width_px=65, height_px=49)
    >>> cam.cx_px, cam.cy_px
    (32.0, 24.0)
    >>> rows, cols, z = cam.project([[0.5, -0.25, 2.0]])  # x = 0.25, y = -0.125
    >>> float(rows[0]), float(cols[0]), float(z[0])
    (11.5, 57.0, 2.0)
    """

    focal_px: float
    width_px: int
    height_px: int
    cx_px: float | None = None
    cy_px: float | None = None

    def __post_init__(self) -> None:
        # Stored as Python numbers: a 0-d array (or NumPy scalar) given for one would make the camera unhashable.
        focal = check_within(
            "focal_px",
            self.focal_px,
            advice="expected a focal length in pixels in that range (beyond it the normalised coordinates and depths overflow or vanish in float arithmetic)",
        )
        object.__setattr__(self, "focal_px", focal)
        check_image_size(self)
        object.__setattr__(self, "width_px", int(self.width_px))
        object.__setattr__(self, "height_px", int(self.height_px))
        if self.cx_px is None:
            object.__setattr__(self, "cx_px", (self.width_px - 1) / 2.0)
        if self.cy_px is None:
            object.__setattr__(self, "cy_px", (self.height_px - 1) / 2.0)
        reach = _principal_point_reach(self.width_px, self.height_px)
        for name, size in (("cx_px", self.width_px), ("cy_px", self.height_px)):
            value = check_finite(name, getattr(self, name), unit="pixels")
            centre = (size - 1) / 2.0
            if not abs(value - centre) <= reach:
                msg = f"{name} = {value:g} px: expected {_principal_point_expected(centre, reach)}"
                raise ValueError(msg)
            object.__setattr__(self, name, value)

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape ``(rows, cols)``."""
        return (int(self.height_px), int(self.width_px))

    @property
    def matrix(self) -> np.ndarray:
        """The 3 x 3 intrinsic matrix ``K`` (OpenCV's camera matrix: ``(col, row, 1) ~ K (X, Y, Z)``)."""
        return np.array([[self.focal_px, 0.0, self.cx_px], [0.0, self.focal_px, self.cy_px], [0.0, 0.0, 1.0]])

    def reduced(self, factor: float, shape) -> PinholeCamera:
        """This camera for its image reduced ``factor`` times to ``shape`` ``(rows, cols)`` (e.g. ``cv2.pyrDown``).

        Pixel centres map as ``c' = (c + 0.5) / factor - 0.5``.
        """
        factor = check_positive_finite("factor", factor)
        h, w = shape
        return PinholeCamera(self.focal_px / factor, w, h, (self.cx_px + 0.5) / factor - 0.5, (self.cy_px + 0.5) / factor - 0.5)

    def to_normalized(self, rows, cols):
        """Pixel ``(row, col)`` to normalised image coordinates ``(x, y)``."""
        x = (as_real("cols", cols) - self.cx_px) / self.focal_px
        y = (as_real("rows", rows) - self.cy_px) / self.focal_px
        return x, y

    def to_pixel(self, x, y):
        """Normalised ``(x, y)`` to pixel ``(row, col)``."""
        rows = self.cy_px + self.focal_px * as_real("y", y)
        cols = self.cx_px + self.focal_px * as_real("x", x)
        return rows, cols

    def project(self, points):
        """Project camera-frame points, shape ``(..., 3)``, to ``(row, col, Z)``.

        Points at ``Z <= 0`` (at or behind the camera) are projected all the
        same (through the centre, or to inf at 0): test ``Z > 0`` where it matters.
        """
        points = as_real("points", points)
        if points.shape[-1] != 3:
            msg = f"points must have shape (..., 3), got {points.shape}"
            raise ValueError(msg)
        z = points[..., 2]
        rows, cols = self.to_pixel(points[..., 0] / z, points[..., 1] / z)
        return rows, cols, z

    def back_project(self, rows, cols, depth):
        """Pixel positions and depth Z to camera-frame points, shape ``(..., 3)``."""
        x, y = self.to_normalized(rows, cols)
        depth = as_real("depth", depth)
        return np.stack(np.broadcast_arrays(x * depth, y * depth, depth), axis=-1)


def _read_only_copy(vec: np.ndarray) -> np.ndarray:
    """A copy of ``vec`` that cannot be written to (the field of a frozen dataclass: neither its caller nor its user can change it)."""
    out = np.array(vec, dtype=float)
    out.flags.writeable = False
    return out


@dataclass(frozen=True)
class RigidMotion:
    """Instantaneous rigid motion ``(V, Omega)`` of the scene relative to a camera.

    ``translation`` is ``V`` in scene units per unit time; ``rotation`` is
    ``Omega`` in radians per unit time, both in camera coordinates, so that a
    scene point moves as ``dP/dt = V + Omega x P`` (paper eq. 1). ``|Omega|``
    is at most 1e30 (the upper end of the speeds' range).

    Immutable: both are read-only copies of the vectors given. Two motions are
    equal when their vectors are (``np.array_equal``), and equal motions hash
    alike (a motion can be a set member or a dict key).
    """

    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        object.__setattr__(self, "translation", _read_only_copy(as_vector3("translation", self.translation)))
        rotation = _read_only_copy(as_vector3("rotation", self.rotation))
        hi = UNIT_SCALE_RANGE[1]
        if _magnitude(rotation) > hi:
            msg = (
                f"rotation = [{', '.join(f'{float(w):g}' for w in rotation)}] rad per unit time: expected an angular velocity"
                f" of at most {hi:g} in magnitude (beyond it the rotational flow overflows; a small-motion method needs a few"
                " degrees per frame)"
            )
            raise ValueError(msg)
        object.__setattr__(self, "rotation", rotation)

    def __eq__(self, other) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        return np.array_equal(self.translation, other.translation) and np.array_equal(self.rotation, other.rotation)

    def __hash__(self) -> int:
        # the values the equality compares (0.0 and -0.0 are equal and hash alike; the vectors are finite)
        return hash((self.__class__, tuple(self.translation.tolist()), tuple(self.rotation.tolist())))

    def __reduce__(self):
        # copies and pickles are built as new motions (read-only vectors), not by filling in the fields
        return (self.__class__, (self.translation, self.rotation))

    @classmethod
    def about_center(cls, *, rotation, center, translation=(0.0, 0.0, 0.0)) -> RigidMotion:
        """Rotation ``rotation`` (rad/unit time) about an axis through ``center``.

        ``dP/dt = translation + rotation x (P - center)``, i.e.
        ``V = translation - rotation x center``.
        """
        rotation = as_vector3("rotation", rotation)
        center = as_vector3("center", center)
        translation = as_vector3("translation", translation)
        return cls(translation - np.cross(rotation, center), rotation)

    @classmethod
    def camera_translation(cls, velocity) -> RigidMotion:
        """Scene motion seen by a camera translating with ``velocity`` (V = -T)."""
        return cls(-as_vector3("velocity", velocity), np.zeros(3))

    def __add__(self, other: RigidMotion) -> RigidMotion:
        if not isinstance(other, RigidMotion):
            return NotImplemented  # Python's TypeError: unsupported operand type(s)
        return RigidMotion(self.translation + other.translation, self.rotation + other.rotation)

    def __sub__(self, other: RigidMotion) -> RigidMotion:
        """Relative motion ``(V_m - V_s, Omega_m - Omega_s)`` (paper eq. 2, 4)."""
        if not isinstance(other, RigidMotion):
            return NotImplemented
        return RigidMotion(self.translation - other.translation, self.rotation - other.rotation)

    def __neg__(self) -> RigidMotion:
        return RigidMotion(-self.translation, -self.rotation)

    def scaled(self, factor: float) -> RigidMotion:
        """Motion over ``factor`` units of time (or with velocities times ``factor``)."""
        factor = check_finite("factor", factor)
        return RigidMotion(self.translation * factor, self.rotation * factor)

    @property
    def is_pure_rotation(self) -> bool:
        """True when the translation is exactly zero (depth cannot be recovered)."""
        return not np.any(self.translation)


def _rotational_flow(x, y, omega):
    wx, wy, wz = omega
    u = -wx * x * y + wy * (1.0 + x * x) - wz * y
    v = -wx * (1.0 + y * y) + wy * x * y + wz * x
    return u, v


def image_flow(x, y, inverse_depth, motion: RigidMotion):
    """Image flow ``(u, v)`` in normalised units per unit time (paper eq. 1).

    .. math::
        u = -\\Omega_X x y + \\Omega_Y (1 + x^2) - \\Omega_Z y + (V_X - x V_Z)/Z

        v = -\\Omega_X (1 + y^2) + \\Omega_Y x y + \\Omega_Z x + (V_Y - y V_Z)/Z

    ``inverse_depth`` is ``1/Z`` (0 for points at infinity).

    Parameters
    ----------
    x, y : array_like
        Normalised image coordinates ``x = X/Z``, ``y = Y/Z`` (pixel offsets from the
        principal point over the focal length: :meth:`PinholeCamera.to_normalized`).
    inverse_depth : array_like
        ``1/Z`` in 1/scene units; 0 gives the rotational flow alone. Not checked: a
        negative value (a point behind the camera) is used as given.
    motion : RigidMotion
        Motion ``(V, Omega)`` of the scene relative to the camera, ``V`` in scene units
        and ``Omega`` in radians per unit time (a camera translating by ``T`` sees ``V = -T``).

    Returns
    -------
    u, v : ndarray of float64
        Flow along ``x`` (+col) and ``y`` (+row) in normalised units per unit time, of
        the broadcast shape of ``x``, ``y`` and ``inverse_depth`` (NumPy float64 scalars
        for scalar input). NaN inputs give NaN.

    Raises
    ------
    TypeError
        ``motion`` is not a :class:`RigidMotion`, or ``x``, ``y`` or ``inverse_depth``
        is not real numbers (complex, text, objects).
    ValueError
        The three do not broadcast together (NumPy's error).
    """
    motion = _motion("motion", motion)
    x, y, rho = as_real("x", x), as_real("y", y), as_real("inverse_depth", inverse_depth)
    vx, vy, vz = motion.translation
    ur, vr = _rotational_flow(x, y, motion.rotation)
    return ur + (vx - x * vz) * rho, vr + (vy - y * vz) * rho


def image_flow_px(camera: PinholeCamera, rows, cols, depth, motion: RigidMotion):
    """Image flow in pixels per unit time at pixel positions with depth ``Z``.

    Returns ``(flow_col, flow_row)``: eq. 1 multiplied by the focal length.

    Parameters
    ----------
    camera : PinholeCamera
        Focal length and principal point (px) that map ``rows``, ``cols`` to the
        normalised ``x``, ``y`` of eq. 1.
    rows, cols : array_like
        Pixel positions (``row`` downward, ``col`` to the right; need not be integers).
    depth : array_like
        Depth ``Z`` along the optical axis in scene units (those of
        ``motion.translation``). ``inf`` gives the rotational flow alone; 0 gives
        infinite or NaN flow; a negative depth (behind the camera) is used as given.
    motion : RigidMotion
        Scene motion relative to the camera, per unit time (as in :func:`image_flow`).

    Returns
    -------
    flow_col, flow_row : ndarray of float64
        ``f u`` and ``f v``: the flow along +col and +row in px per unit time, of the
        broadcast shape of ``rows``, ``cols`` and ``depth`` (NumPy float64 scalars for
        scalar input).

    Raises
    ------
    TypeError
        ``camera`` is not a :class:`PinholeCamera`, ``motion`` not a :class:`RigidMotion`,
        or ``rows``, ``cols`` or ``depth`` is not real numbers (complex, text, objects).
    """
    x, y = _camera("camera", camera).to_normalized(rows, cols)
    with np.errstate(divide="ignore", invalid="ignore"):  # depth 0: infinite flow, NaN where a term is inf * 0
        rho = 1.0 / as_real("depth", depth)
        u, v = image_flow(x, y, rho, motion)
    return camera.focal_px * u, camera.focal_px * v


def normal_flow_px(camera: PinholeCamera, rows, cols, depth, alpha, motion: RigidMotion):
    """Normal flow ``Vn = u cos(alpha) + v sin(alpha)`` in px per unit time (eq. 3).

    Parameters
    ----------
    camera : PinholeCamera
        Focal length and principal point (px) of the image.
    rows, cols : array_like
        Pixel positions.
    depth : array_like
        Depth ``Z`` in scene units (as in :func:`image_flow_px`).
    alpha : array_like
        Direction of the normal ``n = (cos alpha, sin alpha)`` in radians, measured from
        the +col axis toward +row: ``atan2(I_row, I_col)``
        (:attr:`nfdepth.normal_flow.GradientField.alpha`).
    motion : RigidMotion
        Scene motion relative to the camera, per unit time (as in :func:`image_flow`).

    Returns
    -------
    ndarray of float64
        Signed normal flow in px per unit time (> 0 along ``n``), of the broadcast shape
        of ``rows``, ``cols``, ``depth`` and ``alpha`` (a NumPy float64 for scalar input).

    Raises
    ------
    TypeError
        ``camera`` is not a :class:`PinholeCamera`, ``motion`` not a :class:`RigidMotion`,
        or ``rows``, ``cols``, ``depth`` or ``alpha`` is not real numbers (complex, text,
        objects).

    Examples
    --------
    A camera moving right at 2 units per unit time sees a point 400 units
    ahead at the principal point move left at ``f Vx / Z = 100 * -2 / 400``:

    >>> cam = PinholeCamera(focal_px=100.0, width_px=65, height_px=49)
    >>> motion = RigidMotion.camera_translation((2.0, 0.0, 0.0))
    >>> float(normal_flow_px(cam, 24.0, 32.0, 400.0, 0.0, motion))
    -0.5
    """
    fu, fv = image_flow_px(camera, rows, cols, depth, motion)
    alpha = as_real("alpha", alpha)
    with np.errstate(invalid="ignore"):  # an infinite flow (depth 0) across its normal: NaN
        return fu * np.cos(alpha) + fv * np.sin(alpha)


def relative_normal_flow_coefficients(camera: PinholeCamera, rows, cols, alpha, relative_motion: RigidMotion):
    """Coefficients of paper eq. 4 written as ``dVn = A + B / Z`` (px per unit time).

    ``A = f * (rotational flow of dOmega) . n`` and
    ``B = f * (dVx - x dVz, dVy - y dVz) . n`` with ``n = (cos alpha, sin alpha)``.
    Inverse depth follows as ``rho = (dVn - A) / B`` where ``B != 0``.

    Parameters
    ----------
    camera : PinholeCamera
        Focal length and principal point (px) of the reference image, in which the
        relative normal flow is measured.
    rows, cols : array_like
        Pixel positions of the points.
    alpha : array_like
        Normal direction in radians, from the +col axis toward +row
        (``atan2(I_row, I_col)``).
    relative_motion : RigidMotion
        ``(dV, dOmega) = (V_m - V_s, Omega_m - Omega_s)``: the scene's motion relative
        to camera m minus that relative to camera s (``motion_m - motion_s``), per unit
        time, ``dV`` in scene units, ``dOmega`` in radians.

    Returns
    -------
    A, B : ndarray of float64
        ``A`` in px per unit time: the relative rotation's normal flow (no depth in it).
        ``B`` in px per unit time per unit inverse depth: the relative translation's
        normal flow at ``Z = 1`` scene unit; 0 (up to rounding) where the relative
        motion has no translation or the normal is perpendicular to the translational
        flow (depth undeterminable). Both of the broadcast shape of ``rows``, ``cols`` and ``alpha``
        (0-d for scalar input).

    Raises
    ------
    TypeError
        ``camera`` is not a :class:`PinholeCamera`, ``relative_motion`` not a
        :class:`RigidMotion`, or ``rows``, ``cols`` or ``alpha`` is not real numbers
        (complex, text, objects).
    """
    relative_motion = _motion("relative_motion", relative_motion)
    x, y = _camera("camera", camera).to_normalized(rows, cols)
    alpha = as_real("alpha", alpha)
    c, s = np.cos(alpha), np.sin(alpha)
    ur, vr = _rotational_flow(x, y, relative_motion.rotation)
    vx, vy, vz = relative_motion.translation
    f = camera.focal_px
    a = f * (ur * c + vr * s)
    b = f * ((vx - x * vz) * c + (vy - y * vz) * s)
    return np.asarray(a, dtype=float), np.asarray(b, dtype=float)
