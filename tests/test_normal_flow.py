"""Normal-flow estimation (paper section 3.1) against analytic ground truth."""

import numpy as np
import pytest
from scipy.special import erf

from nfdepth._validate import MAX_SCALE_PX
from nfdepth.normal_flow import (
    STENCILS,
    GradientField,
    estimate_noise_std,
    gaussian_smooth,
    gradients,
    noise_gains,
    normal_flow,
)


def ramp(a, b, c, t, shape=(12, 14)):
    r, col = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    return a * col + b * r + c * t


@pytest.mark.parametrize("stencil", STENCILS)
@pytest.mark.parametrize("dt", [1.0, 2.0, 0.25])
def test_three_frame_stencil_exact_on_linear_ramp(stencil, dt):
    frames = [ramp(2.5, -1.5, 4.0, t) for t in (-dt, 0.0, dt)]
    g = gradients(frames, frame_interval=dt, stencil=stencil)
    inner = (slice(2, -2), slice(2, -2))  # the four-point difference pads the border
    np.testing.assert_allclose(g.grad_col[inner], 2.5, rtol=1e-12)
    np.testing.assert_allclose(g.grad_row[inner], -1.5, rtol=1e-12)
    np.testing.assert_allclose(g.grad_t[inner], 4.0, rtol=1e-12)
    assert g.shape == (11, 13)


def test_two_frame_horn_schunck_exact_on_ramp():
    frames = [ramp(1.0, 2.0, -3.0, t) for t in (0.0, 0.5)]
    g = gradients(frames, frame_interval=0.5, stencil="paper")
    np.testing.assert_allclose(g.grad_col, 1.0)
    np.testing.assert_allclose(g.grad_row, 2.0)
    np.testing.assert_allclose(g.grad_t, -3.0)


def test_ramp_normal_flow_and_direction():
    # I = 3 col + 4 row - 10 t  ->  |grad| = 5, Vn = 10 / 5 = 2, alpha = atan2(4, 3)
    frames = [ramp(3.0, 4.0, -10.0, t) for t in (-1, 0, 1)]
    g = normal_flow(frames, sigma_px=0, dtype=np.float64)
    np.testing.assert_allclose(g.normal_flow[3:-3, 3:-3], 2.0, rtol=1e-12)
    np.testing.assert_allclose(g.alpha[3:-3, 3:-3], np.arctan2(4, 3), rtol=1e-12)


def test_identical_frames_give_exactly_zero_flow():
    rng = np.random.default_rng(3)
    img = rng.uniform(0, 255, (30, 40))
    g = normal_flow([img, img, img], sigma_px=1.5)
    vn = g.normal_flow
    assert np.all(vn[np.isfinite(vn)] == 0.0)


def test_cell_centres_are_half_pixel_offsets():
    rows, cols = GradientField.cell_centres((2, 3))
    np.testing.assert_array_equal(rows[:, 0], [0.5, 1.5])
    np.testing.assert_array_equal(cols[0], [0.5, 1.5, 2.5])


def moving_edge(theta, speed, dt, shape=(64, 64), s0=0.5):
    """A straight blurred edge moving along its normal at `speed` px per unit time."""
    r, c = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    n = (np.cos(theta), np.sin(theta))
    out = []
    for t in (-dt, 0.0, dt):
        d = (c - 31.3) * n[0] + (r - 31.7) * n[1] - speed * t
        out.append(100.0 * erf(d / (np.sqrt(2) * s0)))
    return out


def edge_cells(g):
    mag = g.magnitude
    m = mag > 0.9 * mag[20:44, 20:44].max()
    m[:20] = m[44:] = False
    m[:, :20] = m[:, 44:] = False
    return m


@pytest.mark.parametrize("theta", [0.0, np.pi / 8, np.pi / 4, 2.0])
def test_matched_stencil_recovers_edge_speed(theta):
    # One triple spanning 2 px of motion per frame (the paper's moving camera).
    frames = moving_edge(theta, 1.0, 2.0)
    g = normal_flow(frames, sigma_px=2.5, frame_interval=2.0, dtype=np.float64)
    vn = g.normal_flow[edge_cells(g)]
    # Remaining error: Simpson's rule, d^4 / (60 sigma^4) ~ 0.4 % for d = 2, sigma = 2.5.
    np.testing.assert_allclose(vn, 1.0, rtol=0.006)


def test_paper_stencil_is_biased_where_matched_is_not():
    frames = moving_edge(0.0, 1.0, 2.0)
    errs = {}
    for stencil in STENCILS:
        g = normal_flow(frames, sigma_px=1.5, frame_interval=2.0, stencil=stencil, dtype=np.float64)
        errs[stencil] = np.median(np.abs(g.normal_flow[edge_cells(g)] - 1.0))
    # measured: paper ~ 4-5 %, simpson ~ 3 % (2-point difference bias), matched ~ 2.5 %
    assert errs["matched"] < errs["simpson"] < errs["paper"]


def test_noise_estimate_and_gains():
    rng = np.random.default_rng(5)
    img = rng.normal(0, 2.0, (200, 200))
    assert estimate_noise_std(img) == pytest.approx(2.0, rel=0.05)  # 40k samples: ~1 % sampling error
    assert estimate_noise_std(np.full((20, 20), 7.0)) == 0.0
    # Empirical check of the temporal gain: I_t*dt of pure noise frames.
    frames = [rng.normal(0, 1.0, (300, 300)) for _ in range(3)]
    g = normal_flow(frames, sigma_px=2.0, dtype=np.float64)
    temporal, spatial = noise_gains(sigma_px=2.0)
    inner = (slice(10, -10), slice(10, -10))
    assert np.std(g.grad_t[inner]) == pytest.approx(temporal, rel=0.1)  # correlated samples: ~5 % spread
    assert np.std(g.grad_col[inner]) == pytest.approx(spatial, rel=0.1)


def test_gaussian_smooth_preserves_mean_and_zero_sigma_copies():
    rng = np.random.default_rng(0)
    img = rng.uniform(0, 1, (40, 40)).astype(np.float32)
    assert gaussian_smooth(img, sigma_px=0) is not img
    np.testing.assert_array_equal(gaussian_smooth(img, sigma_px=0), img)
    assert gaussian_smooth(img, sigma_px=2).mean() == pytest.approx(img.mean(), rel=1e-3)


def test_float32_and_float64_agree():
    frames = moving_edge(0.4, 0.5, 1.0)
    g32 = normal_flow(frames, sigma_px=2.0, dtype=np.float32)
    g64 = normal_flow(frames, sigma_px=2.0, dtype=np.float64)
    m = edge_cells(g64)
    np.testing.assert_allclose(g32.normal_flow[m], g64.normal_flow[m], rtol=1e-4)  # float32 epsilon x gain


@pytest.mark.parametrize(
    ("frames", "kwargs", "exc", "match"),
    [
        ([np.zeros((5, 5))] * 4, {}, ValueError, "frames must hold 2 or 3 frames, got 4"),
        ([np.zeros((5, 5)), np.zeros((5, 6)), np.zeros((5, 5))], {}, ValueError, "same shape"),
        ([np.zeros((5, 5))] * 2 + [np.full((5, 5), np.nan)], {}, ValueError, r"frames\[2\] contains 25 non-finite"),
        ([np.zeros((5, 5, 3))] * 3, {}, ValueError, "2-D grey image"),
        ([np.zeros((5, 5))] * 3, {"sigma_px": -1}, ValueError, "sigma_px must be a finite number >= 0"),
        ([np.zeros((5, 5))] * 3, {"frame_interval": 0}, ValueError, "frame_interval must be a positive"),
        ([np.zeros((5, 5))] * 3, {"stencil": "sobel"}, ValueError, "stencil must be one of"),
        ([np.zeros((5, 5))] * 3, {"dtype": np.int16}, ValueError, "dtype=int16 is not supported"),
        ([np.zeros((5, 5), dtype=complex)] * 3, {}, TypeError, "must be real"),
        ("abc", {}, TypeError, "frames must be a sequence of 2-D arrays"),
    ],
)
def test_bad_input(frames, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        normal_flow(frames, **kwargs)


@pytest.mark.parametrize("matched", [True, False])
@pytest.mark.parametrize("shape", [(2, 2), (3, 5), (37, 52)])
def test_row_difference_is_the_transposed_column_difference(matched, shape):
    """The difference along rows works on rows directly; it must equal the column difference of the transpose, bit for bit."""
    from nfdepth.normal_flow import _diff

    rng = np.random.default_rng(5)
    for dtype in (np.float32, np.float64):
        image = rng.normal(0.0, 40.0, shape).astype(dtype)
        expected = _diff(image.T, matched, axis=1).T
        got = _diff(image, matched, axis=0)
        assert got.dtype == expected.dtype
        np.testing.assert_array_equal(got, expected)


def test_normal_flow_along_a_shared_gradient():
    """``-I_t / |g|`` for a given gradient ``g``: on I = 3 col + 4 row - 10 t, 10 / 5 = 2 px along
    its own gradient, 10 / 10 = 1 along one twice as steep; NaN where ``g`` vanishes."""
    frames = [ramp(3.0, 4.0, -10.0, t) for t in (-1, 0, 1)]
    g = normal_flow(frames, sigma_px=0, dtype=np.float64)
    inner = (slice(3, -3), slice(3, -3))
    np.testing.assert_allclose(g.normal_flow_along(g.grad_col, g.grad_row)[inner], 2.0, rtol=1e-12)
    gc, gr = np.full(g.shape, 6.0), np.full(g.shape, -8.0)
    gc[5, 5] = gr[5, 5] = 0.0
    vn = g.normal_flow_along(gc, gr)
    np.testing.assert_allclose(np.delete(vn[inner].ravel(), (5 - 3) * (g.shape[1] - 6) + (5 - 3)), 1.0, rtol=1e-12)
    assert np.isnan(vn[5, 5]) and np.isfinite(vn[inner]).sum() == vn[inner].size - 1


@pytest.mark.parametrize("n_frames", [2, 3])
@pytest.mark.parametrize("stencil", ["matched", "paper"])
def test_noise_gains_without_smoothing(stencil, n_frames):
    """sigma_px=0: a white pixel's 2 x 2 cell mean has a sum of squares of 4 / 16, so I_t dt
    (half the difference of the outer frames of a triple, the difference of a pair) has
    std sqrt(2 / 4) / 2 or sqrt(2 / 4), exactly. Both gains against pure-noise frames: 90k
    samples correlated over ~2 px, ~1 % sampling error (measured within 0.6 %); 3 %."""
    temporal, spatial = noise_gains(sigma_px=0, stencil=stencil, n_frames=n_frames)
    assert temporal == pytest.approx(np.sqrt(0.5) / (2.0 if n_frames == 3 else 1.0), rel=1e-12)
    rng = np.random.default_rng(11)
    g = gradients([rng.normal(0.0, 1.0, (300, 300)) for _ in range(n_frames)], frame_interval=1.0, stencil=stencil)
    inner = (slice(5, -5), slice(5, -5))
    assert np.std(g.grad_t[inner]) == pytest.approx(temporal, rel=0.03)
    assert np.std(g.grad_col[inner]) == pytest.approx(spatial, rel=0.03)
    assert np.std(g.grad_row[inner]) == pytest.approx(spatial, rel=0.03)
    with pytest.raises(ValueError, match=r"^stencil must be one of \('matched', 'simpson', 'paper'\), got 'sobel'$"):
        noise_gains(sigma_px=0, stencil="sobel")


@pytest.mark.parametrize(
    ("bad", "error", "message"),
    [
        (np.ones(5), ValueError, r"must be a non-empty 2-D image \(rows, cols\), got shape \(5,\)"),
        (np.ones((4, 5, 3)), ValueError, r".*got shape \(4, 5, 3\)$"),
        (np.ones((0, 5)), ValueError, r".*got shape \(0, 5\)$"),
        (np.ones((4, 5), complex), TypeError, r"must be a real numeric 2-D array, got dtype complex128"),
        (np.array([["a", "b"], ["c", "d"]]), TypeError, r".*got dtype <U1$"),
    ],
)
def test_smoothing_and_gradients_refuse_what_is_no_image(bad, error, message):
    """gaussian_smooth and gradients (public) passed these to OpenCV or NumPy: a 1-D image came back as (1, 5),
    a complex one as complex gradients, others as a raw cv2.error."""
    with pytest.raises(error, match=r"^image " + message):
        gaussian_smooth(bad, sigma_px=1.0)
    with pytest.raises(error, match=r"^smoothed_frames\[0\] " + message):
        gradients([bad, bad, bad])


def test_smoothing_and_gradients_take_integer_and_list_images():
    ramp = np.add.outer(np.arange(8), 2 * np.arange(9))
    for image in (ramp.astype(np.int64), ramp.tolist(), ramp.astype(np.uint8)):
        np.testing.assert_allclose(gaussian_smooth(image, sigma_px=1.0), gaussian_smooth(ramp.astype(float), sigma_px=1.0), atol=1e-12)
        g = gradients([image, image, image], stencil="simpson")
        np.testing.assert_allclose(g.grad_col[2:-2, 2:-2], 2.0)
        np.testing.assert_allclose(g.grad_row[2:-2, 2:-2], 1.0)


@pytest.mark.parametrize("kind", ["f4", "f8"])
def test_big_endian_floats_are_smoothed_as_native_ones(kind):
    """A big-endian float array (np.load of a '>f4' .npy, FITS data) went to OpenCV as raw bytes: a constant 100
    smoothed to 7e-41. Smoothing keeps a constant (the kernel sums to 1: float rounding only) and a big-endian
    image gives the native image's result bit for bit, in the native byte order of its precision."""
    native = np.full((6, 8), 100.0, dtype=kind)
    big = native.astype(">" + kind)
    for sigma in (0.0, 1.0, 2.5):
        got = gaussian_smooth(big, sigma_px=sigma)
        assert got.dtype == np.dtype(kind) and got.dtype.isnative
        np.testing.assert_array_equal(got, gaussian_smooth(native, sigma_px=sigma))
        np.testing.assert_allclose(got, 100.0, rtol=1e-6 if kind == "f4" else 1e-12)
    # the gradients of big-endian frames: the ramp's exact gradient, in native floats
    frames = [ramp(2.0, -3.0, 5.0, t).astype(">" + kind) for t in (-1, 0, 1)]
    g = gradients(frames)
    inner = (slice(2, -2), slice(2, -2))
    assert g.grad_col.dtype == np.dtype(kind) and g.grad_col.dtype.isnative
    for got, want in ((g.grad_col, 2.0), (g.grad_row, -3.0), (g.grad_t, 5.0)):
        np.testing.assert_allclose(got[inner], want, rtol=1e-6 if kind == "f4" else 1e-12)


def _dense_noise_gains(sigma_px, stencil, n_frames):
    """The gains from the dense 2-D filters (Gaussian outer product, then the stencil on it): the brute force."""
    import importlib

    module = importlib.import_module("nfdepth.normal_flow")  # the module (nfdepth.normal_flow is also the function)

    g = module._gaussian_kernel_1d(sigma_px)
    pad = np.pad(np.outer(g, g), 3)
    cell = 0.25 * (pad[:-1, :-1] + pad[:-1, 1:] + pad[1:, :-1] + pad[1:, 1:])
    temporal = np.sqrt(2.0 * np.sum(cell**2)) / (2.0 if n_frames == 3 else 1.0)
    weights = np.asarray(module._TEMPORAL_WEIGHTS[stencil] if n_frames == 3 else (0.5, 0.5))
    gc, _ = module._cell_gradient(pad, stencil == "matched")
    return temporal, np.sqrt(np.sum(gc**2) * np.sum(weights**2))


@pytest.mark.parametrize("n_frames", [2, 3])
@pytest.mark.parametrize("stencil", STENCILS)
def test_noise_gains_are_those_of_the_dense_filters(stencil, n_frames):
    """The gains come from 1-D factors (the filters are separable); they equal the dense 2-D filters' to 1e-12
    relative (summation order: measured 3e-16)."""
    for sigma in (0.0, 0.7, 1.5, 3.0):
        got = noise_gains(sigma_px=sigma, stencil=stencil, n_frames=n_frames)
        np.testing.assert_allclose(got, _dense_noise_gains(sigma, stencil, n_frames), rtol=1e-12, atol=0)


def test_noise_gains_at_the_largest_smoothing():
    """sigma_px = 1e4 (then allowed; 5000 now) built a dense (8 sigma + 1)**2 kernel: MemoryError (48 GB). Now it takes kilobytes.

    At sigma = 5000 (OpenCV's kernel is a Gaussian up to 46341 taps, sigma 5792), the continuous limit: the
    kernel g, truncated at 4 sigma and normalised (c = 1 / erf(4 / sqrt 2)), has sum(g**2) = c**2 erf(4) /
    (2 sqrt(pi) sigma) (the 2-tap cell mean changes it by 1 / (8 sigma**2)), so I_t dt has std sqrt(2) S / 2
    (a triple) or sqrt(2) S (a pair), S that sum; a difference of g has a sum of squares of c**2 / (4 sqrt(pi)
    sigma**3) plus the truncation's two jumps of g(4 sigma), each once (two-point difference) or in three taps
    (matched: (3/4 + 1/12)**2 + 2 (1/12)**2 = 102/144), and I_col's std is sqrt(S D sum(w**2)) with the frames'
    weights w. What remains is the sums' end corrections, O(1 / sigma): measured 6e-8 and 3e-7; 1e-6 here."""
    import tracemalloc

    from scipy.special import erf

    tracemalloc.start()
    try:
        temporal, spatial = noise_gains(sigma_px=MAX_SCALE_PX)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 16 * 2**20 and 0 < spatial < temporal < 1
    sigma = 5000.0
    c = 1.0 / erf(4.0 / np.sqrt(2.0))
    S = c**2 * erf(4.0) / (2.0 * np.sqrt(np.pi) * sigma)
    g_end = c * np.exp(-8.0) / (np.sqrt(2.0 * np.pi) * sigma)
    for stencil in STENCILS:
        D = c**2 / (4.0 * np.sqrt(np.pi) * sigma**3) + 2.0 * (102.0 / 144.0 if stencil == "matched" else 1.0) * g_end**2
        for n_frames, weights in ((2, (0.5, 0.5)), (3, (1 / 3, 1 / 3, 1 / 3) if stencil == "paper" else (1 / 6, 4 / 6, 1 / 6))):
            want = (np.sqrt(2.0) * S / (2.0 if n_frames == 3 else 1.0), np.sqrt(S * D * np.sum(np.square(weights))))
            np.testing.assert_allclose(noise_gains(sigma_px=sigma, stencil=stencil, n_frames=n_frames), want, rtol=1e-6, atol=0)


def test_the_largest_smoothing_is_a_gaussian_of_its_sigma():
    """OpenCV's kernel is a Gaussian up to 46341 taps only: at sigma 1e4 (then allowed) its spread was 24457 px."""
    from nfdepth.normal_flow import _gaussian_kernel_1d

    k = _gaussian_kernel_1d(MAX_SCALE_PX)
    x = np.arange(k.size) - k.size // 2
    # truncated at 4 sigma: the spread is sigma sqrt(1 - 8 phi(4) / (2 Phi(4) - 1)) = 0.99946 sigma
    np.testing.assert_allclose(np.sqrt(np.sum(k * x**2) / np.sum(k)), 0.99946 * MAX_SCALE_PX, rtol=1e-4)
    with pytest.raises(ValueError, match=r"^sigma_px = 5001 px is beyond any image: expected a Gaussian scale of at most 5000 px"):
        gaussian_smooth(np.zeros((4, 4)), sigma_px=5001)
