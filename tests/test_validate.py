"""The shared numeric validators: what counts as a number, an integer, a 3-vector.

``float('2')`` parses text and ``float(True)`` is 1.0, so the validators
refuse str / bytes / bool / complex before converting; integer options refuse
floats, integral ones included. NumPy scalars and 0-d numeric arrays pass.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from nfdepth._validate import (
    as_vector3,
    check_finite,
    check_fraction,
    check_int,
    check_nonnegative_finite,
    check_nonzero_finite,
    check_positive_finite,
    check_positive_or_inf,
    check_reach,
    check_view_index,
)

NUMBER_CHECKS = [
    (check_finite, "a finite number"),
    (check_positive_finite, "a positive finite number"),
    (check_nonnegative_finite, "a finite number >= 0"),
    (check_nonzero_finite, "a non-zero finite number"),
    (check_reach, "a number >= 0 (inf: no limit)"),
    (check_positive_or_inf, "a number > 0 (inf: no limit)"),
    (check_fraction, "a number within [0, 1]"),
]


@pytest.mark.parametrize(("check", "what"), NUMBER_CHECKS, ids=[c[0].__name__ for c in NUMBER_CHECKS])
@pytest.mark.parametrize(
    ("value", "why"),
    [
        ("0.5", "str, not a number"),
        (b"0.5", "bytes, not a number"),
        (np.str_("0.5"), "str, not a number"),
        (np.array("0.5"), "str, not a number"),
        (True, "bool, not a number"),
        (np.False_, "bool, not a number"),
        (np.array(True), "bool, not a number"),
        (0.5 + 0j, "complex, not a real number"),
        (np.complex64(0.5), "complex, not a real number"),
    ],
)
def test_numbers_refuse_text_bools_and_complex(check, what, value, why):
    with pytest.raises(TypeError) as info:
        check("speed_px", value)
    assert str(info.value) == f"speed_px must be {what}, got {value!r} ({why})"


@pytest.mark.parametrize(("check", "what"), NUMBER_CHECKS, ids=[c[0].__name__ for c in NUMBER_CHECKS])
@pytest.mark.parametrize("value", [0.5, np.float32(0.5), np.float64(0.5), np.array(0.5), np.array(0.5, dtype=np.float16)])
def test_numbers_accept_floats_numpy_scalars_and_0d_arrays(check, what, value):
    got = check("speed_px", value)
    assert type(got) is float and got == 0.5


@pytest.mark.parametrize("value", [1, np.int8(1), np.uint64(1), np.array(1)])
def test_numbers_accept_integers(value):
    assert check_positive_finite("speed_px", value) == 1.0
    assert check_fraction("speed_px", value) == 1.0


@pytest.mark.parametrize(("value", "why"), [(None, None), ([1.0], None), ("abc", "str, not a number")])
def test_number_message_for_other_types(value, why):
    with pytest.raises(TypeError) as info:
        check_positive_finite("speed_px", value)
    tail = f" ({why})" if why else ""
    assert str(info.value) == f"speed_px must be a positive finite number, got {value!r}{tail}"


@pytest.mark.parametrize(
    ("value", "why"),
    [
        (2.5, "not a whole number"),
        (np.float32(2.5), "not a whole number"),
        (float("nan"), "not a whole number"),
        (float("inf"), "not a whole number"),
        (2.0, "float; give an int such as 2"),
        (np.float64(3.0), "float; give an int such as 3"),
        (np.array(4.0), "float; give an int such as 4"),
        ("2", "str, not a number"),
        (b"2", "bytes, not a number"),
        (True, "bool, not a number"),
        (np.True_, "bool, not a number"),
        (2 + 0j, "complex, not a real number"),
        (None, None),
        ([2], None),
    ],
)
def test_integers_refuse_floats_text_and_bools(value, why):
    tail = f" ({why})" if why else ""
    with pytest.raises(TypeError) as info:
        check_int("levels", value, 1)
    assert str(info.value) == f"levels must be an integer >= 1, got {value!r}{tail}"
    with pytest.raises(TypeError) as info:
        check_view_index("reference", value, 5)
    assert str(info.value) == f"reference must be an int view index, got {value!r}{tail}"


@pytest.mark.parametrize("value", [3, np.int8(3), np.uint16(3), np.int64(3), np.array(3)])
def test_integers_accept_python_and_numpy_integers(value):
    got = check_int("levels", value, 1)
    assert type(got) is int and got == 3
    got = check_view_index("reference", value, 5)
    assert type(got) is int and got == 3


def test_integer_range_errors_stay_value_errors():
    with pytest.raises(ValueError, match=r"^levels must be an integer >= 1, got 0$"):
        check_int("levels", 0, 1)
    with pytest.raises(ValueError, match=r"^reference must be a view index in 0\.\.2, got np\.int64\(3\)$"):
        check_view_index("reference", np.int64(3), 3)


@pytest.mark.parametrize(
    ("value", "why"),
    [
        (["1", "0", "0"], "str, not a number"),
        (("1", 0, 0), "str, not a number"),
        ([0, False, 1], "bool, not a number"),
        (np.array([True, False, True]), "array of bool, not numbers"),
        (np.array(["1", "0", "0"]), "array of <U1, not numbers"),
        (np.array([1j, 0, 0]), "array of complex128, not numbers"),
    ],
)
def test_vectors_refuse_text_and_bools(value, why):
    with pytest.raises(TypeError) as info:
        as_vector3("velocity", value)
    assert str(info.value) == f"velocity must be 3 numbers, got {value!r} ({why})"


@pytest.mark.parametrize("value", [[1, 0, 0], (1.0, 0.0, 0.0), np.array([1, 0, 0], dtype=np.int32), [np.float32(1), np.int64(0), 0.0]])
def test_vectors_accept_numbers(value):
    np.testing.assert_array_equal(as_vector3("velocity", value), [1.0, 0.0, 0.0])


def test_scale_px_caps_gaussian_scales():
    """Sigmas and windows beyond any image are refused by name (a huge one overflowed OpenCV's kernel size: an internal error)."""
    from nfdepth._validate import MAX_SCALE_PX, check_scale_px

    assert check_scale_px("sigma_px", 0) == 0.0 and check_scale_px("sigma_px", MAX_SCALE_PX) == MAX_SCALE_PX
    with pytest.raises(ValueError, match=r"sigma_px = 1e\+300 px is beyond any image: expected a Gaussian scale of at most 5000 px"):
        check_scale_px("sigma_px", 1e300)
    with pytest.raises(ValueError, match="a positive finite number"):
        check_scale_px("dense_window_px", 0, zero_ok=False)
    with pytest.raises(ValueError, match="a finite number >= 0"):
        check_scale_px("sigma_px", -1)


@pytest.mark.parametrize(
    ("entry", "name"),
    [
        ("gaussian_smooth", "sigma_px"),
        ("normal_flow_edges", "sigma_px"),
        ("normal_flow_edges", "corner_window_px"),
        ("static_stereo", "dense_window_px"),
        ("static_stereo", "cost_sigma_px"),
    ],
)
def test_huge_gaussian_scales_are_refused_where_they_enter(entry, name):
    from nfdepth.fast import normal_flow_edges
    from nfdepth.normal_flow import gaussian_smooth
    from nfdepth.stereo import static_stereo

    views = [np.random.default_rng(k).random((24, 32)).astype(np.float32) for k in range(3)]
    calls = {
        "gaussian_smooth": lambda **kw: gaussian_smooth(views[0], **kw),
        "normal_flow_edges": lambda **kw: normal_flow_edges(views, **{"sigma_px": 1.0, **kw}),
        "static_stereo": lambda **kw: static_stereo(views, reference=1, **kw),
    }
    with pytest.raises(ValueError, match=rf"{name} = 1e\+300 px is beyond any image"):
        calls[entry](**{name: 1e300})


@pytest.mark.parametrize("entry", ["normal_flow", "normal_flow_edges", "dynamic_stereo"])
def test_frame_interval_outside_its_range_is_refused(entry):
    """A time step of 1e-300 overflowed the noise formula of dynamic stereo (an internal error); every entry refuses it by name."""
    from nfdepth._validate import check_frame_interval

    assert check_frame_interval("frame_interval", 1e-30) == 1e-30
    frames = [np.random.default_rng(k).random((24, 32)) for k in range(3)]
    with pytest.raises(ValueError, match=r"frame_interval = 1e-300 is outside 1e-30\.\.1e\+30"):
        if entry == "normal_flow":
            from nfdepth.normal_flow import normal_flow

            normal_flow(frames, sigma_px=1.0, frame_interval=1e-300)
        elif entry == "normal_flow_edges":
            from nfdepth.fast import normal_flow_edges

            normal_flow_edges(frames, sigma_px=1.0, frame_interval=1e-300)
        else:
            from nfdepth.camera import PinholeCamera, RigidMotion
            from nfdepth.pipelines import dynamic_stereo

            five = [np.random.default_rng(k).random((24, 32)) for k in range(5)]
            cam = PinholeCamera(30.0, 32, 24)
            dynamic_stereo(five, camera=cam, relative_motion=RigidMotion(translation=(1.0, 0.0, 0.0)), sigma_px=1.0, frame_interval=1e-300)


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("guided_scale", 1e300, r"guided_scale = 1e\+300 makes the guided filter's radius 4e\+300 px"),
        ("cost_radius", 10**9, r"cost_radius = 1000000000 px is beyond any image"),
        ("max_std_px", 1e-300, r"max_std_px = 1e-300 px is below any measurable standard deviation"),
        ("noise_std", 1e300, r"noise_std = 1e\+300 is beyond any image's intensities"),
    ],
)
def test_static_stereo_refuses_extreme_expert_options(option, value, message):
    """Values that crashed (OpenCV's kernel size, float overflow) or ran without end are refused by name."""
    from nfdepth.stereo import static_stereo

    views = [np.random.default_rng(k).random((24, 32)).astype(np.float32) for k in range(3)]
    with pytest.raises(ValueError, match=message):
        static_stereo(views, reference=1, **{option: value})


def test_static_stereo_reach_beyond_the_image_is_no_limit():
    """A dense reach past the image's diagonal limits nothing, as inf does (1e300 crashed OpenCV's dilation)."""
    from nfdepth.stereo import static_stereo

    rng = np.random.default_rng(3)
    base = rng.random((40, 60)).astype(np.float32) * 100
    views = [np.roll(base, k, axis=1) for k in (-1, 0, 1)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a random texture: ambiguity warnings are not the point
        far = static_stereo(views, reference=1, dense_reach_px=1e300)
        unlimited = static_stereo(views, reference=1, dense_reach_px=np.inf)
    np.testing.assert_array_equal(far.disparity, unlimited.disparity)


def test_check_int_refuses_integers_beyond_int64_kernels():
    """border_px = 10**30 overflowed the compiled kernels' int64 (an OverflowError); integers stop at 2**53."""
    from nfdepth.fast import normal_flow_edges

    assert check_int("border_px", 2**53, 0) == 2**53
    with pytest.raises(ValueError, match=r"border_px must be an integer from 0 to 2\*\*53, got 10000000000000000000000000000000"):
        check_int("border_px", 10**31, 0)
    frames = [np.random.default_rng(k).random((24, 32)).astype(np.float32) for k in range(3)]
    with pytest.raises(ValueError, match="border_px must be an integer from 0 to 2"):
        normal_flow_edges(frames, sigma_px=1.0, border_px=10**30)


def test_check_threshold_bounds_what_meets_float32_maps():
    """Thresholds and ridges above 1e30 are refused (1e300 overflowed float32 casts: NumPy warnings, wrong tests); inf only where it means no limit."""
    from nfdepth._validate import MAX_THRESHOLD, check_threshold

    assert check_threshold("min_gradient", 0) == 0.0 and check_threshold("min_gradient", MAX_THRESHOLD) == MAX_THRESHOLD
    assert check_threshold("max_edge_std_px", np.inf, positive=True, inf_ok=True) == np.inf
    with pytest.raises(ValueError, match=r"^min_gradient = 1e\+300 is beyond the float32 maps it applies to: expected at most 1e\+30$"):
        check_threshold("min_gradient", 1e300)
    with pytest.raises(ValueError, match=r"max_edge_std_px = 1e\+39 .*; give inf for no limit$"):
        check_threshold("max_edge_std_px", 1e39, positive=True, inf_ok=True)
    # below the range and non-numbers: the messages of the underlying checks
    with pytest.raises(ValueError, match=r"^cost_eps must be a positive finite number, got 0$"):
        check_threshold("cost_eps", 0, positive=True)
    with pytest.raises(ValueError, match=r"^min_gradient must be a finite number >= 0, got inf$"):
        check_threshold("min_gradient", np.inf)
    with pytest.raises(ValueError, match=r"must be a number >= 0 \(inf: no limit\), got -1"):
        check_threshold("reach", -1, inf_ok=True)
    with pytest.raises(TypeError, match=r"\(str, not a number\)"):
        check_threshold("guided_eps", "0.1", positive=True)


def test_check_iterations_stops_at_a_thousand():
    """10**9 iterations ran for hours (each is a pass over the image); counts stop at MAX_ITERATIONS."""
    from nfdepth._validate import MAX_ITERATIONS, check_iterations

    assert check_iterations("edge_iterations", 0, 0) == 0 and check_iterations("edge_iterations", MAX_ITERATIONS, 0) == MAX_ITERATIONS
    with pytest.raises(ValueError, match=r"^iterations_per_level = 1001 is more iterations than can help .*: expected 1 to 1000$"):
        check_iterations("iterations_per_level", 1001, 1)
    with pytest.raises(ValueError, match=r"^edge_iterations must be an integer >= 0, got -1$"):
        check_iterations("edge_iterations", -1, 0)
    with pytest.raises(TypeError, match=r"float; give an int such as 3"):
        check_iterations("edge_iterations", 3.0, 0)


def test_float32_images_refuse_intensities_whose_gradient_products_overflow():
    """Intensities of 1e17 made static stereo's float32 gradient products overflow (NumPy warnings, a wrong map); float32 work stops at 1e15."""
    from nfdepth._validate import MAX_FLOAT32_INTENSITY, as_image
    from nfdepth.fast import normal_flow_edges
    from nfdepth.stereo import static_stereo

    img = np.random.default_rng(0).random((24, 32)) * MAX_FLOAT32_INTENSITY
    assert as_image("im", img).dtype == np.float32  # the bound itself is accepted
    with pytest.raises(ValueError, match=r"^im has intensities up to 2e\+15, beyond 1e\+15: the float32 work squares gradients, .*rescale the intensities"):
        as_image("im", np.full((4, 4), -2e15))
    assert as_image("im", np.full((4, 4), 1e30), np.float64).max() == 1e30  # float64 work has room
    with pytest.raises(ValueError, match=r"^im contains 1 non-finite"):  # NaN and inf are still named as such
        as_image("im", np.where(np.eye(4, dtype=bool) & (np.arange(4) == 0), np.nan, 1e20))
    views = [np.random.default_rng(k).random((24, 32)) * 1e17 for k in range(3)]
    with pytest.raises(ValueError, match=r"views\[0\] has intensities up to .*, beyond 1e\+15"):
        static_stereo(views, reference=1)
    with pytest.raises(ValueError, match=r"frames\[0\] has intensities up to"):
        normal_flow_edges(views, sigma_px=1.0)


def test_images_whose_intensities_are_too_small_for_float32_squares_are_refused_where_asked():
    """``min_peak`` (the fast path passes MIN_FLOAT32_INTENSITY = 1e-15): a non-zero peak below it is refused, with
    the advice to rescale; zero is no scale and passes, as do NaN (reported as such) and images without the option."""
    from nfdepth._validate import MIN_FLOAT32_INTENSITY, as_frames, as_image

    tiny = np.full((4, 4), -3e-16)
    with pytest.raises(ValueError, match=r"^im has intensities only up to 3e-16, below 1e-15: the float32 work squares gradients, which underflow below about 1e-19; rescale the intensities \(e\.g\. to 0-255 or 0-1\)$"):
        as_image("im", tiny, min_peak=MIN_FLOAT32_INTENSITY)
    with pytest.raises(ValueError, match=r"^frames\[1\] has intensities only up to 3e-16, below 1e-15"):
        as_frames("frames", [np.ones((4, 4)), tiny], min_peak=MIN_FLOAT32_INTENSITY)
    assert as_image("im", tiny).min() == np.float32(-3e-16)  # the reference path (np.hypot) takes them
    assert as_image("im", np.full((4, 4), 1e-15), min_peak=MIN_FLOAT32_INTENSITY).max() == np.float32(1e-15)  # the bound itself
    assert not as_image("im", np.zeros((4, 4)), min_peak=MIN_FLOAT32_INTENSITY).any()
    with pytest.raises(ValueError, match=r"^im contains 16 non-finite"):
        as_image("im", np.full((4, 4), np.nan), min_peak=MIN_FLOAT32_INTENSITY)


def test_native_byte_order():
    """Big-endian arrays (what OpenCV would read as garbage) come back native, with their values; native ones as they are."""
    from nfdepth._validate import as_image, native

    a = np.arange(12, dtype=np.float32).reshape(3, 4)
    for kind in (">f4", ">f8", ">i2", "<f4", "=f8"):
        got = native(a.astype(kind))
        assert got.dtype.isnative and got.dtype.kind == np.dtype(kind).kind and got.dtype.itemsize == np.dtype(kind).itemsize
        np.testing.assert_array_equal(got, a)
    assert native(a) is a
    assert as_image("im", a.astype(">f8")).dtype == np.float32 and as_image("im", a.astype(">f4"), np.float64).dtype.isnative


class _BytesPath:
    def __fspath__(self):
        return b"view.png"


def test_paths_refuse_what_is_no_path_with_the_parameters_name():
    """Every public reader and writer names its path parameter and the type it got (not pathlib's
    "expected str, bytes or os.PathLike object"); str and os.PathLike are taken as they are."""
    from pathlib import Path

    from nfdepth._validate import as_path
    from nfdepth.io import make_output_folder, read_image, read_pfm, write_array
    from nfdepth.plot import save_figure
    from nfdepth.rig import load_poses, load_rig
    from nfdepth.video import read_video, write_video_frame

    assert as_path("path", "a/b.png") == Path("a/b.png") and as_path("path", Path("c.pfm")) == Path("c.pfm")
    calls = [
        (read_image, ()), (read_pfm, ()), (load_rig, ()), (load_poses, ()), (read_video, ()), (make_output_folder, ()),
        (write_array, (np.zeros((2, 2)),)), (save_figure, None), (write_video_frame, None),
    ]
    for bad, got in ((None, "NoneType"), (3, "int"), (b"view.png", "bytes"), (_BytesPath(), "_BytesPath")):
        for fn, rest in calls:
            if fn is save_figure:
                args, name = (None, bad), "path"
            elif fn is write_video_frame:
                args, name = (None, bad), "folder"
            else:
                args, name = (bad, *rest), "path"
            with pytest.raises(TypeError, match=rf"^{name} must be a file path \(str or os\.PathLike\), got {got}$"):
                fn(*args)
