"""Static stereo with x and y baselines together (nfdepth.xy_stereo)."""

import re
import warnings

import numpy as np
import pytest
from textured_planes import slanted_plane_views

import nfdepth
from nfdepth.depth import Reason
from nfdepth.stereo import StereoResult, static_stereo
from nfdepth.xy_stereo import XYStereoResult, fuse_axes, static_stereo_xy

# wave normals within 0.3 rad of the column (image y) axis: edges within 17 degrees
# of horizontal, i.e. nearly parallel to the row's baseline
HORIZONTAL_EDGES = (np.pi / 2 - 0.3, np.pi / 2 + 0.3)


def _inner(shape, margin=12):
    m = np.zeros(shape, bool)
    m[margin:-margin, margin:-margin] = True
    return m


def _result(d, s, reason=None, edge=None):
    d = np.asarray(d, np.float32)
    reason = np.where(np.isfinite(d), Reason.OK, Reason.NOT_EDGE).astype(np.uint8) if reason is None else np.asarray(reason, np.uint8)
    edge = np.isfinite(d) if edge is None else edge
    return StereoResult(d, np.asarray(s, np.float32), edge, reason, 1, 0.0)


# ----------------------------------------------------------------- fuse_axes


def test_fusion_is_the_inverse_variance_mean():
    """Two consistent measurements (chi^2 <= 1): the weighted least-squares mean and its std."""
    row = _result([[2.0, 2.0]], [[0.1, 0.3]])
    col = _result([[2.1, 2.2]], [[0.2, 0.3]])
    d, s, reason, count, conflict = fuse_axes(row, col)
    w1, w2 = 1 / 0.01, 1 / 0.04
    assert d[0, 0] == pytest.approx((2.0 * w1 + 2.1 * w2) / (w1 + w2), rel=1e-6)
    assert s[0, 0] == pytest.approx((w1 + w2) ** -0.5, rel=1e-6)
    assert d[0, 1] == pytest.approx(2.1, rel=1e-6)  # equal weights: the plain mean
    assert s[0, 1] == pytest.approx(0.3 / np.sqrt(2), rel=1e-6)
    assert (reason == Reason.OK).all() and (count == 2).all() and not conflict.any()


def test_fusion_widens_the_std_when_the_axes_disagree_beyond_their_errors():
    """chi^2 = (dx - dy)^2 / (sx^2 + sy^2) = 4 scales the variance by 4 (std x 2)."""
    row = _result([[3.0]], [[0.1]])
    col = _result([[3.0 + 2 * np.sqrt(0.02)]], [[0.1]])
    _, s, reason, _, conflict = fuse_axes(row, col)
    assert s[0, 0] == pytest.approx(2.0 * 0.1 / np.sqrt(2), rel=1e-5)
    assert reason[0, 0] == Reason.OK and not conflict.any()


def test_fusion_refuses_a_pixel_whose_axes_disagree_in_pixels_and_in_std():
    row = _result([[3.0, 3.0, 3.0]], [[0.05, 0.5, 0.05]])
    col = _result([[4.0, 4.0, 3.3]], [[0.05, 0.5, 0.05]])
    d, s, reason, count, conflict = fuse_axes(row, col)
    # 1 px apart at 14 sigma: refused; 1 px at 1.4 sigma: kept; 0.3 px at 4 sigma: kept (below 0.5 px)
    assert conflict.tolist() == [[True, False, False]]
    assert reason[0, 0] == Reason.UNCERTAIN and np.isnan(d[0, 0]) and np.isnan(s[0, 0])
    assert np.isfinite(d[0, 1:]).all() and (count == 2).all()
    assert not fuse_axes(row, col, max_axis_disagreement_px=np.inf)[4].any()


def test_fusion_keeps_a_pixel_measured_on_one_axis_as_it_is():
    row = _result([[2.5, np.nan]], [[0.1, np.nan]], reason=[[Reason.OK, Reason.UNDETERMINABLE]])
    col = _result([[np.nan, 4.0]], [[np.nan, 0.2]], reason=[[Reason.UNDETERMINABLE, Reason.OK]])
    d, s, reason, count, _ = fuse_axes(row, col)
    assert d.tolist() == [[2.5, 4.0]] and s[0].tolist() == pytest.approx([0.1, 0.2])
    assert (reason == Reason.OK).all() and count.tolist() == [[1, 1]]


def test_fusion_reports_the_most_specific_reason_where_neither_axis_measured():
    codes = [Reason.NOT_EDGE, Reason.UNDETERMINABLE, Reason.UNCERTAIN, Reason.CORNER, Reason.NO_DATA]
    other = [Reason.UNDETERMINABLE, Reason.NOT_EDGE, Reason.UNDETERMINABLE, Reason.NOT_EDGE, Reason.UNDETERMINABLE]
    nan = np.full((1, 5), np.nan)
    _, _, reason, count, _ = fuse_axes(_result(nan, nan, reason=[codes]), _result(nan, nan, reason=[other]))
    assert reason.tolist() == [[Reason.UNDETERMINABLE, Reason.UNDETERMINABLE, Reason.UNCERTAIN, Reason.CORNER, Reason.NO_DATA]]
    assert (count == 0).all()


def test_fusion_of_zero_stds_is_the_plain_mean():
    """noise_std=0 on noise-free input can give std 0 on both axes: no division by zero."""
    d, s, reason, _, _ = fuse_axes(_result([[1.0]], [[0.0]]), _result([[1.2]], [[0.0]]), max_axis_disagreement_px=np.inf)
    assert d[0, 0] == pytest.approx(1.1) and np.isfinite(s[0, 0]) and reason[0, 0] == Reason.OK


# ------------------------------------------------------------- static_stereo_xy


def test_a_column_measures_the_edges_a_row_cannot():
    """Texture whose edges lie within 17 degrees of horizontal: the row sees them move
    along their normal with weight cos^2 (small) or not at all (below min_cos); the column
    with sin^2. Measured: row 428 edge points at a median error 0.049 px, fused 2650 at
    0.015 px; dense median error 0.093 (row) -> 0.026 px (fused)."""
    row, col, truth = slanted_plane_views(3.0, 0.0125, noise=2.0, min_wavelength_px=4.0, angles_rad=HORIZONTAL_EDGES, column=True)
    inner = _inner(truth.shape)
    edges = static_stereo_xy(row, col, row_reference=1, column_reference=1, noise_std=2.0, edges_only=True)
    assert isinstance(edges, XYStereoResult)
    ok_row = np.isfinite(edges.row.disparity) & inner
    ok = np.isfinite(edges.disparity) & inner
    assert ok.sum() > 4 * ok_row.sum()
    err = np.abs(edges.disparity - truth)
    assert np.median(err[ok]) < 0.03
    assert np.median(err[ok]) < 0.5 * np.median(np.abs(edges.row.disparity - truth)[ok_row])
    assert np.percentile(err[ok], 99) < 0.25
    # the horizontal edges the row refuses (edge parallel to its baseline) now have depth
    undeterminable = (edges.row.reason == Reason.UNDETERMINABLE) & inner
    assert undeterminable.sum() > 100
    assert np.mean(np.isfinite(edges.disparity[undeterminable])) > 0.8
    dense = static_stereo_xy(row, col, row_reference=1, column_reference=1, noise_std=2.0)
    both = np.isfinite(dense.disparity) & np.isfinite(dense.row.disparity) & inner
    assert both.sum() > 0.95 * inner.sum()
    assert np.median(np.abs(dense.disparity - truth)[both]) < 0.5 * np.median(np.abs(dense.row.disparity - truth)[both])


def test_fused_uncertainty_shrinks_and_stays_calibrated():
    """Isotropic texture, both axes informative: where both measured a point and agree, the
    fused std is below either axis's, about 1/sqrt(2) of it where the two are alike
    (measured median std at the edge points 0.021 px against 0.026 / 0.031), and the
    median |error| / std stays near 0.674 (measured 0.62-0.63)."""
    row, col, truth = slanted_plane_views(3.0, 0.0125, noise=2.0, min_wavelength_px=4.0, column=True)
    inner = _inner(truth.shape)
    for edges_only in (True, False):
        r = static_stereo_xy(row, col, row_reference=1, column_reference=1, noise_std=2.0, edges_only=edges_only)
        both = (r.axis_count == 2) & np.isfinite(r.disparity) & inner
        assert both.sum() > (1000 if edges_only else 0.9 * inner.sum())
        sx, sy, s = r.row.uncertainty[both], r.column.uncertainty[both], r.uncertainty[both]
        consistent = np.abs(r.row.disparity - r.column.disparity)[both] ** 2 <= sx**2 + sy**2
        assert (s[consistent] <= 1.0001 * np.minimum(sx, sy)[consistent]).all()
        alike = consistent & (np.abs(np.log(sx / sy)) < np.log(1.25))
        assert alike.sum() > 100
        assert np.median(s[alike] / np.minimum(sx, sy)[alike]) < 0.8
        z = np.abs(r.disparity - truth)[both] / r.uncertainty[both]
        assert 1 / 1.5 <= np.median(z) / 0.674 <= 1.5
        assert np.median(np.abs(r.disparity - truth)[both]) <= 1.05 * min(
            np.median(np.abs(r.row.disparity - truth)[both]), np.median(np.abs(r.column.disparity - truth)[both])
        )


def test_the_pyramid_seen_by_a_row_and_a_column():
    """The paper's still pyramid from a plus-shaped rig (baseline 2 along X and along Y):
    every edge point either axis measured is in the fused output, within 0.015 px of the
    true disparity f B / Z (measured: max 0.010 px, 328 points against 314 / 317)."""
    from nfdepth.synthetic import (
        paper_camera,
        paper_pyramid,
        static_sequence,
        surface_depth_at,
    )

    cam, poly = paper_camera(), paper_pyramid()
    row = static_sequence(poly, cam, n_views=3, camera_step=(2.0, 0.0, 0.0), dtype=np.float32)
    col = static_sequence(poly, cam, n_views=3, camera_step=(0.0, 2.0, 0.0), dtype=np.float32)
    r = static_stereo_xy(row.frames, col.frames, row_reference=1, column_reference=1, edges_only=True)
    rows, cols = np.mgrid[0:200, 0:200]
    truth = cam.focal_px * 2.0 / surface_depth_at(poly, cam, rows, cols)
    on = np.isfinite(truth)
    fused = np.isfinite(r.disparity)
    either = (np.isfinite(r.row.disparity) | np.isfinite(r.column.disparity)) & ~r.conflict
    assert (fused == either).all()
    assert (fused & on).sum() > max((np.isfinite(r.row.disparity) & on).sum(), (np.isfinite(r.column.disparity) & on).sum())
    assert np.abs(r.disparity - truth)[fused & on].max() < 0.015
    z = r.depth(focal_px=cam.focal_px, baseline=2.0)
    assert np.nanmin(z[on]) > 190 and np.nanmax(z[on]) < 410


def test_each_axis_is_static_stereo_along_it():
    """The row's and the column's own results are those of static_stereo along x and y,
    bit for bit, in the reference image's orientation."""
    row, col, _ = slanted_plane_views(2.0, 0.0, shape=(64, 80), noise=1.0, column=True)
    r = static_stereo_xy(row, col, row_reference=1, column_reference=1, noise_std=1.0)
    a = static_stereo(row, reference=1, noise_std=1.0)
    b = static_stereo(col, reference=1, axis="y", noise_std=1.0)
    for mine, ref in ((r.row, a), (r.column, b)):
        assert mine.disparity.shape == (64, 80)
        np.testing.assert_array_equal(mine.disparity, ref.disparity)
        np.testing.assert_array_equal(mine.uncertainty, ref.uncertainty)


def test_public_name():
    assert nfdepth.static_stereo_xy is static_stereo_xy
    assert nfdepth.XYStereoResult is XYStereoResult


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"column_reference": 0}, ValueError, "must be the same image"),
        ({"row_reference": 3}, ValueError, r"row_reference must be a view index in 0..2"),
        ({"column_reference": True}, TypeError, "column_reference must be an int"),
        ({"axis": "y"}, TypeError, "axis belongs to one axis"),
        ({"positions": [0, 1, 2]}, TypeError, "positions belongs to one axis"),
        ({"column_positions": [0, 1]}, ValueError, "^column: positions"),
        ({"max_axis_disagreement_px": 0}, ValueError, "max_axis_disagreement_px"),
        ({"max_axis_disagreement_px": float("nan")}, ValueError, "max_axis_disagreement_px"),
        ({"sigma_px": -1}, ValueError, "^row: sigma_px"),
    ],
)
def test_bad_input(kwargs, exc, match):
    row, col, _ = slanted_plane_views(2.0, 0.0, shape=(48, 48), noise=1.0, column=True)
    args = {"row_reference": 1, "column_reference": 1} | kwargs
    with pytest.raises(exc, match=match):
        static_stereo_xy(row, col, **args)


def test_views_of_another_size_are_refused():
    row, col, _ = slanted_plane_views(2.0, 0.0, shape=(48, 48), noise=1.0, column=True)
    small = [v[:40] for v in col]
    with pytest.raises(ValueError, match="one size"):
        static_stereo_xy(row, small, row_reference=1, column_reference=1)


def test_without_the_cost_volume_there_is_no_search_range():
    """cost_volume=False: neither axis searches a range, so the fused result reports none;
    with it, the range holding both axes' ranges. The differential fields of a slanted
    plane (2-2.8 px, noise 1) fuse to the truth: measured median error 0.004 px, at most
    0.026 px, on every inner pixel (bounds 0.01 and 0.05 px)."""
    row, col, truth = slanted_plane_views(2.0, 0.01, shape=(64, 80), noise=1.0, column=True)
    r = static_stereo_xy(row, col, row_reference=1, column_reference=1, noise_std=1.0, cost_volume=False)
    assert r.search_range_px is None and r.row.search_range_px is None and r.column.search_range_px is None
    inner = _inner(truth.shape)
    ok = np.isfinite(r.disparity) & inner
    assert ok.sum() > 0.95 * inner.sum()
    err = np.abs(r.disparity - truth)[ok]
    assert np.median(err) < 0.01 and err.max() < 0.05
    searched = static_stereo_xy(row, col, row_reference=1, column_reference=1, noise_std=1.0)
    (a, b), (c, d) = searched.row.search_range_px, searched.column.search_range_px
    assert searched.search_range_px == (min(a, c), max(b, d))


def test_fusion_refuses_maps_of_two_shapes():
    with pytest.raises(ValueError, match=r"^the row's and the column's maps must have one shape, got \(1, 2\) and \(2, 1\)$"):
        fuse_axes(_result([[1.0, 2.0]], [[0.1, 0.1]]), _result([[1.0], [2.0]], [[0.1], [0.1]]))


# ------------------------------------------------------------------ the CLI


@pytest.fixture
def cross_files(tmp_path):
    import cv2

    row, col, truth = slanted_plane_views(3.0, 0.0, shape=(64, 96), noise=1.0, angles_rad=HORIZONTAL_EDGES, column=True)
    names = {}
    for label, views in (("row", row), ("col", col)):
        for k, v in enumerate(views):
            path = tmp_path / (f"{label}{k}.png" if (label, k) != ("col", 1) else "row1.png")
            cv2.imwrite(str(path), np.round(np.clip(v, 0, 255) * 256).astype(np.uint16))
            names[label, k] = str(path)
    return names, truth


def test_cli_stereo_with_a_column(cross_files, tmp_path, capsys):
    """`nfdepth stereo ROW... --column COL...` writes the fused map, the same as the library on the same files."""
    from nfdepth.cli import main
    from nfdepth.io import read_image, read_pfm

    names, truth = cross_files
    row = [names["row", k] for k in range(3)]
    col = [names["col", 0], names["row", 1], names["col", 2]]
    out, std = tmp_path / "d.pfm", tmp_path / "s.pfm"
    code = main(["stereo", *row, "--column", *col, "--edges-only", "--out", str(out), "--uncertainty", str(std)])
    printed, err = capsys.readouterr()
    assert code == 0, err
    assert "row and column fused" in printed
    lib = static_stereo_xy([read_image(p) for p in row], [read_image(p) for p in col], row_reference=1, column_reference=1, edges_only=True)
    np.testing.assert_array_equal(read_pfm(out), lib.disparity)
    np.testing.assert_array_equal(read_pfm(std), lib.uncertainty)
    got = read_pfm(out)
    ok = np.isfinite(got) & _inner(got.shape, margin=8)
    assert ok.sum() > 3 * (np.isfinite(lib.row.disparity) & _inner(got.shape, margin=8)).sum()
    assert np.median(np.abs(got - truth)[ok]) < 0.05


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--column", "COL0", "ROW0", "COL2"], "must be the same image"),
        (["--column", "COL0", "ROW1", "COL2", "--axis", "y"], "--column needs the main views to be the horizontal row"),
        (["--column-reference", "1"], "need --column"),
        (["--column", "COL0", "ROW1", "--column-reference", "2"], "--column-reference must index one of the 2 column views"),
        (["--column", "COL0", "ROW1", "COL2", "--column-positions", "0", "1"], "column: positions must hold one number per view"),
        (["--column", "COL0"], "--column needs at least 2 views"),
    ],
)
def test_cli_stereo_column_errors(cross_files, tmp_path, capsys, extra, message):
    from nfdepth.cli import main

    names, _ = cross_files
    subst = {"COL0": names["col", 0], "COL2": names["col", 2], "ROW0": names["row", 0], "ROW1": names["row", 1]}
    out = tmp_path / "d.pfm"
    code = main(["stereo", *(names["row", k] for k in range(3)), *(subst.get(a, a) for a in extra), "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 2
    assert message in err and err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


def test_cli_fill_writes_a_complete_map_and_marks_the_filled_pixels(cross_files, tmp_path, capsys):
    """`--fill`: every pixel of a line with a value gets one; `--fill-mask` says which were
    filled (1) or measured (0); the uncertainty stays NaN at the filled ones."""
    from nfdepth.cli import main
    from nfdepth.io import read_image, read_pfm

    names, _ = cross_files
    row = [names["row", k] for k in range(3)]
    out, std, mask = tmp_path / "d.pfm", tmp_path / "s.pfm", tmp_path / "m.npy"
    # the holes: the part of the slanted scene beyond a given range (nearer than 2.98 px)
    code = main(["stereo", *row, "--disparity-range", "1", "2.98", "--fill", "--fill-mask", str(mask), "--out", str(out), "--uncertainty", str(std)])
    printed, err = capsys.readouterr()
    assert code == 0, err
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lib = static_stereo([read_image(p) for p in row], reference=1, disparity_range_px=(1.0, 2.98))
    filled, where = lib.filled()
    got, m, s = read_pfm(out), np.load(mask), read_pfm(std)
    np.testing.assert_array_equal(got, filled)
    lines = np.isfinite(lib.disparity).any(axis=1)
    assert lines.sum() > 0.6 * lines.size
    assert np.isfinite(got[lines]).all() and np.isnan(got[~lines]).all() and where.sum() > 0.02 * got.size
    np.testing.assert_array_equal(m, np.where(np.isfinite(got), where, np.nan).astype(np.float32))
    measured = np.isfinite(lib.disparity)
    assert np.isnan(s[where]).all()
    np.testing.assert_array_equal(s[measured], lib.uncertainty[measured])
    assert f"{int(where.sum())} filled" in printed
    code = main(["stereo", *row, "--fill-mask", str(tmp_path / "m2.npy"), "--out", str(tmp_path / "d2.pfm")])
    _, err = capsys.readouterr()
    assert code == 2 and "--fill-mask needs --fill" in err


def test_cli_column_positions_from_the_rig(cross_files, tmp_path, capsys):
    """`[stereo] column_positions` reaches the fusion when --column is given, contradicting
    --column-positions is an error, and without --column the row runs alone."""
    from nfdepth.cli import main
    from nfdepth.io import read_image, read_pfm

    names, _ = cross_files
    rig = tmp_path / "rig.toml"
    rig.write_text('[camera]\nfocal_px = 100.0\nwidth_px = 96\nheight_px = 64\n\n[stereo]\nbaseline = 1.0\naxis = "x"\ncolumn_positions = [0.0, 1.0, 2.5]\n')
    row = [names["row", k] for k in range(3)]
    col = [names["col", 0], names["row", 1], names["col", 2]]
    out = tmp_path / "d.pfm"
    code = main(["stereo", *row, "--column", *col, "--rig", str(rig), "--edges-only", "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 0, err
    # the column's views lie at 0, 1, 2: 2.5 does not fit them, and the run says so
    assert re.search(r"warning: the views do not fit the positions given: paired with the reference view 1 alone, .* at view 0 1\.[12]\d, view 2 0\.[78]\d times", err), err
    with pytest.warns(UserWarning, match="the views do not fit the positions given"):
        lib = static_stereo_xy(
            [read_image(p) for p in row], [read_image(p) for p in col], row_reference=1, column_reference=1, column_positions=[0.0, 1.0, 2.5], edges_only=True
        )
    np.testing.assert_array_equal(read_pfm(out), lib.depth(focal_px=100.0, baseline=1.0).astype(np.float32))
    code = main(["stereo", *row, "--column", *col, "--column-positions", "0", "1", "2", "--rig", str(rig), "--out", str(tmp_path / "e.pfm")])
    _, err = capsys.readouterr()
    assert code == 2 and "contradicts the rig file's column_positions" in err
    code = main(["stereo", *row, "--rig", str(rig), "--edges-only", "--out", str(tmp_path / "f.pfm")])
    printed, err = capsys.readouterr()
    assert code == 0, err
    assert "fused" not in printed
    assert err == "nfdepth: warning: the rig file's column_positions are for a column of views, and no --column is given: the row is measured alone\n"


def test_a_row_and_a_column_of_misstated_spacing_warn():
    """The pyramid's column given at twice its spacing (``column_positions`` 0, 2, 4 against the row's 0, 1, 2 for
    equal baselines), or at 1.5 times: the column's disparities come out at half (two thirds) of the row's, which
    one scene cannot give, and the fusion refused what disagreed without a word (Art: 7.8 % of the pixels kept).
    Now a warning names the column's median scale against the row's; with the spacing right (1.000) none."""
    from nfdepth.synthetic import paper_camera, paper_pyramid, static_sequence

    cam, poly = paper_camera(), paper_pyramid()
    row = static_sequence(poly, cam, n_views=3, camera_step=(2.0, 0.0, 0.0), dtype=np.float32)
    col = static_sequence(poly, cam, n_views=3, camera_step=(0.0, 2.0, 0.0), dtype=np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        static_stereo_xy(row.frames, col.frames, row_reference=1, column_reference=1)
    for positions, scale in (([0.0, 2.0, 4.0], r"0\.5"), ([0.0, 1.5, 3.0], r"0\.667")):
        with pytest.warns(UserWarning, match=rf"^the column's disparities are a median {scale} times the row's at the \d+ pixels both measure"):
            static_stereo_xy(row.frames, col.frames, row_reference=1, column_reference=1, column_positions=positions)
    # 10 % off: every pixel both lines measure was refused for disagreeing (0.6 % of a textured scene kept), and the
    # factor of 1.15 this check had said nothing; 5 % off biased the fused map by 2.6 %
    for positions, scale in (([0.0, 1.1, 2.2], r"0\.9\d\d"), ([0.0, 1.05, 2.1], r"0\.9[5-6]\d")):
        with pytest.warns(UserWarning, match=rf"^the column's disparities are a median {scale} times the row's at the \d+ pixels both measure \(\d+ % refused"):
            static_stereo_xy(row.frames, col.frames, row_reference=1, column_reference=1, column_positions=positions)


def test_a_warning_both_axes_give_is_said_once():
    """A range that misses the pyramid, given to both lines: each axis's static stereo gives the same lost-scene
    warning, which was printed twice, word for word; now once."""
    from nfdepth.synthetic import paper_camera, paper_pyramid, static_sequence

    cam, poly = paper_camera(), paper_pyramid()
    row = static_sequence(poly, cam, n_views=3, camera_step=(2.0, 0.0, 0.0), dtype=np.float32)
    col = static_sequence(poly, cam, n_views=3, camera_step=(0.0, 2.0, 0.0), dtype=np.float32)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        static_stereo_xy(row.frames, col.frames, row_reference=1, column_reference=1, disparity_range_px=(5.0, 9.0))
    messages = [str(w.message) for w in caught]
    assert len(messages) == 1 and "no unique match between disparities 5 and 9 px" in messages[0], messages


def test_an_axis_warning_keeps_its_class_and_attributes():
    """The axes' warnings were said again from their text and category: a NoEdgePointsWarning (whose message is
    built from its parts) came out as "no edge points: no edge points: ..." without its rule. It is said as it
    came, once."""
    flat = [np.full((48, 64), 0.5, np.float32)] * 3
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        static_stereo_xy(flat, flat, row_reference=1, column_reference=1)
    (said,) = [w.message for w in caught if isinstance(w.message, nfdepth.NoEdgePointsWarning)]
    assert str(said).startswith("no edge points: the images are textureless (") and str(said).count("no edge points") == 1
    assert said.rule == "zero crossing"


def test_the_fusion_does_not_depend_on_the_unit_of_the_positions():
    """The pyramid's column stated at twice its spacing: with positions in steps (0, 1, 2 and 0, 2, 4) the fusion
    refuses what disagrees and warns (median scale 0.5); the same positions in hundredths (0, 100, 200 and 0, 200,
    400) were fused in silence, since ``max_axis_disagreement_px`` and the warning's 0.25 px floor were compared
    with disparities per unit of position (0.005-0.01 per hundredth, never 0.5 apart). Now both compare px at the
    smallest neighbour spacing: the disparities and stds come out 100 times smaller, everything else the same."""
    from nfdepth.synthetic import paper_camera, paper_pyramid, static_sequence

    cam, poly = paper_camera(), paper_pyramid()
    row = static_sequence(poly, cam, n_views=3, camera_step=(2.0, 0.0, 0.0), dtype=np.float32)
    col = static_sequence(poly, cam, n_views=3, camera_step=(0.0, 2.0, 0.0), dtype=np.float32)
    results, said = [], []
    for unit in (1.0, 100.0):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            r = static_stereo_xy(row.frames, col.frames, row_reference=1, column_reference=1, row_positions=[0.0, unit, 2 * unit], column_positions=[0.0, 2 * unit, 4 * unit])
        results.append(r)
        said.append([str(w.message) for w in caught])
    a, b = results
    assert len(said[0]) == 1 and said[0][0].startswith("the column's disparities are a median 0.5 times the row's"), said[0]
    assert said[1] == said[0]
    assert a.conflict.sum() > 100
    np.testing.assert_array_equal(b.conflict, a.conflict)
    np.testing.assert_array_equal(b.reason, a.reason)
    # float32 disparities per unit of position: 100 times smaller, to float32 rounding
    np.testing.assert_allclose(100.0 * b.disparity, a.disparity, rtol=1e-5, equal_nan=True)
    np.testing.assert_allclose(100.0 * b.uncertainty, a.uncertainty, rtol=1e-5, equal_nan=True)


def test_fuse_axes_counts_the_disagreement_in_px_at_the_spacing():
    """Disparities per unit of position 0.03 and 0.04 at a spacing of 100 units are 3 and 4 px: refused (1 px apart at
    14 std); with the default spacing of 1 they were 0.01 px apart and kept."""
    row = _result([[0.03]], [[0.0005]])
    col = _result([[0.04]], [[0.0005]])
    assert not fuse_axes(row, col)[4].any()
    d, s, reason, _, conflict = fuse_axes(row, col, spacing=100.0)
    assert conflict.tolist() == [[True]] and reason[0, 0] == Reason.UNCERTAIN and np.isnan(d[0, 0]) and np.isnan(s[0, 0])
    for bad, exc in ((0.0, ValueError), (float("nan"), ValueError), ("1", TypeError)):
        with pytest.raises(exc, match="^spacing must be a positive finite number"):
            fuse_axes(row, col, spacing=bad)
