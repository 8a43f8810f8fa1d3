"""Normal-flow estimation (paper section 3.1) against analytic ground truth."""

import numpy as np
import pytest
from scipy.special import erf

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
