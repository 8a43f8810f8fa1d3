"""The cost volume's sub-sample fit where views shift the scene little (interleaved grids, stereo step 3c).

The equiangular fit of the winner is biased toward the candidates by an
amount that cycles with the phase of the true disparity between them (0.09
steps RMS, nearly a sine). Where the nearest view shifts the scene by less
than 4 px that is over a per cent, so there the midpoints between the
candidates join the volume and the fit averages the two grids' estimates,
whose sines cancel. Measured numbers (before -> now) are in each test.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from test_stereo_uneven_rows import _row_scores
from textured_planes import slanted_plane_views

from nfdepth.stereo import static_stereo


def _phase_bias(d0_px, step_px=0.5, phases=12):
    """Median error of the dense map of a fronto-parallel textured plane at ``phases`` disparities between two candidates."""
    bias = []
    for k in range(phases):
        d0 = d0_px + step_px * k / phases
        views, truth = slanted_plane_views(d0, 0.0, noise=0.5)
        r = static_stereo(views, reference=1, cost_step_px=step_px)
        d = r.disparity[10:-10, 10:-10]
        ok = np.isfinite(d)
        assert ok.mean() > 0.95
        bias.append(np.median(d[ok] - truth[10:-10, 10:-10][ok]))
    return np.asarray(bias)


def test_the_interleaved_fit_cancels_the_pixel_locking_bias():
    """Plane at 3-3.5 px per view (below the 4 px rule): RMS bias 0.046 -> 0.007 px, max 0.067 -> 0.014 px."""
    bias = _phase_bias(3.0)
    assert np.sqrt(np.mean(bias**2)) < 0.015
    assert np.abs(bias).max() < 0.03


def test_large_shifts_keep_the_plain_grid():
    """At 6 px per view the rule does not apply: the plain fit's bias (0.045 px RMS, 0.09 steps) is left as it was."""
    bias = _phase_bias(6.0)
    assert 0.03 < np.sqrt(np.mean(bias**2)) < 0.06


@pytest.mark.parametrize(
    ("along", "noise", "most_median"),
    [
        ((-1.0, 1.0), 1.0, 0.01),  # 3.03 % -> 0.42 %
        ((-0.5, 0.5), 1.0, 0.03),  # 7.35 % -> 1.37 % (>10 % off: 12.7 % -> 4.4 %)
        ((-1.0, 1.0), 4.0, 0.018),  # 2.07 % -> 1.33 %
        ((-2.0, -1.0, 1.0, 2.0), 1.0, 0.006),  # 1.13 % -> 0.20 %
    ],
)
def test_rows_with_small_shifts_are_precise(along, noise, most_median):
    """The exact board-and-wall scene (1.7-2.5 px per unit of position): equal rows whose views shift it by 1-5 px."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "no edge points": the isotropic texture is all corners for the edge test
        median, wrong, cover, z = _row_scores(along, noise)
    assert cover > 0.99
    assert median < most_median
    assert wrong < 0.05
    assert 0.3 < z < 1.5  # measured 0.47-0.85
