"""Dynamic and static stereo from relative normal flow (paper sections 2.3, 3.2, 3.3).

*Dynamic stereo* (paper Fig. 3): five images ``I1 ... I5`` taken at equal
time steps; ``I1, I3, I5`` come from the moving camera, ``I2, I3, I4`` from
the stationary one, and both cameras take ``I3`` at the same instant and
place. Each triple gives a normal-flow field registered on ``I3``; the moving
camera's triple spans twice the time, so each temporal derivative is divided
by its own time step before the flows are subtracted.

*Static stereo* (paper section 2.3): views taken at positions spaced by
``baseline`` along a known direction are a sequence with unit time step, seen
by a camera whose partner is still; the relative normal flow is the
sequence's own normal flow and the relative motion is ``-baseline`` along
the direction of travel.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from ._exposure import _plateaus, clipped_apart, match_nearby_exposures
from ._validate import UNIT_SCALE_RANGE, as_frames, as_vector3, check_bool, check_frame_interval, check_noise_std, check_scale_px, check_within, float_dtype
from .camera import PinholeCamera, RigidMotion, _magnitude, _motion
from .depth import InverseDepth, Reason, fuse_inverse_depth, solve_inverse_depth
from .edges import EdgeSelection, _no_edge_points_warning, select_edge_points
from .normal_flow import GradientField, estimate_noise_std, gaussian_smooth, gradients, noise_gains

__all__ = ["EdgeDepth", "dynamic_stereo", "static_stereo_edges"]

#: Fewest determinable edge points before a majority with negative inverse
#: depth is reported as a likely ordering/sign mistake.
_ORDER_CHECK_MIN_POINTS = 10


@dataclass(frozen=True)
class EdgeDepth:
    """Depth at the strong zero-crossing edge points of the reference image.

    Per-point arrays have shape ``(N,)`` and cover every strong,
    non-corner edge point; ``valid`` tells which have a depth. Positions are
    cell centres in pixel coordinates of the reference (middle) image.

    Attributes
    ----------
    rows, cols : ndarray
        Pixel position of each point (``row + 0.5``, ``col + 0.5`` of its cell).
    alpha : ndarray
        Normal direction (radians) used by the depth solver.
    gradient : ndarray
        Gradient magnitude (intensity per pixel).
    delta_vn : ndarray
        Relative normal flow in px per unit time.
    delta_vn_std : ndarray
        Its standard deviation: the image noise's part, and the three-image
        stencil's own error (``STENCIL_REL_STD`` = 0.4 % of ``delta_vn``) in
        quadrature.
    inverse_depth : InverseDepth
        ``rho``, ``rho_std``, reason codes.
    camera : PinholeCamera
    relative_motion : RigidMotion
    selection : EdgeSelection
        The full-grid edge rules (for figures).
    flows : dict of str to ndarray
        Full cell-grid normal-flow fields, e.g. ``"moving"``,
        ``"stationary"``, ``"relative"`` (px per unit time).
    noise_std : float
        Image noise (grey levels), given or estimated.
    exposure : list or None
        :func:`dynamic_stereo` with ``match_exposure``: per image ``I1 ..
        I5``, the ``(gain, offset)`` undone (``I_k = gain I3 + offset``) or
        None; None when every image shares ``I3``'s exposure.
    """

    rows: np.ndarray
    cols: np.ndarray
    alpha: np.ndarray
    gradient: np.ndarray
    delta_vn: np.ndarray
    delta_vn_std: np.ndarray
    inverse_depth: InverseDepth
    camera: PinholeCamera
    relative_motion: RigidMotion
    selection: EdgeSelection
    flows: dict = field(default_factory=dict)
    noise_std: float = 0.0
    exposure: list | None = None

    @property
    def valid(self) -> np.ndarray:
        """Points that have a depth."""
        return self.inverse_depth.valid

    @property
    def reason(self) -> np.ndarray:
        """:class:`nfdepth.depth.Reason` code of each point."""
        return self.inverse_depth.reason

    @property
    def depth(self) -> np.ndarray:
        """Depth Z of each point (NaN where undeterminable)."""
        return self.inverse_depth.depth

    @property
    def depth_std(self) -> np.ndarray:
        """First-order standard deviation of Z."""
        return self.inverse_depth.depth_std

    @property
    def points(self) -> np.ndarray:
        """3-D points ``(X, Y, Z)`` in the reference camera frame, shape (N, 3)."""
        return self.camera.back_project(self.rows, self.cols, self.depth)

    def __len__(self) -> int:
        return int(self.rows.size)


def _noise_level(noise_std, frames) -> float:
    """The image noise std: ``noise_std`` checked, else the median of the frames' estimates."""
    if noise_std is None:
        return float(np.median([estimate_noise_std(f) for f in frames]))
    return check_noise_std("noise_std", noise_std)


def _vn_std(field: GradientField, vn: np.ndarray, noise: float, *, sigma_px: float, stencil: str, dt: float):
    """Standard deviation of one normal-flow estimate from white image noise."""
    temporal, spatial = noise_gains(sigma_px=sigma_px, stencil=stencil)
    mag = field.magnitude
    # beyond float32 (a frame interval of 1e-30 gives flows of ~1e30 px per unit time): inf, no estimate
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return noise * np.sqrt((temporal / dt) ** 2 + (vn * spatial) ** 2) / mag


#: The three-image stencil's own error in the relative normal flow, as a fraction of it, added in quadrature to
#: the image noise's part of its standard deviation: on the noise-free pyramid (experiments 1-4 and static
#: stereo) the median |error| is 0.16-0.43 % of the flow, a standard deviation of 0.23-0.64 %. Without it,
#: noise-free images (renders, the demo's files) had an error bar of exactly 0; with noise of 1 grey level
#: (a standard deviation near 1.9 % of the flow) it widens the error bar by about 2 % of itself.
STENCIL_REL_STD = 0.004
#: Smoothing below which dynamic stereo warns: on the paper's pyramid (demo files) the median depth error is
#: 20.5 / 10.7 / 2.6 / 0.29 % at sigma 0 / 0.5 / 1 / 3 px, median |error| / std 43 / 24 / 6.4 / 0.73; textured
#: planes with noise 1 give +3-5 % at 0-1 px.
MIN_SIGMA_PX = 1.5


def _edge_result(
    *,
    camera,
    relative_motion,
    shared: GradientField,
    smoothed_middle,
    delta_vn,
    delta_vn_std,
    flows,
    noise,
    edge_options,
    min_cos,
    max_rel_std=None,
    order_hint: str = "",
):
    selection = select_edge_points(shared, smoothed_middle, **edge_options)
    rows_grid, cols_grid = GradientField.cell_centres(shared.shape)
    m = selection.mask
    if not m.any():
        warnings.warn(
            _no_edge_points_warning(
                selection,
                f" in the reference image of shape {smoothed_middle.shape}",
                border=f"within {BORDER_SIGMAS:g} sigma_px ({edge_options['border_px']} px) of the border, where the smoothing reaches past it (lower sigma_px / --sigma-px)",
                consequence="the result is empty",
            ),
            stacklevel=3,
        )
    rows, cols = rows_grid[m], cols_grid[m]
    alpha = shared.alpha[m]
    # the stencil's own error, which no image noise shows (noise-free images had a standard deviation of 0)
    std_m = np.hypot(delta_vn_std[m], STENCIL_REL_STD * np.abs(delta_vn[m]))
    inv = solve_inverse_depth(
        delta_vn[m],
        camera=camera,
        rows=rows,
        cols=cols,
        alpha=alpha,
        relative_motion=relative_motion,
        delta_vn_std=std_m,
        min_cos=min_cos,
        max_rel_std=max_rel_std,
    )
    _warn_if_mostly_behind(inv, order_hint, delta_vn[m], std_m)
    return EdgeDepth(
        rows=rows,
        cols=cols,
        alpha=alpha,
        gradient=shared.magnitude[m],
        delta_vn=delta_vn[m],
        delta_vn_std=std_m,
        inverse_depth=inv,
        camera=camera,
        relative_motion=relative_motion,
        selection=selection,
        flows=flows,
        noise_std=noise,
    )


def _point_pixels(rows, cols, shape) -> tuple[np.ndarray, np.ndarray]:
    """The pixel ``(row, col)`` indices of sub-pixel point positions, clipped to ``shape``."""
    return (np.clip(np.floor(rows).astype(np.int64), 0, shape[0] - 1), np.clip(np.floor(cols).astype(np.int64), 0, shape[1] - 1))


def _void_points(res: EdgeDepth, where: np.ndarray, reason: Reason, *, determinable_only: bool = False) -> None:
    """The edge points of ``res`` whose pixel lies in ``where`` (all, or the determinable ones) get ``reason`` and NaN, in place."""
    inv = res.inverse_depth
    void = where[_point_pixels(res.rows, res.cols, where.shape)]
    if determinable_only:
        void &= inv.reason == Reason.OK
    inv.reason[void] = reason
    inv.rho[void] = np.nan
    inv.rho_std[void] = np.nan


#: An image whose clipped share (pixels at its own highest or lowest value) differs from I3's by more than
#: this, with no exposure matched, is reported.
_CLIPPED_APART = 0.25


def _warn_if_clipped_apart(frames, applied) -> None:
    """Warn where an image of dynamic stereo's five clips far more (or less) of itself than ``I3`` and no exposure was matched.

    Its exposure could not be compared with ``I3``'s (too few unclipped
    pixels) or explained too little to undo: its intensities differ from
    ``I3``'s wherever one of them is clipped, and eq. 4 reads that as motion
    (``I2, I4`` three times brighter, 86 % clipped at 255: a median error of 11.4 %).
    """
    shares = [float(np.mean(top | bottom)) for top, bottom in (_plateaus(f) for f in frames)]
    apart = [k for k, (share, fit) in enumerate(zip(shares, applied)) if k != 2 and fit is None and abs(share - shares[2]) > _CLIPPED_APART]
    if apart:
        which = ", ".join(f"I{k + 1} ({100.0 * shares[k]:.0f} %)" for k in apart)
        warnings.warn(
            f"{which} clipped: pixels at {'its' if len(apart) == 1 else 'their'} highest or lowest value, against {100.0 * shares[2]:.0f} % of I3's; "
            "the exposures could not be matched, and the depths are wrong where one image is clipped; "
            "take the images at one exposure, without clipped highlights",
            UserWarning,
            stacklevel=3,
        )


def _warn_if_mostly_behind(inv: InverseDepth, order_hint: str, delta_vn, delta_vn_std) -> None:
    """Warn when most determinable points come out behind the camera (a sign mistake), or show no relative motion.

    A point whose relative normal flow ``delta_vn`` lies within 2 ``delta_vn_std``
    of 0 is no evidence of a sign: where most ``NOT_POSITIVE`` points are such,
    the images show no relative motion (the same image five times, a rig
    standing still) or the scene is at infinity.
    """
    reason = inv.reason
    behind = int(np.count_nonzero(reason == Reason.NOT_POSITIVE))
    ahead = int(np.count_nonzero(reason == Reason.OK))
    if behind + ahead >= _ORDER_CHECK_MIN_POINTS and behind > ahead:
        with np.errstate(invalid="ignore"):
            still = np.abs(delta_vn) <= 2.0 * np.asarray(delta_vn_std)
        idle = int(np.count_nonzero(still & (reason == Reason.NOT_POSITIVE)))
        if idle > behind - idle:
            warnings.warn(
                f"{behind} of {behind + ahead} determinable edge points have a negative inverse depth or none (given NaN with reason"
                f" NOT_POSITIVE), {idle} of them no relative motion at all (relative normal flow within 2 std of 0): do the images"
                " differ (not one image given twice), did the cameras move relative to each other as the rig says, is the scene within range?",
                UserWarning,
                stacklevel=3,
            )
            return
        warnings.warn(
            f"{behind} of {behind + ahead} determinable edge points have a negative inverse depth "
            f"(behind the camera; given NaN with reason NOT_POSITIVE); {order_hint}",
            UserWarning,
            stacklevel=3,
        )


#: The differential method's range: the three-frame stencil follows a point's
#: displacement across a triple up to about 2 px (beyond, depth errors grow to tens
#: of percent at 4 px; the measured flow itself saturates near 4 px). A median
#: displacement of the edge points above it warns; the video pipeline bounds the
#: motion it leaves after warping by it.
_DIFFERENTIAL_RANGE_PX = 2.0
#: Start of that warning (video.py aggregates it over the frames of a run).
_DISPLACEMENT_WARNING = "the edge points move a median of"


def _median_displacement(mask, flow, span: float = 1.0) -> float:
    """Median ``|Vn| * span`` (px) over the edge points ``mask`` of a normal-flow map; 0 below 10 points."""
    shift = np.abs(flow[mask]) * span
    shift = shift[np.isfinite(shift)]
    return float(np.median(shift)) if shift.size >= _ORDER_CHECK_MIN_POINTS else 0.0


def _depth_bearing_mask(res: EdgeDepth) -> np.ndarray:
    """Mask (the shape of ``res.selection.mask``) of the edge points of ``res`` that eq. 4 could solve (``OK``, ``NOT_POSITIVE`` or ``UNCERTAIN``).

    The edges parallel to the motion do not move: counted in, they hid a
    displacement beyond the stencil's range at the points that carry a depth
    (a scene two-thirds edges along the motion: 5 px across I1..I3 at the
    depth-bearing points, a median of 1.2 px over all edge points, no warning
    and depths 12-30 % off).
    """
    mask = np.zeros(res.selection.mask.shape, bool)
    solved = np.isin(res.inverse_depth.reason, (Reason.OK, Reason.NOT_POSITIVE, Reason.UNCERTAIN))
    mask[_point_pixels(res.rows[solved], res.cols[solved], mask.shape)] = True
    return mask


def _warn_if_beyond_differential_range(mask, triples) -> None:
    """Warn when the edge points (``mask``: those that carry a depth, :func:`_depth_bearing_mask`) move more than the stencil follows across a triple.

    ``triples`` holds ``(name, normal flow map, time span of the triple)``;
    the displacement is ``|Vn| * span`` (px).
    """
    worst = None
    for name, flow, span in triples:
        median = _median_displacement(mask, flow, span)
        if median > _DIFFERENTIAL_RANGE_PX and (worst is None or median > worst[1]):
            worst = (name, median)
    if worst is not None:
        warnings.warn(
            f"{_DISPLACEMENT_WARNING} {worst[1]:.1f} px across the {worst[0]} (its measured normal flow), beyond the"
            " differential method's range of about 2 px: depths are wrong by up to tens of percent (at 4 px); use frames"
            " closer together or downsample the images (nfdepth video: leave --levels at its default)",
            UserWarning,
            stacklevel=3,
        )


def _check_min_size(name: str, shape) -> None:
    if min(shape) < 3:
        msg = f"{name} must be at least 3x3 pixels, got shape {shape}"
        raise ValueError(msg)


#: Edge points closer to the image border than this many sigma are not selected: the smoothing
#: reflects the frames there, and the mirror image moves the other way. Measured on a step edge
#: moving 0.5 px a frame (sigma 2-3 px): depth 17-53 % low at 0.5-1 sigma from the border, 3-8 %
#: at 1.5, 0.3-0.9 % at 2, none from 2.5 on (the standard deviation covered none of it).
BORDER_SIGMAS = 2.5


def _border_px(sigma_px: float) -> int:
    """How far from the border edge points are selected: :data:`BORDER_SIGMAS` sigma, at least 2 px."""
    return max(2, math.ceil(BORDER_SIGMAS * sigma_px))


def _check_sigma_fits(sigma_px: float, shape) -> None:
    """Refuse a ``sigma_px`` whose border (:func:`_border_px`) leaves no cell of an image of ``shape`` for edge points."""
    widest = (min(shape) - 2) // 2  # the cells, one fewer than the pixels, keep one inside 2 * border
    border = _border_px(sigma_px)
    if border > max(widest, 2):
        msg = (
            f"sigma_px = {sigma_px:g} px leaves no edge point in images of {shape[1]}x{shape[0]} px: they are taken "
            f"{BORDER_SIGMAS:g} sigma_px ({border} px) from the border, where the smoothing reaches past it; expected at "
            f"most {widest / BORDER_SIGMAS:.3g} px"
        )
        raise ValueError(msg)


def _edge_options(min_gradient, max_corner_ratio, corner_window_px, sigma_px) -> dict:
    """Options of :func:`select_edge_points`; the corner window defaults to 2 sigma, the border to :data:`BORDER_SIGMAS` sigma (at least 2 px)."""
    window = corner_window_px if corner_window_px is not None else max(2.0 * sigma_px, 1.0)
    border = _border_px(sigma_px)
    return {"min_gradient": min_gradient, "max_corner_ratio": max_corner_ratio, "corner_window_px": window, "border_px": border}


def _check_camera(camera, shape):
    if not isinstance(camera, PinholeCamera):
        msg = f"camera must be a nfdepth.PinholeCamera, got {type(camera).__name__}"
        raise TypeError(msg)
    if camera.shape != shape:
        msg = f"camera image size {camera.shape} (rows, cols) does not match the frames' shape {shape}"
        raise ValueError(msg)


def dynamic_stereo(
    frames,
    *,
    camera: PinholeCamera,
    relative_motion: RigidMotion,
    frame_interval: float = 1.0,
    sigma_px: float = 3.0,
    stencil: str = "matched",
    min_gradient: float | None = None,
    max_corner_ratio: float = 0.05,
    corner_window_px: float | None = None,
    min_cos: float = 0.25,
    max_rel_std: float | None = None,
    noise_std: float | None = None,
    match_exposure: bool = True,
    dtype=np.float32,
) -> EdgeDepth:
    """Depth from the five-image dynamic stereo sequence (paper Fig. 3, eq. 4).

    Parameters
    ----------
    frames : sequence of 5 ndarray, shape (H, W)
        ``I1 ... I5`` at equal time steps: ``I1, I3, I5`` from the moving
        camera, ``I2, I3, I4`` from the stationary one (``I3`` shared).
    camera : PinholeCamera
        Intrinsics shared by both cameras (their image planes coincide at I3).
    relative_motion : RigidMotion
        ``(V_m - V_s, Omega_m - Omega_s)``: the scene's motion relative to
        the moving camera minus that relative to the stationary one, per unit
        time. A moving camera translating by ``T`` gives ``V = -T``.
    frame_interval : float
        Time between consecutive images ``I_k`` and ``I_k+1``.
    sigma_px : float
        Gaussian smoothing (px). Below ``MIN_SIGMA_PX`` (1.5 px) a warning:
        the stencil's error on barely smoothed edges outgrows its error bar.
        Edge points are taken ``BORDER_SIGMAS`` (2.5) sigma from the border:
        a ``sigma_px`` that leaves none is refused.
    stencil : {"matched", "simpson", "paper"}
        Gradient stencil (:mod:`nfdepth.normal_flow`).
    min_gradient, max_corner_ratio, corner_window_px
        Edge-point rules (:func:`nfdepth.edges.select_edge_points`);
        ``corner_window_px`` defaults to ``2 * sigma_px`` (at least 1 px):
        the smoothing spreads a corner over about two sigma.
    min_cos, max_rel_std : float
        Determinability threshold and optional bound on the relative
        uncertainty of depth (:func:`nfdepth.depth.solve_inverse_depth`).
    noise_std : float, optional
        Image noise (grey levels); estimated from the frames when omitted.
    dtype : numpy dtype
        ``float32`` (default) or ``float64``: the arithmetic's precision.
    match_exposure : bool
        Map each image onto ``I3``'s exposure first where it differs
        (:func:`nfdepth._exposure.match_nearby_exposures`: two cameras, or
        automatic exposure between frames). Eq. 4 reads every intensity
        difference as motion: on the paper's pyramid (experiment 1), ``I4``
        5 % brighter than the rest took the median depth error from 0.16 %
        to 67 %, and ``I2, I4`` at ``1.2 I + 10`` to 1.5 %. Edge points
        within twice ``sigma_px`` of a highlight that one image's exposure
        clipped and ``I3``'s did not are ``UNCERTAIN``.

    Returns
    -------
    EdgeDepth
        ``flows`` holds ``"moving"``, ``"stationary"`` and ``"relative"``;
        ``exposure`` what was matched.
    """
    dt = float_dtype(dtype)
    frames = as_frames("frames", frames, 5, dtype=dt)
    _check_min_size("frames", frames[0].shape)
    _check_camera(camera, frames[0].shape)
    relative_motion = _motion("relative_motion", relative_motion)
    if relative_motion.is_pure_rotation:
        msg = (
            f"relative_motion has no translation (translation={relative_motion.translation.tolist()}, "
            "a pure rotation): depth is undeterminable; the cameras need a non-zero relative translation"
        )
        raise ValueError(msg)
    step = check_frame_interval("frame_interval", frame_interval)
    if 2.0 * step > UNIT_SCALE_RANGE[1]:  # the moving camera's triple spans two intervals
        msg = (
            f"frame_interval = {step:g} is outside {UNIT_SCALE_RANGE[0]:g}..{0.5 * UNIT_SCALE_RANGE[1]:g} (the moving camera's "
            "frames 1, 3, 5 are two intervals apart): give times in a unit that keeps it in that range (e.g. frames)"
        )
        raise ValueError(msg)
    sigma_px = check_scale_px("sigma_px", sigma_px)
    _check_sigma_fits(sigma_px, frames[0].shape)
    if sigma_px < MIN_SIGMA_PX:
        warnings.warn(
            f"sigma_px = {sigma_px:g} px smooths the images too little for the three-image stencil: its error on sharp edges"
            f" outgrows the error bar (the paper's pyramid: depth 20 % off at 0 px, 2.6 % at 1 px, 0.3 % at 3); use {MIN_SIGMA_PX:g} px or more",
            UserWarning,
            stacklevel=2,
        )
    taken, exposure = frames, None
    if check_bool("match_exposure", match_exposure):
        frames, applied = match_nearby_exposures(frames, middle=2)
        frames = [np.asarray(f, dt) for f in frames]
        exposure = applied if any(a is not None for a in applied) else None
        _warn_if_clipped_apart(taken, applied)
    noise = _noise_level(noise_std, frames)
    s = [gaussian_smooth(f, sigma_px=sigma_px) for f in frames]
    moving = gradients([s[0], s[2], s[4]], frame_interval=2.0 * step, stencil=stencil)
    stationary = gradients([s[1], s[2], s[3]], frame_interval=step, stencil=stencil)
    vn_m = moving.normal_flow
    vn_s = stationary.normal_flow
    delta = vn_m - vn_s
    std = np.hypot(
        _vn_std(moving, vn_m, noise, sigma_px=sigma_px, stencil=stencil, dt=2.0 * step),
        _vn_std(stationary, vn_s, noise, sigma_px=sigma_px, stencil=stencil, dt=step),
    )
    shared = GradientField(
        0.5 * (moving.grad_col + stationary.grad_col),
        0.5 * (moving.grad_row + stationary.grad_row),
        moving.grad_t - stationary.grad_t,
    )
    edge_options = _edge_options(min_gradient, max_corner_ratio, corner_window_px, sigma_px)
    result = _edge_result(
        camera=camera,
        relative_motion=relative_motion,
        shared=shared,
        smoothed_middle=s[2],
        delta_vn=delta,
        delta_vn_std=std,
        flows={"moving": vn_m, "stationary": vn_s, "relative": delta},
        noise=noise,
        edge_options=edge_options,
        min_cos=min_cos,
        max_rel_std=max_rel_std,
        order_hint="are the frames in time order I1..I5, and is relative_motion's sign right (V = -T for a camera moving by T)?",
    )
    if exposure is not None:
        reach = int(np.ceil(2.0 * sigma_px))  # the smoothing spreads a plateau's edge this far
        apart = np.zeros(frames[2].shape, bool)
        for k, fit in enumerate(exposure):
            if fit is not None:
                apart |= clipped_apart(taken[2], taken[k], fit, reach)
        if apart.any():  # the edge points beside a highlight one image's exposure clipped: wrong flows, UNCERTAIN
            _void_points(result, apart, Reason.UNCERTAIN, determinable_only=True)
        result = replace(result, exposure=exposure)
    triples = [("moving camera's frames (I1, I3, I5)", vn_m, 2.0 * step), ("stationary camera's frames (I2, I3, I4)", vn_s, step)]
    _warn_if_beyond_differential_range(_depth_bearing_mask(result), triples)
    return result


#: Largest normal displacement (px) a triple of :func:`static_stereo_edges` measures
#: beside the nearest one: beyond it the three-frame stencil is biased.
_MAX_TRIPLE_MOTION_PX = 1.25


def static_stereo_edges(
    views,
    *,
    camera: PinholeCamera,
    baseline: float,
    direction=(1.0, 0.0, 0.0),
    reference: int | None = None,
    sigma_px: float = 2.0,
    stencil: str = "matched",
    min_gradient: float | None = None,
    max_corner_ratio: float = 0.05,
    corner_window_px: float | None = None,
    min_cos: float = 0.25,
    max_rel_std: float | None = None,
    noise_std: float | None = None,
    max_span: int | None = None,
    dtype=np.float32,
) -> EdgeDepth:
    """Depth at edge points from equally spaced static views (paper section 2.3).

    Parameters
    ----------
    views : sequence of >= 3 ndarray, shape (H, W)
        Views taken at positions ``P_k = P_0 + k * baseline * direction``
        (camera moving toward ``direction`` from first to last), same
        orientation.
    camera : PinholeCamera
        Intrinsics (shared).
    baseline : float
        Distance between neighbouring views (scene units, > 0).
    direction : 3 floats
        Direction of travel in the camera frame (normalised here);
        ``(1, 0, 0)`` for a horizontal row, ``(0, 1, 0)`` for a vertical one.
    reference : int, optional
        Index of the view that gets depth; default the middle view. It needs
        a neighbour on each side.
    max_span : int, optional
        Use the symmetric triples ``(ref - k, ref, ref + k)`` for
        ``k = 1 .. max_span`` (default: all that fit) and fuse their inverse
        depths by weighted least squares (:func:`nfdepth.depth.fuse_inverse_depth`).
        At each point a triple ``k > 1`` counts only while the point's
        displacement in it, ``k`` times its normal flow per step (measured by
        the nearest triple), stays within 1.25 px: beyond it the three-frame
        stencil is biased, and the farther triples, which weigh ``k**2`` more,
        would carry that bias into the fused depth and an error bar blind
        to it (7 views at 0.75-1 px per step: median error 2.4-3.8 %, 6-11
        times the std, without this rule; 0.5-1.0 % and 0.75-0.9 with it).
    sigma_px, stencil, min_gradient, max_corner_ratio, corner_window_px, min_cos, max_rel_std, noise_std, dtype
        As for :func:`dynamic_stereo`, but ``sigma_px`` defaults to 2 px
        (3 there) and ``max_corner_ratio`` to 0.05 as there; no exposure
        matching (the views of a static row: :func:`nfdepth.static_stereo`
        matches them).

    Returns
    -------
    EdgeDepth
        With ``flows["relative"]`` the normal flow of the ``k = 1`` triple.
    """
    dt = float_dtype(dtype)
    views = as_frames("views", views, min_count=3, dtype=dt)
    _check_min_size("views", views[0].shape)
    _check_camera(camera, views[0].shape)
    baseline = check_within("baseline", baseline, advice="give it in a unit that keeps it there (inverse depths are per unit of baseline)")
    direction = as_vector3("direction", direction)  # numbers: bools, text and complex refused
    if not np.any(direction):
        msg = f"direction must be 3 finite numbers, not all zero, got {direction.tolist()}"
        raise ValueError(msg)
    direction = direction / _magnitude(direction)  # (safe for components of 1e-300 or 1e300: only the direction counts)
    n = len(views)
    if reference is not None and (isinstance(reference, bool) or not isinstance(reference, (int, np.integer))):
        msg = f"reference must be an int view index (1..{n - 2}) or None, got {reference!r}"
        raise TypeError(msg)
    ref = n // 2 if reference is None else int(reference)
    if not 1 <= ref <= n - 2:
        msg = f"reference must index a view with a neighbour on each side (1..{n - 2}), got {reference!r}"
        raise ValueError(msg)
    span = min(ref, n - 1 - ref)
    if max_span is not None:
        if isinstance(max_span, bool) or not isinstance(max_span, (int, np.integer)):
            msg = f"max_span must be an int >= 1 or None, got {max_span!r}"
            raise TypeError(msg)
        if int(max_span) < 1:
            msg = f"max_span must be >= 1, got {max_span!r}"
            raise ValueError(msg)
        span = min(span, int(max_span))
    sigma_px = check_scale_px("sigma_px", sigma_px)
    _check_sigma_fits(sigma_px, views[0].shape)
    noise = _noise_level(noise_std, views)
    s = [gaussian_smooth(v, sigma_px=sigma_px) for v in views]
    relative_motion = RigidMotion(translation=-baseline * direction)
    fields = [gradients([s[ref - k], s[ref], s[ref + k]], frame_interval=float(k), stencil=stencil) for k in range(1, span + 1)]
    flows = [f.normal_flow for f in fields]
    stds = [_vn_std(f, vn, noise, sigma_px=sigma_px, stencil=stencil, dt=float(k)) for k, (f, vn) in enumerate(zip(fields, flows), 1)]
    first = fields[0]
    shared = GradientField(
        np.mean([f.grad_col for f in fields], axis=0), np.mean([f.grad_row for f in fields], axis=0), first.grad_t
    )
    if span == 1:
        delta, std = flows[0], stds[0]
    else:
        # All triples measure the same flow per unit step; combine them with
        # inverse-variance weights (B is common, so this is the WLS of eq. 4).
        # Without image noise (std 0) every triple gets the same weight.
        # Triple k sees a point move by k times its flow per step: beyond about
        # 1 px the stencil is biased (the differential range), so there only
        # the nearer triples count (the first always does).
        reach = np.abs(flows[0])
        with np.errstate(invalid="ignore"):
            used = [f if k == 1 else np.where(k * reach <= _MAX_TRIPLE_MOTION_PX, f, np.nan) for k, f in enumerate(flows, 1)]
        ones = np.ones_like(flows[0])
        delta, fused_std, _ = fuse_inverse_depth(np.stack(used), 0.0, ones, np.stack(stds) if noise > 0 else ones)
        std = fused_std if noise > 0 else np.zeros_like(delta)
    edge_options = _edge_options(min_gradient, max_corner_ratio, corner_window_px, sigma_px)
    result = _edge_result(
        camera=camera,
        relative_motion=relative_motion,
        shared=shared,
        smoothed_middle=s[ref],
        delta_vn=delta,
        delta_vn_std=std,
        flows={"relative": flows[0]},
        noise=noise,
        edge_options=edge_options,
        min_cos=min_cos,
        max_rel_std=max_rel_std,
        order_hint="are the views in the wrong order? The camera must move toward `direction` from the first view to the last",
    )
    _warn_if_beyond_differential_range(_depth_bearing_mask(result), [("nearest views", flows[0], 1.0)])
    return result


__all__ += ["Reason"]
