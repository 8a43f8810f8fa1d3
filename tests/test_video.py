"""``nfdepth video``: a camera translating past the pyramid, fused over time."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_runner import run_cli

import nfdepth.cli
from nfdepth import NoEdgePointsWarning, synthetic
from nfdepth.cli import main
from nfdepth.rig import RigError, load_rig
from nfdepth.video import depth_from_video, read_video

STEP = (1.0, 0.0, 0.0)  # camera translation per frame: 0.25-0.5 px of disparity
N_FRAMES = 9


@pytest.fixture(autouse=True)
def plugin(monkeypatch):
    monkeypatch.setattr(nfdepth.cli, "_PLUGIN_COMMANDS", ("_cli_rig",))


@pytest.fixture(scope="module")
def scene():
    rng = np.random.default_rng(1)
    return synthetic.static_sequence(
        synthetic.paper_pyramid(), synthetic.paper_camera(), n_views=N_FRAMES, camera_step=STEP, reference_index=0, noise_std=1.0, rng=rng
    )


def true_depth(scene, frame_index, rows, cols):
    motion = synthetic.CameraMotion(velocity_per_t=STEP)
    return synthetic.surface_depth_at(scene.polyhedron, scene.camera, rows, cols, camera_motion=motion, time=float(frame_index))


def errors(scene, res):
    """Relative errors of the fused and the single-triple depth at this frame's edge points."""
    m = res.measured & np.isfinite(res.inverse_depth)
    ii, jj = np.nonzero(m)
    z = true_depth(scene, res.index, ii + 0.5, jj + 0.5)
    fused = np.abs(res.depth[m] - z) / z
    single = np.abs(1.0 / res.measured_inverse_depth[m] - z) / z
    return fused, single, m


@pytest.fixture
def sequence_dir(tmp_path, scene):
    folder = tmp_path / "frames"
    folder.mkdir()
    for k, frame in enumerate(scene.frames):
        # natural order: f2 sorts before f10
        assert cv2.imwrite(str(folder / f"f{k}.png"), np.round(frame * 200).astype(np.uint16))  # 255 + noise fits in 16 bits
    return folder


@pytest.fixture
def rail_rig(tmp_path):
    p = tmp_path / "rail.toml"
    p.write_text("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[video]\nvelocity = [1.0, 0.0, 0.0]\n")
    return p


def test_fusion_sharpens_depth(scene):
    results = list(depth_from_video(list(scene.frames), camera=scene.camera, velocity=STEP))
    assert [r.index for r in results] == list(range(1, N_FRAMES - 1))
    med_fused, med_single, std_rel = [], [], []
    for r in results:
        fused, single, m = errors(scene, r)
        assert m.sum() > 300
        med_fused.append(np.median(fused))
        med_single.append(np.median(single))
        std_rel.append(np.median(r.inverse_depth_std[m] / r.inverse_depth[m]))
    # first frame: nothing to fuse yet
    assert med_fused[0] == pytest.approx(med_single[0])
    # fused error falls as frames arrive and ends well below one triple's
    assert np.mean(med_fused[-3:]) < 0.7 * med_fused[0]
    assert np.mean(med_fused[-3:]) < 0.7 * np.mean(med_single[-3:])
    assert np.mean(med_fused[-3:]) < 0.015  # measured ~0.8 % (one triple: ~2 %)
    # and so does the reported std, monotonically
    assert all(b < a for a, b in zip(std_rel, std_rel[1:]))
    assert std_rel[-1] < 0.6 * std_rel[0]
    assert results[-1].count[results[-1].measured].max() >= N_FRAMES - 3


def test_positions_equal_velocity(scene):
    a = list(depth_from_video(list(scene.frames[:5]), camera=scene.camera, velocity=STEP))
    pos = np.arange(5)[:, None] * np.asarray(STEP)
    b = list(depth_from_video(list(scene.frames[:5]), camera=scene.camera, positions=pos))
    np.testing.assert_array_equal(a[-1].inverse_depth, b[-1].inverse_depth)


def test_library_argument_errors(scene):
    with pytest.raises(TypeError, match="exactly one of rig, velocity, positions"):
        next(depth_from_video(scene.frames, camera=scene.camera))
    with pytest.raises(ValueError, match="exactly one of"):
        next(depth_from_video(scene.frames, camera=scene.camera, velocity=STEP, positions=np.zeros((9, 3))))
    with pytest.raises(ValueError, match="not all zero"):
        next(depth_from_video(scene.frames, camera=scene.camera, velocity=(0, 0, 0)))
    for name, bad, exc in (("max_age", -1, ValueError), ("max_age", 2.5, TypeError), ("first_frame", -1, ValueError), ("first_frame", True, TypeError)):
        with pytest.raises(exc, match=f"{name} must be an integer >= 0, got {bad!r}"):
            next(depth_from_video(scene.frames, camera=scene.camera, velocity=STEP, **{name: bad}))


def test_depths_beyond_float32_are_refused(scene):
    """A speed in extreme units puts the depths beyond float32, in which frames are returned: an error, not a map of zeros."""
    from nfdepth.camera import PinholeCamera

    cam = scene.camera
    huge = PinholeCamera(1e30, cam.width_px, cam.height_px)  # the largest focal length accepted
    with pytest.raises(ValueError, match=r"an inverse depth of .* does not fit a float32 output .*give the rig's focal length"):
        list(depth_from_video(list(scene.frames[:3]), camera=huge, velocity=np.asarray(STEP) * 1e30))


def _write_avi(path, frames):
    """``frames`` (grey, 200 x 200) as an MJPG video at ``path``; skips where OpenCV cannot write one."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10, (200, 200), True)
    if not writer.isOpened():
        pytest.skip("no MJPG writer in this OpenCV build")
    for f in frames:
        writer.write(cv2.cvtColor(np.clip(f, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR))
    writer.release()
    return path


def test_read_video_sources(tmp_path, sequence_dir, scene):
    frames = list(read_video(sequence_dir))
    assert len(frames) == N_FRAMES and frames[0].dtype == np.float32
    np.testing.assert_allclose(frames[2] / 200, scene.frames[2], atol=0.01)
    assert len(read_video(str(sequence_dir / "f*.png"))) == N_FRAMES
    avi = _write_avi(tmp_path / "v.avi", scene.frames[:4])
    got = list(read_video(avi))
    assert len(got) == 4 and got[0].shape == (200, 200) and got[0].dtype == np.float32
    assert np.median(np.abs(got[1] - scene.frames[1])) < 3


def test_read_video_errors(tmp_path):
    from nfdepth.io import ImageReadError

    with pytest.raises(ImageReadError, match="no such file"):
        read_video(tmp_path / "missing.mp4")
    with pytest.raises(ImageReadError, match="matches no files"):
        read_video(str(tmp_path / "*.png"))
    with pytest.raises(ImageReadError, match="no image files"):
        read_video(tmp_path)


def test_video_cli_npz(tmp_path, capsys, sequence_dir, rail_rig, scene):
    out = tmp_path / "depth.npz"
    code, stdout, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", out)
    assert code == 0, err
    assert "frames/s" in err and f"{N_FRAMES}/{N_FRAMES} frames" in err
    assert f"depth for {N_FRAMES - 2} frames" in stdout
    data = np.load(out)
    assert list(data["index"]) == list(range(1, N_FRAMES - 1))
    assert data["depth"].shape == (N_FRAMES - 2, 200, 200) and data["depth"].dtype == np.float32
    assert data["focal_px"] == 100.0
    last = data["depth"][-1]
    m = np.isfinite(last) & np.isfinite(data["measured_inverse_depth"][-1])
    ii, jj = np.nonzero(m)
    z = true_depth(scene, int(data["index"][-1]), ii + 0.5, jj + 0.5)
    assert np.median(np.abs(last[m] - z) / z) < 0.015
    # no --force: refused, file untouched
    before = out.stat().st_mtime_ns
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", out)
    assert code == 4 and "--force" in err and out.stat().st_mtime_ns == before


def test_video_cli_folder_and_poses(tmp_path, capsys, sequence_dir, rail_rig):
    poses = tmp_path / "poses.csv"
    poses.write_text("frame,x,y,z\n" + "".join(f"{k},{k * 1.0},0,0\n" for k in range(N_FRAMES)))
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, "video", str(sequence_dir / "*.png"), "--rig", rail_rig, "--poses", poses, "--out", out, "--quiet")
    assert code == 0, err
    assert err == ""
    names = sorted(p.name for p in out.iterdir())
    assert names[0] == "depth_000001.tif" and len(names) == 2 * (N_FRAMES - 2)
    assert not any(n.startswith(".") for n in names)  # no temporary files left
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", out)
    assert code == 4 and "use --force" in err


def test_video_cli_errors(tmp_path, capsys, sequence_dir, rail_rig):
    small = tmp_path / "small.toml"
    small.write_text("[camera]\nfocal_px = 100\nwidth_px = 320\nheight_px = 240\n[video]\nvelocity = [1, 0, 0]\n")
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", small, "--out", tmp_path / "a.npz")
    assert code == 2 and "= 320x240 (small.toml) does not match frame 0 of " in err and err.count("\n") == 1
    assert not (tmp_path / "a.npz").exists()

    novideo = tmp_path / "nv.toml"
    novideo.write_text("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n")
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", novideo, "--out", tmp_path / "a.npz")
    assert code == 2 and "no [video] section" in err

    two = tmp_path / "two"
    two.mkdir()
    for k in range(2):
        (two / f"f{k}.png").write_bytes((sequence_dir / f"f{k}.png").read_bytes())
    code, _, err = run_cli(capsys, "video", two, "--rig", rail_rig, "--out", tmp_path / "a.npz")
    assert code == 2 and "at least 3 frames" in err

    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", tmp_path / "a.txt")
    assert code == 2 and "must be a .npz file or a folder" in err

    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", tmp_path / "a.npz", "--unit", "m")
    assert code == 2 and err.strip() == "nfdepth: error: --unit labels the colour bar of --figure: give --figure too"  # was: ignored
    assert not (tmp_path / "a.npz").exists()

    code, _, err = run_cli(capsys, "video", tmp_path / "nothing.mp4", "--rig", rail_rig, "--out", tmp_path / "a.npz")
    assert code == 3 and "no such file" in err

    short = tmp_path / "short.csv"
    short.write_text("frame,x,y,z\n0,0,0,0\n1,1,0,0\n2,2,0,0\n")
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--poses", short, "--out", tmp_path / "a.npz")
    assert code == 2 and "no row for frame 3" in err and err.count("\n") == 1
    assert not (tmp_path / "a.npz").exists()


def test_forward_motion_reprojection():
    """Camera moving along the optical axis: eq. 4's general translation and the reprojection warp."""
    step = (0.0, 0.0, 3.0)
    cam = synthetic.paper_camera()
    sc = synthetic.static_sequence(
        synthetic.paper_pyramid(), cam, n_views=7, camera_step=step, reference_index=0, noise_std=1.0, rng=np.random.default_rng(0)
    )
    motion = synthetic.CameraMotion(velocity_per_t=step)
    results = list(depth_from_video(list(sc.frames), camera=cam, velocity=step))
    r = results[-1]
    m = r.measured & np.isfinite(r.inverse_depth)
    ii, jj = np.nonzero(m)
    z = synthetic.surface_depth_at(sc.polyhedron, cam, ii + 0.5, jj + 0.5, camera_motion=motion, time=float(r.index))
    assert m.sum() > 300
    assert np.median(np.abs(r.depth[m] - z) / z) < 0.01  # measured ~0.3 %
    assert np.median(r.count[m]) >= 3


# ------------------------------------------------------------------ two synchronised videos (nfdepth dynamic)

PAPER_RIG = Path(__file__).resolve().parents[1] / "examples" / "paper_pyramid_rig.toml"
PAIR_T = np.array(synthetic.PAPER_MOVING_CAMERA_VELOCITY)  # the moving camera, per frame (the rig's [motion])
PAIR_CROSSINGS = (4, 12)
PAIR_FRAMES = 17


def _pair_videos(crossings=PAIR_CROSSINGS, n=PAIR_FRAMES, time_offset=0.0):
    """Two synchronised videos of the rotating pyramid (paper experiment 1).

    The reference camera stands at the origin; the moving camera passes
    through it at each crossing with velocity PAIR_T (a carousel: it comes
    round again), so frame k of the moving video is taken from
    ``(k - c) * PAIR_T``, c the nearest crossing, at the same instant k as
    frame k of the reference video. The object rotates, so the scene
    changes between crossings.
    """
    poly, cam = synthetic.paper_pyramid(), synthetic.paper_camera()
    om = synthetic.PAPER_EXPERIMENTS[1].object_motion()

    def moving_position(k):
        c = min(crossings, key=lambda c: abs(c - k))
        return (k - c) * PAIR_T

    moving = [
        synthetic.render(poly, cam, object_motion=om, camera_motion=synthetic.CameraMotion(position=moving_position(k)), time=k + time_offset).image
        for k in range(n)
    ]
    reference = [synthetic.render(poly, cam, object_motion=om, time=k + time_offset).image for k in range(n)]

    def truth(crossing, rows, cols):
        return synthetic.surface_depth_at(poly, cam, rows, cols, object_motion=om, time=crossing + time_offset)

    return moving, reference, truth


@pytest.fixture(scope="module")
def pair():
    return _pair_videos()


def _rel_errors(truth, res):
    r = res.result
    ok = r.valid
    z = truth(res.index, r.rows[ok], r.cols[ok])
    return np.abs(r.depth[ok] - z) / z


def test_interleaved_frames_are_the_papers_sequence():
    """Crossing at frame 2 of videos whose frame k is taken at t = k - 2: the paper's I1..I5 exactly."""
    from nfdepth.video import interleaved_frames

    moving, reference, _ = _pair_videos(crossings=(2,), n=5, time_offset=-2.0)
    scene = synthetic.paper_dynamic_sequence(1)
    frames = interleaved_frames(moving, reference, 2)
    for k, (got, want) in enumerate(zip(frames, scene.frames), 1):
        np.testing.assert_allclose(got, want, atol=1e-3, err_msg=f"I{k}")  # float32 of the same rendering
    np.testing.assert_array_equal(interleaved_frames(moving, reference, 2, shared="reference")[2], np.float32(reference[2]))
    with pytest.raises(ValueError, match=r"crossing 3 needs frames 1\.\.5, but the videos have 5 frames"):
        interleaved_frames(moving, reference, 3)
    with pytest.raises(ValueError, match="shared must be one of"):
        interleaved_frames(moving, reference, 2, shared="left")


def test_videos_library_matches_truth(pair):
    from nfdepth.rig import load_rig
    from nfdepth.video import dynamic_stereo_from_videos

    moving, reference, truth = pair
    rig = load_rig(PAPER_RIG)
    # generators in, as read_video gives them: frames are consumed in lockstep
    results = list(dynamic_stereo_from_videos(iter(moving), iter(reference), rig=rig, crossings=PAIR_CROSSINGS))
    assert [r.index for r in results] == list(PAIR_CROSSINGS)
    for res in results:
        rel = _rel_errors(truth, res)
        assert rel.size > 500
        assert np.median(rel) < 0.005 and rel.max() < 0.02  # measured: median 0.16-0.18 %, max 0.5-0.7 %
        assert res.registration_residual == 0.0  # the cameras coincide exactly at the crossing
        assert res.depth.shape == (200, 200) and np.isfinite(res.depth).sum() == res.result.valid.sum()
    # a crossing the videos do not cover
    with pytest.raises(ValueError, match=r"crossing 16 needs frames 14\.\.18, but the videos end after 17 frames"):
        list(dynamic_stereo_from_videos(moving, reference, rig=rig, crossings=[4, 16]))
    with pytest.raises(RigError, match="motion.crossings is missing"):
        next(dynamic_stereo_from_videos(moving, reference, rig=rig))
    with pytest.raises(ValueError, match="frame 1 has no two frames before it"):
        next(dynamic_stereo_from_videos(moving, reference, rig=rig, crossings=[1]))
    # a crossing's warnings are named by it and keep their class and attributes
    with pytest.warns(NoEdgePointsWarning, match=r"^crossing 4: no edge points: all \d+ strong zero crossings .* are corners") as said:
        list(dynamic_stereo_from_videos(moving, reference, rig=rig, crossings=[4], max_corner_ratio=0.0))
    assert [(w.message.rule, w.message.consequence) for w in said.list] == [("corner", "the result is empty")]


def test_videos_wrong_crossing_warns(pair):
    """Off by one frame the cameras are 2 units apart: frame c of the two videos differ, and we say so."""
    from nfdepth.rig import load_rig
    from nfdepth.video import dynamic_stereo_from_videos

    moving, reference, _ = pair
    with pytest.warns(UserWarning, match="crossing 5: the two cameras' frames 5 differ"):
        res = list(dynamic_stereo_from_videos(moving, reference, rig=load_rig(PAPER_RIG), crossings=[5]))
    assert res[0].registration_residual > 10


def _write_folder(folder, frames):
    folder.mkdir()
    for k, f in enumerate(frames):
        assert cv2.imwrite(str(folder / f"f{k}.png"), np.round(f * 256).astype(np.uint16))  # 16-bit: no 8-bit quantisation
    return folder


def test_dynamic_cli_videos_folders(tmp_path, capsys, pair):
    moving, reference, truth = pair
    m = _write_folder(tmp_path / "moving", moving)
    r = _write_folder(tmp_path / "reference", reference)
    rig = tmp_path / "rig.toml"
    rig.write_text(PAPER_RIG.read_text().replace("frame_interval = 1.0", "frame_interval = 1.0\ncrossings = [4, 12]"))
    out, fig = tmp_path / "pair.npz", tmp_path / "pair.png"
    code, stdout, err = run_cli(capsys, "dynamic", "--moving-video", m, "--reference-video", r, "--rig", rig, "--out", out, "--figure", fig, "--unit", "m")
    assert code == 0, err
    assert "crossing 4: depth at" in stdout and "crossing 12: depth at" in stdout
    data = np.load(out)
    assert list(data["crossing"]) == [4, 12] and data["depth"].shape == (2, 200, 200)
    for k, c in enumerate(PAIR_CROSSINGS):
        ii, jj = np.nonzero(np.isfinite(data["depth"][k]))
        z = truth(c, ii + 0.5, jj + 0.5)  # map pixel [i, j] holds the point at the cell centre
        rel = np.abs(data["depth"][k][ii, jj] - z) / z
        assert ii.size > 500 and np.median(rel) < 0.005
        assert np.all(np.isfinite(data["depth_std"][k][ii, jj]))
    assert fig.read_bytes()[:4] == b"\x89PNG" and (tmp_path / "pair_std.png").read_bytes()[:4] == b"\x89PNG"
    # again: outputs exist, refused before any work
    code, _, err = run_cli(capsys, "dynamic", "--moving-video", m, "--reference-video", r, "--rig", rig, "--out", out)
    assert code == 4 and "--force" in err
    # --crossings overrides the rig; a folder output holds one depth and std map per crossing
    folder = tmp_path / "maps"
    code, stdout, err = run_cli(capsys, "dynamic", "--moving-video", m, "--reference-video", r, "--rig", PAPER_RIG, "--crossings", "12", "--out", folder, "--shared", "reference")
    assert code == 0, err
    assert sorted(p.name for p in folder.iterdir()) == ["depth_000012.tif", "depth_std_000012.tif"]


def test_dynamic_cli_videos_mjpg(tmp_path, capsys, pair):
    """8-bit MJPG videos: quantisation and JPEG error (~1 grey level RMS) set the accuracy."""
    moving, reference, truth = pair
    paths = []
    for name, frames in (("m.avi", moving), ("r.avi", reference)):
        writer = cv2.VideoWriter(str(tmp_path / name), cv2.VideoWriter_fourcc(*"MJPG"), 10, (200, 200), True)
        if not writer.isOpened():
            pytest.skip("no MJPG writer in this OpenCV build")
        for f in frames:
            writer.write(cv2.cvtColor(np.clip(np.rint(f), 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR))
        writer.release()
        paths.append(tmp_path / name)
    out = tmp_path / "pair.npz"
    code, _, err = run_cli(capsys, "dynamic", "--moving-video", paths[0], "--reference-video", paths[1], "--rig", PAPER_RIG, "--crossings", "4", "12", "--out", out)
    assert code == 0, err
    data = np.load(out)
    for k, c in enumerate(PAIR_CROSSINGS):
        ii, jj = np.nonzero(np.isfinite(data["depth"][k]))
        z = truth(c, ii + 0.5, jj + 0.5)
        rel = np.abs(data["depth"][k][ii, jj] - z) / z
        # The MJPG frames differ from the float renderings by ~1.07 grey levels RMS, about
        # the README's noise-std-1 case (median 0.7-1.2 %, p95 3-5 % for static stereo);
        # measured here: median 1.4-1.5 %, p95 6-8 %. Bounds at about twice that.
        assert ii.size > 400
        assert np.median(rel) < 0.03 and np.percentile(rel, 95) < 0.15


def test_dynamic_cli_videos_errors(tmp_path, capsys, pair):
    moving, reference, _ = pair
    m = _write_folder(tmp_path / "moving", moving)
    r = _write_folder(tmp_path / "reference", reference[:-1])
    out = tmp_path / "z.npz"
    cases = [
        (["--moving-video", m], "need both --moving-video and --reference-video"),
        (["--moving-video", m, "--reference-video", r, "--crossings", "4", "--csv", tmp_path / "a.csv"], "--csv is for five images"),
        (["--moving-video", m, "--reference-video", r], "has no motion.crossings: give --crossings"),
        (["--moving-video", m, "--reference-video", r, "--crossings", "1"], "--crossings 1: expected a non-empty list"),
        (["--moving-video", m, "--reference-video", r, "--crossings", "4"], "must be synchronised frame by frame: "),
        (["--moving-video", m, "--reference-video", m, "--crossings", "4", "15"], "crossing 15 needs frames 13..17, but the videos have 17 frames"),
        ([tmp_path / "a.png", "--crossings", "4"], "--crossings and --shared go with --moving-video"),
        (["--moving-video", m, "--reference-video", r, "--crossings", "4", "--unit", "m"], "--unit labels the colour bar of --figure: give --figure too"),
        ([], "exactly 5 images"),
    ]
    for extra, fragment in cases:
        code, _, err = run_cli(capsys, "dynamic", *extra, "--rig", PAPER_RIG, "--out", out)
        assert code == 2, (extra, err)
        assert fragment in err and err.count("\n") == 1, (extra, err)
    assert not out.exists()


def test_video_cli_figure(tmp_path, capsys, sequence_dir, rail_rig):
    fig = tmp_path / "fig.png"
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", tmp_path / "d.npz", "--figure", fig, "--quiet")
    assert code == 0, err
    assert fig.read_bytes()[:4] == b"\x89PNG" and (tmp_path / "fig_std.png").read_bytes()[:4] == b"\x89PNG"
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", tmp_path / "e.npz", "--figure", fig, "--quiet")
    assert code == 4 and "--figure" in err and not (tmp_path / "e.npz").exists()
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", tmp_path / "e.npz", "--figure", tmp_path / "f.jpg")
    assert code == 2 and "must end in one of .png" in err


# ------------------------------------------------------------------ static and reversed camera motion


def _static_poses(tmp_path, name, xs):
    p = tmp_path / name
    p.write_text("frame,x,y,z\n" + "".join(f"{k},{x},0,0\n" for k, x in enumerate(xs)))
    return p


def test_static_camera_refused(tmp_path, scene):
    """No frame triple with a baseline: an error, not an all-NaN result."""
    frames = list(scene.frames[:5])
    with pytest.raises(ValueError, match=r"positions: the camera does not move: all 5 positions are \(2, 0, 0\); expected camera positions"):
        next(depth_from_video(frames, camera=scene.camera, positions=np.tile([2.0, 0.0, 0.0], (5, 1))))
    rig_file = tmp_path / "r.toml"
    rig_file.write_text(f'[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[video]\nposes = "{_static_poses(tmp_path, "z.csv", [0] * 5).name}"\n')
    with pytest.raises(RigError, match=r"poses '.*z\.csv': the camera does not move: all 5 positions are \(0, 0, 0\)"):
        next(depth_from_video(frames, rig=load_rig(rig_file)))
    # back and forth: the positions change, but every frame's neighbours coincide
    gen = depth_from_video(frames, camera=scene.camera, positions=[[x, 0, 0] for x in (0, 1, 0, 1, 0)])
    with pytest.raises(ValueError, match=r"does not move in any of the 3 frame triples \(frames 1-3 have the same position"):
        next(gen)


def test_static_triples_skipped_with_one_warning(scene):
    """Some triples move and some do not: the static ones are skipped, with one warning saying how many."""
    xs = [0, 0, 0, 1, 2, 3, 4, 4, 4]  # frames 1 and 7 have coinciding neighbours
    frames = [scene.frames[max(0, min(x, N_FRAMES - 1))] for x in xs]
    with pytest.warns(UserWarning) as record:
        results = list(depth_from_video(frames, camera=scene.camera, positions=[[x, 0, 0] for x in xs]))
    assert [r.index for r in results] == list(range(1, 8))
    assert len(record) == 1, [str(w.message) for w in record]
    text = str(record[0].message)
    assert text.startswith("the camera does not move around 2 of 7 frames (1, 7: the same position one frame before and after)")
    assert "\n" not in text
    first, last = results[0], results[-1]
    assert first.baseline == 0 and not np.any(np.isfinite(first.inverse_depth)) and not first.count.any()
    assert last.baseline == 0 and not last.measured.any()
    # frame 7 carries over the fused depth of frame 6
    assert np.isfinite(last.inverse_depth).sum() > 300
    assert results[3].measured.sum() > 300


def test_video_cli_static_camera(tmp_path, capsys, sequence_dir, rail_rig):
    for name, xs in (("zero.csv", [0] * N_FRAMES), ("wobble.csv", [k % 2 for k in range(N_FRAMES)])):
        poses = _static_poses(tmp_path, name, xs)
        for out in (tmp_path / "s.npz", tmp_path / "folder"):
            code, stdout, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--poses", poses, "--out", out, "--quiet")
            assert code == 2, err
            assert err.count("\n") == 1 and err.startswith("nfdepth: error: ") and "the camera does not move" in err, err
            assert "baseline" in err and stdout == ""
            assert not out.exists()


def test_video_reversed_motion_warns_once(tmp_path, capsys, scene, sequence_dir, rail_rig):
    """Poses moving the wrong way: one summary warning per run, naming the poses, not `direction`."""
    with pytest.warns(UserWarning) as record:
        results = list(depth_from_video(list(scene.frames), camera=scene.camera, velocity=(-1.0, 0.0, 0.0)))
    assert len(results) == N_FRAMES - 2
    assert len(record) == 1, [str(w.message) for w in record]
    text = str(record[0].message)
    n = N_FRAMES - 2
    assert text.startswith(f"in {n} of {n} frames (1-{n}) most edge points came out behind the camera (")
    assert "the camera moves opposite to its given positions" in text and "poses' x, y, z" in text and "same order" in text
    assert "direction" not in text and "\n" not in text
    points = int(text.split("(")[2].split(" of ")[0])
    assert points > 300 * n

    poses = _static_poses(tmp_path, "rev.csv", [-k for k in range(N_FRAMES)])
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--poses", poses, "--out", tmp_path / "r.npz", "--quiet")
    assert code == 0, err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"nfdepth: warning: in {n} of {n} frames (1-{n}) most edge points"), err
    assert "direction" not in err
    # the right way round: no warning
    poses = _static_poses(tmp_path, "fwd.csv", list(range(N_FRAMES)))
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--poses", poses, "--out", tmp_path / "f.npz", "--quiet")
    assert code == 0 and err == ""


# ------------------------------------------------------------------ large coordinates and the speed range


def _maps(res):
    return [res.inverse_depth, res.inverse_depth_std, res.measured_inverse_depth, res.measured_inverse_depth_std]


def test_large_coordinates_give_the_same_depths(scene):
    """Positions far from the origin (map coordinates) with small steps: the same depths as near the origin.

    The old test refused a step below 1e-9 |position| as "not moving" (1 mm at 5e6 m); only steps lost to
    float64 rounding (a few ulps of the coordinates) may count as standing still.
    """
    frames = list(scene.frames[:6])
    near = list(depth_from_video(frames, camera=scene.camera, positions=[[k, 0, 0] for k in range(6)]))
    # exactly representable positions: the same baselines and displacements, so bit-identical maps
    for far in (
        list(depth_from_video(frames, camera=scene.camera, positions=[[5e9 + k, 0, 0] for k in range(6)])),
        list(depth_from_video(frames, camera=scene.camera, velocity=STEP, first_frame=10**9)),
    ):
        assert len(far) == len(near) == 4
        for a, b in zip(near, far):
            assert b.baseline == a.baseline == 1.0
            for x, y in zip(_maps(a), _maps(b)):
                np.testing.assert_array_equal(y, x)
            np.testing.assert_array_equal(b.count, a.count)
    assert far[0].index == 10**9 + 1 and far[0].camera_position.tolist() == [10**9 + 1.0, 0.0, 0.0]

    # 1 mm steps at 5e6 (depths in the same unit, so 1000x smaller than the scene's): each position is
    # rounded by up to ulp(5e6) / 2 = 4.7e-10, so the two-frame step 2e-3 errs by up to 9.3e-10 = 4.7e-7
    # relative, and so do the inverse depths (rho ~ 1 / baseline), plus float32 rounding of the maps
    # (6e-8 each): rtol 1e-6
    mm = list(depth_from_video(frames, camera=scene.camera, positions=[[k * 1e-3, 0, 0] for k in range(6)]))
    far = list(depth_from_video(frames, camera=scene.camera, positions=[[5e6 + k * 1e-3, 0, 0] for k in range(6)]))
    assert len(far) == len(mm) == 4
    for a, b in zip(mm, far):
        assert b.baseline == pytest.approx(a.baseline, rel=4.7e-7)
        assert np.count_nonzero(b.measured) > 300
        np.testing.assert_array_equal(b.count, a.count)
        for x, y in zip(_maps(a), _maps(b)):
            np.testing.assert_array_equal(np.isfinite(y), np.isfinite(x))
            np.testing.assert_allclose(y, x, rtol=1e-6)
    # and the depths are the scene's, scaled to millimetres
    np.testing.assert_allclose(far[-1].depth[far[-1].measured], 1e-3 * near[-1].depth[near[-1].measured], rtol=1e-6)


def test_steps_lost_to_rounding_do_not_move(scene):
    """Positions that differ by an ulp or two (rounding noise of one position) still count as standing still, and the message says so."""
    x, d = 5e6, float(np.spacing(5e6))
    with pytest.raises(ValueError, match=r"does not move in any of the 3 frame triples .* around frames 1-3 the positions differ by no more than"
                       r" float64 rounding \(4 ulps of coordinates up to 5e\+06\): give them relative to a nearby origin"):
        next(depth_from_video(list(scene.frames[:5]), camera=scene.camera, positions=[[x + k * d, 0, 0] for k in range(5)]))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"velocity": (1e300, 0, 0)}, r"velocity = \(1e\+300, 0, 0\): expected a speed of 1e-30 to 1e\+30 per frame in its largest component"),
        ({"velocity": (1e-300, 0, 0)}, r"velocity = \(1e-300, 0, 0\): expected a speed of 1e-30 to 1e\+30 per frame"),
        ({"positions": [[k * 1e300, 0, 0] for k in range(5)]},
         r"positions: the camera moves from \(0, 0, 0\) at frame 0 to \(1e\+300, 0, 0\) at frame 1, a step of 1e\+300: expected a speed of 1e-30 to 1e\+30 per frame, or 0 where it stands still"),
        ({"positions": [[0, 0, 0]] * 2 + [[0, 1e-40, 0]] * 3},
         r"positions: the camera moves from \(0, 0, 0\) at frame 1 to \(0, 1e-40, 0\) at frame 2, a step of 1e-40: expected a speed"),
        ({"velocity": STEP, "process_noise": 1e300}, r"process_noise = 1e\+300 is beyond the float32 maps it applies to: expected at most 1e\+30"),
        ({"velocity": STEP, "min_std_px": 1e300}, r"min_std_px = 1e\+300 is beyond the float32 maps it applies to: expected at most 1e\+30"),
        ({"velocity": STEP, "noise_std": 1e300}, r"noise_std = 1e\+300 is beyond any image's intensities: expected at most 1e\+30"),
        ({"velocity": STEP, "gate": 1e300}, r"gate = 1e\+300 is beyond the float32 maps it applies to: expected at most 1e\+30"),
    ],
)
def test_speeds_and_options_out_of_range_refused(scene, kwargs, match):
    """Were: overflow warnings, then 'the camera does not move' (or overflowing variances)."""
    with pytest.raises(ValueError, match=match):
        next(depth_from_video(list(scene.frames[:5]), camera=scene.camera, **kwargs))


def test_speed_range_ends_accepted(scene):
    """The ends of the ranges run without a warning (pytest turns warnings into errors)."""
    frames = list(scene.frames[:3])
    (tiny,) = depth_from_video(frames, camera=scene.camera, velocity=(1e-30, 0, 0))
    (unit,) = depth_from_video(frames, camera=scene.camera, velocity=STEP)
    assert np.nanmedian(tiny.depth) == pytest.approx(1e-30 * np.nanmedian(unit.depth), rel=1e-6)
    res = list(depth_from_video(frames, camera=scene.camera, velocity=STEP, process_noise=1e30, min_std_px=1e30, noise_std=1e30, gate=1e30))
    assert np.count_nonzero(res[0].measured) > 300
    # a central-difference step just above 1e30 (rounding of 3e30 - 1e30) is named as such, not as the pipeline's `baseline`
    step = (3 * 1e30 - 1e30) / 2
    assert step > 1e30
    with pytest.raises(ValueError, match=rf"^velocity: the camera's step around frame 2 \(half the distance from frame 1 to frame 3\) is {re.escape(repr(step))}: expected a step of 1e-30 to 1e\+30"):
        list(depth_from_video(list(scene.frames[:4]), camera=scene.camera, velocity=(1e30, 0, 0)))


def test_video_cli_poses_beyond_the_speed_range(tmp_path, capsys, sequence_dir, rail_rig):
    """`--poses` with x = k * 1e300: was an overflow warning and 'the camera does not move'."""
    poses = _static_poses(tmp_path, "huge.csv", [k * 1e300 for k in range(N_FRAMES)])
    code, stdout, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--poses", poses, "--out", tmp_path / "h.npz", "--quiet")
    assert code == 2, err
    assert err.count("\n") == 1 and stdout == "", err
    assert "poses '" in err and "huge.csv': the camera moves from (0, 0, 0) at frame 0 to (1e+300, 0, 0) at frame 1, a step of 1e+300" in err
    assert "expected a speed of 1e-30 to 1e+30 per frame" in err
    assert not (tmp_path / "h.npz").exists()
    # the same in the rig's own [video] positions
    rig = tmp_path / "far.toml"
    rig.write_text("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[video]\npositions = [[0, 0, 0], [1e300, 0, 0], [2e300, 0, 0]]\n")
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rig, "--out", tmp_path / "h.npz", "--quiet")
    assert code == 2 and err.count("\n") == 1, err
    assert "far.toml': video.positions: the camera moves from (0, 0, 0) at frame 0 to (1e+300, 0, 0) at frame 1" in err


# ------------------------------------------------------------------ more inputs and outputs


def test_read_video_unsupported_extension(tmp_path):
    from nfdepth.io import ImageReadError
    from nfdepth.video import VIDEO_EXTENSIONS

    p = tmp_path / "notes.txt"
    p.write_text("x")
    with pytest.raises(ImageReadError) as info:
        read_video(p)
    assert str(info.value) == (
        f"cannot read video '{p}': unsupported extension '.txt'; give a video ({', '.join(VIDEO_EXTENSIONS)}), a folder of images or a glob pattern"
    )


def _garbage_video(tmp_path):
    p = tmp_path / "clip.mp4"
    p.write_bytes(b"this is not a video")
    return p


def test_video_file_opencv_cannot_open(tmp_path, capsys, rail_rig):
    from nfdepth.io import ImageReadError

    bad = _garbage_video(tmp_path)
    source = read_video(bad)
    assert source.paths is None and source.video == bad and len(source) == 0
    with pytest.raises(ImageReadError, match=re.escape(f"cannot read video '{bad}': OpenCV could not open it")):
        next(iter(source))
    code, stdout, _ = run_cli(capsys, "video", bad, "--rig", rail_rig, "--out", tmp_path / "d.npz")
    assert code == 3 and stdout == "" and not (tmp_path / "d.npz").exists()


def test_video_cli_unopenable_file_is_one_line(tmp_path, capfd, rail_rig):
    bad = _garbage_video(tmp_path)
    code = main(["video", str(bad), "--rig", str(rail_rig), "--out", str(tmp_path / "d.npz")])
    err = capfd.readouterr().err
    assert code == 3
    assert err == f"nfdepth: error: cannot read video '{bad}': OpenCV could not open it\n"  # was: two '[mov,mp4,...] moov atom not found' lines first


def test_video_cli_short_video_file(tmp_path, capsys, scene):
    """A video file's frame count is only known once read: two frames are refused after reading, with nothing written."""
    avi = _write_avi(tmp_path / "two.avi", scene.frames[:2])
    rig = tmp_path / "rig.toml"
    rig.write_text("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[video]\nvelocity = [1.0, 0.0, 0.0]\n")
    for out in (tmp_path / "d.npz", tmp_path / "folder"):
        code, stdout, err = run_cli(capsys, "video", avi, "--rig", rig, "--out", out, "--quiet")
        assert (code, stdout, err) == (2, "", f"nfdepth: error: video needs at least 3 frames, '{avi}' gave 2\n")
        assert not out.exists()


def test_video_cli_out_folder_errors(tmp_path, capsys, sequence_dir, rail_rig):
    afile = tmp_path / "results"
    afile.write_text("x")
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", afile)
    assert (code, err) == (4, f"nfdepth: error: --out '{afile}' exists and is not a folder\n")
    assert afile.read_text() == "x"
    missing = tmp_path / "nodir" / "out"
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", missing)
    assert (code, err) == (4, f"nfdepth: error: --out '{missing}': directory '{tmp_path / 'nodir'}' does not exist\n")
    assert not (tmp_path / "nodir").exists()
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", tmp_path / "d.npz", "--sigma-px", "-1")
    assert (code, err) == (2, "nfdepth: error: --sigma-px must be a finite number >= 0, got -1\n")


def test_video_cli_progress_on_a_terminal_ends_its_line_before_an_error(tmp_path, monkeypatch, sequence_dir, rail_rig):
    """On a terminal the bar redraws in place ('\\r'); an error starts on a line of its own."""
    import io as _io
    import sys
    import types

    from nfdepth import _cli_rig

    class Terminal(_io.StringIO):
        def isatty(self):
            return True

    clock = iter(np.arange(1000.0, 2000.0, 0.5))  # every reading 0.5 s later: each frame redraws the bar
    monkeypatch.setattr(_cli_rig, "time", types.SimpleNamespace(perf_counter=lambda: float(next(clock))))
    broken = sequence_dir / "f6.png"
    broken.write_bytes(broken.read_bytes()[:60])
    term = Terminal()
    monkeypatch.setattr(sys, "stderr", term)
    code = main(["video", str(sequence_dir), "--rig", str(rail_rig), "--out", str(tmp_path / "d.npz")])
    assert code == 3
    text = term.getvalue()
    bar, error = text.rsplit("\n", 2)[:2]
    assert error == f"nfdepth: error: cannot read image '{broken}': OpenCV could not decode it as PNG (broken or truncated file?)"
    redraws = bar.split("\r")
    assert redraws[0] == "" and len(redraws) == 7  # frames 0..5 read, each drawn over the last
    for k, line in enumerate(redraws[1:], 1):
        filled = int(24 * k / N_FRAMES)
        assert re.fullmatch(rf"video \[{'#' * filled}{'-' * (24 - filled)}\] {k}/{N_FRAMES} frames, \d+\.\d frames/s, ETA \d+ s", line), line
    assert not (tmp_path / "d.npz").exists()


class _FakeStream:
    def __init__(self, tty):
        self.tty, self.text = tty, ""

    def isatty(self):
        return self.tty

    def write(self, s):
        self.text += s

    def flush(self):
        pass


def _progress(monkeypatch, total, *, tty, quiet=False):
    import types

    from nfdepth import _cli_rig

    now = [100.0]
    monkeypatch.setattr(_cli_rig, "time", types.SimpleNamespace(perf_counter=lambda: now[0]))
    stream = _FakeStream(tty)
    return _cli_rig._Progress(total, quiet=quiet, stream=stream), stream, now


def test_progress_bar_redraws_a_terminal_line_at_most_every_tenth_of_a_second(monkeypatch):
    p, out, now = _progress(monkeypatch, 4, tty=True)
    now[0] = 101.0
    p.step()  # 1 frame in 1 s
    assert out.text == "\rvideo [######------------------] 1/4 frames, 1.0 frames/s, ETA 3 s"
    now[0] = 101.05
    p.step()  # 0.05 s later: not redrawn
    assert out.text.count("\r") == 1
    now[0] = 103.0
    p.step()
    assert out.text.endswith("\rvideo [##################------] 3/4 frames, 1.0 frames/s, ETA 1 s")
    p.abort()
    assert out.text.endswith(" ETA 1 s\n")
    now[0] = 104.0
    p.step()  # 1 s after the last redraw: redrawn
    p.close()
    assert out.text.endswith("\rvideo [########################] 4/4 frames, 1.0 frames/s, ETA 0 s\rvideo [########################] 4/4 frames, 1.0 frames/s, ETA 0 s\n")


def test_progress_in_a_log_writes_a_line_per_tenth_at_most_every_5_s(monkeypatch):
    p, out, now = _progress(monkeypatch, 20, tty=False)
    for k in range(1, 21):
        now[0] = 100.0 + 2.0 * k  # a frame every 2 s
        p.step()
    # every 2nd frame is a tenth; a line when 5 s have passed since the last one: frames 4, 8, 12, 16, 20
    lines = out.text.splitlines()
    assert [line.split("] ")[1].split(" frames")[0] for line in lines] == ["4/20", "8/20", "12/20", "16/20", "20/20"]
    assert lines[0] == "video [####--------------------] 4/20 frames, 0.5 frames/s, ETA 32 s"
    p.abort()  # not a terminal: no line to end
    assert out.text.count("\n") == 5


def test_progress_without_a_frame_count_and_quiet(monkeypatch):
    p, out, now = _progress(monkeypatch, 0, tty=True)  # a video whose container does not say how many frames
    now[0] = 102.0
    p.step(3)
    p.close()
    assert out.text == "\rvideo: 3 frames, 1.5 frames/s\rvideo: 3 frames, 1.5 frames/s\n"
    q, quiet, now = _progress(monkeypatch, 5, tty=True, quiet=True)
    now[0] = 101.0
    q.step()
    q.abort()
    q.close()
    assert quiet.text == ""


# ------------------------------------------------------------------ library: arguments and outputs


def test_depth_from_video_argument_errors(scene):
    from nfdepth.camera import PinholeCamera
    from nfdepth.rig import rig_from_dict

    frames = list(scene.frames[:3])
    with pytest.raises(TypeError, match=r"^depth_from_video needs a camera: pass rig=\.\.\. or camera=PinholeCamera\(\.\.\.\)$"):
        next(depth_from_video(frames, velocity=STEP))
    with pytest.raises(ValueError, match=r"^positions must have shape \(N, 3\) with finite values, got shape \(3, 2\)$"):
        next(depth_from_video(frames, camera=scene.camera, positions=np.zeros((3, 2))))
    with pytest.raises(ValueError, match=r"^positions must have shape \(N, 3\) with finite values, got shape \(3, 3\)$"):
        next(depth_from_video(frames, camera=scene.camera, positions=[[0, 0, 0], [1, 0, 0], [np.nan, 0, 0]]))
    cam = {"focal_px": 100, "width_px": 200, "height_px": 200}
    with pytest.raises(RigError, match=r"^the rig has no \[video\] section: expected video\.velocity, video\.positions or video\.poses$"):
        next(depth_from_video(frames, rig=rig_from_dict({"camera": cam})))
    # frames of another size than the camera's
    small = [f[:100, :120] for f in frames]
    with pytest.raises(ValueError, match=r"^frame 7 has size 120x100, the camera 200x200$"):
        next(depth_from_video(small, camera=scene.camera, velocity=STEP, first_frame=7))
    with pytest.raises(RigError, match=r"camera\.width_px x camera\.height_px = 200x200 does not match frame 0 \(120x100\)"):
        next(depth_from_video(small, rig=rig_from_dict({"camera": cam, "video": {"velocity": [1, 0, 0]}})))
    # an explicit camera of the frames' size overrides the rig's
    own = PinholeCamera(100.0, 120, 100)
    assert len(list(depth_from_video(small, rig=rig_from_dict({"camera": cam, "video": {"velocity": [1, 0, 0]}}), camera=own))) == 1


def test_rig_video_positions_equal_its_velocity(tmp_path, scene):
    """[video] positions = [[0,0,0], [1,0,0], ...] is the same motion as velocity = [1, 0, 0]: bit-identical maps."""
    head = "[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[video]\n"
    (tmp_path / "v.toml").write_text(head + "velocity = [1.0, 0.0, 0.0]\n")
    (tmp_path / "p.toml").write_text(head + "positions = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0]]\n")
    a = list(depth_from_video(list(scene.frames[:5]), rig=load_rig(tmp_path / "v.toml")))
    b = list(depth_from_video(list(scene.frames[:5]), rig=load_rig(tmp_path / "p.toml")))
    assert [r.index for r in b] == [1, 2, 3]
    for x, y in zip(a, b):
        assert y.baseline == x.baseline == 1.0
        np.testing.assert_array_equal(y.inverse_depth, x.inverse_depth)
        np.testing.assert_array_equal(y.camera_position, x.camera_position)
    assert np.isfinite(b[-1].inverse_depth).sum() > 300
    (tmp_path / "s.toml").write_text(head + "positions = [[3, 0, 0], [3, 0, 0], [3, 0, 0]]\n")
    with pytest.raises(RigError, match=re.escape(f"rig '{tmp_path / 's.toml'}': video.positions: the camera does not move: all 3 positions are (3, 0, 0)")):
        next(depth_from_video(list(scene.frames[:3]), rig=load_rig(tmp_path / "s.toml")))


def test_write_video_npz_without_a_camera(tmp_path, scene):
    from nfdepth.video import NPZ_ARRAYS, write_video_npz

    results = list(depth_from_video(list(scene.frames[:4]), camera=scene.camera, velocity=STEP))
    path = write_video_npz(results, tmp_path / "v.npz")
    with np.load(path) as data:
        assert sorted(data.files) == sorted(["index", "camera_position", "baseline", *NPZ_ARRAYS])  # no focal_px, cx_px, cy_px
        assert data["index"].tolist() == [1, 2] and data["baseline"].tolist() == [1.0, 1.0]
        np.testing.assert_array_equal(data["camera_position"], [[1.0, 0, 0], [2.0, 0, 0]])
        np.testing.assert_array_equal(data["depth"][1], results[1].depth)
    empty = write_video_npz([], tmp_path / "e.npz", camera=scene.camera)
    with np.load(empty) as data:
        assert data["index"].shape == (0,) and data["camera_position"].shape == (0, 3) and data["depth"].shape == (0, 0, 0)
        assert float(data["focal_px"]) == scene.camera.focal_px


def test_flat_videos_give_empty_crossings_without_a_residual(tmp_path):
    """No edge point at a crossing (textureless frames): an empty result, residual 0, and only the textureless warning."""
    from nfdepth.video import dynamic_stereo_from_videos, write_crossings_npz

    flat = [np.full((200, 200), 100.0)] * 5
    with pytest.warns(UserWarning, match="no edge points: the images are textureless") as record:
        (res,) = dynamic_stereo_from_videos(flat, flat, rig=load_rig(PAPER_RIG), crossings=[2])
    assert len(record) == 1
    assert res.index == 2 and len(res.result) == 0
    assert res.registration_residual == 0.0 and res.noise_std == 0.0
    assert not res.valid.any() and res.depth.shape == (200, 200)
    path = write_crossings_npz([res], tmp_path / "c.npz")
    with np.load(path) as data:
        assert sorted(data.files) == ["crossing", "depth", "depth_std", "noise_std", "registration_residual"]
        assert data["crossing"].tolist() == [2] and np.isnan(data["depth"]).all()


def test_video_cli_missing_poses_file(tmp_path, capsys, sequence_dir, rail_rig):
    missing = tmp_path / "poses.csv"
    code, stdout, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--poses", missing, "--out", tmp_path / "d.npz")
    assert (code, stdout, err) == (3, "", f"nfdepth: error: cannot read poses file '{missing}': no such file\n")
    assert not (tmp_path / "d.npz").exists()


def test_positions_that_run_out_are_refused(scene):
    """The library's ``positions=`` are named as the argument (a ValueError), not as a rig key."""
    with pytest.raises(ValueError, match=r"^positions has 3 entries: no position for frame 3 \(one per frame, from first_frame\)$") as info:
        list(depth_from_video(list(scene.frames[:5]), camera=scene.camera, positions=[[0, 0, 0], [1, 0, 0], [2, 0, 0]]))
    assert not isinstance(info.value, RigError)


def test_video_cli_rig_positions_that_run_out_name_the_rig(tmp_path, capsys, sequence_dir):
    """Every rig problem names the file (docs/rig-format.md, Errors); poses that run out do ('poses in 'p.csv': no row for frame 3')."""
    rig = tmp_path / "short.toml"
    rig.write_text("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[video]\npositions = [[0, 0, 0], [1, 0, 0], [2, 0, 0]]\n")
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rig, "--out", tmp_path / "d.npz", "--quiet")
    assert code == 2 and not (tmp_path / "d.npz").exists()
    assert f"'{rig}'" in err, err  # was: "nfdepth: error: video.positions has 3 entries: no position for frame 3"


def test_video_cli_broken_frame_leaves_no_maps_in_the_folder(tmp_path, capsys, sequence_dir, rail_rig):
    broken = sequence_dir / "f6.png"
    broken.write_bytes(broken.read_bytes()[:60])
    out = tmp_path / "maps"
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", out, "--quiet")
    assert code == 3 and err.count("\n") == 1 and "f6.png': OpenCV could not decode it as PNG" in err
    assert not out.exists() or list(out.iterdir()) == []  # was: depth_00000[1-4].tif and their std maps


def _update_per_pixel(prior, rho_m, var_m, *, gate, max_age):
    """The fusion rule of ``nfdepth.video._update`` written out pixel by pixel (the reference its arrays must equal)."""
    h, w = rho_m.shape
    rho, var = np.full((h, w), np.nan), np.full((h, w), np.nan)
    age, count = np.zeros((h, w), np.int32), np.zeros((h, w), np.int32)
    consumed = set()
    fused = {}
    for i in range(h):
        for j in range(w):
            if not np.isfinite(rho_m[i, j]):
                continue
            src = (i, j) if np.isfinite(prior.var[i, j]) else None
            if src is None:  # the lowest-variance 3 x 3 neighbour with a prior, the first in row order on ties
                best = np.inf
                for di in (-1, 0, 1):
                    for dj in (-1, 0, 1):
                        a, b = i + di, j + dj
                        if (di, dj) != (0, 0) and 0 <= a < h and 0 <= b < w and np.isfinite(prior.var[a, b]) and prior.var[a, b] < best:
                            best, src = prior.var[a, b], (a, b)
            if src is not None:
                consumed.add(src)
                p_rho, p_var = prior.rho[src], prior.var[src]
                if abs(p_rho - rho_m[i, j]) <= gate * np.sqrt(p_var + var_m[i, j]):
                    info = 1.0 / p_var + 1.0 / var_m[i, j]
                    fused[i, j] = ((p_rho / p_var + rho_m[i, j] / var_m[i, j]) / info, 1.0 / info, prior.count[src] + 1)
                    continue
            fused[i, j] = (rho_m[i, j], var_m[i, j], 1)
    for i in range(h):
        for j in range(w):
            if np.isfinite(prior.rho[i, j]) and (i, j) not in fused and (i, j) not in consumed and prior.age[i, j] <= max_age:
                rho[i, j], var[i, j], age[i, j], count[i, j] = prior.rho[i, j], prior.var[i, j], prior.age[i, j], prior.count[i, j]
    for (i, j), (r, v, c) in fused.items():
        rho[i, j], var[i, j], age[i, j], count[i, j] = r, v, 0, c
    return rho, var, age, count


def test_fusion_update_equals_the_per_pixel_rule():
    """The Kalman update visits only the measured pixels: the same state as the rule applied pixel by pixel,
    with priors on the border, ties between neighbours, inconsistent measurements and old points."""
    from nfdepth.video import _State, _update

    rng = np.random.default_rng(7)
    h, w = 23, 31
    for trial in range(6):
        prior = _State((h, w))
        has = rng.random((h, w)) < 0.4
        prior.rho[has] = rng.uniform(0.1, 1.0, has.sum())
        prior.var[has] = rng.choice([1e-4, 2e-4, 4e-4], has.sum())  # few values: ties between neighbours
        prior.age[has] = rng.integers(0, 4, has.sum())
        prior.count[has] = rng.integers(1, 9, has.sum())
        rho_m, var_m = np.full((h, w), np.nan), np.full((h, w), np.nan)
        meas = rng.random((h, w)) < (0.1 if trial % 2 else 0.6)
        rho_m[meas] = rng.uniform(0.1, 1.0, meas.sum())
        var_m[meas] = rng.uniform(1e-4, 1e-2, meas.sum())
        got = _update(prior, rho_m, var_m, gate=4.0, max_age=2)
        want = _update_per_pixel(prior, rho_m, var_m, gate=4.0, max_age=2)
        for name, a, b in zip(("rho", "var", "age", "count"), (got.rho, got.var, got.age, got.count), want):
            np.testing.assert_array_equal(a, b, err_msg=f"trial {trial}: {name}")
        assert np.isfinite(got.rho).sum() > meas.sum()  # some unmeasured points survive
        assert (got.count > 1).any()  # and some are fused


def test_noise_estimated_once_per_frame_gives_the_per_triple_median(scene, monkeypatch):
    """Each frame's noise is estimated once and serves its three triples: the depths equal those from
    the noise the pipeline would get by estimating every triple's frames afresh (given per run here)."""
    from nfdepth import video
    from nfdepth.normal_flow import estimate_noise_std

    calls = []
    real = video.estimate_noise_std
    monkeypatch.setattr(video, "estimate_noise_std", lambda f: calls.append(1) or real(f))
    frames = list(scene.frames[:5])
    estimated = list(depth_from_video(frames, camera=scene.camera, velocity=STEP))
    assert len(calls) == len(frames)
    for k, frame in enumerate(estimated):
        noise = float(np.median([estimate_noise_std(np.asarray(f, np.float32)) for f in frames[k : k + 3]]))  # as read
        given = list(depth_from_video(frames[k : k + 3], camera=scene.camera, velocity=STEP, noise_std=noise, first_frame=k))
        assert given[0].index == frame.index
        np.testing.assert_array_equal(frame.measured_inverse_depth_std, given[0].measured_inverse_depth_std)


def test_the_frames_whose_exposure_was_undone_are_reported(scene, tmp_path, capsys, rail_rig):
    """Frame 3 of the sequence 20 % brighter: the triples around it report the exposures undone
    (``VideoDepthFrame.exposure``, each outer frame against the middle one: frame 3 at 1.2 in the triples of frames
    2 and 4, its neighbours at 1 / 1.2 in its own) and ``nfdepth video`` says so; equal frames report nothing."""
    frames = [np.asarray(f, np.float32) for f in scene.frames[:6]]
    plain = list(depth_from_video(frames, camera=scene.camera, velocity=STEP))
    assert all(r.exposure is None for r in plain)
    frames[3] = np.float32(1.2) * frames[3]
    lit = {r.index: r.exposure for r in depth_from_video(frames, camera=scene.camera, velocity=STEP)}
    assert lit[1] is None
    assert lit[2][0] is None and lit[2][1][0] == pytest.approx(1.2, rel=0.01)
    assert lit[3][0][0] == pytest.approx(1 / 1.2, rel=0.01) and lit[3][1][0] == pytest.approx(1 / 1.2, rel=0.01)
    assert lit[4][0][0] == pytest.approx(1.2, rel=0.01) and lit[4][1] is None
    folder = tmp_path / "lit"
    folder.mkdir()
    for k, frame in enumerate(frames):
        assert cv2.imwrite(str(folder / f"f{k}.png"), np.round(np.clip(frame, 0, 320) * 200).astype(np.uint16))
    code = main(["video", str(folder / "*.png"), "--rig", str(rail_rig), "--out", str(tmp_path / "v.npz"), "--quiet"])
    printed, err = capsys.readouterr()
    assert code == 0, err
    assert re.search(r", exposure matched in 3 triples \(frames 2, 3, 4; gains 0\.8\d\d?\.\.1\.2\d?, offsets -\d+(\.\d+)?\.\.\+\d+(\.\d+)?\) -> ", printed), printed  # offsets in the files' 16-bit levels


def test_a_failed_video_run_removes_the_folder_it_made(tmp_path, capsys, sequence_dir, rail_rig):
    """Frame 6 of a different size: the run fails after writing frames 1-4's maps into the --out folder it created.
    It removes the maps and (new) the folder it made; a folder that was there before stays."""
    frames = tmp_path / "cut"
    frames.mkdir()
    for k in range(N_FRAMES):
        img = cv2.imread(str(sequence_dir / f"f{k}.png"), cv2.IMREAD_UNCHANGED)
        assert cv2.imwrite(str(frames / f"f{k}.png"), img[:, :190] if k == 6 else img)
    out = tmp_path / "maps"
    code, _, err = run_cli(capsys, "video", frames, "--rig", rail_rig, "--out", out, "--quiet")
    assert code == 2 and "does not match frame 6" in err and err.count("\n") == 1
    assert err.strip().endswith(f"removed the 8 output(s) it had completed and the folder it made ({out})"), err
    assert not out.exists()
    out.mkdir()
    code, _, err = run_cli(capsys, "video", frames, "--rig", rail_rig, "--out", out, "--quiet")
    assert code == 2 and err.strip().endswith("removed the 8 output(s) it had completed"), err
    assert out.is_dir() and not any(out.iterdir())


def test_a_blank_frame_is_named_and_not_measured(scene, tmp_path, capsys, rail_rig):
    """Frame 4 of one value throughout (a dropped frame): before, its own triple warned of a textureless image without
    naming it, and its neighbours' triples read the jump as motion and warned that the camera moves opposite to its
    poses. Now one warning names the frame and the triples left unmeasured (3-5), which carry the fused depth."""
    frames = [np.asarray(f, np.float32) for f in scene.frames]
    frames[4] = np.full_like(frames[4], 128.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        results = {r.index: r for r in depth_from_video(frames, camera=scene.camera, velocity=STEP)}
    messages = [str(w.message) for w in caught]
    assert messages == [
        (
            "frame 4 holds one value throughout (a blank or dropped frame?): the triples of 3 of 7 frames (3-5) are not"
            " measured and carry the fused depth of the frames before for up to 2 frames (max_age)"
        )
    ], messages
    assert [k for k, r in results.items() if r.measured.any()] == [1, 2, 6, 7]
    assert np.isfinite(results[3].depth).any() and np.isfinite(results[4].depth).any()  # carried
    assert not np.isfinite(results[5].depth).any()  # beyond max_age
    folder = tmp_path / "blank"
    folder.mkdir()
    for k, frame in enumerate(frames):
        assert cv2.imwrite(str(folder / f"f{k}.png"), np.round(frame * 200).astype(np.uint16))
    code, printed, err = run_cli(capsys, "video", str(folder / "*.png"), "--rig", rail_rig, "--out", tmp_path / "v.npz", "--quiet")
    assert code == 0 and "frame 4 holds one value throughout" in err, err
    assert "depth for 7 frames (of 9; the first and last have no triple), 1 of them without any (frame 5) -> " in printed, printed


def test_swapped_videos_are_named_as_a_likely_cause(pair):
    """The moving and the reference videos given the other way round: every point comes out behind the camera. The
    warning used to ask whether I1..I5 were in time order (there are no images I1..I5 to order here)."""
    from nfdepth.video import dynamic_stereo_from_videos

    moving, reference, _ = pair
    with pytest.warns(UserWarning) as caught:
        (res,) = dynamic_stereo_from_videos(reference, moving, rig=load_rig(PAPER_RIG), crossings=PAIR_CROSSINGS[:1])
    behind = [str(w.message) for w in caught if "negative inverse depth" in str(w.message)]
    assert len(behind) == 1 and behind[0].startswith(f"crossing {PAIR_CROSSINGS[0]}: "), behind
    assert behind[0].endswith("are the moving and the reference videos swapped, or is the rig's motion of the wrong sign (V = -T for a camera moving by T)?")
    assert res.valid.sum() == 0


# ------------------------------------------------------------------ acceptance pass 5 (video)


def test_library_refuses_fewer_than_three_frames(scene):
    cam = synthetic.paper_camera()
    with pytest.raises(ValueError, match=r"^depth_from_video needs at least 3 frames, got 0 \(an empty iterable; a video file or folder: pass read_video\(path\)\)$"):
        list(depth_from_video([], camera=cam, velocity=STEP))
    with pytest.raises(ValueError, match=r"^depth_from_video needs at least 3 frames, got 2$"):
        list(depth_from_video(scene.frames[:2], camera=cam, velocity=STEP))


def test_a_folder_of_frames_leaves_hidden_files_out(sequence_dir):
    """macOS's ._f0.png beside f0.png became frame 0 (a decode error, or every frame one off against the poses)."""
    (sequence_dir / "._f0.png").write_bytes(b"\0\5\26\7 resource fork")
    (sequence_dir / ".hidden.png").write_bytes((sequence_dir / "f0.png").read_bytes())
    names = [Path(p).name for p in read_video(sequence_dir).paths]
    assert names == [f"f{k}.png" for k in range(N_FRAMES)]


def test_poses_with_a_byte_order_mark_are_read(tmp_path):
    """Excel's "CSV UTF-8" opens with a byte-order mark: the header read '\\ufeffframe'."""
    from nfdepth.rig import load_poses

    p = tmp_path / "p.csv"
    p.write_bytes("frame,x,y,z\n0,0,0,0\n1,1,0,0\n2,2,0,0\n".encode("utf-8-sig"))
    poses = load_poses(p)
    np.testing.assert_array_equal(np.asarray(poses.positions)[:, 0], [0.0, 1.0, 2.0])


def test_video_output_folder_that_cannot_be_made_is_a_write_error(tmp_path, capsys, sequence_dir, rail_rig):
    (tmp_path / "afile").write_text("x")
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", tmp_path / "afile" / "sub", "--quiet")
    assert (code, err) == (4, f"nfdepth: error: --out '{tmp_path / 'afile' / 'sub'}': '{tmp_path / 'afile'}' is not a directory\n")
    from nfdepth.io import OutputWriteError, make_output_folder

    with pytest.raises(OutputWriteError, match=r"cannot write '.*afile.*sub': '.*afile' is not a directory"):
        make_output_folder(tmp_path / "afile" / "sub")


def test_a_truncated_video_file_is_reported(tmp_path, scene):
    """Half an MJPG AVI decodes its first frames and then stops: that was taken as the whole video, without a word."""
    frames = [scene.frames[k % N_FRAMES] for k in range(40)]
    whole = _write_avi(tmp_path / "whole.avi", frames)
    assert sum(1 for _ in read_video(whole)) == 40  # an intact file: no warning (filterwarnings = error)
    cut = tmp_path / "cut.avi"
    data = whole.read_bytes()
    cut.write_bytes(data[: len(data) // 2])
    with pytest.warns(UserWarning, match=r"video '.*cut\.avi' declares 40 frames, but only the first (\d+) could be decoded \(a truncated or damaged file\?\)"):
        n = sum(1 for _ in read_video(cut))
    assert 5 < n < 30


def test_a_dense_map_behind_the_camera_is_reported_without_edge_points():
    """A camera moving opposite to its given velocity over a band-limited texture (no edge point survives the corner
    rule): the dense maps came out half negative with no sign warning; now the run says so."""
    from nfdepth import PinholeCamera

    rng = np.random.default_rng(2)
    h, w, f, z, step = 96, 128, 300.0, 10.0, 0.5
    texture = cv2.GaussianBlur(rng.normal(size=(h, w + 8)).astype(np.float32), (0, 0), 2.0)
    texture = 128 + 40 * texture / texture.std()
    cols = np.arange(w, dtype=np.float32)
    frames = []
    for k in range(5):  # the content moves toward +col: the camera moves toward -X
        shifted = np.stack([np.interp(cols + 4 - k * step, np.arange(w + 8), row) for row in texture])
        frames.append((shifted + rng.normal(0, 1.0, shifted.shape)).astype(np.float32))
    cam = PinholeCamera(focal_px=f, width_px=w, height_px=h)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        results = list(depth_from_video(frames, camera=cam, velocity=(step * z / f, 0, 0), dense=True))
    said = [str(c.message) for c in caught]
    behind = [s for s in said if "most of the dense map lies behind the camera" in s]
    assert len(behind) == 1 and "the camera moves opposite to its given positions" in behind[0], said
    assert all(np.nanmedian(r.dense_inverse_depth) < 0 for r in results)
    # no edge point in any frame (a blob texture): said once for the run, in the video's own words (was once per frame,
    # naming max_corner_ratio, which depth_from_video does not take)
    none = [s for s in said if s.startswith("no edge points")]
    assert len(none) == 1 and none[0].startswith("no edge points: in 3 of 3 frames (1-3), e.g. frame 1: all ") and "max_corner_ratio" not in none[0], none
    (run,) = [c.message for c in caught if isinstance(c.message, NoEdgePointsWarning)]  # its category, with the first frame's rule
    assert (run.rule, run.hint, run.consequence) == ("corner", "(a texture of blobs rather than edges: the dense maps measure it)", "")


# ------------------------------------------------------------------ checked at the call, not at the first frame


def _untouched():
    """Frames that fail the test if anything reads them."""
    raise AssertionError("the frames were read before the arguments were checked")
    yield  # pragma: no cover


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"stencil": "sobel"}, r"^stencil must be one of \('matched', 'simpson', 'paper'\), got 'sobel'$"),
        ({"min_cos": 2.0}, r"^min_cos must be within \[0, 1\], got 2"),
        ({"sigma_px": -1.0}, "sigma_px"),
        ({"velocity": None}, "velocity"),
    ],
)
def test_depth_from_video_checks_its_arguments_at_the_call(kwargs, match):
    """Were checked at the first frame (a generator): a wrong stencil or min_cos only once a video had been opened and a triple read."""
    options = {"camera": synthetic.paper_camera(), "velocity": STEP, **kwargs}
    with pytest.raises((ValueError, TypeError), match=match):
        depth_from_video(_untouched(), **options)


def test_videos_library_checks_its_arguments_at_the_call():
    from nfdepth.rig import load_rig
    from nfdepth.video import dynamic_stereo_from_videos

    rig = load_rig(PAPER_RIG)
    for kwargs, error, match in [
        ({"crossings": [1]}, ValueError, "frame 1 has no two frames before it"),
        ({"crossings": [4], "shared": "left"}, ValueError, "shared must be one of"),
        ({"crossings": [4], "sigma": 2.0}, TypeError, r"^unknown option 'sigma' for dynamic stereo: expected some of sigma_px, stencil, "),
        ({"crossings": [4], "frame_interval": 2.0}, TypeError, r"^frame_interval comes from the rig \(\[motion\] frame_interval\), not from an option"),
        ({"crossings": [4], "camera": synthetic.paper_camera()}, TypeError, r"^camera comes from the rig \(\[camera\]\)"),
    ]:
        with pytest.raises(error, match=match):
            dynamic_stereo_from_videos(_untouched(), _untouched(), rig=rig, **kwargs)


def test_rig_options_that_the_rig_gives_are_named():
    """Was Python's 'got multiple values for keyword argument' from inside the library."""
    from nfdepth.rig import dynamic_stereo_from_rig, load_rig

    frames = list(synthetic.paper_dynamic_sequence(1).frames)
    with pytest.raises(TypeError, match=r"^relative_motion comes from the rig \(\[motion\]\)"):
        dynamic_stereo_from_rig(frames, load_rig(PAPER_RIG), relative_motion=None)
    with pytest.raises(TypeError, match=r"^unknown options 'sigma', 'levels' for dynamic stereo"):
        dynamic_stereo_from_rig(frames, load_rig(PAPER_RIG), sigma=2.0, levels=3)


def test_video_cli_names_the_file_of_a_bad_frame(tmp_path, capsys, sequence_dir, rail_rig):
    """Was 'frame 3 (60x50)' / 'frame 4 contains ... non-finite': which of a folder's files, the user had to count."""
    assert cv2.imwrite(str(sequence_dir / "f3.png"), np.zeros((50, 60), np.uint8))
    code, out, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", tmp_path / "o.npz")
    assert code == 2 and out == ""
    assert err.strip().endswith(f"does not match frame 3 ('{sequence_dir / 'f3.png'}', 60x50)")
    assert not (tmp_path / "o.npz").exists()
    frame = cv2.imread(str(sequence_dir / "f4.png"), cv2.IMREAD_UNCHANGED).astype(np.float32)
    frame[5, 5] = np.nan
    (sequence_dir / "f3.png").unlink()
    (sequence_dir / "f4.png").unlink()
    assert cv2.imwrite(str(sequence_dir / "f4.tif"), frame)
    code, _, err = run_cli(capsys, "video", sequence_dir, "--rig", rail_rig, "--out", tmp_path / "o.npz")
    assert code == 2
    assert err == f"nfdepth: error: frame 3 ('{sequence_dir / 'f4.tif'}') contains 1 non-finite (NaN or inf) pixel(s); expected finite intensities\n"


def test_crossings_refusals_name_the_argument():
    """Were a bare 'a non-empty list of frame indices ...' TypeError from the library."""
    from nfdepth.rig import check_crossings
    from nfdepth.video import dynamic_stereo_from_videos, interleaved_frames

    with pytest.raises(TypeError, match=r"^crossings = \[4\.5\]: expected a non-empty list of frame indices \(integers >= 2\), strictly increasing$"):
        dynamic_stereo_from_videos([], [], rig=load_rig(PAPER_RIG), crossings=[4.5])
    with pytest.raises(TypeError, match=r"^crossings = '4': expected a non-empty list"):
        dynamic_stereo_from_videos([], [], rig=load_rig(PAPER_RIG), crossings="4")
    with pytest.raises(ValueError, match=r"^a non-empty list of frame indices \(integers >= 2\), strictly increasing$"):
        check_crossings([5, 5])  # bare, for a caller that names the value (rig file, --crossings)
    with pytest.raises(ValueError, match=r"^crossing must be an integer >= 2, got 1$"):
        interleaved_frames([np.zeros((4, 4))] * 9, [np.zeros((4, 4))] * 9, 1)


def test_a_video_file_whose_name_has_brackets_is_read_as_itself(tmp_path, scene):
    """'clip[1].avi' was taken as a glob: refused (no file matched), or 'clip1.avi', another video, read without a word."""
    named = _write_avi(tmp_path / "clip[1].avi", scene.frames[:4])
    _write_avi(tmp_path / "clip1.avi", scene.frames[4:6])  # what the pattern matches
    source = read_video(named)
    assert source.video == named and source.paths is None
    got = list(source)
    assert len(got) == 4 and np.median(np.abs(got[1] - scene.frames[1])) < 3  # its own frames
    assert read_video(str(tmp_path / "clip[1-9].avi")).paths == [tmp_path / "clip1.avi"]  # no file of that name: a pattern, as before


def _one_buffer(frames):
    """``frames`` handed over in one reused buffer, as ``cv2.VideoCapture.read(buf)`` does."""
    buf = np.empty_like(np.asarray(frames[0], np.float32))
    for f in frames:
        buf[...] = f
        yield buf


def test_a_reader_that_reuses_one_buffer_gives_the_same_depths(scene, pair):
    """The windows kept the caller's float32 arrays: with one reused buffer every frame of a triple was the newest one,
    no depth at all and a warning that the edge points lay behind the camera."""
    from nfdepth.video import dynamic_stereo_from_videos

    frames = [np.asarray(f, np.float32) for f in scene.frames[:6]]
    fresh = list(depth_from_video(frames, camera=scene.camera, velocity=STEP))
    reused = list(depth_from_video(_one_buffer(frames), camera=scene.camera, velocity=STEP))
    assert [r.index for r in reused] == [r.index for r in fresh] == [1, 2, 3, 4]
    for a, b in zip(fresh, reused):
        assert np.isfinite(a.inverse_depth).sum() > 300
        np.testing.assert_array_equal(b.inverse_depth, a.inverse_depth)
        np.testing.assert_array_equal(b.measured_inverse_depth_std, a.measured_inverse_depth_std)
    moving, reference = ([np.asarray(f, np.float32) for f in video[:9]] for video in pair[:2])
    truth = pair[2]
    want = next(dynamic_stereo_from_videos(moving, reference, rig=load_rig(PAPER_RIG), crossings=[4]))
    got = next(dynamic_stereo_from_videos(_one_buffer(moving), _one_buffer(reference), rig=load_rig(PAPER_RIG), crossings=[4]))
    assert want.valid.sum() > 500 and np.median(_rel_errors(truth, got)) < 0.005
    np.testing.assert_array_equal(got.depth, want.depth)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"velocity": "abc"}, r"^velocity must be numbers \(the camera translation per frame, x y z\), got 'abc' \(dtype <U3\)$"),
        ({"velocity": {1, 2, 3}}, r"^velocity must be numbers \(.*\), got \{1, 2, 3\} \(dtype object\)$"),
        ({"velocity": [[1, 0], [0]]}, r"^velocity must be numbers \(.*\), got \[\[1, 0\], \[0\]\] \(rows of unequal length\)$"),
        ({"velocity": [1j, 0, 0]}, r"^velocity must be numbers \(.*\), got \[1j, 0, 0\] \(dtype complex128\)$"),
        ({"positions": [["a", "b", "c"]] * 3}, r"^positions must be numbers \(the camera's optical centre at every frame, shape \(N, 3\)\), got .* \(dtype <U1\)$"),
        ({"positions": [[0, 0, 0], [1, 0], [2, 0, 0]]}, r"^positions must be numbers \(.*\), got .* \(rows of unequal length\)$"),
        ({"positions": np.arange(9).reshape(3, 3) * 1j}, r"^positions must be numbers \(.*\), got an array \(dtype complex128\)$"),
        ({"positions": [[None] * 3] * 3}, r"^positions must be numbers \(.*\), got .* \(dtype object\)$"),
    ],
)
def test_motion_that_is_no_numbers_is_named(kwargs, match):
    """Were NumPy's own 'could not convert string to float', 'inhomogeneous shape', 'float() argument ... not set', or a
    ComplexWarning and then 'the camera does not move' (the imaginary positions dropped)."""
    with pytest.raises(TypeError, match=match):
        depth_from_video(_untouched(), camera=synthetic.paper_camera(), **kwargs)


def test_videos_library_refuses_a_frame_that_is_no_image(pair):
    """Was 'IndexError: tuple index out of range' from the size check; a frame of another size keeps its message."""
    from nfdepth.video import dynamic_stereo_from_videos

    moving, reference, _ = pair
    rig = load_rig(PAPER_RIG)
    for bad, error, match in [
        (None, TypeError, r"^moving frame 0 must be a numeric 2-D array, got dtype object$"),
        ("abc", TypeError, r"^moving frame 0 must be a numeric 2-D array, got dtype <U3$"),
        (np.float32(3.0), ValueError, r"^moving frame 0 must be a 2-D grey image \(rows, cols\), got shape \(\)$"),
        (np.zeros(200), ValueError, r"^moving frame 0 must be a 2-D grey image \(rows, cols\), got shape \(200,\)$"),
        (np.zeros((100, 120)), RigError, r"^camera\.width_px x camera\.height_px = 200x200 \(paper_pyramid_rig\.toml\) does not match moving frame 0 \(120x100\)$"),
    ]:
        with pytest.raises(error, match=match):
            list(dynamic_stereo_from_videos([bad] * 9, reference[:9], rig=rig, crossings=[4]))
    with pytest.raises(TypeError, match=r"^reference frame 2 must be a numeric 2-D array, got dtype object$"):
        list(dynamic_stereo_from_videos(moving[:9], reference[:2] + [None] * 7, rig=rig, crossings=[4]))


def _write_ffv1_grey(path, frames, depth):
    """``frames`` (uint8 or uint16) as a lossless grey FFV1 video; skips where this OpenCV build cannot write one."""
    params = [cv2.VIDEOWRITER_PROP_DEPTH, depth, cv2.VIDEOWRITER_PROP_IS_COLOR, 0]
    h, w = frames[0].shape
    writer = cv2.VideoWriter(str(path), cv2.CAP_FFMPEG, cv2.VideoWriter_fourcc(*"FFV1"), 10, (w, h), params)
    if not writer.isOpened():
        pytest.skip("no FFV1 grey writer in this OpenCV build")
    for f in frames:
        writer.write(f)
    writer.release()
    if not path.is_file() or path.stat().st_size == 0:
        pytest.skip("this OpenCV build wrote no FFV1 grey video")
    return path


def test_a_16_bit_grey_video_keeps_its_values(tmp_path, scene):
    """A lossless 16-bit grey FFV1 video came through OpenCV's 8-bit BGR: its first frame's maximum 202 instead of
    the stored 51786 (49 grey levels of 5216). Its frames are now its values, as a 16-bit PNG's; 8-bit videos as before."""
    stored = [np.round(np.asarray(f) * 200).astype(np.uint16) for f in scene.frames[:3]]  # 255 + noise fits in 16 bits
    deep = _write_ffv1_grey(tmp_path / "g16.mkv", stored, cv2.CV_16U)
    got = list(read_video(deep))
    assert len(got) == 3 and all(g.dtype == np.float32 and g.shape == (200, 200) for g in got)
    for g, s in zip(got, stored):
        assert s.max() > 40000
        np.testing.assert_array_equal(g, s.astype(np.float32))
    # the same frames through the 16-bit PNGs of a folder: the same values
    folder = tmp_path / "png"
    folder.mkdir()
    for k, s in enumerate(stored):
        assert cv2.imwrite(str(folder / f"f{k}.png"), s)
    for g, p in zip(got, read_video(folder)):
        np.testing.assert_array_equal(g, p)
    shallow = [np.clip(np.round(np.asarray(f)), 0, 255).astype(np.uint8) for f in scene.frames[:3]]
    for g, s in zip(read_video(_write_ffv1_grey(tmp_path / "g8.mkv", shallow, cv2.CV_8U)), shallow):
        np.testing.assert_allclose(g, s, atol=1e-3)  # lossless 8 bits (through OpenCV's BGR and BT.601 luma), no warning


@pytest.mark.parametrize(
    ("tag", "bits"),
    [
        (b"Y1\x00\x10", 16), (b"\x10\x001Y", 16), (b"Y1\x00\x0a", 10), (b"Y3\x0b\x0a", 10), (b"\x0c\x0a3Y", 12), (b"G3\x00\x0c", 12),
        (b"Y4\x00\x10", 16), (b"RGB0", 16), (b"0BGR", 16), (b"RBA@", 16), (b"@BRA", 16),
        (b"I420", 8), (b"Y800", 8), (b"BGRA", 8), (b"RGB\x18", 8), (b"BGR\x00", 8), (b"\x00RGB", 8), (b"Y41B", 8), (b"Y4\x0b\x08", 8),
    ],
)
def test_the_bits_of_a_decoded_pixel_format(tag, bits):
    """FFmpeg's tags of its raw pixel formats (libavcodec/raw.c; ``'0'`` is 48, ``'@'`` 64): those deeper than 8 bits,
    which OpenCV would read at 8 bits, are warned of (gray16le is read as it is)."""
    from nfdepth.video import _stored_bits

    assert _stored_bits(int.from_bytes(tag, "little")) == bits
