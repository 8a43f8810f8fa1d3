"""The aggregated matching-cost volume of static stereo and its winner-take-all.

Step 3c of :mod:`nfdepth.stereo`: for every constant disparity ``d_j`` of a
candidate list, per view ``k`` the truncated absolute difference of
intensity and column gradient between the reference and view ``k`` shifted
by ``t_k d_j``, averaged over the views on one side of the reference,
aggregated by a guided filter (He et al. 2010; cost-volume filtering, Hosni
et al. 2011); the better side wins (Kang & Szeliski 2001), and where the
sides reach unequally far the mean over all views competes against
one-sided costs raised by a penalty (:func:`_both_sides`). The winner over
the candidates gets an equiangular sub-sample fit, and the best cost more
than ``exclude_px`` away from it measures how unique the match is.

Two implementations with the same arithmetic (float32 costs, float64 box
sums):

* NumPy/OpenCV (:func:`_cost_slices` + :func:`_streaming_wta`), the
  reference and the fallback without numba: about 30 full-image array
  operations and eight ``cv2.boxFilter`` calls per candidate.
* numba (:func:`_nb_best_disparity`, used when :data:`nfdepth.fast.USE_NUMBA`):
  per candidate the sides' mean costs (the view shift is constant along a
  row, so it is a fixed-weight two-tap interpolation), then two fused
  passes over both sides at once -- the guided filter's first box sums with
  its coefficients, the second box sums with the better side's output -- as
  running sums in float64 (``cv2.boxFilter``'s own accumulator type), then the
  winner-take-all update over chunks of candidates: slice by slice, its
  per-pixel state (planes along each row) in branch-free loops that numba
  vectorises, and the sub-sample fit in one more kernel. The image is cut into row strips fixed by
  its height (:func:`_row_strips`), each with a halo of twice the box
  radius, that run on ``threads`` threads (the kernels release the GIL), so
  the result does not depend on the thread count. Results agree with the reference to
  float32 rounding (box sums in another order: a few ulp; on the 640 x 480
  Middlebury Art crop of the benchmark they are bit-identical); a cost tie
  within that rounding can pick the other candidate.

Both stream the candidates, so memory is O(pixels) whatever the disparity
range.
"""

from __future__ import annotations

import functools
import itertools
import math
import threading

import cv2
import numpy as np

from . import fast as _fast
from ._scratch import STEREO as _SCRATCH

try:  # optional compiled kernels; the NumPy/OpenCV path otherwise
    from numba import njit as _njit
except ImportError:  # pragma: no cover - depends on the environment
    _njit = None

_CHUNK = 8  # candidates per winner-take-all update of the numba path
_MIN_STRIP_ROWS = 128  # rows per strip of the numba path (see _row_strips)
_MAX_STRIPS = 16


def _box(a: np.ndarray, radius: int) -> np.ndarray:
    return cv2.boxFilter(a, -1, (2 * radius + 1, 2 * radius + 1), normalize=True, borderType=cv2.BORDER_REFLECT)


class _GuidedAggregator:
    """Guided filter (He et al. 2010) with the guide statistics computed once."""

    def __init__(self, guide, radius, eps):
        self.g = guide.astype(np.float32)
        self.r = int(radius)
        self.mi = _box(self.g, self.r)
        vi = _box(self.g * self.g, self.r) - self.mi * self.mi
        self.inv = (1.0 / (np.maximum(vi, 0.0) + np.float32(eps))).astype(np.float32)

    def __call__(self, p):
        mp = _box(p, self.r)
        a = (_box(self.g * p, self.r) - self.mi * mp) * self.inv
        b = mp - a * self.mi
        return (_box(a, self.r) * self.g + _box(b, self.r)).astype(np.float32)


def _match_features(smoothed):
    """Intensity and column gradient of every view, for the truncated matching cost."""
    return [(s, cv2.Sobel(s, cv2.CV_32F, 1, 0, ksize=1, borderType=cv2.BORDER_REFLECT) * np.float32(0.5)) for s in smoothed]


def _shift_cols(img, s):
    """``out(r, c) = img(r, c - s)`` (linear interpolation, border replicated)."""
    h, w = img.shape
    m = np.array([[1.0, 0.0, -float(s)], [0.0, 1.0, 0.0]], np.float64)
    return cv2.warpAffine(img, m, (w, h), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE)


def _sides(t, ref):
    """View indices left and right of the reference (each non-empty list)."""
    sides = [[k for k in range(len(t)) if k != ref and np.sign(t[k]) == sgn] for sgn in (-1, 1)]
    return [ks for ks in sides if ks]


# Penalty of a one-sided cost against the views of both sides, per unit of
# the sides' asymmetry (module docstring), in units of the truncated cost.
_ONE_SIDE_PENALTY = 0.1
# ... raised by up to _NEAR_SIDE_GAIN times where the nearer side's farthest view
# shifts the scene by less than _NEAR_SIDE_SHIFT_PX (see _near_side_gain)
_NEAR_SIDE_SHIFT_PX = 2.0
_NEAR_SIDE_GAIN = 3.0


def _near_side_gain(shift_px) -> float:
    """How much the one-sided penalty grows where the nearer side shifts the scene by ``shift_px`` (median, px).

    ``_NEAR_SIDE_SHIFT_PX / shift_px``, between 1 and ``_NEAR_SIDE_GAIN``; 1
    where the shift is unknown (NaN). A side whose views hardly shift the
    scene has an aggregated cost curve too flat to place a disparity: a
    near view that shifts the scene by 0.4 px has a cost minimum ten times
    as wide as a far view that shifts it by 4 px, and its noise dips below
    the both-sides cost at points both sides see. On the exact
    board-and-wall scene (views -0.2 / 2, the near view shifting it 0.3-0.5
    px) the plain penalty let it win there: dense median error 1.07 %, 4.9
    times the far view's alone; with the gain, 0.28 % (1.3 times). At 2 px
    and more the gain is 1: on the real seven-view rows downsampled by 6
    (near view 2-4 px) a gain up to 4 px cost coverage and pixels within
    0.5 px.
    """
    if not shift_px >= 0.0:
        return 1.0
    if shift_px == 0.0:
        return _NEAR_SIDE_GAIN
    return min(max(_NEAR_SIDE_SHIFT_PX / shift_px, 1.0), _NEAR_SIDE_GAIN)


def _both_sides(t, ref, full_cost, shift_px=math.nan):
    """``(w_left, w_right, penalty, extra)`` of the both-sides cost, or ``None`` where the sides reach equally far.

    The one-sided minimum (Kang & Szeliski 2001) keeps a pixel that one side
    cannot see; but where one side reaches much less far than the other its
    shallow cost curve wins the minimum at unoccluded pixels too, and the
    estimate has that side's precision. So the views of both sides (each side's
    aggregated cost weighted by its number of views, i.e. the mean over all
    views) compete as well, against one-sided costs raised by ``penalty =
    _ONE_SIDE_PENALTY (1 - near / far) full_cost`` (``near``, ``far``: the
    two sides' farthest positions; ``full_cost``: the cost of a mismatch),
    and by ``extra = (gain - 1) penalty`` more where both sides have a view
    inside the image at that candidate (``gain``: :func:`_near_side_gain` of
    the nearer side's shift, ``near`` times ``shift_px``, the median
    disparity in px per unit of ``t``; NaN: unknown, gain 1, no extra).
    Along the border that only one side sees, the other side's views fall
    outside the image at the true disparity but inside at smaller ones,
    where their mismatch mixed into the both-sides cost would otherwise beat
    a one-sided cost raised by the extra (measured: at 4 grey levels of
    noise, views -0.5 / 2, the 4 columns at the border came out near 0
    instead of 1.67 px). Rows that reach as far on both sides keep the plain
    minimum.
    """
    sides = _sides(t, ref)
    if len(sides) < 2:
        return None
    reach = sorted(max(abs(float(t[k])) for k in ks) for ks in sides)
    asymmetry = 1.0 - reach[0] / reach[1]
    if not asymmetry > 1e-6:
        return None
    n0, n1 = len(sides[0]), len(sides[1])
    penalty = _ONE_SIDE_PENALTY * asymmetry * full_cost
    extra = (_near_side_gain(reach[0] * shift_px) - 1.0) * penalty
    return np.float32(n0 / (n0 + n1)), np.float32(n1 / (n0 + n1)), np.float32(penalty), np.float32(extra)


def _cost_slices(feats, t, ref, candidates, agg, *, tau_i, tau_g, alpha, shift_px=math.nan):
    """Aggregated one-sided matching cost of each constant disparity in ``candidates``, one slice at a time.

    Per view the cost is ``(1 - alpha) min(|I_k - I_ref|, tau_i) + alpha
    min(|G_k - G_ref|, tau_g)`` (intensity and column gradient, truncated;
    cost-volume filtering after Hosni et al. 2011), averaged over the views on
    one side of the reference, aggregated by the guided filter ``agg``; the
    better side wins (Kang & Szeliski 2001), or both sides where they reach
    unequally far (:func:`_both_sides`). Yields one ``(h, w)`` slice per
    candidate, so the volume is never held in memory.
    """
    i_ref, g_ref = feats[ref]
    h, w = i_ref.shape
    cols = np.arange(w, dtype=np.float32)[None, :]
    sides = _sides(t, ref)
    mismatch = (1.0 - alpha) * tau_i + alpha * tau_g  # the cost of a view that matches nowhere
    both = _both_sides(t, ref, mismatch, shift_px)
    for dj in candidates:
        best = None
        aggregated = []
        for ks in sides:
            acc = np.zeros((h, w), np.float32)
            cnt = np.zeros((1, w), np.float32)
            for k in ks:
                s = float(t[k]) * float(dj)
                ins = ((cols - s) >= 0) & ((cols - s) <= w - 1)
                ci = np.minimum(np.abs(_shift_cols(feats[k][0], s) - i_ref), tau_i)
                cg = np.minimum(np.abs(_shift_cols(feats[k][1], s) - g_ref), tau_g)
                acc += np.where(ins, (1.0 - alpha) * ci + alpha * cg, 0.0)
                cnt += ins
            mean = np.where(cnt > 0, acc / np.maximum(cnt, 1.0), mismatch).astype(np.float32)
            a = agg(mean)
            a = np.where(np.broadcast_to(cnt > 0, (h, w)), a, np.inf).astype(np.float32)
            aggregated.append(a)
            best = a if best is None else np.minimum(best, a)
        if both is not None:
            w0, w1, penalty, extra = both
            both_seen = np.isfinite(aggregated[0]) & np.isfinite(aggregated[1])
            best = np.minimum(best + (penalty + extra * both_seen.astype(np.float32)), w0 * aggregated[0] + w1 * aggregated[1])
        yield best


def _candidate_step(candidates) -> float:
    """Spacing of the equally spaced ``candidates`` (1 for a single one)."""
    return float(candidates[1] - candidates[0]) if len(candidates) > 1 else 1.0


def _wta_subpixel(vol, candidates, *, interleave=False):
    """Winner-take-all over the whole cost volume with a sub-sample (equiangular) fit: ``(d, c_best)``.

    The plain definition that the streamed versions are tested against. With
    ``interleave`` the winner is taken over the even candidates (the
    search's grid; the odd ones lie halfway between) and refined by
    :func:`_interleaved_fit`.
    """
    n = len(candidates)
    idx = 2 * np.argmin(vol[::2], axis=0) if interleave else np.argmin(vol, axis=0)
    c0 = np.take_along_axis(vol, idx[None], 0)[0]

    def cost_at(k):  # the cost k candidates from the winner (inf outside the volume)
        jj = idx + k
        c = np.take_along_axis(vol, np.clip(jj, 0, n - 1)[None], 0)[0]
        return np.where((jj >= 0) & (jj < n), c, np.float32(np.inf))

    if interleave:
        return _interleaved_fit(idx, cost_at, candidates), c0
    cm = np.where(idx > 0, cost_at(-1), c0)
    cp = np.where(idx < n - 1, cost_at(1), c0)
    return _v_fit(idx, c0, cm, cp, candidates, _candidate_step(candidates)), c0


def _v_offset(cm, c0, cp, inner):
    """Equiangular (V) sub-sample offset of a minimum ``c0`` between ``cm`` and ``cp``, in samples, clipped to +-0.5 (0 unless ``inner``).

    The truncated absolute-difference cost is V-shaped about its minimum,
    and a parabola would pull toward the samples (Shimizu & Okutomi 2005).
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        slope = np.maximum(cm, cp) - c0
        off = np.where(inner & (slope > 0), 0.5 * (cm - cp) / slope, 0.0)
    return np.clip(np.nan_to_num(off), -0.5, 0.5)


def _v_fit(idx, c0, cm, cp, candidates, step):
    """Sub-sample position of the winner ``idx`` from its cost ``c0`` and its neighbours' ``cm``, ``cp``."""
    n = len(candidates)
    off = _v_offset(cm, c0, cp, (idx > 0) & (idx < n - 1))
    d = np.asarray(candidates, np.float32)[idx] + off * step
    return d.astype(np.float32)


def _grid_step(candidates) -> float:
    """Spacing of the interleaved search's grid, the even ``candidates`` (the odd ones lie halfway between)."""
    return float(candidates[2] - candidates[0]) if len(candidates) > 2 else 1.0


def _interleaved_fit(idx, cost_at, candidates):
    """Sub-sample winner of the grid of even ``candidates``, refined with the odd ones halfway between.

    The equiangular fit's bias cycles with the phase of the true disparity
    between its samples (pixel locking; about 0.09 grid steps RMS, nearly a
    sine of the phase). The winner ``idx`` (even) is fitted on its grid
    (``idx - 2, idx, idx + 2``: the plain search's result) and the odd
    neighbour that costs less on the grid of odd candidates (``j - 2, j, j +
    2``, ``j = idx +- 1``); the two phases differ by half a step, so the sine
    cancels in their mean (as Shimizu & Okutomi's half-pixel-shifted matching
    does), while each fit keeps the noise tolerance of samples a whole step
    apart. On a clean minimum the two fits differ by twice the bias (0.3
    steps at most); where they differ by more than half a step, the grids
    see different minima (a sharp, aliased edge: on the bundled noise-free
    pyramid the mean there cost a quarter of the edge points the dense field
    confirms), and the winner's grid alone gives the fit, as it does where
    the odd neighbour is no minimum of its grid (a second surface's costs
    within three candidates: near a depth step) or lies within three
    candidates of an end.
    ``cost_at(k)``: the costs ``k`` candidates from the winner.
    """
    n = len(candidates)
    cand32 = np.asarray(candidates, np.float32)
    span = _grid_step(candidates)
    c0, cm1, cp1 = cost_at(0), cost_at(-1), cost_at(1)
    d_a = cand32[idx] + _v_offset(cost_at(-2), c0, cost_at(2), (idx >= 2) & (idx <= n - 3)) * span
    right = cp1 < cm1
    j = np.clip(idx + np.where(right, 1, -1), 0, n - 1)
    c_j = np.where(right, cp1, cm1)
    c_jm, c_jp = np.where(right, cm1, cost_at(-3)), np.where(right, cost_at(3), cp1)
    d_b = cand32[j] + _v_offset(c_jm, c_j, c_jp, True) * span
    # the odd neighbour is its grid's minimum there, and both fits find the same one
    both = (idx >= 3) & (idx <= n - 4) & (c_j <= c_jm) & (c_j <= c_jp) & (np.abs(d_a - d_b) <= 0.5 * span)
    return np.where(both, np.float32(0.5) * (d_a + d_b), d_a).astype(np.float32)


def _window_half(candidates, exclude_px, *, interleave=False):
    """``m``: slices at least ``m`` from the winner are always more than ``exclude_px`` from its sub-sample position.

    At least 2, so that the window around the winner holds both neighbours
    of its sub-sample fit (steps over twice ``exclude_px`` would give 1).
    With ``interleave``, twice the ``m`` of the grid of even candidates
    for a fit up to 3/4 of its step from the winner (at least 4:
    :func:`_interleaved_fit` reads three candidates either side), whose
    candidates alone count for the uniqueness cost.
    """
    step = _candidate_step(candidates)
    if interleave:  # the grid's step; the fit moves up to 3/4 of it from the winner (_interleaved_fit)
        grid = _grid_step(candidates)
        return 2 * max(2, int(np.floor((exclude_px + 0.75 * grid) / grid)) + 1), step
    return max(2, int(np.floor((exclude_px + 0.5 * step) / step)) + 1), step


def _wta_finish(idx, best, win, far, candidates, step, m, exclude_px, interleave=False):
    """Sub-sample winner and uniqueness cost from the streamed state (see :func:`_streaming_wta`)."""
    n = len(candidates)
    cand32 = np.asarray(candidates, np.float32)
    if interleave:
        d = _interleaved_fit(idx, lambda k: best if k == 0 else win[m - 1 + k], candidates)
    else:
        cm = np.where(idx > 0, win[m - 2], best)  # m >= 2 (_window_half)
        cp = np.where(idx < n - 1, win[m], best)
        d = _v_fit(idx, best, cm, cp, candidates, step)
    c_second = far.copy()
    # interleaved: the even candidates only, as the plain search of that grid
    reach = m - 2 if interleave else m - 1  # (m even when interleaved: the even offsets up to m - 2)
    for k in range(-reach, reach + 1, 2 if interleave else 1):
        jj = np.clip(idx + k, 0, n - 1)
        far_k = (np.abs(cand32[jj] - d) > exclude_px) & (idx + k >= 0) & (idx + k < n)
        np.minimum(c_second, np.where(far_k, win[m - 1 + k], np.inf), out=c_second)
    return d, best, c_second


def _streaming_wta(slices, candidates, *, exclude_px=1.0, interleave=False):
    """:func:`_wta_subpixel` and the uniqueness cost over a stream of cost slices, in O(pixels) memory.

    Returns ``(d, c_best, c_second)``: the sub-sample winner, its cost, and
    the best cost among candidates more than ``exclude_px`` from ``d`` -- the
    same values as the full volume gives. Kept per pixel: the winner's index
    and cost, the costs of the ``m - 1`` slices either side of it, the
    minimum over slices at least ``m`` before it and at least ``m`` after it
    (``m`` such that those are always more than ``exclude_px`` from any
    sub-sample position of the winner), and a ring of the last ``m`` slices.
    With ``interleave`` only the even slices compete and count for the
    minima; the odd ones are kept near the winner for its fit.
    """
    m, step = _window_half(candidates, exclude_px, interleave=interleave)
    ring = [None] * m  # ring[j % m] = slice j
    idx = best = pre = after = win = None
    for j, c in enumerate(slices):
        if idx is None:
            h, w = c.shape
            idx = np.zeros((h, w), np.int32)
            best = np.full((h, w), np.inf, np.float32)
            pre = np.full((h, w), np.inf, np.float32)  # min of slices 0 .. j - m
            after = np.full((h, w), np.inf, np.float32)  # min of slices idx + m .. j
            win = np.full((2 * m - 1, h, w), np.inf, np.float32)  # win[m - 1 + k] = slice idx + k
            far_before = np.full((h, w), np.inf, np.float32)  # min of slices 0 .. idx - m
        grid = not interleave or j % 2 == 0  # a slice of the search's grid (m is even when interleaved)
        if j >= m and grid:
            np.minimum(pre, ring[j % m], out=pre)
        ring[j % m] = c
        new = (c < best) if grid else np.zeros(c.shape, bool)
        rel = j - idx
        # pixels whose winner stays: record the slice near it, or fold it into the far minimum
        for k in range(1, m):
            np.copyto(win[m - 1 + k], c, where=(rel == k) & ~new)
        if grid:
            np.minimum(after, np.where((rel >= m) & ~new, c, np.inf), out=after)
        if new.any():
            idx[new] = j
            best[new] = c[new]
            win[m - 1][new] = c[new]
            for k in range(1, m):
                win[m - 1 - k][new] = ring[(j - k) % m][new] if j - k >= 0 else np.inf
                win[m - 1 + k][new] = np.inf
            after[new] = np.inf
            far_before[new] = pre[new]  # slices 0 .. j - m
    if idx is None:
        msg = "no cost slices"
        raise ValueError(msg)
    return _wta_finish(idx, best, win, np.minimum(far_before, after), candidates, step, m, exclude_px, interleave)


def best_disparity(feats, t, ref, candidates, guide, *, radius, eps, tau_i, tau_g, alpha, exclude_px=1.0, interleave=False, shift_px=math.nan, threads=1):
    """Winner of the aggregated cost volume over ``candidates`` and its uniqueness.

    Parameters
    ----------
    feats : list of (intensity, column gradient) per view, float32 (h, w)
    t : ndarray
        View positions relative to the reference (units of the disparity).
    ref : int
        Reference view index.
    candidates : ndarray, float64
        Equally spaced constant disparities.
    guide : ndarray, float32 (h, w)
        Guide image of the aggregation (the reference, normalised).
    radius, eps : int, float
        Guided-filter box radius and ridge.
    tau_i, tau_g, alpha : float
        Truncations and gradient weight of the per-view cost.
    exclude_px : float
        Candidates farther than this from the winner count for ``c_second``.
    interleave : bool
        The even candidates are the search's grid and the odd ones lie
        halfway between: the winner and its uniqueness are the grid's, and
        the odd ones refine its sub-sample fit (:func:`_interleaved_fit`).
    shift_px : float
        The scene's median disparity, px per unit of ``t`` (NaN: unknown):
        where the sides reach unequally far, a nearer side that shifts the
        scene little pays a larger one-sided penalty (:func:`_both_sides`).
    threads : int
        Threads of the numba path, over the row strips of :func:`_row_strips`
        (the result does not depend on it).

    Returns
    -------
    d, c_best, c_second : ndarray, float32 (h, w)
    """
    agg = _GuidedAggregator(guide, radius, eps)
    if _fast.USE_NUMBA and _njit is not None:
        return _nb_best_disparity(feats, t, ref, candidates, agg, tau_i=tau_i, tau_g=tau_g, alpha=alpha, exclude_px=exclude_px, interleave=interleave, shift_px=shift_px, threads=threads)
    slices = _cost_slices(feats, t, ref, candidates, agg, tau_i=tau_i, tau_g=tau_g, alpha=alpha, shift_px=shift_px)
    return _streaming_wta(slices, candidates, exclude_px=exclude_px, interleave=interleave)


def _row_strips(h, radius):
    """Row strips of the numba cost volume: a power of two of them, fixed by the image height and box radius.

    The strips depend only on ``h`` and ``radius``, never on the thread
    count, so results are the same on any machine. Each strip is at least
    ``max(_MIN_STRIP_ROWS, 8 radius)`` rows (its halo recomputes ``4 radius``
    rows of per-view costs), at most ``_MAX_STRIPS``.
    """
    n = 1
    while 2 * n <= _MAX_STRIPS and h / (2 * n) >= max(_MIN_STRIP_ROWS, 8 * radius):
        n *= 2
    edges = [round(k * h / n) for k in range(n + 1)]
    return list(itertools.pairwise(edges))


def _nb_best_disparity(feats, t, ref, candidates, agg, *, tau_i, tau_g, alpha, exclude_px, interleave=False, shift_px=math.nan, threads=1):
    """:func:`best_disparity` with the fused numba kernels (see the module docstring), strips on ``threads`` threads."""
    h, w = feats[0][0].shape
    # the views' features stacked (scratch: read by the kernels only)
    fi = np.stack([f[0] for f in feats], out=_SCRATCH.empty("intensity", (len(feats), h, w)))
    fg = np.stack([f[1] for f in feats], out=_SCRATCH.empty("gradient", (len(feats), h, w)))
    r = agg.r
    sides = [np.asarray(ks, np.int64) for ks in _sides(t, ref)]
    shifts = [[np.array([float(t[k]) * float(dj) for k in ks], np.float64) for ks in sides] for dj in candidates]
    f32 = np.float32
    a1, a2 = f32(1.0 - alpha), f32(alpha)
    ti, tg = f32(tau_i), f32(tau_g)
    mismatch = (1.0 - alpha) * tau_i + alpha * tau_g
    fill = f32(mismatch)
    both = _both_sides(t, ref, mismatch, shift_px)
    add_r, sub_r = _box_index(h, r)
    add_c, sub_c = _box_index(w, r)
    init_c = _window_rows(0, w, r)
    inv_area = 1.0 / float((2 * r + 1) ** 2)
    n = len(candidates)
    if n == 0:
        msg = "no cost slices"
        raise ValueError(msg)
    m, step = _window_half(candidates, exclude_px, interleave=interleave)
    out = [np.empty((h, w), f32) for _ in range(3)]  # d, c_best, c_second

    stop = threading.Event()  # set by _run_strips on a failure or an interrupt

    def run_strip(y0, y1):
        # output rows y0 .. y1 - 1 need guided coefficients r rows beyond, and those costs r rows further
        ya, yb = max(0, y0 - r), min(h, y1 + r)
        yp, yq = max(0, y0 - 2 * r), min(h, y1 + 2 * r)
        init_ab, init_out = _window_rows(ya, h, r), _window_rows(y0, h, r)
        two = len(sides) == 2
        p, q, a, b, colcnt, buf, idx, state = _strip_scratch(yq - yp, yb - ya, y1 - y0, min(_CHUNK, n), w, m)
        for j0 in range(0, n, buf.shape[1]):
            if stop.is_set():
                return
            count = min(buf.shape[1], n - j0)
            for jj in range(count):
                for si, ks in enumerate(sides):
                    _nb_side_cost(fi, fg, ks, shifts[j0 + jj][si], ref, a1, a2, ti, tg, fill, agg.g, p[si], q[si], colcnt[si], yp, yq)
                _nb_box_coeffs(p, q, agg.mi, agg.inv, init_ab, init_c, add_r, sub_r, add_c, sub_c, inv_area, a, b, ya, yb, yp, ya, two)
                _nb_box_finish(a, b, agg.g, colcnt, init_out, init_c, add_r, sub_r, add_c, sub_c, inv_area, buf, jj, y0, y1, ya, two, both)
            _nb_wta_chunk(buf, count, j0, m, idx, state, interleave)
        _nb_wta_result(idx, state, candidates, step, m, exclude_px, [o[y0:y1] for o in out], interleave=interleave)

    strips = _row_strips(h, r)
    # the kernels (and NumPy's loops of the finish) release the GIL; each strip
    # writes its own rows; on a failure or an interrupt the running strips end
    # at their next chunk
    _fast._run_strips(lambda i: run_strip(*strips[i]), len(strips), int(threads), stop=stop)
    return tuple(out)


def _window_rows(y, n, r):
    """The (cv2.BORDER_REFLECT) indices ``y - r .. y + r`` of a box window in a length-``n`` axis."""
    return np.array([cv2.borderInterpolate(i, n, cv2.BORDER_REFLECT) for i in range(y - r, y + r + 1)], np.int64)


def _strip_scratch(rows_cost, rows_coeff, rows_out, chunk, w, m):
    """One strip's scratch of :func:`_nb_best_disparity`, kept by the thread that runs it (:mod:`nfdepth._scratch`).

    Allocated anew for every strip, these cost about 4400 page faults per
    640 x 480 call (about 60 B per pixel of a strip).

    ``p, q`` (per side, the costs and their products with the guide, over
    ``rows_cost``), ``a, b`` (the guided coefficients, ``rows_coeff``), the
    column counts, the chunk of aggregated slices, and the winner-take-all
    index and state in :func:`_nb_wta_state`'s layout, initialised.
    """
    f32 = np.float32
    bufs = [_SCRATCH.empty(name, (2, rows, w), f32) for name, rows in (("p", rows_cost), ("q", rows_cost), ("a", rows_coeff), ("b", rows_coeff))]
    bufs.append(_SCRATCH.empty("colcnt", (2, w), f32))
    bufs.append(_SCRATCH.empty("chunk", (rows_out, chunk, w), f32))  # candidates j0 .. j0 + chunk - 1, one row plane each
    return (*bufs, *_nb_wta_state((rows_out, w), m, scratch=_SCRATCH))


def _nb_wta_state(shape, m, *, scratch=None):
    """Winner index and the per-row state planes of :func:`_nb_wta_chunk`, initialised (the arrays from ``scratch`` if given)."""
    # per row: best, prefix minimum, far minimum, the 2 m - 1 costs around the winner, the ring of m slices
    h, w = shape
    empty = np.empty if scratch is None else functools.partial(scratch.empty, "wta")
    idx, state = empty((h, w), np.int32), empty((h, 3 + (2 * m - 1) + m, w), np.float32)
    idx.fill(0)
    state.fill(np.inf)
    return idx, state


def _nb_wta_result(idx, state, candidates, step, m, exclude_px, out=None, *, interleave=False):
    """``(d, c_best, c_second)`` from the winner index and state of :func:`_nb_wta_chunk` (as :func:`_wta_finish`), into ``out`` if given."""
    if out is None:
        out = [np.empty(idx.shape, np.float32) for _ in range(3)]
    # float32 as NumPy computes _wta_finish: a Python float step and exclude_px are weak scalars
    step = _grid_step(candidates) if interleave else step
    _nb_wta_finish(idx, state, np.asarray(candidates, np.float32), np.float32(step), m, np.float32(exclude_px), bool(interleave), *out)
    return tuple(out)


def _box_index(n, r):
    """Source indices entering (``i + r + 1``) and leaving (``i - r``) a running box sum, reflected as cv2.BORDER_REFLECT."""
    add = np.array([cv2.borderInterpolate(i + r + 1, n, cv2.BORDER_REFLECT) for i in range(n)], np.int64)
    sub = np.array([cv2.borderInterpolate(i - r, n, cv2.BORDER_REFLECT) for i in range(n)], np.int64)
    return add, sub


if _njit is not None:
    _jit = _njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False)
    _jit_inline = _njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False, inline="always")

    @_jit_inline
    def _nb_view_cost(i0, i1, g0, g1, i_ref, g_ref, w0, f, a1, a2, tau_i, tau_g):
        """One pixel's truncated cost of a view sampled between its taps (intensities ``i0, i1``, gradients ``g0, g1``; weights ``w0, f``)."""
        vi = i0 * w0 + i1 * f
        vg = g0 * w0 + g1 * f
        return a1 * min(abs(vi - i_ref), tau_i) + a2 * min(abs(vg - g_ref), tau_g)

    @_jit_inline
    def _nb_side_cost_clamped(ik, gk, ir, gr, o, f, w0, a1, a2, tau_i, tau_g, acc, c_lo, c_hi):
        """Add columns ``c_lo .. c_hi - 1`` of one view's truncated cost to ``acc``, taps clamped to the row (border replicated)."""
        w = ik.size
        for c in range(c_lo, c_hi):
            i0 = min(max(c + o, 0), w - 1)
            i1 = min(i0 + 1, w - 1)
            acc[c] += _nb_view_cost(ik[i0], ik[i1], gk[i0], gk[i1], ir[c], gr[c], w0, f, a1, a2, tau_i, tau_g)

    @_jit
    def _nb_side_cost(fi, fg, ks, shifts, ref, a1, a2, tau_i, tau_g, fill, guide, p, q, colcnt, r_lo, r_hi):
        """Mean truncated cost of the views ``ks`` shifted by ``shifts`` (``p``) and ``guide * p`` (``q``), rows ``r_lo .. r_hi - 1``.

        Row ``r`` goes to row ``r - r_lo`` of ``p`` and ``q``.

        View ``k`` at column ``c`` is sampled at ``x = c - s``: with ``o =
        floor(-s)`` and ``f = -s - o``, between columns ``c + o`` and ``c + o + 1``
        with the same weights on the whole image (border replicated, as
        ``cv2.warpAffine``); columns with ``x`` outside ``[0, w - 1]`` do not count.
        """
        w = fi.shape[2]
        nk = ks.size
        lo = np.empty(nk, np.int64)
        hi = np.empty(nk, np.int64)
        mid_lo = np.empty(nk, np.int64)
        mid_hi = np.empty(nk, np.int64)
        off = np.empty(nk, np.int64)
        frac = np.empty(nk, np.float32)
        for c in range(w):
            colcnt[c] = 0.0
        for v in range(nk):
            s = shifts[v]
            o = math.floor(-s)
            off[v] = o
            frac[v] = np.float32(-s - o)
            first = w
            last = -1
            for c in range(w):
                x = np.float32(c) - np.float32(s)
                if x >= 0 and x <= w - 1:
                    colcnt[c] += 1.0
                    if c < first:
                        first = c
                    last = c
            lo[v] = first
            hi[v] = last + 1
            # columns whose taps c + o and c + o + 1 both lie inside the row need no clamping
            mid_lo[v] = min(max(first, -o), last + 1)
            mid_hi[v] = max(mid_lo[v], min(last + 1, w - 1 - o))
        acc = np.empty(w, np.float32)
        one = np.float32(1.0)
        for r in range(r_lo, r_hi):
            ir = fi[ref, r]
            gr = fg[ref, r]
            for c in range(w):
                acc[c] = 0.0
            for v in range(nk):
                k = ks[v]
                ik = fi[k, r]
                gk = fg[k, r]
                o = off[v]
                f = frac[v]
                g0 = one - f
                # the border columns with clamped taps, then the interior on
                # views of the rows that start at its first column: indexed
                # from 0 alike, that loop vectorises (five times faster)
                _nb_side_cost_clamped(ik, gk, ir, gr, o, f, g0, a1, a2, tau_i, tau_g, acc, lo[v], mid_lo[v])
                c0 = mid_lo[v]
                ik0, ik1, gk0, gk1 = ik[c0 + o :], ik[c0 + o + 1 :], gk[c0 + o :], gk[c0 + o + 1 :]
                ir0, gr0, acc0 = ir[c0:], gr[c0:], acc[c0:]
                for j in range(mid_hi[v] - c0):
                    acc0[j] += _nb_view_cost(ik0[j], ik1[j], gk0[j], gk1[j], ir0[j], gr0[j], g0, f, a1, a2, tau_i, tau_g)
                _nb_side_cost_clamped(ik, gk, ir, gr, o, f, g0, a1, a2, tau_i, tau_g, acc, mid_hi[v], hi[v])
            gd = guide[r]
            pr = p[r - r_lo]
            qr = q[r - r_lo]
            for c in range(w):
                cn = colcnt[c]
                mean = acc[c] / max(cn, one) if cn > 0 else fill
                pr[c] = mean
                qr[c] = gd[c] * mean

    # Two box filters at once as running sums (float64, cv2.boxFilter's accumulator):
    # column sums over the rows of the window, then a running sum along each row.
    @_jit_inline
    def _nb_columns_init(a, b, rows, off, col_a, col_b):
        """Column sums of ``a`` and ``b`` over the (reflected) image ``rows`` of the first window (image row ``y`` is array row ``y - off``)."""
        w = a.shape[1]
        for c in range(w):
            col_a[c] = 0.0
            col_b[c] = 0.0
        for yy in rows:
            y = yy - off
            for c in range(w):
                col_a[c] += a[y, c]
                col_b[c] += b[y, c]

    @_jit_inline
    def _nb_columns_step(a, b, y_add, y_sub, col_a, col_b):
        """Slide the column sums one row down: add array row ``y_add``, drop array row ``y_sub``."""
        for c in range(a.shape[1]):
            col_a[c] += np.float64(a[y_add, c]) - np.float64(a[y_sub, c])
            col_b[c] += np.float64(b[y_add, c]) - np.float64(b[y_sub, c])

    @_jit_inline
    def _nb_columns_init_sides(a, b, rows, off, two):
        """Column sums of ``a`` and ``b`` (planes: sides; side 1 only if ``two``) over the image ``rows`` of the first window."""
        w = a.shape[2]
        col_a0 = np.empty(w, np.float64)
        col_b0 = np.empty(w, np.float64)
        col_a1 = np.empty(w, np.float64)
        col_b1 = np.empty(w, np.float64)
        _nb_columns_init(a[0], b[0], rows, off, col_a0, col_b0)
        if two:
            _nb_columns_init(a[1], b[1], rows, off, col_a1, col_b1)
        return col_a0, col_b0, col_a1, col_b1

    @_jit_inline
    def _nb_columns_step_sides(a, b, y_add, y_sub, col_a0, col_b0, col_a1, col_b1, two):
        """:func:`_nb_columns_step` of both sides (side 1 only if ``two``)."""
        _nb_columns_step(a[0], b[0], y_add, y_sub, col_a0, col_b0)
        if two:
            _nb_columns_step(a[1], b[1], y_add, y_sub, col_a1, col_b1)

    @_jit_inline
    def _nb_row_start(col_a, col_b, cols):
        """Box sums of the first window of a row from the column sums."""
        sa = 0.0
        sb = 0.0
        for x in cols:
            sa += col_a[x]
            sb += col_b[x]
        return sa, sb

    @_jit
    def _nb_box_coeffs(p, q, mi, inv, init_r, init_c, add_r, sub_r, add_c, sub_c, inv_area, a, b, y_lo, y_hi, src_off, dst_off, two):
        """Guided-filter coefficients ``a = (box(q) - mi box(p)) inv``, ``b = box(p) - a mi`` of both sides (float64 running sums).

        ``p``, ``q``, ``a``, ``b`` hold one plane per side; plane 1 is used
        only if ``two``. The two sides' running sums are independent chains
        in one loop, which hides the latency of each. Image rows ``y_lo ..
        y_hi - 1``; ``init_r`` are the (reflected) image rows of ``y_lo``'s
        window. Image row ``y`` is row ``y - src_off`` of ``p``, ``q`` and row
        ``y - dst_off`` of ``a``, ``b``.
        """
        w = p.shape[2]
        colp0, colq0, colp1, colq1 = _nb_columns_init_sides(p, q, init_r, src_off, two)
        for y in range(y_lo, y_hi):
            sp0, sq0 = _nb_row_start(colp0, colq0, init_c)
            sp1, sq1 = _nb_row_start(colp1, colq1, init_c) if two else (0.0, 0.0)
            mir = mi[y]
            invr = inv[y]
            a0 = a[0, y - dst_off]
            b0 = b[0, y - dst_off]
            a1 = a[1, y - dst_off]
            b1 = b[1, y - dst_off]
            for x in range(w):
                m = mir[x]
                iv = invr[x]
                mp = np.float32(sp0 * inv_area)
                mq = np.float32(sq0 * inv_area)
                av = (mq - m * mp) * iv
                a0[x] = av
                b0[x] = mp - av * m
                xa = add_c[x]
                xs = sub_c[x]
                sp0 += colp0[xa] - colp0[xs]
                sq0 += colq0[xa] - colq0[xs]
                if two:
                    mp = np.float32(sp1 * inv_area)
                    mq = np.float32(sq1 * inv_area)
                    av = (mq - m * mp) * iv
                    a1[x] = av
                    b1[x] = mp - av * m
                    sp1 += colp1[xa] - colp1[xs]
                    sq1 += colq1[xa] - colq1[xs]
            if y + 1 < y_hi:
                _nb_columns_step_sides(p, q, add_r[y] - src_off, sub_r[y] - src_off, colp0, colq0, colp1, colq1, two)

    @_jit
    def _nb_box_finish(a, b, guide, colcnt, init_r, init_c, add_r, sub_r, add_c, sub_c, inv_area, out, plane, y_lo, y_hi, src_off, two, mix):
        """The better side's guided-filter output ``box(a) guide + box(b)`` (inf in columns its views miss) into ``out[:, plane]``.

        Both sides in one loop (as :func:`_nb_box_coeffs`; side 1 only if
        ``two``); side 1 wins only where its cost is lower. With ``mix =
        (w0, w1, penalty, extra)`` (:func:`_both_sides`; ``None``: the plain
        minimum) the better side's cost plus ``penalty`` (plus ``extra``
        where both sides have a value) competes with ``w0 side0 + w1
        side1``. Image rows ``y_lo .. y_hi - 1`` (row ``y -
        y_lo`` of ``out``); image row ``y`` is row ``y - src_off`` of ``a``
        and ``b``.
        """
        w = a.shape[2]
        cnt0, cnt1 = colcnt[0], colcnt[1]
        inf = np.float32(np.inf)
        cola0, colb0, cola1, colb1 = _nb_columns_init_sides(a, b, init_r, src_off, two)
        for y in range(y_lo, y_hi):
            sa0, sb0 = _nb_row_start(cola0, colb0, init_c)
            sa1, sb1 = _nb_row_start(cola1, colb1, init_c) if two else (0.0, 0.0)
            gr = guide[y]
            orow = out[y - y_lo, plane]
            for x in range(w):
                g = gr[x]
                v = np.float32(sa0 * inv_area) * g + np.float32(sb0 * inv_area)
                if cnt0[x] == 0:
                    v = inf
                xa = add_c[x]
                xs = sub_c[x]
                sa0 += cola0[xa] - cola0[xs]
                sb0 += colb0[xa] - colb0[xs]
                if two:
                    v1 = np.float32(sa1 * inv_area) * g + np.float32(sb1 * inv_area)
                    if cnt1[x] == 0:
                        v1 = inf
                    if mix is None:  # (numba compiles this case without the other branch)
                        if v1 < v:
                            v = v1
                    elif mix[3] == 0:  # (loop-invariant: the plain penalty costs nothing more)
                        v = min(min(v, v1) + mix[2], mix[0] * v + mix[1] * v1)
                    else:
                        pen = mix[2] + mix[3] * np.float32((v < inf) & (v1 < inf))
                        v = min(min(v, v1) + pen, mix[0] * v + mix[1] * v1)
                    sa1 += cola1[xa] - cola1[xs]
                    sb1 += colb1[xa] - colb1[xs]
                orow[x] = v
            if y + 1 < y_hi:
                _nb_columns_step_sides(a, b, add_r[y] - src_off, sub_r[y] - src_off, cola0, colb0, cola1, colb1, two)

    @_jit
    def _nb_wta_chunk(chunk, count, j0, m, idx, state, interleave):
        """Winner-take-all update over slices ``j0 .. j0 + count - 1`` (``chunk[:, :count]``), as :func:`_streaming_wta`.

        ``state[r]`` holds planes of the row's best cost, prefix minimum
        (slices ``0 .. j - m``), far minimum, the ``2 m - 1`` costs around the
        winner and the ring of the last ``m`` slices (slice ``j`` in plane
        ``j % m``). Slice by slice, each plane is updated along the row in a
        branch-free loop that numba vectorises: first the window (whose
        update reads the winner before this slice), then the rest. With
        ``interleave`` an odd slice is only recorded near the winner and in
        the ring (:func:`_streaming_wta`).
        """
        h = chunk.shape[0]
        w = chunk.shape[2]
        inf = np.float32(np.inf)
        nw = 2 * m - 1
        for r in range(h):
            st = state[r]
            ir = idx[r]
            bst = st[0]
            pr = st[1]
            fr = st[2]
            for jq in range(count):
                j = j0 + jq
                cost = chunk[r, jq]
                if interleave and j % 2 == 1:
                    for e in range(m, nw):  # the winner's later slices (odd offsets from an even winner)
                        win = st[3 + e]
                        k = e - (m - 1)
                        for c in range(w):
                            win[c] = cost[c] if j - ir[c] == k else win[c]
                    ring = st[3 + nw + j % m]
                    for c in range(w):
                        ring[c] = cost[c]
                    continue
                for e in range(nw):
                    win = st[3 + e]
                    k = e - (m - 1)  # win holds slice idx + k
                    # a new winner's window: its earlier slices from the ring (inf before
                    # slice 0), itself, its later ones unknown (inf); a kept winner's later
                    # slices are filled in as they come
                    src = cost if k == 0 else st[3 + nw + (j + k) % m]
                    known = k == 0 or (k < 0 and j + k >= 0)
                    later = k > 0
                    for c in range(w):
                        # every value loaded before the choice, so that the loop is branch-free
                        cv = cost[c]
                        s_c = src[c]
                        old = win[c]
                        kept = cv if later and j - ir[c] == k else old
                        win[c] = (s_c if known else inf) if cv < bst[c] else kept
                ring = st[3 + nw + j % m]  # slice j - m, then slice j
                if j >= m:
                    for c in range(w):
                        old = ring[c]
                        p_c = pr[c]
                        pr[c] = min(p_c, old)
                for c in range(w):
                    cv = cost[c]
                    b_c = bst[c]
                    i_c = ir[c]
                    f = fr[c]
                    p_c = pr[c]
                    new = cv < b_c
                    far = cv if (j - i_c >= m) & (cv < f) else f
                    fr[c] = p_c if new else far
                    bst[c] = cv if new else b_c
                    ir[c] = j if new else i_c
                    ring[c] = cv

    @_jit_inline
    def _nb_v_offset(cm, c0, cp, inner):
        """:func:`_v_offset` of one pixel: NaN-propagating maximum, nan_to_num, clip (float32)."""
        half = np.float32(0.5)
        slope = (cm if (math.isnan(cm) or cm > cp) else cp) - c0
        off = np.float32(0.0)
        if inner and slope > 0:
            off = half * (cm - cp) / slope
            if math.isnan(off):
                off = np.float32(0.0)
        return min(max(off, -half), half)

    @_jit
    def _nb_wta_finish(idx, state, cand32, step, m, exclude, interleave, d, c_best, c_second):
        """:func:`_wta_finish` of the state of :func:`_nb_wta_chunk` into ``d``, ``c_best``, ``c_second``, with its float32 arithmetic.

        ``step``: the candidates' spacing, or with ``interleave`` the grid's (:func:`_grid_step`).
        """
        h, w = idx.shape
        n = cand32.size
        half = np.float32(0.5)
        reach = m - 2 if interleave else m - 1  # the window's offsets of the winner's grid (_wta_finish)
        kstep = 2 if interleave else 1
        for r in range(h):
            st = state[r]
            for c in range(w):
                i = idx[r, c]
                c0 = st[0, c]
                if interleave:
                    # _interleaved_fit: the even winner on its grid, averaged with the cheaper odd neighbour on the odd grid
                    cm1 = st[3 + m - 2, c]
                    cp1 = st[3 + m, c]
                    dv = cand32[i] + _nb_v_offset(st[3 + m - 3, c], c0, st[3 + m + 1, c], i >= 2 and i <= n - 3) * step
                    if cp1 < cm1:
                        j, c_j, c_jm, c_jp = i + 1, cp1, cm1, st[3 + m + 2, c]
                    else:
                        j, c_j, c_jm, c_jp = i - 1, cm1, st[3 + m - 4, c], cp1
                    if i >= 3 and i <= n - 4 and c_j <= c_jm and c_j <= c_jp:
                        d_b = cand32[j] + _nb_v_offset(c_jm, c_j, c_jp, True) * step
                        if abs(dv - d_b) <= half * step:
                            dv = half * (dv + d_b)
                else:
                    cm = st[3 + m - 2, c] if i > 0 else c0
                    cp = st[3 + m, c] if i < n - 1 else c0
                    dv = cand32[i] + _nb_v_offset(cm, c0, cp, i > 0 and i < n - 1) * step
                d[r, c] = dv
                c_best[r, c] = c0
                # np.minimum over the far window entries (NaN-propagating)
                c2 = st[2, c]
                for k in range(-reach, reach + 1, kstep):
                    jj = min(max(i + k, 0), n - 1)
                    if abs(cand32[jj] - dv) > exclude and i + k >= 0 and i + k < n:
                        v = st[3 + m - 1 + k, c]
                        c2 = v if not math.isnan(c2) and (math.isnan(v) or v < c2) else c2
                c_second[r, c] = c2
