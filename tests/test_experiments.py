"""The paper's experiments reproduced (issue: Table 1, experiment 4, static).

Targets: maximum relative error of the relative normal flow, corners
excluded, at least as good as the paper in every column (ours must reach
0.01 / 0.02 / 0.06 / 0.02 / 0.01), medians <= 0.5 %, and depth errors within
10 % of the flow errors (depth error = flow error to first order, eq. 6).
"""

import json

import numpy as np
import pytest

from nfdepth.experiments import EXPERIMENTS, PAPER_REPORTED, error_stats, run_paper_experiment

TARGET_MAX = {"exp1": 0.01, "exp2": 0.02, "exp3": 0.06, "exp4": 0.02, "static": 0.01}


@pytest.fixture(scope="module")
def results():
    return {name: run_paper_experiment(name) for name in EXPERIMENTS}


@pytest.mark.parametrize("name", EXPERIMENTS)
def test_noise_free_maxima_beat_the_paper(results, name):
    s = results[name].summary()
    flow, depth = s["flow_rel_error"], s["depth_rel_error"]
    assert s["points"] >= 300  # the paper's figures show a few hundred edge points
    assert flow["max"] <= TARGET_MAX[name] <= PAPER_REPORTED[name]
    assert flow["median"] <= 0.005
    assert depth["max"] <= 1.1 * flow["max"] + 1e-4
    assert depth["median"] <= 1.1 * flow["median"] + 1e-4


def test_literal_stencil_is_worse_where_the_hint_says(results):
    # The printed stencil (equal frame weights, two-point difference) cannot reach
    # the paper's numbers for experiments 2-4 (measured 0.11 / 0.38 / 0.19).
    literal = run_paper_experiment("exp3", stencil="paper").summary()["flow_rel_error"]["max"]
    assert literal > 3 * results["exp3"].summary()["flow_rel_error"]["max"]


def test_depth_points_are_on_the_pyramid(results):
    r = results["exp1"]
    z = r.result.depth[r.result.valid]
    assert np.nanmin(z) > 195 and np.nanmax(z) < 405  # apex at 200, base at 400
    pts = r.result.points[r.result.valid]
    np.testing.assert_allclose(pts[:, 2], z)


def test_noisy_experiment_is_seeded_and_reported(tmp_path):
    a = run_paper_experiment("exp1", noise_std=1.0, seed=3).summary()
    b = run_paper_experiment("exp1", noise_std=1.0, seed=3).summary()
    assert a == {**b, "runtime_s": a["runtime_s"]}
    # Noise of 1 grey level on edges of contrast 50: the per-point noise floor is
    # about 1-2 % of the relative flow (see README); p95 measured 3.3-5 %.
    assert a["flow_rel_error"]["median"] < 0.02
    assert a["flow_rel_error"]["p95"] < 0.06
    json.dumps(a)


def test_error_stats_ignores_nan():
    s = error_stats([np.nan, 0.1, 0.3, 0.2])
    assert s["max"] == pytest.approx(0.3)
    assert s["median"] == pytest.approx(0.2)
    assert s["count"] == 3
    assert np.isnan(error_stats([])["max"])


def test_unknown_experiment():
    with pytest.raises(ValueError, match="experiment must be one of"):
        run_paper_experiment("exp9")


@pytest.mark.parametrize("name", ["exp1", "exp3", "static"])
def test_noise_p95_with_uncertainty_bound(name):
    # With std-1 noise every point's error is dominated by noise (its predicted
    # std is calibrated); refusing points whose predicted relative std exceeds
    # 1.5 % keeps the strong edges (about 210 points) with p95 <= 3 %
    # (measured 1.1-2.2 % over seeds 0 and 1).
    for seed in (0, 1):
        res = run_paper_experiment(name, noise_std=1.0, seed=seed, max_rel_std=0.015)
        s = res.summary()
        assert s["points"] >= 150
        assert s["flow_rel_error"]["p95"] <= 0.03
        assert np.all(res.result.reason[~res.result.valid] != 0)


def test_noise_uncertainty_is_calibrated():
    # z-scores of the relative-flow error against its predicted std: unit spread
    # (measured 0.98-1.10 over experiments); 1.5x is the calibration bound.
    res = run_paper_experiment("exp1", noise_std=1.0, seed=0)
    ok = np.isfinite(res.flow_error)
    z = (res.result.delta_vn[ok] - res.true_delta_vn[ok]) / res.result.delta_vn_std[ok]
    assert 1 / 1.5 < np.std(z) < 1.5


@pytest.mark.parametrize("name", ["exp1", "exp2", "exp3", "exp4", "static"])
def test_noise_free_images_keep_an_error_bar(name):
    """Without image noise the estimated noise is 0, and so was every point's standard deviation, while the stencil's
    own error leaves the depths 0.16-0.43 % off (median). Its share (``STENCIL_REL_STD``, 0.4 % of the flow) keeps
    the error bar honest: measured median |error| / std 0.39-1.08 (a calibrated one: 0.67); with noise of 1 grey
    level it stays calibrated (0.68-0.70, and the test above)."""
    res = run_paper_experiment(name)
    ok = res.result.valid
    assert res.result.noise_std == 0.0 and ok.sum() > 300
    std = res.result.depth_std[ok]
    assert np.all(std > 0)
    ratio = np.median(np.abs(res.result.depth[ok] - res.true_depth[ok]) / std)
    assert 0.67 / 2.0 < ratio < 0.67 * 2.0


def test_experiment_noise_is_checked():
    """noise_std='1' was "'>' not supported between instances of 'str' and 'int'"."""
    from nfdepth.experiments import run_paper_experiment

    with pytest.raises(TypeError, match=r"^noise_std must be a finite number >= 0, got '1' \(str, not a number\)$"):
        run_paper_experiment("exp1", noise_std="1")
    with pytest.raises(ValueError, match=r"^noise_std must be a finite number >= 0, got -1$"):
        run_paper_experiment("exp1", noise_std=-1)
