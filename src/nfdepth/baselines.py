"""What a user would run instead of nfdepth, on the same rectified views.

Two families, each returning **neighbour-step** disparity at the reference
view in pixels (NaN where the method gives no answer), in the project's
convention: pixel ``(row, col)`` of the reference is seen at
``(row, col - t_k d)`` in a view ``t_k`` steps further toward +X.

* Two-view block matching (OpenCV): :func:`sgbm_disparity` (semi-global
  matching, Hirschmüller 2008) and :func:`stereo_bm_disparity` (block
  matching). They use **one pair** whose baseline is one neighbour step, so
  their raw disparity already is the neighbour-step disparity.
  :func:`pair_disparity_at_reference` picks that pair from a row of views
  (the reference and its right neighbour, or, for the last view, its left
  neighbour with both images mirrored).
* Waxman & Sinha's relative **optical** flow (the paper's section 2.1,
  eq. 2): :func:`waxman_sinha_disparity`. Dense optical flow (OpenCV DIS or
  Farnebäck) from the reference to every other view; with a static scene and
  a stationary partner camera the relative flow is the moving camera's flow,
  and with the relative motion known (translation along x, ``ΔV = -t_k b``)
  eq. 2 reduces to ``Δu = f ΔVx / Z = -t_k d``, so each view gives
  ``d = -u_k / t_k`` and several views are fused by least squares,
  ``d = -Σ t_k u_k / Σ t_k²`` (weights ``t_k²``: the flow error is about the
  same in pixels for every view, so far views constrain ``d`` more).

All functions take grey (or colour) float or uint8 images on a 0..255 scale.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import cv2
import numpy as np

from ._validate import (
    check_bool,
    check_int,
    check_positive_finite,
    check_threshold,
    check_view_distances,
)

__all__ = [
    "BaselineResult",
    "sgbm_disparity",
    "stereo_bm_disparity",
    "pair_disparity_at_reference",
    "waxman_sinha_disparity",
    "default_num_disparities",
]

_SGBM_MODES = {
    "sgbm": cv2.STEREO_SGBM_MODE_SGBM,
    "hh": cv2.STEREO_SGBM_MODE_HH,
    "sgbm3way": cv2.STEREO_SGBM_MODE_SGBM_3WAY,
    "hh4": cv2.STEREO_SGBM_MODE_HH4,
}


@dataclass(frozen=True)
class BaselineResult:
    """Disparity of a peer method and its wall-clock time.

    Attributes
    ----------
    disparity : ndarray, float32, shape (H, W)
        Neighbour-step disparity at the reference (px), NaN where unknown.
    runtime_s : float
        Wall-clock time of the estimate (image conversion included).
    method : str
        E.g. ``"sgbm"``, ``"waxman_sinha/dis"``.
    """

    disparity: np.ndarray
    runtime_s: float
    method: str


# ----------------------------------------------------------------- helpers



def _check_views_reference(views, reference) -> list:
    """The views as a list (at least 2), with ``reference`` an index into them."""
    views = list(views)
    n = len(views)
    if n < 2:
        msg = f"views must hold at least 2 images, got {n}"
        raise ValueError(msg)
    if isinstance(reference, bool) or int(reference) != reference or not 0 <= reference < n:
        msg = f"reference must index one of the {n} views (0..{n - 1}), got {reference!r}"
        raise ValueError(msg)
    return views


def _check_positions(positions, n: int, reference: int, what: str) -> np.ndarray:
    """``positions`` (default 0, 1, ..., n - 1) as floats: ``n`` finite, strictly increasing numbers, the views
    1e-30 to 1e30 units from the reference (:func:`check_view_distances`); ``what`` ends the message of a wrong
    count or order ("positions must be ``what``, got ...").
    """
    if positions is None:
        return np.arange(n, dtype=float)
    pos = np.asarray(positions, dtype=float)
    if pos.shape == (n,) and not np.all(np.isfinite(pos)):  # before the differences: inf - inf warns
        msg = f"positions must be {n} strictly increasing finite numbers, got {positions!r}"
        raise ValueError(msg)
    if pos.shape != (n,) or not np.all(np.diff(pos) > 0):
        msg = f"positions must be {what}, got {positions!r}"
        raise ValueError(msg)
    check_view_distances(pos, reference)
    return pos


def _as_uint8(image, name: str) -> np.ndarray:
    a = np.asarray(image)
    if a.ndim == 3 and a.shape[2] in (3, 4):
        a = a[..., :3]
    elif a.ndim != 2:
        msg = f"{name} must be a (H, W) or (H, W, 3) image, got shape {a.shape}"
        raise ValueError(msg)
    if a.dtype == np.uint8:
        return np.ascontiguousarray(a)
    if not np.issubdtype(a.dtype, np.number) or a.dtype == np.bool_:
        msg = f"{name} must be numeric, got dtype {a.dtype}"
        raise TypeError(msg)
    af = a.astype(np.float32)
    if not np.all(np.isfinite(af)):
        msg = f"{name} holds NaN or infinite values"
        raise ValueError(msg)
    return np.ascontiguousarray(np.clip(np.rint(af), 0, 255).astype(np.uint8))


def _grey_uint8(image, name: str) -> np.ndarray:
    a = _as_uint8(image, name)
    if a.ndim == 3:
        a = cv2.cvtColor(a, cv2.COLOR_RGB2GRAY)
    return a


_MIN_PAIR_PX = 8  # the smallest side of a pair that StereoSGBM / StereoBM take here
_MIN_DISPARITIES = 16  # OpenCV's smallest numDisparities
_SGBM_BLOCK_PX = 5  # sgbm_disparity's default block
_BM_BLOCK_PX = 15  # stereo_bm_disparity's default block
_DIS_MIN_SIDE_PX = 12  # cv2.DISOpticalFlow needs a side at least this long


def _min_width_px(block_size: int, num_disparities: int = _MIN_DISPARITIES) -> int:
    """The narrowest view StereoSGBM / StereoBM take with ``num_disparities`` and a ``block_size`` block (see :func:`_check_width`)."""
    return num_disparities + block_size // 2 + 1


def _check_pair(left, right):
    l8, r8 = _as_uint8(left, "left"), _as_uint8(right, "right")
    if l8.shape != r8.shape:
        msg = f"left and right must have the same shape, got {l8.shape} and {r8.shape}"
        raise ValueError(msg)
    if min(l8.shape[:2]) < _MIN_PAIR_PX:
        msg = f"images must be at least {_MIN_PAIR_PX}x{_MIN_PAIR_PX} px, got {l8.shape[1]}x{l8.shape[0]}"
        raise ValueError(msg)
    return l8, r8


def default_num_disparities(width: int, max_disparity=None) -> int:
    """A multiple of 16 covering ``max_disparity`` (+10 % and 2 px margin), else ``width / 8``.

    Capped so that at least 16 columns remain (OpenCV leaves the first
    ``numDisparities`` columns of the left image unmatched). ``width`` is an
    integer >= 1 (px).
    """
    width = check_int("width", width, 1)
    if max_disparity is not None and np.isfinite(max_disparity):
        want = 1.1 * float(max_disparity) + 2.0
    else:
        want = width / 8.0
    n = int(16 * max(1, int(np.ceil(want / 16.0))))
    cap = max(16, 16 * ((int(width) - 16) // 16))
    return min(n, cap)


def _check_max_disparity(max_disparity, width: int) -> float | None:
    """``max_disparity`` as float: None, or a positive finite number below ``width`` (beyond it no pixel is matched)."""
    if max_disparity is None:
        return None
    max_disparity = check_positive_finite("max_disparity", max_disparity)
    if max_disparity >= width:
        msg = (
            f"the images are {width} px wide: max_disparity = {max_disparity:g} px is beyond them (no pixel is seen that far); "
            f"expected a positive number below {width} (None: from the width)"
        )
        raise ValueError(msg)
    return max_disparity


def _check_num_disparities(num_disparities, width: int, max_disparity=None) -> int:
    max_disparity = _check_max_disparity(max_disparity, width)
    if num_disparities is None:
        return default_num_disparities(width, max_disparity)
    if isinstance(num_disparities, bool) or int(num_disparities) != num_disparities or num_disparities < 16 or num_disparities % 16:
        msg = f"num_disparities must be a positive multiple of 16, got {num_disparities!r}"
        raise ValueError(msg)
    return int(num_disparities)


def _check_width(width: int, nd: int, bs: int, name: str) -> None:
    """OpenCV needs ``width - numDisparities > blockSize // 2`` (else it raises an internal error)."""
    if width < _min_width_px(bs, nd):
        msg = (
            f"the images are {width} px wide: {name} with {nd} disparities and a {bs} px block needs more than "
            f"{nd + bs // 2} columns (use larger images, e.g. a smaller downsampling factor)"
        )
        raise ValueError(msg)


def _check_block(block_size, *, low: int, high: int) -> int:
    msg = f"block_size must be an odd integer in [{low}, {high}], got {block_size!r}"
    if isinstance(block_size, bool) or not isinstance(block_size, (int, float, np.integer, np.floating)):
        raise TypeError(msg)
    if not (math.isfinite(block_size) and int(block_size) == block_size and low <= block_size <= high and block_size % 2 == 1):
        raise ValueError(msg)
    return int(block_size)


def _from_fixed_point(raw: np.ndarray, min_disparity: int) -> np.ndarray:
    d = raw.astype(np.float32) / 16.0
    d[raw < min_disparity * 16] = np.nan  # OpenCV marks invalid as (minDisparity - 1) * 16
    return d


# ----------------------------------------------------------------- two-view matching


def sgbm_disparity(left, right, *, num_disparities=None, block_size: int = _SGBM_BLOCK_PX, mode: str = "hh", max_disparity=None) -> np.ndarray:
    """Semi-global matching (``cv2.StereoSGBM``) disparity of ``left``.

    ``left`` is the view further toward -X (the reference, view ``k``) and
    ``right`` the next one (view ``k + 1``): the scene shifts toward -col in
    ``right``, which is OpenCV's convention for the left image. The pair's
    baseline is one neighbour step, so the result is the neighbour-step
    disparity at ``left``.

    Tuning as a user would, from the OpenCV documentation: ``P1 = 8 cn bs²``,
    ``P2 = 32 cn bs²``, ``uniquenessRatio = 10``, ``disp12MaxDiff = 1``
    (left-right check), ``preFilterCap = 63``, speckle filtering (window
    100 px, range 2 px), ``minDisparity = 0``.

    Parameters
    ----------
    left, right : ndarray, shape (H, W) or (H, W, 3)
        Rectified grey or RGB images, 0..255 (float is rounded to uint8).
    num_disparities : int, optional
        Positive multiple of 16 (search range ``0 .. num_disparities - 1``).
        Default :func:`default_num_disparities` (from ``max_disparity`` if
        given, else ``W / 8``).
    block_size : int
        Odd, 1..11 (matching window side).
    mode : {"hh", "sgbm", "sgbm3way", "hh4"}
        OpenCV's path mode; "hh" is the full 8-path variant.
    max_disparity : float, optional
        The largest disparity expected (px), a positive number below the
        width, used only when ``num_disparities`` is None (the search range
        then ends at most 16 columns short of the width).

    Returns
    -------
    ndarray, float32, shape (H, W)
        Disparity in px (OpenCV's 4-bit fixed point / 16), NaN where invalid
        (no unique match, left-right disagreement, speckle, or the left band
        of ``num_disparities`` columns).
    """
    l8, r8 = _check_pair(left, right)
    if mode not in _SGBM_MODES:
        msg = f"mode must be one of {', '.join(_SGBM_MODES)}, got {mode!r}"
        raise ValueError(msg)
    bs = _check_block(block_size, low=1, high=11)
    nd = _check_num_disparities(num_disparities, l8.shape[1], max_disparity)
    _check_width(l8.shape[1], nd, bs, "StereoSGBM")
    cn = 1 if l8.ndim == 2 else 3
    matcher = cv2.StereoSGBM_create(
        minDisparity=0,
        numDisparities=nd,
        blockSize=bs,
        P1=8 * cn * bs * bs,
        P2=32 * cn * bs * bs,
        disp12MaxDiff=1,
        preFilterCap=63,
        uniquenessRatio=10,
        speckleWindowSize=100,
        speckleRange=2,
        mode=_SGBM_MODES[mode],
    )
    return _from_fixed_point(matcher.compute(l8, r8), 0)


def stereo_bm_disparity(left, right, *, num_disparities=None, block_size: int = _BM_BLOCK_PX, max_disparity=None) -> np.ndarray:
    """Block matching (``cv2.StereoBM``) disparity of ``left``; conventions as :func:`sgbm_disparity`.

    Grey uint8 input (colour is converted), prefilter x-Sobel (OpenCV's
    default), ``textureThreshold = 10``, ``uniquenessRatio = 15``, speckle
    filtering (100 px, 2 px), ``disp12MaxDiff = 1``. ``block_size`` odd,
    5..51; ``max_disparity`` a positive number below the width.
    """
    l8, r8 = _check_pair(left, right)
    l8, r8 = _grey_uint8(l8, "left"), _grey_uint8(r8, "right")
    bs = _check_block(block_size, low=5, high=51)
    nd = _check_num_disparities(num_disparities, l8.shape[1], max_disparity)
    _check_width(l8.shape[1], nd, bs, "StereoBM")
    matcher = cv2.StereoBM_create(numDisparities=nd, blockSize=bs)
    matcher.setTextureThreshold(10)
    matcher.setUniquenessRatio(15)
    matcher.setSpeckleWindowSize(100)
    matcher.setSpeckleRange(2)
    matcher.setDisp12MaxDiff(1)
    return _from_fixed_point(matcher.compute(l8, r8), 0)


def pair_disparity_at_reference(views, *, reference: int, method: str = "sgbm", positions=None, **options) -> BaselineResult:
    """Two-view matching at ``views[reference]`` with its nearest neighbour.

    Uses the right neighbour (``reference + 1``) as OpenCV's right image;
    for the last view, the left neighbour with both images mirrored
    left-right (the mirrored pair has the usual geometry), and the result
    mirrored back. The raw disparity is divided by the pair's spacing in
    ``positions`` (default one step) to give the neighbour-step disparity.

    Parameters
    ----------
    views : sequence of ndarray
        Rectified views ordered toward +X.
    reference : int
        Index of the reference view.
    method : {"sgbm", "bm"}
    positions : sequence of float, optional
        Camera positions in neighbour steps (default 0, 1, 2, ...).
    **options
        Passed to :func:`sgbm_disparity` / :func:`stereo_bm_disparity`;
        ``max_disparity`` is the neighbour-step maximum and is scaled by the
        spacing here.
    """
    views = _check_views_reference(views, reference)
    n = len(views)
    fn = {"sgbm": sgbm_disparity, "bm": stereo_bm_disparity}.get(method)
    if fn is None:
        msg = f"method must be 'sgbm' or 'bm', got {method!r}"
        raise ValueError(msg)
    pos = _check_positions(positions, n, reference, f"{n} strictly increasing numbers")
    t0 = time.perf_counter()
    mirrored = reference == n - 1
    other = reference - 1 if mirrored else reference + 1
    spacing = abs(pos[other] - pos[reference])
    if options.get("max_disparity") is not None:
        max_disparity = check_threshold("max_disparity", options["max_disparity"], positive=True)
        options = {**options, "max_disparity": max_disparity * spacing}
    ref, oth = views[reference], views[other]
    if mirrored:
        d = fn(np.ascontiguousarray(np.asarray(ref)[:, ::-1]), np.ascontiguousarray(np.asarray(oth)[:, ::-1]), **options)[:, ::-1]
    else:
        d = fn(ref, oth, **options)
    d = np.ascontiguousarray(d / np.float32(spacing), dtype=np.float32)
    return BaselineResult(d, time.perf_counter() - t0, method)


# ----------------------------------------------------------------- Waxman & Sinha


def _flow(method: str, ref8: np.ndarray, other8: np.ndarray, init=None) -> np.ndarray:
    if method == "dis":
        dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
        if init is not None:  # DIS starts from a same-size CV_32FC2 flow passed in (its coarsest scale)
            return dis.calc(ref8, other8, np.ascontiguousarray(init, dtype=np.float32))
        return dis.calc(ref8, other8, None)
    flags = 0
    flow = None
    if init is not None:
        flags = cv2.OPTFLOW_USE_INITIAL_FLOW
        flow = np.ascontiguousarray(init, dtype=np.float32)
    return cv2.calcOpticalFlowFarneback(ref8, other8, flow, 0.5, 5, 15, 3, 5, 1.2, flags)


def waxman_sinha_disparity(views, *, reference: int, positions=None, method: str = "dis", chain: bool = True) -> BaselineResult:
    """Waxman & Sinha's depth from relative optical flow (paper eq. 2), static case.

    Dense optical flow ``(u_k, v_k)`` from the reference to every other view
    ``k``; the reference camera stands still, so the relative flow is the
    flow itself, and with the relative motion a pure x translation
    (``ΔV = -(t_k b, 0, 0)``, ``ΔΩ = 0``) eq. 2 gives
    ``u_k = -t_k f b / Z = -t_k d`` (``v_k`` carries no depth). The views are
    fused by least squares with weights ``t_k²``: ``d = -Σ t_k u_k / Σ t_k²``.

    Parameters
    ----------
    views : sequence of >= 2 ndarray, shape (H, W) or (H, W, 3)
        Rectified views ordered toward +X, 0..255.
    reference : int
        Index of the view that gets the output.
    positions : sequence of float, optional
        Camera positions in neighbour steps, strictly increasing (default
        0, 1, 2, ...); ``t_k = positions[k] - positions[reference]``.
    method : {"dis", "farneback"}
        ``cv2.DISOpticalFlow`` (preset MEDIUM) or
        ``cv2.calcOpticalFlowFarneback`` (5 levels, window 15).
    chain : bool
        Compute the views in order of increasing ``|t_k|`` and start each
        flow from the disparity fused so far (``-t_k d``): far views move
        several times more than a neighbour, beyond what a flow pyramid
        recovers reliably. False: every flow from zero.

    Returns
    -------
    BaselineResult
        Dense disparity (every pixel; NaN only where the flow is not finite).
    """
    views = _check_views_reference(views, reference)
    n = len(views)
    if method not in ("dis", "farneback"):
        msg = f"method must be 'dis' or 'farneback', got {method!r}"
        raise ValueError(msg)
    chain = check_bool("chain", chain)
    pos = _check_positions(positions, n, reference, f"{n} strictly increasing finite numbers")
    t0 = time.perf_counter()
    grey = [_grey_uint8(v, f"views[{i}]") for i, v in enumerate(views)]
    shapes = {g.shape for g in grey}
    if len(shapes) != 1:
        msg = f"all views must have the same size, got {sorted(shapes)}"
        raise ValueError(msg)
    ref8 = grey[reference]
    if method == "dis" and max(ref8.shape[:2]) < _DIS_MIN_SIDE_PX:
        msg = (
            f"the views are {ref8.shape[1]}x{ref8.shape[0]} px: DIS optical flow needs a side of at least {_DIS_MIN_SIDE_PX} px "
            "(method='farneback' takes smaller ones)"
        )
        raise ValueError(msg)
    t = pos - pos[reference]
    order = sorted((k for k in range(n) if k != reference), key=lambda k: (abs(t[k]), k))
    num = np.zeros(ref8.shape, np.float64)
    den = 0.0
    for k in order:
        init = None
        if chain and den > 0:
            init = np.zeros((*ref8.shape, 2), np.float32)
            init[..., 0] = -t[k] * (num / den)
        flow = _flow(method, ref8, grey[k], init)
        num += -t[k] * flow[..., 0]
        den += t[k] ** 2
    d = (num / den).astype(np.float32)
    d[~np.isfinite(d)] = np.nan
    return BaselineResult(d, time.perf_counter() - t0, f"waxman_sinha/{method}")
