"""Video depth for image motions beyond the differential method's 1-2 px per frame (``levels``, coarse to fine)."""

from __future__ import annotations

import re
import warnings

import cv2
import numpy as np
import pytest

import nfdepth.cli
from nfdepth import synthetic
from nfdepth._translating_pyramid import (
    _motion_limit,
    dense_prior,
    flow_directions,
    outer_flow_directions,
    warp_outer_frames,
)
from nfdepth.camera import PinholeCamera, RigidMotion, image_flow_px
from nfdepth.cli import main
from nfdepth.pipelines import static_stereo_edges
from nfdepth.video import _outer_steps, depth_from_video


def _sequence(step, n_views=3):
    return synthetic.static_sequence(
        synthetic.paper_pyramid(), synthetic.paper_camera(), n_views=n_views, camera_step=step, reference_index=1, noise_std=1.0, rng=np.random.default_rng(1)
    )


def _relative_errors(scene, frame, step, rho):
    """|Z - Z_true| / Z_true where ``rho`` (a map of ``frame``) is finite; map pixel [i, j] is the cell centre (i + 0.5, j + 0.5)."""
    ii, jj = np.nonzero(np.isfinite(rho))
    motion = synthetic.CameraMotion(velocity_per_t=step)
    z = synthetic.surface_depth_at(scene.polyhedron, scene.camera, ii + 0.5, jj + 0.5, camera_motion=motion, time=float(frame - 1))
    return np.abs(1.0 / rho[ii, jj] - z) / z


def _measured(scene, step, **options):
    (res,) = depth_from_video(list(scene.frames), camera=scene.camera, velocity=step, **options)
    return res


@pytest.mark.parametrize(
    ("step", "motion_px"),
    [((32.0, 0.0, 0.0), 10.5), ((0.0, 24.0, 0.0), 7.9), ((8.0, 0.0, 32.0), 2.0)],
    ids=["lateral-10px", "vertical-8px", "forward"],
)
def test_large_motions_are_measured_coarse_to_fine(step, motion_px):
    """Lateral, vertical and forward steps of several px per frame: the paper's single level fails, the pyramid does not.

    The median lateral motion of the edge points is ``motion_px`` (2 px for
    the forward step, whose radial part adds up to several px at the image
    corners). Measured (noise 1 grey level, as in test_video): median
    relative error 0.07-0.12 %, p90 0.5-0.9 % with the pyramid (forward, warped
    to first order without the depth change: 0.45 %, p90 1.3 %), against
    35-94 % on one level; the bounds leave a factor of 3 or more.
    """
    scene = _sequence(step)
    res = _measured(scene, step)
    err = _relative_errors(scene, res.index, step, res.measured_inverse_depth)
    assert err.size > 500
    assert np.median(err) < 0.015
    assert np.percentile(err, 90) < 0.05
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        single = _relative_errors(scene, res.index, step, _measured(scene, step, levels=1).measured_inverse_depth)
    assert np.median(single) > 0.1  # why the pyramid is the default
    # and the single level says so (the forward step's edge points move a median of 3.8 px, its radial part included)
    said = [str(w.message) for w in caught if "beyond the differential method's range" in str(w.message)]
    assert len(said) == 1, said
    assert said[0].startswith("in 1 of 1 frames (1) the edge points move a median of up to ") and "leave levels (--levels) at its default" in said[0]
    # the motion really is that large: f |T_lateral| / Z at the points (the forward step adds its radial part)
    rows, cols = np.nonzero(np.isfinite(res.measured_inverse_depth))
    z = synthetic.surface_depth_at(scene.polyhedron, scene.camera, rows + 0.5, cols + 0.5)
    lateral = np.median(scene.camera.focal_px * np.hypot(step[0], step[1]) / z)
    assert lateral > 0.9 * motion_px or step[2] > 0


def test_small_motions_stay_accurate():
    """0.33 px per frame: the pyramid keeps (here improves) the single level's accuracy (median 1.7 against 2.7 %, same points)."""
    step = (1.0, 0.0, 0.0)
    scene = _sequence(step)
    pyramid = _relative_errors(scene, 1, step, _measured(scene, step).measured_inverse_depth)
    single = _relative_errors(scene, 1, step, _measured(scene, step, levels=1).measured_inverse_depth)
    assert np.median(pyramid) <= 1.1 * np.median(single)
    assert pyramid.size >= 0.98 * single.size


def test_one_level_is_the_papers_measurement():
    """``levels=1``: the measured inverse depths are exactly those of static_stereo_edges on the triple (no prior, no warp).
    The step moves the edge points 2.6 px per frame (a quarter of the 10.5 px of 32 units), just beyond the single
    level's range, and it says so (it did not: its own flow read the motion as within it)."""
    step = (8.0, 0.0, 0.0)
    scene = _sequence(step)
    with pytest.warns(UserWarning, match=r"the edge points move a median of up to 2\.\d px per frame"):
        res = _measured(scene, step, levels=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        edges = static_stereo_edges(list(scene.frames), camera=scene.camera, baseline=8.0, direction=step, sigma_px=2.0)
    ok = edges.valid
    ii, jj = np.floor(edges.rows[ok]).astype(int), np.floor(edges.cols[ok]).astype(int)
    expected = np.full(res.measured_inverse_depth.shape, np.nan, np.float32)
    expected[ii, jj] = edges.inverse_depth.rho[ok]
    np.testing.assert_array_equal(res.measured_inverse_depth, expected)


def _uneven(positions_x, direction=(1.0, 0.0, 0.0)):
    """Frames of the paper's pyramid from cameras at ``x * direction``, noise 1 grey level, and their positions."""
    rng = np.random.default_rng(1)
    positions = np.outer(positions_x, direction)
    frames = [
        synthetic.render(
            synthetic.paper_pyramid(), synthetic.paper_camera(), camera_motion=synthetic.CameraMotion(position=p), noise_std=1.0, rng=rng
        ).image
        for p in positions
    ]
    return frames, positions


def _errors_at_the_middle(frames, positions, *, signed=False, **options):
    """Relative depth errors at the middle frame's edge points (the middle camera at the origin)."""
    (res,) = depth_from_video(frames, camera=synthetic.paper_camera(), positions=positions, **options)
    rows, cols = np.nonzero(np.isfinite(res.measured_inverse_depth))
    z = synthetic.surface_depth_at(synthetic.paper_pyramid(), synthetic.paper_camera(), rows + 0.5, cols + 0.5)
    error = (1.0 / res.measured_inverse_depth[rows, cols] - z) / z
    return error if signed else np.abs(error)


@pytest.mark.parametrize("before", [0.5, 0.7], ids=["steps-1:3", "steps-7:13"])
def test_unequal_steps_are_warped_each_by_its_own(before):
    """A camera that speeds up (or drops a frame): steps of ``before`` and ``2 - before`` times 32 units, 5-16 px.

    Each outer frame is warped by its own step. Measured: median relative
    error 0.07 % at 550 points for either, as with equal steps (0.08 %);
    warped by the central step +/-T instead, 2.3 % (1:3) and 1.5 % (7:13).
    """
    x = np.array([-before, 0.0, 2.0 - before]) * 32.0
    frames, positions = _uneven(x)
    err = _errors_at_the_middle(frames, positions)
    assert err.size > 400
    assert np.median(err) < 0.004


@pytest.mark.parametrize("before", [0.35, 0.7], ids=["steps-1:2", "steps-2:1"])
def test_unequal_steps_along_the_optical_axis_are_unbiased(before):
    """A path along (1, 0, 1), steps of 5.6 and 11.2 units (Z = 200-400): each outer frame is warped with the
    depth change of its own finite step, ``rho a_j / (1 - rho t_jz)``. Measured: median signed error -0.01 to
    +0.00 % (equal steps +0.01 %); with the first-order warp ``rho a_j`` -1.71 % and +1.55 %."""
    x = np.array([-before, 0.0, 1.05 - before]) * 16.0
    err = _errors_at_the_middle(*_uneven(x, (1.0, 0.0, 1.0)), signed=True)
    assert err.size > 800
    assert abs(np.median(err)) < 0.005


def test_a_camera_reversing_within_its_triple_keeps_few_wrong_points():
    """Frames at -32, 0, -16 units (10.5 and 5 px; the central step is 8): the residual bound counts the motion
    in the farther outer frame, four times the central step's. With two levels, whose prior fails at some
    points, measured: 8 % of the kept points more than 10 % off, median 0.43 % (counted per central step:
    27 %, median 0.97 %); default levels 0 %, 0.30 %."""
    frames, positions = _uneven(np.array([-32.0, 0.0, -16.0]))
    two = _errors_at_the_middle(frames, positions, levels=2)
    assert two.size > 200 and np.mean(two > 0.1) < 0.15
    default = _errors_at_the_middle(frames, positions)
    assert default.size > 500 and np.median(default) < 0.01 and np.mean(default > 0.1) < 0.01


@pytest.mark.parametrize(("step", "motion_px"), [((32.0, 0.0, 0.0), 10.5), ((0.0, 24.0, 0.0), 7.9), ((3.0, 0.0, 0.0), 1.0)])
def test_the_coarse_motion_is_the_true_one(step, motion_px):
    """The single level's motion check: the pyramid's prior on the frames reduced to a quarter gives the edge points'
    median motion (10.5 / 7.9 / 1.0 px per frame at the measured points) within 20 %, where the single level's own
    aliased flow reads a fast motion as slow. Measured: 9.2 / 6.9 / 0.92 px (the reduced prior blurs the object's
    contour into the background, so it reads 12-13 % low there)."""
    from nfdepth._translating_pyramid import coarse_motion_px
    from nfdepth.edges import select_edge_points
    from nfdepth.normal_flow import gaussian_smooth, normal_flow

    scene = _sequence(step)
    frames = [np.asarray(f, np.float32) for f in scene.frames]
    mask = select_edge_points(normal_flow(frames, sigma_px=2.0), gaussian_smooth(frames[1], sigma_px=2.0)).mask
    got = coarse_motion_px(frames, scene.camera, -np.asarray(step), mask)
    assert got == pytest.approx(motion_px, rel=0.2)


@pytest.mark.data
def test_the_single_level_says_when_a_real_row_moves_too_fast():
    """Tsukuba as a video (5 px per frame): its single level's aliased flow read the motion as within range, and no
    warning came, at 88.6 % bad-1px; the prior's motion names 5.0 px. The pyramid (default) stays quiet."""
    from nfdepth import datasets

    try:
        scene = datasets.load_scene("tsukuba")
    except datasets.DataNotFoundError:
        pytest.skip("real data not found: set NFDEPTH_DATA or put it at ../shared/data")
    frames = [np.asarray(v, np.float32) for v in scene.views]
    cam = PinholeCamera(615.0, scene.shape[1], scene.shape[0])
    for levels, warns in ((1, True), (None, False)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            list(depth_from_video(frames, camera=cam, velocity=(0.1, 0.0, 0.0), levels=levels))
        said = [str(w.message) for w in caught if "beyond the differential method's range" in str(w.message)]
        assert bool(said) == warns, said
        if warns:
            assert re.search(r"move a median of up to [4-6]\.\d px per frame", said[0]), said[0]


def test_equal_steps_keep_the_central_warp():
    """Outer steps of exactly -/+T give exactly the central field's -a and a; positions equal to rounding count as equal steps."""
    cam = PinholeCamera(100.0, 40, 30)
    v = np.array([-0.3, 0.1, 0.05])  # V = -T
    central = flow_directions(cam, v, (30, 40))
    given = outer_flow_directions(cam, v, (v, -v), central)  # t_k-1 = -T = V, t_k+1 = T = -V
    equal = outer_flow_directions(cam, v, None, central)
    for (a, b, kz), (c, d, kz_equal) in zip(given, equal):
        np.testing.assert_array_equal(a, c)
        np.testing.assert_array_equal(b, d)
        assert kz == kz_equal
    np.testing.assert_array_equal(equal[1][0], central[0])
    np.testing.assert_array_equal(equal[0][1], -central[1])
    # k_z = t_jz / (f |V|): t_k+1 = -V
    assert equal[1][2] == pytest.approx(-0.05 / (100.0 * np.linalg.norm(v)))
    # an outer frame taken where the middle one was does not move
    paused = outer_flow_directions(cam, v, (np.zeros(3), -2.0 * v), central)
    assert not np.any(paused[0][0]) and not np.any(paused[0][1]) and paused[0][2] == 0.0
    np.testing.assert_allclose(paused[1][0], 2.0 * central[0], rtol=1e-6)
    # positions 0.1, 0.2, 0.3: steps of 0.1 to float64 rounding
    step = np.array([0.1, 0.0, 0.0])
    assert _outer_steps(np.eye(3), [(0.1, 0, 0), (0.2, 0, 0), (0.3, 0, 0)], step) is None
    before, after = _outer_steps(np.eye(3), [(0.0, 0, 0), (0.1, 0, 0), (0.3, 0, 0)], 1.5 * step)
    np.testing.assert_allclose(before, -step)
    np.testing.assert_allclose(after, 2.0 * step)


def test_warp_reads_each_outer_frame_at_its_own_motion():
    """The outer frames are read at ``x + rho a_j`` (bilinear, border replicated) and ``inside`` says where both reads fall
    inside; without it, the same frames. The update's bound is 1 px of the fastest frame's motion: with equal steps the
    central field's length, bit for bit."""
    cam = PinholeCamera(100.0, 40, 30)
    v = np.array([-0.3, 0.1, 0.05])
    central = flow_directions(cam, v, (30, 40))
    rng = np.random.default_rng(3)
    frames = [rng.random((30, 40), dtype=np.float32) for _ in range(3)]
    rho = rng.uniform(0.0, 4.0, (30, 40)).astype(np.float32)
    for steps in (None, (v, -2.0 * v)):
        directions = outer_flow_directions(cam, v, steps, central)
        before, after, inside = warp_outer_frames(frames, rho, directions)
        rows, cols = np.mgrid[0:30, 0:40].astype(np.float32)
        both = np.ones((30, 40), bool)
        for got, frame, (a_col, a_row, k_z) in zip((before, after), (frames[0], frames[2]), directions):
            moved = rho / np.maximum(np.float32(1.0) - rho * np.float32(k_z), np.float32(0.05))
            map_c, map_r = cols + moved * a_col, rows + moved * a_row
            want = cv2.remap(frame, map_c, map_r, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            np.testing.assert_array_equal(got, want)
            both &= (map_c >= 0) & (map_c <= 39) & (map_r >= 0) & (map_r <= 29)
        np.testing.assert_array_equal(inside, both)
        assert 0 < both.mean() < 1
        b2, a2, none = warp_outer_frames(frames, rho, directions, inside=False)
        assert none is None and np.array_equal(b2, before) and np.array_equal(a2, after)
        fastest = np.maximum(np.hypot(*directions[0][:2]), np.hypot(*directions[1][:2]))
        want_limit = 1.0 / np.maximum(np.maximum(np.hypot(*central), fastest), np.float32(1e-12))
        np.testing.assert_array_equal(_motion_limit(*central, directions, steps is None), want_limit.astype(np.float32))


def test_one_level_warns_of_unequal_steps():
    """``levels=1`` takes the frames as equally spaced: steps of 2 and 6 units (0.65 and 1.95 px) give a median error of 4 %
    (0.5 % with equal steps), and a warning that names the frame; the pyramid, warping each frame by its own step, 0.5 %."""
    x = np.array([-2.0, 0.0, 6.0])
    frames, positions = _uneven(x)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        single = _errors_at_the_middle(frames, positions, levels=1)
    said = [str(w.message) for w in caught if "the steps before and after" in str(w.message)]
    assert len(said) == 1, [str(w.message) for w in caught]
    assert said[0].startswith("in 1 of 1 frames (1) the steps before and after the frame differ") and "--levels" in said[0]
    assert np.median(single) > 0.02
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # neither the pyramid nor equal steps warn
        pyramid = _errors_at_the_middle(frames, positions)
        _errors_at_the_middle(*_uneven(np.array([-4.0, 0.0, 4.0])), levels=1)
    assert np.median(pyramid) < 0.01


def test_dense_prior_follows_a_fronto_parallel_plane():
    """A textured plane at depth 50 moving 10 px per frame: the dense prior is 10 px (``rho f |V|``) to 0.05 px inside the frame."""
    rng = np.random.default_rng(3)
    h, w = 96, 128
    texture = cv2.GaussianBlur(rng.normal(128.0, 40.0, (h, w + 40)).astype(np.float32), (0, 0), 1.5)
    frames = [texture[:, 20 + 10 * k : 20 + 10 * k + w] for k in (-1, 0, 1)]  # the camera moves +x: the scene shifts toward -col
    cam = PinholeCamera(500.0, w, h)
    prior = dense_prior(frames, cam, (-1.0, 0.0, 0.0), levels=4)
    inner = prior[16:-16, 24:-24]
    assert np.max(np.abs(inner - 10.0)) < 0.05, np.percentile(np.abs(inner - 10.0), [50, 99, 100])


def test_flow_directions_are_eq1_per_unit_motion():
    """``a(x) / (f |V|)`` against :func:`nfdepth.camera.image_flow_px` at unit inverse depth, any units."""
    cam = PinholeCamera(1e20, 40, 30, cx_px=17.0, cy_px=11.0)
    v = np.array([3e-20, -1e-20, 2e-20])
    a_col, a_row = flow_directions(cam, v, (30, 40))
    rows, cols = np.mgrid[0:30, 0:40].astype(float)
    u, w = image_flow_px(cam, rows, cols, 1.0, RigidMotion(translation=tuple(v)))
    scale = cam.focal_px * np.linalg.norm(v)
    np.testing.assert_allclose(a_col, u / scale, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(a_row, w / scale, rtol=1e-6, atol=1e-7)
    half_col, _ = flow_directions(cam, v, (15, 20), scale=2.0)  # a level's pixel (i, j) is full-resolution (2 i, 2 j)
    np.testing.assert_allclose(half_col, a_col[::2, ::2] / 2.0, rtol=1e-6, atol=1e-7)


def test_residual_bound_removes_the_points_the_prior_missed():
    """Two levels for 8 px of motion: the coarse level sees 4 px and the prior fails at some points.

    The bound (default 1 px) keeps only points whose remaining motion is
    within the differential range: it removes points, never adds them, and
    the removed ones are the wrong ones (measured: 445 points at 2 px, 333 at
    1 px; median error of the removed 3.6 times that of the kept).
    """
    step = (32.0, 0.0, 0.0)
    scene = _sequence(step)
    loose = _measured(scene, step, levels=2, max_residual_px=2.0).measured_inverse_depth
    tight = _measured(scene, step, levels=2).measured_inverse_depth
    kept, dropped = np.isfinite(tight), np.isfinite(loose) & ~np.isfinite(tight)
    assert not np.any(kept & ~np.isfinite(loose))
    assert dropped.sum() > 50
    err_kept = _relative_errors(scene, 1, step, np.where(kept, loose, np.nan))
    err_dropped = _relative_errors(scene, 1, step, np.where(dropped, loose, np.nan))
    assert np.median(err_dropped) > 2.0 * np.median(err_kept)


@pytest.mark.parametrize(
    ("options", "exc", "message"),
    [
        ({"levels": 0}, ValueError, "levels must be an integer >= 1, got 0"),
        ({"levels": 2.0}, TypeError, "levels must be an integer >= 1, got 2.0"),
        ({"levels": 6}, ValueError, r"levels = 6 halves a 200x200 frame below 8 px: expected 1 to 5 \(default: down to 24 px\)"),
        ({"max_residual_px": 0}, ValueError, "max_residual_px"),
        ({"max_residual_px": 2.5}, ValueError, r"max_residual_px = 2.5 px is beyond the differential method's range: expected at most 2 px"),
        ({"edge_step_px": -1}, ValueError, "edge_step_px"),
    ],
)
def test_option_errors(options, exc, message):
    scene = _sequence((1.0, 0.0, 0.0))
    with pytest.raises(exc, match=message):
        next(depth_from_video(list(scene.frames), camera=scene.camera, velocity=(1.0, 0.0, 0.0), **options))


def test_tsukuba_row_as_a_video(tsukuba):
    """Tsukuba's five views as the frames of a camera moving +x (5 px per frame at the median).

    Measured at the reference view (frame 2, fused over frames 1-2): median
    relative error 4.25 %, bad-1px 5.4 % at 809 points with the pyramid (the
    truth's whole pixels alone give a median of 3.8 %); one level: 41 % and
    89 %. Without the depth-step test (``edge_step_px=0``) the pyramid keeps
    1180 points at 19 % bad-1px: most wrong points lie beside a step.
    """
    cam = PinholeCamera(100.0, tsukuba.shape[1], tsukuba.shape[0])  # disparity per view step = 100 rho

    def errors(levels, **options):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a few behind-camera points at the image border
            frames = {r.index: r for r in depth_from_video(list(tsukuba.views), camera=cam, velocity=(1.0, 0.0, 0.0), levels=levels, **options)}
        rho = frames[tsukuba.reference_index].inverse_depth
        m = np.isfinite(rho) & tsukuba.valid
        return np.abs(100.0 * rho[m] - tsukuba.disparity[m]), tsukuba.disparity[m]

    err, truth = errors(None)
    assert err.size > 600
    assert np.median(err / truth) < 0.06
    assert np.mean(err > 1.0) < 0.11
    loose, _ = errors(None, edge_step_px=0)
    assert loose.size > err.size and np.mean(loose > 1.0) > 2 * np.mean(err > 1.0)
    err, truth = errors(1)
    assert np.median(err / truth) > 0.3
    assert np.mean(err > 1.0) > 0.8


def test_cli_levels(tmp_path, capsys, monkeypatch):
    """``nfdepth video --levels``: passed to the library; a bad value is one line, exit 2, no output."""
    monkeypatch.setattr(nfdepth.cli, "_PLUGIN_COMMANDS", ("_cli_rig",))
    step = (16.0, 0.0, 0.0)
    scene = _sequence(step, n_views=3)
    folder = tmp_path / "frames"
    folder.mkdir()
    for k, frame in enumerate(scene.frames):
        assert cv2.imwrite(str(folder / f"f{k}.png"), np.round(frame * 200).astype(np.uint16))
    rig = tmp_path / "rig.toml"
    rig.write_text("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[video]\nvelocity = [16.0, 0.0, 0.0]\n")
    assert main(["video", str(folder), "--rig", str(rig), "--out", str(tmp_path / "bad.npz"), "--levels", "9", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--levels 9 halves a 200x200 frame below 8 px: expected 1 to 5" in err[0], err
    assert not (tmp_path / "bad.npz").exists()
    rel = {}
    for levels in ("1", "4"):
        target = tmp_path / f"d{levels}.npz"
        assert main(["video", str(folder), "--rig", str(rig), "--out", str(target), "--levels", levels, "--quiet"]) == 0
        with np.load(target) as z:
            depth = z["depth"][0]
        rel[levels] = _relative_errors(scene, 1, step, 1.0 / depth)
    capsys.readouterr()
    assert np.median(rel["4"]) < 0.015
    assert np.median(rel["1"]) > 0.1


def test_frames_without_edge_points_give_empty_maps():
    """Frames without edge points through the pyramid (flat but for one corner pixel): empty maps and the no-edge-point
    warning (was: cv2.remap's assertion on an empty map). Frames of one value throughout are not measured at all:
    one warning names them."""
    speck = np.full((64, 80), 7.0, np.float32)
    speck[0, 0] = 7.5
    for frames_in, warned in (([speck] * 4, "no edge points"), ([np.full((64, 80), 7.0, np.float32)] * 4, "frames 0-3 hold one value throughout")):
        with pytest.warns(UserWarning, match=warned):
            frames = list(depth_from_video(frames_in, camera=PinholeCamera(100.0, 80, 64), velocity=(1.0, 0.0, 0.0)))
        assert [f.index for f in frames] == [1, 2]
        assert all(np.isnan(f.inverse_depth).all() and np.isnan(f.measured_inverse_depth).all() for f in frames)


@pytest.mark.parametrize("step", [(32.0, 0.0, 0.0), (8.0, 0.0, 32.0)], ids=["lateral-10px", "forward"])
def test_edge_points_where_the_prior_is_not_flat_are_uncertain(step):
    """Where the prior varies by more than ``edge_step_px`` (1 px of motion) within 4 px, the points are worse.

    The pyramid's faces are slanted (0.85 px of true motion over 9 px at 10
    px per frame), and the prior is smoothed across its ridges and
    silhouette. Measured: the test drops 137 of 697 points (lateral) and
    108 of 850 (forward), whose median errors are 3.4 and 1.8 times those
    of the kept ones; ``edge_step_px=0`` keeps them all, a superset.
    """
    scene = _sequence(step)
    default = _measured(scene, step).measured_inverse_depth
    every = _measured(scene, step, edge_step_px=0).measured_inverse_depth
    kept, dropped = np.isfinite(default), np.isfinite(every) & ~np.isfinite(default)
    assert not np.any(kept & ~np.isfinite(every)) and 50 < dropped.sum() < 0.4 * kept.sum()
    np.testing.assert_array_equal(default[kept], every[kept])
    err_kept = _relative_errors(scene, 1, step, np.where(kept, every, np.nan))
    err_dropped = _relative_errors(scene, 1, step, np.where(dropped, every, np.nan))
    assert np.median(err_dropped) > 1.4 * np.median(err_kept)


@pytest.mark.parametrize("step", [(32.0, 0.0, 0.0), (1.0, 0.0, 0.0)], ids=["lateral-10px", "lateral-0.33px"])
def test_noise_is_estimated_on_the_frames_as_taken(step):
    """Warping interpolates the outer frames, which hides part of their noise: estimated on the
    warped triple it came out 0.62-0.67 for noise of 1 grey level, and the std 1.6-1.7 times too
    small (median |z| 1.15-1.65). From the frames as taken: 1.05, median |z| 0.67-1.04."""
    from nfdepth._translating_pyramid import edge_depth_coarse_to_fine
    from nfdepth.normal_flow import estimate_noise_std

    scene = _sequence(step)
    frames = [np.asarray(f, np.float32) for f in scene.frames]
    baseline = float(np.linalg.norm(step))
    res = edge_depth_coarse_to_fine(frames, camera=scene.camera, baseline=baseline, direction=np.asarray(step) / baseline, levels=4)
    assert res.noise_std == pytest.approx(float(np.median([estimate_noise_std(f) for f in frames])))
    assert 0.9 < res.noise_std < 1.2
    ok = res.valid
    truth = synthetic.surface_depth_at(scene.polyhedron, scene.camera, res.rows[ok], res.cols[ok])
    z = np.abs(res.inverse_depth.rho[ok] - 1.0 / truth) / res.inverse_depth.rho_std[ok]
    assert np.median(z) < 1.3
