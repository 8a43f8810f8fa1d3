"""The command line end to end: exit codes, outputs, one-line errors."""

import json
import subprocess
import sys

import numpy as np
import pytest
from cli_runner import run_cli

from nfdepth.experiments import run_paper_experiment


def is_png(path):
    with open(path, "rb") as fh:
        return fh.read(8) == b"\x89PNG\r\n\x1a\n"


def test_reproduce_json_and_figures(tmp_path, capsys):
    js = tmp_path / "r.json"
    code, out, err = run_cli(capsys, "reproduce", "--only", "exp1", "static", "--json", str(js), "--out", str(tmp_path / "figs"), "--no-compare")
    assert code == 0, err
    assert "exp1" in out and "static" in out
    data = json.loads(js.read_text())
    assert set(data) == {"exp1", "static"}
    for entry in data.values():
        assert entry["points"] > 0
        for key in ("flow_rel_error", "depth_rel_error"):
            assert set(entry[key]) >= {"max", "p95", "median"}
    figs = sorted((tmp_path / "figs").glob("*.png"))
    names = {f.name for f in figs}
    assert {"exp1_a_I3.png", "exp1_a_dps.png", "exp1_a_dpm.png", "exp1_b_Vnr.png", "exp1_b_Vns.png", "exp1_b_Vnm.png", "exp1_c_edges.png", "exp1_d_yz.png"} <= names
    assert all(is_png(f) for f in figs)


def test_reproduce_literal_stencil_and_noise(tmp_path, capsys):
    js = tmp_path / "r.json"
    code, out, err = run_cli(capsys, "reproduce", "--only", "exp2", "--stencil", "paper", "--noise", "0.5", "--seed", "2", "--json", str(js))
    assert code == 0, err
    data = json.loads(js.read_text())
    assert data["exp2"]["stencil"] == "paper"
    # the options reach the experiment: the same seed gives the same numbers (runtime aside)
    expected = run_paper_experiment("exp2", stencil="paper", noise_std=0.5, seed=2).summary()
    got = data["exp2"]
    for key in ("points", "edge_points", "flow_rel_error", "depth_rel_error"):
        assert got[key] == pytest.approx(expected[key], rel=1e-12), key
    # and they matter: the literal stencil with noise is far off the default noise-free run (0.126 against <= 0.031)
    assert got["flow_rel_error"]["max"] > 0.05


def test_demo_writes_figures(tmp_path, capsys):
    code, out, err = run_cli(capsys, "demo", "--out", str(tmp_path / "demo"))
    assert code == 0, err
    assert "edge points with depth" in out
    demo = tmp_path / "demo"
    assert len(list(demo.glob("*.png"))) >= 10
    from nfdepth.io import read_pfm

    depth = read_pfm(demo / "depth.pfm")
    finite = depth[np.isfinite(depth)]
    assert finite.size > 300  # edge points of the pyramid
    assert 195 < finite.min() and finite.max() < 410  # apex 200, base 400
    header = (demo / "points.ply").read_bytes()[:200]
    assert header.startswith(b"ply\nformat binary_little_endian 1.0")
    assert len(list((demo / "example").glob("pyramid_view*.png"))) == 3


@pytest.mark.parametrize(
    ("argv", "code", "fragment"),
    [
        (["reproduce", "--noise", "-1"], 2, "--noise must be a finite number >= 0"),
        (["reproduce", "--stencil", "sobel"], 2, "invalid choice"),
        (["no-such-command"], 2, "invalid choice"),
    ],
)
def test_bad_arguments_one_line(capsys, argv, code, fragment):
    got, out, err = run_cli(capsys, *argv)
    assert got == code
    assert fragment in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err


def test_python_dash_m_and_version():
    res = subprocess.run([sys.executable, "-m", "nfdepth", "--version"], capture_output=True, text=True, check=False)
    assert res.returncode == 0
    assert res.stdout.startswith("nfdepth ")


def test_no_command_prints_help(capsys):
    code, out, err = run_cli(capsys)
    assert code == 2
    assert "COMMAND" in out


# ------------------------------------------------------------ reproduce options


def _without_runtime(summary):
    return {k: v for k, v in summary.items() if k != "runtime_s"}


def test_reproduce_compares_with_the_literal_stencil_by_default(tmp_path, capsys):
    """A stencil other than the paper's adds the paper's literal stencil as a column and a JSON entry."""
    js = tmp_path / "r.json"
    code, out, err = run_cli(capsys, "reproduce", "--only", "exp1", "static", "--json", str(js))
    assert code == 0, err
    data = json.loads(js.read_text())
    lines = out.splitlines()
    assert lines[1].endswith("| literal-stencil max median")
    for name in ("exp1", "static"):
        entry = data[name]
        assert entry["stencil"] == "matched"
        literal = run_paper_experiment(name, stencil="paper").summary()
        assert _without_runtime(entry["literal_stencil"]) == _without_runtime(literal)
        assert _without_runtime(entry)["flow_rel_error"] == run_paper_experiment(name).summary()["flow_rel_error"]
        row = next(line for line in lines if line.startswith(name))
        lf = literal["flow_rel_error"]
        assert row.endswith(f"| {lf['max']:>19.4f} {lf['median']:6.4f}"), row
    # the literal stencil is measurably worse on experiment 1 (the reason for the comparison)
    assert data["exp1"]["literal_stencil"]["flow_rel_error"]["max"] > 2 * data["exp1"]["flow_rel_error"]["max"]
    # --no-compare drops both
    code, out, err = run_cli(capsys, "reproduce", "--only", "exp1", "--json", str(js), "--no-compare")
    assert code == 0, err
    assert "literal" not in out and "literal_stencil" not in json.loads(js.read_text())["exp1"]


def test_reproduce_sigma_and_max_rel_std_reach_the_experiments(tmp_path, capsys):
    js = tmp_path / "r.json"
    argv = ["--only", "exp2", "--noise", "1", "--sigma-px", "2.5", "--max-rel-std", "0.02", "--no-compare", "--json", str(js)]
    code, _, err = run_cli(capsys, "reproduce", *argv)
    assert code == 0, err
    got = _without_runtime(json.loads(js.read_text())["exp2"])
    want = _without_runtime(run_paper_experiment("exp2", noise_std=1.0, sigma_px=2.5, max_rel_std=0.02).summary())
    import nfdepth

    settings = {"nfdepth_version": nfdepth.__version__, "noise_std": 1.0, "seed": 0, "sigma_px": 2.5, "max_rel_std": 0.02, "stencil": "matched"}
    assert got == {**want, "stencil": "matched", "settings": settings}  # two runs with other settings are told apart
    assert 0.67 / 1.5 < got["median_error_over_std"] < 0.67 * 1.5
    # and each matters: --max-rel-std 0.02 refuses about half the points, --sigma-px 2.5 keeps more than the default 4 px
    loose = run_paper_experiment("exp2", noise_std=1.0, sigma_px=2.5).summary()["points"]
    assert 0 < got["points"] < 0.6 * loose
    assert loose > run_paper_experiment("exp2", noise_std=1.0).summary()["points"]


def _strict_json(text):
    """``json.loads`` refusing the tokens ``NaN``, ``Infinity``, ``-Infinity`` (not JSON; Python's encoder writes them by default)."""

    def refuse(token):
        raise ValueError(f"not JSON: {token}")

    return json.loads(text, parse_constant=refuse)


def test_reproduce_json_without_points_is_json(tmp_path, capsys):
    """An experiment that keeps no point has no error statistics: null in the JSON, not the bare NaN no JSON reader takes."""
    js = tmp_path / "r.json"
    code, _, err = run_cli(capsys, "reproduce", "--only", "exp1", "--noise", "1", "--max-rel-std", "0.005", "--no-compare", "--json", js)
    assert code == 0, err
    entry = _strict_json(js.read_text())["exp1"]
    assert entry["points"] == 0 and entry["edge_points"] > 0  # (to_jsonable drops an "edge_points" key: kept here)
    for key in ("flow_rel_error", "depth_rel_error"):
        assert entry[key] == {"max": None, "p95": None, "median": None, "count": 0}
    assert entry["median_error_over_std"] is None
    assert entry["settings"]["max_rel_std"] == 0.005


@pytest.mark.parametrize(
    ("argv", "code", "line"),
    [
        (["--json", "{tmp}/same.json", "--out", "{tmp}/same.json"], 2,
         "--json and --out name the same path '{tmp}/same.json'; expected a different path for each output (--json a file, --out a folder)"),
        (["--json", "{tmp}/r.json", "--out", "{tmp}/./r.json"], 2, "--json and --out name the same path '{tmp}/r.json'"),
        (["--json", "{tmp}/r.json", "--out", "{tmp}/r.json/figs"], 2,
         "--out '{tmp}/r.json/figs' lies inside --json '{tmp}/r.json' (a file); expected a different path for each output, the folder outside the JSON file"),
        (["--out", "{tmp}/afile/figs"], 4, "--out '{tmp}/afile/figs': '{tmp}/afile' is not a directory"),
        (["--out", "{tmp}/afile/figs/deeper"], 4, "--out '{tmp}/afile/figs/deeper': '{tmp}/afile' is not a directory"),
        (["--out", "{tmp}/afile"], 4, "--out '{tmp}/afile' exists and is not a directory; expected a folder for the output files"),
    ],
)
def test_reproduce_refuses_its_output_paths_before_any_work(tmp_path, capsys, argv, code, line):
    """Output paths that could only fail once every experiment has run (then exit 4) are refused first."""
    (tmp_path / "afile").write_text("x")
    argv = [a.format(tmp=tmp_path) for a in argv]
    got, out, err = run_cli(capsys, "reproduce", "--only", "exp1", "--no-compare", *argv)
    assert (got, out) == (code, ""), err
    assert err.startswith(f"nfdepth: error: {line.format(tmp=tmp_path)}") and len(err.splitlines()) == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


@pytest.mark.skipif(not hasattr(__import__("os"), "symlink"), reason="symbolic links")
def test_reproduce_out_a_link_to_a_missing_folder(tmp_path, capsys):
    import os

    link = tmp_path / "link"
    os.symlink(tmp_path / "missing", link)
    code, out, err = run_cli(capsys, "reproduce", "--only", "exp1", "--no-compare", "--out", link)
    assert (code, out) == (4, "")
    assert err == f"nfdepth: error: --out '{link}' exists and is not a directory (a link to a missing folder); expected a folder for the output files\n"
    code, out, err = run_cli(capsys, "reproduce", "--only", "exp1", "--no-compare", "--out", link / "figs")
    assert (code, out) == (4, "") and err == f"nfdepth: error: --out '{link / 'figs'}': directory '{link}' does not exist\n"


@pytest.mark.parametrize(
    ("argv", "line"),
    [
        (["--sigma-px", "0"], "--sigma-px must be a positive number, got 0.0"),
        (["--sigma-px", "nan"], "--sigma-px must be a positive number, got nan"),
        (["--max-rel-std", "-0.5"], "--max-rel-std must be a positive number, got -0.5"),
        (["--max-rel-std", "inf"], "--max-rel-std must be a positive number, got inf"),
        (["--noise", "nan"], "--noise must be a finite number >= 0, got nan"),
    ],
)
def test_reproduce_refuses_bad_options_before_any_work(tmp_path, capsys, argv, line):
    js = tmp_path / "r.json"
    code, out, err = run_cli(capsys, "reproduce", "--only", "exp1", *argv, "--json", str(js), "--out", str(tmp_path / "figs"))
    assert (code, out, err) == (2, "", f"nfdepth: error: {line}\n")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------ bench


def test_bench_passes_its_options_through(tmp_path, capsys, monkeypatch):
    from nfdepth import bench

    calls = []
    monkeypatch.setattr(bench, "bench_main", lambda **kwargs: calls.append(kwargs) or 0)
    js = tmp_path / "b.json"
    code, _, err = run_cli(capsys, "bench", "--quick", "--threads", "1", "--json", str(js))
    assert code == 0, err
    assert calls == [{"json_path": str(js), "quick": True, "threads": 1}]
    code, _, err = run_cli(capsys, "bench")
    assert code == 0 and calls[-1] == {"json_path": None, "quick": False, "threads": 1}
    # an unusable --json is refused before the benchmark runs
    code, _, err = run_cli(capsys, "bench", "--json", str(tmp_path / "nodir" / "b.json"))
    assert code == 4 and err == f"nfdepth: error: --json '{tmp_path / 'nodir' / 'b.json'}': directory '{tmp_path / 'nodir'}' does not exist\n"
    assert len(calls) == 2


def test_bench_says_why_the_art_views_are_missing(tmp_path, monkeypatch):
    """NFDEPTH_DATA set to a missing folder is told as such (it said "set NFDEPTH_DATA"); a data folder without Art, named."""
    from nfdepth import bench

    monkeypatch.setenv("NFDEPTH_DATA", str(tmp_path / "absent"))
    with pytest.warns(UserWarning) as caught:
        records = bench.run_benchmarks(sizes=[(60, 80)], repeats=1, scenes=("middlebury-art",))
    assert len(caught) == 1
    assert f"NFDEPTH_DATA={str(tmp_path / 'absent')!r} is not a directory" in str(caught[0].message)
    assert f"NFDEPTH_DATA={str(tmp_path / 'absent')!r} is not a directory" in records[0]["skipped"]
    (tmp_path / "data").mkdir()
    monkeypatch.setenv("NFDEPTH_DATA", str(tmp_path / "data"))
    with pytest.warns(UserWarning) as caught:
        records = bench.run_benchmarks(sizes=[(60, 80)], repeats=1, scenes=("middlebury-art",))
    art = tmp_path / "data" / "middlebury2005" / "Art"
    assert records[0]["skipped"].startswith(f"skipped: the Middlebury 2005 Art views were not found in '{art}' (set NFDEPTH_DATA")
    # views there that cannot be decoded: said so, not "not found"
    art.mkdir(parents=True)
    for i in range(7):
        (art / f"view{i}.png").write_bytes(b"not a PNG")
    with pytest.warns(UserWarning) as caught:
        records = bench.run_benchmarks(sizes=[(60, 80)], repeats=1, scenes=("middlebury-art",))
    assert records[0]["skipped"] == f"skipped: the Middlebury 2005 Art views in '{art}' could not be read as images (are the files intact?)"


# ------------------------------------------------------------ evaluate: refused before any work


@pytest.mark.parametrize(
    ("argv", "code", "line"),
    [
        (["--json", "{tmp}/r.txt"], 2, "--json '{tmp}/r.txt' must end in one of .json"),
        (["--json", "{tmp}/adir.json"], 4, "--json '{tmp}/adir.json' is a directory; expected a file path"),
        (["--json", "{tmp}/nodir/r.json"], 4, "--json '{tmp}/nodir/r.json': directory '{tmp}/nodir' does not exist"),
        (["--maps", "{tmp}/afile"], 4, "--maps '{tmp}/afile' exists and is not a directory; expected a folder for the output files"),
        (["--maps", "{tmp}/afile/maps"], 4, "--maps '{tmp}/afile/maps': '{tmp}/afile' is not a directory"),
        (["--json", "{tmp}/x.json", "--maps", "{tmp}/x.json"], 2,
         "--json and --maps name the same path '{tmp}/x.json'; expected a different path for each output (--json a file, --maps a folder)"),
        (["--methods", "sgbm", "bm", "--cost-step-px", "1e9"], 2,
         "--cost-step-px spaces nfdepth's cost volume: add nfdepth to --methods (now sgbm bm), or leave --cost-step-px out"),
        (["--downsample", "0"], 2, "--downsample must be a positive integer, got 0"),
        (["--views", "two"], 2, "--views must be 'three' or 'all', got 'two'"),
        (["--cost-step-px", "0"], 2, "--cost-step-px must be a positive number, got 0"),
    ],
)
def test_evaluate_refuses_bad_options_before_reading_data(tmp_path, capsys, argv, code, line):
    (tmp_path / "adir.json").mkdir()
    (tmp_path / "afile").write_text("x")
    before = sorted(tmp_path.rglob("*"))
    argv = [a.format(tmp=tmp_path) for a in argv]
    # a data folder that does not exist: the options are checked first
    got, out, err = run_cli(capsys, "evaluate", "tsukuba", "--data", str(tmp_path / "no-data"), *argv)
    assert (got, out, err) == (code, "", f"nfdepth: error: {line.format(tmp=tmp_path)}\n")
    assert sorted(tmp_path.rglob("*")) == before


def test_evaluate_group_checks_downsample_for_every_scene_first(tmp_path, capsys):
    """A factor too large for the group's last scene is refused before the first scene's results are printed or written."""
    from nfdepth.datasets import DataNotFoundError, data_root

    try:
        data_root()
    except DataNotFoundError:
        pytest.skip("real data not found: set NFDEPTH_DATA")
    js = tmp_path / "r.json"
    code, out, err = run_cli(capsys, "evaluate", "middlebury2005", "--methods", "sgbm", "--downsample", "36", "--json", str(js))
    assert (code, out) == (2, "")
    assert err == (
        "nfdepth: error: --downsample 36 is too large for middlebury2005/Reindeer (671x555 px): expected an integer from 1 to 35"
        " (sgbm needs views of at least 8x8 px, more than 18 px wide)\n"
    )
    assert not js.exists()


# ------------------------------------------------------------------ stereo


def _plane_views_files(tmp_path, *, transpose=False):
    """Three 16-bit PNG views (64 x 64) of a textured plane moving 3 px per view along x (along y: ``transpose``)."""
    import cv2

    rng = np.random.default_rng(4)
    rows, cols = np.mgrid[0:64, 0:64].astype(float)
    n = 30
    wavelength, angle, phase = rng.uniform(6.0, 20.0, n), rng.uniform(0.0, np.pi, n), rng.uniform(0.0, 2 * np.pi, n)
    ky, kx = 2 * np.pi * np.sin(angle) / wavelength, 2 * np.pi * np.cos(angle) / wavelength
    names = []
    for k in range(3):
        c = cols + (k - 1) * 3.0  # view k sees the reference's (r, c) at (r, c - 3 (k - 1))
        image = 128.0 + 60.0 / np.sqrt(n / 2) * np.sin(ky * rows[..., None] + kx * c[..., None] + phase).sum(-1)
        names.append(str(tmp_path / f"{'y' if transpose else 'x'}{k}.png"))
        cv2.imwrite(names[-1], np.round((image.T if transpose else image) * 256).astype(np.uint16))
    return names


def test_stereo_axis_against_the_rig_file(tmp_path, capsys):
    """``--axis`` given explicitly and contradicting the rig file's ``axis`` is refused, whichever of x and y it is.
    Before, ``--axis x`` was taken for the parser's default: a rig's ``axis = "y"`` replaced it without a word and a row
    moving along x was measured along y (0.6 % of the pixels, depths 63-8150 for a plane at 33). Not given, the rig decides;
    given as the rig says, it runs."""
    from nfdepth.io import read_pfm

    rig = {}
    for axis in ("x", "y"):
        rig[axis] = tmp_path / f"rig_{axis}.toml"
        rig[axis].write_text(f'[camera]\nfocal_px = 100.0\nwidth_px = 64\nheight_px = 64\n\n[stereo]\nbaseline = 1.0\naxis = "{axis}"\n')
    along_x = _plane_views_files(tmp_path)
    out = tmp_path / "d.pfm"
    for given, in_rig in (("x", "y"), ("y", "x")):
        code, printed, err = run_cli(capsys, "stereo", *along_x, "--rig", rig[in_rig], "--axis", given, "--out", out)
        assert (code, printed, err) == (2, "", f"nfdepth: error: --axis {given} contradicts the rig file's axis = {in_rig}\n")
        assert not out.exists()
    # the rig's axis where none is given, along either axis: the plane at 100 / 3 scene units
    for axis, names in (("x", along_x), ("y", _plane_views_files(tmp_path, transpose=True))):
        for extra in ([], ["--axis", axis]):
            code, printed, err = run_cli(capsys, "stereo", *names, "--rig", rig[axis], *extra, "--out", out, "--force")
            assert code == 0 and err == "", err
            inner = read_pfm(out)[10:-10, 10:-10]
            assert np.isfinite(inner).mean() > 0.9 and np.nanmedian(np.abs(inner / (100.0 / 3.0) - 1.0)) < 0.01
