"""Zero-crossing edge points and corner rejection (paper section 3.2)."""

import numpy as np
import pytest
from scipy.special import erf

from nfdepth.edges import corner_ratio, laplacian_zero_crossings, select_edge_points
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
    assert np.isnan(ratio[5, 5]) or ratio[5, 5] >= 0  # flat region: no gradient at all


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
