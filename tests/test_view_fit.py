"""The compiled per-pixel fit of static stereo (nfdepth._view_fit) against the NumPy reference in nfdepth.stereo, bit for bit."""

import cv2
import numpy as np
import pytest

from nfdepth import _view_fit, fast, stereo
from nfdepth.normal_flow import _cell_gradient, _cell_mean

pytestmark = pytest.mark.skipif(_view_fit._njit is None, reason="numba not installed")


def _same(a, b):
    """Bit-identical float arrays (NaN where the other has NaN; -0 and +0 told apart)."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.dtype == b.dtype and a.shape == b.shape
    np.testing.assert_array_equal(a.view(np.uint32), b.view(np.uint32))


def _views(rng, n_views, ref, shape):
    """Differences, inside masks and gradients of the non-reference views, with zero weights, ties and views outside the image."""
    h, w = shape
    k = n_views - 1
    diffs = rng.normal(0.0, 3.0, (k, h, w)).astype(np.float32)
    diffs[:, :, :5] = 0.0  # exact zeros: energies tie, s_tt and the residual vanish
    diffs[:, 7, :] = diffs[0, 7, :]  # equal differences in every view
    inside = (rng.random((k, h, w)) > 0.2).astype(np.float32)
    inside[:, :3, :] = 0.0  # no view inside: every weight 0
    inside[:, 3, :] = 1.0
    gcs = rng.normal(0.0, 5.0, (k, h, w)).astype(np.float32)
    grs = rng.normal(0.0, 5.0, (k, h, w)).astype(np.float32)
    return diffs, inside, gcs, grs


@pytest.mark.parametrize(("positions", "ref"), [((0.0, 1.0, 2.0), 1), ((0.0, 1.0), 0), ((-3.0, -1.0, 0.0, 0.5, 2.0, 4.0), 2)])
def test_occlusion_weights_and_fit_match_numpy(positions, ref):
    rng = np.random.default_rng(len(positions))
    shape = (40, 1100)  # more pixels than one chunk, not a multiple of it
    t = np.asarray(positions) - positions[ref]
    n = len(t)
    views = [k for k in range(n) if k != ref]
    diffs, inside, gcs, grs = _views(rng, n, ref, shape)
    floor = 4.0 * 0.37**2

    def as_list(a):
        return [None if k == ref else a[views.index(k)] for k in range(n)]

    w_ref = stereo._occlusion_weights(t, ref, as_list(diffs), as_list(inside), floor, 1.5)
    w_nb = stereo._occlusion_weights_stacked(diffs, inside, floor, 1.5)
    for j, k in enumerate(views):
        _same(w_nb[j], w_ref[k])
    assert (w_nb[:, :3] == 0).all()
    assert ((w_nb > 0) & (w_nb < 1)).any() == (len(views) > 1)  # a lone view keeps weight 1 where inside

    slope, s_tt, chi2, sum_m = stereo._regress(t, ref, as_list(diffs), w_ref)
    ref_gc = rng.normal(0.0, 5.0, shape).astype(np.float32)
    ref_gr = rng.normal(0.0, 5.0, shape).astype(np.float32)
    wsum = np.zeros(shape, np.float32)
    gc = np.zeros(shape, np.float32)
    gr = np.zeros(shape, np.float32)
    for j in range(len(views)):
        wsum += w_nb[j]
        gc += w_nb[j] * (0.5 * (ref_gc + gcs[j]))
        gr += w_nb[j] * (0.5 * (ref_gr + grs[j]))
    with np.errstate(divide="ignore", invalid="ignore"):
        grad_col = np.where(wsum > 0, gc / wsum, 0.0).astype(np.float32)
        grad_row = np.where(wsum > 0, gr / wsum, 0.0).astype(np.float32)

    out = np.full((6, *shape), np.nan, np.float32)
    k = len(views)
    tk = np.array([t[v] for v in views], np.float32)
    flat = [a.reshape(k, -1) for a in (diffs, w_nb, gcs, grs)]
    _view_fit._nb_fit(tk, *flat, ref_gc.ravel(), ref_gr.ravel(), *out.reshape(6, -1))
    for got, want in zip(out, (slope, s_tt, chi2, sum_m, grad_col, grad_row)):
        _same(got, want)
    assert (out[0][:3] == 0).all() and (out[4][:3] == 0).all()  # no weight: slope and gradient 0


def test_occlusion_weights_propagate_nan_as_numpy():
    """A NaN energy wins the minimum (np.minimum) and gives weight 0, as in the reference."""
    energy = np.array([[1.0, np.nan, 4.0, np.inf], [2.0, 3.0, np.nan, np.inf]], np.float32)
    inside = np.array([[1.0, 1.0, 1.0, 1.0], [1.0, 1.0, 0.0, 1.0]], np.float32)
    out = np.empty_like(energy)
    _view_fit._nb_occlusion_weights(energy, inside, np.float32(0.5), out)
    best = np.minimum.reduce([np.where(inside[k] > 0, energy[k], np.inf) for k in range(2)])
    with np.errstate(invalid="ignore"):
        want = [np.where(np.isfinite(r), np.minimum(r, 1.0) ** 2, 0.0) * inside[k] for k, r in enumerate(2.0 * (best + np.float32(0.5)) / (np.where(inside > 0, energy, np.inf) + np.float32(0.5)))]
    _same(out, np.asarray(want, np.float32))
    np.testing.assert_array_equal(out[:, 1], 0.0)  # NaN in one view: no weight anywhere
    np.testing.assert_array_equal(out[:, 3], 0.0)  # both views infinitely far off


@pytest.mark.parametrize("shape", [(2, 2), (2, 5), (3, 3), (4, 2), (5, 6), (33, 71)])
def test_pair_stencil_matches_cell_gradient(shape):
    """Cell gradients of the warped view and its cell-mean difference, every border case of the edge padding."""
    rng = np.random.default_rng(shape[0] * 100 + shape[1])
    nodes = rng.normal(100.0, 20.0, shape).astype(np.float32)
    ref_nodes = rng.normal(100.0, 20.0, shape).astype(np.float32)
    h, w = shape[0] - 1, shape[1] - 1
    out = np.full((3, h, w), np.nan, np.float32)
    _view_fit._nb_pair_stencil(nodes, ref_nodes, stereo._STENCIL_NEAR, stereo._STENCIL_WIDE, *out)
    gc, gr = _cell_gradient(nodes, True)
    _same(out[0], gc)
    _same(out[1], gr)
    _same(out[2], _cell_mean(nodes - ref_nodes))


def test_measure_is_the_same_compiled_or_not(monkeypatch):
    """The whole per-level measurement (warps, stencils, weights, photometric offsets, fit) is bit-identical on both paths."""
    rng = np.random.default_rng(5)
    base = rng.normal(0.0, 1.0, (60, 90)).astype(np.float32)
    base = cv2.GaussianBlur(base, (0, 0), 2.0) * 400.0 + 100.0
    t = np.array([-2.0, -1.0, 0.0, 1.0])
    ref = 2
    d = (3.0 + 0.02 * np.arange(90, dtype=np.float32))[None, :].repeat(60, 0)
    views = [cv2.warpAffine(base, np.array([[1.0, 0.0, 3.1 * tk], [0.0, 1.0, 0.0]]), (90, 60), borderMode=cv2.BORDER_REFLECT) + np.float32(0.5 * k) for k, tk in enumerate(t)]
    reference = stereo._ReferenceNodes.of(views[ref])
    results = {}
    for use in (False, True):
        monkeypatch.setattr(fast, "USE_NUMBA", use)
        results[use] = stereo._measure(views, t, ref, d, floor=0.1, window_px=1.5, reference=reference, offset_window_px=4.0)
    a, b = results[True], results[False]
    for name in ("slope", "grad_col", "grad_row", "s_tt", "chi2", "dof", "count", "ref_nodes"):
        _same(getattr(a, name), getattr(b, name))
    for k in range(len(t)):
        if k == ref:
            assert a.weights[k] is None and a.offsets[k] is None
            continue
        _same(a.weights[k], b.weights[k])
        _same(a.offsets[k], b.offsets[k])
    assert (a.weights[0] < 1).any() and np.abs(a.offsets[3]).max() > 0.1  # the weights and offsets did something
