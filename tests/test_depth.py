"""Depth solvers (paper eq. 4-6) round-trip analytic relative normal flow."""

import warnings

import numpy as np
import pytest

from nfdepth.camera import PinholeCamera, RigidMotion, normal_flow_px
from nfdepth.depth import (
    Reason,
    depth_x_translation,
    depth_y_translation,
    depth_z_translation,
    fuse_inverse_depth,
    solve_inverse_depth,
)

CAM = PinholeCamera(focal_px=120.0, width_px=160, height_px=120)


def random_points(rng, n=500):
    rows = rng.uniform(0, 119, n)
    cols = rng.uniform(0, 159, n)
    z = rng.uniform(50, 1000, n)
    alpha = rng.uniform(-np.pi, np.pi, n)
    return rows, cols, z, alpha


@pytest.mark.parametrize("seed", range(5))
def test_general_motion_round_trip_machine_precision(seed):
    rng = np.random.default_rng(seed)
    rows, cols, z, alpha = random_points(rng)
    m_moving = RigidMotion(translation=rng.normal(0, 2, 3), rotation=rng.normal(0, 0.01, 3))
    m_static = RigidMotion(translation=rng.normal(0, 1, 3), rotation=rng.normal(0, 0.01, 3))
    rel = m_moving - m_static
    dvn = normal_flow_px(CAM, rows, cols, z, alpha, m_moving) - normal_flow_px(CAM, rows, cols, z, alpha, m_static)
    inv = solve_inverse_depth(dvn, camera=CAM, rows=rows, cols=cols, alpha=alpha, relative_motion=rel, min_cos=0.05)
    ok = inv.valid
    assert ok.mean() > 0.85  # only near-parallel edges (|cos| < 0.05) are refused
    np.testing.assert_allclose(inv.depth[ok], z[ok], rtol=1e-9)  # float64 with B >= 0.05 |flow|
    assert np.all(inv.reason[~ok] == Reason.UNDETERMINABLE)
    assert np.all(np.isnan(inv.depth[~ok]))


def test_special_cases_agree_with_general_solver():
    rng = np.random.default_rng(7)
    rows, cols, z, alpha = random_points(rng, 200)
    for axis, fn in enumerate((depth_x_translation, depth_y_translation)):
        t = np.zeros(3)
        t[axis] = -2.0
        rel = RigidMotion(translation=t)
        dvn = normal_flow_px(CAM, rows, cols, z, alpha, rel)
        kw = {"delta_vx": -2.0} if axis == 0 else {"delta_vy": -2.0}
        zs = fn(dvn, alpha, focal_px=CAM.focal_px, **kw)
        ok = np.isfinite(zs)
        np.testing.assert_allclose(zs[ok], z[ok], rtol=1e-9)
        assert ok.mean() > 0.95
    rel = RigidMotion(translation=(0, 0, 1.5))
    dvn = normal_flow_px(CAM, rows, cols, z, alpha, rel)
    zs = depth_z_translation(dvn, alpha, camera=CAM, rows=rows, cols=cols, delta_vz=1.5)
    ok = np.isfinite(zs)
    np.testing.assert_allclose(zs[ok], z[ok], rtol=1e-8)
    # exact flows of points in front of the camera: every depth comes back (a wrong sign gives none)
    assert ok.mean() > 0.95


def test_paper_eq6_by_hand():
    # f = 100, dVx = -2, alpha = 0, Z = 400 -> dVn = -0.5 px per unit time
    assert depth_x_translation(-0.5, 0.0, focal_px=100, delta_vx=-2.0) == pytest.approx(400.0)


def test_pure_rotation_is_undeterminable_not_a_number():
    rel = RigidMotion(rotation=(0.0, 0.0, 0.01))
    inv = solve_inverse_depth([0.3, -0.2], camera=CAM, rows=[10, 50], cols=[20, 80], alpha=[0.1, 1.0], relative_motion=rel)
    assert np.all(inv.reason == Reason.UNDETERMINABLE)
    assert np.all(np.isnan(inv.rho))


def test_edge_parallel_to_baseline_and_wrong_sign():
    rel = RigidMotion(translation=(-2.0, 0, 0))
    inv = solve_inverse_depth(
        [-0.5, 0.5, -0.5], camera=CAM, rows=[60, 60, 60], cols=[80, 80, 80], alpha=[np.pi / 2, 0.0, 0.0], relative_motion=rel
    )
    assert inv.reason.tolist() == [Reason.UNDETERMINABLE, Reason.NOT_POSITIVE, Reason.OK]
    assert inv.depth[2] == pytest.approx(120 * 2 / 0.5)  # f = 120 px


def test_uncertainty_is_noise_over_b():
    rel = RigidMotion(translation=(-2.0, 0, 0))
    inv = solve_inverse_depth(
        [-0.5], camera=CAM, rows=[59.5], cols=[79.5], alpha=[0.0], relative_motion=rel, delta_vn_std=[0.01]
    )
    assert inv.rho_std[0] == pytest.approx(0.01 / (120 * 2))


def test_fusion_is_weighted_least_squares():
    rho_true = 1 / 250.0
    b = np.array([[-240.0], [120.0], [-60.0]])
    a = np.array([[0.1], [-0.2], [0.0]])
    std = np.array([[0.01], [0.02], [0.04]])
    noise = np.array([[0.01], [-0.02], [0.04]])
    dvn = a + b * rho_true + noise
    rho, rho_std, count = fuse_inverse_depth(dvn, a, b, std)
    w = 1 / std**2
    expected = np.sum(w * b * (dvn - a)) / np.sum(w * b * b)
    assert rho[0] == pytest.approx(expected)
    assert rho_std[0] == pytest.approx(1 / np.sqrt(np.sum(w * b * b)))
    assert count[0] == 3
    # NaN measurements are skipped
    dvn[1, 0] = np.nan
    _, _, count = fuse_inverse_depth(dvn, a, b, std)
    assert count[0] == 2


def test_bad_special_case_input():
    with pytest.raises(ValueError, match="delta_vx must be a non-zero finite translation"):
        depth_x_translation(0.5, 0.0, focal_px=100, delta_vx=0.0)
    with pytest.raises(ValueError, match="focal_px must be a positive"):
        depth_x_translation(0.5, 0.0, focal_px=-1, delta_vx=1.0)
    with pytest.raises(ValueError, match="min_cos must be within"):
        solve_inverse_depth([1.0], camera=CAM, rows=[1], cols=[1], alpha=[0], relative_motion=RigidMotion((1, 0, 0)), min_cos=2)
    with pytest.raises(TypeError, match=r"^camera must be a nfdepth.PinholeCamera, got dict$"):
        depth_z_translation(0.5, 0.0, camera={"focal_px": 120.0}, rows=[1.0], cols=[1.0], delta_vz=1.0)
    # a complex direction or flow lost its imaginary part with only a ComplexWarning
    with pytest.raises(TypeError, match=r"^alpha must be real numbers, got dtype complex128$"):
        depth_x_translation(0.5, [0.1j], focal_px=100, delta_vx=1.0)
    with pytest.raises(TypeError, match=r"^alpha must be real numbers, got dtype <U3$"):
        depth_y_translation(0.5, ["0.1"], focal_px=100, delta_vy=1.0)
    with pytest.raises(TypeError, match=r"^alpha must be real numbers, got dtype complex128$"):
        depth_z_translation(0.5, 1j, camera=CAM, rows=[1.0], cols=[1.0], delta_vz=1.0)
    for name in ("delta_vn", "a", "b"):
        args = {"delta_vn": [1.0, 2.0], "a": [0.0, 0.0], "b": [1.0, 1.0]}
        args[name] = [1.0, 1j] if name != "b" else ["1", "2"]
        with pytest.raises(TypeError, match=rf"^{name} must be real numbers, got dtype "):
            fuse_inverse_depth(args["delta_vn"], args["a"], args["b"], [0.1, 0.1])
    from nfdepth.edges import block_structure_tensor, corner_ratio

    for fn in (block_structure_tensor, corner_ratio):
        with pytest.raises(TypeError, match=r"^grad_row must be real numbers, got dtype complex128$"):
            fn(np.ones((6, 6)), np.ones((6, 6)) * 1j, window_sigma_px=1.0)


def test_uncertainty_bound_marks_uncertain():
    rel = RigidMotion(translation=(-2.0, 0, 0))
    kw = {"camera": CAM, "rows": [59.5, 59.5], "cols": [79.5, 79.5], "alpha": [0.0, 0.0], "relative_motion": rel}
    # rho = 0.5 / 240; rel std = std / 0.5
    inv = solve_inverse_depth([-0.5, -0.5], delta_vn_std=[0.001, 0.05], max_rel_std=0.01, **kw)
    assert inv.reason.tolist() == [Reason.OK, Reason.UNCERTAIN]
    assert np.isnan(inv.depth[1])
    with pytest.raises(ValueError, match="max_rel_std needs delta_vn_std"):
        solve_inverse_depth([-0.5], max_rel_std=0.1, camera=CAM, rows=[1], cols=[1], alpha=[0], relative_motion=rel)


def test_static_stereo_edges_fuses_the_triples_up_to_max_span():
    """Seven noisy views of the paper's pyramid (reference the middle one): ``max_span=1`` is
    the middle triple alone (the three middle views give the same depths); ``max_span=2``
    fuses the triples k = 1, 2 by inverse-variance least squares. The k = 2 triple moves twice
    as far, so its std is about half: the fused std is 1 / sqrt(1 + 4) = 0.45 of the
    triple's for independent triples (they share the reference; measured 0.48, bound
    0.4-0.6), and the median relative depth error against the rendered surface about halves
    (measured 2.0 % -> 1.0 %; 0.43-0.53 of it over four noise draws; bound 0.7 and 1.5 %)."""
    from nfdepth import synthetic
    from nfdepth.pipelines import static_stereo_edges

    scene = synthetic.paper_static_sequence(n_views=7, noise_std=2.0, rng=np.random.default_rng(0), image_size_px=120)
    kw = {"camera": scene.camera, "baseline": 2.0, "noise_std": 2.0}
    one = static_stereo_edges(scene.frames, max_span=1, **kw)
    middle = static_stereo_edges(scene.frames[2:5], **kw)
    np.testing.assert_array_equal(one.depth, middle.depth)
    np.testing.assert_array_equal(one.rows, middle.rows)
    two = static_stereo_edges(scene.frames, max_span=2, **kw)
    np.testing.assert_array_equal(static_stereo_edges(scene.frames[1:6], **kw).depth, two.depth)  # the default: every triple that fits

    def rel_error(r):
        ok = r.valid
        assert ok.sum() > 300
        truth = synthetic.surface_depth_at(scene.polyhedron, scene.camera, r.rows[ok], r.cols[ok])
        return np.median(np.abs(r.depth[ok] - truth) / truth), np.median(r.inverse_depth.rho_std[ok] / r.inverse_depth.rho[ok])

    (err1, std1), (err2, std2) = rel_error(one), rel_error(two)
    assert 0.4 <= std2 / std1 <= 0.6, std2 / std1
    assert err2 < 0.7 * err1 and err2 < 0.015, (err1, err2)
    for bad in (True, 1.5):
        with pytest.raises(TypeError, match=rf"^max_span must be an int >= 1 or None, got {bad!r}$"):
            static_stereo_edges(scene.frames, max_span=bad, **kw)


@pytest.mark.parametrize("step", [2.0, 3.0, 4.0])
def test_far_triples_count_only_within_the_differential_range(step):
    """Seven views at 0.5, 0.75 and 1 px of motion per step (noise 1 grey level): triple k moves
    k times as far, and beyond about 1.25 px its stencil is biased. Fusing every triple regardless
    gave median errors of 0.89, 2.36 and 3.76 % with stds 2-11 times too small (median |z| 1.9,
    6.0, 11.4). Counted only within 1.25 px, the fused depth is about as good as the nearest
    triple's or better (measured 0.59 / 1.46, 0.96 / 0.92, 0.51 / 0.50 %) and its std honest
    (median |z| 0.75-0.9, against 0.67 for Gaussian errors). Bounds: 1.1 times the nearest
    triple's error (the old fusion: 0.6, 2.6 and 7.5 times), |z| below 1.2."""
    from nfdepth import synthetic
    from nfdepth.pipelines import static_stereo_edges

    scene = synthetic.static_sequence(
        synthetic.paper_pyramid(), synthetic.paper_camera(), n_views=7, camera_step=(step, 0.0, 0.0), reference_index=3, noise_std=1.0, rng=np.random.default_rng(0)
    )

    def errors(max_span):
        res = static_stereo_edges(scene.frames, camera=scene.camera, baseline=step, max_span=max_span)
        ok = res.valid
        assert ok.sum() > 600
        truth = synthetic.surface_depth_at(scene.polyhedron, scene.camera, res.rows[ok], res.cols[ok])
        rho = res.inverse_depth.rho[ok]
        return np.median(np.abs(1.0 / rho - truth) / truth), np.median(np.abs(rho - 1.0 / truth) / res.inverse_depth.rho_std[ok])

    (single, _), (fused, z) = errors(1), errors(None)
    assert fused < 1.1 * single, (fused, single)
    assert z < 1.2


def test_motions_beyond_the_stencils_range_warn():
    """Edge points moving a median of more than 2 px across a triple: one warning naming the triple.

    The stencil's measured normal flow saturates near 4 px (sigma 2), so the
    motion is underestimated there and depths are wrong by tens of percent
    (18 % at 4 px, 94 % at 8 px, tests/test_video_coarse_to_fine.py). 1 px
    per step stays silent (the suite turns warnings into errors).
    """
    from nfdepth import synthetic
    from nfdepth.pipelines import dynamic_stereo, static_stereo_edges

    def row(step, n):
        return synthetic.static_sequence(synthetic.paper_pyramid(), synthetic.paper_camera(), n_views=n, camera_step=(step, 0.0, 0.0), reference_index=n // 2)

    slow, fast = row(4.0, 5), row(16.0, 5)
    static_stereo_edges(slow.frames, camera=slow.camera, baseline=4.0)
    with pytest.warns(UserWarning, match=r"^the edge points move a median of 3\.\d px across the nearest views \(its measured normal flow\), beyond the differential method's range of about 2 px"):
        static_stereo_edges(fast.frames[1:4], camera=fast.camera, baseline=16.0)
    # five frames of one moving camera as I1..I5: the moving triple (I1, I3, I5) spans two steps, the other
    # one; the relative flow is then about zero, so its depths are no depths (ignored here)
    motion = RigidMotion(translation=(-4.0, 0.0, 0.0))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*behind the camera", category=UserWarning)
        dynamic_stereo(row(1.0, 5).frames, camera=slow.camera, relative_motion=motion)
        with pytest.warns(UserWarning, match=r"^the edge points move a median of \d\.\d px across the moving camera's frames \(I1, I3, I5\)"):
            dynamic_stereo(row(6.0, 5).frames, camera=slow.camera, relative_motion=motion)  # 1.5 px per frame


@pytest.mark.parametrize("sigma_px", [2.0, 3.0])
def test_edge_points_near_the_border_are_not_selected(sigma_px):
    """The smoothing reflects the frames at the border, and the mirror image moves the other way: a moving step
    edge 1-1.5 sigma from the border read depths 8-53 % low (a few tens of its std). The pipelines keep no edge
    point within 2.5 sigma of the border; inside, the same edge is exact to 0.5 %."""
    from nfdepth.pipelines import BORDER_SIGMAS, static_stereo_edges

    h, w, d = 32, 64, 0.5  # a vertical step moving 0.5 px per view: depth 100 / 0.5 = 200
    cols = np.arange(w, dtype=float)[None, :].repeat(h, axis=0)
    cam = PinholeCamera(focal_px=100.0, width_px=w, height_px=h)
    for at_sigmas, selected in ((1.0, False), (1.5, False), (4.0, True), (6.0, True)):
        c0 = -0.5 + at_sigmas * sigma_px
        views = [100 + 50 * np.tanh((cols - c0 + (k - 1) * d) / 1.5) for k in range(3)]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # no edge points: the warning says so
            res = static_stereo_edges(views, camera=cam, baseline=1.0, sigma_px=sigma_px)
        near = res.cols < BORDER_SIGMAS * sigma_px
        assert not near.any()
        assert res.valid.any() == selected, at_sigmas
        if selected:
            assert np.nanmedian(res.depth[res.valid]) == pytest.approx(200.0, rel=0.005)


def test_fuse_inverse_depth_takes_exact_measurements_and_refuses_a_negative_std():
    """std 0 (exact data) gave NaN and count 0; a negative std was taken as missing. Exact measurements now outweigh
    the rest (equal weights among them, std 0); a negative std is an error."""
    rho, rho_std, count = fuse_inverse_depth([[-2.0, 1.0], [-2.0, 2.0]], 0.0, -200.0, [[0.0, 0.0], [0.0, 0.2]])
    np.testing.assert_allclose(rho, [0.01, -0.005])
    np.testing.assert_array_equal(rho_std, [0.0, 0.0])
    np.testing.assert_array_equal(count, [2, 1])  # the second point: its exact measurement alone
    with pytest.raises(ValueError, match=r"^delta_vn_std must be >= 0 \(NaN: unknown\), got 1 negative value\(s\), the lowest -0.1$"):
        fuse_inverse_depth([[-2.0], [-2.0]], 0.0, -200.0, [[0.1], [-0.1]])
    cam = PinholeCamera(focal_px=100.0, width_px=64, height_px=48)
    with pytest.raises(ValueError, match=r"^delta_vn_std must be >= 0"):
        solve_inverse_depth([-0.5], camera=cam, rows=[23.5], cols=[31.5], alpha=[0.0], relative_motion=RigidMotion((-2, 0, 0)), delta_vn_std=[-0.05])


def test_fuse_inverse_depth_neither_overflows_nor_underflows():
    """The sums w B^2 and w B (dVn - A) were taken as they stand: B = 1e-200 underflowed them to 0 (NaN, with a count
    of 1), std = 1e-200 overflowed them (NaN with std 0). Relative to the most informative measurement they do neither;
    the results are the analytic ones at any scale."""
    for scale in (1e-200, 1e-100, 1.0, 1e100, 1e200):
        # rho = dVn / B per measurement: 1 and 3 with equal information: mean 2, std (std / |B|) / sqrt(2)
        rho, rho_std, count = fuse_inverse_depth([scale, 3 * scale], 0.0, scale, [scale, scale])
        assert rho == pytest.approx(2.0, rel=1e-12)
        assert rho_std == pytest.approx(np.sqrt(0.5), rel=1e-12)
        assert count == 2
        rho, rho_std, count = fuse_inverse_depth([1.0, 3.0], 0.0, 1.0, [scale, scale])
        assert rho == pytest.approx(2.0, rel=1e-12)
        assert rho_std == pytest.approx(scale * np.sqrt(0.5), rel=1e-12)
        assert count == 2
    # information so large that |B| / std overflows counts as exact (std 0), as a std of 0 does
    rho, rho_std, count = fuse_inverse_depth([1.0, 5.0], 0.0, 1.0, [1e-320, 1.0])
    assert (float(rho), float(rho_std), int(count)) == (1.0, 0.0, 1)
    # one measurement 1e200 times less informative than the other: its weight is 0 to float precision
    rho, rho_std, count = fuse_inverse_depth([1.0, 5.0], 0.0, 1.0, [1e-100, 1e100])
    assert (float(rho), float(rho_std), int(count)) == (1.0, 1e-100, 2)


def test_special_cases_refuse_an_undeterminable_normal_as_eq4_does():
    """Eq. 6 for a normal perpendicular to the translational flow is 0 / 0; in floats cos(pi/2) = 6e-17 gave
    Z = 2.4e-14 for any measured flow, a depth that looked like one. Below min_cos (at least 1e-12) it is NaN, as
    solve_inverse_depth has it; with min_cos the three solvers refuse what eq. 4's solver refuses."""
    f, t = 100.0, -2.0
    # x translation, normal along y: cos(alpha) = 6e-17
    assert np.isnan(depth_x_translation(-0.5, np.pi / 2, focal_px=f, delta_vx=t))
    assert np.isnan(depth_y_translation(-0.5, 0.0, focal_px=f, delta_vy=t))
    # z translation: the principal point, and a normal perpendicular to the radial direction
    cx, cy = CAM.cx_px, CAM.cy_px
    rows, cols = np.array([cy, cy, cy]), np.array([cx, cx + 30.0, cx + 30.0])
    z = depth_z_translation([0.3, 0.3, 0.3], [0.0, np.pi / 2, 0.0], camera=CAM, rows=rows, cols=cols, delta_vz=-1.5)
    assert np.isnan(z[:2]).all() and z[2] > 0
    # min_cos: the points eq. 4's solver refuses at the same bound, and only those
    rng = np.random.default_rng(8)
    rows, cols, depth, alpha = random_points(rng, 400)
    for translation, fn, kw in (
        ((-2.0, 0, 0), depth_x_translation, {"focal_px": CAM.focal_px, "delta_vx": -2.0}),
        ((0, -2.0, 0), depth_y_translation, {"focal_px": CAM.focal_px, "delta_vy": -2.0}),
        ((0, 0, 1.5), depth_z_translation, {"camera": CAM, "rows": rows, "cols": cols, "delta_vz": 1.5}),
    ):
        rel = RigidMotion(translation=translation)
        dvn = normal_flow_px(CAM, rows, cols, depth, alpha, rel)
        general = solve_inverse_depth(dvn, camera=CAM, rows=rows, cols=cols, alpha=alpha, relative_motion=rel, min_cos=0.5)
        special = fn(dvn, alpha, min_cos=0.5, **kw)
        np.testing.assert_array_equal(np.isfinite(special), general.reason == Reason.OK)
        assert 0.2 < np.isnan(special).mean() < 0.6  # min_cos 0.5 refuses the normals within 30 degrees of perpendicular
        np.testing.assert_allclose(special[np.isfinite(special)], depth[np.isfinite(special)], rtol=1e-8)
    with pytest.raises(ValueError, match=r"^min_cos must be within \[0, 1\], got 1.5$"):
        depth_y_translation(-0.5, 0.0, focal_px=f, delta_vy=t, min_cos=1.5)
