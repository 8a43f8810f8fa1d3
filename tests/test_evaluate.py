"""nfdepth.evaluate, nfdepth.baselines and ``nfdepth evaluate``."""

import dataclasses
import json
import math
import re
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_runner import run_cli
from scipy import ndimage

from nfdepth import baselines
from nfdepth.datasets import DataNotFoundError, MultiViewScene, data_root, list_scenes
from nfdepth.evaluate import (
    GAUSSIAN_MEDIAN_Z,
    depth_step_mask,
    disparity_errors,
    error_map_png,
    evaluate_dataset,
    evaluate_scene,
    evaluation_rows,
    photometric_truth_offset,
    render_markdown,
    resolve_dataset,
    rounding_median_rel,
    select_views,
    to_jsonable,
)


def _cli_has_evaluate():
    from nfdepth.cli import _PLUGIN_COMMANDS

    return "_cli_evaluate" in _PLUGIN_COMMANDS


needs_cli = pytest.mark.skipif(not _cli_has_evaluate(), reason="_cli_evaluate not yet in nfdepth.cli._PLUGIN_COMMANDS")


# ------------------------------------------------------------------ disparity_errors


def test_disparity_errors_exact_values():
    truth = np.array([[10.0, 10.0, 10.0, 10.0], [5.0, 5.0, np.nan, 20.0]])
    est = np.array([[10.0, 11.0, 9.6, np.nan], [5.0, 7.0, 3.0, 20.4]])
    # pairs with both finite: (10,10) (11,10) (9.6,10) (5,5) (7,5) (20.4,20); truth finite at 7 pixels
    e = disparity_errors(est, truth)
    assert e["points"] == 6 and e["truth_points"] == 7
    assert e["density"] == pytest.approx(6 / 7)
    err = np.array([0.0, 1.0, 0.4, 0.0, 2.0, 0.4])
    rel = np.array([0.0, 0.1, 0.04, 0.0, 0.4, 0.02])
    assert e["median_rel"] == pytest.approx(np.median(rel))  # (0.02 + 0.04) / 2
    assert e["median_rel"] == pytest.approx(0.03)
    assert e["p90_rel"] == pytest.approx(np.percentile(rel, 90))
    assert e["bad_1px"] == pytest.approx(1 / 6)  # only the 2 px error; 1.0 is not > 1
    assert e["bad_0_5px"] == pytest.approx(2 / 6)
    assert e["mae_px"] == pytest.approx(err.mean())
    # signed errors 0, +1, -0.4, 0, +2, +0.4: median (0 + 0.4) / 2
    assert e["bias_px"] == pytest.approx(0.2)
    assert math.isnan(e["truth_rounding_rel"])  # no step given
    stepped = disparity_errors(est, truth, truth_step_px=0.5)
    assert stepped["truth_rounding_rel"] == pytest.approx(rounding_median_rel(truth[np.isfinite(est) & np.isfinite(truth)], 0.5))
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="truth_step_px must be a finite number >= 0 or None"):
            disparity_errors(est, truth, truth_step_px=bad)
    with pytest.raises(TypeError, match="truth_step_px must be a finite number >= 0 or None, got 'fine'"):
        disparity_errors(est, truth, truth_step_px="fine")


def test_rms_ratio_reads_a_two_valued_error_bar_that_the_median_reads_low():
    """Errors that are 0 for 90 % of the points and 3 px for the rest (an estimate right, or a whole depth
    step off), with the std their RMS, sqrt(0.1 * 9) px: a calibrated error bar for a user who weights or
    thresholds by it. The median |error| / std reads 0 (half the points are exact); the RMS ratio reads
    exactly 1, and twice the std halves it."""
    truth = np.linspace(5.0, 20.0, 1000).reshape(20, 50)
    est = truth.copy()
    est.flat[::10] += 3.0
    std = np.full(truth.shape, math.sqrt(0.1 * 9.0))
    e = disparity_errors(est, truth, uncertainty=std)
    assert e["median_z"] == 0.0
    assert e["within_3std"] == pytest.approx(0.9)  # the whole-step errors lie at 3 / 0.949 = 3.16 std
    assert e["rms_ratio"] == pytest.approx(1.0, rel=1e-12)
    assert disparity_errors(est, truth, uncertainty=2 * std)["rms_ratio"] == pytest.approx(0.5, rel=1e-12)
    # the truth's rounding enters in quadrature: a step of sqrt(12) px adds 1 px^2 to every std^2
    rounded = disparity_errors(est, truth, uncertainty=std, truth_step_px=math.sqrt(12.0))
    assert rounded["rms_ratio"] == pytest.approx(math.sqrt(0.9 / 1.9), rel=1e-12)


def test_median_z_of_a_calibrated_error_bar_is_a_gaussians():
    """Errors drawn with the std the map reports: median |z| 0.674 and 99.7 % within 3 std (200k points: +-1 %).
    A std half the errors' reads twice that; a truth rounded to a step with an exact estimate and a std of 0
    reads the uniform rounding error over its own std, (step / 4) / (step / sqrt(12)) = 0.866."""
    rng = np.random.default_rng(5)
    truth = rng.uniform(5.0, 20.0, (400, 500))
    std = rng.uniform(0.05, 0.3, truth.shape)
    est = truth + rng.normal(0.0, 1.0, truth.shape) * std
    e = disparity_errors(est, truth, uncertainty=std)
    assert e["median_z"] == pytest.approx(GAUSSIAN_MEDIAN_Z, rel=0.01)
    assert e["rms_ratio"] == pytest.approx(1.0, rel=0.01)
    assert e["within_3std"] == pytest.approx(0.9973, abs=0.001)
    narrow = disparity_errors(est, truth, uncertainty=std / 2)
    assert narrow["median_z"] == pytest.approx(2 * GAUSSIAN_MEDIAN_Z, rel=0.01)
    assert narrow["rms_ratio"] == pytest.approx(2.0, rel=0.01)
    assert all(math.isnan(disparity_errors(est, truth)[key]) for key in ("median_z", "rms_ratio", "within_3std"))
    step = 0.125
    rounded = np.round(truth / step) * step
    r = disparity_errors(truth, rounded, truth_step_px=step, uncertainty=np.zeros(truth.shape))
    assert r["median_z"] == pytest.approx(np.sqrt(12.0) / 4, rel=0.01)
    assert r["within_3std"] == 1.0  # a uniform error never exceeds sqrt(3) of its std
    # only points with a finite std count; an exact estimate with a std of 0 has z = 0
    part = disparity_errors(np.array([[1.0, 2.0, 3.5]]), np.array([[1.0, 2.0, 3.0]]), uncertainty=np.array([[0.0, np.nan, 0.1]]))
    assert part["points"] == 3 and part["median_z"] == pytest.approx(2.5) and part["within_3std"] == 0.5
    # sqrt((0 + 0.25) / 2) / sqrt((0 + 0.01) / 2) = 5
    assert part["rms_ratio"] == pytest.approx(5.0)
    assert disparity_errors(np.array([[1.0, 2.0]]), np.array([[1.0, 2.0]]), uncertainty=np.zeros((1, 2)))["rms_ratio"] == 0.0
    assert disparity_errors(np.array([[1.5, 2.0]]), np.array([[1.0, 2.0]]), uncertainty=np.zeros((1, 2)))["rms_ratio"] == math.inf
    with pytest.raises(ValueError, match=r"uncertainty must have the shape of truth \(400, 500\), got \(2, 2\)"):
        disparity_errors(est, truth, uncertainty=np.ones((2, 2)))
    with pytest.raises(ValueError, match="uncertainty must be a standard deviation"):
        disparity_errors(est, truth, uncertainty=-std)


def test_rounding_floor_of_one_disparity_is_a_quarter_step():
    """All points at d: |u| / d is uniform on [0, step / (2 d)], median step / (4 d)."""
    assert rounding_median_rel(np.full(10, 8.0), 0.125) == pytest.approx(0.125 / 32)
    assert rounding_median_rel([8.0, np.nan, 0.0], 0.125) == pytest.approx(0.125 / 32)
    assert rounding_median_rel([5.0, 7.0], 0.0) == 0.0
    assert math.isnan(rounding_median_rel([np.nan, 0.0], 0.125))


def test_rounding_floor_matches_rounding_a_mixed_truth():
    """The exact median against the median of simulated rounding errors (400k draws: +-0.5 %)."""
    rng = np.random.default_rng(3)
    # 30 % near (about 3 px), 70 % far (about 20 px)
    t = np.where(rng.random(400_000) < 0.3, 3.0, 20.0) * rng.uniform(0.9, 1.1, 400_000)
    step = 0.125
    u = rng.uniform(-step / 2, step / 2, t.size)
    simulated = float(np.median(np.abs(u) / t))
    exact = rounding_median_rel(t, step)
    assert exact == pytest.approx(simulated, rel=0.005)
    # and the mixture's median is not the median point's quarter step: a real mixture effect
    assert abs(exact - step / (4 * np.median(t))) > 0.2 * exact  # 0.209 % against 0.163 %


def test_disparity_errors_mask_and_empty():
    truth = np.array([[1.0, 2.0], [4.0, np.nan]])
    est = np.array([[1.5, np.nan], [4.0, 3.0]])
    e = disparity_errors(est, truth, mask=np.array([[True, True], [False, True]]))
    assert e["points"] == 1 and e["truth_points"] == 2 and e["density"] == 0.5
    assert e["median_rel"] == pytest.approx(0.5) and e["mae_px"] == pytest.approx(0.5)
    assert e["bad_0_5px"] == 0.0 and e["bad_1px"] == 0.0
    empty = disparity_errors(np.full((2, 2), np.nan), truth)
    assert empty["points"] == 0 and empty["density"] == 0.0 and math.isnan(empty["median_rel"])
    assert math.isnan(empty["bias_px"]) and math.isnan(empty["truth_rounding_rel"])
    with pytest.raises(ValueError, match="same shape"):
        disparity_errors(np.zeros((2, 3)), truth)


def _step_truth():
    """10 px left of column 20, 20 px from it on: one step between columns 19 and 20."""
    truth = np.full((30, 40), 10.0)
    truth[:, 20:] = 20.0
    return truth


def test_depth_step_mask_marks_the_step_dilated():
    near = depth_step_mask(_step_truth())
    # columns 19 and 20 make the step; the 9 x 9 square adds 4 either side: 15..24, every row
    expected = np.zeros((30, 40), bool)
    expected[:, 15:25] = True
    np.testing.assert_array_equal(near, expected)
    narrow = depth_step_mask(_step_truth(), width_px=1)
    assert np.array_equal(np.nonzero(narrow.any(axis=0))[0], [19, 20])
    # a jump of exactly the gap is no step, nor is a steep ramp (1.9 px per column)
    assert not depth_step_mask(_step_truth(), gap_px=10.0).any()
    assert not depth_step_mask(np.tile(np.arange(40) * 1.9, (30, 1))).any()
    # a row of the step: the vertical direction counts too
    assert np.array_equal(np.nonzero(depth_step_mask(_step_truth().T, width_px=1).any(axis=1))[0], [19, 20])
    # unknown truth makes no step
    holed = _step_truth()
    holed[:, 20] = np.nan
    assert not depth_step_mask(holed).any()


def test_depth_step_mask_bad_input():
    with pytest.raises(ValueError, match="gap_px must be a positive finite number, got 0"):
        depth_step_mask(_step_truth(), gap_px=0)
    with pytest.raises(ValueError, match="width_px must be odd, got 4"):
        depth_step_mask(_step_truth(), width_px=4)
    with pytest.raises(TypeError, match="width_px must be an integer >= 1, got 2.5"):
        depth_step_mask(_step_truth(), width_px=2.5)
    with pytest.raises(ValueError, match="truth must be a 2-D disparity map"):
        depth_step_mask(np.zeros((2, 3, 4)))


def test_disparity_errors_split_at_depth_steps():
    truth = _step_truth()
    near = depth_step_mask(truth)
    est = truth + np.where(near, 2.0, 0.5)  # wrong near the step only
    e = disparity_errors(est, truth, near_steps=near)
    assert e["near_steps_share"] == pytest.approx(10 / 40)
    assert e["bad_1px_near_steps"] == 1.0 and e["bad_1px_off_steps"] == 0.0
    assert e["bad_1px"] == pytest.approx(10 / 40)
    # only the points scored count: masked to the step, nothing is off it
    at = disparity_errors(est, truth, mask=near, near_steps=near)
    assert at["near_steps_share"] == 1.0 and math.isnan(at["bad_1px_off_steps"])
    plain = disparity_errors(est, truth)
    assert all(math.isnan(plain[k]) for k in ("near_steps_share", "bad_1px_near_steps", "bad_1px_off_steps"))
    with pytest.raises(ValueError, match="near_steps must have the shape of truth"):
        disparity_errors(est, truth, near_steps=near[:, :5])


# ------------------------------------------------------------------ baselines, synthetic


def _texture(shape=(120, 200), seed=0):
    rng = np.random.default_rng(seed)
    tex = ndimage.gaussian_filter(rng.normal(size=shape), 1.5)
    return (tex - tex.min()) / (tex.max() - tex.min()) * 200 + 20


def _row(d, n=3, reference=1, seed=0):
    """Views t = k - reference steps from the reference: reference (r, c) seen at (r, c - t d)."""
    tex = _texture(seed=seed)
    if float(d).is_integer():
        return [np.roll(tex, -int((k - reference) * d), axis=1) for k in range(n)]
    return [ndimage.shift(tex, (0, -(k - reference) * d), order=3, mode="wrap") for k in range(n)]


INNER = (slice(10, -10), slice(40, -40))  # off OpenCV's unmatched band (numDisparities columns) and the wrap seam


@pytest.mark.parametrize("d", [4, 2.5, 1.3])
def test_sgbm_and_bm_recover_constant_disparity(d):
    views = _row(d)
    s = baselines.sgbm_disparity(views[1], views[2], num_disparities=16)
    b = baselines.stereo_bm_disparity(views[1], views[2], num_disparities=16)
    for est in (s, b):
        e = np.abs(est[INNER] - d)
        assert np.isfinite(est[INNER]).mean() > 0.95
        if float(d).is_integer():
            # integer shift: the cost has an exact minimum; OpenCV's result is on a 1/16 px grid
            assert np.nanmedian(e) <= 1 / 16 and np.nanpercentile(e, 90) <= 2 / 16
        else:
            # sub-pixel: parabola fit over integer costs (pixel locking) -> a few 1/16 px, well under 1/4 px
            assert np.nanmedian(e) <= 0.2 and np.nanpercentile(e, 90) <= 0.3
    assert s.dtype == np.float32
    # the invalid band at the left (no match possible) is NaN, not (minDisparity - 1)
    assert np.isnan(s[:, :8]).all()


def test_pair_at_last_reference_is_mirrored():
    views = _row(4, n=3, reference=2)
    r = baselines.pair_disparity_at_reference(views, reference=2, num_disparities=16)
    assert np.nanmedian(np.abs(r.disparity[INNER] - 4)) <= 1 / 16
    assert r.runtime_s >= 0 and r.method == "sgbm"
    # positions scale the pair to a neighbour step: spacing 2 -> half the raw disparity
    r2 = baselines.pair_disparity_at_reference(views, reference=1, positions=[0, 2, 4], num_disparities=16)
    assert np.nanmedian(r2.disparity[INNER]) == pytest.approx(2.0, abs=1 / 16)


@pytest.mark.parametrize("method", ["dis", "farneback"])
@pytest.mark.parametrize("d", [4, 2.5])
def test_waxman_sinha_recovers_constant_disparity(method, d):
    views = _row(d, n=4, reference=1)
    r = baselines.waxman_sinha_disparity(views, reference=1, method=method)
    e = np.abs(r.disparity[INNER] - d)
    assert np.isfinite(r.disparity).all()
    # dense flow on a smooth texture: sub-pixel by construction; DIS's patch fit has a few 1/100 px
    # of bias between integers (0.05 px measured at 2.5 px), Farneback less
    assert np.median(e) < 0.1 and np.percentile(e, 90) < 0.15
    assert r.method == f"waxman_sinha/{method}"


def test_baselines_bad_input():
    a = _texture()
    with pytest.raises(ValueError, match="multiple of 16"):
        baselines.sgbm_disparity(a, a, num_disparities=20)
    with pytest.raises(ValueError, match="same shape"):
        baselines.sgbm_disparity(a, a[:, :100])
    with pytest.raises(ValueError, match="mode"):
        baselines.sgbm_disparity(a, a, mode="fast")
    with pytest.raises(ValueError, match="reference"):
        baselines.waxman_sinha_disparity([a, a], reference=2)
    with pytest.raises(ValueError, match="strictly increasing"):
        baselines.waxman_sinha_disparity([a, a], reference=0, positions=[1, 0])
    for bad, exc in ((4, ValueError), (13, ValueError), (np.nan, ValueError), (5.5, ValueError), ("5", TypeError), (True, TypeError)):
        with pytest.raises(exc, match=r"block_size must be an odd integer in \[1, 11\]"):
            baselines.sgbm_disparity(a, a, block_size=bad)
    assert np.isfinite(baselines.sgbm_disparity(a, a, block_size=5.0)).any()  # a whole float is a whole number
    with pytest.raises(TypeError, match="chain must be True or False, got 'no'"):
        baselines.waxman_sinha_disparity([a, a], reference=0, chain="no")


def test_baselines_take_colour_views():
    """(H, W, 3) views: SGBM matches the colour itself, Waxman-Sinha its BT.601 grey
    (cv2 RGB2GRAY, as for a grey input), a fourth (alpha) channel is dropped. Whole-pixel
    shifts of 4 px: SGBM within its 1/16 px grid, DIS within 0.1 px (as for grey views)."""
    views = _row(4)
    colour = [np.stack([v, 0.5 * v + 60.0, 255.0 - v], axis=2) for v in views]
    s = baselines.sgbm_disparity(colour[1], colour[2], num_disparities=16)
    assert np.isfinite(s[INNER]).mean() > 0.95 and np.nanmedian(np.abs(s[INNER] - 4)) <= 1 / 16
    alpha = [np.concatenate([c, np.full((*c.shape[:2], 1), 7.0)], axis=2) for c in colour]
    np.testing.assert_array_equal(baselines.sgbm_disparity(alpha[1], alpha[2], num_disparities=16), s, strict=True)
    w = baselines.waxman_sinha_disparity(colour, reference=1)
    grey = [cv2.cvtColor(np.rint(c).astype(np.uint8), cv2.COLOR_RGB2GRAY) for c in colour]
    np.testing.assert_array_equal(w.disparity, baselines.waxman_sinha_disparity(grey, reference=1).disparity)
    assert np.median(np.abs(w.disparity[INNER] - 4)) < 0.1


def test_baselines_refusals_name_the_problem():
    a = _texture()
    nan = a.copy()
    nan[3, 4] = np.nan
    cases = [
        (lambda: baselines.pair_disparity_at_reference([a], reference=0), ValueError, r"^views must hold at least 2 images, got 1$"),
        (lambda: baselines.pair_disparity_at_reference([a, a], reference=0, method="sgm"), ValueError, r"^method must be 'sgbm' or 'bm', got 'sgm'$"),
        (lambda: baselines.waxman_sinha_disparity([a, a], reference=0, method="lk"), ValueError, r"^method must be 'dis' or 'farneback', got 'lk'$"),
        (lambda: baselines.waxman_sinha_disparity([a, a[:, :100]], reference=0), ValueError, r"^all views must have the same size, got \[\(120, 100\), \(120, 200\)\]$"),
        (lambda: baselines.sgbm_disparity(np.zeros((4, 5, 6, 7)), a), ValueError, r"^left must be a \(H, W\) or \(H, W, 3\) image, got shape \(4, 5, 6, 7\)$"),
        (lambda: baselines.sgbm_disparity(a, np.zeros((120, 200, 2))), ValueError, r"^right must be a \(H, W\) or \(H, W, 3\) image, got shape \(120, 200, 2\)$"),
        (lambda: baselines.sgbm_disparity(a > 100, a), TypeError, r"^left must be numeric, got dtype bool$"),
        (lambda: baselines.stereo_bm_disparity(a, np.full(a.shape, "x")), TypeError, r"^right must be numeric, got dtype <U1$"),
        (lambda: baselines.sgbm_disparity(nan, a), ValueError, r"^left holds NaN or infinite values$"),
        (lambda: baselines.sgbm_disparity(a[:7], a[:7]), ValueError, r"^images must be at least 8x8 px, got 200x7$"),
    ]
    for call, exc, match in cases:
        with pytest.raises(exc, match=match):
            call()


# ------------------------------------------------------------------ evaluate_scene, synthetic


def _synthetic_scene(d=3.0, n=5, reference=2):
    views = [v.astype(np.float32) for v in _row(d, n=n, reference=reference, seed=1)]
    truth = np.full(views[0].shape, d, np.float32)
    truth[:, :20] = np.nan
    colour = np.repeat(np.clip(views[reference], 0, 255).astype(np.uint8)[..., None], 3, axis=2)
    return MultiViewScene("synthetic", views, reference, truth, None, None, None, 0.0, colour, "test")


def _slanted_scene():
    """Five views of a texture whose disparity grows from 2 to 4 px per step down the rows (cubic-spline shifts)."""
    tex = _texture(shape=(160, 200), seed=1)
    h, w = tex.shape
    d = 2.0 + 2.0 * np.arange(h) / h
    views = [
        np.stack([ndimage.shift(tex[r], -(k - 2) * d[r], order=3, mode="wrap") for r in range(h)]).astype(np.float32) for k in range(5)
    ]
    truth = np.repeat(d[:, None], w, axis=1).astype(np.float32)
    return MultiViewScene("slanted", views, 2, truth, None, None, None, 0.0, np.zeros((h, w, 3), np.uint8), "test")


@pytest.mark.parametrize("view", [0, 1, 3, 4])
def test_photometric_truth_offset_finds_a_shifted_truth(view):
    """A right truth reads 0, one stored 0.1 px low reads +0.1 (a view 5 grey levels brighter too).

    Measured: |offset| <= 0.002 px. The bicubic warp's error at a fractional
    shift (up to 0.04 px per step on this texture for one constant
    disparity) cancels over the spread of disparities; 0.005 px allows for it.
    """
    scene = _slanted_scene()
    scene.views[view] = scene.views[view] + np.float32(5.0)
    right = photometric_truth_offset(scene, view)
    assert right["steps"] == view - 2 and right["points"] > 10000
    assert abs(right["offset_px"]) < 0.005
    low = dataclasses.replace(scene, disparity=scene.disparity - np.float32(0.1))
    res = photometric_truth_offset(low, view)
    assert res["offset_px"] == pytest.approx(0.1, abs=0.005)
    assert res["error_at_offset"] < 0.5 * res["error_at_zero"]


def test_photometric_truth_offset_bad_input():
    scene = _synthetic_scene()
    for bad in (2, 5, -1, True, 1.0):
        with pytest.raises(ValueError, match="view must be an index"):
            photometric_truth_offset(scene, bad)
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="search_px must be a positive finite number"):
            photometric_truth_offset(scene, 1, search_px=bad)
    with pytest.raises(TypeError, match="search_px must be a positive finite number, got 'far'"):
        photometric_truth_offset(scene, 1, search_px="far")
    flat = dataclasses.replace(scene, views=[np.full_like(v, 100.0) for v in scene.views])
    with pytest.raises(ValueError, match="smooth, textured pixels"):
        photometric_truth_offset(flat, 1)


def test_select_views():
    assert select_views(5, 2, "three") == [1, 2, 3]
    assert select_views(7, 0, "three") == [0, 1, 2]
    assert select_views(7, 6, "three") == [4, 5, 6]
    assert select_views(2, 0, "three") == [0, 1]
    assert select_views(4, 1, "all") == [0, 1, 2, 3]
    with pytest.raises(ValueError, match="three"):
        select_views(4, 1, "two")


def test_evaluate_scene_shape_and_table(tmp_path):
    res = evaluate_scene(_synthetic_scene(), views="three", methods=("nfdepth", "sgbm", "waxman_sinha"), keep_maps=True)
    assert res["views"] == [1, 2, 3] and res["view_count"] == 3
    assert set(res["methods"]) == {"nfdepth", "sgbm", "waxman_sinha"}
    assert res["truth_step_px"] is None
    for m, entry in res["methods"].items():
        assert entry["runtime_s"] >= 0
        assert entry["dense"]["points"] > 0
        assert set(entry["edges"]) >= {"points", "density", "median_rel", "p90_rel", "bad_1px", "bad_0_5px", "mae_px", "bias_px"}
        assert math.isnan(entry["dense"]["truth_rounding_rel"])
    # peers are scored at exactly nfdepth's edge points
    assert res["methods"]["waxman_sinha"]["edges"]["truth_points"] == res["methods"]["nfdepth"]["edges"]["points"]
    assert res["methods"]["waxman_sinha"]["dense"]["median_rel"] < 0.03
    # whole-pixel shifts of one texture (3 px per view): nfdepth and SGBM match exactly at their
    # edge points (measured 0 and 0.04 % bad-0.5px), so any wiring error (view order, reference,
    # spacing, scale) shows; a constant or doubled disparity fails every bound
    for method in ("nfdepth", "sgbm"):
        e = res["methods"][method]["edges"]
        assert e["points"] > 1000
        assert e["median_rel"] < 0.005 and e["bad_0_5px"] < 0.01, method
    assert res["methods"]["nfdepth"]["dense"]["median_rel"] < 0.01
    table = render_markdown(res)
    assert table.count("\n") == 8 and "sgbm (at nfdepth edges)" in table and "nfdepth (dense, filled)" in table
    filled, dense = res["methods"]["nfdepth"]["filled"], res["methods"]["nfdepth"]["dense"]
    assert filled["points"] >= dense["points"] and filled["density"] > 0.99
    png = error_map_png(tmp_path / "e.png", res["maps"]["sgbm"], res["truth"])
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    only = evaluate_scene(_synthetic_scene(), views="three", methods=["sgbm"])
    assert only["methods"]["sgbm"]["edges"] is None and "nfdepth_at_shared_edges" not in only["methods"]["sgbm"]
    with pytest.raises(ValueError, match="methods"):
        evaluate_scene(_synthetic_scene(), methods=["magic"])


def test_resolve_dataset_unknown(tmp_path):
    with pytest.raises(ValueError, match="unknown dataset 'nosuch'"):
        resolve_dataset("nosuch", data=tmp_path)
    with pytest.raises(ValueError, match="holds no known scene"):
        resolve_dataset(str(tmp_path), data=tmp_path)
    # a folder at the top has fewer than two parents: it was an IndexError ('internal error' at the command line)
    top = Path(tmp_path.anchor)
    for folder in (top, top / tmp_path.parts[1]):
        with pytest.raises(ValueError, match=rf"^dataset folder '{re.escape(str(folder.resolve()))}' holds no known scene"):
            resolve_dataset(folder)


ALL_SCENES = [
    "tsukuba", "teddy", "middlebury2005/Art", "middlebury2005/Books", "middlebury2005/Dolls",
    "middlebury2005/Moebius", "middlebury2005/Reindeer", "motorcycle",
]
MB2005 = ALL_SCENES[2:7]


def _fake_root(root, names=tuple(ALL_SCENES)):
    """Empty files wherever list_scenes looks for these scenes' files (resolving reads none of them)."""
    from nfdepth.datasets import _SCENE_FILES

    for name in names:
        sub, files = _SCENE_FILES[name]
        (root / sub).mkdir(parents=True, exist_ok=True)
        for f in files:
            (root / sub / f).touch()
    return root.resolve()


def test_resolve_dataset_folders(tmp_path):
    """A data root gives every scene present there; a set's or a scene's folder gives that
    scene and the root above it; the middlebury2005 folder gives its five scenes."""
    root = _fake_root(tmp_path / "data")
    assert resolve_dataset(root) == (root, ALL_SCENES)
    assert resolve_dataset(str(root) + "/") == (root, ALL_SCENES)
    for folder, name in (
        ("tsukuba", "tsukuba"),
        ("middlebury2003-teddy", "teddy"),
        ("skimage-motorcycle", "motorcycle"),
        ("middlebury2005/Art", "middlebury2005/Art"),
        ("middlebury2005/Reindeer/", "middlebury2005/Reindeer"),
    ):
        assert resolve_dataset(f"{root}/{folder}") == (root, [name]), folder
    assert resolve_dataset(root / "middlebury2005") == (root, MB2005)
    # the data argument names the root for names, not for folders
    assert resolve_dataset(root / "tsukuba", data=tmp_path) == (root, ["tsukuba"])
    partial = _fake_root(tmp_path / "partial", ["middlebury2005/Art", "tsukuba"])
    assert resolve_dataset(partial) == (partial, ["tsukuba", "middlebury2005/Art"])


def test_resolve_dataset_names_groups_and_lists(tmp_path):
    root = _fake_root(tmp_path / "data", ["tsukuba", "middlebury2005/Art", "motorcycle"])
    assert resolve_dataset("all", data=root) == (root, ["tsukuba", "middlebury2005/Art", "motorcycle"])
    assert resolve_dataset(" ALL ", data=root) == (root, ["tsukuba", "middlebury2005/Art", "motorcycle"])
    # a group is its five scenes: one missing is named before any scene runs
    with pytest.raises(DataNotFoundError, match=r"^scene 'middlebury2005/Books': data files missing: .*Books/disp1.png'.* and 6 more \(check"):
        resolve_dataset("middlebury2005", data=root)
    root = _fake_root(tmp_path / "every", ["tsukuba", "teddy", *MB2005, "motorcycle"])
    assert resolve_dataset("middlebury2005", data=root) == (root, MB2005)
    for alias, name in (
        ("Art", "middlebury2005/Art"),
        ("MIDDLEBURY2005/art", "middlebury2005/Art"),
        ("reindeer", "middlebury2005/Reindeer"),
        ("middlebury2003-teddy", "teddy"),
        ("middlebury2003/teddy", "teddy"),
        ("skimage-motorcycle", "motorcycle"),
        ("Tsukuba", "tsukuba"),
    ):
        assert resolve_dataset(alias, data=root) == (root, [name]), alias
    # a list: each item resolved, in order, without repeats
    got = resolve_dataset(["tsukuba", "Art", "tsukuba", "middlebury2005"], data=root)
    assert got == (root, ["tsukuba", "middlebury2005/Art", "middlebury2005/Books", "middlebury2005/Dolls", "middlebury2005/Moebius", "middlebury2005/Reindeer"])
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(DataNotFoundError, match=rf"^no complete scene under data folder '{empty.resolve()}'$"):
        resolve_dataset("all", data=empty)
    with pytest.raises(ValueError, match=r"^unknown dataset 'nosuch': give one of all, middlebury2005, tsukuba, teddy, middlebury2005/Art, .*motorcycle, or a data folder$"):
        resolve_dataset("nosuch", data=root)


def test_resolve_dataset_keeps_the_root_of_a_folder_in_a_list(tmp_path, monkeypatch):
    """Alone, a scene's folder resolves to its own root; inside a list it must too, or the
    scenes are loaded from another tree (NFDEPTH_DATA's) or not found at all."""
    root = _fake_root(tmp_path / "mine", ["tsukuba"])
    other = _fake_root(tmp_path / "other", ["tsukuba"])
    monkeypatch.setenv("NFDEPTH_DATA", str(other))
    assert resolve_dataset(root / "tsukuba") == (root, ["tsukuba"])
    assert resolve_dataset([root / "tsukuba"]) == (root, ["tsukuba"])
    with pytest.raises(ValueError, match=r"^the datasets of a list must lie under one data root, got .*mine, .*other$"):
        resolve_dataset([root / "tsukuba", other / "tsukuba"])
    with pytest.raises(ValueError, match=r"^dataset is an empty list"):
        resolve_dataset([])


def test_evaluate_dataset_checks_views_and_methods_before_the_data(tmp_path):
    """Bad options are refused before any scene is resolved or loaded."""
    with pytest.raises(ValueError, match=r"^views must be 'all', 'three' or a sequence of view indices, got 'two'$"):
        evaluate_dataset("nosuch", data=tmp_path / "absent", views="two")
    with pytest.raises(ValueError, match=r"^methods must be one or more of nfdepth, sgbm, bm, waxman_sinha, waxman_sinha_farneback, got magic$"):
        evaluate_dataset("nosuch", data=tmp_path / "absent", methods=["magic"])


@pytest.mark.data
def test_evaluate_dataset_scores_every_scene_as_evaluate_scene_does():
    """Two scenes at a quarter size, three views, nfdepth and SGBM: one result per scene in the
    order given, each passed to ``progress`` as it is done, each equal to evaluate_scene's
    (deterministic: every figure but the runtime). Measured dense bad >1 px: nfdepth 2.5 % /
    6.3 %, SGBM 2.2 % / 12.2 % (Tsukuba / Art, 97 % / 94 % of the truth covered by nfdepth);
    bounds about twice that."""
    from nfdepth.datasets import load_scene

    root = _real_root()
    if "middlebury2005/Art" not in list_scenes(root):
        pytest.skip(f"middlebury2005/Art not found under {root}")
    seen = []
    results = evaluate_dataset(["tsukuba", "Art"], data=root, views="three", methods=("nfdepth", "sgbm"), downsample=4, progress=seen.append)
    assert [r["scene"] for r in results] == ["tsukuba", "middlebury2005/Art"]
    assert len(seen) == 2 and all(a is b for a, b in zip(seen, results))
    tsukuba, art = results
    assert (tsukuba["shape"], tsukuba["views"], tsukuba["downsample"], tsukuba["truth_step_px"]) == ([72, 96], [1, 2, 3], 4, 0.25)
    assert (art["shape"], art["views"], art["downsample"], art["truth_step_px"]) == ([138, 173], [0, 1, 2], 4, 1 / 32)
    for res, bound_nf, bound_sgbm in ((tsukuba, 0.05, 0.05), (art, 0.12, 0.25)):
        nf, sgbm = res["methods"]["nfdepth"]["dense"], res["methods"]["sgbm"]["dense"]
        assert nf["density"] > 0.9 and nf["bad_1px"] < bound_nf, res["scene"]
        assert sgbm["bad_1px"] < bound_sgbm, res["scene"]
        alone = evaluate_scene(load_scene(res["scene"], root), views="three", methods=("nfdepth", "sgbm"), downsample=4)
        for method, entry in res["methods"].items():
            for part, errs in entry.items():
                if part != "runtime_s":
                    assert json.dumps(errs, sort_keys=True) == json.dumps(alone["methods"][method][part], sort_keys=True), (res["scene"], method, part)
    # several results make one table: a row per scene, method and point set
    table = render_markdown(results).splitlines()
    for res in results:
        rows = [line for line in table if line.startswith(f"| {res['scene']} /4 | 3 |")]
        assert len(rows) == len(list(evaluation_rows(res))) >= 5
    assert len(table) == 2 + sum(len(list(evaluation_rows(r))) for r in results)


@pytest.mark.data
def test_photometric_truth_offset_of_a_scene_name():
    """A name loads the scene: the same figures as for the loaded scene. Tsukuba's whole-pixel
    labels read high: measured -0.071 / -0.094 px per step (views 1 / 3; the wall alone reads
    4.82-4.85 px against its label 5, test_stereo)."""
    from nfdepth.datasets import load_scene

    root = _real_root()
    by_name = photometric_truth_offset("tsukuba", 3)
    assert by_name == photometric_truth_offset(load_scene("tsukuba", root), 3)
    assert by_name["steps"] == 1 and by_name["points"] > 10000
    assert -0.2 < by_name["offset_px"] < -0.03
    assert by_name["error_at_offset"] < by_name["error_at_zero"]


def test_select_views_takes_a_sequence_of_indices():
    assert select_views(7, 1, (0, 1, 2)) == [0, 1, 2]
    assert select_views(7, 1, np.array([1, 3, 5])) == [1, 3, 5]
    assert select_views(7, 1, [np.int64(2), 4.0]) == [2, 4]
    assert select_views(9, 2, " Three ") == [1, 2, 3]
    for bad in ([0, "x"], 5, [None]):
        with pytest.raises(ValueError, match=r"^views must be 'all', 'three' or a sequence of view indices, got "):
            select_views(7, 1, bad)


def test_fractional_view_indices_are_refused():
    """view_subset refuses [1, 2.7, 3]; through evaluate_scene the same views ran as [1, 2, 3], silently."""
    for bad in ([1, 2.7, 3], [0, 1.5, 3], [True, 2, 3]):
        with pytest.raises(ValueError, match=r"^views must be 'all', 'three' or a sequence of view indices, got "):
            evaluate_scene(_synthetic_scene(), views=bad, methods="sgbm")


def test_evaluate_scene_options_and_refusals():
    scene = _synthetic_scene()
    one = evaluate_scene(scene, views="three", methods="sgbm")  # one method by name
    assert list(one["methods"]) == ["sgbm"]
    # integer shifts of 3 px: SGBM matches exactly (1/16 px grid)
    assert one["methods"]["sgbm"]["dense"]["median_rel"] == 0.0
    with pytest.raises(ValueError, match=r"^methods must be one or more of nfdepth, sgbm, bm, waxman_sinha, waxman_sinha_farneback, got none$"):
        evaluate_scene(scene, methods=())
    with pytest.raises(TypeError, match=r"^scene must be a MultiViewScene or a scene name, got int$"):
        evaluate_scene(42)
    with pytest.raises(TypeError, match=r"^scene must be a MultiViewScene or a scene name, got list$"):
        photometric_truth_offset([], 1)
    for bad in (0, 1.5, -2, float("nan"), float("inf")):
        with pytest.raises(ValueError, match=rf"^downsample must be a positive integer, got {bad!r}$"):
            evaluate_scene(scene, methods="sgbm", downsample=bad)
    for bad in (None, "2", True):  # were int()'s own TypeError, or '2' taken; a bool is no count (downsample_scene's check)
        with pytest.raises(TypeError, match=rf"^downsample must be a positive integer, got {re.escape(repr(bad))}$"):
            evaluate_scene(scene, methods="sgbm", downsample=bad)


def test_to_jsonable_and_error_map_shapes(tmp_path):
    res = {"a": np.int64(3), "b": [np.float32(np.nan), 1.5, np.float64(np.inf)], "c": (np.uint8(7), "x"), "maps": {}, "truth": 1, "edge_points": 2}
    out = to_jsonable(res)
    assert out == {"a": 3, "b": [None, 1.5, None], "c": [7, "x"]}
    assert type(out["a"]) is int and type(out["c"][0]) is int
    with pytest.raises(ValueError, match=r"^estimate and truth must have the same shape, got \(2, 3\) and \(3, 2\)$"):
        error_map_png(tmp_path / "e.png", np.zeros((2, 3)), np.zeros((3, 2)))
    assert not (tmp_path / "e.png").exists()


# ------------------------------------------------------------------ the command line


@needs_cli
def test_cli_unknown_dataset_one_line(capsys, tmp_path):
    code, out, err = run_cli(capsys, "evaluate", "nosuch", "--data", str(tmp_path))
    assert code == 2
    assert err.startswith("nfdepth: error: unknown dataset 'nosuch'") and err.count("\n") == 1


@needs_cli
def test_cli_missing_data_root(capsys, tmp_path):
    code, out, err = run_cli(capsys, "evaluate", "tsukuba", "--data", str(tmp_path / "absent"))
    assert code == 5 and err == f"nfdepth: error: --data '{tmp_path / 'absent'}' is not a directory; expected the data folder (as filled by `nfdepth fetch-data --dest DIR`)\n"


@needs_cli
def test_cli_bad_views_and_json(capsys, tmp_path):
    code, _, err = run_cli(capsys, "evaluate", "tsukuba", "--views", "two")
    assert code == 2 and "--views" in err
    code, _, err = run_cli(capsys, "evaluate", "tsukuba", "--cost-step-px", "0")
    assert code == 2 and err.strip() == "nfdepth: error: --cost-step-px must be a positive number, got 0"
    code, _, err = run_cli(capsys, "evaluate", "tsukuba", "--json", str(tmp_path / "no" / "r.json"))
    assert code == 4 and "does not exist" in err


def _touch_scene(root, sub, files):
    folder = root / sub
    folder.mkdir(parents=True, exist_ok=True)
    for f in files:
        (folder / f).write_bytes(b"x")  # only their presence is checked here


_MB2005_FILES = ["disp1.png", "dmin.txt"] + [f"view{k}.png" for k in range(7)]


def test_an_incomplete_scene_is_skipped_with_a_warning_or_refused_when_named(tmp_path):
    """'all' and a data root take the complete scenes and name each incomplete one; a named scene or group
    with a file missing is refused before any scene runs."""
    from nfdepth.evaluate import resolve_dataset

    _touch_scene(tmp_path, "middlebury2005/Art", _MB2005_FILES)
    _touch_scene(tmp_path, "middlebury2005/Books", [f for f in _MB2005_FILES if f != "view2.png"])
    for dataset, data in (("all", tmp_path), (tmp_path, None)):
        with pytest.warns(UserWarning, match=rf"^scene 'middlebury2005/Books' skipped: its folder '{tmp_path / 'middlebury2005' / 'Books'}' lacks view2.png$"):
            root, names = resolve_dataset(dataset, data)
        assert names == ["middlebury2005/Art"] and root == tmp_path.resolve()
    (tmp_path / "middlebury2005" / "Books" / "view2.png").mkdir()  # there, but not a file
    with pytest.warns(UserWarning, match=r"^scene 'middlebury2005/Books' skipped: .* lacks view2.png \(not a file\)$"):
        assert resolve_dataset("all", tmp_path)[1] == ["middlebury2005/Art"]
    (tmp_path / "middlebury2005" / "Books" / "view2.png").rmdir()
    for dataset in ("middlebury2005", "books", tmp_path / "middlebury2005"):
        with pytest.raises(DataNotFoundError, match=r"^scene 'middlebury2005/Books': data file missing: '.*view2.png' \(check the data folder"):
            resolve_dataset(dataset, tmp_path if isinstance(dataset, str) else None)


@needs_cli
def test_cli_evaluate_refuses_a_group_with_a_file_missing_before_its_first_scene(capsys, tmp_path):
    _touch_scene(tmp_path, "middlebury2005/Art", _MB2005_FILES)  # would run first (and fail: not images)
    _touch_scene(tmp_path, "middlebury2005/Books", _MB2005_FILES[:-1])
    code, out, err = run_cli(capsys, "evaluate", "middlebury2005", "--data", str(tmp_path), "--methods", "sgbm")
    assert code == 5 and out == ""
    assert err == f"nfdepth: error: scene 'middlebury2005/Books': data file missing: '{tmp_path / 'middlebury2005' / 'Books' / 'view6.png'}' (check the data folder, or download it with `nfdepth fetch-data`)\n"


@needs_cli
def test_cli_evaluate_refuses_a_directory_in_a_files_place_as_unreadable_before_its_first_scene(capsys, tmp_path):
    """A directory where a scene file belongs is 'cannot read' (exit 3), as loading the scene says, not 'missing' (exit 5)."""
    _touch_scene(tmp_path, "middlebury2005/Art", _MB2005_FILES)  # would run first (and fail: not images)
    _touch_scene(tmp_path, "middlebury2005/Books", _MB2005_FILES[:-1])
    (tmp_path / "middlebury2005" / "Books" / "view6.png").mkdir()
    code, out, err = run_cli(capsys, "evaluate", "middlebury2005", "--data", str(tmp_path), "--methods", "sgbm")
    assert code == 3 and out == ""
    view6 = tmp_path / "middlebury2005" / "Books" / "view6.png"
    assert err == f"nfdepth: error: scene 'middlebury2005/Books': cannot read '{view6}': it is a directory, not a file; is the data folder intact?\n"
    # an absent file is still named first, as missing
    (tmp_path / "middlebury2005" / "Books" / "view5.png").unlink()
    code, _, err = run_cli(capsys, "evaluate", "middlebury2005", "--data", str(tmp_path), "--methods", "sgbm")
    assert code == 5 and err.startswith("nfdepth: error: scene 'middlebury2005/Books': data file missing: ") and "view5.png" in err and "view6" not in err


@needs_cli
def test_cli_evaluate_json_beside_a_file(capsys, tmp_path):
    (tmp_path / "afile").write_text("")
    code, _, err = run_cli(capsys, "evaluate", "tsukuba", "--json", str(tmp_path / "afile" / "r.json"))
    assert code == 4 and err == f"nfdepth: error: --json '{tmp_path / 'afile' / 'r.json'}': '{tmp_path / 'afile'}' is not a directory\n"


def _real_root():
    try:
        root = data_root()
    except DataNotFoundError:
        pytest.skip("real data not found: set NFDEPTH_DATA or put it at ../shared/data")
    if "tsukuba" not in list_scenes(root):
        pytest.skip(f"tsukuba not found under {root}")
    return root


@pytest.mark.data
@needs_cli
def test_cli_evaluate_tsukuba_json(capsys, tmp_path):
    root = _real_root()
    js = tmp_path / "t.json"
    code, out, err = run_cli(capsys, "evaluate", "tsukuba", "--data", str(root), "--views", "three", "--json", str(js), "--maps", str(tmp_path / "maps"))
    assert code == 0, err
    assert "tsukuba" in out and "nfdepth (edges)" in out and "waxman_sinha (dense)" in out
    data = json.loads(js.read_text())
    assert isinstance(data, list) and len(data) == 1
    res = data[0]
    assert res["scene"] == "tsukuba" and res["views"] == [1, 2, 3] and res["shape"] == [288, 384]
    import nfdepth

    assert res["nfdepth_version"] == nfdepth.__version__
    assert set(res["methods"]) == {"nfdepth", "sgbm", "waxman_sinha"}
    keys = {
        "points", "truth_points", "density", "median_rel", "p90_rel", "bad_1px", "bad_0_5px", "mae_px", "bias_px", "truth_rounding_rel",
        "median_z", "rms_ratio", "within_3std", "near_steps_share", "bad_1px_near_steps", "bad_1px_off_steps",
    }
    assert res["truth_step_px"] == 1.0  # whole-pixel labels
    assert "stored in steps of 1 px" in out and "bias px" in out and "near a depth step" in out and "bad>1 off" in out
    # Tsukuba's layers: about a sixth of the truth lies within 4 px of a step of more than 2 px
    assert 0.1 < res["near_steps_share"] < 0.25
    for name, entry in res["methods"].items():
        assert set(entry) == {"runtime_s", "edges", "dense"} | ({"filled"} if name == "nfdepth" else {"nfdepth_at_shared_edges"})
        assert set(entry["edges"]) == keys and set(entry["dense"]) == keys
        assert 0 < entry["dense"]["density"] <= 1
        # every method is far better than chance on Tsukuba (disparity 5..14 px)
        assert entry["dense"]["median_rel"] < 0.1
        # whole-pixel labels of 5..14 px: a perfect estimate would score a median of 1/4 px over ~8 px
        assert 0.02 < entry["dense"]["truth_rounding_rel"] < 0.05
        # bad-1px is the mixture of its two parts
        d = entry["dense"]
        mix = d["near_steps_share"] * d["bad_1px_near_steps"] + (1 - d["near_steps_share"]) * d["bad_1px_off_steps"]
        assert mix == pytest.approx(d["bad_1px"], abs=1e-12)
    # nfdepth's error bar against the whole-pixel truth (its rounding in quadrature): median |error| / std
    # measured 0.60 at the edge points, 0.33 dense (whose errors near steps are two-valued: small or a
    # whole step); RMS error / RMS std 1.09 and 1.08, calibrated within the project's factor 1.5. The peers
    # report no std.
    assert "err/std" in out and "rms e/s" in out
    nf = res["methods"]["nfdepth"]
    assert all(1 / 1.5 < nf[part]["rms_ratio"] < 1.5 for part in ("edges", "dense")), nf
    assert GAUSSIAN_MEDIAN_Z / 1.5 < nf["edges"]["median_z"] < GAUSSIAN_MEDIAN_Z * 1.5 and nf["edges"]["within_3std"] > 0.9
    assert nf["dense"]["median_z"] < 2 * GAUSSIAN_MEDIAN_Z and nf["filled"]["median_z"] is None
    assert res["methods"]["sgbm"]["dense"]["median_z"] is None and res["methods"]["sgbm"]["nfdepth_at_shared_edges"]["median_z"] > 0
    assert len(list((tmp_path / "maps").glob("tsukuba_3views_*.png"))) == 3
    assert res["stereo_options"] == {}


@pytest.mark.data
@needs_cli
def test_cli_evaluate_cost_step(capsys, tmp_path):
    """``--cost-step-px`` reaches nfdepth's static stereo, is printed and recorded, and is the library's ``cost_step_px``."""
    root = _real_root()
    js = tmp_path / "t.json"
    code, out, err = run_cli(capsys, "evaluate", "tsukuba", "--data", str(root), "--views", "three", "--methods", "nfdepth", "--cost-step-px", "1", "--json", str(js))
    assert code == 0, err
    assert "nfdepth cost_step_px = 1" in out
    res = json.loads(js.read_text())[0]
    assert res["stereo_options"] == {"cost_step_px": 1.0}
    lib = evaluate_scene("tsukuba", views="three", methods=("nfdepth",), stereo_options={"cost_step_px": 1.0})
    default = evaluate_scene("tsukuba", views="three", methods=("nfdepth",))
    for part in ("edges", "dense"):
        assert res["methods"]["nfdepth"][part]["points"] == lib["methods"]["nfdepth"][part]["points"]
        assert res["methods"]["nfdepth"][part]["median_rel"] == pytest.approx(lib["methods"]["nfdepth"][part]["median_rel"], rel=1e-12)
    assert res["methods"]["nfdepth"]["dense"]["median_rel"] != default["methods"]["nfdepth"]["dense"]["median_rel"]


def test_nfdepth_is_also_scored_on_the_points_a_peer_shares(monkeypatch):
    """Where a peer leaves some of nfdepth's edge points without a value, nfdepth is scored on exactly the rest too."""
    from nfdepth import evaluate

    real = evaluate._run_peer

    def holes(method, scene, max_disp):
        r = real(method, scene, max_disp)
        if method == "sgbm":  # no value in the top rows, as a peer rejecting its unsure matches
            r.disparity[:15] = np.nan
        return r

    monkeypatch.setattr(evaluate, "_run_peer", holes)
    res = evaluate_scene(_synthetic_scene(), views="three", methods=("nfdepth", "sgbm", "waxman_sinha"), keep_maps=True)
    edges = res["edge_points"]
    truth = res["truth"]
    for peer in ("sgbm", "waxman_sinha"):
        shared = res["methods"][peer]["nfdepth_at_shared_edges"]
        mask = edges & np.isfinite(res["maps"][peer])
        expected = disparity_errors(res["maps"]["nfdepth"], truth, mask=mask, near_steps=depth_step_mask(truth), uncertainty=res["uncertainty"])
        assert shared.keys() == expected.keys()
        assert all(shared[k] == expected[k] or (math.isnan(shared[k]) and math.isnan(expected[k])) for k in expected)
        assert shared["points"] == res["methods"][peer]["edges"]["points"]
    n_edges = res["methods"]["nfdepth"]["edges"]["points"]
    assert 0 < res["methods"]["sgbm"]["nfdepth_at_shared_edges"]["points"] < n_edges
    assert res["methods"]["waxman_sinha"]["nfdepth_at_shared_edges"]["points"] == n_edges
    # a row for the smaller shared set, right after the peer's own edge row; none for a full one
    labels = [(m, label) for m, label, _, _ in evaluation_rows(res)]
    assert labels.index(("nfdepth", "edges & sgbm")) == labels.index(("sgbm", "at nfdepth edges")) + 1
    assert ("nfdepth", "edges & waxman_sinha") not in labels
    assert "nfdepth (edges & sgbm)" in render_markdown(res)


@pytest.mark.parametrize(("fn", "name", "ok_width", "columns"), [(baselines.sgbm_disparity, "StereoSGBM", 19, 18), (baselines.stereo_bm_disparity, "StereoBM", 24, 23)])
def test_two_view_peers_say_when_the_images_are_too_narrow(fn, name, ok_width, columns):
    """OpenCV needs width - numDisparities > blockSize // 2; below that it raised an internal
    error (``nfdepth evaluate tsukuba --downsample 24``: exit 1). Now a ValueError that says so."""
    img = np.random.default_rng(0).integers(0, 255, (40, 30)).astype(np.uint8)
    assert fn(img[:, :ok_width], img[:, :ok_width]).shape == (40, ok_width)
    with pytest.raises(ValueError, match=rf"^the images are {ok_width - 1} px wide: {name} with 16 disparities and a \d+ px block needs more than {columns} columns"):
        fn(img[:, : ok_width - 1], img[:, : ok_width - 1])


def test_waxman_sinha_dis_too_small_is_a_clear_error():
    """DIS needs a side of 12 px (OpenCV raised its own error); Farneback takes smaller views."""
    views = [np.random.default_rng(k).random((5, 7)) * 255 for k in range(3)]
    with pytest.raises(ValueError, match="DIS optical flow needs a side of at least 12 px"):
        baselines.waxman_sinha_disparity(views, reference=1)
    assert baselines.waxman_sinha_disparity(views, reference=1, method="farneback").disparity.shape == (5, 7)


def test_view_size_problems_names_each_methods_limit():
    from nfdepth.evaluate import view_size_problems

    assert view_size_problems((288, 384), ("nfdepth", "sgbm", "bm", "waxman_sinha", "waxman_sinha_farneback")) == []
    assert view_size_problems((9, 18), ("nfdepth", "sgbm")) == ["sgbm needs views of at least 8x8 px, more than 18 px wide"]
    assert view_size_problems((2, 2), ("nfdepth", "waxman_sinha")) == [
        "nfdepth needs views of at least 3x3 px",
        "waxman_sinha's DIS flow needs a side of at least 12 px",
    ]
    assert view_size_problems((1, 40), ("waxman_sinha_farneback",)) == ["the downsampled views need at least 2x2 px"]
