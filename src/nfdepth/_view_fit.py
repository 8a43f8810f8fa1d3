"""Compiled per-pixel fit over the warped views of static stereo (numba).

Step 2 of :mod:`nfdepth.stereo` (``_measure``): after every view has been
warped toward the reference, each pixel gets occlusion weights
(:func:`nfdepth.stereo._occlusion_weights`), the weighted least-squares slope
of the warped intensities against position, i.e. ``I_t`` of paper eq. 6
fused over the views (:func:`nfdepth.stereo._regress`), and the weighted
mean of the pair stencils' gradients. The NumPy functions in
:mod:`nfdepth.stereo` are the reference and the fallback without numba; they
build about 40 full-image temporaries per call. The kernels here take the
views stacked along a first axis (the reference left out) and flattened,
and make one pass over the pixels in chunks, with the same float32
operations in the same order: the results are bit-identical (the tests
compare them on random inputs, with ties, zero weights and views outside
the image).
"""

from __future__ import annotations

import math

import numpy as np

try:  # optional compiled kernels; the NumPy path of nfdepth.stereo otherwise
    from numba import njit as _njit
except ImportError:  # pragma: no cover - depends on the environment
    _njit = None

_CHUNK = 512  # pixels per chunk: the accumulators stay in the L1 cache

if _njit is not None:
    _jit = _njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False)

    @_jit
    def _nb_occlusion_weights(energy, inside, floor, out):
        """Occlusion weights from the views' local energies (``_occlusion_weights`` after its blurs).

        ``energy``: ``E_k``, the blurred squared differences; ``inside``: 1
        where view ``k``'s warp stays in the image, else 0; all ``(K, N)``
        float32, as ``out``. ``floor`` float32. NaN energies propagate into
        the best energy as ``np.minimum`` does (a NaN weight becomes 0).
        """
        K, N = energy.shape
        inf = np.float32(np.inf)
        two = np.float32(2.0)
        one = np.float32(1.0)
        zero = np.float32(0.0)
        best = np.empty(_CHUNK, np.float32)
        for i0 in range(0, N, _CHUNK):
            n = min(_CHUNK, N - i0)
            for i in range(n):
                best[i] = inf
            for k in range(K):
                ek = energy[k, i0 : i0 + n]
                ik = inside[k, i0 : i0 + n]
                for i in range(n):
                    e = ek[i]
                    e = e if ik[i] > 0 else inf
                    b = best[i]
                    # np.minimum: a NaN on either side wins
                    m = b if math.isnan(b) else min(b, e)
                    best[i] = e if math.isnan(e) else m
            for k in range(K):
                ek = energy[k, i0 : i0 + n]
                ik = inside[k, i0 : i0 + n]
                ok = out[k, i0 : i0 + n]
                for i in range(n):
                    e = ek[i]
                    inn = ik[i]
                    e = e if inn > 0 else inf
                    ratio = (two * (best[i] + floor)) / (e + floor)
                    r = ratio if math.isnan(ratio) else min(one, ratio)
                    w = r * r
                    finite = (ratio - ratio) == zero  # False for inf and NaN
                    ok[i] = (w if finite else zero) * inn

    @_jit
    def _nb_fit(tk, diff, weight, grad_col_k, grad_row_k, ref_grad_col, ref_grad_row, slope, s_tt, chi2, sum_m, grad_col, grad_row):
        """Weighted LS slope of ``D_k`` on ``t_k`` (reference at (0, 0)) and the weighted mean pair gradients.

        ``tk`` (K,) float32 positions; ``diff``, ``weight``, ``grad_col_k``,
        ``grad_row_k`` (K, N) float32: ``D_k``, the occlusion weights and view
        ``k``'s own cell gradients; ``ref_grad_col``, ``ref_grad_row`` (N,)
        the reference's. Writes (N,) float32 outputs: ``slope``, ``s_tt``,
        ``chi2``, ``sum_m`` as ``_regress`` returns them, and ``grad_col``,
        ``grad_row``: the weighted mean over the views of the pair
        stencil's ``0.5 (ref + view)`` gradients, 0 where no view has weight.
        """
        K, N = diff.shape
        half = np.float32(0.5)
        one = np.float32(1.0)
        zero = np.float32(0.0)
        tiny = np.float32(1e-6)
        acc = np.empty((9, _CHUNK), np.float32)
        for i0 in range(0, N, _CHUNK):
            n = min(_CHUNK, N - i0)
            sm, st, stt, sd, sdd, std_, ws, gc, gr = acc[0], acc[1], acc[2], acc[3], acc[4], acc[5], acc[6], acc[7], acc[8]
            for i in range(n):
                sm[i] = one
                st[i] = zero
                stt[i] = zero
                sd[i] = zero
                sdd[i] = zero
                std_[i] = zero
                ws[i] = zero
                gc[i] = zero
                gr[i] = zero
            rgc = ref_grad_col[i0 : i0 + n]
            rgr = ref_grad_row[i0 : i0 + n]
            for k in range(K):
                t = tk[k]
                dk = diff[k, i0 : i0 + n]
                wk = weight[k, i0 : i0 + n]
                gck = grad_col_k[k, i0 : i0 + n]
                grk = grad_row_k[k, i0 : i0 + n]
                for i in range(n):
                    w = wk[i]
                    d = dk[i]
                    wt = w * t
                    wd = w * d
                    sm[i] = sm[i] + w
                    st[i] = st[i] + wt
                    stt[i] = stt[i] + wt * t
                    sd[i] = sd[i] + wd
                    sdd[i] = sdd[i] + wd * d
                    std_[i] = std_[i] + wt * d
                    ws[i] = ws[i] + w
                    gc[i] = gc[i] + w * (half * (rgc[i] + gck[i]))
                    gr[i] = gr[i] + w * (half * (rgr[i] + grk[i]))
            so = slope[i0 : i0 + n]
            tto = s_tt[i0 : i0 + n]
            co = chi2[i0 : i0 + n]
            mo = sum_m[i0 : i0 + n]
            gco = grad_col[i0 : i0 + n]
            gro = grad_row[i0 : i0 + n]
            for i in range(n):
                m = sm[i]
                tbar = st[i] / m
                dbar = sd[i] / m
                a = stt[i] - (m * tbar) * tbar
                b = std_[i] - (m * tbar) * dbar
                c = sdd[i] - (m * dbar) * dbar
                ok = a > tiny
                q = b / a
                s = q if ok else zero
                r = c - s * b
                so[i] = s
                tto[i] = a if ok else zero
                # np.maximum(r, 0): NaN stays NaN, -0 becomes +0
                co[i] = r if r > zero or math.isnan(r) else zero
                mo[i] = m
                wsum = ws[i]
                pos = wsum > zero
                x = gc[i] / wsum
                y = gr[i] / wsum
                gco[i] = x if pos else zero
                gro[i] = y if pos else zero

    @_njit(cache=True, fastmath=False, error_model="numpy", nogil=True, boundscheck=False, inline="always")
    def _matched_col_diff(row, kc1, kc2, out):
        """The matched four-point difference along a node row at its half-integer columns, edge-padded (``normal_flow._diff``)."""
        w = out.size
        last = row.size - 1
        for j in range(w):
            lo = j - 1 if j > 0 else 0
            hi = min(j + 2, last)
            out[j] = kc1 * (row[j + 1] - row[j]) + kc2 * (row[hi] - row[lo])

    @_jit
    def _nb_pair_stencil(nodes, ref_nodes, kc1, kc2, grad_col, grad_row, diff):
        """One warped view's cell gradients and its cell-mean difference from the reference.

        ``nodes``, ``ref_nodes`` (h + 1, w + 1) float32: the warped view and
        the reference on the node grid. Writes (h, w) float32: ``grad_col``,
        ``grad_row``, the matched stencil's ``_cell_gradient(nodes, True)``,
        and ``diff``, ``_cell_mean(nodes - ref_nodes)``; ``kc1``, ``kc2`` the
        stencil's float32 weights (near, wide). Same float32 operations as the
        NumPy functions, element for element.
        """
        hn, wn = nodes.shape
        h, w = hn - 1, wn - 1
        half = np.float32(0.5)
        quarter = np.float32(0.25)
        dc0 = np.empty(w, np.float32)
        dc1 = np.empty(w, np.float32)
        drow = np.empty(wn, np.float32)
        _matched_col_diff(nodes[0], kc1, kc2, dc0)
        for r in range(h):
            a = nodes[r]
            b = nodes[r + 1]
            am = nodes[r - 1 if r > 0 else 0]
            bp = nodes[r + 2 if r + 2 < hn else hn - 1]
            _matched_col_diff(b, kc1, kc2, dc1)
            gcr = grad_col[r]
            for j in range(w):
                gcr[j] = half * (dc0[j] + dc1[j])
            for j in range(wn):
                drow[j] = kc1 * (b[j] - a[j]) + kc2 * (bp[j] - am[j])
            grr = grad_row[r]
            for j in range(w):
                grr[j] = half * (drow[j] + drow[j + 1])
            ra = ref_nodes[r]
            rb = ref_nodes[r + 1]
            dr = diff[r]
            for j in range(w):
                dr[j] = quarter * ((((a[j] - ra[j]) + (a[j + 1] - ra[j + 1])) + (b[j] - rb[j])) + (b[j + 1] - rb[j + 1]))
            dc0, dc1 = dc1, dc0
