"""``nfdepth video``: a camera translating past the pyramid, fused over time."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

import nfdepth.cli
from nfdepth import synthetic
from nfdepth.cli import main
from nfdepth.rig import RigError, load_rig
from nfdepth.video import depth_from_video, read_video

STEP = (1.0, 0.0, 0.0)  # camera translation per frame: 0.25-0.5 px of disparity
N_FRAMES = 9


@pytest.fixture(autouse=True)
def plugin(monkeypatch):
    monkeypatch.setattr(nfdepth.cli, "_PLUGIN_COMMANDS", ("_cli_rig",))


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


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


def test_rotating_poses_rejected(tmp_path, scene):
    (tmp_path / "p.csv").write_text("frame,x,y,z,rx,ry,rz\n0,0,0,0,0,0,0\n1,1,0,0,0,0,0\n2,2,0,0,0,0,5\n")
    (tmp_path / "r.toml").write_text('[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[video]\nposes = "p.csv"\n')
    with pytest.raises(RigError, match="translates without rotating"):
        list(depth_from_video(list(scene.frames[:3]), rig=load_rig(tmp_path / "r.toml")))


def test_library_argument_errors(scene):
    with pytest.raises(TypeError, match="exactly one of rig, velocity, positions"):
        next(depth_from_video(scene.frames, camera=scene.camera))
    with pytest.raises(ValueError, match="exactly one of"):
        next(depth_from_video(scene.frames, camera=scene.camera, velocity=STEP, positions=np.zeros((9, 3))))
    with pytest.raises(ValueError, match="not all zero"):
        next(depth_from_video(scene.frames, camera=scene.camera, velocity=(0, 0, 0)))


def test_read_video_sources(tmp_path, sequence_dir, scene):
    frames = list(read_video(sequence_dir))
    assert len(frames) == N_FRAMES and frames[0].dtype == np.float32
    np.testing.assert_allclose(frames[2] / 200, scene.frames[2], atol=0.01)
    assert len(read_video(str(sequence_dir / "f*.png"))) == N_FRAMES
    avi = tmp_path / "v.avi"
    writer = cv2.VideoWriter(str(avi), cv2.VideoWriter_fourcc(*"MJPG"), 10, (200, 200), True)
    if not writer.isOpened():
        pytest.skip("no MJPG writer in this OpenCV build")
    for f in scene.frames[:4]:
        writer.write(cv2.cvtColor(np.clip(f, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR))
    writer.release()
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
