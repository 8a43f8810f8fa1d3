"""Coarse to fine for a camera translating through a static scene (the video pipeline).

The paper's differential method sees image motions of up to about 1-2 px
per frame: beyond that the three-frame temporal derivative aliases and the
edge points' depths come out wrong by tens of percent, with no sign of it in
their uncertainty. For a triple of frames ``(k-1, k, k+1)`` of a camera
translating by ``T`` per frame (relative motion ``V = -T``, no rotation),
paper eq. 1 gives every point the image motion ``rho a(x)`` per frame, with
``rho = 1/Z`` and the known direction field

.. math::
    a(x) = f (V_X - x V_Z,\\; V_Y - y V_Z)

(px per frame per unit inverse depth), computed as ``a / (f |V|)`` so that
no unit or focal length can overflow float32. So:

1. :func:`dense_prior`: a dense inverse depth, coarse to fine. Gaussian
   pyramids (``cv2.pyrDown``) of the three frames; at each level, from zero
   at the coarsest, the outer frames are warped toward the middle one with
   the current estimate (``cv2.remap``), and the residual inverse depth is
   the weighted least-squares solution of the warped triple's brightness
   constancy ``I_t + rho' (grad I . a) = 0`` over a Gaussian window (a
   step of at most 1 px of motion, then a 5 x 5 median), three times per
   level; the estimate is then upsampled (inverse depth does not scale
   with the image).
2. :func:`warp_outer_frames`: the outer frames at full resolution, warped
   by the prior, so that the triple's remaining motion is the prior's error
   (sub-pixel where the prior holds).

Unequal steps (a camera that speeds up or slows down, a dropped frame, a
middle position off the line through its neighbours): each outer frame is
warped by its own displacement ``t_j = P_j - P_k`` (camera axes), so the
prior's motion ``rho A(x) (-t_j)`` leaves only its error in either frame. The
central difference of the warped frames then reads that error against the
central step ``T = (t_k+1 - t_k-1) / 2``, as with equal steps: the update's
gradient ``grad I . a`` and eq. 4's baseline are ``T``'s. A step along the
optical axis changes the point's depth in that frame to ``Z - t_jz``, so
the warp is eq. 1 for the finite step, ``rho A(x) (-t_j) / (1 - rho t_jz)``
(to first order, unequal steps along (1, 0, 1) left a median bias of up
to 2.7 %), and the residual bound counts the motion of the outer frame
farthest from the middle one (:func:`outer_reach`). Warped by ``+/- T``
instead, the outer frames kept ``(t_k+1 + t_k-1) / 2`` of the prior's motion
each, so the stencil's temporal derivative sat that far from its spatial
gradient (Middlebury 2005 rows with steps of one and two views: median
error 0.56-0.85 % -> 2.3-3.9 %).
3. :func:`edge_depth_coarse_to_fine`: the paper's measurement
   (:func:`nfdepth.pipelines.static_stereo_edges`, eq. 4) on the warped
   triple gives the residual relative normal flow at the edge points; the
   prior's own normal flow ``B rho_prior`` is added back before eq. 4 is
   solved, so reason codes and uncertainties are those of the total. Points
   whose residual motion exceeds ``max_residual_px`` (the prior failed
   there) are ``UNCERTAIN``, and so are points where the prior's motion
   varies by more than ``edge_step_px`` px within 4 px: beside a depth
   step one side of the edge is hidden in an outer frame and the truth of
   the edge's pixel may be either surface, and there (and across a sharp
   ridge) the smooth prior is least accurate. A plane slanted by more than
   1/8 px of motion per px loses its points too. Points whose warp reads
   outside an outer frame are ``NO_DATA``.
"""

from __future__ import annotations

import dataclasses
import warnings

import cv2
import numpy as np

from ._resample import remap_linear, sample_points
from .camera import PinholeCamera, RigidMotion, _magnitude
from .depth import Reason, solve_inverse_depth
from .normal_flow import gaussian_smooth
from .pipelines import _noise_level, _point_pixels, static_stereo_edges

_ITERATIONS = 3  # warp-and-update passes per pyramid level
_SIGMA_PX = 1.0  # smoothing at every level before the dense update
_WINDOW_PX = 4.0  # std of the dense update's Gaussian window (px of that level)
_RIDGE = 1e-3  # of the median window information: textureless windows keep their estimate
_STEP_REACH_PX = 4  # the depth-step test looks this far either side of an edge point (the prior's window is 4 px)


def flow_directions(camera: PinholeCamera, translation, shape, *, scale: float = 1.0):
    """``a(x) / (f |V|)`` at the pixel centres of an image ``shape`` whose pixel ``(i, j)`` is full-resolution ``(scale i, scale j)``.

    ``translation`` is the relative motion ``V`` per frame (``-T`` for a
    camera moving by ``T``). Returns ``(a_col, a_row)``, float32, in px of
    that image per px of the full-resolution image: dividing by ``f |V|``
    keeps them near 1 whatever the units (the inverse depths of this module
    are ``rho f |V|``, the motion per frame in full-resolution px at the
    principal point of a lateral step).
    """
    h, w = shape
    x = (np.arange(w, dtype=np.float64) * scale - camera.cx_px) / camera.focal_px
    y = (np.arange(h, dtype=np.float64) * scale - camera.cy_px) / camera.focal_px
    vx, vy, vz = np.asarray(translation, dtype=float) / _magnitude(translation)
    a_col = np.broadcast_to((vx - x * vz) / scale, (h, w)).astype(np.float32)
    a_row = np.broadcast_to(((vy - y * vz) / scale)[:, None], (h, w)).astype(np.float32)
    return a_col, a_row


def outer_flow_directions(camera: PinholeCamera, translation, outer_steps, central_field, *, scale: float = 1.0):
    """Where frames ``k-1`` and ``k+1`` see a point, per unit of :func:`dense_prior`'s ``rho f |V|``: ``((a_col, a_row, k_z), (a_col, a_row, k_z))``.

    ``translation`` is the central relative motion ``V = -T`` and
    ``central_field`` its :func:`flow_directions` ``(a_col, a_row)`` at
    ``scale``. ``outer_steps`` holds the camera's displacement
    from the middle frame to each outer frame, ``(t_k-1, t_k+1)`` in the
    middle frame's axes; None means equal steps, ``(-T, T)``. Frame ``j``'s
    field is ``A(x) (-t_j) / (f |V|)``: ``-a`` and ``a`` for equal steps
    (exactly, so equal steps give the same warps as before), zero for an
    outer frame taken where the middle one was. ``k_z = t_jz / (f |V|)``:
    a point at ``rho f |V| = r`` moves by ``r a_j / (1 - r k_z)`` (eq. 1 for
    a finite step: its depth in frame ``j`` is ``Z - t_jz``).
    """
    a_col, a_row = central_field
    central = _magnitude(translation)
    if outer_steps is None:
        t_next = -np.asarray(translation, dtype=float)
        outer_steps = (-t_next, t_next)
        fields = [(-a_col, -a_row), (a_col, a_row)]
    else:
        fields = []
        for step in outer_steps:
            length = _magnitude(step)
            if length == 0.0:
                fields.append((np.zeros_like(a_col), np.zeros_like(a_row)))
                continue
            o_col, o_row = flow_directions(camera, -np.asarray(step, dtype=float), a_col.shape, scale=scale)
            ratio = np.float32(length / central)
            fields.append((o_col * ratio, o_row * ratio))
    # t_jz per unit of rho f |V|: the point's depth in frame j is Z - t_jz (its motion is rho a_j / (1 - rho t_jz))
    return tuple((*field, float(step[2]) / (camera.focal_px * central)) for field, step in zip(fields, outer_steps))


def outer_reach(translation, outer_steps) -> float:
    """The farthest outer frame's displacement over the central step ``|V|`` (1 for equal steps, more when the camera reverses)."""
    if outer_steps is None:
        return 1.0
    return max(_magnitude(step) for step in outer_steps) / _magnitude(translation)


def warp_outer_frames(frames, rho, directions, *, inside: bool = True):
    """Frames ``k-1`` and ``k+1`` resampled at ``x + rho a_j(x)`` (linear, border replicated), and where both reads lie inside.

    ``directions`` is :func:`outer_flow_directions`'s pair. Returns
    ``(before, after, inside)``; ``inside`` is None when not asked for.
    """
    h, w = rho.shape
    cols = np.arange(w, dtype=np.float32)[None, :]
    rows = np.arange(h, dtype=np.float32)[:, None]
    out, within = [], (np.ones((h, w), bool) if inside else None)
    map_c, map_r = np.empty((h, w), np.float32), np.empty((h, w), np.float32)
    for frame, (a_col, a_row, k_z) in zip((frames[0], frames[2]), directions):
        # the finite step's depth change (k_z = 0 for a sideways step: rho itself, bit for bit); a point
        # the outer camera passed (1 - rho k_z <= 0) is read as if 20 times nearer, an edge of the frame at most
        moved = rho if k_z == 0.0 else rho / np.maximum(np.float32(1.0) - rho * np.float32(k_z), np.float32(0.05))
        # x + rho a in float32, in place (no temporaries: fresh pages cost a fault each)
        np.add(cols, np.multiply(moved, a_col, out=map_c), out=map_c)
        np.add(rows, np.multiply(moved, a_row, out=map_r), out=map_r)
        out.append(remap_linear(frame, map_c, map_r))
        if inside:
            within &= (map_c >= 0) & (map_c <= w - 1) & (map_r >= 0) & (map_r <= h - 1)
    return out[0], out[1], within


def _motion_limit(a_col, a_row, directions, equal_steps: bool) -> np.ndarray:
    """Largest update of ``rho f |V|`` that moves a point by 1 px of its level, in the middle or the outer frame that moves most."""
    central = np.hypot(a_col, a_row)
    # equal steps: the outer fields are -a and a, whose lengths are the central one's bit for bit
    fastest = central if equal_steps else np.maximum(np.hypot(*directions[0][:2]), np.hypot(*directions[1][:2]))
    return (1.0 / np.maximum(np.maximum(central, fastest), np.float32(1e-12))).astype(np.float32)


def dense_prior(frames, camera: PinholeCamera, translation, *, levels: int, outer_steps=None) -> np.ndarray:
    """Dense ``rho f |V|`` of the middle frame, coarse to fine (step 1 of the module docstring); float32 (H, W).

    ``translation`` is the central relative motion ``V = -T``; ``outer_steps``
    the outer frames' displacements when the steps are unequal
    (:func:`outer_flow_directions`).
    """
    pyramid = [[np.asarray(f, dtype=np.float32) for f in frames]]
    for _ in range(levels - 1):
        pyramid.append([cv2.pyrDown(f) for f in pyramid[-1]])
    rho = None
    for level in range(levels - 1, -1, -1):
        smoothed = [gaussian_smooth(f, sigma_px=_SIGMA_PX) for f in pyramid[level]]
        h, w = smoothed[1].shape
        a_col, a_row = flow_directions(camera, translation, (h, w), scale=2.0**level)
        directions = outer_flow_directions(camera, translation, outer_steps, (a_col, a_row), scale=2.0**level)
        # a step moves a point by at most 1 px of this level (in the outer frame that moves most)
        limit = _motion_limit(a_col, a_row, directions, outer_steps is None)
        rho = np.zeros((h, w), np.float32) if rho is None else cv2.resize(rho, (w, h), interpolation=cv2.INTER_LINEAR)
        g_col = cv2.Sobel(smoothed[1], cv2.CV_32F, 1, 0, ksize=1, borderType=cv2.BORDER_REFLECT) * np.float32(0.5)
        g_row = cv2.Sobel(smoothed[1], cv2.CV_32F, 0, 1, ksize=1, borderType=cv2.BORDER_REFLECT) * np.float32(0.5)
        g = g_col * a_col + g_row * a_row  # brightness change per unit inverse depth
        den = gaussian_smooth(g * g, sigma_px=_WINDOW_PX)
        positive = den[den > 0]
        ridge = np.float32(_RIDGE * float(np.median(positive))) if positive.size else np.float32(1.0)
        den += ridge
        low = -limit
        for _ in range(_ITERATIONS):
            before, after, _ = warp_outer_frames(smoothed, rho, directions, inside=False)
            # the same float32 operations as g (0.5 (after - before)), -num / den, clipped, rho + step; in place
            change = np.subtract(after, before, out=after)
            change *= np.float32(0.5)
            change *= g
            num = gaussian_smooth(change, sigma_px=_WINDOW_PX)
            step = np.negative(num, out=num)
            step /= den
            np.clip(step, low, limit, out=step)
            step += rho
            rho = cv2.medianBlur(step, 5)
    return rho


def coarse_motion_px(window, camera: PinholeCamera, translation, mask, *, outer_steps=None) -> float:
    """Median image motion (full-resolution px per central step) at the cells ``mask`` of the middle frame, or 0 below 10 cells.

    From :func:`dense_prior` on the frames reduced to a quarter (at most;
    the shorter side kept at 32 px or more): the single level's own normal
    flow aliases beyond about 2 px and reads a motion of 10 px as 1-2 px,
    so it cannot say that it was too fast.
    """
    down = 0
    while down < 2 and (min(window[1].shape) >> (down + 1)) >= 32:
        down += 1
    small = [np.asarray(f, np.float32) for f in window]
    for _ in range(down):
        small = [cv2.pyrDown(f) for f in small]
    s = 2.0**down
    h, w = small[1].shape
    cam = camera.reduced(s, (h, w))
    from .stereo import auto_levels

    prior = dense_prior(small, cam, translation, levels=auto_levels((h, w)), outer_steps=outer_steps)
    motion = prior * np.hypot(*flow_directions(cam, translation, (h, w))) * np.float32(s)
    rows, cols = np.nonzero(mask)
    at = motion[np.minimum(rows // int(s), h - 1), np.minimum(cols // int(s), w - 1)]
    at = np.abs(at[np.isfinite(at)])
    return float(np.median(at)) if at.size >= 10 else 0.0


def _step_span(motion: np.ndarray, reach_px: int) -> np.ndarray:
    """Largest minus smallest ``motion`` within ``reach_px`` px (a square window): the step around each pixel."""
    kernel = np.ones((2 * reach_px + 1, 2 * reach_px + 1), np.uint8)
    return cv2.dilate(motion, kernel, borderType=cv2.BORDER_REPLICATE) - cv2.erode(motion, kernel, borderType=cv2.BORDER_REPLICATE)


def edge_depth_coarse_to_fine(
    window,
    *,
    camera: PinholeCamera,
    baseline: float,
    direction,
    levels: int,
    max_residual_px: float = 1.0,
    edge_step_px: float = 1.0,
    outer_steps=None,
    **edge_options,
):
    """Paper eq. 4 at the edge points of the middle frame, on the triple warped by :func:`dense_prior` (module docstring).

    ``window`` holds three float32 frames; ``baseline`` and ``direction``
    (unit, camera axes) are the camera's central step per frame, as for
    :func:`nfdepth.pipelines.static_stereo_edges`, which gets
    ``edge_options``; ``outer_steps`` the outer frames' own displacements
    from the middle one when the steps are unequal (None: ``-/+`` the
    central step). Edge points where the prior's motion varies by more
    than ``edge_step_px`` px within :data:`_STEP_REACH_PX` px are
    ``UNCERTAIN`` (0: no test). Returns its :class:`~nfdepth.pipelines.EdgeDepth`
    with ``delta_vn`` and ``inverse_depth`` of the total motion and
    ``flows["residual"]``, the warped triple's normal flow.
    """
    # the noise of the frames as taken: warping interpolates the outer ones and hides part of it
    # (estimated on the warped triple, the std came out 1.6-2.6 times too small)
    edge_options = {**edge_options, "noise_std": _noise_level(edge_options.get("noise_std"), window)}
    direction = np.asarray(direction, dtype=float)
    translation = -baseline * direction
    prior = dense_prior(window, camera, translation, levels=levels, outer_steps=outer_steps)  # rho f |V|
    a_col, a_row = flow_directions(camera, translation, prior.shape)
    directions = outer_flow_directions(camera, translation, outer_steps, (a_col, a_row))
    before, after, inside = warp_outer_frames(window, prior, directions)
    with warnings.catch_warnings():
        # the residual's sign is the prior's error: negative values are no mistake
        warnings.filterwarnings("ignore", message=r".* determinable edge points have a negative inverse depth", category=UserWarning)
        res = static_stereo_edges([before, window[1], after], camera=camera, baseline=baseline, direction=direction, **edge_options)
    relative_motion = RigidMotion(translation=translation)
    # B rho_prior, with rho_prior = prior / (f |V|) (B is f |V| times a unit vector's normal component)
    b_unit = res.inverse_depth.b / (camera.focal_px * _magnitude(translation))
    total = res.delta_vn + b_unit * sample_points(prior, res.rows, res.cols)
    inv = solve_inverse_depth(
        total,
        camera=camera,
        rows=res.rows,
        cols=res.cols,
        alpha=res.alpha,
        relative_motion=relative_motion,
        delta_vn_std=res.delta_vn_std,
        min_cos=edge_options.get("min_cos", 0.25),
    )
    ok = inv.reason == Reason.OK
    ii, jj = _point_pixels(res.rows, res.cols, prior.shape)
    outside = ~inside[ii, jj]
    inv.reason[ok & outside] = Reason.NO_DATA
    # the residual is per central step; the outer frame farthest from the middle one moved reach times as far
    reach = outer_reach(translation, outer_steps)
    inv.reason[(inv.reason == Reason.OK) & ~(np.abs(res.delta_vn) * reach <= max_residual_px)] = Reason.UNCERTAIN
    if edge_step_px > 0:
        # beside a depth step one side of the edge is hidden in an outer frame and the
        # truth of the edge's pixel may be either surface; there the smooth prior errs most
        motion = prior * np.hypot(a_col, a_row)  # px per frame
        inv.reason[(inv.reason == Reason.OK) & (_step_span(motion, _STEP_REACH_PX)[ii, jj] > edge_step_px)] = Reason.UNCERTAIN
    bad = inv.reason != Reason.OK
    inv.rho[bad] = np.nan
    inv.rho_std[bad] = np.nan
    return dataclasses.replace(res, delta_vn=total, inverse_depth=inv, flows={"residual": res.flows["relative"]})
