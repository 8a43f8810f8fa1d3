"""Static stereo with x and y baselines together: a row and a column of views.

An edge parallel to the baseline does not move along its normal, so one row
of views cannot measure it (``B = 0`` in eq. 4; ``Reason.UNDETERMINABLE``
below ``min_cos``), and an edge at a small angle to it is measured with the
weight ``cos^2``. The paper's own suggested fix is a second baseline at right
angles: a column of views through the same reference camera (a plus-shaped
rig, or the middle row and column of a camera grid) measures the same edge
with the weight ``sin^2``.

:func:`static_stereo_xy` runs :func:`nfdepth.static_stereo` along the row
(``axis="x"``) and along the column (``axis="y"``) and combines the two per
pixel by weighted least squares on inverse depth (disparity ``d = f b / Z``
per unit of position is inverse depth up to the factor ``f b``, the same on
both axes when both lists of positions are in the same unit). Each axis's
estimate is itself the weighted least-squares solution of its own relative
normal flows (eq. 4 / 6), with the variance ``sigma^2``; the two sets of
measurements are independent, so the joint solution over every relative
normal flow of the point is the inverse-variance mean

.. math::
    \\hat d = \\frac{d_x / \\sigma_x^2 + d_y / \\sigma_y^2}{1 / \\sigma_x^2 + 1 / \\sigma_y^2},
    \\qquad \\sigma^2 = \\frac{\\max(1, \\chi^2)}{1 / \\sigma_x^2 + 1 / \\sigma_y^2},
    \\qquad \\chi^2 = \\frac{(d_x - d_y)^2}{\\sigma_x^2 + \\sigma_y^2},

the variance scaled by the reduced chi^2 of the two when they disagree more
than their errors allow (as :func:`nfdepth.static_stereo` does with its own
residuals). A pixel measured along one axis only keeps that axis's value and
standard deviation. Where the two disagree both beyond
``max_axis_disagreement_px`` (px of disparity at the smallest spacing of
neighbouring views of either line, so whatever the positions' unit) and
beyond three standard deviations of their difference (typically a depth
step, which the row and the column see occluded on different sides), the
pixel is ``Reason.UNCERTAIN``.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np

from ._validate import as_frames, check_positive_or_inf, check_view_index, check_within
from .depth import Reason
from .stereo import StereoResult, static_stereo

__all__ = ["XYStereoResult", "fuse_axes", "static_stereo_xy"]

#: Where neither axis has a value: the reason reported, most specific first
#: (an axis that measured the point but doubted it says more than one that
#: could not measure it at all).
_REASON_PRIORITY = (Reason.UNCERTAIN, Reason.NOT_POSITIVE, Reason.NO_DATA, Reason.UNDETERMINABLE, Reason.CORNER, Reason.NOT_EDGE)

#: Variance floor (px^2) for the weights: a std of exactly 0 (``noise_std=0``
#: on noise-free input) would give an infinite weight.
_MIN_VARIANCE = 1e-12

# options that belong to one axis: the row's and column's own arguments
_PER_AXIS = ("views", "reference", "positions", "axis")


@dataclass(frozen=True)
class XYStereoResult(StereoResult):
    """A :class:`~nfdepth.stereo.StereoResult` fused from a row and a column of views.

    ``disparity`` (px per unit of position), ``uncertainty``, ``edge_mask``
    (edge points of either axis) and ``reason`` are the fused maps; ``row``
    and ``column`` are the two axes' own results (the column's in the
    reference image's orientation), ``axis_count`` the number of axes that
    measured each pixel (0, 1 or 2) and ``conflict`` the pixels where both
    did and disagreed (``Reason.UNCERTAIN``). ``runtime_s`` covers both
    axes and the fusion; ``noise_std`` is the row's; ``search_range_px``
    spans both axes' search ranges. ``exposure`` is None: each axis's
    exposures are its own (``row.exposure``, ``column.exposure``); ``axis``
    is ``"x"``, so :meth:`filled` fills along the rows.
    """

    row: StereoResult | None = None
    column: StereoResult | None = None
    axis_count: np.ndarray | None = None
    conflict: np.ndarray | None = None


def _smallest_step(positions) -> float:
    """The smallest spacing of neighbouring views of one line (``positions`` as static stereo took them; None: step 1)."""
    return 1.0 if positions is None else float(np.min(np.diff(np.asarray(positions, dtype=np.float64))))


def _union_range(a, b):
    """The smallest range holding the search ranges ``a`` and ``b`` (None where an axis has none)."""
    if a is None or b is None:
        return None
    return (min(a[0], b[0]), max(a[1], b[1]))


def _merged_reason(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per pixel, the more specific of two non-OK reasons (:data:`_REASON_PRIORITY`)."""
    rank = np.zeros(256, np.uint8)
    for i, code in enumerate(_REASON_PRIORITY):
        rank[int(code)] = len(_REASON_PRIORITY) - i
    return np.where(rank[a] >= rank[b], a, b).astype(np.uint8)


#: The row and the column measure one scene per unit of position: where the column's disparities are a median of
#: more than this factor above or below the row's (at the pixels both measure, of at least _AXES_MIN_BOTH), or where
#: more than _AXES_CONFLICT_SHARE of those pixels are refused for disagreeing, a warning says so (positions in two
#: units, or misstated). Measured with the spacing right: the bundled pyramid's row and column 1.000, Art's row with
#: a column made from view 1 warped by the truth 1.00; misstated by a factor of 2 either way 0.50 / 1.99 (the fused
#: map had kept 7.8-16 % of Art's pixels, without a word). A column spacing 5 % off biased the fused map by 2.6 %
#: and one 10-14 % off left 0.5-0.6 % of it (the rest refused), both without a word at the factor of 1.15 this was.
_AXES_SCALE = 1.04
_AXES_CONFLICT_SHARE = 0.5
_AXES_MIN_BOTH = 100


def _warn_if_axes_disagree(
    row, column, both: np.ndarray, conflict: np.ndarray, *, spacing: float = 1.0, positions: str = "row_positions / column_positions, --positions / --column-positions"
) -> None:
    """Warn when the column's disparities are a median scale apart from the row's, or mostly refused (positions in two units?).

    ``both``: the pixels fused from both lines; ``conflict``: those both
    lines measured but that were refused for disagreeing; ``spacing``: as
    for :func:`fuse_axes` (the row's disparities times it are px: a
    disparity below 0.25 px gives no ratio to trust).
    """
    measured = both | conflict
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = column.disparity[measured] / row.disparity[measured]
    ratio = ratio[np.isfinite(ratio) & (np.abs(row.disparity[measured]) * spacing >= 0.25)]
    if ratio.size < _AXES_MIN_BOTH:
        return
    scale = float(np.median(ratio))
    n = int(np.count_nonzero(measured))
    refused = np.count_nonzero(conflict) / n
    if 1.0 / _AXES_SCALE <= scale <= _AXES_SCALE and refused <= _AXES_CONFLICT_SHARE:
        return
    warnings.warn(
        f"the column's disparities are a median {scale:.3g} times the row's at the {n} pixels both measure ({100.0 * refused:.0f} %"
        " refused for disagreeing, UNCERTAIN), where one scene gives both the same per unit of position; are both lines'"
        f" positions right, in one unit ({positions})?",
        UserWarning,
        stacklevel=3,
    )


def fuse_axes(row: StereoResult, column: StereoResult, *, max_axis_disagreement_px: float = 0.5, spacing: float = 1.0):
    """Fuse two disparity maps of one reference view (module docstring).

    ``row``, ``column``: :class:`~nfdepth.stereo.StereoResult` or anything
    with ``disparity``, ``uncertainty`` and ``reason`` maps in one unit
    (:func:`nfdepth.rectify.calibrated_grid_depth` passes two calibrated
    lines' inverse depths so). ``spacing``: the neighbour spacing, in the
    unit of position, at which ``max_axis_disagreement_px`` is counted (the
    maps times ``spacing`` are px; 1 for maps in px already); the result
    does not depend on the positions' unit.

    Returns ``(disparity, uncertainty, reason, axis_count, conflict)``:
    float32 maps with NaN where no value, uint8 reasons, the number of axes
    with a value, and the pixels refused for disagreeing.
    """
    limit = check_positive_or_inf("max_axis_disagreement_px", max_axis_disagreement_px)
    spacing = check_within("spacing", spacing, advice="the smallest spacing of neighbouring views, in the unit of position")
    for name, part in (("row", row), ("column", column)):
        if not all(hasattr(part, a) for a in ("disparity", "uncertainty", "reason")):
            msg = f"{name} must be a StereoResult (or have disparity, uncertainty and reason maps), got {type(part).__name__}"
            raise TypeError(msg)
    if row.disparity.shape != column.disparity.shape:
        msg = f"the row's and the column's maps must have one shape, got {row.disparity.shape} and {column.disparity.shape}"
        raise ValueError(msg)
    ok_x = row.reason == Reason.OK
    ok_y = column.reason == Reason.OK
    both = ok_x & ok_y
    dx = np.where(ok_x, row.disparity, 0.0).astype(np.float64)
    dy = np.where(ok_y, column.disparity, 0.0).astype(np.float64)
    floor = _MIN_VARIANCE / spacing**2  # _MIN_VARIANCE px^2 in the maps' unit
    vx = np.maximum(np.where(ok_x, row.uncertainty, 1.0).astype(np.float64) ** 2, floor)
    vy = np.maximum(np.where(ok_y, column.uncertainty, 1.0).astype(np.float64) ** 2, floor)
    wx, wy = 1.0 / vx, 1.0 / vy
    diff = dx - dy
    chi2 = diff**2 / (vx + vy)
    fused = (wx * dx + wy * dy) / (wx + wy)
    fused_var = np.maximum(chi2, 1.0) / (wx + wy)
    disparity = np.where(both, fused, np.where(ok_x, dx, dy))
    variance = np.where(both, fused_var, np.where(ok_x, vx, vy))
    conflict = both & (np.abs(diff) * spacing > limit) & (chi2 > 9.0)
    reason = np.where(ok_x | ok_y, np.uint8(Reason.OK), _merged_reason(row.reason, column.reason)).astype(np.uint8)
    reason[conflict] = Reason.UNCERTAIN
    bad = reason != Reason.OK
    disparity = np.where(bad, np.nan, disparity).astype(np.float32)
    std = np.where(bad, np.nan, np.sqrt(variance)).astype(np.float32)
    count = (ok_x.astype(np.uint8) + ok_y.astype(np.uint8)).astype(np.uint8)
    return disparity, std, reason, count, conflict


def static_stereo_xy(
    row_views,
    column_views,
    *,
    row_reference: int,
    column_reference: int,
    row_positions=None,
    column_positions=None,
    max_axis_disagreement_px: float = 0.5,
    **options,
) -> XYStereoResult:
    """Disparity of one reference view from a row and a column of views (x and y baselines).

    Parameters
    ----------
    row_views : sequence of >= 2 ndarray (H, W)
        Views along a horizontal line, ordered so that the camera moves
        toward +X from first to last (as :func:`nfdepth.static_stereo`).
    column_views : sequence of >= 2 ndarray (H, W)
        Views along a vertical line through the same reference camera,
        ordered so that the camera moves toward +Y (image rows down) from
        first to last: scene points shift toward -row.
    row_reference, column_reference : int
        Index of the shared reference view in each list; the two must be the
        same image (pixel for pixel).
    row_positions, column_positions : sequence of float, optional
        Camera positions along each line, **in one unit for both** (default:
        equally spaced, step 1, i.e. the row's and the column's neighbour
        spacing are assumed equal). The output is disparity per unit of
        position, so give both when the spacings differ.
    max_axis_disagreement_px : float
        A pixel measured on both axes whose two disparities differ by more
        than this many px at the smallest spacing of neighbouring views of
        either line (the disparities per unit of position times that
        spacing: the same refusals whatever the positions' unit) and by more
        than three standard deviations of their difference is ``UNCERTAIN``
        (``inf``: never).
    **options
        Any other keyword argument of :func:`nfdepth.static_stereo`
        (``edges_only``, ``sigma_px``, ``levels``, ``noise_std``, ``threads``,
        ...), used for both axes.

    Returns
    -------
    XYStereoResult
        The fused maps, with the two axes' own results in ``row`` and
        ``column``.

    Raises
    ------
    TypeError
        An option meant per axis (``views``, ``reference``, ``positions``,
        ``axis``) is given in ``options``.
    ValueError, TypeError
        The two reference views differ or have different shapes, or any
        check of :func:`nfdepth.static_stereo` fails (the message says
        which axis).
    """
    start = time.perf_counter()
    clash = sorted(k for k in options if k in _PER_AXIS)
    if clash:
        msg = f"{', '.join(clash)} {'belongs' if len(clash) == 1 else 'belong'} to one axis: use row_views / column_views, row_reference / column_reference and row_positions / column_positions"
        raise TypeError(msg)
    limit = check_positive_or_inf("max_axis_disagreement_px", max_axis_disagreement_px)
    rows = as_frames("row_views", row_views, min_count=2, dtype=np.float32)
    cols = as_frames("column_views", column_views, min_count=2, dtype=np.float32)
    row_reference = check_view_index("row_reference", row_reference, len(rows))
    column_reference = check_view_index("column_reference", column_reference, len(cols))
    ref_x, ref_y = rows[row_reference], cols[column_reference]
    if ref_x.shape != ref_y.shape:
        msg = f"the row's and the column's views must have one size, got {ref_x.shape} and {ref_y.shape}"
        raise ValueError(msg)
    if not np.array_equal(ref_x, ref_y):
        msg = (
            "the row's reference view and the column's must be the same image (the camera both lines pass through), "
            f"but they differ at {int(np.count_nonzero(ref_x != ref_y))} pixels"
        )
        raise ValueError(msg)
    results = {}
    said = []  # the axes' warnings, each said once (the two lines often share one: a range that misses the scene)
    for axis, views, ref, positions in (("x", rows, row_reference, row_positions), ("y", cols, column_reference, column_positions)):
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                results[axis] = static_stereo(views, reference=ref, positions=positions, axis=axis, **options)
        except (TypeError, ValueError) as exc:
            if type(exc) not in (TypeError, ValueError):
                raise
            which = "row" if axis == "x" else "column"
            raise type(exc)(f"{which}: {exc}") from exc
        known = {(str(m), type(m)) for m in said}
        said += [w.message for w in caught if (str(w.message), w.category) not in known]
    for message in said:
        warnings.warn(message, stacklevel=2)  # (the warning itself: a NoEdgePointsWarning keeps its rule and reason)
    row, column = results["x"], results["y"]
    # the disparities are per unit of position: in px at the smallest neighbour spacing of either line, whatever the unit
    spacing = min(_smallest_step(row_positions), _smallest_step(column_positions))
    disparity, std, reason, count, conflict = fuse_axes(row, column, max_axis_disagreement_px=limit, spacing=spacing)
    if not said:  # an axis's own warning says what is wrong with it
        _warn_if_axes_disagree(row, column, count == 2, conflict, spacing=spacing)
    edge_mask = row.edge_mask | column.edge_mask
    return XYStereoResult(
        disparity=disparity,
        uncertainty=std,
        edge_mask=edge_mask,
        reason=reason,
        levels=row.levels,
        runtime_s=time.perf_counter() - start,
        noise_std=row.noise_std,
        search_range_px=_union_range(row.search_range_px, column.search_range_px),
        row=row,
        column=column,
        axis_count=count,
        conflict=conflict,
    )
