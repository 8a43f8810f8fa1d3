"""Views that move across the baseline (a row given as a column, or the reverse) are named.

For motions too small for the cost volume to lose its matches (sub-pixel to a
few px per view) only the global shift of the views says that they move along
the other axis (:func:`nfdepth.stereo._shift_message`); for larger ones the
coarse search across the baseline says it (tests/test_search_range.py). Either
way there is one warning.
"""

import re
import warnings

import numpy as np
import pytest
from scipy import ndimage
from textured_planes import slanted_plane_views

from nfdepth.stereo import _shift_message, _view_shifts, static_stereo
from nfdepth.xy_stereo import static_stereo_xy

SHAPE = (96, 128)
ACROSS = "across the baseline"


def _base(shape=SHAPE, seed=7):
    """A smooth random texture (std 30 grey levels about 128), with a margin for the shifts."""
    rng = np.random.default_rng(seed)
    big = ndimage.gaussian_filter(rng.normal(size=(shape[0] + 16, shape[1] + 16)), 1.5)
    return 128.0 + 30.0 * big / big.std()


def _line(step, axis, n=3, shape=SHAPE):
    """``n`` views of one texture, the camera moving toward +X (axis "x") or +Y by ``step`` px per view:
    the scene shifts toward -col (-row); the middle view is the reference."""
    base = _base(shape)
    views = []
    for k in range(n):
        s = -(k - n // 2) * step
        moved = ndimage.shift(base, (0.0, s) if axis == "x" else (s, 0.0), order=3, mode="nearest")
        views.append(moved[8:-8, 8:-8].astype(np.float32))
    return views


def _messages(fn, *args, **kwargs):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fn(*args, **kwargs)
    return result, [str(w.message) for w in caught]


@pytest.mark.parametrize("step", [0.5, 2.0])
@pytest.mark.parametrize("moving", ["x", "y"])
def test_the_shift_is_measured(step, moving):
    """The global shift (col, row) of each view against the reference, to 0.1 px."""
    shifts = _view_shifts(_line(step, moving), 1)
    assert shifts[1] is None
    for k, sign in ((0, 1.0), (2, -1.0)):
        expected = (sign * step, 0.0) if moving == "x" else (0.0, sign * step)
        np.testing.assert_allclose(shifts[k], expected, atol=0.1)


@pytest.mark.parametrize("d", [1.0, 3.0])
def test_every_view_is_measured_as_in_a_pair_of_its_own(d):
    """A sum of sinusoids (phase-correlation centroid biased: 1 px read as 0.49): the
    Lucas-Kanade steps find the shift; the views are left as they were (cv2.phaseCorrelate
    windows its inputs in place), so every view is measured as alone with the reference."""
    views = slanted_plane_views(d, 0.0, shape=(64, 96), noise=1.0)[0]
    copies = [v.copy() for v in views]
    shifts = _view_shifts(views, 1)
    for k, sign in ((0, 1.0), (2, -1.0)):
        np.testing.assert_allclose(shifts[k], (sign * d, 0.0), atol=0.05)
        assert shifts[k] == _view_shifts([views[1], views[k]], 0)[1]
    for v, c in zip(views, copies):
        np.testing.assert_array_equal(v, c)


@pytest.mark.parametrize("step", [0.5, 2.0])
@pytest.mark.parametrize("axis", ["x", "y"])
def test_the_check_names_views_moving_across_the_axis(step, axis):
    """The check alone, at both motions (at 2 px static_stereo's coarse search speaks first)."""
    other = "y" if axis == "x" else "x"
    views = _line(step, other)
    message = _shift_message(views, 1, axis=axis)
    line = "row" if axis == "x" else "column"
    assert message.startswith(f"views 0 and 2 of the {line} (axis='{axis}') shift by ("), message
    assert f"px (col, row) against its reference view 1: the scene moves along {other}, {ACROSS}. Give axis='{other}' (--axis {other})" in message
    pairs = [tuple(map(float, p)) for p in re.findall(r"\(([+-]\d+\.\d\d), ([+-]\d+\.\d\d)\)", message)]
    assert len(pairs) == 2
    across = [p[1] if axis == "x" else p[0] for p in pairs]
    along = [p[0] if axis == "x" else p[1] for p in pairs]
    np.testing.assert_allclose(across, [step, -step], atol=0.1)
    np.testing.assert_allclose(along, [0.0, 0.0], atol=0.05)
    assert _shift_message(views, 1, axis=other) is None


@pytest.mark.parametrize("cost_volume", [True, False])
@pytest.mark.parametrize("axis", ["x", "y"])
def test_small_motions_across_the_axis_warn_once(axis, cost_volume):
    """0.5 px per view across the baseline: the cost volume matches, silently wrong, so the
    global shift warns -- once, without the wrong-order warning of the map's signs."""
    other = "y" if axis == "x" else "x"
    _, messages = _messages(static_stereo, _line(0.5, other), reference=1, axis=axis, cost_volume=cost_volume)
    assert len(messages) == 1, messages
    assert f"the scene moves along {other}, {ACROSS}. Give axis='{other}' (--axis {other})" in messages[0]


@pytest.mark.parametrize("axis", ["x", "y"])
def test_larger_motions_across_the_axis_warn_once(axis):
    """2 px per view: the coarse search across the baseline warns (its own message, ending
    with the same advice); the global shift adds no second warning."""
    other = "y" if axis == "x" else "x"
    _, messages = _messages(static_stereo, _line(2.0, other), reference=1, axis=axis)
    assert len(messages) == 1, messages
    assert f"do the views move along {other}?" in messages[0]
    assert f"Give axis='{other}' (--axis {other})" in messages[0]


@pytest.mark.parametrize("step", [0.5, 2.0])
@pytest.mark.parametrize("axis", ["x", "y"])
def test_the_right_axis_gives_no_warning(step, axis):
    result, messages = _messages(static_stereo, _line(step, axis), reference=1, axis=axis)
    assert messages == []
    assert np.nanmedian(result.disparity) == pytest.approx(step, abs=0.05)


def test_views_in_the_wrong_order_are_no_axis_mix_up():
    """Reversed views move along the axis (the other way): the wrong-order warning only."""
    _, messages = _messages(static_stereo, _line(1.0, "x")[::-1], reference=1)
    assert messages and all(ACROSS not in m for m in messages)
    assert any("wrong order" in m for m in messages), messages


def test_identical_views_warn_only_as_identical():
    view = _line(0.5, "x")[1]
    _, messages = _messages(static_stereo, [view, view.copy(), view.copy()], reference=1)
    assert [m for m in messages if "same image" in m] and all(ACROSS not in m for m in messages), messages
    assert _view_shifts([view, view], 0)[1] == (0.0, 0.0)


@pytest.mark.parametrize(
    "views",
    [
        [np.full((40, 48), 100.0, np.float32)] * 3,  # constant: no phase-correlation peak
        [np.float32(100.0 + 30.0 * np.random.default_rng(k).random((40, 48))) for k in range(3)],  # unrelated
        [np.float32(100.0 + 30.0 * np.random.default_rng(k).random((8, 9))) for k in range(3)],  # too small to measure
        [np.tile(np.float32(100.0 + 30.0 * np.sin(np.arange(48) / 2.0)), (40, 1))] * 3,  # parallel lines
    ],
    ids=["constant", "unrelated", "tiny", "stripes"],
)
def test_nothing_to_measure_is_no_warning(views):
    assert _shift_message(views, 1, axis="x") is None
    assert _shift_message(views, 1, axis="y") is None


def test_a_horizontal_column_in_the_xy_fusion_is_named():
    row = _line(0.5, "x")
    _, messages = _messages(static_stereo_xy, row, row, row_reference=1, column_reference=1)
    assert len(messages) == 1, messages
    assert messages[0].startswith("views 0 and 2 of the column (axis='y') shift by (+0.5"), messages[0]
    assert "the views of the column (--column) lie on a vertical line" in messages[0]
    _, messages = _messages(static_stereo_xy, row, _line(0.5, "y"), row_reference=1, column_reference=1)
    assert messages == []


@pytest.fixture
def line_files(tmp_path):
    """The row and the column (through one reference view) as .npy files."""
    from nfdepth.io import write_array

    names = {}
    for moving in ("x", "y"):
        for k, view in enumerate(_line(0.5, moving)):
            names[moving, k] = str(write_array(tmp_path / f"{moving}{k}.npy", view))
    names["y", 1] = names["x", 1]
    return names


@pytest.mark.parametrize(
    ("main", "column", "warned"),
    [
        ("x", "x", "views 0 and 2 of the column (axis='y')"),  # the row given as the column too
        ("y", None, "views 0 and 2 of the row (axis='x')"),  # a column run as a row
        ("x", "y", None),
        ("x", None, None),
    ],
)
def test_cli_names_a_row_column_mix_up_in_one_line(line_files, tmp_path, capsys, main, column, warned):
    from nfdepth.cli import main as cli

    argv = ["stereo", *(line_files[main, k] for k in range(3))]
    if column:
        argv += ["--column", *(line_files[column, k] for k in range(3))]
    code = cli([*argv, "--out", str(tmp_path / "d.pfm")])
    _, err = capsys.readouterr()
    assert code == 0, err
    if warned is None:
        assert err == ""
    else:
        assert err.count("\n") == 1 and err.startswith(f"nfdepth: warning: {warned} shift by ("), err
        assert ACROSS in err
