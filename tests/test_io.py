"""Tests of nfdepth.io: readers, writers, atomic writes, errors."""

from __future__ import annotations

import os
import re

import cv2
import numpy as np
import pytest
import tifffile

from nfdepth.io import (
    ImageRangeError,
    ImageReadError,
    OutputExistsError,
    OutputWriteError,
    atomic_write,
    depth_to_points,
    read_image,
    read_pfm,
    to_grey,
    to_rgb8,
    write_array,
    write_colormap_png,
    write_pfm,
    write_ply,
)


def _ramp(h=5, w=7):
    return (np.arange(h)[:, None] * 10.0 + np.arange(w)[None, :]).astype(np.float32)


def _no_temp_files(folder):
    return [p.name for p in folder.iterdir() if p.name.endswith(".tmp")] == []


# ------------------------------------------------------------------ PFM


def test_pfm_round_trip_keeps_orientation_and_nan(tmp_path):
    a = _ramp()
    a[1, 2] = np.nan
    a[3, 4] = np.inf
    p = write_pfm(tmp_path / "a.pfm", a)
    b = read_pfm(p)
    assert b.dtype == np.float32 and b.shape == a.shape
    np.testing.assert_array_equal(b, a)  # NaN positions compared equal
    assert b[0, 0] == 0 and b[-1, 0] == 40  # top row stays on top


def test_pfm_file_layout_is_middlebury(tmp_path):
    a = _ramp(2, 3)
    p = write_pfm(tmp_path / "a.pfm", a)
    raw = p.read_bytes()
    assert raw.startswith(b"Pf\n3 2\n-1.0\n")
    body = np.frombuffer(raw[len(b"Pf\n3 2\n-1.0\n") :], "<f4").reshape(2, 3)
    np.testing.assert_array_equal(body, a[::-1])  # bottom row first


def test_pfm_big_endian_and_colour_read(tmp_path):
    a = _ramp(3, 4)
    p = tmp_path / "be.pfm"
    p.write_bytes(b"Pf\n4 3\n1.0\n" + np.ascontiguousarray(a[::-1], ">f4").tobytes())
    np.testing.assert_array_equal(read_pfm(p), a)
    rgb = np.stack([a, 2 * a, 3 * a], axis=-1)
    write_pfm(tmp_path / "c.pfm", rgb)
    np.testing.assert_array_equal(read_pfm(tmp_path / "c.pfm"), rgb)
    np.testing.assert_allclose(read_image(tmp_path / "c.pfm"), to_grey(rgb), rtol=1e-6)


def test_truncated_pfm(tmp_path):
    p = tmp_path / "t.pfm"
    p.write_bytes(b"Pf\n4 3\n-1.0\n" + b"\0" * 10)
    with pytest.raises(ImageReadError, match=r"cannot read image '.*t\.pfm': truncated PFM"):
        read_pfm(p)


# ------------------------------------------------------------------ write_array


@pytest.mark.parametrize("ext", [".pfm", ".tif", ".tiff", ".npy"])
def test_write_array_round_trip(tmp_path, ext):
    a = _ramp()
    a[2, 3] = np.nan
    p = write_array(tmp_path / f"d{ext}", a)
    b = read_image(p)
    assert b.dtype == np.float32
    np.testing.assert_array_equal(b, a)
    assert _no_temp_files(tmp_path)


def test_write_array_tiff_is_float32(tmp_path):
    p = write_array(tmp_path / "d.tif", _ramp().astype(np.float64))
    assert tifffile.imread(p).dtype == np.float32


def test_write_array_npy_keeps_float64(tmp_path):
    a = _ramp().astype(np.float64) / 3
    p = write_array(tmp_path / "d.npy", a)
    b = np.load(p)
    assert b.dtype == np.float64
    np.testing.assert_array_equal(b, a)
    np.testing.assert_array_equal(read_image(p, dtype=np.float64), a)


def test_write_array_rejects_bad_input(tmp_path):
    with pytest.raises(ValueError, match=r"path must end in one of \.pfm"):
        write_array(tmp_path / "d.png", _ramp())
    with pytest.raises(ValueError, match=r"array must be a non-empty array of shape \(H, W\), got shape \(2, 3, 4\)"):
        write_array(tmp_path / "d.npy", np.zeros((2, 3, 4)))
    with pytest.raises(TypeError, match="array must be a real numeric array"):
        write_array(tmp_path / "d.npy", np.array([["a", "b"]]))


# ------------------------------------------------------------------ atomic writes


def test_atomic_write_refuses_overwrite_without_force(tmp_path):
    p = tmp_path / "x.npy"
    write_array(p, _ramp())
    before = p.read_bytes()
    with pytest.raises(OutputExistsError, match=r"exists; pass force=True \(--force"):
        write_array(p, _ramp() + 1)
    assert p.read_bytes() == before
    write_array(p, _ramp() + 1, force=True)
    np.testing.assert_array_equal(np.load(p), _ramp() + 1)
    assert _no_temp_files(tmp_path)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["x.npy"]


def test_atomic_write_failure_leaves_nothing(tmp_path):
    def boom(fh):
        fh.write(b"partial")
        raise RuntimeError("writer failed")

    with pytest.raises(RuntimeError, match="writer failed"):
        atomic_write(tmp_path / "y.bin", boom)
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_bad_directory(tmp_path):
    with pytest.raises(OutputWriteError, match="does not exist"):
        atomic_write(tmp_path / "missing" / "z.bin", lambda fh: fh.write(b"1"))
    with pytest.raises(OutputWriteError, match="is a directory"):
        atomic_write(tmp_path, lambda fh: fh.write(b"1"), force=True)
    assert issubclass(OutputWriteError, ValueError) and issubclass(OutputExistsError, ValueError)


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="needs POSIX permissions and a non-root user")
def test_atomic_write_unwritable_directory(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(OutputWriteError, match="cannot write"):
            atomic_write(ro / "z.bin", lambda fh: fh.write(b"1"))
    finally:
        ro.chmod(0o700)


def test_atomic_write_refused_directory_any_user(tmp_path, monkeypatch):
    """The same error path for every user (root may write anywhere): the OS refuses the temporary file."""
    import errno
    import tempfile

    def refuse(*args, **kwargs):
        raise PermissionError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    with pytest.raises(OutputWriteError, match="cannot write .*z.bin.*Permission denied"):
        atomic_write(tmp_path / "z.bin", lambda fh: fh.write(b"1"))
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_full_disk_leaves_nothing(tmp_path):
    """A write that fails half way (disk full) leaves neither the target nor the temporary file."""
    import errno

    def half_then_full(fh):
        fh.write(b"partial")
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(OutputWriteError, match="No space left on device"):
        atomic_write(tmp_path / "z.bin", half_then_full)
    assert list(tmp_path.iterdir()) == []
    # an existing file survives a failed replacement untouched
    (tmp_path / "z.bin").write_bytes(b"old")
    with pytest.raises(OutputWriteError):
        atomic_write(tmp_path / "z.bin", half_then_full, force=True)
    assert [p.name for p in tmp_path.iterdir()] == ["z.bin"] and (tmp_path / "z.bin").read_bytes() == b"old"


@pytest.mark.skipif(os.name != "posix", reason="POSIX file modes")
def test_figure_file_mode_follows_umask(tmp_path):
    from nfdepth import plot

    mask = os.umask(0o027)
    try:
        fig = plot.colormap_panel(_ramp(), title="ramp", unit="px")
        png = plot.save_figure(fig, tmp_path / "sub" / "f.png")
        arr = write_array(tmp_path / "a.npy", _ramp())
    finally:
        os.umask(mask)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_mode & 0o777 == arr.stat().st_mode & 0o777 == 0o640
    assert _no_temp_files(tmp_path / "sub")


def test_colour_bar_range_checks_and_clipping_arrows():
    """The figure's range is checked as the plain PNG's is; values beyond it are drawn at its ends and the bar says so."""
    from nfdepth import plot

    ramp = np.arange(100, dtype=float).reshape(10, 10)
    with pytest.raises(ValueError, match=r"^vmax must be >= vmin, got vmin=5, vmax=1$"):
        plot.colormap_panel(ramp, title="r", unit="px", vmin=5, vmax=1)
    with pytest.raises(ValueError, match=r"^vmin must be a finite number, got nan$"):
        plot.colormap_panel(ramp, title="r", unit="px", vmin=float("nan"))

    def extend(**kw):
        fig = plot.colormap_panel(ramp, title="r", unit="px", **kw)
        (image,) = fig.axes[0].images
        return fig.axes[1]._colorbar.extend, image.get_clim()

    assert extend() == ("both", (pytest.approx(0.99), pytest.approx(98.01)))  # the 1st-99th percentiles
    assert extend(vmin=-1, vmax=99) == ("neither", (-1, 99))
    assert extend(vmin=-1, vmax=50) == ("max", (-1, 50))
    assert extend(vmin=500)[0] == "min"  # one end given beyond the data: the other follows it (no vmax < vmin error)
    empty = plot.colormap_panel(np.full((4, 4), np.nan), title="r", unit="depth")  # a run with no depth: no 0..1 scale
    assert len(empty.axes) == 1 and [t.get_text() for t in empty.axes[0].texts] == ["no finite value"]


def test_atomic_write_file_mode_follows_umask(tmp_path):
    p = atomic_write(tmp_path / "m.bin", lambda fh: fh.write(b"abc"))
    mask = os.umask(0o022)
    os.umask(mask)
    assert p.read_bytes() == b"abc"
    if os.name == "posix":
        assert p.stat().st_mode & 0o777 == 0o666 & ~mask


# ------------------------------------------------------------------ reading images


def test_png_16bit_read_exactly(tmp_path):
    a = np.arange(6 * 9, dtype=np.uint16).reshape(6, 9) * 1200
    p = tmp_path / "a.png"
    assert cv2.imwrite(str(p), a)
    b = read_image(p)
    assert b.dtype == np.float32 and b.max() == a.max() > 255
    np.testing.assert_array_equal(b, a.astype(np.float32))
    np.testing.assert_array_equal(read_image(p, dtype=None), a)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_pgm_read_exactly(tmp_path, dtype):
    a = (np.arange(5 * 8).reshape(5, 8) * (7 if dtype == np.uint8 else 1600)).astype(dtype)
    p = tmp_path / "a.pgm"
    assert cv2.imwrite(str(p), a)
    assert p.read_bytes()[:2] == b"P5"
    np.testing.assert_array_equal(read_image(p, dtype=np.float64), a.astype(np.float64))


def test_colour_png_to_grey_is_bt601_luma(tmp_path):
    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 256, size=(6, 7, 3), dtype=np.uint8)
    p = tmp_path / "c.png"
    assert cv2.imwrite(str(p), rgb[..., ::-1])  # cv2 writes BGR
    expected = 0.299 * rgb[..., 0] + 0.587 * rgb[..., 1] + 0.114 * rgb[..., 2]
    np.testing.assert_allclose(read_image(p, dtype=np.float64), expected, rtol=0, atol=1e-9)
    np.testing.assert_allclose(read_image(p), expected, rtol=1e-6)
    np.testing.assert_array_equal(read_image(p, grey=False, dtype=None), rgb)  # RGB order


def test_colour_ppm_and_rgba_png(tmp_path):
    rgb = np.random.default_rng(1).integers(0, 256, size=(4, 5, 3), dtype=np.uint8)
    p = tmp_path / "c.ppm"
    assert cv2.imwrite(str(p), rgb[..., ::-1])
    np.testing.assert_array_equal(read_image(p, grey=False, dtype=None), rgb)
    rgba = np.concatenate([rgb, np.full((4, 5, 1), 7, np.uint8)], axis=-1)
    q = tmp_path / "a.png"
    assert cv2.imwrite(str(q), rgba[..., [2, 1, 0, 3]])
    np.testing.assert_allclose(read_image(q), to_grey(rgb), rtol=1e-6)  # alpha dropped


def test_jpeg_and_tiff_colour(tmp_path):
    grey = np.full((8, 8), 120, np.uint8)
    p = tmp_path / "g.jpg"
    assert cv2.imwrite(str(p), grey)
    assert abs(float(read_image(p).mean()) - 120) < 1.5
    rgb = np.random.default_rng(2).integers(0, 256, size=(4, 5, 3), dtype=np.uint8)
    t = tmp_path / "c.tif"
    tifffile.imwrite(t, rgb)
    np.testing.assert_allclose(read_image(t), to_grey(rgb), rtol=1e-6)


def test_to_grey_shapes_and_errors():
    g = np.arange(6, dtype=np.uint8).reshape(2, 3)
    assert to_grey(g).dtype == np.float32
    np.testing.assert_array_equal(to_grey(g), g)
    np.testing.assert_array_equal(to_grey(np.stack([g, g], -1)), g)
    assert to_grey(np.ones((2, 2, 3))).dtype == np.float64
    np.testing.assert_allclose(to_grey(np.ones((2, 2, 3))), 1.0)
    with pytest.raises(ValueError, match=r"got shape \(2, 2, 5\)"):
        to_grey(np.ones((2, 2, 5)))
    with pytest.raises(TypeError, match="real numeric"):
        to_grey(np.ones((2, 2), complex))


# ------------------------------------------------------------------ read errors


def test_truncated_png(tmp_path):
    p = tmp_path / "t.png"
    assert cv2.imwrite(str(p), np.random.default_rng(3).integers(0, 256, (64, 64), dtype=np.uint8))
    data = p.read_bytes()
    p.write_bytes(data[: len(data) // 2])
    with pytest.raises(ImageReadError, match=r"cannot read image '.*t\.png': .*(broken or truncated)"):
        read_image(p)


def test_truncated_ppm_and_jpeg(tmp_path):
    p = tmp_path / "t.ppm"
    p.write_bytes(b"P6\n10 10\n255\n" + b"\1" * 50)
    with pytest.raises(ImageReadError, match=r"cannot read image '.*t\.ppm'"):
        read_image(p)
    j = tmp_path / "t.jpg"
    assert cv2.imwrite(str(j), np.zeros((16, 16), np.uint8))
    j.write_bytes(j.read_bytes()[:-40])
    with pytest.raises(ImageReadError, match="truncated JPEG"):
        read_image(j)


@pytest.mark.parametrize("name", ["e.png", "e.pgm", "e.tif", "e.npy", "e.pfm"])
def test_empty_file(tmp_path, name):
    p = tmp_path / name
    p.write_bytes(b"")
    with pytest.raises(ImageReadError, match=rf"cannot read image '.*{re.escape(name)}': the file is empty"):
        read_image(p)


def test_directory_missing_unsupported(tmp_path):
    d = tmp_path / "dir.png"
    d.mkdir()
    with pytest.raises(ImageReadError, match=r"cannot read image '.*dir\.png': it is a directory"):
        read_image(d)
    with pytest.raises(ImageReadError, match=r"cannot read image '.*nope\.png': no such file"):
        read_image(tmp_path / "nope.png")
    with pytest.raises(ImageReadError, match=r"no such file"):
        read_image(tmp_path / "nope.xyz")
    u = tmp_path / "a.gif"
    u.write_bytes(b"GIF89a")
    with pytest.raises(ImageReadError, match=r"unsupported extension '\.gif'"):
        read_image(u)
    assert issubclass(ImageReadError, ValueError)


def test_garbage_tiff_and_npy(tmp_path):
    for name in ("g.tif", "g.npy"):
        p = tmp_path / name
        p.write_bytes(b"this is not an image at all")
        with pytest.raises(ImageReadError, match=rf"cannot read image '.*{re.escape(name)}'"):
            read_image(p)


def test_float64_beyond_float32_is_named_not_called_non_finite(tmp_path):
    big = np.full((4, 5), 1.0)
    big[1, 2] = 1e300
    big[2, 3] = -1e40
    big[0, 0] = np.nan  # a NaN in the file is not an overflow
    np.save(tmp_path / "big.npy", big)
    msg = re.escape(f"cannot read image '{tmp_path / 'big.npy'}': 2 pixel(s) beyond the float32 range (max |value| 1e+300, float32 reaches 3.4e+38)")
    with pytest.raises(ImageRangeError, match=msg) as info:
        read_image(tmp_path / "big.npy")
    assert isinstance(info.value, ImageReadError)
    np.save(tmp_path / "rgb.npy", np.stack([big] * 3, axis=-1))
    with pytest.raises(ImageRangeError, match=": 2 pixel"):
        read_image(tmp_path / "rgb.npy")
    # float64 keeps them; dtype=None keeps the stored array; in range float64 is only narrowed
    assert read_image(tmp_path / "big.npy", dtype=np.float64)[1, 2] == 1e300
    assert read_image(tmp_path / "big.npy", dtype=None).dtype == np.float64
    np.save(tmp_path / "ok.npy", np.full((4, 5), 3e38))
    assert read_image(tmp_path / "ok.npy").dtype == np.float32


def test_read_image_dtype_check(tmp_path):
    p = write_array(tmp_path / "a.npy", _ramp())
    with pytest.raises(ValueError, match="dtype=int32 is not supported"):
        read_image(p, dtype=np.int32)
    bad = tmp_path / "b.npy"
    np.save(bad, np.zeros((2, 3, 4, 5)))
    with pytest.raises(ImageReadError, match=r"shape \(2, 3, 4, 5\)"):
        read_image(bad)


# ------------------------------------------------------------------ colour map


def test_colormap_png(tmp_path):
    a = _ramp()
    a[0, 0] = np.nan
    p = write_colormap_png(tmp_path / "q.png", a, cmap="viridis")
    img = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
    assert img.shape == (5, 7, 3) and img.dtype == np.uint8
    assert (img[0, 0] == 0).all()  # NaN black
    from matplotlib import colormaps

    top = np.array(colormaps["viridis"](1.0, bytes=True)[:3])
    np.testing.assert_array_equal(img[-1, -1, ::-1], top)  # max -> end of map (RGB)
    with pytest.raises(OutputExistsError):
        write_colormap_png(p, a)
    write_colormap_png(p, np.full((3, 3), np.nan), force=True)  # all unknown: black
    assert (cv2.imread(str(p)) == 0).all()
    with pytest.raises(ValueError, match="cmap must be a Matplotlib colour map name"):
        write_colormap_png(tmp_path / "r.png", a, cmap="no-such-map")
    with pytest.raises(ValueError, match="vmax must be >= vmin"):
        write_colormap_png(tmp_path / "r.png", a, vmin=3, vmax=1)


# ------------------------------------------------------------------ PLY


def _parse_ply(path):
    raw = path.read_bytes()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    header = raw[:end].decode("ascii").splitlines()
    n = int(next(line for line in header if line.startswith("element vertex")).split()[-1])
    props = [line.split() for line in header if line.startswith("property")]
    fields = [(p[2], "<f4" if p[1] == "float" else "u1") for p in props]
    return header, np.frombuffer(raw[end:], dtype=np.dtype(fields), count=n), len(raw) - end


def test_ply_header_count_and_vertices(tmp_path):
    pts = np.array([[1.5, -2.0, 3.25], [np.nan, 0, 1], [4, 5, 6], [0, np.inf, 1]])
    col = np.array([[255, 0, 10], [1, 2, 3], [7, 8, 9], [4, 5, 6]], np.uint8)
    p = write_ply(tmp_path / "c.ply", pts, colors=col)
    header, v, nbytes = _parse_ply(p)
    assert header[:2] == ["ply", "format binary_little_endian 1.0"]
    assert "element vertex 2" in header and header[-1] == "end_header"
    assert [h for h in header if h.startswith("property")] == [
        "property float x", "property float y", "property float z",
        "property uchar red", "property uchar green", "property uchar blue",
    ]
    assert nbytes == 2 * 15
    assert (v["x"][0], v["y"][0], v["z"][0]) == (1.5, -2.0, 3.25)
    assert (v["red"][0], v["green"][0], v["blue"][0]) == (255, 0, 10)
    assert (v["x"][1], v["red"][1]) == (4, 7)


def test_ply_without_colours_and_errors(tmp_path):
    p = write_ply(tmp_path / "p.ply", np.eye(3))
    header, v, nbytes = _parse_ply(p)
    assert "element vertex 3" in header and not any("red" in h for h in header) and nbytes == 36
    with pytest.raises(ValueError, match=r"points_xyz must have shape \(N, 3\), got shape \(3, 2\)"):
        write_ply(tmp_path / "q.ply", np.ones((3, 2)))
    with pytest.raises(TypeError, match="colors must be integers"):
        write_ply(tmp_path / "q.ply", np.ones((2, 3)), colors=np.ones((2, 3)))
    with pytest.raises(ValueError, match="colors must lie in 0..255"):
        write_ply(tmp_path / "q.ply", np.ones((2, 3)), colors=np.full((2, 3), 300))


def test_depth_to_points_follows_conventions():
    z = np.full((3, 5), 2.0)
    z[0, 0] = np.nan
    z[2, 4] = -1
    img = np.arange(15, dtype=np.uint8).reshape(3, 5)
    pts, col = depth_to_points(z, focal_px=4.0, image=img)
    assert pts.shape == (13, 3) and col.shape == (13, 3) and col.dtype == np.uint8
    # pixel (row 1, col 2) is the image centre -> on the optical axis
    i = 5 - 1 + 2  # row-major index among kept pixels: row 0 has 4 kept, then (1,0),(1,1),(1,2)
    np.testing.assert_allclose(pts[i], [0, 0, 2])
    np.testing.assert_array_equal(col[i], [7, 7, 7])
    pts2, none = depth_to_points(z, focal_px=4.0, cx_px=0.0, cy_px=0.0)
    assert none is None
    # pixel (row 2, col 3): X = (3 - 0) * 2 / 4, Y = (2 - 0) * 2 / 4
    np.testing.assert_allclose(pts2[-1], [1.5, 1.0, 2.0])
    with pytest.raises(ValueError, match="focal_px must be a positive finite number"):
        depth_to_points(z, focal_px=0)
    with pytest.raises(ValueError, match=r"image must have shape \(3, 5\)"):
        depth_to_points(z, focal_px=1, image=np.zeros((2, 2)))


def test_to_rgb8_scales_every_bit_depth_to_8_bits():
    grey16 = np.array([[0, 1000], [30000, 60000]], dtype=np.uint16)
    out = to_rgb8(grey16)
    assert out.shape == (2, 2, 3) and out.dtype == np.uint8
    np.testing.assert_array_equal(out[..., 0], np.rint(grey16 * 255.0 / 60000))
    np.testing.assert_array_equal(out[..., 0], out[..., 2])
    rgba8 = np.arange(2 * 2 * 4, dtype=np.uint8).reshape(2, 2, 4)
    np.testing.assert_array_equal(to_rgb8(rgba8), rgba8[..., :3])  # 8-bit kept, alpha dropped
    rgba16 = np.zeros((1, 2, 4), np.uint16)
    rgba16[..., 3] = 65535  # alpha does not set the scale
    rgba16[0, 1, :3] = (100, 300, 400)
    np.testing.assert_array_equal(to_rgb8(rgba16)[0, 1], [64, 191, 255])
    floats = np.array([[0.5, np.nan], [-1.0, np.inf]])  # below 1: scaled as 0..1
    np.testing.assert_array_equal(to_rgb8(floats)[..., 0], [[128, 0], [0, 255]])
    np.testing.assert_array_equal(to_rgb8(np.zeros((2, 2, 2)))[..., 1], 0)  # grey + alpha
    with pytest.raises(ValueError, match="shape"):
        to_rgb8(np.zeros((2, 2, 5)))
    with pytest.raises(TypeError, match="dtype"):
        to_rgb8(np.array([["a"]]))


def test_to_float32_map_refuses_values_float32_cannot_hold():
    """Finite depths beyond float32 would be written as inf (or 0); NaN and inf pass as they are."""
    from nfdepth.io import to_float32_map

    ok = np.array([[1.5, np.nan], [np.inf, -2.0e30]])
    out = to_float32_map(ok)
    assert out.dtype == np.float32
    np.testing.assert_array_equal(out, ok.astype(np.float32))
    with pytest.raises(ValueError, match=r"a depth of 5e\+40 does not fit a float32 output .*: use metres"):
        to_float32_map(np.array([1.0, 5e40]), what="a depth", hint="use metres")
    with pytest.raises(ValueError, match=r"a value of 1e-50 does not fit"):
        to_float32_map(np.array([1.0, 1e-50]))


# ------------------------------------------------------------------ more read paths


def test_pfm_bad_scale_and_directory(tmp_path):
    p = tmp_path / "s.pfm"
    p.write_bytes(b"Pf\n2 2\n--1\n" + b"\0" * 16)  # the header's number pattern matches, the number does not parse
    with pytest.raises(ImageReadError) as info:
        read_pfm(p)
    assert str(info.value) == f"cannot read image '{p}': bad PFM scale b'--1'"
    with pytest.raises(ImageReadError, match=r"^cannot read image '.*': it is a directory, not a file$"):
        read_pfm(tmp_path)


@pytest.mark.parametrize("name", ["m.tif", "m.tiff", "m.npy"])
def test_missing_tiff_and_npy(tmp_path, name):
    with pytest.raises(ImageReadError) as info:
        read_image(tmp_path / name)
    assert str(info.value) == f"cannot read image '{tmp_path / name}': no such file"


def test_unreadable_file_names_the_reason(tmp_path, monkeypatch):
    """The OS refusing the read (permissions; root ignores them, so simulated) is a read error naming the file."""
    import errno
    from pathlib import Path

    p = tmp_path / "v.png"
    assert cv2.imwrite(str(p), np.zeros((4, 4), np.uint8))

    def refused(self):
        raise PermissionError(errno.EACCES, "Permission denied", str(self))

    monkeypatch.setattr(Path, "read_bytes", refused)
    with pytest.raises(ImageReadError) as info:
        read_image(p)
    assert str(info.value) == f"cannot read image '{p}': Permission denied"


def test_planar_tiff_is_read_as_rgb(tmp_path):
    """A TIFF stored plane by plane, (3, H, W), comes back as (H, W, 3) in R, G, B order."""
    rgb = np.random.default_rng(4).integers(0, 256, size=(5, 7, 3), dtype=np.uint8)
    p = tmp_path / "planar.tif"
    tifffile.imwrite(p, np.moveaxis(rgb, -1, 0), photometric="rgb", planarconfig="separate")
    assert tifffile.imread(p).shape == (3, 5, 7)
    np.testing.assert_array_equal(read_image(p, grey=False, dtype=None), rgb)
    np.testing.assert_allclose(read_image(p, dtype=np.float64), 0.299 * rgb[..., 0] + 0.587 * rgb[..., 1] + 0.114 * rgb[..., 2], atol=1e-9)


def test_npy_contents_checked(tmp_path):
    np.save(tmp_path / "one.npy", _ramp()[..., None])  # (H, W, 1): a grey map
    np.testing.assert_array_equal(read_image(tmp_path / "one.npy"), _ramp())
    assert read_image(tmp_path / "one.npy", grey=False, dtype=None).shape == (5, 7)
    for name, array, dtype in (("c.npy", np.ones((2, 2), complex), "complex128"), ("s.npy", np.array([["a", "b"]]), "<U1")):
        np.save(tmp_path / name, array)
        with pytest.raises(ImageReadError) as info:
            read_image(tmp_path / name)
        assert str(info.value) == f"cannot read image '{tmp_path / name}': holds dtype {dtype}, expected real numbers"
    np.save(tmp_path / "b.npy", np.array([[True, False]]))
    np.testing.assert_array_equal(read_image(tmp_path / "b.npy"), [[1.0, 0.0]])


def test_npy_header_asking_for_too_much_memory(tmp_path):
    """A broken header claiming 2**47 float64 values (1 PB): a read error, not a MemoryError."""
    from numpy.lib import format as npy_format

    p = tmp_path / "huge.npy"
    with open(p, "wb") as fh:
        npy_format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False, "shape": (2**47,)})
        fh.write(b"\0" * 64)
    with pytest.raises(ImageReadError) as info:
        read_image(p)
    assert str(info.value) == f"cannot read image '{p}': its NPY header asks for more memory than is available (broken header?)"


# ------------------------------------------------------------------ more atomic-write paths


def test_atomic_write_needs_a_callable(tmp_path):
    with pytest.raises(TypeError, match=r"^writer_fn must be callable, got bytes$"):
        atomic_write(tmp_path / "x.bin", b"data")
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_a_target_that_appears_meanwhile_is_kept(tmp_path):
    """Another writer creates the target while ours is being written: without force ours is refused, theirs kept."""
    target = tmp_path / "x.bin"

    def racing(fh):
        target.write_bytes(b"theirs")  # another process, between our check and our rename
        fh.write(b"ours")

    with pytest.raises(OutputExistsError, match=r"exists; pass force=True"):
        atomic_write(target, racing)
    assert target.read_bytes() == b"theirs"
    assert [p.name for p in tmp_path.iterdir()] == ["x.bin"]  # no temporary file


@pytest.mark.parametrize("race", [False, True])
def test_atomic_write_without_hard_links(tmp_path, monkeypatch, race):
    """A file system without hard links (FAT, some network shares): written by rename; a target that appeared is still refused."""
    import errno

    def no_links(src, dst):
        raise OSError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(os, "link", no_links)
    target = tmp_path / "x.bin"

    def writer(fh):
        if race:
            target.write_bytes(b"theirs")
        fh.write(b"ours")

    if race:
        with pytest.raises(OutputExistsError, match=r"exists; pass force=True"):
            atomic_write(target, writer)
    else:
        assert atomic_write(target, writer) == target
    assert target.read_bytes() == (b"theirs" if race else b"ours")
    assert [p.name for p in tmp_path.iterdir()] == ["x.bin"]


# ------------------------------------------------------------------ more PLY and point paths


def test_ply_refuses_non_numbers_and_mismatched_colours(tmp_path):
    with pytest.raises(TypeError, match=r"^points_xyz must be a real numeric array, got dtype <U1$"):
        write_ply(tmp_path / "p.ply", np.array([["a", "b", "c"]]))
    with pytest.raises(TypeError, match=r"^points_xyz must be a real numeric array, got dtype complex128$"):
        write_ply(tmp_path / "p.ply", np.ones((2, 3), complex))
    with pytest.raises(ValueError, match=r"^colors must have shape \(2, 3\) like points_xyz, got shape \(3, 3\)$"):
        write_ply(tmp_path / "p.ply", np.ones((2, 3)), colors=np.zeros((3, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []


def test_depth_to_points_principal_point_and_float_colours():
    z = np.full((2, 2), 4.0)
    for name in ("cx_px", "cy_px"):
        with pytest.raises(ValueError, match=rf"^{name} must be a finite number, got nan$"):
            depth_to_points(z, focal_px=2.0, **{name: np.nan})
    image = np.array([[-3.0, 100.4], [np.nan, 300.0]])  # float: rounded, clipped to 0..255, NaN black
    pts, col = depth_to_points(z, focal_px=2.0, image=image)
    np.testing.assert_array_equal(col, [[0, 0, 0], [100, 100, 100], [0, 0, 0], [255, 255, 255]])
    assert col.dtype == np.uint8
    # (col - 0.5) * 4 / 2, (row - 0.5) * 4 / 2
    np.testing.assert_array_equal(pts, np.array([[-1, -1, 4], [1, -1, 4], [-1, 1, 4], [1, 1, 4]], np.float32))
    rgb16 = np.zeros((2, 2, 3), np.uint16)
    rgb16[0, 1] = (10, 200, 65535)
    _, col16 = depth_to_points(z, focal_px=2.0, image=rgb16)
    np.testing.assert_array_equal(col16[1], [10, 200, 255])  # not scaled: clipped (to_rgb8 scales)


def test_compressed_tiffs_that_tifffile_cannot_decode_are_read_by_opencv(tmp_path):
    """OpenCV writes LZW-compressed TIFFs by default, which tifffile decodes only with the optional imagecodecs: such
    files were refused as 'not a readable TIFF'. They are read through OpenCV instead (8 and 16 bits, RGB; and
    OpenCV's uncompressed float32 as before)."""
    import tifffile

    rng = np.random.default_rng(0)
    cases = {
        "u8": rng.integers(0, 256, (24, 32), dtype=np.uint8),
        "u16": rng.integers(0, 65536, (24, 32), dtype=np.uint16),
        "f32": rng.normal(100.0, 30.0, (24, 32)).astype(np.float32),
        "rgb": rng.integers(0, 256, (24, 32, 3), dtype=np.uint8),
    }
    for name, img in cases.items():
        path = tmp_path / f"{name}.tif"
        assert cv2.imwrite(str(path), img[..., ::-1] if img.ndim == 3 else img)
        with tifffile.TiffFile(path) as tif:
            assert tif.pages[0].compression == (1 if name == "f32" else 5)  # LZW (OpenCV leaves float32 uncompressed)
        got = read_image(path, grey=False, dtype=None)
        np.testing.assert_array_equal(got, img)


# ------------------------------------------------------------------ acceptance pass 5 (files in and out)


def test_pfm_with_crlf_header_reads_right_and_misaligned_data_is_refused(tmp_path):
    """A Windows writer's CR LF after the scale is one line end: the pixels are not read one byte off."""
    a = np.arange(12, dtype=np.float32).reshape(3, 4) + 0.5
    p = tmp_path / "c.pfm"
    p.write_bytes(b"Pf\r\n4 3\r\n-1.0\r\n" + a[::-1].astype("<f4").tobytes())
    np.testing.assert_array_equal(read_pfm(p), a)
    p.write_bytes(b"Pf\n4 3\n-1.0\n" + a[::-1].astype("<f4").tobytes() + b"\0")  # one byte too many
    with pytest.raises(ImageReadError, match=r"expected 48 bytes of pixel data after the header \(4 x 3 x 1 float32\), found 49"):
        read_pfm(p)


def test_tiff_colour_types_are_honoured_or_refused(tmp_path):
    """Palette -> its colours, MinIsWhite inverted, 1 bit -> 0/255; stacks, CMYK and YCbCr refused (not read as RGB)."""
    from PIL import Image

    rng = np.random.default_rng(5)
    rgb = rng.integers(0, 256, (20, 30, 3), dtype=np.uint8)
    grey = rng.integers(0, 256, (20, 30), dtype=np.uint8)
    Image.fromarray(rgb).convert("P").save(tmp_path / "p.tif")
    Image.fromarray(rgb).convert("P").save(tmp_path / "p.png")
    np.testing.assert_array_equal(read_image(tmp_path / "p.tif", grey=False, dtype=None), read_image(tmp_path / "p.png", grey=False, dtype=None))
    tifffile.imwrite(tmp_path / "w.tif", grey, photometric="miniswhite")
    np.testing.assert_array_equal(read_image(tmp_path / "w.tif", dtype=None), 255 - grey)
    bits = grey > 128
    tifffile.imwrite(tmp_path / "b.tif", bits, photometric="minisblack")
    Image.fromarray(bits).save(tmp_path / "b.png")
    np.testing.assert_array_equal(read_image(tmp_path / "b.tif", dtype=None), bits.astype(np.uint8) * 255)
    tifffile.imwrite(tmp_path / "bw.tif", bits)  # tifffile's bilevel default is MinIsWhite: a set bit is black, as viewers show it
    np.testing.assert_array_equal(read_image(tmp_path / "bw.tif", dtype=None), (~bits).astype(np.uint8) * 255)
    np.testing.assert_array_equal(read_image(tmp_path / "b.tif", dtype=None), read_image(tmp_path / "b.png", dtype=None))
    tifffile.imwrite(tmp_path / "s.tif", np.stack([grey, grey, grey]), photometric="minisblack")
    with pytest.raises(ImageReadError, match=r"'.*s\.tif': holds 3 images \(pages\); expected one image per file"):
        read_image(tmp_path / "s.tif")
    with tifffile.TiffWriter(tmp_path / "two.tif") as w:
        w.write(grey)
        w.write(grey)
    with pytest.raises(ImageReadError, match=r"holds 2 images \(pages\)"):
        read_image(tmp_path / "two.tif")
    Image.fromarray(rgb).convert("CMYK").save(tmp_path / "k.tif")
    with pytest.raises(ImageReadError, match=r"holds CMYK \(separated\) colour; expected a grey, RGB or palette TIFF"):
        read_image(tmp_path / "k.tif")
    Image.fromarray(rgb).convert("YCbCr").save(tmp_path / "y.tif")
    with pytest.raises(ImageReadError, match=r"holds YCbCr colour"):
        read_image(tmp_path / "y.tif")
    tifffile.imwrite(tmp_path / "planar.tif", np.moveaxis(rgb, -1, 0), photometric="rgb", planarconfig="separate")
    np.testing.assert_array_equal(read_image(tmp_path / "planar.tif", grey=False, dtype=None), rgb)


def test_damaged_jpeg_is_refused_and_decoder_messages_stay_off_stderr(tmp_path, capfd):
    """A JPEG whose data end early but with an end marker decodes (the rest grey): libjpeg says so on stderr only."""
    img = np.tile(np.arange(200, dtype=np.uint8), (200, 1))
    _, enc = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 95])
    data = enc.tobytes()
    p = tmp_path / "half.jpg"
    p.write_bytes(data[: len(data) // 2] + b"\xff\xd9")
    with pytest.raises(ImageReadError, match=r"'.*half\.jpg': damaged JPEG \(libjpeg: Corrupt JPEG data: premature end of data segment\)"):
        read_image(p)
    (tmp_path / "whole.jpg").write_bytes(data)
    assert read_image(tmp_path / "whole.jpg").shape == (200, 200)
    _, png = cv2.imencode(".png", np.random.default_rng(1).integers(0, 256, (300, 300), dtype=np.uint8))
    (tmp_path / "cut.png").write_bytes(png.tobytes()[: int(png.size * 0.95)])
    with pytest.raises(ImageReadError, match=r"could not decode it as PNG"):
        read_image(tmp_path / "cut.png")
    assert capfd.readouterr().err == ""


def test_writers_refuse_another_format_s_name_and_values_beyond_float32(tmp_path):
    with pytest.raises(ValueError, match=r"path must end in \.png, got '.*x\.pfm'"):
        write_colormap_png(tmp_path / "x.pfm", np.ones((3, 3)))
    with pytest.raises(ValueError, match=r"path must end in \.ply"):
        write_ply(tmp_path / "x.png", np.ones((2, 3)))
    big = np.array([[1.0, 1e300], [2.0, np.nan]])
    for ext in (".pfm", ".tif"):
        with pytest.raises(ValueError, match=rf"a value of 1e\+300 does not fit a float32 output .*a \{ext} file stores float32: rescale the map, or write \.npy"):
            write_array(tmp_path / f"m{ext}", big)
    with pytest.raises(ValueError, match=r"a value of 1e\+300"):
        write_pfm(tmp_path / "m.pfm", big)
    with pytest.raises(ValueError, match=r"a coordinate of 1e\+300 does not fit"):
        write_ply(tmp_path / "p.ply", np.array([[1.0, 2.0, 1e300]]))
    np.testing.assert_array_equal(np.load(write_array(tmp_path / "m.npy", big)), big)  # float64 kept
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.npy"]


@pytest.mark.skipif(not hasattr(os, "symlink"), reason="needs symbolic links")
def test_a_link_to_a_missing_file_counts_as_existing(tmp_path):
    """os.link refuses a dangling link at the end of the write: it is refused up front, and replaced with force."""
    link = tmp_path / "dl.pfm"
    try:
        os.symlink(tmp_path / "nowhere.pfm", link)
    except OSError:  # pragma: no cover - no symlink rights (Windows)
        pytest.skip("cannot create symbolic links here")
    with pytest.raises(OutputExistsError, match="exists; pass force=True") as info:
        write_array(link, np.ones((2, 2)))
    assert info.value.path == link
    write_array(link, np.ones((2, 2)), force=True)
    assert not link.is_symlink() and read_pfm(link).shape == (2, 2)


def test_colormap_png_limits_are_numbers(tmp_path):
    """vmin='abc' was NumPy's 'could not convert string to float', vmin=True taken as 1.0."""
    from nfdepth.io import write_colormap_png

    for value, match in (("abc", r"^vmin must be a finite number, got 'abc' \(str, not a number\)$"), (True, r"^vmin must be a finite number, got True \(bool, not a number\)$")):
        with pytest.raises(TypeError, match=match):
            write_colormap_png(tmp_path / "m.png", np.ones((3, 3)), vmin=value)
    with pytest.raises(ValueError, match=r"^vmax must be a finite number, got inf$"):
        write_colormap_png(tmp_path / "m.png", np.ones((3, 3)), vmax=float("inf"))
    assert not list(tmp_path.iterdir())


def test_point_cloud_principal_point_is_a_number():
    """cx_px='a' was Python's 'could not convert string to float'."""
    from nfdepth.io import depth_to_points

    with pytest.raises(TypeError, match=r"^cx_px must be a finite number, got 'a' \(str, not a number\)$"):
        depth_to_points(np.ones((4, 4)), focal_px=100.0, cx_px="a")
    with pytest.raises(ValueError, match=r"^cy_px must be a finite number, got inf$"):
        depth_to_points(np.ones((4, 4)), focal_px=100.0, cy_px=float("inf"))


def test_a_complete_jpeg_with_bytes_after_its_end_is_read(tmp_path):
    """A trailer after the end-of-image marker (a phone's motion photo appends a video there) was 'truncated JPEG'."""
    rng = np.random.default_rng(4)
    img = cv2.GaussianBlur((rng.random((48, 64)) * 255).astype(np.uint8), (0, 0), 2)
    p = tmp_path / "a.jpg"
    for params in ([], [cv2.IMWRITE_JPEG_PROGRESSIVE, 1], [cv2.IMWRITE_JPEG_RST_INTERVAL, 2]):
        assert cv2.imwrite(str(p), img, params)
        data = p.read_bytes()
        want = read_image(p)
        for trailer in (b"\n", b"\0" * 7, rng.bytes(4096), b"\xff\xd8\xff\xe1" + rng.bytes(300) + b"\xff\xd9"):
            p.write_bytes(data + trailer)
            np.testing.assert_array_equal(read_image(p), want)
        # cut anywhere inside, it is refused, also when what is left ends in FF D9 by chance
        for cut in (len(data) // 3, len(data) - 40, len(data) - 3):
            p.write_bytes(data[:cut])
            with pytest.raises(ImageReadError, match="truncated JPEG"):
                read_image(p)
        scan = data.rindex(b"\xff\xda")
        p.write_bytes(data[: scan + 30] + b"\xff\xd9")  # the scan cut short, then an end marker: refused all the same
        with pytest.raises(ImageReadError, match="truncated JPEG|damaged JPEG"):
            read_image(p)


def test_a_tiff_that_cannot_be_read_is_an_image_read_error(tmp_path, monkeypatch):
    """A TIFF the system refuses to read was a raw PermissionError (the CLI: 'cannot write', exit 4)."""
    import pathlib

    p = tmp_path / "denied.tif"
    tifffile.imwrite(p, np.zeros((4, 4), np.uint8))

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tifffile, "TiffFile", refuse)
    monkeypatch.setattr(pathlib.Path, "read_bytes", refuse)
    with pytest.raises(ImageReadError, match=r"^cannot read image '.*denied\.tif': Permission denied$"):
        read_image(p)


def test_write_array_npy_keeps_wide_floats_and_refuses_what_it_cannot_hold(tmp_path):
    """Big-endian float64 and long double were written as float32: 1e300 became inf."""
    a = _ramp().astype(np.float64) * 1e298
    for dtype in (">f8", np.longdouble):
        p = write_array(tmp_path / "w.npy", a.astype(dtype), force=True)
        b = np.load(p)
        assert b.dtype == np.float64
        np.testing.assert_array_equal(b, a)
    b = np.load(write_array(tmp_path / "h.npy", (a / 1e298).astype(">f4")))  # other floats: float32
    assert b.dtype == np.float32
    np.testing.assert_array_equal(b, _ramp())
    if np.finfo(np.longdouble).max > np.finfo(np.float64).max:
        huge = np.full((2, 2), np.longdouble(10) ** 400)
        with pytest.raises(ValueError, match=r"^a value of 1\.00e\+400 does not fit a float64 output \(about 1e-308 to 1\.8e308\): rescale the map$"):
            write_array(tmp_path / "x.npy", huge)
        assert not (tmp_path / "x.npy").exists()


def test_colormap_png_one_end_given_beyond_the_data(tmp_path):
    """vmin=20 on values 0..10 said 'vmax must be >= vmin, got vmin=20.0, vmax=10.0': a vmax never given."""
    from matplotlib import colormaps

    a = np.linspace(0.0, 10.0, 12).reshape(3, 4)
    low, mid, high = (np.array(colormaps["turbo"](v, bytes=True)[:3]) for v in (0.0, 0.5, 1.0))

    def drawn(**limits):
        p = write_colormap_png(tmp_path / "m.png", a, force=True, **limits)
        return cv2.imread(str(p))[..., ::-1]

    assert (drawn(vmin=20.0) == low).all()  # every value below vmin
    assert (drawn(vmax=-5.0) == high).all()  # every value above vmax
    img = drawn(vmin=5.0, vmax=5.0)  # one value: below it low, above it high
    assert (img[a < 5] == low).all() and (img[a > 5] == high).all()
    b = a.copy()
    b[0, 0] = 5.0
    p = write_colormap_png(tmp_path / "n.png", b, vmin=5.0, vmax=5.0)
    assert (cv2.imread(str(p))[0, 0, ::-1] == mid).all()
    with pytest.raises(ValueError, match=r"^vmax must be >= vmin, got vmin=3\.0, vmax=1\.0$"):
        write_colormap_png(tmp_path / "r.png", a, vmin=3, vmax=1)
