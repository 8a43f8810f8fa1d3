"""Tests of nfdepth.datasets against the real data (marked ``data``) and its error paths."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from nfdepth import datasets as D
from nfdepth.datasets import DataNotFoundError, MultiViewScene


@pytest.fixture(scope="module")
def root():
    try:
        return D.data_root()
    except DataNotFoundError:
        pytest.skip("real data not found: set NFDEPTH_DATA or put it at ../shared/data")


def _warp_errors(scene: MultiViewScene, k: int):
    """Mean |grey| error of view ref+k warped onto the reference by k*d, and unwarped."""
    ref = scene.reference
    view = scene.views[scene.reference_index + k]
    d = scene.disparity
    h, w = ref.shape
    rows, cols = np.mgrid[0:h, 0:w].astype(np.float32)
    map_x = (cols - k * np.nan_to_num(d)).astype(np.float32)
    warped = cv2.remap(view, map_x, rows, cv2.INTER_LINEAR)
    m = np.isfinite(d) & (map_x >= 0) & (map_x <= w - 1)
    return float(np.abs(warped - ref)[m].mean()), float(np.abs(view - ref)[m].mean())


# (loader, n views, ref index, shape, disparity min, max, NaN % range, {k: max warped error})
CASES = {
    "tsukuba": (5, 2, (288, 384), 5.0, 14.0, (20.5, 20.9), {-1: 4.0, 1: 4.6, 2: 7.7}),
    "teddy": (9, 2, (375, 450), 3.125, 13.1875, (1.9, 2.1), {1: 4.0, 2: 4.4, -1: 6.6}),
    "middlebury2005/Art": (7, 1, (555, 695), 9.125, 28.0, (0.1, 0.9), {1: 4.4, 2: 6.8}),
    "middlebury2005/Books": (7, 1, (555, 695), 1.125, 27.625, (0.1, 0.9), {1: 4.4}),
    "middlebury2005/Dolls": (7, 1, (555, 695), 1.125, 27.625, (0.1, 0.9), {1: 4.4}),
    "middlebury2005/Moebius": (7, 1, (555, 695), 8.0, 27.25, (0.1, 0.9), {1: 4.4}),
    "middlebury2005/Reindeer": (7, 1, (555, 671), 1.375, 25.125, (0.1, 0.9), {1: 4.4}),
    "motorcycle": (2, 0, (500, 741), 7.19, 59.91, (7.2, 7.4), {1: 7.6}),
}


@pytest.fixture(scope="module")
def scenes(root):
    return {}


def _load(scenes, name):
    if name not in scenes:
        scenes[name] = D.load_scene(name)
    return scenes[name]


@pytest.mark.data
def test_list_scenes(root):
    assert D.list_scenes() == list(CASES)


@pytest.mark.data
@pytest.mark.parametrize("name", list(CASES))
def test_scene_matches_source(scenes, name):
    n, ref, shape, dlo, dhi, nan_pct, warp = CASES[name]
    sc = _load(scenes, name)
    assert sc.name == name and len(sc.views) == n and sc.reference_index == ref
    assert all(v.shape == shape and v.dtype == np.float32 for v in sc.views)
    assert sc.disparity.shape == shape and sc.disparity.dtype == np.float32
    assert sc.colour_reference.shape == (*shape, 3) and sc.colour_reference.dtype == np.uint8
    assert 0 <= min(float(v.min()) for v in sc.views) and max(float(v.max()) for v in sc.views) <= 255
    d = sc.disparity
    assert np.nanmin(d) == pytest.approx(dlo, abs=0.01) and np.nanmax(d) == pytest.approx(dhi, abs=0.01)
    assert nan_pct[0] <= 100 * np.isnan(d).mean() <= nan_pct[1]
    for k, limit in warp.items():
        warped, unwarped = _warp_errors(sc, k)
        assert warped <= limit, (k, warped)
        assert unwarped > 3 * warped, (k, warped, unwarped)
    assert sc.source


@pytest.mark.data
def test_warp_sign_and_scale(scenes):
    """The stated scale and sign are the right ones: 1.5x or the opposite sign is much worse."""
    sc = _load(scenes, "tsukuba")
    good = _warp_errors(sc, 1)[0]
    for factor in (1.5, -1.0, 0.5):
        wrong = dataclasses.replace(sc, disparity=sc.disparity * np.float32(factor))
        assert _warp_errors(wrong, 1)[0] > 3 * good


@pytest.mark.data
def test_tsukuba_integer_layers(scenes):
    sc = _load(scenes, "tsukuba")
    d = sc.disparity
    assert set(np.unique(d[np.isfinite(d)]).tolist()) == {5.0, 6.0, 7.0, 8.0, 10.0, 11.0, 14.0}
    assert sc.truth_step_px == 1.0


@pytest.mark.data
@pytest.mark.parametrize("name", ["teddy", "middlebury2005/Art", "middlebury2005/Moebius"])
def test_truth_lies_on_its_step(scenes, name):
    """Every stored disparity is a whole number of ``truth_step_px``; motorcycle's float truth has none."""
    sc = _load(scenes, name)
    d = sc.disparity[np.isfinite(sc.disparity)].astype(np.float64) / sc.truth_step_px
    np.testing.assert_array_equal(d, np.round(d))
    assert _load(scenes, "motorcycle").truth_step_px is None


@pytest.mark.data
@pytest.mark.parametrize(
    ("name", "zlo", "zhi"),
    [("middlebury2005/Art", 1410, 2190), ("middlebury2005/Reindeer", 1390, 2480), ("motorcycle", 2110, 5020)],
)
def test_metric_depth(scenes, name, zlo, zhi):
    sc = _load(scenes, name)
    z = sc.depth()
    assert sc.baseline_unit == "mm" and z.dtype == np.float32
    assert np.nanmin(z) == pytest.approx(zlo, abs=10) and np.nanmax(z) == pytest.approx(zhi, abs=10)
    np.testing.assert_array_equal(np.isnan(z), np.isnan(sc.disparity))


@pytest.mark.data
def test_offsets(scenes):
    assert _load(scenes, "middlebury2005/Art").disparity_offset_px == 25.0
    assert _load(scenes, "middlebury2005/Reindeer").disparity_offset_px == pytest.approx(230 / 8)
    mc = _load(scenes, "motorcycle")
    assert (mc.focal_px, mc.baseline, mc.disparity_offset_px) == (994.978, 193.001, 31.086)
    assert mc.principal_point_px == (311.193, 254.877)


@pytest.mark.data
def test_depth_unknown_scale_raises(scenes):
    with pytest.raises(ValueError, match="no published focal length and baseline"):
        _load(scenes, "teddy").depth()


@pytest.mark.data
def test_downsample_scene(scenes):
    sc = _load(scenes, "middlebury2005/Art")
    small = D.downsample_scene(sc, 4)
    assert small.shape == (555 // 4, 695 // 4) and len(small.views) == 7
    assert small.colour_reference.shape == (*small.shape, 3) and small.colour_reference.dtype == np.uint8
    assert small.focal_px == 1870 / 4 and small.disparity_offset_px == 25 / 4 and small.baseline == 40
    assert 6.5 < np.nanmax(small.disparity) <= 7.0  # 28 px / 4, block-averaged
    # depth is preserved (up to block averaging of disparity)
    z = sc.depth()[:552, :692].reshape(138, 4, 173, 4)
    ok = np.isfinite(z).all(axis=(1, 3))
    assert np.isfinite(small.disparity[ok]).all()
    assert np.median(np.abs(small.depth()[ok] / z.mean(axis=(1, 3))[ok] - 1)) < 0.01
    # the block mean of the views is exact area averaging
    np.testing.assert_allclose(small.views[1][0, 0], sc.views[1][:4, :4].mean(), rtol=1e-5)
    # warping still works at the smaller size
    warped, unwarped = _warp_errors(small, 1)
    assert warped < 5.5 and unwarped > 4 * warped  # 4.7 vs 24.7 (4.1 vs 26.2 at full size)
    assert sc.truth_step_px == 1 / 8 and small.truth_step_px == 1 / 32
    assert D.downsample_scene(sc, 1).disparity.shape == sc.disparity.shape
    mc = D.downsample_scene(_load(scenes, "motorcycle"), 2)
    assert mc.principal_point_px == pytest.approx(((311.193 + 0.5) / 2 - 0.5, (254.877 + 0.5) / 2 - 0.5))


@pytest.mark.data
def test_view_subset(scenes):
    sc = _load(scenes, "teddy")
    sub = D.view_subset(sc, [1, 2, 3])
    assert len(sub.views) == 3 and sub.reference_index == 1 and sub.views[0] is sc.views[1]
    np.testing.assert_array_equal(sub.disparity, sc.disparity)
    wide = D.view_subset(sc, [0, 2, 4, 6])
    assert wide.reference_index == 1
    np.testing.assert_array_equal(wide.disparity, 2 * sc.disparity)
    assert _warp_errors(wide, 1)[0] < 5  # im4 onto im2 with the doubled step
    with pytest.raises(ValueError, match="must include the reference view 2"):
        D.view_subset(sc, [3, 4])
    with pytest.raises(ValueError, match="equally spaced"):
        D.view_subset(sc, [1, 2, 4])
    with pytest.raises(ValueError, match="lie in 0..8"):
        D.view_subset(sc, [2, 9])
    assert sc.truth_step_px == 1 / 16 and wide.truth_step_px == 1 / 8
    art = D.view_subset(_load(scenes, "middlebury2005/Art"), [1, 3, 5])
    assert art.baseline == 80 and art.disparity_offset_px == 50 and art.truth_step_px == 1 / 4
    np.testing.assert_allclose(art.depth(), _load(scenes, "middlebury2005/Art").depth(), rtol=1e-5)


# ------------------------------------------------------------------ no data needed


def _synthetic_scene():
    rng = np.random.default_rng(0)
    views = [rng.random((8, 10)).astype(np.float32) for _ in range(3)]
    disp = np.full((8, 10), 2.0, np.float32)
    disp[0, 0] = np.nan  # one NaN in the first 2x2 block
    disp[2:4, 2:4] = np.nan  # a whole block
    disp[4, 4] = disp[4, 5] = disp[5, 4] = np.nan  # three of four
    colour = np.zeros((8, 10, 3), np.uint8)
    return MultiViewScene("syn", views, 1, disp, 100.0, 10.0, "mm", 0.0, colour, "synthetic")


def test_downsample_nan_rule():
    sc = _synthetic_scene()
    small = D.downsample_scene(sc, 2)
    assert small.disparity.shape == (4, 5)
    assert small.disparity[0, 0] == 1.0  # 3 of 4 valid: mean / 2
    assert np.isnan(small.disparity[1, 1]) and np.isnan(small.disparity[2, 2])
    strict = D.downsample_scene(sc, 2, min_valid_fraction=1.0)
    assert np.isnan(strict.disparity[0, 0]) and strict.disparity[0, 1] == 1.0
    np.testing.assert_allclose(small.depth()[0, 1], sc.depth()[0, 2])
    with pytest.raises(ValueError, match="factor must be a positive integer, got 0"):
        D.downsample_scene(sc, 0)
    with pytest.raises(ValueError, match="factor must be a positive integer, got 1.5"):
        D.downsample_scene(sc, 1.5)
    with pytest.raises(ValueError, match="factor=5 is too large"):
        D.downsample_scene(sc, 5)


def test_missing_root_mentions_env(tmp_path, monkeypatch):
    monkeypatch.setenv("NFDEPTH_DATA", str(tmp_path / "nowhere"))
    with pytest.raises(DataNotFoundError, match="NFDEPTH_DATA"):
        D.data_root()
    with pytest.raises(DataNotFoundError, match="NFDEPTH_DATA"):
        D.load_tsukuba()
    with pytest.raises(DataNotFoundError, match="NFDEPTH_DATA"):
        D.data_root(tmp_path / "also-missing")
    assert issubclass(DataNotFoundError, ValueError)


def test_no_root_anywhere(tmp_path, monkeypatch):
    monkeypatch.delenv("NFDEPTH_DATA", raising=False)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(D, "_repo_candidate", lambda: None)
    monkeypatch.setattr(D, "_download_candidate", lambda: None)  # no `nfdepth fetch-data` folder either
    with pytest.raises(DataNotFoundError, match=r"tried NFDEPTH_DATA \(not set\).*shared.data.*fetch-data"):
        D.data_root()


def test_missing_file_is_named(tmp_path, monkeypatch):
    (tmp_path / "tsukuba").mkdir()
    monkeypatch.setenv("NFDEPTH_DATA", str(tmp_path))
    with pytest.raises(DataNotFoundError, match=r"data file missing: '.*scene1\.row3\.col1\.ppm'"):
        D.load_scene("tsukuba")
    assert D.list_scenes() == []
    with pytest.raises(ValueError, match="name must be one of tsukuba, teddy"):
        D.load_scene("nope")
    with pytest.raises(ValueError, match="scene must be one of Art, Books"):
        D.load_middlebury2005("Laundry")


def test_repr_is_one_line_without_arrays():
    assert repr(_synthetic_scene()) == (
        "MultiViewScene(name='syn', views=3 x 8x10, reference_index=1, focal_px=100.0, baseline=10.0 mm, disparity_offset_px=0.0)"
    )


def test_scene_checks_refuse_wrong_types_and_ranges():
    sc = _synthetic_scene()
    cases = [
        (lambda: D.load_scene(5), TypeError, r"^name must be a str such as 'tsukuba', got int$"),
        (lambda: D.load_scene("middlebury2005/Laundry"), ValueError, r"^name must be one of tsukuba, teddy, middlebury2005/Art, .*, motorcycle, got 'middlebury2005/Laundry'$"),
        (lambda: D.load_middlebury2005(5), TypeError, r"^scene must be a str, one of Art, Books, Dolls, Moebius, Reindeer; got int$"),
        (lambda: D.downsample_scene("syn", 2), TypeError, r"^scene must be a MultiViewScene, got str$"),
        (lambda: D.downsample_scene(sc, "2"), TypeError, r"^factor must be a positive integer, got '2'$"),
        (lambda: D.downsample_scene(sc, True), TypeError, r"^factor must be a positive integer, got True$"),
        (lambda: D.downsample_scene(sc, 2, min_valid_fraction=0), ValueError, r"^min_valid_fraction must be in \(0, 1\], got 0$"),
        (lambda: D.downsample_scene(sc, 2, min_valid_fraction=1.5), ValueError, r"^min_valid_fraction must be in \(0, 1\], got 1.5$"),
        (lambda: D.view_subset(None, [0, 1]), TypeError, r"^scene must be a MultiViewScene, got NoneType$"),
        (lambda: D.view_subset(sc, [0.5, 1]), TypeError, r"^indices must be a sequence of integers, got \[0.5, 1\]$"),
        (lambda: D.view_subset(sc, [True, 2]), TypeError, r"^indices must be a sequence of integers, got \[True, 2\]$"),
        (lambda: D.view_subset(sc, 1), TypeError, r"^indices must be a sequence of integers, got 1$"),
        (lambda: D.view_subset(sc, [1]), ValueError, r"^indices must hold at least two views, got \[1\]$"),
    ]
    for call, exc, match in cases:
        with pytest.raises(exc, match=match):
            call()
    # whole floats are whole numbers
    assert D.view_subset(sc, [0.0, 1.0]).reference_index == 1
    assert D.downsample_scene(sc, 2.0).disparity.shape == (4, 5)


def test_data_root_search_order(tmp_path, monkeypatch):
    """NFDEPTH_DATA unset: ../shared/data of the working directory first, then a shared/data
    beside a folder above the package, then the fetch-data folder if it holds a set."""
    monkeypatch.delenv("NFDEPTH_DATA", raising=False)
    cwd_data = tmp_path / "a" / "shared" / "data"
    cwd_data.mkdir(parents=True)
    (tmp_path / "a" / "main").mkdir()
    beside = tmp_path / "b" / "shared" / "data"
    beside.mkdir(parents=True)
    monkeypatch.setattr(D, "__file__", str(tmp_path / "b" / "main" / "src" / "nfdepth" / "datasets.py"))
    fetched = tmp_path / "cache" / "nfdepth" / "data"
    (fetched / "tsukuba").mkdir(parents=True)
    monkeypatch.setattr(D._fetch, "default_data_dir", lambda: fetched)
    monkeypatch.chdir(tmp_path / "a" / "main")
    assert D.data_root() == cwd_data.resolve()
    elsewhere = tmp_path / "d" / "e"
    elsewhere.mkdir(parents=True)
    monkeypatch.chdir(elsewhere)  # no ../shared/data here
    assert D.data_root() == beside.resolve()  # the nearest folder above the package's file
    monkeypatch.setattr(D, "_repo_candidate", lambda: None)  # (a shared/data above tmp_path would count too)
    # the fetch-data folder counts once a set's SHA256SUMS is written
    with pytest.raises(DataNotFoundError, match=rf"the download folder {fetched} \(no data set there\)"):
        D.data_root()
    (fetched / "tsukuba" / "SHA256SUMS").write_text("")
    assert D.data_root() == fetched.resolve()

    def homeless():
        raise RuntimeError("Could not determine home directory.")

    monkeypatch.setattr(D._fetch, "default_data_dir", homeless)
    with pytest.raises(DataNotFoundError, match=r"a shared/data folder beside any parent of .*, the download folder \(no home directory\); set NFDEPTH_DATA="):
        D.data_root()


def _write_art(root, *, shape=(12, 16), dmin="200", disp=None):
    """A Middlebury 2005 'Art' folder of small 8-bit grey PNGs: view k holds 10 k + col, disp1.png 8 x (1 + col % 4)."""
    folder = root / "middlebury2005" / "Art"
    folder.mkdir(parents=True, exist_ok=True)
    h, w = shape
    cols = np.tile(np.arange(w, dtype=np.uint8), (h, 1))
    for k in range(7):
        cv2.imwrite(str(folder / f"view{k}.png"), (10 * k + cols).astype(np.uint8))
    if disp is None:
        disp = (8 * (1 + cols % 4)).astype(np.uint8)
        disp[0, 0] = 0  # unknown
    cv2.imwrite(str(folder / "disp1.png"), disp)
    (folder / "dmin.txt").write_text(dmin)
    return folder


def test_middlebury2005_loader_decodes_its_files(tmp_path):
    """disp1.png holds 8 d (0: unknown), dmin.txt the full-size dmin (offset dmin / 8); grey
    views come back as their values, the colour reference as the grey view in three channels."""
    _write_art(tmp_path)
    sc = D.load_scene("middlebury2005/art", tmp_path)
    assert sc.name == "middlebury2005/Art" and sc.reference_index == 1 and len(sc.views) == 7
    cols = np.arange(16)
    np.testing.assert_array_equal(sc.views[3], np.tile(30.0 + cols, (12, 1)).astype(np.float32))
    expected = np.tile((1 + cols % 4).astype(np.float32), (12, 1))
    expected[0, 0] = np.nan
    np.testing.assert_array_equal(sc.disparity, expected)
    assert sc.disparity_offset_px == 25.0 and sc.truth_step_px == 1 / 8
    assert sc.colour_reference.shape == (12, 16, 3) and sc.colour_reference.dtype == np.uint8
    for c in range(3):
        np.testing.assert_array_equal(sc.colour_reference[..., c], np.tile(10 + cols, (12, 1)))
    # a colour disparity file with equal channels is grey
    grey3 = np.repeat((8 * (1 + np.tile(cols, (12, 1)) % 4)).astype(np.uint8)[..., None], 3, axis=2)
    _write_art(tmp_path, disp=grey3)
    np.testing.assert_array_equal(D.load_middlebury2005("Art", tmp_path).disparity, np.tile((1 + cols % 4).astype(np.float32), (12, 1)))


def test_damaged_scene_files_are_named(tmp_path):
    folder = _write_art(tmp_path, dmin="abc")
    with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': '{folder / 'dmin.txt'}' should hold one finite number \(dmin in full-size px\), got 'abc'$"):
        D.load_middlebury2005("Art", tmp_path)
    _write_art(tmp_path, dmin="")
    with pytest.raises(DataNotFoundError, match=r"should hold one finite number \(dmin in full-size px\), got ''$"):
        D.load_middlebury2005("Art", tmp_path)
    for text in ("nan", "-inf", "1e999"):  # every depth of the scene would be NaN
        _write_art(tmp_path, dmin=text)
        with pytest.raises(D.DataFileError, match=rf"should hold one finite number \(dmin in full-size px\), got '{text}'$"):
            D.load_middlebury2005("Art", tmp_path)
    colour = np.zeros((12, 16, 3), np.uint8)
    colour[..., 2] = 40
    _write_art(tmp_path, disp=colour)
    with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': cannot read image '{folder / 'disp1.png'}': expected a grey disparity map, got colour$"):
        D.load_middlebury2005("Art", tmp_path)
    _write_art(tmp_path, disp=np.full((12, 17), 16, np.uint8))
    with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': ground truth '{folder / 'disp1.png'}' is 17x12 px but the views are 16x12 px; are the files intact\?$"):
        D.load_middlebury2005("Art", tmp_path)
    _write_art(tmp_path, disp=np.zeros((12, 16), np.uint8))  # every pixel coded unknown
    with pytest.raises(D.DataFileError, match=r"^scene 'middlebury2005/Art': ground truth '.*disp1.png' holds no known disparity \(every pixel is coded unknown\); is the file intact\?$"):
        D.load_middlebury2005("Art", tmp_path)
    _write_art(tmp_path)
    cv2.imwrite(str(folder / "view4.png"), np.zeros((12, 15), np.uint8))
    with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': view '{folder / 'view4.png'}' is 15x12 px, '{folder / 'view0.png'}' 16x12 px; are the files intact\?$"):
        D.load_middlebury2005("Art", tmp_path)
    moto = tmp_path / "skimage-motorcycle"
    moto.mkdir()
    for side in ("left", "right"):
        cv2.imwrite(str(moto / f"motorcycle_{side}.png"), np.zeros((6, 8), np.uint8))
    (moto / "motorcycle_disp.npz").write_bytes(b"not a zip file")
    with pytest.raises(DataNotFoundError, match=rf"^scene 'motorcycle': cannot read disparity '{moto / 'motorcycle_disp.npz'}': "):
        D.load_motorcycle(tmp_path)
    np.savez(moto / "motorcycle_disp.npz", other=np.zeros((6, 8)))
    with pytest.raises(DataNotFoundError, match=r"^scene 'motorcycle': cannot read disparity '.*': 'arr_0 is not a file in the archive'$"):
        D.load_motorcycle(tmp_path)
    np.savez(moto / "motorcycle_disp.npz", np.where(np.eye(6, 8) > 0, np.inf, 20.0))
    mc = D.load_motorcycle(tmp_path)  # +inf (unknown) is NaN
    np.testing.assert_array_equal(np.isnan(mc.disparity), np.eye(6, 8) > 0)
    assert np.nanmax(mc.disparity) == 20.0 and mc.colour_reference.shape == (6, 8, 3)


def test_unreadable_scene_files_are_data_file_errors(tmp_path, monkeypatch):
    """A file of a data set that is there but cannot be read is a DataFileError naming the scene, the file and the reason."""
    folder = _write_art(tmp_path)
    (folder / "view3.png").write_bytes(b"not a png")
    with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': cannot read image '{folder / 'view3.png'}': OpenCV could not decode it as PNG \(broken or truncated file\?\)$"):
        D.load_scene("middlebury2005/Art", tmp_path)
    folder = _write_art(tmp_path)
    (folder / "disp1.png").write_bytes(b"")
    with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': cannot read image '{folder / 'disp1.png'}': the file is empty$"):
        D.load_middlebury2005("Art", tmp_path)
    folder = _write_art(tmp_path)
    (folder / "view5.png").unlink()
    (folder / "view5.png").mkdir()
    with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': cannot read '{folder / 'view5.png'}': it is a directory, not a file; is the data folder intact\?$"):
        D.load_middlebury2005("Art", tmp_path)
    (folder / "view5.png").rmdir()
    folder = _write_art(tmp_path)
    (folder / "dmin.txt").write_bytes(b"\xff\xfe2\x000\x000\x00")  # UTF-16
    with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': cannot read '{folder / 'dmin.txt'}': not UTF-8 text \('utf-8' codec can't decode byte 0xff in position 0: invalid start byte\); expected one number \(dmin in full-size px\)$"):
        D.load_middlebury2005("Art", tmp_path)
    (folder / "dmin.txt").unlink()
    (folder / "dmin.txt").mkdir()
    with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': cannot read '{folder / 'dmin.txt'}': it is a directory, not a file; is the data folder intact\?$"):
        D.load_middlebury2005("Art", tmp_path)
    (folder / "dmin.txt").rmdir()
    folder = _write_art(tmp_path)
    real_read_text = type(folder).read_text

    def denied(self, *args, **kwargs):
        if self.name == "dmin.txt":
            raise PermissionError(13, "Permission denied", str(self))
        return real_read_text(self, *args, **kwargs)

    with monkeypatch.context() as m:  # (the tests may run as root, whom file modes do not stop)
        m.setattr(type(folder), "read_text", denied)
        with pytest.raises(D.DataFileError, match=rf"^scene 'middlebury2005/Art': cannot read '{folder / 'dmin.txt'}': Permission denied; expected one number \(dmin in full-size px\)$"):
            D.load_middlebury2005("Art", tmp_path)
    tsukuba = tmp_path / "tsukuba"
    tsukuba.mkdir()
    for k in range(1, 6):
        cv2.imwrite(str(tsukuba / f"scene1.row3.col{k}.ppm"), np.zeros((6, 8, 3), np.uint8))
    (tsukuba / "truedisp.row3.col3.pgm").write_bytes(b"P5\n8 6\n255\n\x10")  # truncated
    with pytest.raises(D.DataFileError, match=rf"^scene 'tsukuba': cannot read image '{tsukuba / 'truedisp.row3.col3.pgm'}': "):
        D.load_tsukuba(tmp_path)
    moto = tmp_path / "skimage-motorcycle"
    moto.mkdir()
    for side in ("left", "right"):
        cv2.imwrite(str(moto / f"motorcycle_{side}.png"), np.zeros((6, 8), np.uint8))
    np.savez(moto / "motorcycle_disp.npz", np.full((6, 8), 20.0))
    whole = (moto / "motorcycle_disp.npz").read_bytes()
    (moto / "motorcycle_disp.npz").write_bytes(whole[: len(whole) // 2])  # a truncated zip
    with pytest.raises(D.DataFileError, match=rf"^scene 'motorcycle': cannot read disparity '{moto / 'motorcycle_disp.npz'}': "):
        D.load_motorcycle(tmp_path)
    with open(moto / "motorcycle_disp.npz", "wb") as fh:  # one array, not an archive
        np.save(fh, np.full((6, 8), 20.0))
    with pytest.raises(D.DataFileError, match=r"^scene 'motorcycle': cannot read disparity '.*': expected an \.npz archive holding arr_0, got a single \.npy array$"):
        D.load_motorcycle(tmp_path)
    np.savez(moto / "motorcycle_disp.npz", np.full((6, 8), 20.0))
    (moto / "motorcycle_right.png").write_bytes(b"\x89PNG\r\n\x1a\n")  # the signature alone
    with pytest.raises(D.DataFileError, match=rf"^scene 'motorcycle': cannot read image '{moto / 'motorcycle_right.png'}': "):
        D.load_scene("motorcycle", tmp_path)
