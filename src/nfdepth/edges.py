"""Zero-crossing edge points with corner rejection (paper section 3.2).

The paper estimates normal flow only at *zero-crossing edge points*: zero
crossings of the Laplacian of the Gaussian-smoothed middle frame where the
gradient is strong. Corner points, whose gradient direction is not defined,
are disregarded. Here both rules work on the same 2 x 2 cell grid as the
gradients of :mod:`nfdepth.normal_flow`:

* a cell is a zero crossing when the Laplacian at its four corner pixels
  changes sign, one of them beyond float32 rounding (``ROUNDING_LAPLACIAN``
  times the largest smoothed intensity: a smooth ramp's rounding is no sign);
* a cell is *strong* when ``|grad I| >= min_gradient`` (intensity per pixel;
  by default a fraction of a high percentile of the image's gradient) and
  above float32 rounding, ``ROUNDING_GRADIENT`` times the largest smoothed
  intensity (:func:`rounding_gradient_floor`);
* a cell is a *corner* when the eigenvalue ratio ``lambda_2 / lambda_1`` of
  the structure tensor (gradient outer products averaged with a Gaussian
  window, built on the 2 x 2 block grid and read back bilinearly) exceeds
  ``max_corner_ratio``: along a straight edge the ratio is
  near 0, where two edge directions meet it grows toward 1. The rule needs
  no ground truth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ._quantile import percentile
from ._validate import (
    as_real,
    check_fraction,
    check_int,
    check_scale_px,
    check_threshold,
    is_real_numeric,
    native,
)
from .normal_flow import GradientField

#: Gradients below this fraction of the largest smoothed intensity are float32
#: rounding, not edges. Smoothing a flat image leaves ripples of a few 1e-8 of
#: its value (a constant 7, 50 x 60 px: |grad I| = 2e-7 at 46 cells), and a
#: threshold relative to the image's own gradients would accept them.
ROUNDING_GRADIENT = 1e-6

#: A Laplacian below this fraction of the largest smoothed intensity is float32
#: rounding (its five terms, each rounded to 2**-24 of the largest value, and
#: the sum), not a sign: a zero crossing needs one of its four corners beyond
#: it. A noise-free linear ramp has a Laplacian of rounding alone and gave
#: zero crossings at random cells (916 "edge points" on a 48 x 48 ramp).
ROUNDING_LAPLACIAN = 4e-6


def rounding_gradient_floor(smoothed_middle: np.ndarray) -> float:
    """Largest gradient magnitude that is float32 rounding of ``smoothed_middle``'s intensities (``ROUNDING_GRADIENT`` times its largest ``|value|``)."""
    a = np.asarray(smoothed_middle)
    return ROUNDING_GRADIENT * float(np.max(np.abs(a))) if a.size else 0.0

__all__ = [
    "EdgeSelection",
    "NoEdgePointsWarning",
    "laplacian_zero_crossings",
    "block_structure_tensor",
    "corner_ratio",
    "select_edge_points",
]


def laplacian_zero_crossings(smoothed: np.ndarray) -> np.ndarray:
    """Cells (2 x 2 pixel groups) across which the Laplacian changes sign.

    Parameters
    ----------
    smoothed : ndarray, shape (H, W)
        The Gaussian-smoothed middle frame (so the Laplacian is a LoG).

    Returns
    -------
    ndarray of bool, shape (H-1, W-1)
        True for cell ``[r, c]`` (centre ``(r + 0.5, c + 0.5)``) whose four
        corner pixels have Laplacian values of both signs, one of them beyond
        ``ROUNDING_LAPLACIAN`` times the largest ``|smoothed|`` (rounding is no sign).
    """
    img = np.asarray(smoothed)
    if img.ndim != 2 or min(img.shape) < 2 or not is_real_numeric(img):
        msg = f"smoothed must be a real 2-D image of at least 2x2 pixels, got dtype {img.dtype}, shape {img.shape}"
        raise ValueError(msg)
    if img.dtype.type in (np.float32, np.float64):
        img = native(img)  # a big-endian float array in its own precision (OpenCV would read its bytes as native numbers)
    else:
        img = img.astype(np.float64)  # OpenCV's Laplacian takes no int32/int64/bool input
    lap = cv2.Laplacian(img, -1, ksize=1, borderType=cv2.BORDER_REFLECT)
    corners = np.stack([lap[:-1, :-1], lap[:-1, 1:], lap[1:, :-1], lap[1:, 1:]])
    tol = ROUNDING_LAPLACIAN * float(np.max(np.abs(img)))
    return (corners.max(axis=0) > 0) & (corners.min(axis=0) < 0) & (np.abs(corners).max(axis=0) > tol)


def _corner_window_blocks(window_sigma_px: float) -> tuple[float, int]:
    """Gaussian of the block-grid structure tensor: ``(sigma, radius)`` in blocks.

    Variances add: the 2 x 2 block mean contributes 1/4 px^2 per axis and the
    bilinear read-back at a cell (weights 3/4, 1/4 at 2 px spacing) 3/4 px^2,
    so the block grid's Gaussian gets ``sqrt(window^2 - 1) / 2`` blocks and
    the whole window has the requested variance. Windows of 1 px or less
    get a minimal 0.1-block Gaussian: effectively a 1 px window.
    """
    window_sigma_px = check_scale_px("window_sigma_px", window_sigma_px, zero_ok=False)
    sigma = max(math.sqrt(max(window_sigma_px**2 - 1.0, 0.0)) / 2.0, 0.1)
    return sigma, max(1, int(math.ceil(3.0 * sigma)))


def block_structure_tensor(grad_col: np.ndarray, grad_row: np.ndarray, *, window_sigma_px: float) -> np.ndarray:
    """Structure tensor ``(J_cc, J_rr, J_cr)`` on the 2 x 2 block grid, shape (3, ceil(h/2), ceil(w/2)).

    Gradient outer products averaged over 2 x 2 blocks of cells (an odd last
    row or column is replicated), then smoothed with the Gaussian of
    :func:`_corner_window_blocks` (reflected border). Block ``[i, j]`` is
    centred on cell position ``(2i + 0.5, 2j + 0.5)``.

    Parameters
    ----------
    grad_col, grad_row : array_like, shape (h, w)
        Spatial derivatives ``I_col``, ``I_row`` at the cell centres (intensity per
        px, e.g. :class:`~nfdepth.normal_flow.GradientField`'s), non-empty, 2-D, of one
        shape; worked on in float64. A NaN spreads over the window.
    window_sigma_px : float
        Standard deviation in px (cells) of the whole window once read back at the
        cells, as :func:`corner_ratio` does: > 0, finite, at most 5000. The block grid
        gets a Gaussian of ``sqrt(window_sigma_px**2 - 1) / 2`` blocks (at least 0.1),
        truncated at 3 of its sigmas; windows of 1 px or less all get the minimal one.

    Returns
    -------
    ndarray of float64, shape (3, ceil(h/2), ceil(w/2))
        The planes ``J_cc``, ``J_rr``, ``J_cr``: windowed means of ``I_col**2``,
        ``I_row**2`` and ``I_col I_row``, in (intensity per px) squared.

    Raises
    ------
    ValueError
        ``grad_col`` and ``grad_row`` differ in shape, are not 2-D or are empty, or
        ``window_sigma_px`` is not positive, not finite or above 5000 (:data:`nfdepth._validate.MAX_SCALE_PX`).
    TypeError
        ``window_sigma_px`` is not a number (a str or bool too), or ``grad_col`` or
        ``grad_row`` is not real numbers (complex, text, objects).
    """
    sigma, radius = _corner_window_blocks(window_sigma_px)
    gc, gr = as_real("grad_col", grad_col), as_real("grad_row", grad_row)
    if gc.shape != gr.shape or gc.ndim != 2 or gc.size == 0:
        msg = f"grad_col and grad_row must be non-empty 2-D arrays of one shape, got {gc.shape} and {gr.shape}"
        raise ValueError(msg)
    h, w = gc.shape
    ksize = (2 * radius + 1, 2 * radius + 1)
    if h % 2 or w % 2:  # replicate the odd last row / column (its products are the replicated products)
        gc, gr = (cv2.copyMakeBorder(g, 0, h % 2, 0, w % 2, cv2.BORDER_REPLICATE) for g in (gc, gr))
    # the four cells of every block, as strided views: the products are taken block-sized (no
    # full-grid temporaries, whose fresh pages cost more than the arithmetic)
    cells = [(gc[i::2, j::2], gr[i::2, j::2]) for i in (0, 1) for j in (0, 1)]
    out = np.empty((3, (h + 1) // 2, (w + 1) // 2))
    for dst, (a, b) in zip(out, ((0, 0), (1, 1), (0, 1))):
        block = cells[0][a] * cells[0][b]
        for cell in cells[1:]:
            block += cell[a] * cell[b]
        block *= 0.25
        cv2.GaussianBlur(block, ksize, sigma, dst=dst, borderType=cv2.BORDER_REFLECT)
    return out


def _block_read_back(n: int, blocks: int):
    """Bilinear weights from the block grid back to ``n`` cells along one axis.

    Cell ``y`` sits at block coordinate ``(y - 0.5) / 2``: between blocks
    ``lo = (y - 1) // 2`` and ``lo + 1``, with weight 3/4 on the nearer one;
    indices are clamped to the grid (replicated border).
    """
    y = np.arange(n)
    lo = (y - 1) // 2
    w_hi = np.where(y % 2 == 0, 0.75, 0.25)
    return np.clip(lo, 0, blocks - 1), np.clip(lo + 1, 0, blocks - 1), 1.0 - w_hi, w_hi


def _read_back(tensor: np.ndarray, shape) -> np.ndarray:
    """The block tensor (3, hb, wb) read back at every cell of ``shape``: the
    bilinear weights of :func:`_block_read_back` on both axes.

    ``cv2.resize`` (``INTER_LINEAR``, exact 2x) maps cell ``y`` to ``y / 2 -
    1/4`` blocks with replicated edges: the same weights (3/4, 1/4), in its
    own summation order (within 1e-15 relative of the separable formula,
    tests/test_edges.py).
    """
    h, w = shape
    hb, wb = tensor.shape[1:]
    out = np.empty((3, h, w))
    # plane by plane into contiguous planes (the same values as one resize of the three merged:
    # its channels are interpolated alike), several times faster than de-interleaving a merged result
    for plane, dst in zip(tensor, out):
        dst[...] = cv2.resize(np.ascontiguousarray(plane), (2 * wb, 2 * hb), interpolation=cv2.INTER_LINEAR)[:h, :w]
    return out


def corner_ratio(grad_col: np.ndarray, grad_row: np.ndarray, *, window_sigma_px: float) -> np.ndarray:
    """Structure-tensor eigenvalue ratio ``lambda_2 / lambda_1`` in [0, 1] at every cell.

    0 on a straight edge (one gradient direction in the window), near 1 at
    corners and junctions, NaN where the window holds no gradient at all.
    The tensor is :func:`block_structure_tensor` read back at each cell by
    bilinear interpolation: a window of ``window_sigma_px`` (variance
    matched) at a quarter of a full-grid Gaussian's samples, so that the
    fast path's share of it costs a fraction of one smoothing pass. At edge
    points its ratio is within ~0.005 (90th percentile) of a full-grid
    Gaussian window's for windows of 2 px or more, ~0.014 at 1-1.5 px
    (tests/test_edges.py).

    Parameters
    ----------
    grad_col, grad_row : array_like, shape (h, w)
        Spatial derivatives at the cell centres, as in :func:`block_structure_tensor`.
    window_sigma_px : float
        Standard deviation of the Gaussian window in px (> 0, finite, at most 5000);
        ``corner_window_px`` of :func:`select_edge_points`.

    Returns
    -------
    ndarray of float64, shape (h, w)
        ``lambda_2 / lambda_1``, the smaller over the larger eigenvalue of the
        windowed tensor at each cell, within [0, 1]; NaN where the window holds no
        gradient (``lambda_1 = 0``) or reaches a NaN gradient.

    Raises
    ------
    ValueError
        ``grad_col`` and ``grad_row`` differ in shape, are not 2-D or are empty, or
        ``window_sigma_px`` is not positive, not finite or above 5000 (:data:`nfdepth._validate.MAX_SCALE_PX`).
    TypeError
        ``window_sigma_px`` is not a number (a str or bool too), or ``grad_col`` or
        ``grad_row`` is not real numbers (complex, text, objects).
    """
    jxx, jyy, jxy = _read_back(block_structure_tensor(grad_col, grad_row, window_sigma_px=window_sigma_px), np.shape(grad_col))
    # 0.5 (jxx + jyy) +/- sqrt(max(0.25 (jxx - jyy)^2 + jxy^2, 0)), in place in the read-back's planes
    # (fresh full-grid float64 temporaries cost more than the arithmetic)
    half_trace = np.add(jxx, jyy)
    half_trace *= 0.5
    root = np.subtract(jxx, jyy, out=jxx)
    root *= root
    root *= 0.25
    root += np.multiply(jxy, jxy, out=jxy)
    np.sqrt(np.maximum(root, 0.0, out=root), out=root)
    lam1 = np.add(half_trace, root, out=jyy)
    lam2 = np.maximum(np.subtract(half_trace, root, out=root), 0.0, out=root)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.divide(lam2, lam1, out=lam2)
    ratio[lam1 <= 0] = np.nan
    return ratio


@dataclass(frozen=True)
class EdgeSelection:
    """Which cells are usable edge points, and why the others are not.

    Attributes
    ----------
    mask : ndarray of bool, shape (H-1, W-1)
        Strong zero-crossing edge points that are not corners.
    zero_crossing, strong : ndarray of bool, shape (H-1, W-1)
        The individual rules.
    corner : ndarray of bool, shape (H-1, W-1)
        The corner rule where it decides: strong zero crossings whose
        ``corner_ratio`` exceeds ``max_corner_ratio`` (the rule alone is
        ``corner_ratio > max_corner_ratio``).
    min_gradient : float
        The gradient threshold used (intensity per pixel).
    corner_ratio : ndarray, shape (H-1, W-1)
        The structure-tensor eigenvalue ratio.
    border_px : int
        The border used: ``mask`` leaves out the ``border_px`` outermost rows and
        columns of cells (all cells when the grid is not larger than ``2 border_px``).
    """

    mask: np.ndarray
    zero_crossing: np.ndarray
    strong: np.ndarray
    corner: np.ndarray
    min_gradient: float
    corner_ratio: np.ndarray
    border_px: int = 0


def _inside(shape, border_px: int) -> np.ndarray:
    """Cells at least ``border_px`` from every side of a grid of ``shape`` (none when it is not larger than ``2 border_px``)."""
    inside = np.zeros(shape, bool)
    b = border_px
    if shape[0] > 2 * b and shape[1] > 2 * b:
        inside[b : shape[0] - b, b : shape[1] - b] = True
    return inside


class NoEdgePointsWarning(UserWarning):
    """No point of an image passed the edge rules (section 3.2): the result has no edge point.

    Filter it by category (``warnings.filterwarnings("ignore",
    category=nfdepth.NoEdgePointsWarning)``) or read why from its attributes
    (empty for one raised from a message alone, ``warnings.warn(text,
    NoEdgePointsWarning)``).

    Attributes
    ----------
    rule : str
        The first rule that left none: ``"zero crossing"`` (no zero crossing of the
        Laplacian: a textureless image), ``"gradient"`` (none reaches the gradient
        threshold), ``"corner"`` (all strong ones are corners) or ``"border"`` (the rest
        lie too near the border).
    reason : str
        Why, in words (the message after "no edge points: ", without ``hint``).
    hint : str
        The option that would keep some, in parentheses, or "".
    consequence : str
        What the caller does without them (the message's last part after "; "), or "".
    """

    def __init__(self, message: str = "", *, rule: str = "", reason: str = "", hint: str = "", consequence: str = ""):
        super().__init__(message)
        self.rule, self.reason, self.hint, self.consequence = rule, reason, hint, consequence


def _no_edge_points(reason: str, rule: str, hint: str = "", consequence: str = "") -> NoEdgePointsWarning:
    """The warning whose message is "no edge points: REASON[ HINT][; CONSEQUENCE]"."""
    message = "no edge points: " + reason + (f" {hint}" if hint else "") + (f"; {consequence}" if consequence else "")
    return NoEdgePointsWarning(message, rule=rule, reason=reason, hint=hint, consequence=consequence)


def _no_edge_points_warning(
    selection: EdgeSelection, where: str = "", *, border: str = "within border_px of the border", consequence: str = ""
) -> NoEdgePointsWarning:
    """Why ``selection`` holds no edge point: the first rule that left none.

    ``where`` (e.g. " in the reference image") follows the rule's name;
    ``border`` says where the border rule left them (in the caller's
    options); ``consequence`` ends the message. The corner rule is judged on
    the cells inside the border (``selection.border_px``) first: where strong
    zero crossings lie there, all of them corners, the corner rule is to blame
    even if some non-corner ones lie in the border band; the border only where
    none lies inside.
    """
    zero = selection.zero_crossing
    if not zero.any():
        return _no_edge_points(f"the images are textureless (no zero crossing of the Laplacian{where})", "zero crossing", consequence=consequence)
    strong = zero & selection.strong
    if not strong.any():
        return _no_edge_points(
            f"the images are textureless (no zero crossing{where} reaches the gradient threshold "
            f"{selection.min_gradient:.4g} nor float32 rounding's; lower min_gradient if that is too high)",
            "gradient",
            consequence=consequence,
        )
    kept = strong & ~selection.corner
    hint = "(raise max_corner_ratio to keep some)"
    if not kept.any():
        return _no_edge_points(f"all {int(np.count_nonzero(strong))} strong zero crossings{where} are corners", "corner", hint, consequence)
    inner = strong & _inside(strong.shape, selection.border_px)
    if inner.any():  # the non-corner ones all lie in the border band, the ones inside are all corners
        return _no_edge_points(f"all {int(np.count_nonzero(inner))} strong zero crossings{where} away from the border are corners", "corner", hint, consequence)
    return _no_edge_points(f"the {int(np.count_nonzero(kept))} strong zero crossings{where} all lie {border}", "border", consequence=consequence)


def _comparable_threshold(value: float, dtype) -> float:
    """``value`` as a comparison with an array of ``dtype`` sees it: cast to that dtype.

    The same outcome as the implicit cast (NEP 50: a Python float takes the
    array's dtype), without NumPy's overflow warning when the value lies
    beyond float32's range (it becomes inf), e.g. ``relative_gradient``
    times a huge percentile.
    """
    with np.errstate(over="ignore"):
        return float(np.asarray(value, dtype=np.result_type(np.dtype(dtype), np.float32)))


def select_edge_points(
    field: GradientField,
    smoothed_middle: np.ndarray,
    *,
    min_gradient: float | None = None,
    relative_gradient: float = 0.1,
    max_corner_ratio: float = 0.1,
    corner_window_px: float = 2.0,
    border_px: int = 2,
) -> EdgeSelection:
    """Strong zero-crossing edge points, corners rejected (paper section 3.2).

    Parameters
    ----------
    field : GradientField
        Gradients at cell centres (from :func:`nfdepth.normal_flow.normal_flow`):
        ``grad_col``, ``grad_row`` and ``grad_t`` real, non-empty, 2-D, of one shape
        (H-1, W-1); ``grad_col`` and ``grad_row`` finite (``grad_t`` is not read).
    smoothed_middle : ndarray, shape (H, W)
        The smoothed middle frame, for the Laplacian zero crossings: real, finite.
    min_gradient : float, optional
        Absolute gradient threshold in intensity per pixel. Default:
        ``relative_gradient`` times the 99th percentile of ``|grad I|``.
    relative_gradient : float
        Fraction used when ``min_gradient`` is not given.
    max_corner_ratio : float
        Largest structure-tensor eigenvalue ratio accepted (0..1); larger
        means a corner. 1 disables the rule.
    corner_window_px : float
        Standard deviation of the structure tensor's Gaussian window.
    border_px : int
        Cells this close to the image border are dropped (their smoothing
        saw the reflected border).

    Returns
    -------
    EdgeSelection
        All maps of shape (H-1, W-1), cell ``[r, c]`` centred at pixel
        ``(r + 0.5, c + 0.5)``. ``mask``: the usable edge points, cells that are
        zero crossings (:func:`laplacian_zero_crossings`), strong (``|grad I| >=
        min_gradient`` and above float32 rounding, :func:`rounding_gradient_floor`)
        and not corners, outside the ``border_px`` outermost rows and columns of
        cells (none when the grid is not larger than ``2 border_px``).
        ``zero_crossing`` and ``strong``: those rules alone, border included;
        ``corner``: the strong zero crossings whose ``corner_ratio`` exceeds
        ``max_corner_ratio`` (or is NaN); ``min_gradient``: the threshold used (given or
        computed), a float; ``corner_ratio``: :func:`corner_ratio` with
        ``corner_window_px``; ``border_px``: the border used.

    Raises
    ------
    TypeError
        ``field`` is no :class:`~nfdepth.normal_flow.GradientField` or holds gradients
        that are not real numbers (complex, text, objects); an option is not a number.
    ValueError
        ``field``'s gradients are not non-empty 2-D arrays of one shape, ``grad_col`` or
        ``grad_row`` holds NaN or inf, ``smoothed_middle`` does (or is not one pixel
        larger than the cell grid along each axis), or an option is out of its range.
    """
    grad_col, grad_row = _checked_field(field)
    smoothed_middle = np.asarray(smoothed_middle)
    border_px = check_int("border_px", border_px, 0)
    mag = np.hypot(grad_col, grad_row)
    if smoothed_middle.shape != (mag.shape[0] + 1, mag.shape[1] + 1):
        msg = f"smoothed_middle must have shape {(mag.shape[0] + 1, mag.shape[1] + 1)}, got {smoothed_middle.shape}"
        raise ValueError(msg)
    if is_real_numeric(smoothed_middle):  # otherwise laplacian_zero_crossings says what it is
        _check_finite("smoothed_middle", smoothed_middle, "intensities")
    max_corner_ratio = check_fraction("max_corner_ratio", max_corner_ratio)
    corner_window_px = check_scale_px("corner_window_px", corner_window_px, zero_ok=False)
    if min_gradient is None:
        relative_gradient = check_threshold("relative_gradient", relative_gradient)
        high = float(percentile(mag, 99.0)) if mag.size else 0.0
        min_gradient = relative_gradient * high
    else:
        min_gradient = check_threshold("min_gradient", min_gradient)
    try:
        zero = laplacian_zero_crossings(smoothed_middle)
    except ValueError as exc:  # told with this function's parameter name
        raise ValueError(str(exc).replace("smoothed must", "smoothed_middle must", 1)) from None
    strong = (mag >= _comparable_threshold(min_gradient, mag.dtype)) & (mag > rounding_gradient_floor(smoothed_middle))
    ratio = corner_ratio(grad_col, grad_row, window_sigma_px=corner_window_px)
    corner = ~(ratio <= max_corner_ratio)
    mask = zero & strong & ~corner & _inside(mag.shape, border_px)
    return EdgeSelection(mask, zero, strong, corner & zero & strong, float(min_gradient), ratio, border_px)


def _check_finite(name: str, arr: np.ndarray, what: str) -> None:
    """Refuse NaN or inf in ``arr`` (two reductions, no temporary; counted only when there are some)."""
    if arr.size and not (np.isfinite(arr.min()) and np.isfinite(arr.max())):  # NaN propagates into both, inf shows in one
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        msg = f"{name} contains {bad} non-finite (NaN or inf) value(s); expected finite {what}"
        raise ValueError(msg)


def _checked_field(field) -> tuple[np.ndarray, np.ndarray]:
    """``field``'s ``(grad_col, grad_row)`` as arrays, once the field is a :class:`GradientField` of
    real, non-empty 2-D gradients of one shape, its spatial ones finite (``grad_t`` is not used here)."""
    if not isinstance(field, GradientField):
        msg = f"field must be a nfdepth.GradientField (from normal_flow), got {type(field).__name__}"
        raise TypeError(msg)
    grads = {}
    for name in ("grad_col", "grad_row", "grad_t"):
        arr = np.asarray(getattr(field, name))
        if not is_real_numeric(arr):
            msg = f"field.{name} must be real numbers, got dtype {arr.dtype}"
            raise TypeError(msg)
        if arr.ndim != 2 or arr.size == 0:
            msg = f"field.{name} must be a non-empty 2-D array on the cell grid (rows - 1, cols - 1), got shape {arr.shape}"
            raise ValueError(msg)
        grads[name] = arr
    shapes = {name: arr.shape for name, arr in grads.items()}
    if len(set(shapes.values())) > 1:
        listed = ", ".join(f"{name} {shape}" for name, shape in shapes.items())
        msg = f"field's gradients must share one cell grid (one shape), got {listed}"
        raise ValueError(msg)
    for name in ("grad_col", "grad_row"):
        _check_finite(f"field.{name}", grads[name], "gradients")
    return grads["grad_col"], grads["grad_row"]
