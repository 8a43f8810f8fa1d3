"""Fast single-level normal flow and edge points (float32, OpenCV kernels).

Same results as the plain reference path --
:func:`nfdepth.normal_flow.normal_flow` followed by
:func:`nfdepth.edges.select_edge_points` -- to float32 rounding, computed
with far fewer passes over the image:

* **Linearity.** Smoothing and every derivative stencil are linear, so the
  Simpson-weighted spatial gradient of a triple is the stencil of the
  smoothed *weighted sum* ``w0 f0 + w1 f1 + w2 f2``, and ``I_t`` is the cell
  mean of the smoothed *difference* ``f2 - f0``. A triple costs three
  Gaussian passes -- weighted sum, difference and middle frame (for the
  Laplacian zero crossings) -- instead of three plus the stencil's work on
  each frame. The 2 x 2 cell mean of ``I_t`` is folded into its Gaussian
  (an even-length separable kernel; exact, borders included, because both
  are applied to reflected *source* indices).
* **Small stencils as one filter.** The matched 4-point difference along one
  axis with the 2-tap mean along the other is one ``cv2.filter2D`` call with
  a 2 x 4 kernel; ``BORDER_REPLICATE`` reproduces the reference's edge
  padding exactly.
* **No per-call allocations.** Intermediates live in a per-thread
  workspace keyed by image size (6 float32 + 3 bool images and the block
  tensor, 30 B/px). The
  four outputs come from a pool of two sets that is recycled once the
  caller holds no reference to a set (checked with CPython reference
  counts against a private sentinel), so results that are kept are never
  overwritten. Reason: fresh pages cost a page fault each, ~5 us apiece on
  this kind of VM, and glibc returns large freed blocks to the kernel, so
  re-allocating ~1.2 MB per output per call cost ~1300 faults (several ms)
  per 640 x 480 triple. The sparse work runs in bands of rows for the same
  reason (small temporaries).
* **Sparse corner test.** The structure tensor is the reference's block-grid
  one (:func:`nfdepth.edges.block_structure_tensor`: 2 x 2 block means of
  the gradient products, one 3-channel Gaussian pass over a quarter of the
  cells); it is read back bilinearly and its eigenvalue ratio evaluated only
  at the candidate cells (strong zero crossings inside the border), in
  float64.
* **Angle.** ``alpha`` is computed (float64 ``atan2``; float32 on the numba
  path) only at the edge points (numba path) or candidate edge points
  (fallback), where it is used; it is NaN elsewhere. A full-grid angle costs
  more than a blur (``np.arctan2``) or is not deterministic (``cv2.phase``'s
  SIMD path depends on buffer alignment).

**Backends.** With numba installed (``USE_NUMBA``; set ``NFDEPTH_NO_NUMBA=1``
to force the fallback) everything after the smoothing runs as two compiled
loops (``fastmath=False``: bit-identical across runs, buffers and thread
counts): one pass over the cell grid (combined stencils, ``I_t``,
``|grad I|``, ``vn``, Laplacian signs in cv2's own summation order, the list
of zero-crossing cells), then, after the percentile (exact, as
``np.percentile``), the block tensor (its block means accumulated in the
cell-grid pass, ``cv2.sepFilter2D`` for the window), a branch-free compaction of
the strong candidates and one pass over them: bilinear read-back,
eigenvalue test (float64, branch-free), with the
accepted points' gradients packed for NumPy's SIMD float32 ``atan2`` (the
reference's own; a scalar call costs ~25 ns a point). The percentile
partitions only the values a subsample brackets (:mod:`nfdepth._quantile`). It blurs the three frames separately (3 Gaussian passes), so
:class:`StreamingNormalFlow` keeps only the smoothed frames and a new frame
costs one Gaussian pass plus the fused work; streamed and from-scratch
results are bit-identical. Without numba the numpy/OpenCV path below runs
(first numba call compiles, ~9 s; cached on disk afterwards, ~0.4 s).

**Threads** (numba path, ``threads=``, default ``cv2.getNumThreads()``). The
blurs, the cell-grid pass and the edge-point tests run in row strips of at
least 2**17 pixels (a 640 x 480 image: two) on a shared pool, with the
percentile beside the block tensor's window in between. The calling thread
claims strips as well, so it never waits for a worker that has not woken
(an idle core of a VM can take longer to wake than a strip takes). A strip is
blurred from its rows plus the kernel radius (bit-identical to the whole
image's ``cv2.sepFilter2D``, which itself runs on one thread), the cell-grid
pass primes its row ring at the strip's first row (an even one: whole
blocks of the tensor), and each strip lists and packs its candidates in its
own part of the buffers, so results are bit-identical for any thread count.

:class:`StreamingNormalFlow` keeps each frame's smoothed image (and its cell
mean) in a ring, so a video costs one Gaussian pass per new frame plus the
per-triple work.

Positions: every output belongs to cell ``[r, c]`` -- the centre ``(r + 0.5,
c + 0.5)`` of a 2 x 2 pixel group -- at the time of the middle frame, shape
``(H - 1, W - 1)``, exactly as in :mod:`nfdepth.normal_flow`.

Differences from the reference (all at float32 rounding level; ``alpha`` is
NaN off the candidate edge points, see above):

* sums are taken in a different order (weighted sum before smoothing), so
  gradients agree to ~1e-6 of their scale, not bit for bit;
* the block structure tensor is built in float32 (the reference uses float64),
  so a cell whose corner ratio equals ``max_corner_ratio`` to ~1e-6 can fall
  on the other side; likewise a gradient magnitude equal to the threshold to
  one ulp. These threshold ties are the only way the masks can differ.
"""

from __future__ import annotations

import itertools
import math
import os
import sys
import threading
from collections import deque
from dataclasses import dataclass

import cv2
import numpy as np

from ._quantile import percentile
from ._validate import MIN_FLOAT32_INTENSITY, as_frames, as_image, check_fraction, check_frame_interval, check_int, check_scale_px, check_threshold
from .edges import ROUNDING_GRADIENT, ROUNDING_LAPLACIAN, _block_read_back, _comparable_threshold, _corner_window_blocks
from .normal_flow import _MATCHED_NEAR, _MATCHED_WIDE, _TEMPORAL_WEIGHTS, _check_stencil

try:  # optional: the fused compiled kernels (numba); the numpy/OpenCV path otherwise
    from numba import njit as _njit
except ImportError:  # pragma: no cover - depends on the environment
    _njit = None

#: True when the fused numba kernels are used (numba importable and
#: ``NFDEPTH_NO_NUMBA`` unset). Tests flip it to cover both paths.
USE_NUMBA = _njit is not None and not os.environ.get("NFDEPTH_NO_NUMBA")

__all__ = ["NormalFlowEdges", "normal_flow_edges", "StreamingNormalFlow", "USE_NUMBA"]

_TWO_PI = np.float32(2.0 * np.pi)
_PI = np.float32(np.pi)


@dataclass(frozen=True)
class NormalFlowEdges:
    """Normal flow and edge points of one triple, on the cell grid (H-1, W-1).

    Unpacks as ``vn, alpha, magnitude, mask = result``.

    Attributes
    ----------
    vn : ndarray float32
        Normal flow ``-I_t / |grad I|`` in px per unit time (NaN where the
        gradient is exactly 0).
    alpha : ndarray float32
        Normal direction ``atan2(I_row, I_col)`` in radians, in [-pi, pi]:
        at the edge points (``mask``; the numpy/OpenCV fallback also at the
        strong candidates, a superset), NaN elsewhere.
    magnitude : ndarray float32
        ``|grad I|`` in intensity per pixel.
    mask : ndarray bool
        Strong, non-corner zero-crossing edge points away from the border
        (:func:`nfdepth.edges.select_edge_points`).
    min_gradient : float
        Gradient threshold used.
    """

    vn: np.ndarray
    alpha: np.ndarray
    magnitude: np.ndarray
    mask: np.ndarray
    min_gradient: float

    def __iter__(self):
        return iter((self.vn, self.alpha, self.magnitude, self.mask))


# --------------------------------------------------------------- parameters


@dataclass(frozen=True)
class _Params:
    sigma_px: float
    frame_interval: float
    stencil: str
    min_gradient: float | None
    relative_gradient: float
    max_corner_ratio: float
    corner_window_px: float
    border_px: int


def _params(sigma_px, frame_interval, stencil, min_gradient, relative_gradient, max_corner_ratio, corner_window_px, border_px):
    sigma_px = check_scale_px("sigma_px", sigma_px)
    frame_interval = check_frame_interval("frame_interval", frame_interval)
    _check_stencil(stencil)
    if min_gradient is not None:
        min_gradient = check_threshold("min_gradient", min_gradient)
    relative_gradient = check_threshold("relative_gradient", relative_gradient)
    max_corner_ratio = check_fraction("max_corner_ratio", max_corner_ratio)
    if corner_window_px is None:
        corner_window_px = max(sigma_px, 1.0)
    corner_window_px = check_scale_px("corner_window_px", corner_window_px, zero_ok=False)
    border_px = check_int("border_px", border_px, 0)
    return _Params(sigma_px, frame_interval, stencil, min_gradient, relative_gradient, max_corner_ratio, corner_window_px, border_px)


def _gauss_kernel(sigma_px: float, radius_sigmas: float) -> np.ndarray:
    """The float64 Gaussian kernel that ``cv2.GaussianBlur`` uses (reference's truncation)."""
    radius = max(1, int(np.ceil(radius_sigmas * sigma_px)))
    return cv2.getGaussianKernel(2 * radius + 1, sigma_px, cv2.CV_64F).ravel()


# ----------------------------------------------------------------- workspace


class _Pool:
    """Recycled output sets for one image size (see :meth:`outputs`)."""

    def __init__(self, shape):
        self.shape = shape
        self.pool: list = []  # recycled output sets (vn, alpha, mag, mask)

    def outputs(self):
        """Output arrays ``(vn, alpha, mag, mask)`` for one call.

        Fresh pages cost a page fault each (~300 per 0.3 Mpx float32 array,
        several microseconds apiece on a VM) and glibc hands large freed
        blocks back to the kernel, so a loop that allocates its outputs anew
        pays that every call. Instead, up to two sets are kept here and a set
        is reused once nothing outside this pool refers to any of its arrays
        (CPython reference counts: a result, a view or an exported buffer all
        hold references), so results a caller keeps are never overwritten.
        """
        for item in self.pool:
            # The last entry is a private sentinel that is never handed out: it
            # sees exactly the references a free array sees, whatever this
            # interpreter's reference-counting details are.
            counts = [sys.getrefcount(x) for x in item]
            if max(counts[:4]) <= counts[4]:
                return item[:4]
        h, w = self.shape[0] - 1, self.shape[1] - 1
        f32 = np.float32
        item = (np.empty((h, w), f32), np.empty((h, w), f32), np.empty((h, w), f32), np.empty((h, w), bool), np.empty(0, f32))
        if len(self.pool) < 2:
            self.pool.append(item)
        return item[:4]


def _tensor_buffers(h, w):
    """Block-grid structure tensor ((hb, wb, 3) float32, smoothed in place: 3 B/px) and its read-back tables."""
    hb, wb = (h + 1) // 2, (w + 1) // 2
    return np.empty((hb, wb, 3), np.float32), _block_read_back(h, hb) + _block_read_back(w, wb)


class _Workspace(_Pool):
    """Reusable buffers of the numpy/OpenCV path (one size, one thread): 6 float32 + 3 bool images + block tensor, 30 B/px."""

    def __init__(self, shape):
        super().__init__(shape)
        H, W = shape
        h, w = H - 1, W - 1
        f32 = np.float32
        self.A = np.empty((H, W), f32)  # weighted sum -> Laplacian -> product
        self.D = np.empty((H, W), f32)  # f2 - f0 -> smoothed middle frame -> product
        self.Gs = np.empty((H, W), f32)  # smoothed weighted sum (read again at the candidates)
        self.gt = np.empty((H, W), f32)  # I_t at cells ([:h, :w])
        self.gc = np.empty((H, W), f32)  # I_col at cells ([:h, :w])
        self.gr = np.empty((H, W), f32)  # I_row at cells ([:h, :w])
        self.b1 = np.empty((H, W), bool)
        self.b2 = np.empty((H, W), bool)
        self.b3 = np.empty((h, w), bool)
        self.tensor, self.read_back = _tensor_buffers(h, w)


class _NbWorkspace(_Pool):
    """Reusable buffers of the numba path: 3 smoothed frames (from scratch only), I_col, I_row, candidate list, block tensor (27 or 15 B/px; on threads, the blur strips' scratch rows: about 4 B/px more)."""

    def __init__(self, shape, frames=True):
        super().__init__(shape)
        H, W = shape
        h, w = H - 1, W - 1
        # smoothed frames (from-scratch calls only: a stream keeps its own ring)
        self.G = np.empty((3, H, W), np.float32) if frames else None
        self.gc = np.empty((h, w), np.float32)
        self.gr = np.empty((h, w), np.float32)
        # zero-crossing cells (flat cell indices) and their start in each cell row
        self.cand = np.empty(h * w, np.int32 if h * w < 2**31 else np.int64)
        self.rows = np.empty(h, np.int64)
        self.tensor, self.read_back = _tensor_buffers(h, w)
        self._scratch: dict = {}  # per thread that runs a blur strip (threads > 1 only), see _blur_strips

    def scratch(self, key: int, rows: int) -> np.ndarray:
        """Float32 rows ``(rows, W)`` of thread ``key``'s own buffer (kept; grown when needed)."""
        buf = self._scratch.get(key)
        if buf is None or buf.shape[0] < rows:
            buf = self._scratch[key] = np.empty((rows, self.shape[1]), np.float32)
        return buf[:rows]


_local = threading.local()


def _workspace(shape, cls=None):
    cls = cls or (_NbWorkspace if USE_NUMBA else _Workspace)
    ws = getattr(_local, "ws", None)
    if ws is None or ws.shape != shape or type(ws) is not cls:
        ws = cls(shape)
        _local.ws = ws
    return ws


# ------------------------------------------------------------------ kernels


class _Kernels:
    """Separable / small kernels for one parameter set (cached)."""

    def __init__(self, p: _Params):
        self.p = p
        self.smooth = p.sigma_px > 0
        if self.smooth:
            g = _gauss_kernel(p.sigma_px, 4.0)
            self.g = g.astype(np.float32)
            self.radius = (g.size - 1) // 2
            # Gaussian folded with the 2-tap mean (cell mean of I_t), scaled by 1/(2 dt) on one axis.
            gm = 0.5 * (np.append(g, 0.0) + np.insert(g, 0, 0.0))
            self.gm_x = (gm / (2.0 * p.frame_interval)).astype(np.float32)
            self.gm_y = gm.astype(np.float32)
        w = _TEMPORAL_WEIGHTS[p.stencil]
        self.weights = tuple(float(x) for x in w)
        if p.stencil == "matched":
            row = np.array([-_MATCHED_WIDE, -_MATCHED_NEAR, _MATCHED_NEAR, _MATCHED_WIDE])
            self.anchor_shift = 1  # taps at c-1 .. c+2
        else:
            row = np.array([-1.0, 1.0])
            self.anchor_shift = 0  # taps at c .. c+1
        k_col = 0.5 * np.vstack([row, row])  # 2 rows x n cols
        self.k_col = k_col.astype(np.float32)
        self.k_row = np.ascontiguousarray(k_col.T).astype(np.float32)
        self.box = np.full((2, 2), 0.25, np.float32)
        sigma_b, radius_b = _corner_window_blocks(p.corner_window_px)
        self.tb = cv2.getGaussianKernel(2 * radius_b + 1, sigma_b, cv2.CV_64F).astype(np.float32)
        # numba path: float32 constants, as the reference's float32 arithmetic uses them
        f32 = np.float32
        self.nb_weights = tuple(f32(x) for x in w)
        self.kc1, self.kc2 = f32(_MATCHED_NEAR), f32(_MATCHED_WIDE)
        self.matched = p.stencil == "matched"
        self.tdiv = f32(2.0 * p.frame_interval)

    def smooth_block_tensor(self, T):
        """The corner window's Gaussian over the block tensor ``T`` (hb, wb, 3), in place (cv2 buffers rows)."""
        return cv2.sepFilter2D(T, cv2.CV_32F, self.tb, self.tb, dst=T, borderType=cv2.BORDER_REFLECT)


_kernel_cache: dict = {}


def _kernels(p: _Params) -> _Kernels:
    k = _kernel_cache.get(p)
    if k is None:
        if len(_kernel_cache) > 32:
            _kernel_cache.clear()
        k = _Kernels(p)
        _kernel_cache[p] = k
    return k


def _blur(src, dst, k: _Kernels):
    if k.smooth:
        return cv2.sepFilter2D(src, cv2.CV_32F, k.g, k.g, dst=dst, borderType=cv2.BORDER_REFLECT)
    np.copyto(dst, src)
    return dst


# -------------------------------------------------------------- numba path
#
# Everything after the smoothing, fused: one pass over the cell grid
# (stencils, I_t, |grad I|, vn, Laplacian signs, zero-crossing list), the
# percentile, then one pass over the candidate rows (strong test, angle,
# structure tensor at the strong candidates only). Compiled with
# fastmath=False (no reassociation, no FMA contraction), each call over
# one strip of rows: every element's arithmetic is fixed, so results are
# bit-identical across runs, buffers and thread counts.

if _njit is not None:

    @_njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False)
    def _nb_dense(G0, G1, G2, w0, w1, w2, kc1, kc2, matched, tdiv, b, lap_tol, gc, gr, mag, vn, alpha, mask, cand, rows, T, r_lo, r_hi):
        """One pass over cell rows ``r_lo .. r_hi - 1``: stencils, I_t, |grad I|, vn, zero crossings, block tensor.

        Writes ``gc, gr, mag, vn`` (cells), fills ``alpha`` with NaN and ``mask``
        with False, lists the zero-crossing cells inside the border (flat
        cell indices, row-major) in ``cand`` from position ``r_lo * w`` on
        (the strip's own part), with the list's start in each cell row in
        ``rows``, and returns the list's end. ``T`` (hb, wb, 3) receives the gradient products
        averaged over 2 x 2 blocks of cells (an odd last row or column
        replicated; the four products summed in the reference's order,
        :func:`nfdepth.edges.block_structure_tensor`). ``r_lo`` must be even
        (whole blocks); each cell's arithmetic does not depend on the rows
        chosen, so strips give the whole grid's results bit for bit.
        """
        H, W = G1.shape
        h, w = H - 1, W - 1
        half = np.float32(0.5)
        quarter = np.float32(0.25)
        m4 = np.float32(-4.0)
        tol = np.float32(lap_tol)
        nan = np.float32(np.nan)
        S = np.empty((4, W + 2), np.float32)  # weighted sums, rows y-1..y+2 (ring), edge-padded by 1
        DC = np.empty((2, W), np.float32)  # column differences of rows r, r+1 (ring)
        DR = np.empty(W, np.float32)  # row differences between rows r, r+1
        Dt = np.empty((2, W), np.float32)  # f2 - f0, rows r, r+1 (ring)
        PS = np.empty((2, W), np.uint8)  # Laplacian > 0, rows r, r+1 (ring)
        NG = np.empty((2, W), np.uint8)  # Laplacian < 0
        ZC = np.empty(W, np.uint8)
        inside = h > 2 * b and w > 2 * b
        ncand = r_lo * w
        # prime: rows r_lo - 1, r_lo, r_lo + 1 (clamped)
        for y in range(r_lo - 1, r_lo + 2):
            _comb_row(G0, G1, G2, w0, w1, w2, min(max(y, 0), H - 1), S[(y + 4) % 4])
        _dcol_row(S[r_lo % 4], kc1, kc2, matched, DC[r_lo % 2], w)
        _diff_row(G2, G0, r_lo, Dt[r_lo % 2])
        _lap_row(G1, r_lo, m4, tol, PS[r_lo % 2], NG[r_lo % 2])
        for r in range(r_lo, r_hi):
            y2 = r + 2
            _comb_row(G0, G1, G2, w0, w1, w2, min(y2, H - 1), S[y2 % 4])
            s_m1 = S[(r + 3) % 4]
            s_0 = S[r % 4]
            s_1 = S[(r + 1) % 4]
            s_2 = S[y2 % 4]
            d0 = DC[r % 2]
            d1 = DC[(r + 1) % 2]
            _dcol_row(s_1, kc1, kc2, matched, d1, w)
            t0 = Dt[r % 2]
            t1 = Dt[(r + 1) % 2]
            _diff_row(G2, G0, r + 1, t1)
            p0 = PS[r % 2]
            p1 = PS[(r + 1) % 2]
            n0 = NG[r % 2]
            n1 = NG[(r + 1) % 2]
            _lap_row(G1, r + 1, m4, tol, p1, n1)
            # row differences between pixel rows r and r + 1 (edge-padded rows)
            if matched:
                for x in range(W):
                    DR[x] = kc1 * (s_1[x + 1] - s_0[x + 1]) + kc2 * (s_2[x + 1] - s_m1[x + 1])
            else:
                for x in range(W):
                    DR[x] = s_1[x + 1] - s_0[x + 1]
            rows[r] = ncand
            gcr = gc[r]
            grr = gr[r]
            mr = mag[r]
            vr = vn[r]
            ar = alpha[r]
            kr = mask[r]
            for c in range(w):
                a = half * (d0[c] + d1[c])
                bb = half * (DR[c] + DR[c + 1])
                t = (quarter * (((t0[c] + t0[c + 1]) + t1[c]) + t1[c + 1])) / tdiv
                m = np.float32(math.sqrt(a * a + bb * bb))
                v = -t / m
                gcr[c] = a
                grr[c] = bb
                mr[c] = m
                vr[c] = nan if m == 0 else v
                ar[c] = nan
                kr[c] = False
            # block tensor: even rows start the block sums, odd rows (or a
            # replicated last even row) finish them
            # (the row's parity hoisted out of the loops: 0.06 ms less per 640 x 480 triple)
            tr = T[r // 2]
            last = r % 2 == 0 and r == h - 1
            nb = tr.shape[0]
            npair = w // 2  # blocks of two cells; an odd last column is its own pair
            if r % 2 == 0:
                for j in range(npair):
                    x0, x1, y0, y1 = gcr[2 * j], gcr[2 * j + 1], grr[2 * j], grr[2 * j + 1]
                    tr[j, 0] = x0 * x0 + x1 * x1
                    tr[j, 1] = y0 * y0 + y1 * y1
                    tr[j, 2] = x0 * y0 + x1 * y1
                for j in range(npair, nb):
                    x0, y0 = gcr[w - 1], grr[w - 1]
                    tr[j, 0] = x0 * x0 + x0 * x0
                    tr[j, 1] = y0 * y0 + y0 * y0
                    tr[j, 2] = x0 * y0 + x0 * y0
            if r % 2 == 1 or last:
                for j in range(npair):
                    x0, x1, y0, y1 = gcr[2 * j], gcr[2 * j + 1], grr[2 * j], grr[2 * j + 1]
                    tr[j, 0] = quarter * ((tr[j, 0] + x0 * x0) + x1 * x1)
                    tr[j, 1] = quarter * ((tr[j, 1] + y0 * y0) + y1 * y1)
                    tr[j, 2] = quarter * ((tr[j, 2] + x0 * y0) + x1 * y1)
                for j in range(npair, nb):
                    x0, y0 = gcr[w - 1], grr[w - 1]
                    tr[j, 0] = quarter * ((tr[j, 0] + x0 * x0) + x0 * x0)
                    tr[j, 1] = quarter * ((tr[j, 1] + y0 * y0) + y0 * y0)
                    tr[j, 2] = quarter * ((tr[j, 2] + x0 * y0) + x0 * y0)
            if inside and b <= r < h - b:
                for c in range(w):
                    op = p0[c] | p0[c + 1] | p1[c] | p1[c + 1]
                    on = n0[c] | n0[c + 1] | n1[c] | n1[c + 1]
                    # both signs, and one corner beyond rounding (laplacian_zero_crossings)
                    ZC[c] = (op > 0) & (on > 0) & ((op | on) >= 2)
                base = r * w
                for c in range(b, w - b):
                    cand[ncand] = base + c
                    ncand += ZC[c]
        return ncand


    @_njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False, inline="always")
    def _comb_row(G0, G1, G2, w0, w1, w2, y, out):
        W = G1.shape[1]
        a0 = G0[y]
        a1 = G1[y]
        a2 = G2[y]
        for x in range(W):
            out[x + 1] = (w0 * a0[x] + w1 * a1[x]) + w2 * a2[x]
        out[0] = out[1]
        out[W + 1] = out[W]


    @_njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False, inline="always")
    def _dcol_row(s, kc1, kc2, matched, out, w):
        if matched:
            for c in range(w):
                out[c] = kc1 * (s[c + 2] - s[c + 1]) + kc2 * (s[c + 3] - s[c])
        else:
            for c in range(w):
                out[c] = s[c + 2] - s[c + 1]


    @_njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False, inline="always")
    def _diff_row(A, B, y, out):
        a = A[y]
        bb = B[y]
        for x in range(a.size):
            out[x] = a[x] - bb[x]


    @_njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False, inline="always")
    def _lap_row(G, y, m4, tol, pos, neg):
        """Signs of cv2.Laplacian(ksize=1, BORDER_REFLECT) of row y, same summation order (bit-identical).

        ``pos`` is 1 where the Laplacian is above 0, 2 where above ``tol``
        (beyond rounding); ``neg`` the same below 0 and ``-tol``.
        """
        H, W = G.shape
        up = G[y - 1 if y > 0 else 0]
        dn = G[y + 1 if y < H - 1 else H - 1]
        row = G[y]
        ntol = -tol
        if W == 1:
            v = ((up[0] + row[0]) + m4 * row[0] + row[0]) + dn[0]
            pos[0] = (v > 0) + (v > tol)
            neg[0] = (v < 0) + (v < ntol)
            return
        v = (((up[0] + row[0]) + m4 * row[0]) + row[1]) + dn[0]
        pos[0] = (v > 0) + (v > tol)
        neg[0] = (v < 0) + (v < ntol)
        for x in range(1, W - 1):
            v = (((up[x] + row[x - 1]) + m4 * row[x]) + row[x + 1]) + dn[x]
            pos[x] = (v > 0) + (v > tol)
            neg[x] = (v < 0) + (v < ntol)
        x = W - 1
        v = (((up[x] + row[x - 1]) + m4 * row[x]) + row[x]) + dn[x]
        pos[x] = (v > 0) + (v > tol)
        neg[x] = (v < 0) + (v < ntol)


    @_njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False)
    def _nb_select(gc, gr, mag, cand, rows, thr, floor, T, r0, r1, wr0, wr1, c0, c1, wc0, wc1, max_ratio, mask, r_lo, r_hi, end):
        """Strong test and corner test at the zero-crossing cells of rows ``r_lo .. r_hi - 1``.

        ``cand[off:end]`` and ``rows`` are the list of those rows'
        zero-crossing cells and its start in each cell row, as
        :func:`_nb_dense` left them (``off = r_lo * w``). The smoothed block
        tensor ``T`` (hb, wb, 3) is read back bilinearly at each strong
        candidate with the tables of :func:`nfdepth.edges._block_read_back`,
        and its eigenvalue ratio is tested in float64. Sets ``mask``; returns
        the number ``n`` of edge points, whose cell indices are left in
        ``cand[off:off + n]`` and gradients in the elements ``off .. off + n - 1``
        of ``gc``/``gr`` (overwritten in place; cells of these rows only, so
        strips of rows can run at once).

        Row by row, so that a cell's row is known without an integer division
        (one 64-bit division per point cost a third of this function's time).
        Both passes compact without a branch (the outcome is unpredictable; a
        mispredicted branch costs ~15 cycles): each candidate is written at
        the next free position, which the following candidate overwrites
        unless this one is kept. Safe in place: cell indices strictly
        increase, so the write position never passes a position still to be
        read.
        """
        w = gc.shape[1]
        off = r_lo * w
        # strong candidates (``rows`` then indexes them)
        nstrong = off
        start = off
        for r in range(r_lo, r_hi):
            stop = rows[r + 1] if r + 1 < r_hi else end
            rows[r] = nstrong
            mr = mag[r]
            base = r * w
            for q in range(start, stop):
                flat = cand[q]
                m = mr[flat - base]
                cand[nstrong] = flat
                nstrong += (m >= thr) & (m > floor)
            start = stop
        # corner test; the edge points are packed at the front (from ``off``)
        count = off
        for r in range(r_lo, r_hi):
            ra, rb, wa, wb_ = r0[r], r1[r], wr0[r], wr1[r]
            Ta = T[ra]
            Tb = T[rb]
            mk = mask[r]
            gcr = gc[r]
            grr = gr[r]
            base = r * w
            for q in range(rows[r], rows[r + 1] if r + 1 < r_hi else nstrong):
                flat = cand[q]
                c = flat - base
                ca, cb, ua, ub = c0[c], c1[c], wc0[c], wc1[c]
                ta, tb, tc, td = Ta[ca], Tb[ca], Ta[cb], Tb[cb]
                jxx = ua * (wa * np.float64(ta[0]) + wb_ * np.float64(tb[0])) + ub * (wa * np.float64(tc[0]) + wb_ * np.float64(td[0]))
                jyy = ua * (wa * np.float64(ta[1]) + wb_ * np.float64(tb[1])) + ub * (wa * np.float64(tc[1]) + wb_ * np.float64(td[1]))
                jxy = ua * (wa * np.float64(ta[2]) + wb_ * np.float64(tb[2])) + ub * (wa * np.float64(tc[2]) + wb_ * np.float64(td[2]))
                # eigenvalue ratio in float64, the reference's formula; no
                # short-circuit branches (the outcome is unpredictable)
                hf = 0.5 * (jxx + jyy)
                dd = jxx - jyy
                d = 0.25 * (dd * dd) + jxy * jxy
                root = math.sqrt(max(d, 0.0))
                lam1 = hf + root
                lam2 = max(hf - root, 0.0)
                ok = (lam1 > 0.0) & (lam2 / lam1 <= max_ratio)
                mk[c] = ok
                # The caller takes the angles with numpy's SIMD atan2 (the
                # reference's, bit for bit; ~40x faster than a scalar atan2
                # call per point).
                gyv = grr[c]
                gxv = gcr[c]
                cand[count] = flat
                gr.flat[count] = gyv
                gc.flat[count] = gxv
                count += ok
        return count - off


def _nb_run(ws: _NbWorkspace, k: _Kernels, G0, G1, G2, threads: int = 1) -> NormalFlowEdges:
    """Normal flow and edge points from three smoothed frames (numba path), in row strips on ``threads`` threads."""
    p = k.p
    vn, alpha, mag, mask = ws.outputs()
    w = mag.shape[1]
    strips = _cell_strips(*mag.shape, threads)
    ends = [0] * len(strips)
    w0, w1, w2 = k.nb_weights
    peak = _peak(G1)
    lap_tol = ROUNDING_LAPLACIAN * peak

    def dense(i):
        r_lo, r_hi = strips[i]
        ends[i] = _nb_dense(G0, G1, G2, w0, w1, w2, k.kc1, k.kc2, k.matched, k.tdiv, p.border_px, lap_tol, ws.gc, ws.gr, mag, vn, alpha, mask, ws.cand, ws.rows, ws.tensor, r_lo, r_hi)

    _run_strips(dense, len(strips), threads)
    ncand = sum(e - r_lo * w for e, (r_lo, _) in zip(ends, strips))
    threshold = [p.min_gradient]

    def percentile_or_tensor(i):
        if i == 0 and p.min_gradient is None:
            threshold[0] = p.relative_gradient * (float(percentile(mag, 99.0)) if mag.size else 0.0)
        elif i == 1:
            k.smooth_block_tensor(ws.tensor)

    # the block tensor's window beside the percentile (both on this thread when no worker is awake)
    _run_strips(percentile_or_tensor, 2 if ncand else 1, threads if len(strips) > 1 else 1)
    min_gradient = threshold[0]
    if ncand:
        T = ws.tensor
        # float32 threshold: the reference compares float32 magnitudes with a Python float (NEP 50)
        thr, floor = np.float32(_comparable_threshold(min_gradient, np.float32)), np.float32(ROUNDING_GRADIENT * peak)
        flat_gc, flat_gr, flat_alpha = ws.gc.ravel(), ws.gr.ravel(), alpha.ravel()

        def select(i):
            r_lo, r_hi = strips[i]
            off = r_lo * w
            n = _nb_select(ws.gc, ws.gr, mag, ws.cand, ws.rows, thr, floor, T, *ws.read_back, float(p.max_corner_ratio), mask, r_lo, r_hi, ends[i])
            # the edge points' gradients are packed at the strip's front of gc/gr (see _nb_select)
            angle = flat_gc[off : off + n]
            np.arctan2(flat_gr[off : off + n], angle, out=angle)
            flat_alpha[ws.cand[off : off + n]] = angle

        _run_strips(select, len(strips), threads)
    return NormalFlowEdges(vn, alpha, mag, mask, float(min_gradient))


# ------------------------------------------------------------ row strips

_STRIP_MIN_PIXELS = 1 << 17  # per strip at least: below, waking a thread costs about what it saves (see _cell_strips)
_pools: dict = {}
_pools_lock = threading.Lock()


def _threads(threads) -> int:
    """The ``threads`` argument: default OpenCV's ``cv2.getNumThreads()`` (so ``cv2.setNumThreads`` governs it)."""
    return max(1, cv2.getNumThreads()) if threads is None else check_int("threads", threads, 1)


def _cell_strips(h: int, w: int, threads: int) -> list:
    """Row strips ``(r_lo, r_hi)`` of an ``h`` x ``w`` grid for ``threads`` threads, each starting on an even row.

    Each strip holds at least ``_STRIP_MIN_PIXELS`` (and two rows). Results
    do not depend on the strips: every row's arithmetic is the same in any
    strip (see :func:`_nb_dense`).
    """
    min_rows = max(2, -(-_STRIP_MIN_PIXELS // max(w, 1)))
    n = max(1, min(int(threads), h // min_rows))
    edges = [0] + [2 * round(i * h / (2 * n)) for i in range(1, n)] + [h]
    return [(a, b) for a, b in itertools.pairwise(edges) if b > a]


def _pool(threads: int):
    """A shared pool of ``threads - 1`` workers (the calling thread runs a strip itself)."""
    pool = _pools.get(threads)
    if pool is None:
        with _pools_lock:
            pool = _pools.get(threads)
            if pool is None:
                from concurrent.futures import ThreadPoolExecutor

                pool = _pools[threads] = ThreadPoolExecutor(max_workers=threads - 1, thread_name_prefix="nfdepth-fast")
    return pool


def _forget_pools() -> None:
    """In a forked child: the parent's pool threads do not exist there (a task would wait forever), nor does a lock's holder."""
    global _pools_lock
    _pools.clear()
    _pools_lock = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pools)


def _run_strips(fn, n: int, threads: int, *, stop: threading.Event | None = None) -> None:
    """``fn(i)`` for every ``i`` in ``range(n)``, on this thread and up to ``threads - 1`` pool workers.

    Strips are claimed one at a time, this thread included, so a worker that
    wakes late (an idle core can take longer to wake than a strip takes)
    only finds less work: this thread never waits for a worker that has not
    started, and the whole is never much slower than on one thread. Returns
    once every strip has ended (they write into the caller's buffers); a
    strip's exception is raised then, and strips not yet started are skipped.
    An interrupt (an exception that is no ``Exception``: ``KeyboardInterrupt``,
    the CLI's SIGTERM) wins over a strip's error, which may be its
    consequence (numba, interrupted while compiling a kernel in this thread,
    fails the other threads' calls of it). ``stop``, if given, is set as soon
    as a strip fails or the caller is interrupted, so that long strips
    polling it can end early.
    """
    if n <= 1 or threads <= 1:
        for i in range(n):
            fn(i)
        return
    claim = itertools.count()  # next() is atomic under the GIL
    done = threading.Condition(threading.Lock())
    state = {"left": n, "error": None}

    def record(exc):  # holding ``done``
        old = state["error"]
        if old is None or (isinstance(old, Exception) and not isinstance(exc, Exception)):
            state["error"] = exc
        if stop is not None:
            stop.set()

    def work():
        for i in claim:
            if i >= n:
                return
            error = None
            if state["error"] is None:
                try:
                    fn(i)
                except BaseException as exc:  # noqa: BLE001 - KeyboardInterrupt included: re-raised by the caller
                    error = exc
            with done:
                if error is not None:
                    record(error)
                state["left"] -= 1
                if not state["left"]:
                    done.notify_all()

    pool = _pool(threads)
    for _ in range(min(threads, n) - 1):
        pool.submit(work)
    work()
    with done:
        while state["left"]:
            try:
                done.wait()
            except BaseException as exc:  # noqa: BLE001 - e.g. KeyboardInterrupt: raised once the running strips have ended
                record(exc)
    if state["error"] is not None:
        raise state["error"]


def _blur_strips(srcs, dsts, k: _Kernels, threads: int, scratch) -> None:
    """``_blur`` of each source into its destination, in row strips on ``threads`` threads.

    A strip is smoothed from its rows plus the kernel radius on each side
    (reflected only at the image's own border), so it is bit-identical to
    the whole image's ``cv2.sepFilter2D``; it goes through scratch rows of
    the thread that runs it (``scratch(thread id, rows)``) and only its own
    rows are copied out. Every (image, strip) pair is one task.
    """
    H = srcs[0].shape[0]
    strips = _cell_strips(H, srcs[0].shape[1], threads)
    if not k.smooth or len(strips) == 1:
        for src, dst in zip(srcs, dsts):
            _blur(src, dst, k)
        return
    R = k.radius
    tasks = [(src, dst, y0, y1) for src, dst in zip(srcs, dsts) for y0, y1 in strips]

    def blur(i):
        src, dst, y0, y1 = tasks[i]
        a, b = max(0, y0 - R), min(H, y1 + R)
        tmp = scratch(threading.get_ident(), b - a)
        cv2.sepFilter2D(src[a:b], cv2.CV_32F, k.g, k.g, dst=tmp, borderType=cv2.BORDER_REFLECT)
        dst[y0:y1] = tmp[y0 - a : y1 - a]

    _run_strips(blur, len(tasks), threads)


# --------------------------------------------------------------- the core


def _finish(ws: _Workspace, k: _Kernels, Gs, G1, gt_full) -> NormalFlowEdges:
    """Everything after smoothing: stencils, flow, angle, edge points.

    ``Gs`` (smoothed weighted sum) and ``G1`` (smoothed middle frame) are
    only read; ``gt_full`` (I_t at cells) may be overwritten. Scratch use of
    the workspace: ``A`` (Laplacian), then ``A``, ``gt`` and ``D`` hold the
    structure-tensor products (``Gs`` is read again at the candidates).
    """
    p = k.p
    H, W = ws.shape
    h, w = H - 1, W - 1
    a = k.anchor_shift
    # I_col: difference along columns (taps c-a ..), mean of rows r, r+1.
    cv2.filter2D(Gs, cv2.CV_32F, k.k_col, dst=ws.gc, anchor=(a, 0), borderType=cv2.BORDER_REPLICATE)
    cv2.filter2D(Gs, cv2.CV_32F, k.k_row, dst=ws.gr, anchor=(0, a), borderType=cv2.BORDER_REPLICATE)
    gc = ws.gc[:h, :w]
    gr = ws.gr[:h, :w]
    gt = gt_full[:h, :w]
    f32 = np.float32

    vn, alpha, mag, mask = ws.outputs()
    # |grad I| with numpy (correctly rounded element-wise, so independent of
    # buffer alignment; cv2.magnitude's SIMD path is not).
    np.multiply(gc, gc, out=mag)
    np.multiply(gr, gr, out=alpha)  # alpha is scratch until it is filled below
    np.add(mag, alpha, out=mag)
    np.sqrt(mag, out=mag)
    # numpy's division is correctly rounded whatever the buffer alignment
    # (cv2.divide with a scale is not: its SIMD and scalar paths differ by an
    # ulp, which made pooled and fresh output buffers disagree).
    with np.errstate(divide="ignore", invalid="ignore"):
        np.divide(gt, mag, out=vn)
    np.negative(vn, out=vn)
    if cv2.countNonZero(mag) < mag.size:
        np.copyto(vn, f32(np.nan), where=mag == 0)
    # alpha = atan2(gr, gc) only where it is used: at the candidate edge
    # points (below); NaN elsewhere. (cv2.phase on the whole grid was fast but
    # its SIMD path depends on buffer alignment, so reused buffers gave results
    # differing by an ulp: not deterministic.)
    alpha.fill(np.nan)
    b3 = ws.b3

    # Edge points.
    if p.min_gradient is None:
        high = float(percentile(mag, 99.0)) if mag.size else 0.0
        min_gradient = p.relative_gradient * high
    else:
        min_gradient = p.min_gradient
    mask.fill(False)
    b = p.border_px
    if h > 2 * b and w > 2 * b:
        # Laplacian zero crossings of the smoothed middle frame (4 corners of each cell).
        peak = _peak(G1)  # for both rounding floors
        lap = ws.A
        cv2.Laplacian(G1, cv2.CV_32F, dst=lap, ksize=1, borderType=cv2.BORDER_REFLECT)
        pos, neg = ws.b1, ws.b2
        np.greater(lap, 0, out=pos)
        np.less(lap, 0, out=neg)
        rs, cs = slice(b, h - b), slice(b, w - b)
        rs1, cs1 = slice(b + 1, h - b + 1), slice(b + 1, w - b + 1)
        inner = mask[rs, cs]
        tmp = b3[rs, cs]
        for src, dst in ((pos, inner), (neg, tmp)):
            np.logical_or(src[rs, cs], src[rs, cs1], out=dst)
            dst |= src[rs1, cs]
            dst |= src[rs1, cs1]
        inner &= tmp
        # and one corner beyond rounding (laplacian_zero_crossings)
        np.abs(lap, out=lap)
        np.greater(lap, np.float32(ROUNDING_LAPLACIAN * peak), out=pos)
        np.logical_or(pos[rs, cs], pos[rs, cs1], out=tmp)
        tmp |= pos[rs1, cs]
        tmp |= pos[rs1, cs1]
        inner &= tmp
        m = mag[rs, cs]
        np.greater_equal(m, _comparable_threshold(min_gradient, m.dtype), out=tmp)  # float32 compare, as the reference (NEP 50)
        inner &= tmp
        floor = ROUNDING_GRADIENT * peak
        if not min_gradient > floor:
            np.greater(m, floor, out=tmp)
            inner &= tmp
        if inner.any():
            # Structure tensor on the block grid (products in the free buffers);
            # the sparse work below (exact angle, eigenvalue ratio) runs in bands
            # of rows so that its temporaries stay small (large freed blocks go
            # back to the kernel and cost page faults on the next call).
            T = ws.tensor
            hb, wb = T.shape[0], T.shape[1]
            rows0, cols0 = 2 * np.arange(hb), 2 * np.arange(wb)
            rows1, cols1 = np.minimum(rows0 + 1, h - 1), np.minimum(cols0 + 1, w - 1)
            for ch, (buf, (u, v)) in enumerate(zip((ws.A, ws.gt, ws.D), ((gc, gc), (gr, gr), (gc, gr)))):
                prod = buf[:h, :w]
                cv2.multiply(u, v, dst=prod)
                top, bot = prod[rows0], prod[rows1]
                T[:, :, ch] = np.float32(0.25) * (((top[:, cols0] + top[:, cols1]) + bot[:, cols0]) + bot[:, cols1])
            k.smooth_block_tensor(T)
            step = max(1, _BAND_CELLS // w)
            for r0 in range(b, h - b, step):
                r1 = min(r0 + step, h - b)
                idx = np.flatnonzero(mask[r0:r1])
                if idx.size:
                    idx += r0 * w
                    _sparse(ws, alpha, mask, idx, w, p.max_corner_ratio, Gs, k.matched, peak)
    return NormalFlowEdges(vn, alpha, mag, mask, float(min_gradient))


_BAND_CELLS = 16384


def _sparse(ws: _Workspace, alpha, mask, idx, w, max_ratio, Gs, matched, peak):
    """Exact angle and corner rejection at the candidate cells ``idx`` (flat, cell grid).

    ``Gs``: the smoothed weighted sum; ``peak``: the largest ``|value|`` of the smoothed middle frame.
    """
    fi = idx + idx // w  # flat index into the (H, W) buffers
    rr, cc = idx // w, idx % w
    # Angle at the candidate edge points (float64 atan2, as the reference).
    gcs = ws.gc.ravel()[fi].astype(np.float64)
    grs = ws.gr.ravel()[fi].astype(np.float64)
    # Where the stencil's rows of Gs are equal (an edge along the columns), the reference's
    # differences give I_row = +0 exactly, but cv2.filter2D's sum of weighted taps leaves
    # float32 rounding of either sign (-6e-6 at -150 grey levels): an edge dark on the right
    # got alpha = -pi + 2e-7 instead of +pi. I_row is set to +0 there (nowhere else). Only
    # cells whose |I_row| is within rounding are looked at (looking at every candidate cost
    # a quarter more time): a sum of at most 8 taps (sum |k| <= 2) errs by at most about
    # 8 * 2**-24 * 2 = 1e-6 of the largest |value| it reads, and 1e-5 of the middle frame's
    # peak leaves room for outer frames brighter than it.
    near = np.flatnonzero(np.abs(grs) <= 1e-5 * peak)
    if near.size:
        grs[near[_equal_rows(Gs, rr[near], cc[near], matched)]] = 0.0
    alpha.ravel()[idx] = np.arctan2(grs, gcs)
    # Eigenvalue ratio of the block tensor read back bilinearly (float64, as the reference).
    r0, r1, wr0, wr1, c0, c1, wc0, wc1 = ws.read_back
    T = ws.tensor
    ua, ub, wa, wb = wc0[cc, None], wc1[cc, None], wr0[rr, None], wr1[rr, None]
    top = wa * T[r0[rr], c0[cc]].astype(np.float64) + wb * T[r1[rr], c0[cc]].astype(np.float64)
    bot = wa * T[r0[rr], c1[cc]].astype(np.float64) + wb * T[r1[rr], c1[cc]].astype(np.float64)
    jxx, jyy, jxy = (ua * top + ub * bot).T
    half = 0.5 * (jxx + jyy)
    root = np.sqrt(np.maximum(0.25 * (jxx - jyy) ** 2 + jxy**2, 0.0))
    lam1 = half + root
    lam2 = np.maximum(half - root, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ok = (lam1 > 0) & (lam2 / lam1 <= max_ratio)
    mask.ravel()[idx[~ok]] = False


def _equal_rows(Gs, rr, cc, matched) -> np.ndarray:
    """True at cells ``(rr, cc)`` whose row stencil reads equal values of ``Gs`` (rows ``r-1 .. r+2``
    edge-clamped for the matched stencil, else ``r, r+1``; columns ``c, c+1``): the reference's I_row is +0 there."""
    last = Gs.shape[0] - 1
    equal = np.ones(rr.shape, bool)
    for col in (cc, cc + 1):
        first = Gs[rr, col]
        for dr in (-1, 1, 2) if matched else (1,):
            equal &= Gs[np.clip(rr + dr, 0, last), col] == first
    return equal


def _peak(G1) -> float:
    """The largest ``|value|`` of the smoothed middle frame (one SIMD pass, ~0.01 ms at 640 x 480), for the rounding floors."""
    return float(cv2.norm(np.ascontiguousarray(G1), cv2.NORM_INF)) if G1.size else 0.0


def _check_frame_shape(frames):
    H, W = frames[0].shape
    if H < 2 or W < 2:  # pragma: no cover - as_image already checks
        msg = f"frames must be at least 2x2, got {frames[0].shape}"
        raise ValueError(msg)


def normal_flow_edges(
    frames,
    *,
    sigma_px: float,
    frame_interval: float = 1.0,
    stencil: str = "matched",
    min_gradient: float | None = None,
    relative_gradient: float = 0.1,
    max_corner_ratio: float = 0.1,
    corner_window_px: float | None = None,
    border_px: int = 2,
    threads: int | None = None,
) -> NormalFlowEdges:
    """Normal flow and edge points of a frame triple, fast path.

    The same as ``g = normal_flow(frames, sigma_px=..., frame_interval=...,
    stencil=...)`` followed by ``select_edge_points(g, gaussian_smooth(frames[1]),
    ...)`` (float32), to float32 rounding; see the module docstring.

    Parameters
    ----------
    frames : sequence of 3 ndarray (H, W), or ndarray (3, H, W)
        Equally spaced grey frames in time order (converted to float32), finite,
        each of largest ``|value|`` 0 or from 1e-15 to 1e15: the float32 squares of
        gradients underflow below (``_validate.MIN_FLOAT32_INTENSITY``) and overflow
        above; rescale such intensities.
    sigma_px : float
        Gaussian smoothing in pixels (0: none).
    frame_interval : float
        Time between consecutive frames; flows are per unit time.
    stencil : {"matched", "simpson", "paper"}
        Gradient stencil (:mod:`nfdepth.normal_flow`).
    min_gradient, relative_gradient, max_corner_ratio, border_px
        Edge-point rules (:func:`nfdepth.edges.select_edge_points`).
    corner_window_px : float, optional
        Structure-tensor window; default ``max(sigma_px, 1)``, as
        ``static_stereo`` takes its edge points (the paper's pipelines,
        ``dynamic_stereo`` and ``static_stereo_edges``, use ``2 sigma_px``).
    threads : int, optional
        Threads of the numba path: the blurs, the cell-grid pass and the
        edge-point tests run in row strips of at least 2**17 pixels (smaller
        images run on one thread), on a shared pool. Results are
        bit-identical for any thread count. Default
        OpenCV's ``cv2.getNumThreads()``, so ``cv2.setNumThreads`` governs it
        (the numpy/OpenCV fallback uses OpenCV's own threads only).

    Returns
    -------
    NormalFlowEdges
        ``vn, alpha, magnitude, mask`` on the cell grid ``(H-1, W-1)``.
    """
    p = _params(sigma_px, frame_interval, stencil, min_gradient, relative_gradient, max_corner_ratio, corner_window_px, border_px)
    threads = _threads(threads)
    # frames whose intensities are all tiny are refused: float32 squares of their gradients underflow (see MIN_FLOAT32_INTENSITY)
    f0, f1, f2 = as_frames("frames", frames, 3, dtype=np.float32, min_peak=MIN_FLOAT32_INTENSITY)
    k = _kernels(p)
    ws = _workspace(f0.shape)
    if isinstance(ws, _NbWorkspace):
        if not k.smooth:
            return _nb_run(ws, k, f0, f1, f2, threads)
        G = ws.G
        _blur_strips((f0, f1, f2), G, k, threads, ws.scratch)
        return _nb_run(ws, k, G[0], G[1], G[2], threads)
    w0, w1, w2 = k.weights
    # Weighted sum and difference; then three smoothing passes.
    cv2.addWeighted(f0, w0, f2, w2, 0.0, dst=ws.A)
    cv2.scaleAdd(f1, w1, ws.A, dst=ws.A)
    cv2.subtract(f2, f0, dst=ws.D)
    Gs = _blur(ws.A, ws.Gs, k)
    if k.smooth:
        # Gaussian folded with the 2 x 2 cell mean and 1 / (2 dt): I_t at cells.
        cv2.sepFilter2D(ws.D, cv2.CV_32F, k.gm_x, k.gm_y, dst=ws.gt, anchor=(k.radius, k.radius), borderType=cv2.BORDER_REFLECT)
    else:
        cv2.filter2D(ws.D, cv2.CV_32F, k.box * np.float32(0.5 / p.frame_interval), dst=ws.gt, anchor=(0, 0), borderType=cv2.BORDER_REFLECT)
    G1 = _blur(f1, ws.D, k)  # D is free now
    return _finish(ws, k, Gs, G1, ws.gt)


class StreamingNormalFlow:
    """Normal flow and edge points of a video, one new frame at a time.

    Each pushed frame is smoothed once and its 2 x 2 cell mean taken once;
    both are kept in a ring of three, so the triple ``(f[t-2], f[t-1], f[t])``
    costs one smoothing pass plus the per-triple work (stencils, flow,
    angle, edge points). Results are those of :func:`normal_flow_edges` on
    the latest three frames, centred on the middle one.

    Parameters are those of :func:`normal_flow_edges`.

    Examples
    --------
    >>> stream = StreamingNormalFlow(sigma_px=2.0)
    >>> for frame in frames:                     # doctest: +SKIP
    ...     result = stream.push(frame)          # None for the first two
    """

    def __init__(
        self,
        *,
        sigma_px: float,
        frame_interval: float = 1.0,
        stencil: str = "matched",
        min_gradient: float | None = None,
        relative_gradient: float = 0.1,
        max_corner_ratio: float = 0.1,
        corner_window_px: float | None = None,
        border_px: int = 2,
        threads: int | None = None,
    ):
        self._p = _params(sigma_px, frame_interval, stencil, min_gradient, relative_gradient, max_corner_ratio, corner_window_px, border_px)
        self._threads = None if threads is None else _threads(threads)  # None: cv2.getNumThreads() at each push
        self._k = _kernels(self._p)
        self._shape = None
        self._ring: deque = deque()  # (smoothed, cell mean) per frame, oldest first
        self._spare: list = []
        self._count = 0

    @property
    def frames_seen(self) -> int:
        """Frames pushed since creation or the last :meth:`reset`."""
        return self._count

    def reset(self) -> None:
        """Forget all frames (e.g. at a scene cut); the next frame may have another size."""
        while self._ring:
            self._spare.append(self._ring.popleft())
        self._count = 0
        self._shape = None  # the workspace and spare buffers follow the next frame's size
        self._spare.clear()

    def push(self, frame) -> NormalFlowEdges | None:
        """Add the next frame; return the result for the latest triple, or None before the third frame."""
        img = as_image(f"frame {self._count}", frame, np.float32, min_peak=MIN_FLOAT32_INTENSITY)
        if self._shape is None:
            self._shape = img.shape
            self._numba = USE_NUMBA
            self._ws = _NbWorkspace(img.shape, frames=False) if self._numba else _Workspace(img.shape)
        elif img.shape != self._shape:
            msg = f"frame {self._count} has shape {img.shape}, but this stream's frames have shape {self._shape}"
            raise ValueError(msg)
        k = self._k
        if len(self._ring) == 3:
            self._spare.append(self._ring.popleft())
        if self._numba:
            # ring of smoothed frames only: one blur per frame plus the fused per-triple work
            threads = _threads(self._threads)
            G = self._spare.pop() if self._spare else np.empty(self._shape, np.float32)
            _blur_strips((img,), (G,), k, threads, self._ws.scratch)
            self._ring.append(G)
            self._count += 1
            if len(self._ring) < 3:
                return None
            return _nb_run(self._ws, k, *self._ring, threads)
        if self._spare:
            G, B = self._spare.pop()
        else:
            G = np.empty(self._shape, np.float32)
            B = np.empty(self._shape, np.float32)
        _blur(img, G, k)
        # Cell mean of the smoothed frame (cells [:h, :w]).
        cv2.filter2D(G, cv2.CV_32F, k.box, dst=B, anchor=(0, 0), borderType=cv2.BORDER_REFLECT)
        self._ring.append((G, B))
        self._count += 1
        if len(self._ring) < 3:
            return None
        (G0, B0), (G1, _), (G2, B2) = self._ring
        ws = self._ws
        w0, w1, w2 = k.weights
        cv2.addWeighted(G0, w0, G2, w2, 0.0, dst=ws.Gs)
        cv2.scaleAdd(G1, w1, ws.Gs, dst=ws.Gs)
        s = 0.5 / self._p.frame_interval
        cv2.addWeighted(B2, s, B0, -s, 0.0, dst=ws.gt)
        return _finish(ws, k, ws.Gs, G1, ws.gt)
