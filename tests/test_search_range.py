"""The cost volume's search range: the coarse search (stereo step 3d) and ``disparity_range_px``."""

import re
import warnings

import cv2
import numpy as np
import pytest

from nfdepth import stereo
from nfdepth.stereo import static_stereo
from nfdepth.xy_stereo import static_stereo_xy


def _texture(shape, seed):
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.uniform(0, 255, shape).astype(np.float32), (0, 0), 1.5)


def _moved(img, shift_px):
    """``out(r, c) = img(r, c - shift_px)``, linear interpolation, border reflected."""
    h, w = img.shape
    m = np.float32([[1, 0, shift_px], [0, 1, 0]])
    return cv2.warpAffine(img, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


def _layers(shape, d_background, d_foreground, box):
    """Three views (positions -1, 0, 1) of a textured background and a textured rectangle ``box`` in front of it."""
    background, foreground = _texture(shape, 1), _texture(shape, 2)
    r0, r1, c0, c1 = box
    inside = np.zeros(shape, np.float32)
    inside[r0:r1, c0:c1] = 1.0
    views = []
    for t in (-1, 0, 1):
        m = _moved(inside, -t * d_foreground)
        views.append(_moved(background, -t * d_background) * (1 - m) + _moved(foreground, -t * d_foreground) * m)
    return views


def _plane(shape, d, seed=0):
    base = _texture(shape, seed)
    return [_moved(base, -t * d) for t in (-1, 0, 1)]


SHAPE = (240, 320)
BOX = (60, 180, 106, 213)


def _foreground(r):
    r0, r1, c0, c1 = BOX
    return r.disparity[r0 + 5 : r1 - 5, c0 + 5 : c1 - 5]


def test_a_foreground_far_in_front_of_its_background_is_found(monkeypatch):
    """A rectangle at 40 px in front of a background at 8 px: the coarse-to-fine field
    follows the background only, and without the coarse search every foreground value
    that passes is wrong (measured: 24 % of them, all off by more than 1 px)."""
    views = _layers(SHAPE, 8.0, 40.0, BOX)
    r = static_stereo(views, reference=1)
    fg = _foreground(r)
    assert np.isfinite(fg).mean() > 0.99
    assert np.median(np.abs(fg[np.isfinite(fg)] - 40.0)) < 0.02
    assert r.search_range_px[0] <= 8.0 and r.search_range_px[1] >= 40.0
    bg = r.disparity[5 : BOX[0] - 5, 70:-70]
    assert np.isfinite(bg).mean() > 0.99 and np.median(np.abs(bg[np.isfinite(bg)] - 8.0)) < 0.02
    # the same without the search: the test exercises it
    monkeypatch.setattr(stereo, "_RETRY_SHARE", 1.0)
    without = _foreground(static_stereo(views, reference=1))
    ok = np.isfinite(without)
    assert ok.mean() < 0.5 and not (np.abs(without[ok] - 40.0) < 1.0).any()


def test_a_whole_scene_beyond_the_pyramid_reach():
    """30 px per view step in 120 x 160 px views (three levels): was 0.1 % valid, all wrong."""
    r = static_stereo(_plane((120, 160), 30.0), reference=1)
    inner = r.disparity[5:-5, 65:-5]
    assert np.isfinite(inner).mean() > 0.99
    assert np.median(np.abs(inner - 30.0)) < 0.02


def test_the_coarse_search_leaves_a_scene_it_agrees_with_alone(monkeypatch):
    """Where the coarse-to-fine range holds the scene the search changes nothing (bit for bit)."""
    views = _layers((120, 160), 6.0, 12.0, (30, 90, 50, 110))
    r = static_stereo(views, reference=1)
    monkeypatch.setattr(stereo, "_RETRY_SHARE", -1.0)  # search every time
    again = static_stereo(views, reference=1)
    np.testing.assert_array_equal(r.disparity, again.disparity)
    np.testing.assert_array_equal(r.uncertainty, again.uncertainty)
    assert r.search_range_px == again.search_range_px


def test_a_periodic_texture_keeps_the_coarse_to_fine_result(monkeypatch):
    """A texture repeating every 16 px, 1 px per step: the search sees the aliases and widens
    the range, where they make most pixels ambiguous; the first, unique result is kept."""
    tile = np.tile(_texture((48, 16), 3), (1, 4))
    views = [np.roll(tile, -k, axis=1).astype(np.float32) for k in range(3)]
    calls = []
    real = stereo._widen_by_coarse_search

    def spy(lo, hi, *args, **kwargs):
        calls.append(real(lo, hi, *args, **kwargs))
        return calls[-1]

    monkeypatch.setattr(stereo, "_RETRY_SHARE", -1.0)
    monkeypatch.setattr(stereo, "_widen_by_coarse_search", spy)
    r = static_stereo(views, reference=1)
    assert calls and calls[0][1] - calls[0][0] > 16  # the widened range holds an alias
    ok = np.isfinite(r.disparity[:, 8:-8])
    assert ok.mean() > 0.9
    assert np.median(np.abs(r.disparity[:, 8:-8][ok] - 1.0)) < 0.02
    assert r.search_range_px[1] - r.search_range_px[0] < 16


def test_a_wider_range_must_match_more_pixels_to_be_kept(monkeypatch):
    """The widened range of the coarse search replaces the first only when it leaves at least
    ``_RETRY_MIN_GAIN`` (1 %) of the textured pixels fewer unmatched: a smaller gain is aliasing or noise,
    not a part of the scene the first range missed."""
    views = _layers((120, 160), 6.0, 12.0, (30, 90, 50, 110))
    first = static_stereo(views, reference=1)
    real_search = stereo._search
    monkeypatch.setattr(stereo, "_RETRY_SHARE", -1.0)  # search every time
    monkeypatch.setattr(stereo, "_widen_by_coarse_search", lambda lo, hi, coarse: (lo, hi + 20.0))  # a wider range to retry
    for gain, kept in ((0.5 * stereo._RETRY_MIN_GAIN, False), (stereo._RETRY_MIN_GAIN, True)):
        shares = []

        def search(*args, gain=gain, shares=shares, **kwargs):
            out = real_search(*args, **kwargs)
            shares.append(out[4])
            if len(shares) == 2:  # the retry: as if it matched `gain` more of the textured pixels
                out = (*out[:4], shares[0] - gain, *out[5:])
            return out

        monkeypatch.setattr(stereo, "_search", search)
        r = static_stereo(views, reference=1, match_exposure=False)  # (the exposure pass would search too)
        assert len(shares) == 2
        assert (r.search_range_px != first.search_range_px) is kept
        if not kept:
            np.testing.assert_array_equal(r.disparity, first.disparity)


def test_an_explicit_range_reproduces_the_automatic_result():
    """``disparity_range_px`` set to the range the automatic search used gives the same maps
    without the pyramid (levels 1)."""
    views = _layers((120, 160), 6.0, 12.0, (30, 90, 50, 110))
    auto = static_stereo(views, reference=1)
    given = static_stereo(views, reference=1, disparity_range_px=auto.search_range_px)
    assert auto.levels > 1 and given.levels == 1
    assert given.search_range_px == auto.search_range_px
    for name in ("disparity", "uncertainty", "reason", "edge_mask"):
        np.testing.assert_array_equal(getattr(given, name), getattr(auto, name))


def test_an_explicit_range_finds_what_the_pyramid_cannot():
    """45 px per step in 60 x 80 px views is beyond the automatic search (half the coarsest width);
    a range given by the user holds it."""
    views = _plane((60, 80), 30.0)
    r = static_stereo(views, reference=1, disparity_range_px=(0, 40))
    inner = r.disparity[5:-5, 35:-5]
    assert np.isfinite(inner).mean() > 0.99 and np.median(np.abs(inner - 30.0)) < 0.02
    assert r.search_range_px == (0.0, 40.0)


def test_a_range_that_misses_the_scene_warns():
    views = _plane((60, 80), 20.0)
    with pytest.warns(UserWarning, match=r"100 % of the textured pixels have no unique match between disparities 0 and 10 px"):
        r = static_stereo(views, reference=1, disparity_range_px=(0, 10))
    assert np.isfinite(r.disparity).mean() < 0.05


@pytest.mark.parametrize(("shape", "d", "extra"), [((120, 160), 30.0, {}), ((240, 320), 45.0, {}), ((120, 160), 6.0, {"disparity_range_px": (0, 20)})])
def test_views_in_the_wrong_order_beyond_the_pyramid(shape, d, extra):
    """Reversed views whose motion the pyramid cannot follow (or outside a given range) give
    no negative disparities to warn about; the coarse search of the reversed order says it
    (measured: reversed 93-100 % unique, as given 11-23 %)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        static_stereo(_plane(shape, d)[::-1], reference=1, **extra)
    messages = [str(w.message) for w in caught]
    lost = [m for m in messages if "no unique match" in m]
    assert len(lost) == 1, messages
    assert re.search(r": are the views in the wrong order\? Reversed, (9\d|100) % .* match uniquely, against (1|2)\d % as given", lost[0]), lost[0]


@pytest.mark.parametrize(
    "views",
    [
        _plane((60, 80), 45.0),  # in order, beyond the search's reach (half the coarsest width)
        [_texture((120, 160), k) for k in (3, 4, 5)],  # unrelated images
    ],
    ids=["beyond-reach", "unrelated"],
)
def test_a_lost_scene_in_the_right_order_is_not_called_reversed(views):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        static_stereo(views, reference=1)
    messages = [str(w.message) for w in caught]
    assert any("the scene may lie outside that range" in m for m in messages), messages
    assert not any("wrong order" in m for m in messages), messages


@pytest.mark.parametrize(("d", "shape"), [(6.0, (120, 160)), (3.0, (120, 160)), (8.0, (240, 320))])
@pytest.mark.parametrize("axis", ["x", "y"])
def test_views_moving_across_the_baseline_are_named(d, shape, axis):
    """Views that move along the other axis (Tsukuba transposed, run along x, was 40 %
    valid and 99.8 % of that off by more than 1 px, silently): the coarse search across the
    baseline matches far more pixels uniquely (measured on the eight real scenes transposed:
    88-99 % against 43-79 % along it; in the right orientation 11-54 % fewer), and the
    warning names the axis. The right axis gives no warning."""
    views = _plane(shape, d)
    if axis == "y":  # views moving along x, given as a vertical row
        right = static_stereo([np.ascontiguousarray(v.T) for v in views], reference=1, axis="y")
    else:  # views moving along y, given as a horizontal row
        views = [np.ascontiguousarray(v.T) for v in views]
        right = static_stereo(views, reference=1, axis="y")
    assert right.valid.mean() > 0.9
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        wrong = static_stereo(views, reference=1, axis=axis)
    messages = [str(w.message) for w in caught]
    other = "y" if axis == "x" else "x"
    assert len(messages) == 1, messages
    assert re.search(
        rf"no unique match along {axis} \(UNCERTAIN\): do the views move along {other}\? A coarse search across the baseline matches (8\d|9\d|100) % .* Give axis='{other}' \(--axis {other}\)",
        messages[0],
    ), messages[0]
    assert wrong.valid.mean() < 0.3


def test_the_xy_result_spans_both_search_ranges():
    base = _texture((60, 80), 0)
    views = [_moved(base, -t * 4.0) for t in (-1, 0, 1)]
    column = [np.ascontiguousarray(_moved(np.ascontiguousarray(base.T), -t * 4.0).T) for t in (-1, 0, 1)]
    r = static_stereo_xy(views, column, row_reference=1, column_reference=1, disparity_range_px=(1, 9))
    assert r.row.search_range_px == r.column.search_range_px == r.search_range_px == (1.0, 9.0)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ((5, 5), "the smallest first"),
        ((9, 1), "the smallest first"),
        ((0, np.inf), "two finite numbers"),
        ((1,), "must be two numbers"),
        ("0 10", "must be two numbers"),
        ((0, "x"), "must be two numbers"),
    ],
)
def test_bad_ranges_are_refused(value, message):
    with pytest.raises(ValueError, match=f"disparity_range_px .*{message}"):
        static_stereo(_plane((40, 48), 2.0), reference=1, disparity_range_px=value)


def test_a_range_needs_the_cost_volume():
    with pytest.raises(ValueError, match="disparity_range_px needs cost_volume=True"):
        static_stereo(_plane((40, 48), 2.0), reference=1, disparity_range_px=(0, 4), cost_volume=False)


# ------------------------------------------------------------------ the CLI


@pytest.fixture
def plane_files(tmp_path):
    paths = []
    for k, v in enumerate(_plane((60, 80), 30.0)):
        path = tmp_path / f"v{k}.png"
        cv2.imwrite(str(path), np.round(np.clip(v, 0, 255) * 256).astype(np.uint16))
        paths.append(str(path))
    return paths


def test_cli_disparity_range(plane_files, tmp_path, capsys):
    """`nfdepth stereo ... --disparity-range MIN MAX` is the library's ``disparity_range_px``."""
    from nfdepth.cli import main
    from nfdepth.io import read_image, read_pfm

    out = tmp_path / "d.pfm"
    code = main(["stereo", *plane_files, "--disparity-range", "0", "40", "--out", str(out)])
    printed, err = capsys.readouterr()
    assert code == 0, err
    assert "searched 0..40 px" in printed and ", 1 level," in printed
    lib = static_stereo([read_image(p) for p in plane_files], reference=1, disparity_range_px=(0, 40))
    np.testing.assert_array_equal(read_pfm(out), lib.disparity)


def test_cli_cost_step(plane_files, tmp_path, capsys):
    """`nfdepth stereo ... --cost-step-px PX` is the library's ``cost_step_px`` (and changes the map)."""
    from nfdepth.cli import main
    from nfdepth.io import read_image, read_pfm

    out = tmp_path / "d.pfm"
    code = main(["stereo", *plane_files, "--cost-step-px", "1", "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 0, err
    views = [read_image(p) for p in plane_files]
    lib = static_stereo(views, reference=1, cost_step_px=1.0)
    np.testing.assert_array_equal(read_pfm(out), lib.disparity)
    default = static_stereo(views, reference=1)
    assert not np.array_equal(default.disparity, lib.disparity, equal_nan=True)


def test_cost_step_wider_than_the_found_range(plane_files):
    """A candidate step wider than half the range the pyramid found is an error that names the largest usable step."""
    import re
    import warnings

    from nfdepth.io import read_image

    views = [read_image(p) for p in plane_files]
    with pytest.raises(ValueError, match="is wider than half the search range the pyramid found") as info:
        static_stereo(views, reference=1, cost_step_px=1000.0)
    largest = float(re.search(r"at least three candidates, at most ([0-9.]+) px here", str(info.value)).group(1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # three candidates leave most matches ambiguous (a warning says so)
        static_stereo(views, reference=1, cost_step_px=largest)  # the step it names is accepted
    with pytest.raises(ValueError, match="is wider than half"):
        static_stereo(views, reference=1, cost_step_px=largest + 0.25)


def test_cli_bad_disparity_range_before_reading_the_views(tmp_path, capsys):
    """A bad range is a usage error, found before any view is read (as the other options)."""
    from nfdepth.cli import main

    missing = [str(tmp_path / f"none{k}.png") for k in range(3)]
    code = main(["stereo", *missing, "--disparity-range", "9", "1", "--out", str(tmp_path / "d.pfm")])
    _, err = capsys.readouterr()
    assert code == 2 and "--disparity-range must be two finite numbers MIN < MAX, got 9 1" in err


def test_cli_depth_range(plane_files, tmp_path, capsys):
    """`--depth-range NEAR FAR` with `--focal-px F --baseline B` searches the disparities F B / Z: 0.25..inf
    scene units at F B = 10 is `--disparity-range 0 40`, bit for bit."""
    from nfdepth.cli import main
    from nfdepth.io import read_pfm

    scale = ["--focal-px", "100", "--baseline", "0.1"]
    outputs = []
    for k, extra in enumerate((["--depth-range", "0.25", "inf"], ["--disparity-range", "0", "40"])):
        outputs.append(tmp_path / f"d{k}.pfm")
        code = main(["stereo", *plane_files, *scale, *extra, "--out", str(outputs[-1])])
        printed, err = capsys.readouterr()
        assert code == 0, err
        assert "searched 0..40 px" in printed
    np.testing.assert_array_equal(read_pfm(outputs[0]), read_pfm(outputs[1]))


def test_a_given_range_bounds_the_output(capsys):
    """A range given (disparities or depths) is a bound: no value outside it comes back, and a range that misses
    the scene (a plane at 30 px searched over 31..40 px, 20..29.5 px) warns that the scene may lie outside it.
    Measured before: 20..29.5 px returned the whole plane at 29.96-30.01 px, without a warning."""
    views = _plane((60, 80), 30.0)
    for given in ((31.0, 40.0), (20.0, 29.5)):
        with pytest.warns(UserWarning, match=r"no unique match between disparities .*: the scene may lie outside the given range .*, or the views are in the wrong order or not rectified along the baseline$"):
            r = static_stereo(views, reference=1, disparity_range_px=given)
        d = r.disparity[np.isfinite(r.disparity)]
        assert d.size < 0.01 * r.disparity.size and not ((d < given[0]) | (d > given[1])).any()
    r = static_stereo(views, reference=1, disparity_range_px=(25.0, 35.0))
    assert np.isfinite(r.disparity).mean() > 0.9 and np.nanmax(np.abs(r.disparity - 30.0)) < 0.5


def test_cli_depth_range_errors_name_the_depths(plane_files, tmp_path, capsys):
    from nfdepth.cli import main

    scale = ["--focal-px", "100", "--baseline", "0.1"]
    for extra, message in (
        (["--depth-range", "0.4", "0.41"], r"^nfdepth: error: --depth-range 0\.4 0\.41 \(disparities 24\.39\.\.25 px\): that range is narrower than two candidate steps \(1 px per unit of position; --cost-step-px 0\.5 px\): .*; widen or move the depth range$"),
        (["--depth-range", "1e-320", "1"], r"^nfdepth: error: --depth-range \([0-9.e+-]+, 1\) gives the disparities 10\.\.inf px: NEAR is too near for a finite disparity; give a larger NEAR$"),
    ):
        code = main(["stereo", *plane_files, *scale, *extra, "--out", str(tmp_path / "d.pfm")])
        _, err = capsys.readouterr()
        assert code == 2 and re.match(message, err.strip()), err
        assert not (tmp_path / "d.pfm").exists()


def test_cli_fill_at_infinity_has_no_finite_depth(tmp_path, capsys):
    """A scene at infinity (views alike but for their noise) with a textureless band: the band is filled from
    disparities about 0, and those at 0 or below have no finite depth: NaN, and the run says how many."""
    from nfdepth.cli import main
    from nfdepth.io import read_image

    base = _texture((60, 80), 5)
    base[:, 30:50] = 128.0
    rng = np.random.default_rng(2)
    names = []
    for k in range(3):
        names.append(str(tmp_path / f"v{k}.tif"))
        cv2.imwrite(names[-1], (base + rng.normal(0.0, 1.0, base.shape)).astype(np.float32))
    mask = tmp_path / "m.npy"
    code = main(["stereo", *names, "--disparity-range", "-2", "4", "--fill", "--fill-mask", str(mask), "--focal-px", "100", "--baseline", "1", "--out", str(tmp_path / "z.tif")])
    printed, err = capsys.readouterr()
    assert code == 0, err
    z, filled = read_image(tmp_path / "z.tif"), np.load(mask)
    said = re.search(r"(\d+) more filled at a disparity of 0 or less: no finite depth, NaN", printed)
    assert said, printed
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d, where = static_stereo([read_image(n) for n in names], reference=1, disparity_range_px=(-2.0, 4.0)).filled()
    infinite = where & np.isfinite(d) & (d <= 0)
    assert int(said.group(1)) == int(np.count_nonzero(infinite)) > 0
    assert np.isnan(z[infinite]).all() and np.isnan(filled[infinite]).all()
    assert np.isfinite(z[where & (d > 0)]).all()


def test_cli_depth_range_bounds_the_depths_written(tmp_path, capsys):
    """`--depth-range` bounds the depths written exactly, filled ones too (the disparities were bounded to 0.1 px:
    depths up to 1.3 % beyond FAR came back on Tsukuba); the run says how many fills fell outside."""
    from textured_planes import slanted_plane_views

    from nfdepth.cli import main
    from nfdepth.io import read_pfm, write_array

    views, _ = slanted_plane_views(3.0, 0.03, noise=2.0, min_wavelength_px=4.0)
    plane_files = [str(tmp_path / f"s{k}.tif") for k in range(3)]
    for name, view in zip(plane_files, views):
        write_array(name, view)
    scale = ["--focal-px", "100", "--baseline", "0.1"]
    z_all = tmp_path / "all.pfm"
    assert main(["stereo", *plane_files, *scale, "--out", str(z_all)]) == 0
    capsys.readouterr()
    depths = read_pfm(z_all)
    near, far = (float(np.nanpercentile(depths, q)) for q in (20, 70))  # cuts through the plane
    out, mask = tmp_path / "z.pfm", tmp_path / "m.npy"
    code = main(["stereo", *plane_files, *scale, "--depth-range", str(near), str(far), "--fill", "--fill-mask", str(mask), "--out", str(out)])
    printed, err = capsys.readouterr()
    assert code == 0, err
    z, m = read_pfm(out), np.load(mask)
    assert np.isfinite(z).mean() > 0.3 and not ((z < near) | (z > far)).any()
    np.testing.assert_array_equal(np.isfinite(m), np.isfinite(z))
    assert re.search(r"\(\d+ more filled beyond --depth-range: NaN\)", printed), printed


def test_library_depth_range_bounds_the_depths():
    """``StereoResult.depth(depth_range=)``: a range from :func:`disparity_range_for_depths` bounds the disparities to
    0.1 px of its ends, so some depths lie just beyond it; with ``depth_range`` none do, and those inside are the same."""
    from textured_planes import slanted_plane_views

    from nfdepth.stereo import disparity_range_for_depths, static_stereo

    views, _ = slanted_plane_views(3.0, 0.03, noise=2.0, min_wavelength_px=4.0)
    scale = {"focal_px": 100.0, "baseline": 0.1}
    everything = static_stereo(views, reference=1).depth(**scale)
    near, far = (float(np.nanpercentile(everything, q)) for q in (20, 70))  # cuts through the plane
    res = static_stereo(views, reference=1, disparity_range_px=disparity_range_for_depths((near, far), **scale))
    loose = res.depth(**scale)
    bounded = res.depth(**scale, depth_range=(near, far))
    beyond = (loose < near) | (loose > far)
    fb = scale["focal_px"] * scale["baseline"]
    assert beyond.any() and fb / (fb / near + 0.1) * (1 - 1e-6) <= np.nanmin(loose) and np.nanmax(loose) <= fb / (fb / far - 0.1) * (1 + 1e-6)  # 0.1 px
    assert not ((bounded < near) | (bounded > far)).any()
    np.testing.assert_array_equal(bounded, np.where(beyond, np.nan, loose))
    assert np.isfinite(bounded).mean() > 0.3
    np.testing.assert_array_equal(res.depth(**scale, depth_range=(near, np.inf)), np.where(loose < near, np.nan, loose))
    with pytest.raises(ValueError, match="depth_range"):
        res.depth(**scale, depth_range=(far, near))


def test_cli_fill_does_not_go_with_edges_only(plane_files, tmp_path, capsys):
    from nfdepth.cli import main

    code = main(["stereo", *plane_files, "--edges-only", "--fill", "--out", str(tmp_path / "d.pfm")])
    _, err = capsys.readouterr()
    assert code == 2 and err.strip().startswith("nfdepth: error: --fill fills the holes of the dense map: it does not go with --edges-only")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--depth-range", "2", "1", "--focal-px", "100", "--baseline", "0.1"], "--depth-range must be two depths NEAR FAR with 0 < NEAR < FAR (FAR may be inf: no far limit), got 2 1"),
        (["--depth-range", "1", "2"], "--depth-range needs --focal-px and --baseline (to turn the depths into disparities); or give --disparity-range"),
        (["--depth-range", "1", "2", "--disparity-range", "0", "9", "--focal-px", "100", "--baseline", "0.1"], "--depth-range and --disparity-range both set the search range: give one"),
    ],
)
def test_cli_bad_depth_range_before_reading_the_views(tmp_path, capsys, extra, message):
    from nfdepth.cli import main

    missing = [str(tmp_path / f"none{k}.png") for k in range(3)]
    code = main(["stereo", *missing, *extra, "--out", str(tmp_path / "d.pfm")])
    _, err = capsys.readouterr()
    assert code == 2 and err.strip() == f"nfdepth: error: {message}"


def test_cli_disparity_range_errors_name_the_options(plane_files, tmp_path, capsys):
    """A range the library refuses is told in the command line's words: the option and its values as given, the step
    as --cost-step-px (before: "disparity_range_px = (0, 0.5) is narrower ... cost_step_px = 0.5 px"), the rig
    file's key where the range is the rig's; an error of another option under --depth-range is not the range's."""
    from nfdepth.cli import main

    out = str(tmp_path / "d.pfm")
    rig = _rig_file(tmp_path, "disparity_range_px = [0, 0.5]\n")
    step = "two candidate steps ({} px per unit of position; --cost-step-px {} px): expected a range wide enough to tell a match from its neighbours"
    for extra, line in (
        (["--disparity-range", "0", "0.5"], "--disparity-range 0 0.5 is narrower than " + step.format(1, 0.5)),
        (["--disparity-range", "0", "1", "--cost-step-px", "1"], "--disparity-range 0 1 is narrower than " + step.format(2, 1)),
        (["--disparity-range", "0", "0.05", "--positions", "0", "10", "20"], "--disparity-range 0 0.05 is narrower than " + step.format(0.1, 0.5)),
        (["--disparity-range", "500", "1000"], "--disparity-range 500 1000 lies beyond the image: a disparity above 79 px per unit of position moves every pixel out of every view"),
        (["--rig", rig], "the rig file's disparity_range_px = [0, 0.5] is narrower than " + step.format(1, 0.5)),
        (
            ["--depth-range", "1", "10", "--focal-px", "100", "--baseline", "1", "--positions", "2", "1", "0"],
            "--positions must be strictly increasing (views ordered along the baseline), got [2.0, 1.0, 0.0]",
        ),
    ):
        code = main(["stereo", *plane_files, *extra, "--out", out])
        printed, err = capsys.readouterr()
        assert (code, printed, err) == (2, "", f"nfdepth: error: {line}\n")


def _rig_file(tmp_path, stereo_lines):
    path = tmp_path / "rig.toml"
    path.write_text("[camera]\nfocal_px = 100\nwidth_px = 80\nheight_px = 60\n[stereo]\nbaseline = 0.1\n" + stereo_lines)
    return str(path)


def test_rig_disparity_range(plane_files, tmp_path, capsys):
    """A rig's ``[stereo] disparity_range_px`` is ``--disparity-range``; the same range given
    twice agrees, a different one is a one-line error."""
    from nfdepth.cli import main
    from nfdepth.io import read_pfm

    rig = _rig_file(tmp_path, "disparity_range_px = [0, 40]\n")
    outputs = []
    given = ["--disparity-range", "0", "40", "--focal-px", "100", "--baseline", "0.1"]  # what the rig says
    for k, extra in enumerate((["--rig", rig], given, ["--rig", rig, "--disparity-range", "0", "40"])):
        outputs.append(tmp_path / f"d{k}.pfm")
        code = main(["stereo", *plane_files, *extra, "--out", str(outputs[-1])])
        printed, err = capsys.readouterr()
        assert code == 0, err
        assert "searched 0..40 px" in printed
    first = read_pfm(outputs[0])
    # depth 100 px * 0.1 / 30 px; 30 px per step is beyond the automatic search (see above)
    assert np.median(np.abs(first[5:-5, 35:-5] / (10.0 / 30.0) - 1.0)) < 1e-3
    for other in outputs[1:]:
        np.testing.assert_array_equal(read_pfm(other), first)
    out = tmp_path / "d.pfm"
    code = main(["stereo", *plane_files, "--rig", rig, "--disparity-range", "0", "32", "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 2 and not out.exists()
    assert err.strip() == "nfdepth: error: --disparity-range 0 32 contradicts the rig file's disparity_range_px = [0, 40]"


def test_rig_disparity_range_and_a_depth_range(plane_files, tmp_path, capsys):
    from nfdepth.cli import main

    out = tmp_path / "d.pfm"
    rig = _rig_file(tmp_path, "disparity_range_px = [0, 40]\n")
    code = main(["stereo", *plane_files, "--rig", rig, "--depth-range", "0.5", "2", "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 2 and not out.exists()
    assert err.strip() == "nfdepth: error: --depth-range and the rig file's disparity_range_px both set the search range: give one"
    # a rig without a range: its focal length and baseline turn the depths into disparities
    code = main(["stereo", *plane_files, "--rig", _rig_file(tmp_path, ""), "--depth-range", "0.25", "inf", "--out", str(out)])
    printed, err = capsys.readouterr()
    assert code == 0, err
    assert "searched 0..40 px" in printed


def test_rig_bad_disparity_range(plane_files, tmp_path, capsys):
    from nfdepth.cli import main

    out = tmp_path / "d.pfm"
    code = main(["stereo", *plane_files, "--rig", _rig_file(tmp_path, "disparity_range_px = [40, 0]\n"), "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 2 and not out.exists()
    assert len(err.strip().splitlines()) == 1 and "stereo.disparity_range_px = [40, 0]: expected [smallest, largest]" in err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--disparity-range", "9", "1"], "--disparity-range must be two finite numbers MIN < MAX, got 9 1"),
        (["--disparity-range", "0", "inf"], "--disparity-range must be two finite numbers MIN < MAX, got 0 inf"),
        (["--disparity-range", "0"], "expected 2 arguments"),
    ],
)
def test_cli_bad_disparity_range(plane_files, tmp_path, capsys, extra, message):
    from nfdepth.cli import main

    out = tmp_path / "d.pfm"
    code = main(["stereo", *plane_files, "--out", str(out), *extra])
    _, err = capsys.readouterr()
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and message in err
    assert not out.exists()


@pytest.mark.data
@pytest.mark.parametrize("name", ["tsukuba", "middlebury2005/Moebius"])
def test_real_scenes_are_unchanged_by_the_coarse_search(name, monkeypatch):
    """On real scenes the coarse search agrees with the coarse-to-fine range (measured on all
    seven, three and all views): searching every time changes no output. Its raw extremes lie
    a few px beyond that range (Tsukuba -3..20 px against -1..17), within its resolution."""
    from nfdepth import datasets
    from nfdepth.evaluate import select_views

    try:
        scene = datasets.load_scene(name)
    except datasets.DataNotFoundError:
        pytest.skip("real data not found: set NFDEPTH_DATA or put it at ../shared/data")
    sub = datasets.view_subset(scene, select_views(len(scene.views), scene.reference_index, "three"))
    default = static_stereo(sub.views, reference=sub.reference_index, match_exposure=False)  # (its pass would search too)
    calls = []
    real = stereo._widen_by_coarse_search

    def spy(lo, hi, *args, **kwargs):
        calls.append(((lo, hi), real(lo, hi, *args, **kwargs)))
        return calls[-1][1]

    monkeypatch.setattr(stereo, "_RETRY_SHARE", -1.0)
    monkeypatch.setattr(stereo, "_widen_by_coarse_search", spy)
    searched = static_stereo(sub.views, reference=sub.reference_index, match_exposure=False)
    assert len(calls) == 1 and calls[0][0] == calls[0][1]  # no second cost volume
    assert searched.search_range_px == default.search_range_px
    np.testing.assert_array_equal(searched.disparity, default.disparity)


# ------------------------------------------------------------ the range's ends


def test_a_winner_at_an_end_of_the_automatic_range_is_uncertain(monkeypatch):
    """The automatic range ends 2 px beyond the field's robust extremes: a winner there is
    no minimum, its match lies outside the range. A plane at 6 px with one level (its
    field sets -5..5 px): 792 pixels were reported at 5 px, all wrong; now none is, and
    the warning says why. The rule's mutation (no end rejects) brings them back."""
    views = _plane((96, 128), 6.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = static_stereo(views, reference=1, levels=1)
    lo, hi = r.search_range_px
    assert hi < 6.0 and r.valid.sum() < 0.01 * r.valid.size
    assert not np.any(r.disparity[r.valid] >= hi)
    assert any(f"100 % of the textured pixels have no unique match between disparities {lo:g} and {hi:g} px" in str(w.message) for w in caught)
    monkeypatch.setattr(stereo, "_beyond", lambda d, *args: np.zeros(d.shape, bool))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = static_stereo(views, reference=1, levels=1)
    assert r.valid.sum() > 500 and np.all(r.disparity[r.valid] == hi)


def test_a_plane_at_the_end_of_a_given_range_is_measured():
    """A plane exactly at the lower end of a given range is measured, not cut off: the range
    is searched 1 px beyond its ends, and only the outer end counts as outside."""
    r = static_stereo(_plane((96, 128), 2.0), reference=1, disparity_range_px=(2.0, 8.0))
    inner = r.disparity[16:-16, 16:-16]
    assert np.isfinite(inner).mean() > 0.95
    assert np.nanmedian(np.abs(inner - 2.0)) < 0.05


def _cropped_pair(d, shape=(96, 128), margin=40, seed=3):
    """Two views (reference first) of a plane at ``d`` whole px, cut from a wider texture."""
    h, w = shape
    wide = _texture((h, w + 2 * margin), seed)
    return [wide[:, margin + p * d : margin + p * d + w] for p in (0, 1)]


def test_winners_at_the_ranges_end_count_as_unmatched_for_the_coarse_search():
    """Two views of a plane at 20 px: the coarse-to-fine field (range -16..20 px) has the
    plane at the range's end, 15 % of the textured pixels ambiguous. The coarse search
    widens the range to 25 px, with as many ambiguous pixels; it is kept because the
    plane's winners at the first range's end count as unmatched there."""
    r = static_stereo(_cropped_pair(20), reference=0)
    assert r.search_range_px[1] > 20.0
    ok = r.valid
    assert ok.mean() > 0.8
    assert not np.any(np.abs(r.disparity[ok] - 20.0) > 1.0)


@pytest.mark.data
def test_motorcycle_left_border_no_longer_matches_at_the_range_end():
    """Motorcycle (two views, reference on the left): 10928 truth pixels near the left
    border lie outside the other view. 932 of them were reported, 99.8 % off by more than
    1 px, nearly all at the range's lower end (2 px); now 39 are, and dense bad-1px is
    4.64 % (4.95 % before) at 80.25 % coverage (80.51 %)."""
    from nfdepth import datasets

    try:
        scene = datasets.load_scene("motorcycle")
    except datasets.DataNotFoundError:
        pytest.skip("real data not found: set NFDEPTH_DATA or put it at ../shared/data")
    r = static_stereo(scene.views, reference=scene.reference_index)
    truth = np.where(scene.valid, scene.disparity, np.nan)
    has = np.isfinite(truth)
    cols = np.arange(truth.shape[1])[None, :]
    with np.errstate(invalid="ignore"):
        outside = has & (truth > cols + 0.5)
    got = r.valid & has
    assert outside.sum() > 10000
    assert np.count_nonzero(got & outside) < 60
    bad = np.abs(r.disparity[got] - truth[got]) > 1.0
    assert bad.mean() < 0.047 and got.sum() > 0.80 * has.sum()


def test_a_given_range_is_searched_one_px_beyond_its_ends():
    """A plane at 8 px: a given range that ends 1.5 px short of it (0-6.5) used to report it at
    6.5 px; the outer end of the extra px (7.5) now catches it as outside (UNCERTAIN), with the
    lost-match warning. A given range is a bound: one ending 0.4 px short (0-7.6), which measured
    the plane at 8 px before, says so the same way; one ending within the bound's 0.1 px (0-7.95)
    keeps it."""
    views = _plane((96, 128), 8.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        short = static_stereo(views, reference=1, disparity_range_px=(0.0, 6.5))
    assert short.search_range_px == (0.0, 6.5)
    assert not np.any(np.abs(short.disparity[short.valid] - 8.0) > 1.0)
    assert short.valid.mean() < 0.05
    assert any("no unique match between disparities 0 and 6.5 px" in str(w.message) for w in caught)
    with pytest.warns(UserWarning, match="no unique match between disparities 0 and 7.6 px"):
        assert static_stereo(views, reference=1, disparity_range_px=(0.0, 7.6)).valid.mean() < 0.05
    near = static_stereo(views, reference=1, disparity_range_px=(0.0, 7.95))
    inner = near.disparity[8:-8, 16:-16]
    assert np.isfinite(inner).mean() > 0.95 and np.nanmedian(np.abs(inner - 8.0)) < 0.05


def test_a_given_range_is_checked_against_the_candidate_step_and_the_image():
    views = _plane((96, 400), 4.0)
    with pytest.raises(ValueError, match=r"^disparity_range_px = \(0, 0\.1\) is narrower than two candidate steps \(1 px per unit of position; cost_step_px = 0\.5 px\)"):
        static_stereo(views, reference=1, disparity_range_px=(0, 0.1))
    with pytest.raises(ValueError, match=r"disparity_range_px = \(500, 900\) lies beyond the image: a disparity above 399 px per unit of position moves every pixel out of every view"):
        static_stereo(views, reference=1, disparity_range_px=(500, 900))
    # positions in tenths: the same checks in that unit
    with pytest.raises(ValueError, match=r"narrower than two candidate steps \(10 px per unit of position"):
        static_stereo(views, reference=1, positions=(0, 0.1, 0.2), disparity_range_px=(0, 5))
    # clipped to the image, and searched in coarser steps: said so (and, at 1.6 px steps on this
    # smooth texture, most pixels have no unique match)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = static_stereo(views, reference=1, disparity_range_px=(-1000, 1000))
    assert r.search_range_px == (-399.0, 399.0)
    coarse = r"the search range -399\.\.399 px per unit of position holds more than 512 candidates at cost_step_px = 0\.5 px: searched in 1\.5\d* px steps"
    assert any(re.search(coarse, str(w.message)) for w in caught), [str(w.message) for w in caught]


def test_a_given_range_that_misses_most_of_a_real_scene_warns():
    """Art's views 0-2 with 14.37-21.75 px: a third of the truth lies inside. 61 % of the pixels came back NaN and 16 %
    of the kept ones wrong (truth at 10-11 px), without a warning: 62 % of the textured pixels had no unique match,
    below the 75 % that warns. Now more than half of them with their best match at or beyond the range's ends
    (measured 53 %) warns; a range holding the scene (5-30 px: 0 %) does not."""
    from nfdepth import datasets
    from nfdepth.stereo import static_stereo

    try:
        scene = datasets.load_scene("middlebury2005/Art")
    except datasets.DataNotFoundError:
        pytest.skip("real data not found: set NFDEPTH_DATA or put it at ../shared/data")
    views = [np.asarray(v, np.float32) for v in scene.views[:3]]
    with pytest.warns(UserWarning, match=r"^6\d % of the textured pixels have no unique match between disparities 14\.37 and 21\.75 px"):
        static_stereo(views, reference=1, disparity_range_px=(14.37, 21.75))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        static_stereo(views, reference=1, disparity_range_px=(5.0, 30.0))


def test_cli_names_the_unit_of_disparities_per_unit_of_position(plane_files, tmp_path, capsys):
    """With ``--positions`` in another unit than view steps the disparities are px per unit of position: the run's
    line said "px" (a plane at 30 px per step, positions 0 2 4: "range 15..15 px")."""
    from nfdepth.cli import main

    assert main(["stereo", *plane_files, "--positions", "0", "2", "4", "--disparity-range", "0", "20", "--out", str(tmp_path / "d.pfm")]) == 0
    printed = capsys.readouterr().out
    assert re.search(r", range 1[45](\.\d+)?\.\.1[56](\.\d+)? px per unit of position, .*, searched 0\.\.20 px per unit of position -> ", printed), printed
    assert main(["stereo", *plane_files, "--positions", "0", "1", "2", "--disparity-range", "0", "40", "--out", str(tmp_path / "e.pfm")]) == 0
    printed = capsys.readouterr().out
    assert "px per unit" not in printed and "searched 0..40 px -> " in printed, printed
