"""Options of nfdepth.evaluate, nfdepth.baselines and ``nfdepth evaluate`` at and beyond their bounds (found by fuzzing)."""

import math
import re
import types

import cv2
import numpy as np
import pytest
from test_evaluate import _real_root, _step_truth, _synthetic_scene, needs_cli, run_cli

from nfdepth import _cli_evaluate, baselines, evaluate
from nfdepth.evaluate import (
    depth_step_mask,
    error_map_png,
    photometric_truth_offset,
    rounding_median_rel,
    view_size_problems,
)


class _CLIError(Exception):
    def __init__(self, msg, code):
        super().__init__(msg)
        self.code = code


def _noise(shape=(40, 80), seed=0):
    return np.random.default_rng(seed).integers(0, 255, shape).astype(np.uint8)


# ------------------------------------------------------------------ --downsample


def _largest_by_full_scan(factor, shape, methods):
    """The largest usable factor below ``factor`` as the scan over every smaller factor finds it."""
    h, w = shape
    return next((k for k in range(factor - 1, 0, -1) if not view_size_problems((h // k, w // k), methods)), None)


def test_downsample_far_beyond_the_views_is_refused_at_once(monkeypatch):
    """``--downsample 1000000000`` scanned every smaller factor (a billion calls: a hang); now at most one per px of the longer side."""
    calls = []
    real = _cli_evaluate.view_size_problems

    def counted(shape, methods):
        calls.append(shape)
        return real(shape, methods)

    monkeypatch.setattr(_cli_evaluate, "view_size_problems", counted)
    scene = types.SimpleNamespace(name="tsukuba", shape=(288, 384))
    with pytest.raises(_CLIError, match=r"^--downsample 100000 is too large for tsukuba \(384x288 px\): expected an integer from 1 to 20 "
                                        r"\(sgbm needs views of at least 8x8 px, more than 18 px wide\)$") as info:
        _cli_evaluate._check_downsample(100_000, scene, _CLIError, ("sgbm",))
    assert info.value.code == 2
    assert len(calls) <= 384 + 2
    calls.clear()
    with pytest.raises(_CLIError, match=r"^--downsample 1000000000 is too large .* expected an integer from 1 to 20 "):
        _cli_evaluate._check_downsample(10**9, scene, _CLIError, ("sgbm",))
    assert len(calls) <= 384 + 2


@pytest.mark.parametrize("shape", [(288, 384), (375, 450), (20, 30), (12, 3), (1, 1)])
@pytest.mark.parametrize("methods", [("nfdepth",), ("sgbm",), ("nfdepth", "sgbm", "waxman_sinha"), ("bm", "waxman_sinha_farneback")])
def test_downsample_names_the_same_largest_factor_as_the_full_scan(shape, methods):
    h, w = shape
    scene = types.SimpleNamespace(name="s", shape=shape)
    beyond = _largest_by_full_scan(2 * max(shape) + 2, shape, methods)  # every factor above the longer side leaves 0 x 0 px
    longer = max(shape)
    for factor in sorted({*range(2, 60), *range(longer - 2, longer + 4), 2 * longer + 2, 10**6, 10**12} - {0, 1}):
        if not view_size_problems((h // factor, w // factor), methods):
            _cli_evaluate._check_downsample(factor, scene, _CLIError, methods)  # fits: no error
            continue
        largest = _largest_by_full_scan(factor, shape, methods) if factor < 10**6 else beyond
        expected = f"an integer from 1 to {largest}" if largest else "1 (no downsampling"
        with pytest.raises(_CLIError, match=r"expected ") as info:
            _cli_evaluate._check_downsample(factor, scene, _CLIError, methods)
        assert f"expected {expected}" in str(info.value)


@pytest.mark.data
@needs_cli
def test_cli_downsample_of_a_billion_is_one_line_at_once(capsys):
    root = _real_root()
    code, out, err = run_cli(capsys, "evaluate", "tsukuba", "--data", str(root), "--methods", "sgbm", "--downsample", "1000000000")
    assert code == 2 and out == ""
    assert err == (
        "nfdepth: error: --downsample 1000000000 is too large for tsukuba (384x288 px): expected an integer from 1 to 20 "
        "(sgbm needs views of at least 8x8 px, more than 18 px wide)\n"
    )


# ------------------------------------------------------------------ depth_step_mask


def _mask_with_the_full_square(truth, gap_px=2.0, width_px=9):
    """depth_step_mask as it was: the whole width_px x width_px square, however large."""
    tru = np.asarray(truth, dtype=np.float64)
    step = np.zeros(tru.shape, np.uint8)
    with np.errstate(invalid="ignore"):
        across_cols = np.abs(np.diff(tru, axis=1)) > gap_px
        across_rows = np.abs(np.diff(tru, axis=0)) > gap_px
    step[:, 1:] |= across_cols
    step[:, :-1] |= across_cols
    step[1:, :] |= across_rows
    step[:-1, :] |= across_rows
    return cv2.dilate(step, np.ones((width_px, width_px), np.uint8), borderType=cv2.BORDER_CONSTANT, borderValue=0) > 0


@pytest.mark.parametrize("shape", [(7, 12), (12, 5), (1, 9), (9, 1), (1, 1), (6, 6)])
def test_depth_step_mask_is_the_full_squares_for_every_width(shape):
    """The kernel is clipped to 2 n - 1 per axis: the mask is identical to the full square's, at every odd width."""
    rng = np.random.default_rng(shape[0] * 100 + shape[1])
    for _ in range(5):
        truth = rng.choice([1.0, 2.0, 9.0, np.nan], size=shape, p=[0.4, 0.3, 0.2, 0.1])
        for width in range(1, 4 * max(shape) + 4, 2):
            np.testing.assert_array_equal(depth_step_mask(truth, width_px=width), _mask_with_the_full_square(truth, width_px=width))


def test_depth_step_mask_takes_any_width_without_a_huge_kernel(monkeypatch):
    """width_px = 10**6 + 1 was a 10**12-byte kernel (MemoryError), 100001 took 30 s and 10 GB: a wide square marks every pixel."""
    kernels = []
    dilate = cv2.dilate

    def recorded(src, kernel, *args, **kwargs):
        kernels.append(kernel.shape)
        return dilate(src, kernel, *args, **kwargs)

    monkeypatch.setattr(cv2, "dilate", recorded)
    truth = _step_truth()
    for width in (79, 10**5 + 1, 10**6 + 1, 2**53 - 1):
        assert depth_step_mask(truth, width_px=width).all()
        assert not depth_step_mask(np.full((30, 40), 5.0), width_px=width).any()
    h, w = truth.shape
    assert kernels and all(kr <= max(2 * h - 1, 2 * 30 - 1) and kc <= max(2 * w - 1, 2 * 40 - 1) for kr, kc in kernels)
    # just below the whole image: the corners of a 1-px step in the last column stay unmarked
    corner = np.zeros((30, 40))
    corner[0, 39] = 10.0
    near = depth_step_mask(corner, width_px=2 * 38 - 1)
    assert not near[29, 0] and near[29, 1] and near.sum() == 30 * 39


# ------------------------------------------------------------------ photometric_truth_offset


@pytest.mark.parametrize("bad", [1e-300, 0.005, 0.0099, 10.01, 1e3, 1e7, 1e30])
def test_photometric_truth_offset_search_px_out_of_range(bad):
    """1e-300 and 0.005 gave a one-point grid (IndexError), 1e30 NumPy's 'Maximum allowed size exceeded', 1e3 took 9 s, 1e7 hung."""
    with pytest.raises(ValueError, match=rf"^search_px = {re.escape(f'{bad:g}')} px is outside 0\.01\.\.10 px: the offset is searched on a 0\.02 px grid"):
        photometric_truth_offset(_synthetic_scene(), 1, search_px=bad)


def test_photometric_truth_offset_search_px_bounds_are_taken():
    scene = _synthetic_scene()
    default = photometric_truth_offset(scene, 1)
    for search_px in (0.01, 10):
        res = photometric_truth_offset(scene, 1, search_px=search_px)
        assert res["points"] == default["points"] and res["error_at_zero"] == default["error_at_zero"]
        assert abs(res["offset_px"]) < 0.02  # the views are integer shifts of each other: no offset
    assert photometric_truth_offset(scene, 1, search_px=10)["offset_px"] == default["offset_px"]


@pytest.mark.parametrize("name", ["min_gradient", "max_truth_range_px"])
def test_photometric_truth_offset_thresholds(name):
    """-1 was taken, NaN / inf read 'only 0 smooth, textured pixels', 1e300 overflowed a float32 cast."""
    scene = _synthetic_scene()
    for bad in (-1, -1e-9, float("nan"), float("inf"), float("-inf")):
        with pytest.raises(ValueError, match=rf"^{name} must be a finite number >= 0, got {bad!r}$"):
            photometric_truth_offset(scene, 1, **{name: bad})
    for bad in (1e300, 2e30):
        with pytest.raises(ValueError, match=rf"^{name} = {re.escape(f'{bad:g}')} is beyond the float32 maps it applies to: expected at most 1e\+30$"):
            photometric_truth_offset(scene, 1, **{name: bad})
    with pytest.raises(TypeError, match=rf"^{name} must be a finite number >= 0, got '2' \(str, not a number\)$"):
        photometric_truth_offset(scene, 1, **{name: "2"})
    # the bounds themselves: 0 and 1e30
    default = photometric_truth_offset(scene, 1)
    if name == "max_truth_range_px":  # the truth is one constant: its range is 0 everywhere, as large a one changes nothing
        for ok in (0, 0.0, 1e30):
            assert photometric_truth_offset(scene, 1, max_truth_range_px=ok) == default
    else:
        assert photometric_truth_offset(scene, 1, min_gradient=0)["points"] > default["points"]
        with pytest.raises(ValueError, match="^only 0 smooth, textured pixels"):
            photometric_truth_offset(scene, 1, min_gradient=1e30)


# ------------------------------------------------------------------ rounding_median_rel, error_map_png


def test_rounding_median_rel_step_px():
    """inf warned and gave NaN, -1 a negative figure, NaN a NaN: refused; 0 gives 0 as documented."""
    assert rounding_median_rel([4.0], 1.0) == 1 / 16  # a quarter step over the disparity
    assert rounding_median_rel([4.0, 8.0], 0) == 0.0
    assert math.isnan(rounding_median_rel([0.0, np.nan], 1.0))
    assert rounding_median_rel([4.0], 1e30) == pytest.approx(1e30 / 16, rel=1e-15)  # a huge step is still a number
    for bad in (float("inf"), -1, -0.5, float("nan"), float("-inf")):
        with pytest.raises(ValueError, match=rf"^step_px must be a finite number >= 0, got {bad!r}$"):
            rounding_median_rel([4.0, 8.0], bad)
    with pytest.raises(ValueError, match="^step_px must be a finite number >= 0, got -1$"):
        rounding_median_rel([], -1)  # refused before the empty truth's NaN
    for bad in ("1", True, None):
        with pytest.raises(TypeError, match="^step_px must be a finite number >= 0, got "):
            rounding_median_rel([4.0], bad)


def test_error_map_png_vmax(tmp_path):
    """0, -1, NaN and inf wrote a PNG with a broken colour scale."""
    truth = np.full((6, 8), 3.0)
    est = truth + 0.5
    for bad in (0, -1, float("nan"), float("inf")):
        out = tmp_path / f"e{bad}.png"
        with pytest.raises(ValueError, match=rf"^vmax must be a positive finite number, got {bad!r}$"):
            error_map_png(out, est, truth, vmax=bad)
        assert not out.exists()
    with pytest.raises(TypeError, match=r"^vmax must be a positive finite number, got '3' \(str, not a number\)$"):
        error_map_png(tmp_path / "s.png", est, truth, vmax="3")
    assert error_map_png(tmp_path / "ok.png", est, truth, vmax=0.25).stat().st_size > 0


# ------------------------------------------------------------------ baselines: positions


@pytest.mark.parametrize("fn", [baselines.pair_disparity_at_reference, baselines.waxman_sinha_disparity])
def test_baseline_positions_out_of_unit_range(fn):
    """[0, v, 2v]: 1e300 overflowed a cast, 1e-300 divided by zero, inf warned 'invalid value in subtract' (pair)."""
    views = [_noise(seed=k) for k in range(3)]
    for v in (1e300, 1e-300, 1e31, 1e-31):
        with pytest.raises(ValueError, match=rf"^positions must keep the views 1e-30 to 1e\+30 units from the reference .* got {re.escape(str([0.0, v, 2 * v]))}"):
            fn(views, reference=1, positions=[0, v, 2 * v])
    for v in (float("inf"), float("nan")):
        with pytest.raises(ValueError, match=rf"^positions must be 3 strictly increasing finite numbers, got {re.escape(str([0, v, 2 * v]))}$"):
            fn(views, reference=1, positions=[0, v, 2 * v])
    # the reference's distance counts, not the positions': far from 0 is fine when the views are close to each other
    assert np.isfinite(fn(views, reference=1, positions=[1e35, 1e35 + 1e20, 1e35 + 2e20]).disparity).any()


def test_pair_positions_at_the_unit_bounds_scale_exactly():
    views = [np.roll(_noise((40, 120)), -4 * (k - 1), axis=1) for k in range(3)]
    raw = baselines.sgbm_disparity(views[1], views[2], num_disparities=16)
    for unit in (1e-30, 1e30):
        r = baselines.pair_disparity_at_reference(views, reference=1, positions=[0, unit, 2 * unit], num_disparities=16)
        np.testing.assert_array_equal(r.disparity, raw / np.float32(unit))
        assert np.isfinite(r.disparity).any()


def test_waxman_sinha_positions_at_the_unit_bounds():
    views = [np.roll(_noise((40, 120)), -2 * (k - 1), axis=1).astype(np.float32) for k in range(3)]
    steps = baselines.waxman_sinha_disparity(views, reference=1).disparity
    for unit in (1e-30, 1e30):
        d = baselines.waxman_sinha_disparity(views, reference=1, positions=[0, unit, 2 * unit]).disparity
        assert np.isfinite(d).all()
        np.testing.assert_allclose(d * unit, steps, rtol=1e-5, atol=1e-5)


# ------------------------------------------------------------------ baselines: max_disparity, default_num_disparities


@pytest.mark.parametrize("fn", [baselines.sgbm_disparity, baselines.stereo_bm_disparity])
def test_max_disparity_is_checked(fn):
    """NaN, inf, -1 and 0 fell back silently; 1e30 and 10**9 were capped to 64 on 80 px (StereoBM: an all-NaN map)."""
    a, b = _noise(seed=1), _noise(seed=2)
    for bad in (float("nan"), float("inf"), -1, 0, 0.0, float("-inf")):
        with pytest.raises(ValueError, match=rf"^max_disparity must be a positive finite number, got {bad!r}$"):
            fn(a, b, max_disparity=bad)
    for bad, shown in ((1e30, "1e+30"), (10**9, "1e+09"), (80, "80"), (80.5, "80.5")):
        with pytest.raises(ValueError, match=rf"^the images are 80 px wide: max_disparity = {re.escape(shown)} px is beyond them .*below 80"):
            fn(a, b, max_disparity=bad)
    for bad in ("20", True):
        with pytest.raises(TypeError, match="^max_disparity must be a positive finite number, got "):
            fn(a, b, max_disparity=bad)
    # below the width: as before, numDisparities covers it (capped 16 columns short of the width)
    for ok, nd in ((79.99, 64), (50, 64), (20, 32), (1e-9, 16), (12.7, 16)):
        np.testing.assert_array_equal(fn(a, b, max_disparity=ok), fn(a, b, num_disparities=nd))


def test_pair_max_disparity_is_checked_before_scaling():
    views = [_noise(seed=k) for k in range(3)]
    with pytest.raises(ValueError, match=r"^max_disparity = 1e\+300 is beyond the float32 maps it applies to: expected at most 1e\+30$"):
        baselines.pair_disparity_at_reference(views, reference=1, max_disparity=1e300)
    with pytest.raises(ValueError, match="^max_disparity must be a positive finite number, got -1$"):
        baselines.pair_disparity_at_reference(views, reference=1, max_disparity=-1)
    with pytest.raises(TypeError, match=r"^max_disparity must be a positive finite number, got 'x' \(str, not a number\)$"):
        baselines.pair_disparity_at_reference(views, reference=1, max_disparity="x")
    # scaled by the spacing: 39 px per step is 78 px for a pair 2 steps apart
    r = baselines.pair_disparity_at_reference(views, reference=1, positions=[0, 2, 4], max_disparity=39)
    raw = baselines.sgbm_disparity(views[1], views[2], max_disparity=78)
    np.testing.assert_array_equal(r.disparity, raw / np.float32(2))


def test_default_num_disparities_width():
    """0 and -1 gave 16."""
    for bad in (0, -1, -(2**40)):
        with pytest.raises(ValueError, match=rf"^width must be an integer >= 1, got {bad}$"):
            baselines.default_num_disparities(bad)
    for bad in (80.0, True, "80"):
        with pytest.raises(TypeError, match="^width must be an integer >= 1, got "):
            baselines.default_num_disparities(bad)
    assert baselines.default_num_disparities(1) == 16
    assert baselines.default_num_disparities(np.int64(384)) == 48
    assert baselines.default_num_disparities(384, 14) == 32
    assert baselines.default_num_disparities(80, 79.5) == 64
    assert baselines.default_num_disparities(1000, float("nan")) == 128  # no maximum: W / 8, as documented


@pytest.mark.parametrize("method", ["sgbm", "bm"])
def test_evaluate_peers_get_the_same_num_disparities_from_any_truth(method):
    """evaluate passes the truth's largest disparity; one the matchers now refuse (<= 0, >= the width, inf) is clipped to what it gave."""
    scene = _synthetic_scene()  # 120 x 200 px

    def pair(**kw):
        return baselines.pair_disparity_at_reference(scene.views, reference=scene.reference_index, method=method, **kw).disparity

    for truth_max, expected in ((-5.0, {"num_disparities": 16}), (0.0, {"num_disparities": 16}), (0.5, {"num_disparities": 16}),
                                (3.0, {"max_disparity": 3.0}), (150.0, {"max_disparity": 150.0}), (199.5, {"num_disparities": 176}),
                                (1000.0, {"num_disparities": 176}), (math.inf, {}), (math.nan, {}), (None, {})):
        np.testing.assert_array_equal(evaluate._run_peer(method, scene, truth_max).disparity, pair(**expected))
