"""Property-based tests (Hypothesis) of the geometry, the solvers, the validation and the readers.

* eq. 4 round trip: exact normal flow of random cameras, motions and planes
  gives back the inverse depth wherever the point is determinable;
* invariances: scaling depth and translation together; mirroring the image
  left-right with the matching motion (``Vx, Omega_y, Omega_z`` negated) and
  normal (``alpha -> pi - alpha``);
* the validation helpers never let NaN, inf or out-of-range values through;
* fuzz: mutated or truncated PNG/PPM/PFM/TIFF/NPY bytes either read or raise
  :class:`nfdepth.io.ImageReadError`, nothing else.
"""

from __future__ import annotations

import io as _pyio
import math
import tempfile
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import nfdepth as nf
from nfdepth import _validate, io
from nfdepth.depth import Reason

FAST = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])

finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False)
any_float = st.floats(allow_nan=True, allow_infinity=True)


@st.composite
def cameras(draw):
    w = draw(st.integers(8, 4000))
    h = draw(st.integers(8, 4000))
    f = draw(st.floats(20.0, 5000.0))
    cx = draw(st.floats(0.0, w - 1.0))
    cy = draw(st.floats(0.0, h - 1.0))
    return nf.PinholeCamera(f, w, h, cx, cy)


@st.composite
def motions(draw, *, translation=True):
    t = np.array(draw(st.lists(st.floats(-5.0, 5.0), min_size=3, max_size=3)))
    if translation:
        assume(np.linalg.norm(t) > 0.05)
    else:
        t = np.zeros(3)
    w = np.array(draw(st.lists(st.floats(-0.05, 0.05), min_size=3, max_size=3)))
    return nf.RigidMotion(t, w)


@st.composite
def scene_points(draw, camera):
    """Pixels, normals and depths on a random plane ``n . P = d`` in front of the camera."""
    n = 16
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    rows = rng.uniform(0, camera.height_px - 1, n)
    cols = rng.uniform(0, camera.width_px - 1, n)
    alpha = rng.uniform(-np.pi, np.pi, n)
    normal = np.array(draw(st.lists(st.floats(-0.5, 0.5), min_size=2, max_size=2)) + [1.0])
    distance = draw(st.floats(1.0, 1e4))
    x, y = camera.to_normalized(rows, cols)
    denom = normal[0] * x + normal[1] * y + normal[2]
    keep = denom > 0.05
    assume(keep.sum() >= 4)
    depth = distance / denom[keep]
    return rows[keep], cols[keep], alpha[keep], depth


# ------------------------------------------------------------- eq. 4 round trip


@FAST
@given(data=st.data())
def test_exact_normal_flow_round_trips_to_depth(data):
    camera = data.draw(cameras())
    motion = data.draw(motions())
    rows, cols, alpha, depth = data.draw(scene_points(camera))
    dvn = nf.normal_flow_px(camera, rows, cols, depth, alpha, motion)
    inv = nf.solve_inverse_depth(dvn, camera=camera, rows=rows, cols=cols, alpha=alpha, relative_motion=motion, min_cos=0.25)
    ok = inv.valid
    # exact data: a point is either recovered or undeterminable (B ~ 0), never "behind the camera"
    assert set(np.unique(inv.reason[~ok]).tolist()) <= {Reason.UNDETERMINABLE}
    np.testing.assert_allclose(inv.depth[ok], depth[ok], rtol=1e-6)
    assert np.all(np.isnan(inv.rho[~ok]))
    # determinable exactly where |cos| between the normal and the translational flow >= min_cos
    x, y = camera.to_normalized(rows, cols)
    vx, vy, vz = motion.translation
    tx, ty = vx - x * vz, vy - y * vz
    cos = np.abs(tx * np.cos(alpha) + ty * np.sin(alpha)) / np.hypot(tx, ty)
    clear = np.abs(cos - 0.25) > 1e-9
    assert np.array_equal(ok[clear], (cos >= 0.25)[clear])


@FAST
@given(data=st.data())
def test_pure_rotation_is_never_a_depth(data):
    camera = data.draw(cameras())
    motion = data.draw(motions(translation=False))
    rows, cols, alpha, depth = data.draw(scene_points(camera))
    dvn = nf.normal_flow_px(camera, rows, cols, depth, alpha, motion)
    inv = nf.solve_inverse_depth(dvn, camera=camera, rows=rows, cols=cols, alpha=alpha, relative_motion=motion, min_cos=0.0)
    assert np.all(inv.reason == Reason.UNDETERMINABLE)
    assert np.all(np.isnan(inv.depth))


@FAST
@given(data=st.data(), noise=st.floats(0.0, 5.0))
def test_solver_never_presents_a_negative_or_infinite_depth(data, noise):
    camera = data.draw(cameras())
    motion = data.draw(motions())
    rows, cols, alpha, depth = data.draw(scene_points(camera))
    rng = np.random.default_rng(0)
    dvn = nf.normal_flow_px(camera, rows, cols, depth, alpha, motion) + noise * rng.standard_normal(rows.size)
    inv = nf.solve_inverse_depth(dvn, camera=camera, rows=rows, cols=cols, alpha=alpha, relative_motion=motion)
    z = inv.depth
    assert np.all(np.isfinite(z[inv.valid])) and np.all(z[inv.valid] > 0)
    assert np.all(np.isnan(z[~inv.valid]))


# ------------------------------------------------------------------ invariances


@FAST
@given(data=st.data(), scale=st.floats(0.01, 100.0))
def test_scaling_depth_and_translation_together_changes_nothing(data, scale):
    camera = data.draw(cameras())
    motion = data.draw(motions())
    rows, cols, alpha, depth = data.draw(scene_points(camera))
    scaled = nf.RigidMotion(motion.translation * scale, motion.rotation)
    vn = nf.normal_flow_px(camera, rows, cols, depth, alpha, motion)
    vn_scaled = nf.normal_flow_px(camera, rows, cols, depth * scale, alpha, scaled)
    np.testing.assert_allclose(vn_scaled, vn, rtol=1e-9, atol=1e-9 * (1.0 + np.abs(vn).max()))
    a = nf.solve_inverse_depth(vn, camera=camera, rows=rows, cols=cols, alpha=alpha, relative_motion=motion)
    b = nf.solve_inverse_depth(vn, camera=camera, rows=rows, cols=cols, alpha=alpha, relative_motion=scaled)
    assert np.array_equal(a.reason, b.reason)
    np.testing.assert_allclose(b.depth[b.valid], scale * a.depth[a.valid], rtol=1e-8)


def _mirror(motion: nf.RigidMotion) -> nf.RigidMotion:
    """The motion seen in the left-right mirrored world: X -> -X."""
    vx, vy, vz = motion.translation
    wx, wy, wz = motion.rotation
    return nf.RigidMotion((-vx, vy, vz), (wx, -wy, -wz))


@FAST
@given(data=st.data())
def test_left_right_mirror_with_the_matching_motion(data):
    cam = data.draw(cameras())
    camera = nf.PinholeCamera(cam.focal_px, cam.width_px, cam.height_px)  # centred principal point
    motion = data.draw(motions())
    rows, cols, alpha, depth = data.draw(scene_points(camera))
    mirrored_cols = (camera.width_px - 1) - cols
    mirrored_alpha = np.pi - alpha
    vn = nf.normal_flow_px(camera, rows, cols, depth, alpha, motion)
    vn_m = nf.normal_flow_px(camera, rows, mirrored_cols, depth, mirrored_alpha, _mirror(motion))
    np.testing.assert_allclose(vn_m, vn, rtol=1e-9, atol=1e-9 * (1.0 + np.abs(vn).max()))
    a = nf.solve_inverse_depth(vn, camera=camera, rows=rows, cols=cols, alpha=alpha, relative_motion=motion)
    b = nf.solve_inverse_depth(vn, camera=camera, rows=rows, cols=mirrored_cols, alpha=mirrored_alpha, relative_motion=_mirror(motion))
    assert np.array_equal(a.reason, b.reason)
    # float64 rounding in another order, amplified by eq. 4's conditioning: wide-angle
    # draws (focal 20 px, 2060 px wide) reach 1.0017e-9 relative; 1e-8 leaves 10x room
    np.testing.assert_allclose(b.rho[b.valid], a.rho[a.valid], rtol=1e-8)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), sigma=st.sampled_from([0.0, 1.0, 2.0]), stencil=st.sampled_from(["matched", "simpson", "paper"]))
def test_mirrored_frames_give_mirrored_normal_flow(seed, sigma, stencil):
    rng = np.random.default_rng(seed)
    frames = [cv2.GaussianBlur(rng.random((20, 24)), (0, 0), 1.5) * 255.0 for _ in range(3)]
    g = nf.normal_flow(frames, sigma_px=sigma, stencil=stencil, dtype=np.float64)
    gm = nf.normal_flow([f[:, ::-1] for f in frames], sigma_px=sigma, stencil=stencil, dtype=np.float64)
    np.testing.assert_allclose(gm.grad_col, -g.grad_col[:, ::-1], atol=1e-9)
    np.testing.assert_allclose(gm.grad_row, g.grad_row[:, ::-1], atol=1e-9)
    np.testing.assert_allclose(gm.grad_t, g.grad_t[:, ::-1], atol=1e-9)
    strong = g.magnitude[:, ::-1] > 1e-3
    np.testing.assert_allclose(gm.normal_flow[strong], g.normal_flow[:, ::-1][strong], rtol=1e-6, atol=1e-9)


# ------------------------------------------------------------------- validation


@settings(max_examples=200, deadline=None)
@given(value=st.one_of(any_float, st.integers(-10, 10), st.text(max_size=3), st.none()))
def test_scalar_checks_never_let_a_bad_value_through(value):
    try:
        number = None if isinstance(value, str) else float(value)  # text is refused, even '0'
    except (TypeError, ValueError):
        number = None
    for check, good in ((_validate.check_positive_finite, lambda v: v > 0), (_validate.check_nonnegative_finite, lambda v: v >= 0)):
        if number is None:
            with pytest.raises(TypeError, match="must be"):
                check("p", value)
        elif math.isfinite(number) and good(number):
            assert check("p", value) == number
        else:
            with pytest.raises(ValueError, match=r"^p must be .*, got "):
                check("p", value)


@settings(max_examples=100, deadline=None)
@given(values=st.lists(any_float, min_size=0, max_size=4))
def test_vector_and_camera_checks(values):
    ok = len(values) == 3 and all(math.isfinite(v) for v in values)
    if ok:
        assert _validate.as_vector3("v", values).tolist() == values
    else:
        with pytest.raises(ValueError, match="^v must "):
            _validate.as_vector3("v", values)
    for f in values:
        if math.isfinite(f) and 1e-30 <= f <= 1e30:
            assert nf.PinholeCamera(f, 4, 4).focal_px == f
        elif math.isfinite(f) and f > 0:  # depths in float32 maps overflow or vanish beyond that range
            with pytest.raises(ValueError, match=r"focal_px = .* is outside 1e-30\.\.1e\+30"):
                nf.PinholeCamera(f, 4, 4)
        else:
            with pytest.raises(ValueError, match="focal_px must be a positive finite number"):
                nf.PinholeCamera(f, 4, 4)


@settings(max_examples=60, deadline=None)
@given(
    shape=st.tuples(st.integers(0, 5), st.integers(0, 5)),
    bad=st.sampled_from([np.nan, np.inf, -np.inf, None]),
    where=st.integers(0, 24),
    dtype=st.sampled_from([np.float32, np.float64]),
)
def test_as_image_never_returns_a_non_finite_or_tiny_image(shape, bad, where, dtype):
    img = np.ones(shape)
    if bad is not None and img.size:
        img.flat[where % img.size] = bad
    if min(shape) < 2:
        with pytest.raises(ValueError, match="must be at least 2x2 pixels"):
            _validate.as_image("im", img, dtype)
    elif bad is not None:
        with pytest.raises(ValueError, match="im contains 1 non-finite"):
            _validate.as_image("im", img, dtype)
    else:
        out = _validate.as_image("im", img, dtype)
        assert out.dtype == dtype and np.all(np.isfinite(out))


# --------------------------------------------------------------- reader fuzzing


def _valid_files() -> dict[str, bytes]:
    rng = np.random.default_rng(5)
    grey8 = rng.integers(0, 256, (6, 7), dtype=np.uint8)
    rgb16 = rng.integers(0, 65536, (5, 4, 3), dtype=np.uint16)
    out = {
        ".png": cv2.imencode(".png", grey8)[1].tobytes(),
        "16.png": cv2.imencode(".png", rgb16)[1].tobytes(),
        ".ppm": cv2.imencode(".ppm", rgb16[..., :3].astype(np.uint8))[1].tobytes(),
        ".pgm": cv2.imencode(".pgm", grey8)[1].tobytes(),
        ".pfm": b"Pf\n3 2\n-1.0\n" + np.arange(6, dtype="<f4").tobytes(),
    }
    import tifffile

    buf = _pyio.BytesIO()
    tifffile.imwrite(buf, rng.random((4, 5)).astype(np.float32))
    out[".tif"] = buf.getvalue()
    buf = _pyio.BytesIO()
    np.save(buf, rng.random((3, 4)))
    out[".npy"] = buf.getvalue()
    return out


VALID = _valid_files()
_TMP = Path(tempfile.mkdtemp(prefix="nfdepth-fuzz-"))


def _read_or_documented_error(name: str, data: bytes):
    path = _TMP / f"fuzz{name}"
    path.write_bytes(data)
    try:
        arr = io.read_image(path)
    except io.ImageReadError as exc:
        assert str(exc).startswith(f"cannot read image '{path}': ")
        return None
    assert isinstance(arr, np.ndarray) and arr.ndim == 2 and arr.dtype == np.float32
    return arr


def test_valid_fuzz_seeds_read():
    for name, data in VALID.items():
        assert _read_or_documented_error(name, data) is not None, name


@settings(max_examples=150, deadline=None)
@given(
    name=st.sampled_from(sorted(VALID)),
    cut=st.integers(0, 10_000),
    flips=st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 255)), max_size=6),
    insert=st.binary(max_size=12),
)
def test_mutated_files_read_or_raise_image_read_error(name, cut, flips, insert):
    data = bytearray(VALID[name])
    for pos, value in flips:
        data[pos % len(data)] = value
    pos = cut % (len(data) + 1)
    mutated = bytes(data[:pos]) + insert if cut % 2 else bytes(data[:pos]) + insert + bytes(data[pos:])
    _read_or_documented_error(name, mutated)


@settings(max_examples=60, deadline=None)
@given(name=st.sampled_from(sorted(VALID)), data=st.binary(max_size=64))
def test_random_bytes_read_or_raise_image_read_error(name, data):
    _read_or_documented_error(name, data)


@settings(max_examples=40, deadline=None)
@given(width=st.integers(-5, 2**40), height=st.integers(-5, 2**40), scale=st.sampled_from([b"-1.0", b"1", b"0", b"nan", b"-inf", b"1e999"]))
def test_pfm_headers_with_absurd_sizes(width, height, scale):
    data = b"Pf\n" + str(width).encode() + b" " + str(height).encode() + b"\n" + scale + b"\n" + b"\0" * 64
    _read_or_documented_error(".pfm", data)
