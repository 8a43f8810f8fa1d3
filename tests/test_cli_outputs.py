"""What the commands write: never over an input, figures with the usual file mode, PLY colours of 16-bit views."""

import os
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_runner import run_cli

from nfdepth.cli import main

ROOT = Path(__file__).resolve().parents[1]
RIG = ROOT / "examples" / "paper_pyramid_rig.toml"


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The demo's output folder (figures, and the 16-bit example views in ``example/``)."""
    out = tmp_path_factory.mktemp("demo") / "demo"
    mask = os.umask(0o022)
    try:
        assert main(["demo", "--out", str(out)]) == 0
    finally:
        os.umask(mask)
    return out


@pytest.fixture
def work(tmp_path, demo):
    """A copy of the demo's example views (stereo, dynamic, rail) to write next to."""
    example = tmp_path / "example"
    shutil.copytree(demo / "example", example)
    return example


def _views(work):
    return [work / f"pyramid_view{k}.png" for k in range(3)]


# ------------------------------------------------------- outputs are never inputs


def _input_clash_cases(w: Path) -> dict:
    """{name: (argv, option, the input it names)}: each writes one output over one of its inputs."""
    v = [str(p) for p in _views(w)]
    dyn = [str(w / f"dynamic_I{k}.png") for k in range(1, 6)]
    np.save(w / "xn1.npy", cv2.imread(v[1], cv2.IMREAD_UNCHANGED).astype(np.float64))
    npys = [v[0], str(w / "xn1.npy"), v[2]]
    out = str(w.parent / "o.pfm")
    frame = str(w / "rail" / "frame_003.png")
    cases = [
        ("stereo --preview", ["stereo", *v, "--out", out, "--preview", v[0]], "--preview", v[0]),
        ("stereo --out", ["stereo", *npys, "--out", npys[1]], "--out", npys[1]),
        ("stereo --figure", ["stereo", *v, "--out", out, "--figure", v[2]], "--figure", v[2]),
        ("stereo --uncertainty", ["stereo", *npys, "--out", out, "--uncertainty", npys[1]], "--uncertainty", npys[1]),
        ("stereo --column", ["stereo", *v, "--column", str(w / "pyramid_column0.png"), v[1], "--out", out, "--preview", str(w / "pyramid_column0.png")], "--preview", "pyramid_column0.png"),
        ("stereo through a symbolic link", ["stereo", *v, "--out", out, "--preview", str(w / "link.png")], "--preview", v[1]),
        ("stereo relative path", ["stereo", *v, "--out", out, "--preview", os.path.join(str(w), "..", w.name, "pyramid_view1.png")], "--preview", v[1]),
        ("view default output", ["view", v[0]], "the default output", v[0]),  # no --out given: not told as one
        ("view --colorbar", ["view", v[0], "--colorbar", "--out", v[0]], "--out", v[0]),
        ("dynamic --preview", ["dynamic", *dyn, "--rig", RIG, "--out", out, "--preview", dyn[2]], "--preview", dyn[2]),
        ("dynamic --figure", ["dynamic", *dyn, "--rig", RIG, "--out", out, "--figure", dyn[0]], "--figure", dyn[0]),
        ("video --figure", ["video", str(w / "rail" / "*.png"), "--rig", RIG, "--out", str(w.parent / "v.npz"), "--figure", frame], "--figure", frame),
        ("video --out folder", ["video", str(w / "rail"), "--rig", RIG, "--out", str(w / "rail")], "--out", str(w / "rail")),
        (
            "dynamic videos --figure",
            ["dynamic", "--moving-video", str(w / "dynamic_I*.png"), "--reference-video", str(w / "dynamic_I*.png"), "--crossings", "2",
             "--rig", RIG, "--out", str(w.parent / "c.npz"), "--figure", dyn[4]],
            "--figure",
            dyn[4],
        ),
    ]
    return {name: rest for name, *rest in cases}


CLASHES = [
    "stereo --preview", "stereo --out", "stereo --figure", "stereo --uncertainty", "stereo --column", "stereo through a symbolic link",
    "stereo relative path", "view default output", "view --colorbar", "dynamic --preview", "dynamic --figure", "video --figure",
    "video --out folder", "dynamic videos --figure",
]


@pytest.mark.parametrize("name", CLASHES)
def test_an_output_is_never_an_input_even_with_force(work, capfd, name):
    try:
        os.symlink(work / "pyramid_view1.png", work / "link.png")
    except OSError:  # pragma: no cover - Windows without the privilege
        if "symbolic" in name:
            pytest.skip("no symbolic links here")
    cases = _input_clash_cases(work)
    assert sorted(cases) == sorted(CLASHES)
    argv, option, victim = cases[name]
    before = {p: p.read_bytes() for p in work.rglob("*") if p.is_file()}
    listing = sorted(work.parent.rglob("*"))
    code, _, err = run_cli(capfd, *argv, "--force")
    assert code == 2, (name, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"nfdepth: error: {option} '"), lines[0]
    if option.startswith("--"):
        assert "is the input '" in lines[0], lines[0]
    else:  # the path derived from the input's name
        assert lines[0] == f"nfdepth: error: the default output '{victim}' (the input's name with .png) is the input itself; give --out (--force never overwrites an input)"
    assert Path(victim).name in lines[0] and "--force never overwrites an input" in lines[0]
    # nothing written, nothing changed
    assert sorted(work.parent.rglob("*")) == listing
    assert {p: p.read_bytes() for p in work.rglob("*") if p.is_file()} == before


def test_an_output_next_to_the_inputs_is_fine(work, capfd):
    out = work / "pyramid_view1.npy"  # same stem as an input, another file
    code, _, err = run_cli(capfd, "stereo", *_views(work), "--out", out, "--preview", work / "p.png")
    assert code == 0, err
    assert out.is_file() and (work / "p.png").is_file()


# ------------------------------------------------ the folders a failed run made


def test_reproduce_failing_removes_the_folders_it_made(tmp_path, capfd, monkeypatch):
    """A write failing on the 3rd figure (a full disk) removes the figures and the folders ``--out`` made: ``new`` and ``new/figs``."""
    import errno

    from nfdepth import plot

    real, calls = plot.save_figure, []

    def failing(fig, path, **kwargs):
        calls.append(path)
        if len(calls) == 3:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real(fig, path, **kwargs)

    monkeypatch.setattr(plot, "save_figure", failing)
    out = tmp_path / "new" / "figs"
    code, _, err = run_cli(capfd, "reproduce", "--only", "exp1", "--no-compare", "--out", out)
    assert code == 4 and len(calls) == 3
    assert err == (
        f"nfdepth: error: cannot write '{calls[2]}': No space left on device; removed the 2 output(s) it had completed"
        f" and the folders it made ({tmp_path / 'new'}, {out})\n"
    )
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("interruption", "code", "line"), [("KeyboardInterrupt", 130, "interrupted"), ("_Terminated", 143, "terminated (SIGTERM)")])
def test_demo_interrupted_removes_the_folders_it_made(tmp_path, capfd, monkeypatch, interruption, code, line):
    """Ctrl-C or SIGTERM at the demo's last file (its point cloud): no file and no folder of it is left, ``example/rail`` included."""
    from nfdepth import cli, io

    exc = KeyboardInterrupt if interruption == "KeyboardInterrupt" else cli._Terminated

    def interrupted(*args, **kwargs):
        raise exc()

    monkeypatch.setattr(io, "write_ply", interrupted)
    out = tmp_path / "new" / "demo"
    got, _, err = run_cli(capfd, "demo", "--out", out)
    assert got == code
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"nfdepth: {line}; no partial output written; removed the "), err
    made = ", ".join(str(p) for p in (tmp_path / "new", out, out / "example", out / "example" / "rail"))
    assert lines[0].endswith(f" output(s) it had completed and the folders it made ({made})"), err
    assert list(tmp_path.iterdir()) == []


def test_demo_into_an_existing_folder_keeps_it(tmp_path, capfd, monkeypatch):
    """A folder the run did not make stays (with what was in it before); only the run's own files and folders go."""
    from nfdepth import io

    def failing(*args, **kwargs):
        raise OSError(28, "No space left on device", "points.ply")

    monkeypatch.setattr(io, "write_ply", failing)
    (tmp_path / "old.txt").write_text("mine")
    code, _, err = run_cli(capfd, "demo", "--out", tmp_path)
    assert code == 4 and err.strip().endswith(f"and the folders it made ({tmp_path / 'example'}, {tmp_path / 'example' / 'rail'})"), err
    assert [p.name for p in tmp_path.iterdir()] == ["old.txt"]


# ---------------------------------------------------------------- PLY colours


def _ply_records(path: Path):
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")]
    return np.frombuffer(data[end:], dtype=fields)


def test_stereo_ply_colours_follow_16_bit_intensities(work, tmp_path, capfd):
    views = _views(work)
    ply, depth_path = tmp_path / "cloud.ply", tmp_path / "d.npy"
    code, _, err = run_cli(capfd, "stereo", *views, "--rig", RIG, "--out", depth_path, "--ply", ply)
    assert code == 0, err
    rec = _ply_records(ply)
    depth = np.load(depth_path)
    keep = np.isfinite(depth) & (depth > 0)
    assert len(rec) == keep.sum() > 1000
    ref = cv2.imread(str(views[1]), cv2.IMREAD_UNCHANGED)
    assert ref.dtype == np.uint16 and ref.max() > 255
    grey = ref[keep].astype(float)
    for channel in ("red", "green", "blue"):
        np.testing.assert_array_equal(rec[channel], rec["red"])
    red = rec["red"].astype(float)
    # not saturated: the pyramid's faces (grey levels 50..200 of 255, stored x 256) stay below white
    assert np.mean(red == 255) < 0.5 and len(np.unique(red)) >= 5
    # and they are the intensities scaled from the image's range to 0..255
    np.testing.assert_allclose(red, np.rint(grey * 255.0 / ref.max()), atol=0)


def test_dynamic_ply_colours_of_16_bit_images(work, tmp_path, capfd):
    dyn = [work / f"dynamic_I{k}.png" for k in range(1, 6)]
    ply = tmp_path / "dyn.ply"
    code, _, err = run_cli(capfd, "dynamic", *dyn, "--rig", RIG, "--out", tmp_path / "d.pfm", "--ply", ply)
    assert code == 0, err
    red = _ply_records(ply)["red"]
    assert len(red) > 100 and np.mean(red == 255) < 0.5 and len(np.unique(red)) >= 3


# ------------------------------------------------------------------ file modes


@pytest.mark.skipif(os.name != "posix", reason="POSIX file modes")
def test_figures_have_the_mode_of_every_other_output(work, tmp_path, capfd, demo):
    expected = 0o666 & ~0o022
    mask = os.umask(0o022)
    try:
        code, _, err = run_cli(
            capfd, "stereo", *_views(work), "--out", tmp_path / "d.pfm", "--figure", tmp_path / "f.png", "--uncertainty", tmp_path / "s.pfm"
        )
        assert code == 0, err
        code, _, err = run_cli(capfd, "view", tmp_path / "d.pfm", "--colorbar", "--out", tmp_path / "v.png")
        assert code == 0, err
        code, _, err = run_cli(capfd, "reproduce", "--only", "exp1", "--no-compare", "--out", tmp_path / "figs")
        assert code == 0, err
    finally:
        os.umask(mask)
    figures = [tmp_path / "f.png", tmp_path / "f_std.png", tmp_path / "v.png", *(tmp_path / "figs").glob("*.png"), *demo.glob("*.png")]
    assert len(figures) > 20
    modes = {str(p): oct(p.stat().st_mode & 0o777) for p in figures}
    assert set(modes.values()) == {oct(expected)}, modes
    assert (tmp_path / "d.pfm").stat().st_mode & 0o777 == expected  # the same as the other outputs
    assert not list(tmp_path.glob(".*"))  # no temporary file left


# ------------------------------------------------------------ options and messages


def test_float64_views_beyond_float32_say_so(tmp_path, capfd):
    rng = np.random.default_rng(0)
    views = []
    for k in range(3):
        views.append(tmp_path / f"big{k}.npy")
        np.save(views[-1], rng.random((20, 30)) * 1e300)
    code, _, err = run_cli(capfd, "stereo", *views, "--out", tmp_path / "d.pfm")
    assert code == 2
    assert "beyond the float32 range (max |value| 1e+300" in err and "non-finite" not in err
    assert f"cannot read image '{views[0]}': 600 pixel(s)" in err and len(err.strip().splitlines()) == 1
    # the library's "or read it with dtype=float64 in Python" is no advice on the command line
    assert err.endswith("float32 reaches 3.4e+38); rescale the intensities (to 0-255 or 0-1, say): nfdepth works in float32\n"), err
    assert not (tmp_path / "d.pfm").exists()


def test_reproduce_negative_seed_names_the_option(capfd):
    code, _, err = run_cli(capfd, "reproduce", "--seed", "-1")
    assert code == 2
    assert err.strip() == "nfdepth: error: --seed must be an integer >= 0 (the noise generator's seed), got -1"


def test_evaluate_downsample_too_large_names_the_largest_factor(capfd):
    from nfdepth.datasets import DataNotFoundError, data_root

    try:
        data_root()
    except DataNotFoundError:
        pytest.skip("real data not found: set NFDEPTH_DATA")
    code, out, err = run_cli(capfd, "evaluate", "tsukuba", "--downsample", "1000", "--methods", "waxman_sinha_farneback")
    assert code == 2 and out == ""
    assert err.strip() == (
        "nfdepth: error: --downsample 1000 is too large for tsukuba (384x288 px): expected an integer from 1 to 144"
        " (the downsampled views need at least 2x2 px)"
    )
    # the largest factor it names is the largest the scene can be downsampled by
    from nfdepth.datasets import downsample_scene, load_scene

    assert downsample_scene(load_scene("tsukuba"), 144).shape == (2, 2)
    with pytest.raises(ValueError, match="too large"):
        downsample_scene(load_scene("tsukuba"), 145)
    # the methods' own needs: the largest factor named runs, the next one is refused up front
    for methods, largest, why in (
        (["nfdepth"], 96, "nfdepth needs views of at least 3x3 px"),
        (["sgbm"], 20, "sgbm needs views of at least 8x8 px, more than 18 px wide"),
        (["bm"], 16, "bm needs views of at least 8x8 px, more than 23 px wide"),
        (["waxman_sinha"], 32, "waxman_sinha's DIS flow needs a side of at least 12 px"),
    ):
        code, _, err = run_cli(capfd, "evaluate", "tsukuba", "--views", "three", "--methods", *methods, "--downsample", str(largest + 1))
        assert code == 2 and f"expected an integer from 1 to {largest} ({why})" in err, err
        code, _, err = run_cli(capfd, "evaluate", "tsukuba", "--views", "three", "--methods", *methods, "--downsample", str(largest))
        assert code == 0, err


def test_a_directory_output_says_it_is_a_directory(tmp_path, work, capfd):
    (tmp_path / "res").mkdir()
    (tmp_path / "res.pfm").mkdir()
    code, _, err = run_cli(capfd, "stereo", *_views(work), "--out", tmp_path / "res")
    assert code == 2
    assert err.strip().endswith("must end in one of .pfm, .tif, .tiff, .npy; it is a directory, expected a file path")
    code, _, err = run_cli(capfd, "stereo", *_views(work), "--out", tmp_path / "res.pfm")
    assert code == 4
    assert err.strip() == f"nfdepth: error: --out '{tmp_path / 'res.pfm'}' is a directory; expected a file path"
