"""Camera and motion model (paper eq. 1, 3, 4) against hand-derived values."""

import copy
import pickle
import re

import numpy as np
import pytest

from nfdepth.camera import (
    PinholeCamera,
    RigidMotion,
    image_flow,
    image_flow_px,
    normal_flow_px,
    relative_normal_flow_coefficients,
)


@pytest.fixture
def camera():
    return PinholeCamera(focal_px=100.0, width_px=200, height_px=160)


def test_default_principal_point_is_image_centre(camera):
    assert camera.cx_px == pytest.approx(99.5)
    assert camera.cy_px == pytest.approx(79.5)
    assert camera.shape == (160, 200)


def test_project_back_project_round_trip(camera):
    rng = np.random.default_rng(0)
    pts = rng.uniform([-100, -80, 50], [100, 80, 500], size=(50, 3))
    rows, cols, z = camera.project(pts)
    back = camera.back_project(rows, cols, z)
    np.testing.assert_allclose(back, pts, rtol=1e-12, atol=1e-9)  # float64 round trip


def test_intrinsic_matrix_projects_as_the_camera_does():
    cam = PinholeCamera(focal_px=400.0, width_px=200, height_px=160, cx_px=97.0, cy_px=83.5)
    np.testing.assert_array_equal(cam.matrix, [[400.0, 0.0, 97.0], [0.0, 400.0, 83.5], [0.0, 0.0, 1.0]])
    pts = np.array([[0.3, -0.2, 5.0], [-1.0, 0.5, 2.0]])
    uvw = pts @ cam.matrix.T
    rows, cols, _ = cam.project(pts)
    np.testing.assert_allclose(uvw[:, :2] / uvw[:, 2:], np.stack([cols, rows], axis=1), rtol=1e-12)


def test_pure_translation_flow_matches_eq1_by_hand():
    # x=0.1, y=-0.2, Z=4, V=(1,2,3): u = (1 - 0.1*3)/4, v = (2 + 0.2*3)/4
    u, v = image_flow(0.1, -0.2, 0.25, RigidMotion(translation=(1, 2, 3)))
    assert u == pytest.approx(0.7 / 4)
    assert v == pytest.approx(2.6 / 4)


def test_rotation_flow_does_not_depend_on_depth():
    motion = RigidMotion(rotation=(0.01, -0.02, 0.03))
    x, y = np.meshgrid(np.linspace(-0.5, 0.5, 7), np.linspace(-0.4, 0.4, 5))
    u1, v1 = image_flow(x, y, 1 / 10.0, motion)
    u2, v2 = image_flow(x, y, 1 / 1000.0, motion)
    np.testing.assert_array_equal(u1, u2)
    np.testing.assert_array_equal(v1, v2)


def test_scaling_depth_and_translation_leaves_flow_unchanged():
    x, y = 0.3, -0.1
    m1 = RigidMotion(translation=(1.0, -0.5, 0.7), rotation=(0.01, 0.02, 0.0))
    m2 = RigidMotion(translation=(3.0, -1.5, 2.1), rotation=(0.01, 0.02, 0.0))
    np.testing.assert_allclose(image_flow(x, y, 1 / 5.0, m1), image_flow(x, y, 1 / 15.0, m2), rtol=1e-14)


def test_flow_matches_finite_difference_of_moving_point(camera):
    # dP/dt = V + Omega x P; project before and after a small step.
    motion = RigidMotion(translation=(0.5, -1.0, 1.5), rotation=(0.004, -0.003, 0.006))
    p = np.array([30.0, -20.0, 300.0])
    h = 1e-4
    def proj(q):
        r, c, _ = camera.project(q)
        return np.array([c, r])
    vel = motion.translation + np.cross(motion.rotation, p)
    fd = (proj(p + h * vel) - proj(p - h * vel)) / (2 * h)
    row, col, z = camera.project(p)
    fu, fv = image_flow_px(camera, row, col, z, motion)
    np.testing.assert_allclose([fu, fv], fd, rtol=1e-6)  # central difference error O(h^2)


def test_about_center_equals_translation_minus_cross():
    m = RigidMotion.about_center(rotation=(0, 0, 0.1), center=(0, 0, 400), translation=(1, 0, 0))
    np.testing.assert_allclose(m.translation, [1, 0, 0])  # z axis through (0,0,400): omega x c = 0
    m = RigidMotion.about_center(rotation=(0.1, 0, 0), center=(0, 0, 400))
    np.testing.assert_allclose(m.translation, -np.cross([0.1, 0, 0], [0, 0, 400]))


def test_relative_motion_and_camera_translation_sign():
    moving = RigidMotion.camera_translation((2.0, 0, 0))
    np.testing.assert_array_equal(moving.translation, [-2.0, 0, 0])
    rel = moving - RigidMotion()
    np.testing.assert_array_equal(rel.translation, [-2.0, 0, 0])


def test_coefficients_reproduce_normal_flow(camera):
    rng = np.random.default_rng(1)
    rows = rng.uniform(0, 159, 40)
    cols = rng.uniform(0, 199, 40)
    z = rng.uniform(100, 900, 40)
    alpha = rng.uniform(-np.pi, np.pi, 40)
    motion = RigidMotion(translation=(-2, 0.3, 0.4), rotation=(0.001, 0.002, -0.003))
    a, b = relative_normal_flow_coefficients(camera, rows, cols, alpha, motion)
    vn = normal_flow_px(camera, rows, cols, z, alpha, motion)
    np.testing.assert_allclose(a + b / z, vn, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"focal_px": 0, "width_px": 10, "height_px": 10}, "focal_px must be a positive"),
        ({"focal_px": -5, "width_px": 10, "height_px": 10}, "focal_px must be a positive"),
        ({"focal_px": float("nan"), "width_px": 10, "height_px": 10}, "focal_px must be a positive"),
        ({"focal_px": 100, "width_px": 0, "height_px": 10}, "width_px must be a positive integer"),
        ({"focal_px": 100, "width_px": 10, "height_px": 10, "cx_px": float("inf")}, "cx_px must be a finite number"),
    ],
)
def test_bad_camera(kwargs, match):
    with pytest.raises(ValueError, match=match):
        PinholeCamera(**kwargs)


def test_bad_motion():
    with pytest.raises(ValueError, match=r"translation must have shape \(3,\)"):
        RigidMotion(translation=(1, 2))
    with pytest.raises(ValueError, match="rotation must be finite"):
        RigidMotion(rotation=(0, np.nan, 0))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"focal_px": 1e300}, r"^focal_px = 1e\+300 is outside 1e-30\.\.1e\+30: expected a focal length in pixels in that range"),
        ({"focal_px": 1e-300}, r"^focal_px = 1e-300 is outside 1e-30\.\.1e\+30"),
        ({"cx_px": 1e300}, r"^cx_px = 1e\+300 px: expected a principal point within 1e\+06 px of the image centre 4\.5 \(the larger of 1e\+06 px and 100 image sizes"),
        ({"cy_px": -1e6 - 4.6}, r"^cy_px = -1e\+06 px: expected a principal point within 1e\+06 px of the image centre 4\.5"),
        ({"cx_px": 2.01e6, "width_px": 20000, "height_px": 10}, r"^cx_px = 2\.01e\+06 px: expected a principal point within 2e\+06 px of the image centre 9999\.5"),
    ],
)
def test_camera_beyond_the_float_range(kwargs, match):
    """Were accepted (a focal length of 1e-300 px then overflowed in dynamic_stereo, cx = 1e300 gave overflow warnings and an empty map)."""
    with pytest.raises(ValueError, match=match):
        PinholeCamera(**{"focal_px": 100.0, "width_px": 10, "height_px": 10, **kwargs})


def test_camera_range_ends_accepted():
    for f in (1e-30, 1e30):
        assert PinholeCamera(f, 10, 10).focal_px == f
    cam = PinholeCamera(100.0, 10, 10, cx_px=4.5 + 1e6, cy_px=4.5 - 1e6)
    assert (cam.cx_px, cam.cy_px) == (4.5 + 1e6, 4.5 - 1e6)
    wide = PinholeCamera(100.0, 20000, 10, cx_px=9999.5 + 2e6)  # 100 image widths
    assert wide.cx_px == 9999.5 + 2e6


def test_rotation_beyond_the_float_range():
    with pytest.raises(ValueError, match=r"^rotation = \[0, 0, 1e\+300\] rad per unit time: expected an angular velocity of at most 1e\+30 in magnitude"):
        RigidMotion(rotation=(0.0, 0.0, 1e300))
    with pytest.raises(ValueError, match=r"rotation = \[1e\+30, 1e\+30, 0\] rad per unit time"):  # the magnitude, not a component
        RigidMotion(rotation=(1e30, 1e30, 0.0))
    with pytest.raises(ValueError, match=r"rotation = \[1e\+308, -1e\+308, 1e\+308\]"):  # its norm overflows: no warning
        RigidMotion(rotation=(1e308, -1e308, 1e308))
    assert RigidMotion(rotation=(0.0, 0.0, 1e30)).rotation[2] == 1e30


def test_project_refuses_points_that_are_not_3d(camera):
    with pytest.raises(ValueError, match=r"^points must have shape \(\.\.\., 3\), got \(4, 2\)$"):
        camera.project(np.zeros((4, 2)))


def test_motion_sum_and_scaling_are_those_of_eq1():
    """Eq. 1 is linear in (V, Omega): the flow of a sum is the sum of the flows, of a scaled motion the scaled flow."""
    m1 = RigidMotion(translation=(1.0, -2.0, 0.5), rotation=(0.01, 0.0, -0.02))
    m2 = RigidMotion(translation=(0.25, 4.0, -1.5), rotation=(-0.03, 0.005, 0.01))
    s = m1 + m2
    np.testing.assert_array_equal(s.translation, [1.25, 2.0, -1.0])
    np.testing.assert_array_equal(s.rotation, np.array([0.01, 0.0, -0.02]) + np.array([-0.03, 0.005, 0.01]))
    k = m1.scaled(2.5)
    np.testing.assert_array_equal(k.translation, [2.5, -5.0, 1.25])
    np.testing.assert_array_equal(k.rotation, [0.025, 0.0, -0.05])
    x, y, rho = np.array([0.1, -0.3]), np.array([0.2, 0.05]), np.array([1 / 300.0, 1 / 250.0])
    u1, v1 = image_flow(x, y, rho, m1)
    u2, v2 = image_flow(x, y, rho, m2)
    us, vs = image_flow(x, y, rho, s)
    np.testing.assert_allclose([us, vs], [u1 + u2, v1 + v2], rtol=1e-14, atol=1e-18)
    uk, vk = image_flow(x, y, rho, k)
    np.testing.assert_allclose([uk, vk], [2.5 * u1, 2.5 * v1], rtol=1e-14, atol=1e-18)
    # the difference is the sum with the negation (paper eq. 2: relative motion)
    d = m1 - m2
    np.testing.assert_array_equal((m1 + (-m2)).translation, d.translation)
    np.testing.assert_array_equal((m1 + (-m2)).rotation, d.rotation)


def test_scaled_motion_is_checked_like_a_new_one():
    m = RigidMotion(translation=(1.0, 0.0, 0.0), rotation=(0.0, 0.0, 0.01))
    with pytest.raises(ValueError, match=r"^rotation = \[0, 0, 1e\+38\] rad per unit time: expected an angular velocity of at most 1e\+30"):
        m.scaled(1e40)


def test_motion_arithmetic_refuses_what_is_not_a_motion():
    """``RigidMotion + 5`` raised AttributeError and ``scaled("x")`` NumPy's ufunc error; now Python's and nfdepth's TypeErrors."""
    m = RigidMotion(translation=(1.0, 0.0, 0.0))
    with pytest.raises(TypeError, match=r"unsupported operand type\(s\) for \+: 'RigidMotion' and 'int'"):
        m + 5
    with pytest.raises(TypeError, match=r"unsupported operand type\(s\) for -: 'RigidMotion' and 'str'"):
        m - "a"
    with pytest.raises(TypeError, match=r"^factor must be a finite number, got 'x'"):
        m.scaled("x")
    with pytest.raises(ValueError, match=r"^factor must be a finite number, got nan$"):
        m.scaled(float("nan"))


def test_camera_functions_refuse_complex_text_and_wrong_motions():
    """Complex points lost their imaginary part (z = 0: inf) with only a ComplexWarning; a tuple for a motion or
    a zero reduction factor raised AttributeError / ZeroDivisionError from inside."""
    import nfdepth
    from nfdepth.camera import (
        image_flow,
        image_flow_px,
        normal_flow_px,
        relative_normal_flow_coefficients,
    )
    from nfdepth.depth import Reason, solve_inverse_depth

    cam = PinholeCamera(focal_px=100.0, width_px=65, height_px=49)
    with pytest.raises(TypeError, match=r"^points must be real numbers, got dtype complex128$"):
        cam.project(np.array([[1, 2, 3j]]))
    with pytest.raises(TypeError, match=r"^alpha must be real numbers, got dtype <U1$"):
        normal_flow_px(cam, [1.0], [1.0], [1.0], "a", RigidMotion((1, 0, 0)))
    with pytest.raises(TypeError, match=r"^motion must be a nfdepth.RigidMotion .*got tuple$"):
        image_flow(0.0, 0.0, 1.0, (1, 0, 0))
    with pytest.raises(TypeError, match=r"^relative_motion must be a nfdepth.RigidMotion .*got NoneType$"):
        relative_normal_flow_coefficients(cam, [1.0], [1.0], [0.0], None)
    with pytest.raises(ValueError, match=r"^factor must be"):
        cam.reduced(0, (10, 10))
    with pytest.raises(TypeError, match=r"^delta_vn must be real numbers, got dtype complex128$"):
        solve_inverse_depth([1j], camera=cam, rows=[1.0], cols=[1.0], alpha=[0.0], relative_motion=RigidMotion((1, 0, 0)))
    # a point with no position has no data (it read UNDETERMINABLE)
    res = solve_inverse_depth([1.0], camera=cam, rows=[np.nan], cols=[1.0], alpha=[0.0], relative_motion=RigidMotion((1, 0, 0)))
    assert res.reason.tolist() == [Reason.NO_DATA]
    assert nfdepth.stereo.auto_levels((480, 640)) == 5
    for shape in (480, (2.7, 30), ("30", 30), (30,)):
        with pytest.raises(TypeError, match=rf"^shape must be \(rows, cols\) of integers, got {re.escape(repr(shape))}$"):
            nfdepth.stereo.auto_levels(shape)
    with pytest.raises(ValueError, match=r"^shape must be positive"):
        nfdepth.stereo.auto_levels((-4, 5))
    # a smallest side below 1 would halve for ever
    for size in (0, -3):
        with pytest.raises(ValueError, match=rf"^min_size_px must be an integer >= 1, got {size}$"):
            nfdepth.stereo.auto_levels((480, 640), min_size_px=size)
    # every flow of the camera model names a camera that is none
    for fn, args in (
        (image_flow_px, ("cam", 1.0, 1.0, 1.0, RigidMotion((1, 0, 0)))),
        (normal_flow_px, (None, 1.0, 1.0, 1.0, 0.0, RigidMotion((1, 0, 0)))),
        (relative_normal_flow_coefficients, (3, 1.0, 1.0, 0.0, RigidMotion((1, 0, 0)))),
    ):
        with pytest.raises(TypeError, match=r"^camera must be a nfdepth.PinholeCamera, got "):
            fn(*args)
    # depth 0: an infinite flow (inf or NaN where a term is inf * 0), no NumPy warning
    fu, fv = image_flow_px(cam, [1.0, 5.0], [1.0, 5.0], [0.0, 0.0], RigidMotion((1, 0, 0)))
    assert not np.isfinite(fu).any() and not np.isfinite(fv).any()
    assert not np.isfinite(normal_flow_px(cam, 1.0, 1.0, 0.0, 0.5, RigidMotion((1, 0, 0))))


def test_motions_compare_and_hash_by_their_vectors():
    """``==``, ``!=`` and ``in`` raised NumPy's "truth value of an array is ambiguous", ``hash()`` "unhashable type: 'numpy.ndarray'"
    (the dataclass compared and hashed its arrays as tuples)."""
    a = RigidMotion(translation=[1.0, 0.0, 0.0], rotation=[0.0, 0.0, 0.01])
    b = RigidMotion(translation=(1, 0, 0), rotation=np.array([0.0, 0.0, 0.01]))
    c = RigidMotion(translation=[1.0, 0.0, 0.0])
    assert a == b and (a != b) is False and a in [c, b]
    assert a != c and (a == c) is False and a not in [c]
    assert hash(a) == hash(b) and len({a, b, c}) == 2 and {a: 1}[b] == 1
    assert RigidMotion((0.0, 0.0, 0.0)) == RigidMotion((-0.0, 0.0, 0.0))  # as np.array_equal: and they hash alike
    assert hash(RigidMotion((0.0, 0.0, 0.0))) == hash(RigidMotion((-0.0, 0.0, 0.0)))
    assert a != "motion" and (a == (a.translation, a.rotation)) is False and a not in [None, 5]


def test_motion_keeps_read_only_copies_of_its_vectors():
    """A "frozen" motion held the caller's arrays: changing them (or ``motion.translation[0] = ...``) changed the motion."""
    t, w = np.array([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 0.1])
    m = RigidMotion(t, w)
    t[0], w[2] = 9.0, 0.5
    np.testing.assert_array_equal(m.translation, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(m.rotation, [0.0, 0.0, 0.1])
    for vec in (m.translation, m.rotation):
        with pytest.raises(ValueError, match="read-only"):
            vec[0] = 5.0
    assert (m + m).translation.flags.writeable is False and (-m).rotation.flags.writeable is False
    for copied in (copy.copy(m), copy.deepcopy(m), pickle.loads(pickle.dumps(m))):
        assert copied == m and not copied.translation.flags.writeable and not copied.rotation.flags.writeable


def test_camera_given_numpy_numbers_stores_python_ones():
    """A 0-d array given for focal_px or cx_px was kept: the camera could not be hashed (TypeError: unhashable type)."""
    cam = PinholeCamera(np.array(100.0), np.int64(200), np.int32(160), np.array(99.5), np.float32(79.5))
    assert cam == PinholeCamera(100.0, 200, 160) and hash(cam) == hash(PinholeCamera(100.0, 200, 160))
    assert [type(v) for v in (cam.focal_px, cam.width_px, cam.height_px, cam.cx_px, cam.cy_px)] == [float, int, int, float, float]
