"""The fast path and the streaming API against the plain reference implementation."""

from __future__ import annotations

import json
import os

import cv2
import numpy as np
import pytest

from nfdepth import bench, fast
from nfdepth.edges import select_edge_points
from nfdepth.fast import StreamingNormalFlow, normal_flow_edges
from nfdepth.normal_flow import gaussian_smooth, normal_flow


@pytest.fixture(params=["numba", "numpy"], autouse=True)
def backend(request, monkeypatch):
    """Run every test on the fused numba kernels and on the numpy/OpenCV fallback."""
    if request.param == "numba" and not fast.USE_NUMBA:
        pytest.skip("numba not installed (or NFDEPTH_NO_NUMBA set)")
    monkeypatch.setattr(fast, "USE_NUMBA", request.param == "numba")
    fast._local.ws = None
    return request.param


def _texture(shape, seed=0):
    H, W = shape
    rng = np.random.default_rng(seed)
    base = cv2.GaussianBlur(rng.random((H + 40, W + 40)), (0, 0), 3.0)
    base = np.where(base > base.mean(), 200.0, 50.0)
    return cv2.GaussianBlur(base, (0, 0), 1.2)


def _sequence(shape=(96, 128), n=3, shift=(0.7, 0.25), seed=0):
    """Smooth random regions moving by sub-pixel steps (cubic warps), float32."""
    H, W = shape
    base = _texture(shape, seed)
    out = []
    for k in range(n):
        t = k - (n - 1) / 2
        M = np.float64([[1, 0, shift[0] * t], [0, 1, shift[1] * t]])
        img = cv2.warpAffine(base, M, (W + 40, H + 40), flags=cv2.INTER_CUBIC)
        out.append(img[20:-20, 20:-20].astype(np.float32))
    return out


def _reference(frames, *, sigma_px, frame_interval=1.0, stencil="matched", **edge):
    g = normal_flow(frames, sigma_px=sigma_px, frame_interval=frame_interval, stencil=stencil)
    edge.setdefault("corner_window_px", max(sigma_px, 1.0))
    sel = select_edge_points(g, gaussian_smooth(frames[1], sigma_px=sigma_px), **edge)
    return g, sel


def _assert_close(result, g, sel):
    scale = float(np.max(g.magnitude))
    np.testing.assert_allclose(result.magnitude, g.magnitude, rtol=0, atol=1e-5 * scale)
    # Angles compared on the circle, where the direction is defined to float32 precision.
    strong = g.magnitude > 1e-2 * scale
    dal = np.angle(np.exp(1j * (result.alpha.astype(np.float64) - g.alpha)))
    # alpha is computed at the candidate edge points only (NaN elsewhere).
    assert np.all(np.isfinite(result.alpha[sel.mask]))
    assert np.max(np.abs(dal[sel.mask])) < 1e-5
    vn_ref = g.normal_flow
    m = sel.mask
    np.testing.assert_allclose(result.vn[m], vn_ref[m], rtol=1e-5, atol=1e-5 * float(np.max(np.abs(vn_ref[m]))))
    both = strong
    np.testing.assert_allclose(result.vn[both], vn_ref[both], rtol=0, atol=1e-4 * float(np.max(np.abs(vn_ref[both]))))
    assert result.min_gradient == pytest.approx(sel.min_gradient, rel=1e-5)
    # Masks: identical (ties at a threshold could differ; none occur here).
    np.testing.assert_array_equal(result.mask, sel.mask)
    assert sel.mask.sum() > 50


@pytest.mark.parametrize("stencil", ["matched", "simpson", "paper"])
@pytest.mark.parametrize("sigma_px", [0.0, 1.3, 2.0])
def test_fast_matches_reference(stencil, sigma_px):
    frames = _sequence()
    g, sel = _reference(frames, sigma_px=sigma_px, frame_interval=0.5, stencil=stencil)
    result = normal_flow_edges(frames, sigma_px=sigma_px, frame_interval=0.5, stencil=stencil)
    assert result.vn.shape == result.mask.shape == (95, 127)
    assert result.vn.dtype == np.float32 and result.mask.dtype == bool
    _assert_close(result, g, sel)
    vn, alpha, mag, mask = result
    assert vn is result.vn and mask is result.mask


@pytest.mark.parametrize("shape", [(70, 90), (71, 91), (70, 91)])  # cell grids odd, even, mixed: block-grid borders
def test_fast_matches_reference_options(shape):
    frames = _sequence(shape, shift=(-0.4, 0.9), seed=3)
    opts = {"min_gradient": 5.0, "max_corner_ratio": 0.3, "corner_window_px": 1.5, "border_px": 4}
    g, sel = _reference(frames, sigma_px=1.5, **opts)
    result = normal_flow_edges(frames, sigma_px=1.5, **opts)
    _assert_close(result, g, sel)
    assert result.min_gradient == 5.0


def test_fast_exact_on_ramp():
    r, c = np.mgrid[0:12, 0:16].astype(np.float32)
    frames = [2.0 * c + 3.0 * r - 5.0 * t for t in (-1, 0, 1)]
    res = normal_flow_edges(frames, sigma_px=0.0)
    inner = (slice(1, -1), slice(1, -1))  # the matched stencil's edge padding bends the ramp at the border
    np.testing.assert_allclose(res.magnitude[inner], np.hypot(2.0, 3.0), rtol=1e-6)
    assert np.all(np.isnan(res.alpha))  # no edge points on a ramp: no angle computed
    np.testing.assert_allclose(res.vn[inner], 5.0 / np.hypot(2.0, 3.0), rtol=1e-6)
    ref = normal_flow(frames, sigma_px=0.0)
    np.testing.assert_allclose(res.magnitude, ref.magnitude, rtol=1e-6)
    assert not res.mask.any()  # no zero crossings on a ramp


def test_fast_flat_image_has_no_edges():
    # The reference takes differences first and gets exact zeros (vn NaN); the
    # fast path sums kernel taps, which leaves float32 rounding (~1e-7 of the
    # intensity) instead. Either way: no gradient to speak of, no edge points.
    frames = [np.full((10, 12), 7.0, np.float32)] * 3
    res = normal_flow_edges(frames, sigma_px=0.0)
    assert np.all(res.magnitude < 1e-5) and not res.mask.any()
    # vn = -I_t / |grad I| with I_t exactly 0 (three equal frames): 0 or NaN, never a spurious flow
    assert np.all(np.isnan(res.vn) | (np.abs(res.vn) < 1e-3))


def test_streaming_equals_from_scratch():
    frames = _sequence((64, 80), n=7, shift=(0.6, -0.3), seed=5)
    stream = StreamingNormalFlow(sigma_px=1.8, frame_interval=0.25)
    assert stream.push(frames[0]) is None
    assert stream.push(frames[1]) is None
    for t in range(2, len(frames)):
        got = stream.push(frames[t])
        want = normal_flow_edges(frames[t - 2 : t + 1], sigma_px=1.8, frame_interval=0.25)
        scale = float(np.max(want.magnitude))
        np.testing.assert_allclose(got.magnitude, want.magnitude, rtol=0, atol=1e-5 * scale)
        m = want.mask
        np.testing.assert_allclose(got.vn[m], want.vn[m], rtol=1e-5, atol=1e-5 * float(np.max(np.abs(want.vn[m]))))
        np.testing.assert_allclose(got.alpha[m], want.alpha[m], atol=1e-5)
        np.testing.assert_array_equal(got.mask, want.mask)
    assert stream.frames_seen == len(frames)
    stream.reset()
    assert stream.push(frames[0]) is None
    # after a reset (a scene cut) the frames may change size: the stream follows the next frame's
    stream.reset()
    other = _sequence((65, 80), n=3, shift=(0.6, -0.3), seed=6)
    assert stream.push(other[0]) is None and stream.push(other[1]) is None
    got = stream.push(other[2])
    want = normal_flow_edges(other, sigma_px=1.8, frame_interval=0.25)
    np.testing.assert_array_equal(got.mask, want.mask)
    with pytest.raises(ValueError, match=r"frame 3 has shape \(64, 80\), but this stream's frames have shape \(65, 80\)"):
        stream.push(frames[0])  # without a reset the size stays


def test_kept_results_are_never_overwritten():
    # Outputs come from a recycled pool; a result (or a view of one) that the
    # caller still holds must survive later calls unchanged.
    a = _sequence((40, 50), seed=1)
    b = _sequence((40, 50), seed=2)
    first = normal_flow_edges(a, sigma_px=1.5)
    saved = [x.copy() for x in first]
    view = normal_flow_edges(a, sigma_px=1.5).vn[3:10]  # only a view kept
    view_saved = view.copy()
    for _ in range(4):
        other = normal_flow_edges(b, sigma_px=1.5)
    for x, y in zip(first, saved):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(view, view_saved)
    assert not np.shares_memory(other.vn, first.vn) and not np.shares_memory(other.vn, view)
    del first, view, other
    again = normal_flow_edges(a, sigma_px=1.5)  # a free set is reused and rewritten
    for x, y in zip(again, saved):
        np.testing.assert_array_equal(x, y)


def test_streaming_bad_input():
    stream = StreamingNormalFlow(sigma_px=1.0)
    stream.push(np.zeros((10, 12)))
    with pytest.raises(ValueError, match="shape"):
        stream.push(np.zeros((11, 12)))
    with pytest.raises(ValueError, match="non-finite"):
        stream.push(np.full((10, 12), np.nan))
    with pytest.raises(ValueError, match="grey"):
        stream.push(np.zeros((10, 12, 3)))
    with pytest.raises(ValueError, match="sigma_px"):
        StreamingNormalFlow(sigma_px=-1.0)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"sigma_px": -1.0}, ValueError, "sigma_px"),
        ({"sigma_px": 1.0, "frame_interval": 0.0}, ValueError, "frame_interval"),
        ({"sigma_px": 1.0, "stencil": "sobel"}, ValueError, "stencil must be one of"),
        ({"sigma_px": 1.0, "max_corner_ratio": 1.5}, ValueError, "max_corner_ratio"),
        ({"sigma_px": 1.0, "min_gradient": -2.0}, ValueError, "min_gradient"),
        ({"sigma_px": 1.0, "corner_window_px": 0.0}, ValueError, "corner_window_px"),
        ({"sigma_px": 1.0, "max_corner_ratio": "x"}, TypeError, "max_corner_ratio must be a number within \\[0, 1\\], got 'x'"),
        ({"sigma_px": 1.0, "border_px": -1}, ValueError, "border_px must be an integer >= 0, got -1"),
        ({"sigma_px": 1.0, "border_px": 2.5}, TypeError, "border_px must be an integer >= 0, got 2.5"),
        ({"sigma_px": 1.0, "border_px": True}, TypeError, "border_px must be an integer >= 0, got True"),
        ({"sigma_px": "wide"}, TypeError, "sigma_px"),
    ],
)
def test_fast_bad_parameters(kwargs, exc, match):
    frames = _sequence((20, 24))
    with pytest.raises(exc, match=match):
        normal_flow_edges(frames, **kwargs)


def test_fast_bad_frames():
    frames = _sequence((20, 24))
    with pytest.raises(ValueError, match="exactly 3 frames"):
        normal_flow_edges(frames[:2], sigma_px=1.0)
    with pytest.raises(ValueError, match="same shape"):
        normal_flow_edges([frames[0], frames[1], frames[2][:-1]], sigma_px=1.0)
    bad = [f.copy() for f in frames]
    bad[1][3, 4] = np.inf
    with pytest.raises(ValueError, match="non-finite"):
        normal_flow_edges(bad, sigma_px=1.0)
    with pytest.raises(TypeError, match="sequence"):
        normal_flow_edges("abc", sigma_px=1.0)


def _run_benchmarks(**kwargs):
    """``bench.run_benchmarks``; without the data (a fresh machine) the Art scene is skipped with its warning."""
    if bench._middlebury((60, 80)) is not None:
        return bench.run_benchmarks(**kwargs)
    with pytest.warns(UserWarning, match=r"^the middlebury-art scene is skipped"):
        return bench.run_benchmarks(**kwargs)


def test_bench_records_well_formed(backend):
    if backend == "numpy":
        pytest.skip("bench runs the default backend only")
    records = _run_benchmarks(quick=True, sizes=[(120, 160)], repeats=3)
    names = {r["name"] for r in records}
    assert {"nf_edges", "nf_stream_frame", "cv_sgbm", "cv_bm", "cv_dis_fast", "cv_dis_medium", "floor_blur3", "floor_copy3"} <= names
    for r in records:
        assert r["height"] == 120 and r["width"] == 160
        if r["median_ms"] is None:
            assert r["skipped"].startswith("skipped")
            continue
        assert r["median_ms"] > 0 and r["runs"] >= 1 and r["peak_bytes"] >= 0
        assert r["ratio_to_sgbm"] > 0 and r["ratio_to_floor"] > 0
    table = bench.render_markdown(records)
    assert table.startswith("| case |") and "nf_edges" in table
    # SGBM with the disparities this scene needs: the multiple of 16 above static stereo's largest
    from nfdepth.stereo import static_stereo

    covering = [r for r in records if r["name"] == "cv_sgbm_covering" and r["median_ms"] is not None]
    assert covering
    for r in covering:
        frames = bench._rendered((120, 160)) if r["scene"] == "rendered" else bench._middlebury((120, 160))
        top = float(np.nanmax(static_stereo(frames, reference=1).disparity))
        assert r["disparities"] % 16 == 0 and top + 1.0 <= r["disparities"]
        assert r["disparities"] == 16 or top + 1.0 > r["disparities"] - 16  # the smallest such multiple
        stereo = next(x for x in records if x["name"] == "nf_static_stereo" and x["scene"] == r["scene"])
        assert stereo["ratio_to_sgbm_covering"] == pytest.approx(stereo["median_ms"] / r["median_ms"])
        assert f"cv_sgbm_covering ({r['disparities']} disparities)" in table


def test_bench_says_when_the_middlebury_scene_is_missing(monkeypatch, tmp_path):
    """Without the data the Art scene is a skipped record (and a warning), not silently absent."""
    monkeypatch.setenv("NFDEPTH_DATA", str(tmp_path / "absent"))
    with pytest.warns(UserWarning, match=r"^the middlebury-art scene is skipped: the Middlebury 2005 Art views were not found \(set NFDEPTH_DATA.*\); only the rendered scene is timed$"):
        records = bench.run_benchmarks(sizes=[(60, 80)], repeats=1, scenes=("middlebury-art",))
    assert len(records) == 1 and records[0]["median_ms"] is None and records[0]["skipped"].startswith("skipped: the Middlebury 2005 Art views were not found")
    assert "| all cases | middlebury-art | 80×60 | 0.0 | skipped: the Middlebury" in bench.render_markdown(records)


def test_bench_options_are_checked_before_anything_runs(monkeypatch):
    """threads beyond the cores is refused before OpenCV is told (10**9 started thousands of workers)."""
    told = []
    monkeypatch.setattr(bench.cv2, "setNumThreads", told.append)
    cores = os.cpu_count() or 1
    with pytest.raises(ValueError, match=rf"^threads = {cores + 1} is more than this machine's {cores} cores .*: expected 1 to {cores}$"):
        bench.run_benchmarks(sizes=[(60, 80)], threads=cores + 1)
    with pytest.raises(ValueError, match=r"^repeats must be an integer >= 1, got 0$"):
        bench.run_benchmarks(sizes=[(60, 80)], repeats=0)  # was silently 1
    with pytest.raises(ValueError, match=r"^time_budget_s must be a number > 0 \(inf: no limit\), got -1$"):
        bench.run_benchmarks(sizes=[(60, 80)], time_budget_s=-1)
    assert told == []


@pytest.mark.skipif(os.name != "posix", reason="POSIX file modes")
def test_bench_json_is_written_atomically_with_the_outputs_mode(tmp_path, monkeypatch, backend, capsys):
    if backend == "numpy":
        pytest.skip("bench runs the default backend only")
    records = _run_benchmarks(quick=True, sizes=[(60, 80)], repeats=1)
    monkeypatch.setattr(bench, "run_benchmarks", lambda **_: records)
    out = tmp_path / "b.json"
    out.write_text("an older run")
    mask = os.umask(0o027)
    try:
        assert bench.bench_main(json_path=out, quick=True) == 0
    finally:
        os.umask(mask)
    assert out.stat().st_mode & 0o777 == 0o640  # was 0600 (mkstemp's mode)
    payload = json.loads(out.read_text())
    assert payload["records"] == records and payload["sigma_px"] == bench.SIGMA_PX
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.json"]
    assert "| nf_edges |" in capsys.readouterr().out


def test_deterministic_and_streaming_bit_identical(backend):
    # Same inputs, fresh or reused buffers, from scratch or streamed: the same bits.
    frames = _sequence((61, 83), n=5, shift=(0.5, 0.4), seed=7)
    first = [x.copy() for x in normal_flow_edges(frames[:3], sigma_px=1.6)]
    fast._local.ws = None
    for _ in range(2):
        again = normal_flow_edges(frames[:3], sigma_px=1.6)
        for x, y in zip(again, first):
            np.testing.assert_array_equal(x, y)
    if backend != "numba":
        return
    stream = StreamingNormalFlow(sigma_px=1.6)
    for t, f in enumerate(frames):
        got = stream.push(f)
        if t >= 2:
            want = normal_flow_edges(frames[t - 2 : t + 1], sigma_px=1.6)
            for x, y in zip(got, want):
                np.testing.assert_array_equal(x, y)


def test_tiny_images_and_window_larger_than_image():
    # Structure-tensor window wider than the cell grid: reflected borders as cv2's.
    frames = _sequence((9, 11), seed=4)
    opts = {"min_gradient": 0.0, "max_corner_ratio": 1.0, "border_px": 0}
    g, sel = _reference(frames, sigma_px=1.0, corner_window_px=3.0, **opts)
    res = normal_flow_edges(frames, sigma_px=1.0, corner_window_px=3.0, **opts)
    np.testing.assert_array_equal(res.mask, sel.mask)
    np.testing.assert_allclose(res.magnitude, g.magnitude, rtol=0, atol=1e-5 * float(g.magnitude.max()))
    for shape in ((2, 2), (2, 7), (7, 2)):
        fr = [np.arange(shape[0] * shape[1], dtype=np.float32).reshape(shape) * (t + 1) for t in range(3)]
        out = normal_flow_edges(fr, sigma_px=0.8, border_px=0)
        assert out.vn.shape == (shape[0] - 1, shape[1] - 1)


@pytest.mark.parametrize("shape", [(50, 60), (37, 91)])
def test_a_flat_image_has_no_edge_points(shape):
    """The fast path applies the reference's float32-rounding floor (nfdepth.edges.ROUNDING_GRADIENT)."""
    frames = [np.full(shape, 7.0, np.float32)] * 3
    assert not fast.normal_flow_edges(frames, sigma_px=2.0).mask.any()
    stream = fast.StreamingNormalFlow(sigma_px=2.0)
    results = [stream.push(f) for f in frames]
    assert not results[-1].mask.any()


def test_intensities_too_small_for_float32_squares_are_refused():
    """Frames scaled by 1e-22 gave NaN flows and a 1.3 % |grad I| error, by 1e-25 no edge point (float32 squares
    of the gradients underflow; the reference's np.hypot does not). Frames whose peak is non-zero but below 1e-15
    are refused with the advice to rescale; just above it the fast path still matches the reference."""
    frames = _sequence()
    peak = max(float(np.max(np.abs(f))) for f in frames)
    tiny = [f * np.float32(1e-16 / peak) for f in frames]
    with pytest.raises(ValueError, match=r"^frames\[0\] has intensities only up to 1e-16, below 1e-15: the float32 work squares gradients, .*rescale the intensities"):
        normal_flow_edges(tiny, sigma_px=1.5)
    stream = StreamingNormalFlow(sigma_px=1.5)
    with pytest.raises(ValueError, match=r"^frame 0 has intensities only up to 1e-16, below 1e-15: "):
        stream.push(tiny[0])
    assert stream.frames_seen == 0
    # zero is no scale: all-black frames pass (no edge point)
    assert not normal_flow_edges([np.zeros((20, 24), np.float32)] * 3, sigma_px=1.0).mask.any()
    # at twice the bound: the reference's results, to its usual tolerances
    small = [f * np.float32(2e-15 / peak) for f in frames]
    g, sel = _reference(small, sigma_px=1.5)
    _assert_close(normal_flow_edges(small, sigma_px=1.5), g, sel)


@pytest.mark.parametrize(("dark_side", "alpha"), [("right", np.pi), ("left", 0.0), ("below", -np.pi / 2), ("above", np.pi / 2)])
def test_the_normal_of_an_axis_aligned_edge(dark_side, alpha):
    """alpha = atan2(I_row, I_col) of a straight edge along a grid axis: pi where it is dark on the right (I_row
    is exactly 0). The fallback's I_row, a sum of weighted taps, was float32 rounding (-6e-6) there, so it gave
    alpha = -pi + 2e-7 (2 pi from the reference's +pi) at every edge point; now it is the reference's, exactly
    (I_row set to +0 where the stencil's rows are equal). Along the rows the fallback's I_col is rounding in the
    same way, which moves alpha from +-pi/2 by a float32 ulp (no wrap: within 2.4e-7)."""
    c = np.arange(48, dtype=np.float64)[None, :].repeat(40, 0)
    frames = [-100.0 * (c - 0.4 * t > 23.3) - 50.0 for t in (-1, 0, 1)]  # dark (lower) on the right
    turn = {"right": lambda f: f, "left": lambda f: f[:, ::-1], "below": lambda f: f.T, "above": lambda f: f.T[::-1]}[dark_side]
    frames = [np.ascontiguousarray(turn(f)) for f in frames]
    g, sel = _reference(frames, sigma_px=1.5)
    res = normal_flow_edges(frames, sigma_px=1.5)
    np.testing.assert_array_equal(res.mask, sel.mask)
    assert res.mask.sum() >= 30
    np.testing.assert_array_equal(g.alpha[sel.mask], np.float32(alpha))
    if dark_side in ("right", "left"):
        np.testing.assert_array_equal(res.alpha[res.mask], np.float32(alpha))
    else:
        np.testing.assert_allclose(res.alpha[res.mask], alpha, rtol=0, atol=2.4e-7)
