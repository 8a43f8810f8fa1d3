"""Static stereo of rows whose views lie unequally far from the reference.

Scene: the textured board in front of a textured wall with exact depth
(:func:`textured_planes.textured_world_frame`, f = 100 px, 160 x 120; 2.5 px
of disparity per unit of position on the board, 1.7 px on the wall), views
from ``(x, 0, 0)``, the reference at ``x = 0``, ``noise`` grey levels of
Gaussian noise. Before this change a near view set the precision of the
whole row twice over: the cost volume's candidate steps were 0.5 px of the
nearest view (a sub-sample bias of about 0.05 px of its shift), and the
one-sided minimum took its shallow cost curve even where both sides see the
point; a near view that shifts the scene by less than 2 px still won there
until its one-sided penalty grew with how little it shifts the scene
(``_near_side_gain``). Measured medians (before -> now) are in each test;
the bounds are about twice the new ones and far below the old.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from textured_planes import textured_world_frame

from nfdepth._cost_volume import _both_sides, _near_side_gain
from nfdepth.camera import PinholeCamera
from nfdepth.stereo import _candidate_step, static_stereo

CAMERA = PinholeCamera(focal_px=100.0, width_px=160, height_px=120)


def _row_scores(along, noise):
    """Median relative error, share > 10 % off, cover, median |error| / std of the row ``along`` plus the reference at 0."""
    rng = np.random.default_rng(1)
    xs = sorted({0.0, *along})
    shots = [textured_world_frame(CAMERA, np.eye(3), (x, 0.0, 0.0), noise=noise, rng=rng) for x in xs]
    ref = xs.index(0.0)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="no edge points")  # the isotropic texture is all corners for the edge test
        r = static_stereo([s[0] for s in shots], reference=ref, positions=xs)
    truth = CAMERA.focal_px / shots[ref][1]  # px per unit of position
    ok = np.isfinite(r.disparity)
    err = r.disparity[ok].astype(float) - truth[ok]
    rel = np.abs(err) / truth[ok]
    return np.median(rel), np.mean(rel > 0.1), ok.mean(), np.median(np.abs(err) / r.uncertainty[ok])


@pytest.mark.parametrize(
    ("along", "noise", "most_median", "most_wrong"),
    [
        # 10.5 % / 54 % -> 1.0 % / 2.2 % -> 0.81 % / 2.3 % (interleaved) -> 0.34 % / 1.3 % (near-side gain); 1.75 alone: 0.31 % / 1.1 %
        ((-0.25, 1.75), 1.0, 0.007, 0.03),
        ((-0.2, 2.0), 1.0, 0.006, 0.025),  # 16.5 % / 80 % -> 1.5 % / 2.7 % -> 1.1 % / 2.5 % -> 0.28 % / 1.1 %; 2 alone: 0.22 % / 0.6 %
        ((-0.5, 2.0), 4.0, 0.02, 0.05),  # 5.4 % / 29 % -> 0.85 % / 2.4 % -> 1.0 % / 2.3 % (unchanged by the gain); 2 alone: 0.69 % / 0.3 %
        ((-0.25, 1.75), 4.0, 0.03, 0.07),  # 6.6 % / 31 % -> 1.5 % / 3.5 % -> 1.25 % / 2.9 % (unchanged); 1.75 alone: 1.1 % / 0.7 %
    ],
)
def test_a_near_view_does_not_spoil_a_far_one(along, noise, most_median, most_wrong):
    median, wrong, cover, z = _row_scores(along, noise)
    assert cover > 0.95
    assert median < most_median
    assert wrong < most_wrong
    # measured 0.54-1.02 (0.88-1.42 before the near-side gain; 0.59-1.0 while the std counted 0.1 steps of sub-sample bias)
    assert 0.4 < z < 1.3


def test_a_near_view_that_hardly_shifts_the_scene_keeps_the_far_views_precision():
    """Views -0.2 / 2 (the near view shifts the scene by 0.3-0.5 px): within 1.5 times the far view's own median error.
    Measured at noise 1: 0.28 % against 0.22 % for view 2 alone (1.07 % before the near-side gain, 4.9 times)."""
    both, _, cover, _ = _row_scores((-0.2, 2.0), 1.0)
    alone, _, cover_alone, _ = _row_scores((2.0,), 1.0)
    assert both < 1.5 * alone
    assert cover > cover_alone  # and the near view measures the band the far one cannot see


def test_the_band_only_the_near_side_sees_keeps_its_values():
    """Views -0.5 / 2 at noise 4: the columns at the left border, which view 2 cannot see at the true disparity but can at
    smaller ones, are measured by the near view. A first version of the near-side gain raised the one-sided cost there
    too, and they came out near 0 px instead of 1.67."""
    rng = np.random.default_rng(1)
    xs = [-0.5, 0.0, 2.0]
    shots = [textured_world_frame(CAMERA, np.eye(3), (x, 0.0, 0.0), noise=4.0, rng=rng) for x in xs]
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="no edge points")
        r = static_stereo([s[0] for s in shots], reference=1, positions=xs)
    truth = CAMERA.focal_px / shots[1][1]
    band = np.s_[:, :4]  # the wall at 1.67 px per unit: view 2 sees these columns 3.3 px left of the image
    rel = np.abs(r.disparity[band] - truth[band]) / truth[band]
    assert np.isfinite(r.disparity[band]).mean() > 0.95
    assert np.median(rel) < 0.1 and np.mean(rel > 0.5) < 0.05


def test_near_side_gain():
    assert _near_side_gain(float("nan")) == 1.0  # unknown shift: the plain penalty
    assert _near_side_gain(5.0) == _near_side_gain(2.0) == 1.0  # at least 2 px: the plain penalty (every real row here)
    assert _near_side_gain(1.0) == pytest.approx(2.0)
    assert _near_side_gain(0.4) == _near_side_gain(0.0) == 3.0  # at most 3


@pytest.mark.parametrize("noise", [1.0, 4.0])
def test_a_farther_view_makes_the_map_more_precise(noise):
    """Views at -1, 0, 3 against -1, 0, 1: the far view's three times longer baseline shows in the precision.
    Measured medians -1 / 3 against -1 / 1: noise 1: 0.26 % / 0.42 %; noise 4: 0.72 % / 1.33 % (first release: 3.0 % both,
    then the near rows' 0.1-step bias: 0.28 % / 3.0 %, 0.94 % / 2.1 %)."""
    near, _, _, _ = _row_scores((-1.0, 1.0), noise)
    far, wrong, _, _ = _row_scores((-1.0, 3.0), noise)
    assert far < 0.8 * near
    assert wrong < 0.02


def test_candidate_step_follows_the_farthest_view_and_interleaves_only_for_small_shifts():
    assert _candidate_step(0.5, 1.0, 0.4, -2.0, 5.0) == (0.5, True)  # one reach: the step as given, the midpoints for the fit
    assert _candidate_step(0.5, 1.0, 5.0, -2.0, 20.0) == (0.5, False)  # Tsukuba's 5 px: as given
    assert _candidate_step(0.5, 1.0, 0.4, -2.0, 80.0) == (0.5, False)  # over 128 candidates: no midpoints
    assert _candidate_step(0.5, 5.0, 20.0, -2.0, 60.0) == (0.5, False)  # large shifts (Middlebury): as given
    step, interleave = _candidate_step(0.5, 7.0, 0.4, -2.0, 5.0)
    assert step == pytest.approx(0.5 / 7) and interleave  # down to px of the farthest view
    assert _candidate_step(0.5, 7.0, 1.5, -2.0, 5.0)[0] == pytest.approx(0.5 / 3)  # 4 px / 1.5 px, rounded up
    assert _candidate_step(0.5, 7.0, 0.4, -2.0, 30.0) == (pytest.approx(0.5 / 2), True)  # at most 128 candidates
    assert _candidate_step(0.5, 2.0 + 1e-12, 0.4, -2.0, 5.0)[0] == 0.25  # rounding of the positions: whole divisions
    assert _candidate_step(0.5, 7.0, float("nan"), -2.0, 5.0) == (0.5, False)  # no field to measure the shift: as given


def test_both_sides_compete_only_where_the_sides_reach_unequally():
    assert _both_sides(np.array([-1.0, 0.0, 1.0]), 1, 1.0) is None
    assert _both_sides(np.array([-2.0, -1.0, 0.0, 1.0, 2.0]), 2, 1.0) is None
    assert _both_sides(np.array([0.0, 1.0, 2.0]), 0, 1.0) is None  # one side: the plain cost
    t = np.array([-1.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    w0, w1, penalty, extra = _both_sides(t, 1, 2.0)
    assert (w0, w1) == (pytest.approx(1 / 6), pytest.approx(5 / 6))  # the mean over all views
    assert penalty == pytest.approx(0.1 * (1.0 - 1.0 / 5.0) * 2.0)
    assert extra == 0.0  # the scene's shift unknown
    assert _both_sides(t, 1, 2.0, shift_px=30.0)[2:] == (penalty, 0.0)  # Middlebury's shifts: the plain penalty
    # the nearer side (reach 1) shifts the scene by 0.5 px: the extra, where both sides see the point, is twice the penalty
    assert _both_sides(t, 1, 2.0, shift_px=0.5)[3] == pytest.approx(2.0 * penalty)
    # with two views on the near side, its farther one counts
    assert _both_sides(np.array([-2.0, -1.0, 0.0, 5.0]), 2, 2.0, shift_px=0.5)[3] == pytest.approx((2.0 - 1.0) * 0.1 * (1.0 - 2.0 / 5.0) * 2.0)
