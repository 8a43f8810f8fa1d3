"""Depth from relative normal flow (paper eq. 4, 5, 6).

Per point, with everything in pixels per unit time (docs/how-it-works.md, "Conventions"):

.. math::
    \\Delta V_n = A + B \\rho,\\qquad \\rho = 1/Z

``A`` is the relative rotation's normal flow, ``B`` the relative
translation's normal flow at unit inverse depth
(:func:`nfdepth.camera.relative_normal_flow_coefficients`). Inverse depth is
linear in the measurement, so several relative normal flows of one point
(more cameras, x and y baselines) combine by weighted least squares, and the
variance of ``rho`` is the variance of ``dVn`` divided by ``B**2``.

Depth is *undeterminable* where the relative motion has no translation, or
where the edge normal is (nearly) perpendicular to the translational flow:
``|cos|`` of the angle between them below ``min_cos``. Such points, and
points whose inverse depth is not positive (behind the camera or at
infinity), get NaN and a reason code, never a number.
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np

from ._validate import (
    as_real,
    check_fraction,
    check_nonnegative_finite,
    check_nonzero_finite,
    check_positive_finite,
)
from .camera import (
    PinholeCamera,
    RigidMotion,
    _camera,
    _motion,
    relative_normal_flow_coefficients,
)

__all__ = [
    "Reason",
    "InverseDepth",
    "solve_inverse_depth",
    "depth_x_translation",
    "depth_y_translation",
    "depth_z_translation",
    "fuse_inverse_depth",
]


class Reason(IntEnum):
    """Why a point has no depth (0 = it has one)."""

    OK = 0
    NOT_EDGE = 1  #: not a strong zero-crossing edge point
    CORNER = 2  #: gradient direction ill-defined
    UNDETERMINABLE = 3  #: B ~ 0: no translation, or edge parallel to its flow
    NOT_POSITIVE = 4  #: inverse depth <= 0: behind the camera or at infinity
    UNCERTAIN = 5  #: uncertainty above the requested bound
    NO_DATA = 6  #: no usable measurement (NaN input, outside the views)


class InverseDepth:
    """Inverse depth with its standard deviation and reason codes.

    Attributes
    ----------
    rho : ndarray
        Inverse depth ``1/Z`` in 1/scene-units, NaN where not valid.
    rho_std : ndarray
        Standard deviation of ``rho`` (NaN where not valid, or where no noise
        level was given).
    reason : ndarray of uint8
        :class:`Reason` codes; 0 where ``rho`` is valid.
    b : ndarray
        The coefficient ``B`` (px per unit time per unit inverse depth).
    """

    def __init__(self, rho, rho_std, reason, b):
        self.rho = rho
        self.rho_std = rho_std
        self.reason = reason
        self.b = b

    @property
    def valid(self) -> np.ndarray:
        """True where ``rho`` holds a number."""
        return self.reason == Reason.OK

    @property
    def depth(self) -> np.ndarray:
        """Depth ``Z = 1 / rho`` (NaN where not valid)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return 1.0 / self.rho

    @property
    def depth_std(self) -> np.ndarray:
        """First-order standard deviation of ``Z``: ``rho_std / rho**2``."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.rho_std / self.rho**2


def solve_inverse_depth(
    delta_vn,
    *,
    camera: PinholeCamera,
    rows,
    cols,
    alpha,
    relative_motion: RigidMotion,
    delta_vn_std=None,
    min_cos: float = 0.25,
    max_rel_std: float | None = None,
) -> InverseDepth:
    """Inverse depth from relative normal flow, general relative motion (eq. 4).

    Parameters
    ----------
    delta_vn : array_like
        Relative normal flow ``Vn_m - Vn_s`` in px per unit time.
    camera : PinholeCamera
        Intrinsics of the reference image.
    rows, cols : array_like
        Pixel positions of the points (broadcast with ``delta_vn``).
    alpha : array_like
        Normal direction of each point in radians (``atan2(I_row, I_col)``).
    relative_motion : RigidMotion
        ``(V_m - V_s, Omega_m - Omega_s)``: scene motion relative to camera m
        minus that relative to camera s, per unit time.
    delta_vn_std : array_like, optional
        Standard deviation of ``delta_vn``; gives ``rho_std = std / |B|``.
    min_cos : float
        Smallest ``|cos|`` of the angle between the edge normal and the
        translational flow direction accepted (0 accepts all ``B != 0``).
    max_rel_std : float, optional
        Refuse points whose relative standard deviation ``rho_std / rho``
        (= that of depth, to first order) exceeds this bound
        (:attr:`Reason.UNCERTAIN`). Needs ``delta_vn_std``.

    Returns
    -------
    InverseDepth
    """
    camera = _camera("camera", camera)
    relative_motion = _motion("relative_motion", relative_motion)
    min_cos = check_fraction("min_cos", min_cos)
    dvn = as_real("delta_vn", delta_vn)
    alpha = as_real("alpha", alpha)
    a, b = relative_normal_flow_coefficients(camera, rows, cols, alpha, relative_motion)
    x, y = camera.to_normalized(rows, cols)
    vx, vy, vz = relative_motion.translation
    flow_norm = camera.focal_px * np.hypot(vx - x * vz, vy - y * vz)
    dvn, a, b, flow_norm = np.broadcast_arrays(dvn, a, b, flow_norm)
    reason = np.full(dvn.shape, Reason.OK, dtype=np.uint8)
    # no measurement, or no position or direction for it (NaN rows, cols or alpha)
    reason[~np.isfinite(dvn) | ~np.isfinite(alpha * np.ones(dvn.shape)) | ~np.isfinite(a) | ~np.isfinite(b)] = Reason.NO_DATA
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.abs(b) / flow_norm
        determinable = (flow_norm > 0) & (cos >= max(min_cos, 1e-12))
        reason[(reason == Reason.OK) & ~determinable] = Reason.UNDETERMINABLE
        rho = (dvn - a) / b
    reason[(reason == Reason.OK) & ~(rho > 0)] = Reason.NOT_POSITIVE
    ok = reason == Reason.OK
    rho = np.where(ok, rho, np.nan)
    if delta_vn_std is None:
        rho_std = np.full(dvn.shape, np.nan)
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            rho_std = np.where(ok, _check_std("delta_vn_std", delta_vn_std) / np.abs(b), np.nan)
    if max_rel_std is not None:
        bound = check_nonnegative_finite("max_rel_std", max_rel_std)
        if delta_vn_std is None:
            msg = "max_rel_std needs delta_vn_std (the noise of the relative normal flow)"
            raise ValueError(msg)
        with np.errstate(divide="ignore", invalid="ignore"):
            too_uncertain = ok & ~(rho_std <= bound * rho)
        reason[too_uncertain] = Reason.UNCERTAIN
        rho = np.where(too_uncertain, np.nan, rho)
        rho_std = np.where(too_uncertain, np.nan, rho_std)
    return InverseDepth(rho, rho_std, reason, np.asarray(b, dtype=float))


def _special_case(factor, cos, delta_vn, min_cos):
    """``Z = factor * cos / dVn`` where ``|cos| >= min_cos`` (at least 1e-12, as in eq. 4's solver) and ``Z > 0``; NaN elsewhere."""
    min_cos = check_fraction("min_cos", min_cos)
    dvn = as_real("delta_vn", delta_vn)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = factor * cos / dvn
        determinable = np.abs(cos) >= max(min_cos, 1e-12)
    return np.where((z > 0) & np.isfinite(z) & determinable, z, np.nan)  # dVn = 0 (at infinity) is no depth either


def depth_x_translation(delta_vn, alpha, *, focal_px: float, delta_vx: float, min_cos: float = 0.0):
    """Depth when the relative motion is a pure x translation (paper eq. 5, 6).

    ``Z = f dVx cos(alpha) / dVn`` (``dVx`` in scene units per unit time,
    ``dVn`` in px per unit time); NaN where ``Z`` would not be positive.
    Eq. 6 in pixels: the paper's normalised units times ``f``.

    Parameters
    ----------
    delta_vn : array_like
        Relative normal flow ``Vn_m - Vn_s`` in px per unit time.
    alpha : array_like
        Normal direction in radians (``atan2(I_row, I_col)``, from +col toward +row).
    focal_px : float
        Focal length ``f`` in pixels (positive, finite).
    delta_vx : float
        ``dVx``, the x component of the relative motion ``V_m - V_s`` of the scene, in
        scene units per unit time (non-zero): camera m translating toward +X relative
        to camera s gives ``dVx < 0`` (``V = -T``).
    min_cos : float
        Smallest ``|cos(alpha)|`` accepted, in [0, 1]. The default 0 is eq. 6 as printed,
        but for a normal perpendicular to x within 1e-12 (depth undeterminable, where
        ``cos(pi/2)`` is 6e-17, not 0), which gets NaN, as in :func:`solve_inverse_depth`.

    Returns
    -------
    ndarray of float64
        Depth ``Z`` in the scene units of ``delta_vx``, of the broadcast shape of
        ``delta_vn`` and ``alpha`` (0-d for scalar input). NaN where ``Z`` is not a
        positive finite number: ``dVn = 0`` (at infinity), ``dVn`` of the sign that puts
        the point behind the camera, NaN input, ``|cos(alpha)|`` below ``min_cos``. Above
        it, a normal nearly perpendicular to x gives a number, however unreliable
        (:func:`solve_inverse_depth` refuses ``|cos| < 0.25`` by default).

    Raises
    ------
    TypeError
        ``focal_px`` or ``delta_vx`` is not a number (a str or bool too), or
        ``delta_vn`` or ``alpha`` is not real numbers (complex, text, objects).
    ValueError
        ``focal_px`` is not positive and finite, ``delta_vx`` is 0 or not finite, ``min_cos`` is not within [0, 1].

    Examples
    --------
    >>> float(depth_x_translation(-0.5, 0.0, focal_px=100.0, delta_vx=-2.0))  # the flow of normal_flow_px's example
    400.0
    >>> float(depth_x_translation(0.5, 0.0, focal_px=100.0, delta_vx=-2.0))  # would be behind the camera
    nan
    """
    f = check_positive_finite("focal_px", focal_px)
    delta_vx = check_nonzero_finite("delta_vx", delta_vx, what="a non-zero finite translation")
    return _special_case(f * delta_vx, np.cos(as_real("alpha", alpha)), delta_vn, min_cos)


def depth_y_translation(delta_vn, alpha, *, focal_px: float, delta_vy: float, min_cos: float = 0.0):
    """Depth for a pure y translation: ``Z = f dVy sin(alpha) / dVn``.

    Eq. 4 with only ``dVy`` non-zero, the y analogue of eq. 6
    (:func:`depth_x_translation`); NaN where ``Z`` would not be positive.

    Parameters
    ----------
    delta_vn : array_like
        Relative normal flow ``Vn_m - Vn_s`` in px per unit time.
    alpha : array_like
        Normal direction in radians (``atan2(I_row, I_col)``, from +col toward +row).
    focal_px : float
        Focal length ``f`` in pixels (positive, finite).
    delta_vy : float
        ``dVy``, the y component of the relative motion ``V_m - V_s`` of the scene, in
        scene units per unit time (non-zero): camera m translating toward +Y (down)
        relative to camera s gives ``dVy < 0``.
    min_cos : float
        Smallest ``|sin(alpha)|`` (the cosine of the angle between the normal and y)
        accepted, in [0, 1]; the default 0 refuses only ``|sin(alpha)| < 1e-12``
        (:func:`depth_x_translation`).

    Returns
    -------
    ndarray of float64
        Depth ``Z`` in the scene units of ``delta_vy``, of the broadcast shape of
        ``delta_vn`` and ``alpha`` (0-d for scalar input); NaN where ``Z`` is not a
        positive finite number (``dVn = 0``, a point behind the camera, NaN input,
        ``|sin(alpha)|`` below ``min_cos``).

    Raises
    ------
    TypeError
        ``focal_px`` or ``delta_vy`` is not a number (a str or bool too), or
        ``delta_vn`` or ``alpha`` is not real numbers (complex, text, objects).
    ValueError
        ``focal_px`` is not positive and finite, ``delta_vy`` is 0 or not finite, ``min_cos`` is not within [0, 1].
    """
    f = check_positive_finite("focal_px", focal_px)
    delta_vy = check_nonzero_finite("delta_vy", delta_vy, what="a non-zero finite translation")
    return _special_case(f * delta_vy, np.sin(as_real("alpha", alpha)), delta_vn, min_cos)


def depth_z_translation(delta_vn, alpha, *, camera: PinholeCamera, rows, cols, delta_vz: float, min_cos: float = 0.0):
    """Depth for a pure z translation: ``Z = -f dVz (x cos a + y sin a) / dVn``.

    Eq. 4 with only ``dVz`` non-zero; ``x``, ``y`` are the normalised coordinates of
    ``cols``, ``rows``. The translational flow is radial from the principal point, so
    depth is undeterminable there and where the normal is perpendicular to the
    radial direction. NaN where ``Z`` would not be positive.

    Parameters
    ----------
    delta_vn : array_like
        Relative normal flow ``Vn_m - Vn_s`` in px per unit time.
    alpha : array_like
        Normal direction in radians (``atan2(I_row, I_col)``, from +col toward +row).
    camera : PinholeCamera
        Focal length and principal point (px) of the reference image.
    rows, cols : array_like
        Pixel positions of the points.
    delta_vz : float
        ``dVz``, the z component of the relative motion ``V_m - V_s`` of the scene, in
        scene units per unit time (non-zero): camera m moving forward relative to
        camera s gives ``dVz < 0`` (flow away from the principal point).
    min_cos : float
        Smallest ``|cos|`` of the angle between the normal and the radial direction
        ``(x, y)`` accepted, in [0, 1]; the default 0 refuses only ``|cos| < 1e-12`` and
        the principal point itself (:func:`depth_x_translation`).

    Returns
    -------
    ndarray of float64
        Depth ``Z`` in the scene units of ``delta_vz``, of the broadcast shape of
        ``delta_vn``, ``alpha``, ``rows`` and ``cols`` (0-d for scalar input); NaN where
        ``Z`` is not a positive finite number (``dVn = 0``, a point behind the camera,
        NaN input, ``|cos|`` below ``min_cos``, the principal point). Above ``min_cos``, near
        the principal point or with the normal nearly perpendicular to the radial direction,
        ``Z`` is a number, however unreliable.

    Raises
    ------
    TypeError
        ``camera`` is not a :class:`~nfdepth.camera.PinholeCamera`, ``delta_vz`` is not
        a number (a str or bool too), or ``rows``, ``cols``, ``delta_vn`` or ``alpha`` is
        not real numbers (complex, text, objects).
    ValueError
        ``delta_vz`` is 0 or not finite, ``min_cos`` is not within [0, 1].
    """
    camera = _camera("camera", camera)
    delta_vz = check_nonzero_finite("delta_vz", delta_vz, what="a non-zero finite translation")
    x, y = camera.to_normalized(rows, cols)
    alpha = as_real("alpha", alpha)
    radius = np.hypot(x, y)  # the translational flow is radial: cos is that of the normal to (x, y)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = (x * np.cos(alpha) + y * np.sin(alpha)) / radius
    return _special_case(-camera.focal_px * delta_vz * radius, cos, delta_vn, min_cos)


def _check_std(name: str, std) -> np.ndarray:
    """A standard deviation: >= 0 (NaN: unknown), else ValueError."""
    std = as_real(name, std)
    with np.errstate(invalid="ignore"):
        negative = std < 0
    if np.any(negative):
        msg = f"{name} must be >= 0 (NaN: unknown), got {int(np.count_nonzero(negative))} negative value(s), the lowest {float(np.min(std[negative])):g}"
        raise ValueError(msg)
    return std


def fuse_inverse_depth(delta_vn, a, b, delta_vn_std, *, axis: int = 0):
    """Weighted least-squares inverse depth from several measurements of a point.

    Each measurement ``k`` obeys ``dVn_k = A_k + B_k rho`` with noise
    ``std_k``. The estimate and its standard deviation are

    .. math::
        \\hat\\rho = \\frac{\\sum_k w_k B_k (\\Delta V_{n,k} - A_k)}{\\sum_k w_k B_k^2},
        \\qquad \\sigma_\\rho = \\Big(\\sum_k w_k B_k^2\\Big)^{-1/2},
        \\qquad w_k = \\sigma_k^{-2}.

    Measurements with ``B = 0`` or a non-finite ``dVn``, ``A``, ``B`` or std (NaN:
    unknown) are ignored. Measurements of std 0 (exact; or so small against
    ``B`` that ``|B| / std`` overflows) outweigh every other: where a point has
    any, they alone give its estimate (equal weights) and its std is 0. The
    sums are taken relative to a point's most informative measurement, so
    neither a tiny std nor a tiny ``B`` overflows or underflows them. A negative std is refused (ValueError).
    The three results have the broadcast shape of the inputs without ``axis``
    (for 1-D input: 0-d arrays and a NumPy integer).

    Parameters
    ----------
    delta_vn : array_like
        Relative normal flows ``dVn_k`` in px per unit time, the measurements running
        along ``axis``.
    a, b : array_like
        Their coefficients ``A_k`` (px per unit time) and ``B_k`` (px per unit time per
        unit inverse depth) from :func:`nfdepth.camera.relative_normal_flow_coefficients`.
        The model is linear in any units: with ``a = 0`` and ``b = 1`` the result is the
        inverse-variance mean of ``delta_vn``.
    delta_vn_std : array_like
        Standard deviation ``std_k`` of each ``dVn_k`` (>= 0; 0: exact; NaN: unknown).
        All four arrays broadcast together.
    axis : int
        Axis of the broadcast arrays that runs over the measurements.

    Returns
    -------
    rho : ndarray of float64
        Inverse depth ``1/Z`` in 1/scene units (in general the unit of ``(dVn - A) / B``);
        NaN where no measurement is usable. Its sign is not checked (it may be <= 0).
    rho_std : ndarray of float64
        Its standard deviation ``sigma_rho``: 0 where exact measurements decided, NaN
        where ``rho`` is.
    count : ndarray of int
        Number of measurements used per point (the usable ones, or the exact ones where
        a point has any).

    Raises
    ------
    TypeError
        ``delta_vn``, ``a``, ``b`` or ``delta_vn_std`` is not real numbers (complex, text,
        objects).
    ValueError
        ``delta_vn_std`` has a negative value, the arrays do not broadcast together, or
        ``axis`` is out of range (NumPy's ``AxisError``, a ``ValueError``).
    """
    dvn, a, b, std = np.broadcast_arrays(as_real("delta_vn", delta_vn), as_real("a", a), as_real("b", b), _check_std("delta_vn_std", delta_vn_std))
    usable = np.isfinite(dvn) & np.isfinite(a) & np.isfinite(b) & np.isfinite(std) & (b != 0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # each measurement's own inverse depth, and its information |B| / std (inf: exact)
        own = np.where(usable, (dvn - a) / b, 0.0)
        info = np.where(usable, np.abs(b) / std, 0.0)
    exact = usable & np.isinf(info)  # std 0, or so small against B that B / std overflows
    has_exact = np.any(exact, axis=axis, keepdims=True)
    usable = np.where(has_exact, exact, usable)  # the exact measurements alone where a point has any
    info = np.where(has_exact, exact.astype(float), info)  # equal weights among them
    # Weights relative to the point's most informative measurement, in (0, 1]: sum(w B^2) and
    # sum(w B (dVn - A)) neither overflow (std 1e-200) nor underflow to 0 (B 1e-200).
    scale = np.max(info, axis=axis, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.square(info / scale)
        den = np.sum(w, axis=axis)
        rho = np.sum(np.where(w > 0, w * own, 0.0), axis=axis) / den  # (a weight that underflowed to 0 times an inf)
        rho_std = 1.0 / (np.squeeze(scale, axis=axis) * np.sqrt(den))
    rho_std = np.where(np.squeeze(has_exact, axis=axis), 0.0, rho_std)
    count = np.sum(usable, axis=axis)
    none = count == 0
    rho = np.where(none, np.nan, rho)
    rho_std = np.where(none, np.nan, rho_std)
    return rho, rho_std, count
