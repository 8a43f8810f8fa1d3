"""Zero-crossing edge points and corner rejection (paper section 3.2)."""

import re

import numpy as np
import pytest
from scipy.special import erf

from nfdepth.edges import _block_read_back, block_structure_tensor, corner_ratio, laplacian_zero_crossings, rounding_gradient_floor, select_edge_points
from nfdepth.normal_flow import gaussian_smooth, normal_flow


def blurred_square(shape=(60, 60), lo=20.5, hi=40.5, s0=0.7):
    r, c = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    def step(d):
        return 0.5 * (1 + erf(d / (np.sqrt(2) * s0)))
    inside = step(r - lo) * step(hi - r) * step(c - lo) * step(hi - c)
    return 50.0 + 150.0 * inside


def test_zero_crossings_of_a_straight_edge_lie_on_it():
    c = np.arange(40, dtype=float)
    img = np.tile(100 * erf((c - 19.3) / 2.0), (10, 1))
    zc = laplacian_zero_crossings(img)
    cols = np.nonzero(zc[5])[0] + 0.5  # cell centres
    assert cols.size == 1
    assert abs(cols[0] - 19.3) <= 0.5  # the crossing lies inside the cell


def test_corner_ratio_zero_on_edge_high_at_corner():
    img = gaussian_smooth(blurred_square().astype(np.float32), sigma_px=1.5)
    g = normal_flow([img, img, img], sigma_px=0)
    ratio = corner_ratio(g.grad_col, g.grad_row, window_sigma_px=2.0)
    assert ratio[30, 20] < 0.01  # middle of the left side (cell centre 30.5, 20.5)
    assert ratio[20, 20] > 0.2  # the corner: two directions in the window (measured 0.26)
    # no gradient at all in the window: no direction, NaN (not 0, which would pass as an edge)
    flat = np.zeros_like(g.grad_col)
    assert np.isnan(corner_ratio(flat, flat, window_sigma_px=2.0)).all()


def test_select_edge_points_rejects_corners_keeps_sides():
    img = blurred_square().astype(np.float32)
    s = gaussian_smooth(img, sigma_px=1.5)
    g = normal_flow([img, img, img], sigma_px=1.5)
    sel = select_edge_points(g, s, max_corner_ratio=0.1, corner_window_px=1.5)
    rows, cols = np.nonzero(sel.mask)
    assert rows.size > 40
    # every accepted point lies on a side of the square, away from the corners
    on_side = (np.abs(rows + 0.5 - 20.5) <= 1) | (np.abs(rows + 0.5 - 40.5) <= 1) | (np.abs(cols + 0.5 - 20.5) <= 1) | (np.abs(cols + 0.5 - 40.5) <= 1)
    assert on_side.all()
    corner_dist = np.min(
        [np.hypot(rows + 0.5 - a, cols + 0.5 - b) for a in (20.5, 40.5) for b in (20.5, 40.5)], axis=0
    )
    assert corner_dist.min() > 2.0
    assert np.any(sel.corner)


def test_min_gradient_threshold_and_validation():
    img = blurred_square().astype(np.float32)
    s = gaussian_smooth(img, sigma_px=1.5)
    g = normal_flow([img, img, img], sigma_px=1.5)
    sel = select_edge_points(g, s, min_gradient=1e6)
    assert not sel.mask.any()
    with pytest.raises(ValueError, match="max_corner_ratio must be within"):
        select_edge_points(g, s, max_corner_ratio=2)
    with pytest.raises(ValueError, match="smoothed_middle must have shape"):
        select_edge_points(g, s[:-1])
    with pytest.raises(ValueError, match="min_gradient must be a finite number >= 0"):
        select_edge_points(g, s, min_gradient=-1)


def test_block_structure_tensor_of_a_ramp_is_exact():
    # Constant gradient (gc, gr) = (2, -3): every window averages the same outer product.
    h, w = 17, 24  # odd rows: the last block row replicates the last cell row
    gc, gr = np.full((h, w), 2.0), np.full((h, w), -3.0)
    t = block_structure_tensor(gc, gr, window_sigma_px=2.0)
    assert t.shape == (3, 9, 12)
    np.testing.assert_allclose(t[0], 4.0, rtol=1e-12)
    np.testing.assert_allclose(t[1], 9.0, rtol=1e-12)
    np.testing.assert_allclose(t[2], -6.0, rtol=1e-12)
    # one gradient direction everywhere: a straight edge, ratio 0
    np.testing.assert_allclose(corner_ratio(gc, gr, window_sigma_px=2.0), 0.0, atol=1e-12)


def test_block_read_back_is_bilinear_at_cell_positions():
    # A field linear in the block index reads back linear in the cell position
    # (y - 0.5) / 2 away from the clamped first and last cell.
    for n in (9, 10):
        blocks = (n + 1) // 2
        lo, hi, w_lo, w_hi = _block_read_back(n, blocks)
        values = w_lo * np.arange(blocks)[lo] + w_hi * np.arange(blocks)[hi]
        y = np.arange(n)
        inner = (y > 0) & (y < 2 * blocks - 2)
        np.testing.assert_allclose(values[inner], (y[inner] - 0.5) / 2.0, rtol=0, atol=1e-15)
        np.testing.assert_allclose(w_lo + w_hi, 1.0)


def _full_grid_ratio(gc, gr, sigma):
    """The textbook structure tensor: a full-grid Gaussian window of ``sigma`` px."""
    import cv2

    radius = int(np.ceil(3 * sigma))
    ks = (2 * radius + 1, 2 * radius + 1)
    jxx, jyy, jxy = (cv2.GaussianBlur(a * b, ks, sigma, borderType=cv2.BORDER_REFLECT) for a, b in ((gc, gc), (gr, gr), (gc, gr)))
    half = 0.5 * (jxx + jyy)
    root = np.sqrt(0.25 * (jxx - jyy) ** 2 + jxy**2)
    return np.maximum(half - root, 0) / (half + root)


@pytest.mark.parametrize(("window", "p90_max", "flip_max"), [(1.0, 0.02, 0.025), (1.5, 0.02, 0.035), (2.0, 0.008, 0.012), (3.0, 0.005, 0.006)])
def test_corner_ratio_matches_a_full_grid_window(window, p90_max, flip_max):
    # Variance matching (block mean + bilinear read-back + block Gaussian)
    # makes the block-grid window a close stand-in for the full-grid one. At
    # the strong zero crossings of a textured scene (smooth blobs: edges of
    # every curvature), measured: 90th percentile of |ratio difference|
    # 0.014 / 0.012 / 0.005 / 0.003 and corner decisions (at 0.1) flipped
    # for 1.7 / 2.3 / 0.8 / 0.3 % of points at windows 1 / 1.5 / 2 / 3 px;
    # the bounds leave ~1.5x room. Small windows differ more: there the
    # read-back's tent, not the Gaussian, shapes the window.
    rng = np.random.default_rng(5)
    import cv2

    small = rng.random((26, 34))
    img = np.where(cv2.resize(small, (272, 208), interpolation=cv2.INTER_CUBIC) > 0.5, 200.0, 60.0).astype(np.float32)
    s = gaussian_smooth(img, sigma_px=2.0)
    g = normal_flow([s, s, s], sigma_px=0)
    sel = select_edge_points(g, s, max_corner_ratio=1.0, corner_window_px=window)
    pts = sel.mask
    assert pts.sum() > 2000
    new = corner_ratio(g.grad_col, g.grad_row, window_sigma_px=window)[pts]
    old = _full_grid_ratio(g.grad_col.astype(np.float64), g.grad_row.astype(np.float64), window)[pts]
    diff = np.abs(new - old)
    assert np.percentile(diff, 90) < p90_max
    assert np.median(diff) < 0.003
    assert abs(np.mean(new - old)) < 0.005  # no bias toward either decision
    assert np.mean((new <= 0.1) != (old <= 0.1)) < flip_max


def test_corner_ratio_reads_the_block_tensor_back_bilinearly():
    # corner_ratio's read-back (cv2.resize) uses exactly the weights that the
    # fast path applies at its candidates (_block_read_back), odd and even sizes.
    from nfdepth.edges import _read_back

    rng = np.random.default_rng(2)
    for h, w in ((9, 12), (10, 13), (1, 1), (2, 5)):
        tensor = rng.random((3, (h + 1) // 2, (w + 1) // 2))
        r0, r1, wr0, wr1 = _block_read_back(h, tensor.shape[1])
        c0, c1, wc0, wc1 = _block_read_back(w, tensor.shape[2])
        rows = wr0[:, None] * tensor[:, r0, :] + wr1[:, None] * tensor[:, r1, :]
        expected = wc0 * rows[:, :, c0] + wc1 * rows[:, :, c1]
        np.testing.assert_allclose(_read_back(tensor, (h, w)), expected, rtol=1e-14, atol=0)


@pytest.mark.parametrize("shape", [(50, 60), (37, 91)])
def test_a_flat_image_has_no_edge_points(shape):
    """Smoothing a constant 7 leaves float32 ripples (|grad I| up to 4e-7 here); a threshold
    relative to the image's own gradients accepted 32 of them as edge points."""
    frames = [np.full(shape, 7.0, np.float32)] * 3
    g = normal_flow(frames, sigma_px=2.0)
    sel = select_edge_points(g, gaussian_smooth(frames[1], sigma_px=2.0))
    assert not sel.strong.any() and not sel.mask.any()


def test_the_rounding_floor_keeps_faint_real_edges():
    """A step of 0.01 grey levels on an intensity of 200 (5e-5 of it) is still an edge."""
    img = np.full((40, 40), 200.0, np.float32)
    img[:, 20:] += 0.01
    g = normal_flow([img] * 3, sigma_px=1.0)
    sel = select_edge_points(g, gaussian_smooth(img, sigma_px=1.0))
    assert sel.mask[:, 19].sum() >= 30
    assert rounding_gradient_floor(gaussian_smooth(img, sigma_px=1.0)) == pytest.approx(2.0001e-4, rel=1e-4)


def test_zero_crossings_of_integer_and_bool_images_are_those_of_floats():
    """A step from 10 to 200 between columns 19 and 20: the Laplacian is +190 / -190 there,
    so exactly the cells of column 19 cross zero, whatever the image's dtype (OpenCV's
    Laplacian of a uint8 image would clip the negative half to 0 and find none)."""
    img = np.tile(np.repeat([10, 200], 20), (10, 1))
    expected = np.zeros((9, 39), bool)
    expected[:, 19] = True
    for dtype in (np.uint8, np.uint16, np.int32, np.int64, np.float32, np.float64):
        np.testing.assert_array_equal(laplacian_zero_crossings(img.astype(dtype)), expected, err_msg=str(dtype))
    np.testing.assert_array_equal(laplacian_zero_crossings(img > 100), expected)


def test_zero_crossings_and_structure_tensor_refuse_bad_arrays():
    for bad, what in ((np.zeros(5), "dtype float64, shape (5,)"), (np.zeros((1, 5)), "dtype float64, shape (1, 5)"),
                      (np.zeros((4, 4), complex), "dtype complex128, shape (4, 4)"), (np.full((4, 4), "a"), "dtype <U1, shape (4, 4)")):
        with pytest.raises(ValueError, match=rf"^smoothed must be a real 2-D image of at least 2x2 pixels, got {re.escape(what)}$"):
            laplacian_zero_crossings(bad)
    for a, b in (((3, 4), (4, 3)), ((0, 4), (0, 4)), ((3,), (3,))):
        with pytest.raises(ValueError, match=rf"^grad_col and grad_row must be non-empty 2-D arrays of one shape, got {re.escape(str(a))} and {re.escape(str(b))}$"):
            block_structure_tensor(np.zeros(a), np.zeros(b), window_sigma_px=2.0)


@pytest.mark.parametrize("use_numba", [True, False])
def test_a_linear_ramp_has_no_edge_points_inside(monkeypatch, use_numba):
    """A noise-free linear ramp's Laplacian is float32 rounding; its random signs gave zero crossings (916 'edge
    points' on a 48 x 48 ramp, moving or not). A crossing now needs one corner beyond ROUNDING_LAPLACIAN times the
    largest intensity. Only the reflected border, a real kink of the smoothed image, keeps crossings."""
    from nfdepth import fast

    if use_numba and not fast.USE_NUMBA:
        pytest.skip("numba not installed")
    monkeypatch.setattr(fast, "USE_NUMBA", use_numba)
    fast._local.ws = None
    r, c = np.mgrid[0:48, 0:48].astype(np.float32)
    ramp = [2 * (c - 0.3 * t) + 3 * (r - 0.1 * t) + 100 for t in (-1, 0, 1)]
    sigma = 2.0
    inside = np.zeros((47, 47), bool)
    inside[9:-9, 9:-9] = True  # beyond the smoothing's reach (4 sigma) of the reflected border
    smoothed = gaussian_smooth(ramp[1], sigma_px=sigma)
    assert not laplacian_zero_crossings(smoothed)[inside].any()
    reference = select_edge_points(normal_flow(ramp, sigma_px=sigma), smoothed, corner_window_px=sigma).mask
    got = fast.normal_flow_edges(ramp, sigma_px=sigma).mask
    assert not reference[inside].any() and not got[inside].any()
    np.testing.assert_array_equal(got, reference)
    # a real edge of the faintest contrast the strong test keeps is still found
    step = [100 + 0.5 * np.tanh((c - 24.3 + 0.3 * t) / 1.5) for t in (-1, 0, 1)]
    assert fast.normal_flow_edges(step, sigma_px=sigma).mask[:, 23:26].any()


def _dots_and_a_border_edge(t, dots=True, size=48):
    """Small discs (corners everywhere along their rims) inside, a straight edge 2.5 px from the left border."""
    r, c = np.mgrid[0:size, 0:size].astype(float)
    x = c - 0.3 * t
    discs = sum(((x - cx) ** 2 + (r - cy) ** 2 < 2.2**2) for cx in range(12, size - 8, 8) for cy in range(12, size - 8, 8))
    return 100.0 * discs * dots + 60.0 * (x < 2.5)


def test_no_edge_points_warning_judges_the_corner_rule_inside_the_border():
    """Inside the border every strong zero crossing is a corner; the only straight edge lies in the border band.
    The warning blamed the border ("lower sigma_px") although only raising max_corner_ratio keeps points; it
    names the corner rule now, and still the border where nothing strong lies inside."""
    from nfdepth.edges import _no_edge_points_warning

    frames = [_dots_and_a_border_edge(t) for t in (-1, 0, 1)]
    sel = select_edge_points(normal_flow(frames, sigma_px=1.5), gaussian_smooth(np.float32(frames[1]), sigma_px=1.5), border_px=4)
    inside = np.zeros_like(sel.mask)
    inside[4:-4, 4:-4] = True
    strong = sel.zero_crossing & sel.strong
    assert not sel.mask.any() and sel.border_px == 4
    assert (strong & inside).sum() > 100 and (strong & inside & ~sel.corner).sum() == 0  # inside: corners only
    assert (strong & ~inside & ~sel.corner).sum() > 10  # the straight edge, in the border band
    w = _no_edge_points_warning(sel)
    assert (w.rule, w.hint) == ("corner", "(raise max_corner_ratio to keep some)")
    n = int((strong & inside).sum())
    assert str(w) == f"no edge points: all {n} strong zero crossings away from the border are corners (raise max_corner_ratio to keep some)"
    assert select_edge_points(normal_flow(frames, sigma_px=1.5), gaussian_smooth(np.float32(frames[1]), sigma_px=1.5), border_px=4, max_corner_ratio=1.0).mask.any()
    # the edge alone: nothing strong inside, the border is to blame
    frames = [_dots_and_a_border_edge(t, dots=False) for t in (-1, 0, 1)]
    sel = select_edge_points(normal_flow(frames, sigma_px=1.5), gaussian_smooth(np.float32(frames[1]), sigma_px=1.5), border_px=4)
    w = _no_edge_points_warning(sel)
    assert (w.rule, w.hint) == ("border", "") and str(w).endswith("strong zero crossings all lie within border_px of the border")


def test_no_edge_points_warning_of_a_pipeline_names_the_corner_rule():
    """The same through static_stereo_edges (border 2.5 sigma_px = 4 px): the hint was "lower sigma_px"."""
    import nfdepth

    views = [_dots_and_a_border_edge(-k * 4 / 3, size=64) for k in (-1, 0, 1)]
    cam = nfdepth.PinholeCamera(focal_px=100, width_px=64, height_px=64)
    with pytest.warns(nfdepth.NoEdgePointsWarning) as said:
        nfdepth.static_stereo_edges(views, camera=cam, baseline=0.1, sigma_px=1.5)
    (w,) = said.list
    assert (w.message.rule, w.message.hint) == ("corner", "(raise max_corner_ratio to keep some)")
    assert re.fullmatch(r"all \d+ strong zero crossings in the reference image of shape \(64, 64\) away from the border are corners", w.message.reason)


def _field_and_middle(shape=(10, 12)):
    rng = np.random.default_rng(0)
    frames = [rng.random(shape).astype(np.float32) * 100 for _ in range(3)]
    return normal_flow(frames, sigma_px=1.0), gaussian_smooth(frames[1], sigma_px=1.0)


def test_select_edge_points_refuses_non_finite_gradients_and_intensities():
    """One NaN gradient made the percentile threshold NaN and every cell weak: 0 edge points, silently (one NaN
    pixel of smoothed_middle: no zero crossing at all). NaN in grad_t, which the rules do not read, is accepted."""
    from nfdepth.normal_flow import GradientField

    g, middle = _field_and_middle()
    clean = select_edge_points(g, middle, min_gradient=0.0, max_corner_ratio=1.0, border_px=0)
    assert clean.mask.any()
    for name, value, count in (("grad_col", np.nan, 1), ("grad_row", np.inf, 1), ("grad_row", -np.inf, 2)):
        arrays = {k: getattr(g, k).copy() for k in ("grad_col", "grad_row", "grad_t")}
        arrays[name].flat[:count] = value
        with pytest.raises(ValueError, match=rf"^field\.{name} contains {count} non-finite \(NaN or inf\) value\(s\); expected finite gradients$"):
            select_edge_points(GradientField(**arrays), middle)
    bad = middle.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match=r"^smoothed_middle contains 1 non-finite \(NaN or inf\) value\(s\); expected finite intensities$"):
        select_edge_points(g, bad)
    grad_t = g.grad_t.copy()
    grad_t[3, 3] = np.nan
    same = select_edge_points(GradientField(g.grad_col, g.grad_row, grad_t), middle, min_gradient=0.0, max_corner_ratio=1.0, border_px=0)
    np.testing.assert_array_equal(same.mask, clean.mask)


def test_select_edge_points_refuses_a_malformed_field():
    """A field of mismatched, 1-D, empty or complex gradients gave NumPy's errors from deep inside (a broadcast
    error, IndexError, "ufunc 'hypot' not supported"); each is told with the attribute's name."""
    from nfdepth.normal_flow import GradientField

    g, middle = _field_and_middle()
    gc, gr, gt = g.grad_col, g.grad_row, g.grad_t
    cases = [
        (GradientField(gc, gr[:-1], gt), ValueError, r"field's gradients must share one cell grid \(one shape\), got grad_col \(9, 11\), grad_row \(8, 11\), grad_t \(9, 11\)"),
        (GradientField(gc, gr, gt[:, :-1]), ValueError, r"field's gradients must share one cell grid \(one shape\), got grad_col \(9, 11\), grad_row \(9, 11\), grad_t \(9, 10\)"),
        (GradientField(gc[0], gr[0], gt[0]), ValueError, r"field\.grad_col must be a non-empty 2-D array on the cell grid \(rows - 1, cols - 1\), got shape \(11,\)"),
        (GradientField(gc, gr[:0], gt), ValueError, r"field\.grad_row must be a non-empty 2-D array on the cell grid \(rows - 1, cols - 1\), got shape \(0, 11\)"),
        (GradientField(gc.astype(np.complex64), gr, gt), TypeError, r"field\.grad_col must be real numbers, got dtype complex64"),
        (GradientField(gc, gr, np.full(gt.shape, "a")), TypeError, r"field\.grad_t must be real numbers, got dtype <U1"),
    ]
    for field, error, message in cases:
        with pytest.raises(error, match=rf"^{message}$"):
            select_edge_points(field, middle)
    with pytest.raises(TypeError, match=r"^field must be a nfdepth.GradientField \(from normal_flow\), got tuple$"):
        select_edge_points((gc, gr, gt), middle)
    # lists of numbers are arrays too
    listed = select_edge_points(GradientField(gc.tolist(), gr.tolist(), gt.tolist()), middle)
    np.testing.assert_array_equal(listed.mask, select_edge_points(g, middle).mask)


def test_zero_crossings_of_big_endian_floats_are_those_of_native_ones():
    """A big-endian float image is worked on in its own precision, as the native one: a '>f4' image went to
    float64, whose Laplacian gives other signs than float32's at the corners near zero of a bump on a ramp
    (168 zero crossings instead of 171 here)."""
    r, c = np.mgrid[0:40, 0:50].astype(np.float64)
    img = 1000.0 + 3.7 * c + 1.3 * r + 20.0 * np.exp(-((c - 25) ** 2 + (r - 20) ** 2) / 30.0)
    for kind in ("f4", "f8"):
        native = img.astype(kind)
        np.testing.assert_array_equal(laplacian_zero_crossings(native.astype(">" + kind)), laplacian_zero_crossings(native))
