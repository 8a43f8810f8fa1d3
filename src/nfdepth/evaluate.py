"""nfdepth against ground truth and against its peers on the real data sets.

:func:`disparity_errors` scores one disparity map (with the floor that the
truth's own rounding sets, :func:`rounding_median_rel`, and bad-1px split
at and away from the truth's depth steps, :func:`depth_step_mask`);
:func:`photometric_truth_offset` checks a truth against the images, with no
stereo method; :func:`evaluate_scene`
runs nfdepth's :func:`nfdepth.stereo.static_stereo` and the peers of
:mod:`nfdepth.baselines` on one :class:`nfdepth.datasets.MultiViewScene`;
:func:`evaluate_dataset` does it for several scenes; :func:`render_markdown`
turns the results into a table and :func:`error_map_png` draws ``|error|``.

What is compared
----------------
* ``nfdepth`` **edges**: the paper's sparse output, the pixels of
  ``StereoResult.edge_mask`` with a finite disparity; ``density`` is their
  share of the ground-truth pixels.
* ``nfdepth`` **dense**: every finite pixel of ``StereoResult.disparity``.
* each peer **at nfdepth's edge points** (the same pixels; ``density`` is the
  share of those points where the peer gives a value) and **dense**.
* ``nfdepth`` **at the edge points a peer shares** (``"nfdepth_at_shared_edges"``
  of the peer; printed as ``nfdepth (edges & PEER)`` when it is fewer points
  than all of nfdepth's): both on exactly the same points. A peer that
  gives no value at some of them (SGBM's uniqueness, left-right and speckle
  tests, the border its disparity range cannot reach) is otherwise scored
  on another point set than nfdepth.

Peers (see :mod:`nfdepth.baselines`): ``sgbm`` (OpenCV semi-global matching
on the reference and its neighbour, one step of baseline; ``numDisparities``
from the ground truth's largest disparity, as a user who knows the scene's
depth range would set it), ``bm`` (OpenCV block matching, same pair),
``waxman_sinha`` (relative optical flow, paper eq. 2, DIS flow to every view,
least squares) and ``waxman_sinha_farneback`` (the same with Farnebäck flow).
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from ._validate import (
    _check_number,
    check_int,
    check_nonnegative_finite,
    check_positive_finite,
    check_threshold,
    check_within,
)

__all__ = [
    "METHODS",
    "DEFAULT_METHODS",
    "disparity_errors",
    "GAUSSIAN_MEDIAN_Z",
    "rounding_median_rel",
    "depth_step_mask",
    "photometric_truth_offset",
    "select_views",
    "view_size_problems",
    "evaluate_scene",
    "resolve_dataset",
    "evaluate_dataset",
    "evaluation_rows",
    "render_markdown",
    "error_map_png",
    "to_jsonable",
]

METHODS = ("nfdepth", "sgbm", "bm", "waxman_sinha", "waxman_sinha_farneback")
DEFAULT_METHODS = ("nfdepth", "sgbm", "waxman_sinha")
_ERROR_KEYS = (
    "points", "density", "median_rel", "p90_rel", "bad_1px", "bad_0_5px", "mae_px", "bias_px", "truth_rounding_rel",
    "median_z", "rms_ratio", "within_3std", "near_steps_share", "bad_1px_near_steps", "bad_1px_off_steps",
)
#: median |z| of a standard normal: what ``median_z`` of a calibrated error bar reads
GAUSSIAN_MEDIAN_Z = 0.6744897501960817


# ------------------------------------------------------------------ one map


def disparity_errors(estimate, truth, *, mask=None, truth_step_px=None, near_steps=None, uncertainty=None) -> dict:
    """Error figures of a disparity map against the ground truth.

    Parameters
    ----------
    estimate, truth : array_like, shape (H, W)
        Disparity (px); NaN (or inf) where unknown.
    mask : array_like of bool, shape (H, W), optional
        Only these pixels count (also for ``density``).
    truth_step_px : float, optional
        The step in which the truth is stored or labelled
        (:attr:`nfdepth.datasets.MultiViewScene.truth_step_px`); gives
        ``truth_rounding_rel``.
    near_steps : array_like of bool, shape (H, W), optional
        Pixels near the truth's depth steps (:func:`depth_step_mask`); gives
        the bad-1px rate at and away from them.
    uncertainty : array_like, shape (H, W), optional
        The estimate's standard deviation (px, ``StereoResult.uncertainty``);
        gives ``median_z``, ``rms_ratio`` and ``within_3std``.

    Returns
    -------
    dict
        ``points``: pixels where both are finite (and in ``mask``);
        ``truth_points``: pixels where the truth is finite (and in ``mask``);
        ``density``: ``points / truth_points``;
        ``median_rel``, ``p90_rel``: median and 90th percentile of
        ``|d - d_true| / |d_true|`` (pixels with ``d_true == 0`` left out);
        ``bad_1px``, ``bad_0_5px``: fraction of points with
        ``|d - d_true| > 1`` / ``> 0.5`` px; ``mae_px``: mean ``|d - d_true|``;
        ``bias_px``: median of ``d - d_true`` (signed: > 0 is an estimate
        above the truth); ``truth_rounding_rel``: the ``median_rel`` that a
        perfect estimate is expected to score on the same points against a
        truth rounded to ``truth_step_px`` (:func:`rounding_median_rel`),
        NaN without a step; ``median_z``: the median of ``|d - d_true| /
        sqrt(std**2 + truth_step_px**2 / 12)`` (the truth's rounding, a
        uniform error, in quadrature; 0 without a step), which reads
        :data:`GAUSSIAN_MEDIAN_Z` (0.674) where the error bar is calibrated and
        the errors Gaussian, more where it is too narrow; ``rms_ratio``: the
        RMS of ``|d - d_true|`` over the RMS of that scale, 1 where the error
        bar is calibrated whatever the errors' distribution (the figure to
        read where they are two-valued, small or a whole depth step, and the
        median reads low), more where it is too narrow; and
        ``within_3std``: the share of those ratios at most 3 (99.7 % for
        Gaussian errors), over the points with a finite std, NaN without
        ``uncertainty``; ``near_steps_share``: the share of points in
        ``near_steps``, ``bad_1px_near_steps`` / ``bad_1px_off_steps``: the
        bad-1px rate of the points in / outside it (NaN without
        ``near_steps`` or for an empty part).
        Figures of an empty set are NaN (``density`` too when the truth is
        empty).
    """
    if truth_step_px is not None:
        truth_step_px = _check_number("truth_step_px", truth_step_px, "a finite number >= 0 or None", lambda x: math.isfinite(x) and x >= 0)
    est = np.asarray(estimate, dtype=np.float64)
    tru = np.asarray(truth, dtype=np.float64)
    if est.shape != tru.shape:
        msg = f"estimate and truth must have the same shape, got {est.shape} and {tru.shape}"
        raise ValueError(msg)
    has_truth = np.isfinite(tru)
    if mask is not None:
        has_truth &= _bool_map("mask", mask, tru.shape)
    if near_steps is not None:
        near_steps = _bool_map("near_steps", near_steps, tru.shape)
    if uncertainty is not None:
        std_map = np.asarray(uncertainty, dtype=np.float64)
        if std_map.shape != tru.shape:
            msg = f"uncertainty must have the shape of truth {tru.shape}, got {std_map.shape}"
            raise ValueError(msg)
        if np.any(std_map < 0):
            msg = f"uncertainty must be a standard deviation (>= 0 px, NaN where unknown), got a minimum of {np.nanmin(std_map):g}"
            raise ValueError(msg)
    both = has_truth & np.isfinite(est)
    n_truth = int(has_truth.sum())
    n = int(both.sum())
    out = {"points": n, "truth_points": n_truth, "density": n / n_truth if n_truth else math.nan}
    if n == 0:
        out.update({key: math.nan for key in _ERROR_KEYS[2:]})
        return out
    signed = est[both] - tru[both]
    err = np.abs(signed)
    t = np.abs(tru[both])
    rel = err[t > 0] / t[t > 0]
    out["median_rel"] = float(np.median(rel)) if rel.size else math.nan
    out["p90_rel"] = float(np.percentile(rel, 90)) if rel.size else math.nan
    bad = err > 1.0
    out["bad_1px"] = float(np.mean(bad))
    out["bad_0_5px"] = float(np.mean(err > 0.5))
    out["mae_px"] = float(np.mean(err))
    out["bias_px"] = float(np.median(signed))
    out["truth_rounding_rel"] = rounding_median_rel(t, truth_step_px) if truth_step_px is not None else math.nan
    out.update({key: math.nan for key in _ERROR_KEYS[-6:]})
    if uncertainty is not None:
        std = std_map[both]
        known = np.isfinite(std)
        if known.any():
            scale = np.sqrt(std[known] ** 2 + (truth_step_px or 0.0) ** 2 / 12.0)
            with np.errstate(divide="ignore", invalid="ignore"):
                z = np.where(err[known] == 0.0, 0.0, err[known] / scale)  # an exact estimate with a std of 0: z = 0
            out["median_z"] = float(np.median(z))
            mean_sq_err, mean_sq_scale = float(np.mean(err[known] ** 2)), float(np.mean(scale**2))
            out["rms_ratio"] = 0.0 if mean_sq_err == 0.0 else math.sqrt(mean_sq_err / mean_sq_scale) if mean_sq_scale > 0.0 else math.inf
            out["within_3std"] = float(np.mean(z <= 3.0))
    if near_steps is not None:
        near = near_steps[both]
        out["near_steps_share"] = float(np.mean(near))
        if near.any():
            out["bad_1px_near_steps"] = float(np.mean(bad[near]))
        if not near.all():
            out["bad_1px_off_steps"] = float(np.mean(bad[~near]))
    return out


def _bool_map(name: str, value, shape) -> np.ndarray:
    m = np.asarray(value)
    if m.shape != shape:
        msg = f"{name} must have the shape of truth {shape}, got {m.shape}"
        raise ValueError(msg)
    return m.astype(bool)


def depth_step_mask(truth, *, gap_px: float = 2.0, width_px: int = 9) -> np.ndarray:
    """Pixels near a depth step of the truth: Middlebury's "disc" regions.

    A step is a pair of 4-neighbours, both with a finite truth, whose
    disparities differ by more than ``gap_px``; the mask is every pixel of
    such a pair dilated by a ``width_px`` x ``width_px`` square (Scharstein &
    Szeliski, IJCV 2002: gap 2 px, width 9). There, an edge point is on an
    occluding contour whose position the truth and the images may place a
    pixel or two apart, so bad-1px near steps largely measures that
    placement; away from them it measures the matching.

    Parameters
    ----------
    truth : array_like, shape (H, W)
        True disparity (px); NaN where unknown (unknown pixels make no step).
    gap_px : float
        Disparity difference between neighbours that makes a step (> 0).
    width_px : int
        Odd side of the square the steps are dilated by (>= 1); beyond
        ``2 max(H, W) - 1`` it reaches every pixel from every step, as that does.

    Returns
    -------
    ndarray of bool, shape (H, W)
    """
    import cv2

    tru = np.asarray(truth, dtype=np.float64)
    if tru.ndim != 2:
        msg = f"truth must be a 2-D disparity map, got shape {tru.shape}"
        raise ValueError(msg)
    gap_px = check_positive_finite("gap_px", gap_px)
    width_px = check_int("width_px", width_px, 1)
    if width_px % 2 == 0:
        msg = f"width_px must be odd, got {width_px}"
        raise ValueError(msg)
    step = np.zeros(tru.shape, np.uint8)
    with np.errstate(invalid="ignore"):
        across_cols = np.abs(np.diff(tru, axis=1)) > gap_px  # NaN compares False: unknown makes no step
        across_rows = np.abs(np.diff(tru, axis=0)) > gap_px
    step[:, 1:] |= across_cols
    step[:, :-1] |= across_cols
    step[1:, :] |= across_rows
    step[:-1, :] |= across_rows
    # a square of side 2 n - 1 centred anywhere on an n px side covers all of it: a wider one marks
    # the same pixels (clipped per axis, so that a huge width_px needs no huge kernel)
    rows, cols = (min(width_px, max(2 * n - 1, 1)) for n in tru.shape)
    return cv2.dilate(step, np.ones((rows, cols), np.uint8), borderType=cv2.BORDER_CONSTANT, borderValue=0) > 0


def rounding_median_rel(truth, step_px) -> float:
    """Expected median relative error of a perfect estimate against a truth rounded to ``step_px``.

    If each point's truth is off by an independent rounding error ``u``,
    uniform on ``[-step/2, step/2]``, a perfect estimate scores
    ``|u| / |d_true|``; this returns the median of that mixture, exactly:
    ``x`` with ``mean_i min(1, 2 x |d_i| / step) = 1/2`` (points with
    ``d = 0`` or non-finite left out). On a truth measured densely on curved
    and slanted surfaces (Middlebury 2005, Teddy) it is the floor under
    ``median_rel``: estimates better than the truth's resolution score about
    this, however good they are. Where whole
    regions share one rounding error (Tsukuba's fronto-parallel layers,
    labelled in whole pixels) the errors are not independent and an estimate
    can score below it.

    Parameters
    ----------
    truth : array_like
        True disparities (px) of the points scored.
    step_px : float
        Rounding step of the truth (px), a finite number >= 0; 0 gives 0.

    Returns
    -------
    float
        NaN if no point has a finite, non-zero truth.
    """
    step_px = check_nonnegative_finite("step_px", step_px)
    t = np.abs(np.asarray(truth, dtype=np.float64).ravel())
    t = t[np.isfinite(t) & (t > 0)]
    if t.size == 0:
        return math.nan
    if step_px == 0:
        return 0.0
    # a_i: the relative error at which point i's |u| / d_i saturates (u = step/2)
    a = np.sort(0.5 * float(step_px) / t)
    n = a.size
    tail = np.cumsum((1.0 / a)[::-1])[::-1]  # tail[k] = sum over i >= k of 1 / a_i
    k = np.arange(n)
    # F on [a_(k-1), a_k] with k points saturated: F(x) = (k + x tail[k]) / n
    k0 = int(np.argmax(k + a * tail >= 0.5 * n))
    return float((0.5 * n - k0) / tail[k0])


_SEARCH_STEP_PX = 0.02  # photometric_truth_offset's grid step
_SEARCH_PX_RANGE = (0.01, 10.0)  # its search_px: a grid of at least 2 points, at most about 1000


def photometric_truth_offset(scene, view: int, *, search_px: float = 0.3, min_gradient: float = 2.0, max_truth_range_px: float = 0.5) -> dict:
    """The constant offset of the ground truth that best explains the images, measured without any method.

    Warps ``scene.views[view]`` onto the reference with ``truth + delta``
    (both views smoothed by a 1 px Gaussian, then bicubic; pixel ``(r, c)``
    seen at ``(r, c - k (d + delta))`` for ``k = view - reference_index``
    view steps) and returns the ``delta``
    minimising the mean absolute grey difference to the reference, after
    removing the median difference (a global brightness offset). Only
    pixels whose truth is smooth (within ``max_truth_range_px`` over a
    7 x 7 window: no depth steps, no occlusion) and whose column gradient
    is at least ``min_gradient`` grey levels per px (after a 1 px Gaussian)
    count. A truth that is right gives ``delta`` near 0; a truth stored
    truncated rather than rounded reads low by half a step (``+step / 2``).
    The bicubic warp itself errs at fractional shifts (up to 0.04 px per step
    on fine texture at one constant disparity), which cancels over a spread
    of disparities (within 0.002 px on a slanted synthetic plane): the check
    is meant for truths with many disparities, not for one fronto-parallel
    plane.

    Parameters
    ----------
    scene : MultiViewScene or str
    view : int
        Index into ``scene.views``, not the reference.
    search_px : float
        ``delta`` is searched in ``[-search_px, search_px]`` px per view step,
        on a grid of 0.02 px refined at the best point: 0.01 to 10 px.
    min_gradient : float
        Least column gradient (grey levels per px) of a pixel that counts
        (a finite number >= 0).
    max_truth_range_px : float
        Largest range of the truth (px) over a pixel's 7 x 7 window for it to
        count (a finite number >= 0).

    Returns
    -------
    dict
        ``view``, ``steps`` (``k``), ``offset_px`` (``delta``, px per view
        step), ``error_at_zero`` and ``error_at_offset`` (mean absolute grey
        difference), ``points``.
    """
    import cv2
    from scipy.optimize import minimize_scalar

    from . import datasets

    if isinstance(scene, str):
        scene = datasets.load_scene(scene)
    if not isinstance(scene, datasets.MultiViewScene):
        msg = f"scene must be a MultiViewScene or a scene name, got {type(scene).__name__}"
        raise TypeError(msg)
    ref = scene.reference_index
    n = len(scene.views)
    if isinstance(view, bool) or not isinstance(view, (int, np.integer)) or not 0 <= view < n or view == ref:
        msg = f"view must be an index into the scene's {n} views other than the reference {ref}, got {view!r}"
        raise ValueError(msg)
    search_px = check_within(
        "search_px",
        search_px,
        _SEARCH_PX_RANGE,
        unit=" px",
        advice=f"the offset is searched on a {_SEARCH_STEP_PX:g} px grid over [-search_px, search_px] (at least one step wide), "
        "and a truth's offset is a fraction of a pixel (default 0.3)",
    )
    check_threshold("min_gradient", min_gradient)  # checked only: compared as given, as before
    check_threshold("max_truth_range_px", max_truth_range_px)
    steps = int(view) - ref
    # both smoothed alike (1 px Gaussian): the shift is unchanged, the bicubic
    # interpolation error of fine texture (a bias at fractional shifts) drops
    image = cv2.GaussianBlur(np.asarray(scene.views[ref], np.float32), (0, 0), 1.0)
    other = cv2.GaussianBlur(np.asarray(scene.views[view], np.float32), (0, 0), 1.0)
    d = np.asarray(scene.disparity, np.float32)
    known = np.isfinite(d)
    window = np.ones((7, 7), np.uint8)
    filled = np.where(known, d, np.float32(0.0))
    all_known = cv2.erode(known.astype(np.uint8), window, borderType=cv2.BORDER_REPLICATE) > 0
    smooth = cv2.dilate(filled, window) - cv2.erode(filled, window) <= max_truth_range_px
    g = cv2.Sobel(image, cv2.CV_32F, 1, 0, ksize=3) / np.float32(8.0)
    use = all_known & smooth & (np.abs(g) >= min_gradient)
    rows, cols = np.nonzero(use)
    if rows.size < 100:
        msg = f"only {rows.size} smooth, textured pixels with a known truth; need at least 100"
        raise ValueError(msg)
    # the points as a (m, 1024) block: cv2.remap maps are images of fewer than 32767 columns
    m = rows.size
    pad = -m % 1024
    map_y = np.pad(rows.astype(np.float32), (0, pad), constant_values=-2.0).reshape(-1, 1024)
    base_x = cols.astype(np.float64) - steps * d[rows, cols].astype(np.float64)
    values = image[rows, cols]
    w = other.shape[1]

    def error(delta):
        x = (base_x - steps * delta).astype(np.float32)
        map_x = np.pad(x, (0, pad), constant_values=-2.0).reshape(-1, 1024)
        warped = cv2.remap(other, map_x, map_y, cv2.INTER_CUBIC, borderMode=cv2.BORDER_CONSTANT, borderValue=np.nan).ravel()[:m]
        inside = (x >= 0) & (x <= w - 1) & np.isfinite(warped)
        diff = warped[inside] - values[inside]
        return float(np.mean(np.abs(diff - np.median(diff)))) if diff.size else math.inf

    grid = np.linspace(-search_px, search_px, round(2 * search_px / _SEARCH_STEP_PX) + 1)
    errors = [error(x) for x in grid]
    i = int(np.argmin(errors))
    spacing = grid[1] - grid[0]
    lo_b, hi_b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    best = minimize_scalar(error, bounds=(lo_b, hi_b), method="bounded", options={"xatol": 1e-4 * spacing / _SEARCH_STEP_PX})
    delta = float(best.x) if best.fun <= errors[i] else float(grid[i])
    return {
        "view": int(view),
        "steps": steps,
        "offset_px": delta,
        "error_at_zero": error(0.0),
        "error_at_offset": error(delta),
        "points": int(rows.size),
    }


# ------------------------------------------------------------------ one scene


def select_views(n_views: int, reference: int, views="all") -> list:
    """Indices of the views to use.

    ``"all"``: every view. ``"three"``: ``reference - 1, reference,
    reference + 1`` when both exist, else the reference and its next two (or,
    at the end of the row, its previous two); with fewer than three views,
    all of them. A sequence of whole numbers is returned as a list of ints
    (their range is checked later by :func:`nfdepth.datasets.view_subset`).
    """
    msg = f"views must be 'all', 'three' or a sequence of view indices, got {views!r}"
    if isinstance(views, str):
        key = views.strip().lower()
        if key == "all":
            return list(range(n_views))
        if key == "three":
            if n_views <= 3:
                return list(range(n_views))
            if 0 < reference < n_views - 1:
                return [reference - 1, reference, reference + 1]
            if reference == 0:
                return [0, 1, 2]
            return [reference - 2, reference - 1, reference]
        raise ValueError(msg)
    try:
        values = [float(i) for i in views]
    except (TypeError, ValueError):
        raise ValueError(msg) from None
    # whole numbers only (2.0 is view 2; 2.7 is no view, and True is no index)
    if any(isinstance(i, (bool, np.bool_)) for i in views) or not all(v.is_integer() for v in values):
        raise ValueError(msg)
    return [int(v) for v in values]


def _check_methods(methods) -> tuple:
    if isinstance(methods, str):
        methods = (methods,)
    methods = tuple(methods)
    bad = [m for m in methods if m not in METHODS]
    if bad or not methods:
        msg = f"methods must be one or more of {', '.join(METHODS)}, got {', '.join(map(str, bad)) or 'none'}"
        raise ValueError(msg)
    return tuple(dict.fromkeys(methods))


def view_size_problems(shape, methods=DEFAULT_METHODS) -> list:
    """What views of ``shape`` (rows, cols) lack for each of ``methods``, one phrase each; empty when every one can run.

    From the methods' own limits: static stereo's 3 px stencils; StereoSGBM /
    StereoBM's 8 px pairs, their fewest disparities and default blocks;
    DIS's 12 px side; any view at least 2 x 2 px.
    """
    from . import baselines as b
    from .stereo import _MIN_SIZE_PX

    h, w = shape
    problems = []
    for m in _check_methods(methods):
        if m == "nfdepth" and min(h, w) < _MIN_SIZE_PX:
            problems.append(f"nfdepth needs views of at least {_MIN_SIZE_PX}x{_MIN_SIZE_PX} px")
        elif m in ("sgbm", "bm"):
            wide = b._min_width_px(b._SGBM_BLOCK_PX if m == "sgbm" else b._BM_BLOCK_PX)
            if min(h, w) < b._MIN_PAIR_PX or w < wide:
                problems.append(f"{m} needs views of at least {b._MIN_PAIR_PX}x{b._MIN_PAIR_PX} px, more than {wide - 1} px wide")
        elif m == "waxman_sinha" and (min(h, w) < 2 or max(h, w) < b._DIS_MIN_SIDE_PX):
            problems.append(f"waxman_sinha's DIS flow needs a side of at least {b._DIS_MIN_SIDE_PX} px")
    if min(h, w) < 2 and not problems:
        problems.append("the downsampled views need at least 2x2 px")
    return problems


def _run_peer(method: str, scene, max_disparity):
    from . import baselines

    if method in ("sgbm", "bm"):
        if max_disparity is not None:
            # the matchers take a positive max_disparity below the views' width: the truth's largest
            # disparity clipped to 1 .. width - 1 px gives the numDisparities it gave before (16 at the
            # low end, the width's cap at the high end), a non-finite one the default (W / 8) as before
            width = np.shape(scene.views[scene.reference_index])[1]
            max_disparity = min(max(max_disparity, 1.0), width - 1) if math.isfinite(max_disparity) else None
        return baselines.pair_disparity_at_reference(
            scene.views, reference=scene.reference_index, method=method, max_disparity=max_disparity
        )
    flow = "farneback" if method == "waxman_sinha_farneback" else "dis"
    return baselines.waxman_sinha_disparity(scene.views, reference=scene.reference_index, method=flow)


def evaluate_scene(scene, *, views="all", methods=DEFAULT_METHODS, downsample: int = 1, keep_maps: bool = False, stereo_options=None) -> dict:
    """Run nfdepth and its peers on one scene and score them against the truth.

    Parameters
    ----------
    scene : MultiViewScene or str
        A loaded scene or a name for :func:`nfdepth.datasets.load_scene`.
    views : "all", "three" or sequence of int
        Which views to use (see :func:`select_views`); every method gets the
        same ones (the two-view matchers use the reference and its nearest
        neighbour among them).
    methods : sequence of str
        Any of :data:`METHODS`. Peers are scored at nfdepth's edge points only
        when ``"nfdepth"`` is among them.
    downsample : int
        Area-downsample the scene first (:func:`nfdepth.datasets.downsample_scene`).
    keep_maps : bool
        Also return the disparity maps (``"maps"``: method -> ndarray,
        ``"truth"``, ``"edge_points"``, ``"uncertainty"``: nfdepth's std map);
        not JSON-serialisable.
    stereo_options : dict, optional
        Extra keyword arguments for :func:`nfdepth.stereo.static_stereo`.

    Returns
    -------
    dict
        ``nfdepth_version``, ``scene``, ``views`` (indices into the scene's
        row), ``view_count``, ``reference_index`` (into the row),
        ``downsample``, ``shape`` (``[rows, cols]`` of the views scored),
        ``truth_points`` (their pixels with a known truth; an errors dict's
        own ``truth_points`` counts the pixels it was scored over: every known
        one, or for a peer at nfdepth's edge points those points),
        ``truth_step_px`` (the scene's, after view
        selection and downsampling), ``stereo_options`` (as given, ``{}`` by
        default), ``near_steps_share`` (the share of the
        truth's pixels near its depth steps, :func:`depth_step_mask`) and
        ``methods``: method -> ``{"runtime_s", "dense": errors, "edges":
        errors or None}`` (errors as :func:`disparity_errors`, split at the
        depth steps; nfdepth's with ``median_z``, ``rms_ratio`` and ``within_3std`` of its
        ``uncertainty``, the peers' NaN); nfdepth's also has ``"filled"``: its dense map with
        the holes filled from the background (:meth:`StereoResult.filled`,
        every pixel of a line with a value); a peer scored at nfdepth's edge points also
        has ``"nfdepth_at_shared_edges"``: nfdepth's errors at those of its
        edge points where the peer has a value (the same points as the peer's
        ``"edges"`` figures).
    """
    from . import __version__, datasets
    from .stereo import static_stereo

    methods = _check_methods(methods)
    if isinstance(scene, str):
        scene = datasets.load_scene(scene)
    if not isinstance(scene, datasets.MultiViewScene):
        msg = f"scene must be a MultiViewScene or a scene name, got {type(scene).__name__}"
        raise TypeError(msg)
    k = datasets._check_factor(downsample, "downsample")
    full_ref = scene.reference_index
    idx = select_views(len(scene.views), full_ref, views)
    sub = datasets.view_subset(scene, idx) if idx != list(range(len(scene.views))) else scene
    if k > 1:
        sub = datasets.downsample_scene(sub, k)
    truth = sub.disparity
    step = sub.truth_step_px
    steps = depth_step_mask(truth)
    known = np.isfinite(truth)
    max_disp = float(np.nanmax(truth)) if known.any() else None
    out = {
        "nfdepth_version": __version__,
        "scene": scene.name,
        "views": idx,
        "view_count": len(idx),
        "reference_index": full_ref,
        "downsample": k,
        "shape": list(sub.shape),
        "truth_points": int(known.sum()),
        "truth_step_px": step,
        "near_steps_share": float(np.mean(steps[known])) if known.any() else math.nan,
        "stereo_options": dict(stereo_options or {}),
        "methods": {},
    }
    maps = {}
    edge_points = None
    if "nfdepth" in methods:
        res = static_stereo(sub.views, reference=sub.reference_index, **(stereo_options or {}))
        d = np.asarray(res.disparity, dtype=np.float32)
        nf_std = res.uncertainty
        edge_points = np.asarray(res.edge_mask, bool) & np.isfinite(d)
        out["methods"]["nfdepth"] = {
            "runtime_s": float(res.runtime_s),
            "edges": disparity_errors(np.where(edge_points, d, np.nan), truth, truth_step_px=step, near_steps=steps, uncertainty=nf_std),
            "dense": disparity_errors(d, truth, truth_step_px=step, near_steps=steps, uncertainty=nf_std),
            # the dense map with its holes filled from the background (StereoResult.filled)
            "filled": disparity_errors(res.filled()[0], truth, truth_step_px=step, near_steps=steps),
        }
        maps["nfdepth"] = d
    for m in methods:
        if m == "nfdepth":
            continue
        r = _run_peer(m, sub, max_disp)
        out["methods"][m] = {
            "runtime_s": float(r.runtime_s),
            "edges": None if edge_points is None else disparity_errors(r.disparity, truth, mask=edge_points, truth_step_px=step, near_steps=steps),
            "dense": disparity_errors(r.disparity, truth, truth_step_px=step, near_steps=steps),
        }
        if edge_points is not None:
            # nfdepth on exactly the edge points where the peer has a value too:
            # the same point set on both sides (a peer may leave the hard ones out)
            shared = edge_points & np.isfinite(np.asarray(r.disparity, dtype=np.float64))
            out["methods"][m]["nfdepth_at_shared_edges"] = disparity_errors(maps["nfdepth"], truth, mask=shared, truth_step_px=step, near_steps=steps, uncertainty=nf_std)
        maps[m] = r.disparity
    if keep_maps:
        out["maps"] = maps
        out["truth"] = truth
        out["edge_points"] = edge_points
        out["uncertainty"] = None if edge_points is None else nf_std
    return out


# ------------------------------------------------------------------ many scenes


def _known_scene(name: str):
    from .datasets import _SCENE_FILES, MIDDLEBURY2005_SCENES

    key = name.strip().lower()
    aliases = {n.lower(): n for n in _SCENE_FILES}
    aliases.update({"middlebury2003-teddy": "teddy", "middlebury2003/teddy": "teddy", "skimage-motorcycle": "motorcycle"})
    aliases.update({s.lower(): f"middlebury2005/{s}" for s in MIDDLEBURY2005_SCENES})
    return aliases.get(key)


def _few(items, most: int = 3) -> str:
    """``a, b, c and 6 more``."""
    items = list(items)
    return ", ".join(items[:most]) + (f" and {len(items) - most} more" if len(items) > most else "")


def _complete(root: Path, names: list) -> tuple:
    """``(root, names)`` once every file of every named scene is there: a missing one is found before the first scene runs.

    An absent file is a :class:`~nfdepth.datasets.DataNotFoundError`; a
    directory (or another non-file) in a file's place a
    :class:`~nfdepth.datasets.DataFileError`, as loading the scene reports it.
    """
    from .datasets import DataNotFoundError, _require, missing_scene_files

    for name in names:
        missing = missing_scene_files(name, root)
        absent = [p for p in missing if not p.exists()]
        if absent:
            listed = _few(f"'{p}'" for p in absent)
            msg = f"scene {name!r}: data file{'s' if len(absent) > 1 else ''} missing: {listed} (check the data folder, or download it with `nfdepth fetch-data`)"
            raise DataNotFoundError(msg)
        _require(name, missing)  # what is left is there but not a file
    return root, names


def _warn_incomplete(root: Path, present: list) -> list:
    """The scenes ``present`` in a data folder; a warning names each scene whose folder is there but lacks a file (skipped)."""
    from .datasets import _SCENE_FILES, missing_scene_files

    for name, (sub, _files) in _SCENE_FILES.items():
        if name not in present and (Path(root) / sub).is_dir():
            missing = missing_scene_files(name, root)
            warnings.warn(
                f"scene {name!r} skipped: its folder '{Path(root) / sub}' lacks {_few(p.name + (' (not a file)' if p.exists() else '') for p in missing)}",
                UserWarning,
                stacklevel=3,
            )
    return present


def resolve_dataset(dataset, data=None) -> tuple:
    """Turn a dataset argument into ``(root, [scene names])``.

    ``dataset`` is a scene name (``"tsukuba"``, ``"teddy"``,
    ``"middlebury2005/Art"`` or just ``"Art"``, ``"motorcycle"``), a group
    (``"middlebury2005"``: its five scenes; ``"all"``: every scene present),
    a sequence of names, or a folder: a data root (every scene present), a
    set's folder (``.../tsukuba``, ``.../middlebury2005``) or a scene's
    (``.../middlebury2005/Art``).

    A scene whose folder is present but incomplete is skipped with a
    warning where every scene present is asked for (``"all"``, a data root).

    Raises
    ------
    ValueError
        Unknown name (the message lists the known ones).
    DataNotFoundError
        No data root, or a file of a named scene (or group) missing.
    """
    from . import datasets

    if not isinstance(dataset, (str, Path)):
        roots, names = [], []
        for item in dataset:
            root, sub = resolve_dataset(item, data)
            roots.append(Path(root).resolve())
            names.extend(sub)
        if not roots:
            msg = "dataset is an empty list: give at least one scene name or data folder"
            raise ValueError(msg)
        if len(set(roots)) > 1:  # one root loads every scene: a folder keeps its own
            msg = f"the datasets of a list must lie under one data root, got {', '.join(map(str, dict.fromkeys(roots)))}"
            raise ValueError(msg)
        return roots[0], list(dict.fromkeys(names))
    text = str(dataset).strip()
    key = text.lower().rstrip("/")
    if key == "all":
        root = datasets.data_root(data)
        names = datasets.list_scenes(root)
        if not names:
            raise datasets.DataNotFoundError(f"no complete scene under data folder '{root}'")
        return root, _warn_incomplete(root, names)
    if key == "middlebury2005":
        return _complete(datasets.data_root(data), [f"middlebury2005/{s}" for s in datasets.MIDDLEBURY2005_SCENES])
    known = _known_scene(key)
    if known is not None:
        return _complete(datasets.data_root(data), [known])
    path = Path(text).expanduser()
    if path.is_dir():
        path = path.resolve()
        present = datasets.list_scenes(path)
        if present:
            return path, _warn_incomplete(path, present)
        folders = {sub: name for name, (sub, _files) in datasets._SCENE_FILES.items()}
        for depth in (1, 2)[: len(path.parents)]:  # (a folder at the top, '/' or '/tmp', has fewer parents)
            parent = path.parents[depth - 1]
            rel = path.relative_to(parent).as_posix()
            if rel in folders:
                return _complete(parent, [folders[rel]])
        if path.name == "middlebury2005":
            return _complete(path.parent, [f"middlebury2005/{s}" for s in datasets.MIDDLEBURY2005_SCENES])
        msg = f"dataset folder '{path}' holds no known scene (expected a data root or one of {', '.join(folders)})"
        raise ValueError(msg)
    known_names = ", ".join(["all", "middlebury2005", *datasets._SCENE_FILES])
    msg = f"unknown dataset {text!r}: give one of {known_names}, or a data folder"
    raise ValueError(msg)


def evaluate_dataset(root_or_scene_names, *, data=None, views="all", methods=DEFAULT_METHODS, downsample: int = 1, progress=None, **options) -> list:
    """:func:`evaluate_scene` on every scene of a dataset argument (see :func:`resolve_dataset`).

    ``progress``, if given, is called with each scene's result as it is
    done. Returns the list of per-scene dicts.
    """
    from . import datasets

    methods = _check_methods(methods)
    select_views(3, 1, views)  # validate before loading anything
    root, names = resolve_dataset(root_or_scene_names, data)
    results = []
    for name in names:
        scene = datasets.load_scene(name, root)
        res = evaluate_scene(scene, views=views, methods=methods, downsample=downsample, **options)
        if progress is not None:
            progress(res)
        results.append(res)
    return results


# ------------------------------------------------------------------ output


def _pct(x) -> str:
    return "–" if x is None or not np.isfinite(x) else f"{100 * x:.1f} %"


def _rel(x) -> str:
    return "–" if x is None or not np.isfinite(x) else f"{100 * x:.2f} %"


def _px(x, fmt) -> str:
    return "–" if x is None or not np.isfinite(x) else format(x, fmt)


def evaluation_rows(result):
    """The rows of the tables of one :func:`evaluate_scene` result: ``(method, label, errors, runtime_s)``.

    A peer that leaves some of nfdepth's edge points without a value gets a
    row of nfdepth at the points they share, right after its own edge row.
    """
    methods = result["methods"]
    for method, entry in methods.items():
        for part in ("edges", "dense", "filled"):
            errs = entry.get(part)
            if errs is None:
                continue
            label = {"edges": "edges" if method == "nfdepth" else "at nfdepth edges", "dense": "dense", "filled": "dense, filled"}[part]
            yield method, label, errs, entry["runtime_s"]
            shared = entry.get("nfdepth_at_shared_edges") if part == "edges" else None
            if shared is not None and shared["points"] < methods["nfdepth"]["edges"]["points"]:
                yield "nfdepth", f"edges & {method}", shared, methods["nfdepth"]["runtime_s"]


def render_markdown(results) -> str:
    """A markdown table: one row per scene, method and point set."""
    if isinstance(results, dict):
        results = [results]
    head = (
        "| scene | views | method | points | density | median rel | truth rounding | p90 rel | bad >1 px | bad >0.5 px | MAE px | bias px "
        "| median abs(error) / std | RMS error / RMS std | near a depth step | bad >1 px near / off steps | runtime s |\n"
        "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    )
    lines = [head]
    for res in results:
        size = f" /{res['downsample']}" if res.get("downsample", 1) > 1 else ""
        for method, label, e, rt in evaluation_rows(res):
            lines.append(
                f"| {res['scene']}{size} | {res['view_count']} | {method} ({label}) | {e['points']} | {_pct(e['density'])} | "
                f"{_rel(e['median_rel'])} | {_rel(e.get('truth_rounding_rel'))} | {_rel(e['p90_rel'])} | {_pct(e['bad_1px'])} | "
                f"{_pct(e['bad_0_5px'])} | {_px(e['mae_px'], '.3f')} | {_px(e.get('bias_px'), '+.3f')} | {_px(e.get('median_z'), '.2f')} | {_px(e.get('rms_ratio'), '.2f')} | {_pct(e.get('near_steps_share'))} | "
                f"{_pct(e.get('bad_1px_near_steps'))} / {_pct(e.get('bad_1px_off_steps'))} | {rt:.3f} |"
            )
    return "\n".join(lines)


def to_jsonable(obj):
    """Results with NaN/inf as None and numpy scalars as Python numbers (maps dropped)."""
    if isinstance(obj, dict):
        return {k: to_jsonable(v) for k, v in obj.items() if k not in ("maps", "truth", "edge_points", "uncertainty")}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if np.isfinite(obj) else None
    return obj


def error_map_png(path, estimate, truth, *, title: str | None = None, vmax: float = 3.0) -> Path:
    """Write ``|estimate - truth|`` (px) as a colour map with a colour bar.

    Pixels where either is unknown are black. The scale runs 0..``vmax`` px
    (a positive finite number; default 3 px; larger errors saturate).
    """
    from . import plot

    vmax = check_positive_finite("vmax", vmax)
    est = np.asarray(estimate, dtype=np.float64)
    tru = np.asarray(truth, dtype=np.float64)
    if est.shape != tru.shape:
        msg = f"estimate and truth must have the same shape, got {est.shape} and {tru.shape}"
        raise ValueError(msg)
    err = np.abs(est - tru)
    err[~(np.isfinite(est) & np.isfinite(tru))] = np.nan
    fig = plot.colormap_panel(err, title=title or "|disparity error|", unit="|error| px", vmin=0.0, vmax=vmax)
    return plot.save_figure(fig, path)
