"""Exact percentiles and medians of large arrays, without partitioning all of them.

``np.percentile`` and ``np.median`` partition a copy of the whole array:
2-3 ms for one 640 x 480 image, paid several times per static-stereo call
(the noise estimate of every view, the grey-level range, the search range,
the edge threshold, the flat-pixel median). Here a strided subsample
brackets the wanted order statistics, one pass counts the values below the
bracket and collects those inside it (a compiled loop with numba, NumPy
masks without), and only those few percent are partitioned.

The results are NumPy's bit for bit: the same order statistics and the same
interpolation arithmetic (method ``"linear"``; NumPy's weak promotion for a
Python-scalar ``q``, its float64 one for a sequence; :func:`median` takes
the mean of the middle pair as ``np.median`` does). Small arrays, non-float
dtypes, arrays holding NaN and a bracket that misses (a subsample unlike the
whole) fall back to NumPy itself.
"""

from __future__ import annotations

import math

import numpy as np

try:  # optional compiled pass; NumPy masks otherwise
    from numba import njit as _njit
except ImportError:  # pragma: no cover - depends on the environment
    _njit = None

__all__ = ["median", "percentile", "percentiles"]

_MIN_SIZE = 4096  # below: NumPy (the bracket would not pay)
_SAMPLE = 8192  # subsample size aimed at
_MARGIN_SIGMAS = 4.0  # bracket half-width in binomial standard deviations of the subsample rank
_EXTREME = 0.05  # a rank this close to either end (as a fraction) takes the branching pass


def percentile(values, q: float):
    """``np.percentile(values, q)`` for a Python-number ``q`` (method ``"linear"``), bit for bit."""
    a = np.asanyarray(values)
    if not _eligible(a) or not 0 <= q <= 100:  # NumPy's own error for a q outside [0, 100] or NaN
        return np.percentile(a, q)
    qq = np.true_divide(q, 100)
    prev, nxt, gamma = _virtual_index(a.size, qq)
    stats = _order_statistics(a.ravel(), prev, nxt)
    if stats is None:
        return np.percentile(a, q)
    lo, hi = stats
    t = float(gamma)  # NumPy's weak-q path: float32 data stay float32
    diff = hi - lo
    return hi - diff * (1 - t) if t >= 0.5 else lo + diff * t


def percentiles(values, qs) -> np.ndarray:
    """``np.percentile(values, qs)`` for a 1-D sequence ``qs`` (float64 interpolation, as NumPy), bit for bit."""
    a = np.asanyarray(values)
    q = np.true_divide(np.asarray(qs, np.float64), 100)
    if not _eligible(a) or q.ndim != 1 or not np.all((q >= 0) & (q <= 1)):
        return np.percentile(a, qs)
    lows, highs, gammas = [], [], []
    flat = a.ravel()
    for qq in q:
        prev, nxt, gamma = _virtual_index(a.size, qq)
        stats = _order_statistics(flat, prev, nxt)
        if stats is None:
            return np.percentile(a, qs)
        lows.append(stats[0])
        highs.append(stats[1])
        gammas.append(gamma)
    lo, hi, t = np.array(lows, a.dtype), np.array(highs, a.dtype), np.array(gammas, np.float64)
    # numpy's _lerp, operation for operation
    diff = hi - lo
    out = np.add(lo, diff * t)
    np.subtract(hi, diff * (1 - t), out=out, where=t >= 0.5, casting="unsafe", dtype=type(out.dtype))
    return out


def median(values):
    """``np.median(values)`` (the mean of the middle pair for an even count, in the data's dtype), bit for bit."""
    a = np.asanyarray(values)
    if not _eligible(a):
        return np.median(a)
    n = a.size
    k = n // 2
    stats = _order_statistics(a.ravel(), k - 1 if n % 2 == 0 else k, k)
    if stats is None:
        return np.median(a)
    middle = np.array(stats if n % 2 == 0 else stats[1:], a.dtype)
    return np.mean(middle)


def _eligible(a: np.ndarray) -> bool:
    return a.dtype in (np.float32, np.float64) and a.size >= _MIN_SIZE


def _virtual_index(n: int, qq) -> tuple[int, int, float]:
    """NumPy's linear-method neighbours and weight (its virtual index ``(n - 1) * q``)."""
    vi = (n - 1) * qq
    if vi >= n - 1:
        return n - 1, n - 1, 0.0
    prev = int(np.floor(vi))
    return prev, prev + 1, vi - prev


def _order_statistics(a: np.ndarray, prev: int, nxt: int):
    """The ``prev``-th and ``nxt``-th smallest values of the 1-D float array ``a``, or None (NaN present, bracket missed)."""
    n = a.size
    stride = max(1, n // _SAMPLE) | 1  # odd: less aliasing with an image's rows
    sample = np.array(a[::stride])
    m = sample.size
    p = prev / max(n - 1, 1)
    centre = p * (m - 1)
    margin = _MARGIN_SIGMAS * math.sqrt(m * p * (1.0 - p)) + 4.0
    i_lo, i_hi = max(0, math.floor(centre - margin)), min(m - 1, math.ceil(centre + margin))
    part = np.partition(sample, [i_lo, i_hi])
    lo = part[i_lo] if i_lo > 0 else -np.inf
    hi = part[i_hi] if i_hi < m - 1 else np.inf
    if not (lo <= hi):  # NaN in the subsample
        return None
    expected = (i_hi - i_lo + 1) / m
    cap = min(n, int(3.0 * expected * n) + 1024)
    band = np.empty(cap + 1, a.dtype)  # the last slot takes the writes past the capacity
    # the numba switch is fast.USE_NUMBA (imported here: fast imports this module's users)
    from . import fast as _fast

    if _fast.USE_NUMBA and _njit is not None:
        # near an end of the distribution nearly every value falls on one side:
        # branches predict well there, and the branch-free pass wins elsewhere
        kernel = _nb_bracket_branching if min(p, 1.0 - p) < _EXTREME else _nb_bracket
        below, inside, above = kernel(a, a.dtype.type(lo), a.dtype.type(hi), band)
    else:
        below = int(np.count_nonzero(a < lo))
        above = int(np.count_nonzero(a > hi))
        sel = a[(a >= lo) & (a <= hi)]
        inside = sel.size
        band[: min(inside, cap)] = sel[:cap]
    if below + inside + above != n or inside > cap or not (below <= prev and nxt < below + inside):
        return None  # NaN (fails every comparison), or the order statistics lie outside the bracket
    kth = sorted({prev - below, nxt - below})
    got = np.partition(band[:inside], kth)
    return got[prev - below], got[nxt - below]


if _njit is not None:

    @_njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False)
    def _nb_bracket(a, lo, hi, out):
        """Count ``a < lo`` and ``a > hi``; copy the values in ``[lo, hi]`` to ``out`` (in order, up to ``out.size - 1``)."""
        cap = out.size - 1
        below = 0
        above = 0
        inside = 0
        for x in a:
            below += x < lo
            above += x > hi
            out[min(inside, cap)] = x  # branch-free: kept only if the count moves on
            inside += (x >= lo) & (x <= hi)
        return below, inside, above

    @_njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False)
    def _nb_bracket_branching(a, lo, hi, out):
        """:func:`_nb_bracket` with branches: twice as fast where nearly all values lie on one side of the bracket."""
        cap = out.size - 1
        below = 0
        above = 0
        inside = 0
        for x in a:
            if x >= lo and x <= hi:
                if inside < cap:
                    out[inside] = x
                inside += 1
            elif x < lo:
                below += 1
            elif x > hi:
                above += 1
        return below, inside, above
