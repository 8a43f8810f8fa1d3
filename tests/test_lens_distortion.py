"""A rig's lens distortion (``[camera] distortion``): undone in every image before dynamic stereo, video and static rows."""

import numpy as np
import pytest
from scipy import ndimage

from nfdepth import synthetic
from nfdepth.rectify import CalibratedCamera
from nfdepth.rig import RigError, rig_from_dict, rig_to_toml, tomllib
from nfdepth.video import depth_from_video

DISTORTION = (-0.1, 0.02, 0.0005, -0.0005)  # barrel: 8 px in at the middle of an edge of the paper's 200 x 200 view
STEP = (1.0, 0.0, 0.0)


def _rig(distortion=DISTORTION, sections="[video]\nvelocity = [1.0, 0.0, 0.0]\n"):
    text = "[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n"
    if distortion:
        text += "distortion = [" + ", ".join(repr(v) for v in distortion) + "]\n"
    return rig_from_dict(tomllib.loads(text + sections))


def _distort(frame, rig):
    """What a camera with the rig's distortion sees where the ideal pinhole camera sees ``frame`` (cubic spline)."""
    cam = rig.camera
    k = np.array([[cam.focal_px, 0.0, cam.cx_px], [0.0, cam.focal_px, cam.cy_px], [0.0, 0.0, 1.0]])
    lens = CalibratedCamera(matrix=k, width_px=cam.width_px, height_px=cam.height_px, position=np.zeros(3), rotation=np.eye(3), distortion=np.array(rig.distortion))
    xy = lens.rays()
    return ndimage.map_coordinates(np.asarray(frame, np.float32), [cam.cy_px + cam.focal_px * xy[..., 1], cam.cx_px + cam.focal_px * xy[..., 0]], order=3, mode="nearest")


def test_rig_distortion_is_read_written_and_checked():
    rig = _rig()
    assert rig.distortion == DISTORTION
    assert rig_from_dict(tomllib.loads(rig_to_toml(rig))) == rig
    assert rig != _rig(distortion=())
    with pytest.raises(RigError, match=r"camera.distortion = \[0.1\]: expected 4, 5 or 8 finite numbers"):
        _rig(distortion=(0.1,))
    plain = _rig(distortion=())
    frame = np.arange(200 * 200, dtype=np.float32).reshape(200, 200)
    assert np.array_equal(plain.undistort(frame), frame)
    with pytest.raises(RigError, match="does not match the image"):
        rig.undistort(np.zeros((10, 10)))
    # colour: told as without distortion (it was OpenCV's "invalid shape for coordinate array")
    colour = np.zeros((200, 200, 3), np.float32)
    with pytest.raises(ValueError, match=r"^image must be a 2-D grey image \(rows, cols\), got shape \(200, 200, 3\); convert colour"):
        rig.undistort(colour)
    from nfdepth.rig import dynamic_stereo_from_rig

    motion = "[motion]\nvelocity = [1.0, 0.0, 0.0]\n"
    for r in (_rig(sections=motion), _rig(distortion=(), sections=motion)):
        with pytest.raises(ValueError, match=r"^frames\[0\] must be a 2-D grey image \(rows, cols\), got shape \(200, 200, 3\); convert colour"):
            dynamic_stereo_from_rig([colour] * 5, r)


def test_undistort_recovers_the_pinhole_view():
    """A distorted view of the textured plane, undone: the pinhole camera's view within 0.3 grey levels (median)."""
    rig = _rig()
    cam = rig.camera
    k = np.array([[100.0, 0.0, cam.cx_px], [0.0, 100.0, cam.cy_px], [0.0, 0.0, 1.0]])

    def view(dist):
        c = CalibratedCamera(matrix=k, width_px=200, height_px=200, position=np.zeros(3), rotation=np.eye(3), distortion=np.array(dist))
        return synthetic.calibrated_plane_row([c], depth=2.0, slope=0.0, noise_std=0.0, reference_index=0).views[0]

    ideal, distorted = view(()), view(DISTORTION)
    inner = (slice(20, -20), slice(20, -20))
    assert np.median(np.abs(distorted - ideal)[inner]) > 3.0
    assert np.median(np.abs(rig.undistort(distorted) - ideal)[inner]) < 0.3


def test_video_with_lens_distortion():
    """The rail camera over the pyramid through a barrel lens: with the rig's distortion undone the last fused
    frame's median depth error is about the pinhole video's (measured 0.80 against 0.69 %, 699 points each); taken
    as a pinhole camera the distorted frames give 6.5 %."""
    rig = _rig()
    scene = synthetic.static_sequence(synthetic.paper_pyramid(), synthetic.paper_camera(), n_views=6, camera_step=STEP, reference_index=0, noise_std=1.0, rng=np.random.default_rng(1))
    distorted = [_distort(f, rig) for f in scene.frames]

    def last_error(frames, r):
        res = list(depth_from_video(frames, rig=r))[-1]
        m = res.measured & np.isfinite(res.depth)
        ii, jj = np.nonzero(m)
        z = synthetic.surface_depth_at(scene.polyhedron, scene.camera, ii + 0.5, jj + 0.5, camera_motion=synthetic.CameraMotion(velocity_per_t=STEP), time=float(res.index))
        return np.median(np.abs(res.depth[m] - z) / z), m.sum()

    pinhole, n0 = last_error(list(scene.frames), _rig(distortion=()))
    undone, n1 = last_error(distorted, rig)
    ignored, _ = last_error(distorted, _rig(distortion=()))
    assert n1 > 0.8 * n0
    assert undone < 1.5 * pinhole + 0.002
    assert ignored > 3 * undone


def test_dynamic_stereo_with_lens_distortion():
    """Experiment 1's five images through the barrel lens: with the distortion undone, the pinhole images'
    median depth error (measured 0.27 against 0.29 %); ignored, 5.6 %."""
    from nfdepth.rig import dynamic_stereo_from_rig

    scene = synthetic.paper_dynamic_sequence(1)
    v = -np.asarray(scene.relative_motion.translation, float)  # the rig gives the camera's motion, the negative of the scene's
    w = -np.degrees(np.asarray(scene.relative_motion.rotation, float))
    motion = f"[motion]\nvelocity = [{', '.join(repr(float(x)) for x in v)}]\nrotation_deg = [{', '.join(repr(float(x)) for x in w)}]\n"
    rig, plain = _rig(sections=motion), _rig(distortion=(), sections=motion)
    distorted = [_distort(f, rig) for f in scene.frames]

    def median_error(frames, r):
        res = dynamic_stereo_from_rig(frames, r)
        ok = res.valid
        z = np.asarray(scene.depth_at(res.rows[ok], res.cols[ok]), float)
        return np.median(np.abs(res.depth[ok] - z) / z)

    pinhole = median_error(list(scene.frames), plain)
    undone = median_error(distorted, rig)
    assert undone < 1.5 * pinhole + 0.002
    assert median_error(distorted, plain) > 3 * undone


def test_stereo_command_undoes_the_rigs_distortion(tmp_path, capfd):
    """``nfdepth stereo --rig`` on the paper's static row through the barrel lens: the edge points' median depth
    error with the distortion in the rig file about the pinhole row's (measured 0.41 % at 597 points against 0.32 %
    at 314: the resampled views are less sharp, which keeps more of the silhouette), without it 2.0 %."""
    from cli_runner import run_cli

    from nfdepth.io import read_image, write_array

    scene = synthetic.paper_static_sequence()
    rig = _rig(sections="[stereo]\nbaseline = 2.0\n")
    names = []
    for k, f in enumerate(scene.frames):
        names.append(tmp_path / f"v{k}.tif")
        write_array(names[-1], _distort(f, rig))
    pinhole_names = []
    for k, f in enumerate(scene.frames):
        pinhole_names.append(tmp_path / f"p{k}.tif")
        write_array(pinhole_names[-1], np.asarray(f, np.float32))
    errors = {}
    for label, views, dist in (("pinhole", pinhole_names, ()), ("undone", names, DISTORTION), ("ignored", names, ())):
        rig_file = tmp_path / f"{label}.toml"
        rig_file.write_text(rig_to_toml(_rig(distortion=dist, sections="[stereo]\nbaseline = 2.0\n")))
        out = tmp_path / f"{label}.tif"
        code, _, err = run_cli(capfd, "stereo", *views, "--rig", rig_file, "--edges-only", "--out", out, "--ply", tmp_path / f"{label}.ply")
        assert code == 0, err
        depth = read_image(out)
        ok = np.isfinite(depth)
        rows, cols = np.nonzero(ok)
        z = np.asarray(scene.depth_at(rows, cols), float)
        errors[label] = np.median(np.abs(depth[ok] - z) / z)
    assert errors["undone"] < 1.5 * errors["pinhole"] + 0.002
    assert errors["ignored"] > 3 * errors["undone"]
