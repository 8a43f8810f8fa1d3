"""Dynamic stereo's checks on what it was given: motion beyond the stencil's range, no relative motion, too little smoothing,
clipping read at rounding level, and the command line's --noise-std (acceptance pass 5)."""

from __future__ import annotations

import warnings
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_runner import run_cli

import nfdepth
from nfdepth import PinholeCamera, RigidMotion, synthetic
from nfdepth.io import read_pfm
from nfdepth.pipelines import MIN_SIGMA_PX

PAPER_RIG = Path(__file__).resolve().parents[1] / "examples" / "paper_pyramid_rig.toml"
F_PX, W, H, Z = 200.0, 160, 120, 10.0


def _striped_frames(tx: float):
    """A plane at Z = 10: vertical stripes on its left third (they measure the x motion), horizontal ones elsewhere
    (edges along the motion: no depth). The moving camera (I1, I3, I5) translates by tx per unit time."""
    cols, rows = np.meshgrid(np.arange(W) - (W - 1) / 2, np.arange(H) - (H - 1) / 2)

    def view(x0):
        x, y = cols * Z / F_PX + x0, rows * Z / F_PX
        vertical = np.tanh(3 * np.sin(2 * np.pi * x / 1.7))
        horizontal = np.tanh(3 * np.sin(2 * np.pi * y / 1.1 + 0.4))
        return 128 + 50 * np.where(x < -1.0, vertical, horizontal)

    rng = np.random.default_rng(0)
    return [view(t * tx) + rng.normal(0, 1.0, (H, W)) if k in (0, 2, 4) else view(0.0) + rng.normal(0, 1.0, (H, W)) for k, t in enumerate((-2, -1, 0, 1, 2))]


def _run(frames, **options):
    cam = PinholeCamera(focal_px=F_PX, width_px=W, height_px=H)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = nfdepth.dynamic_stereo(frames, camera=cam, relative_motion=RigidMotion(translation=(-options.pop("tx"), 0, 0)), **options)
    return res, [str(w.message) for w in caught]


def test_the_range_check_counts_the_points_that_carry_a_depth():
    """Two-thirds of the edges lie along the motion and do not move: counted in, they hid 4 px across I1..I3 (2.8 % off,
    |error| / std 4.9) behind a median of about 1 px over all edge points, with no warning."""
    res, said = _run(_striped_frames(0.05), tx=0.05)  # 2 px across the moving camera's triple: within range
    z = res.depth[res.valid]
    assert np.median(np.abs(z / Z - 1)) < 0.01 and not [s for s in said if "move a median of" in s]
    res, said = _run(_striped_frames(0.1), tx=0.1)  # 4 px
    beyond = [s for s in said if s.startswith("the edge points move a median of")]
    assert len(beyond) == 1 and "across the moving camera's frames (I1, I3, I5)" in beyond[0]
    assert np.median(res.depth[res.valid] / Z - 1) > 0.02  # the error the warning is about


def test_one_image_five_times_is_no_relative_motion_not_a_sign_mistake(tmp_path):
    scene = synthetic.paper_dynamic_sequence(1)
    same = [scene.frames[2]] * 5
    with pytest.warns(UserWarning, match=r"have a negative inverse depth or none .*, 600 of them no relative motion at all .*do the images differ") as record:
        res = nfdepth.dynamic_stereo(same, camera=scene.camera, relative_motion=scene.relative_motion)
    assert not res.valid.any()
    assert not [w for w in record if "time order" in str(w.message)]  # the sign hint is for a real sign mistake
    with pytest.warns(UserWarning, match=r"are the frames in time order I1..I5"):  # reversed frames: a sign mistake
        nfdepth.dynamic_stereo(scene.frames[::-1], camera=scene.camera, relative_motion=scene.relative_motion)


def test_float64_frames_are_not_read_as_clipped():
    """The rendered white is 255 and 255.0000000000029 side by side in float64: it was 'I1 (14 %), I2 (14 %) clipped'."""
    scene = synthetic.paper_dynamic_sequence(1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = nfdepth.dynamic_stereo(scene.frames, camera=scene.camera, relative_motion=scene.relative_motion, dtype=np.float64)
    z = scene.depth_at(res.rows[res.valid], res.cols[res.valid])
    assert np.median(np.abs(res.depth[res.valid] / z - 1)) < 0.005


def test_too_little_smoothing_warns():
    """At sigma 1 px the paper's pyramid comes out 2.6 % off at |error| / std 6.4 (0.3 % at the default 3)."""
    scene = synthetic.paper_dynamic_sequence(1)
    with pytest.warns(UserWarning, match=r"sigma_px = 1 px smooths the images too little .*use 1.5 px or more"):
        res = nfdepth.dynamic_stereo(scene.frames, camera=scene.camera, relative_motion=scene.relative_motion, sigma_px=1.0)
    z = scene.depth_at(res.rows[res.valid], res.cols[res.valid])
    err = np.abs(res.depth[res.valid] / z - 1)
    assert np.median(err) > 0.01 and np.median(np.abs(res.depth[res.valid] - z) / res.depth_std[res.valid]) > 2  # what it warns of
    assert MIN_SIGMA_PX == 1.5
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        nfdepth.dynamic_stereo(scene.frames, camera=scene.camera, relative_motion=scene.relative_motion, sigma_px=MIN_SIGMA_PX)


def test_dynamic_cli_takes_the_noise_std(tmp_path, capsys):
    """JPEG and compressed video hide the noise the error bar is estimated from: --noise-std gives it."""
    scene = synthetic.paper_dynamic_sequence(1, noise_std=1.0, rng=np.random.default_rng(3))
    paths = []
    for k, frame in enumerate(scene.frames, 1):
        p = tmp_path / f"I{k}.png"
        assert cv2.imwrite(str(p), np.round(frame * 256).astype(np.uint16))
        paths.append(p)
    stds = []
    for noise in ("256", "2048"):  # grey levels of the 16-bit files (the frames x 256)
        code, _, err = run_cli(capsys, "dynamic", *paths, "--rig", PAPER_RIG, "--out", tmp_path / f"d{noise}.pfm", "--uncertainty", tmp_path / f"s{noise}.pfm", "--noise-std", noise)
        assert code == 0, err
        stds.append(read_pfm(tmp_path / f"s{noise}.pfm"))
    ok = np.isfinite(stds[0])
    assert ok.sum() > 100
    ratio = np.median(stds[1][ok] / stds[0][ok])
    assert 4.0 < ratio <= 8.0 + 1e-6  # the noise part grows 8-fold (the stencil's own part stays)
    for bad in ("0", "-1", "nan"):
        code, _, err = run_cli(capsys, "dynamic", *paths, "--rig", PAPER_RIG, "--out", tmp_path / "x.pfm", "--noise-std", bad)
        assert code == 2 and err.startswith("nfdepth: error: --noise-std must be a positive number of grey levels, got")
    assert not (tmp_path / "x.pfm").exists()


def test_a_sigma_that_leaves_no_edge_point_is_refused(tmp_path, capsys):
    """sigma_px = 500 on 200 x 200 frames ran, then said 'within border_px of the border', an option dynamic stereo does not take.

    Edge points are taken 2.5 sigma from the border (``ceil(2.5 sigma)`` px): 200 px frames have 199 cells, which keep one
    cell for a border of at most 99 px, sigma_px 39.6.
    """
    scene = synthetic.paper_dynamic_sequence(1)
    run = {"camera": scene.camera, "relative_motion": scene.relative_motion}
    with pytest.raises(ValueError, match=r"^sigma_px = 39\.7 px leaves no edge point in images of 200x200 px: they are taken 2\.5 sigma_px \(100 px\) from the border, where the smoothing reaches past it; expected at most 39\.6 px$"):
        nfdepth.dynamic_stereo(scene.frames, sigma_px=39.7, **run)
    with pytest.warns(UserWarning, match="no edge points: all .* are corners"):  # the largest that fits runs (and smooths the pyramid away)
        nfdepth.dynamic_stereo(scene.frames, sigma_px=39.6, **run)
    with pytest.raises(ValueError, match=r"^sigma_px = 50 px leaves no edge point in images of 200x200 px"):
        nfdepth.depth_from_video(scene.frames, camera=scene.camera, velocity=(1.0, 0.0, 0.0), sigma_px=50)
    views = [np.tile(np.arange(20.0), (20, 1))] * 3
    with pytest.raises(ValueError, match=r"^sigma_px = 4 px leaves no edge point in images of 20x20 px: .* \(10 px\) .*; expected at most 3\.6 px$"):
        nfdepth.static_stereo_edges(views, camera=PinholeCamera(100.0, 20, 20), baseline=1.0, sigma_px=4)


def test_no_edge_points_near_the_border_name_the_smoothing():
    """An edge within 2.5 sigma of the border: the warning names sigma_px and the border in px, not border_px."""
    cols = np.arange(60)
    views = [np.tile(100 + 50 * np.tanh((cols - 3.5 - 0.3 * k) / 1.5), (60, 1)) for k in range(3)]
    with pytest.warns(UserWarning, match=r"^no edge points: the 59 strong zero crossings in the reference image of shape \(60, 60\) all lie within 2\.5 sigma_px \(5 px\) of the border, where the smoothing reaches past it \(lower sigma_px / --sigma-px\); the result is empty$"):
        res = nfdepth.static_stereo_edges(views, camera=PinholeCamera(100.0, 60, 60), baseline=1.0)
    assert len(res) == 0


def test_poses_errors_count_comment_and_blank_lines(tmp_path):
    """The lines were counted after comments and blank lines were dropped: every later line number was too small."""
    from nfdepth.rig import RigError, load_poses

    p = tmp_path / "poses.csv"
    for text, match in [
        ("frame,x,y,z\n# a comment\n\n0,a,0,0\n", r"^poses '.*' line 4: x = 'a': expected a finite number$"),
        ("# head\nframe,x,y,z\n0,0,0,0\n# x\n2,1,0,0\n1,2,0,0\n", r"^poses '.*' line 6: frame indices must be strictly increasing$"),
        ("\nframe,x,y,z,rx,ry,rz\n0,0,0,0,0,0,0\n\n1,0,0,0,0,0,2e6\n", r"^poses '.*' line 5: rx, ry, rz = \(0, 0, 2e\+06\)"),
        ("\n# c\nfoo\n", r"^poses '.*' line 3: header 'foo'"),
    ]:
        p.write_text(text)
        with pytest.raises(RigError, match=match):
            load_poses(p)


def test_rig_errors_are_nfdepth_errors():
    from nfdepth._validate import NFDepthError
    from nfdepth.rig import RigError

    assert issubclass(RigError, NFDepthError) and issubclass(RigError, ValueError)


def test_an_unquoted_glob_after_the_video_options_is_named(tmp_path, capsys):
    """`--moving-video m/*.png`: the shell's files became the five-image arguments ('give either five images or ...')."""
    files = []
    for k in range(4):
        files.append(tmp_path / f"m{k}.png")
        assert cv2.imwrite(str(files[-1]), np.zeros((8, 8), np.uint8))
    rig = Path(__file__).resolve().parents[1] / "examples" / "paper_pyramid_rig.toml"
    code, out, err = run_cli(capsys, "dynamic", "--moving-video", *files, "--reference-video", tmp_path / "r.mp4", "--rig", rig, "--out", tmp_path / "o.npz")
    assert code == 2 and out == ""
    assert err == (
        f"nfdepth: error: files beside --moving-video and --reference-video: {files[1]} {files[2]} {files[3]}: "
        "quote a glob such as 'frames/*.png', or the shell expands it into files\n"
    )
