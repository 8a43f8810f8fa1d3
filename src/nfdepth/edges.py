"""Zero-crossing edge points with corner rejection (paper section 3.2).

The paper estimates normal flow only at *zero-crossing edge points*: zero
crossings of the Laplacian of the Gaussian-smoothed middle frame where the
gradient is strong. Corner points, whose gradient direction is not defined,
are disregarded. Here both rules work on the same 2 x 2 cell grid as the
gradients of :mod:`nfdepth.normal_flow`:

* a cell is a zero crossing when the Laplacian at its four corner pixels
  changes sign;
* a cell is *strong* when ``|grad I| >= min_gradient`` (intensity per pixel;
  by default a fraction of a high percentile of the image's gradient);
* a cell is a *corner* when the eigenvalue ratio ``lambda_2 / lambda_1`` of
  the structure tensor (gradient outer products averaged with a Gaussian
  window) exceeds ``max_corner_ratio``: along a straight edge the ratio is
  near 0, where two edge directions meet it grows toward 1. The rule needs
  no ground truth.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ._validate import check_nonnegative_finite, check_positive_finite
from .normal_flow import GradientField

__all__ = [
    "EdgeSelection",
    "laplacian_zero_crossings",
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
        corner pixels have Laplacian values of both signs.
    """
    img = np.asarray(smoothed)
    if img.ndim != 2 or min(img.shape) < 2 or not (np.issubdtype(img.dtype, np.number) or img.dtype == bool) or np.iscomplexobj(img):
        msg = f"smoothed must be a real 2-D image of at least 2x2 pixels, got dtype {img.dtype}, shape {img.shape}"
        raise ValueError(msg)
    if img.dtype not in (np.float32, np.float64):
        img = img.astype(np.float64)  # OpenCV's Laplacian takes no int32/int64/bool input
    lap = cv2.Laplacian(img, -1, ksize=1, borderType=cv2.BORDER_REFLECT)
    corners = np.stack([lap[:-1, :-1], lap[:-1, 1:], lap[1:, :-1], lap[1:, 1:]])
    return (corners.max(axis=0) > 0) & (corners.min(axis=0) < 0)


def corner_ratio(grad_col: np.ndarray, grad_row: np.ndarray, *, window_sigma_px: float) -> np.ndarray:
    """Structure-tensor eigenvalue ratio ``lambda_2 / lambda_1`` in [0, 1].

    0 on a straight edge (one gradient direction in the window), near 1 at
    corners and junctions, NaN where the window holds no gradient at all.
    """
    window_sigma_px = check_positive_finite("window_sigma_px", window_sigma_px)
    radius = max(1, int(np.ceil(3.0 * window_sigma_px)))
    ksize = (2 * radius + 1, 2 * radius + 1)
    gc = np.asarray(grad_col, dtype=np.float64)
    gr = np.asarray(grad_row, dtype=np.float64)
    jxx = cv2.GaussianBlur(gc * gc, ksize, window_sigma_px, borderType=cv2.BORDER_REFLECT)
    jyy = cv2.GaussianBlur(gr * gr, ksize, window_sigma_px, borderType=cv2.BORDER_REFLECT)
    jxy = cv2.GaussianBlur(gc * gr, ksize, window_sigma_px, borderType=cv2.BORDER_REFLECT)
    half_trace = 0.5 * (jxx + jyy)
    root = np.sqrt(np.maximum(0.25 * (jxx - jyy) ** 2 + jxy**2, 0.0))
    lam1 = half_trace + root
    lam2 = np.maximum(half_trace - root, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = lam2 / lam1
    ratio[lam1 <= 0] = np.nan
    return ratio


@dataclass(frozen=True)
class EdgeSelection:
    """Which cells are usable edge points, and why the others are not.

    Attributes
    ----------
    mask : ndarray of bool, shape (H-1, W-1)
        Strong zero-crossing edge points that are not corners.
    zero_crossing, strong, corner : ndarray of bool, shape (H-1, W-1)
        The individual rules.
    min_gradient : float
        The gradient threshold used (intensity per pixel).
    corner_ratio : ndarray, shape (H-1, W-1)
        The structure-tensor eigenvalue ratio.
    """

    mask: np.ndarray
    zero_crossing: np.ndarray
    strong: np.ndarray
    corner: np.ndarray
    min_gradient: float
    corner_ratio: np.ndarray


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
        Gradients at cell centres (from :func:`nfdepth.normal_flow.normal_flow`).
    smoothed_middle : ndarray, shape (H, W)
        The smoothed middle frame, for the Laplacian zero crossings.
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
    """
    if not isinstance(field, GradientField):
        msg = f"field must be a nfdepth.GradientField (from normal_flow), got {type(field).__name__}"
        raise TypeError(msg)
    smoothed_middle = np.asarray(smoothed_middle)
    if isinstance(border_px, (bool, np.bool_)) or not isinstance(border_px, (int, np.integer)) or border_px < 0:
        msg = f"border_px must be an int >= 0, got {border_px!r}"
        raise ValueError(msg)
    mag = field.magnitude
    if smoothed_middle.shape != (mag.shape[0] + 1, mag.shape[1] + 1):
        msg = f"smoothed_middle must have shape {(mag.shape[0] + 1, mag.shape[1] + 1)}, got {smoothed_middle.shape}"
        raise ValueError(msg)
    if not 0 <= max_corner_ratio <= 1:
        msg = f"max_corner_ratio must be within [0, 1], got {max_corner_ratio!r}"
        raise ValueError(msg)
    if min_gradient is None:
        relative_gradient = check_nonnegative_finite("relative_gradient", relative_gradient)
        high = float(np.percentile(mag, 99.0)) if mag.size else 0.0
        min_gradient = relative_gradient * high
    else:
        min_gradient = check_nonnegative_finite("min_gradient", min_gradient)
    zero = laplacian_zero_crossings(smoothed_middle)
    strong = (mag >= min_gradient) & (mag > 0)
    ratio = corner_ratio(field.grad_col, field.grad_row, window_sigma_px=corner_window_px)
    corner = ~(ratio <= max_corner_ratio)
    inside = np.zeros_like(zero)
    b = int(border_px)
    if mag.shape[0] > 2 * b and mag.shape[1] > 2 * b:
        inside[b : mag.shape[0] - b, b : mag.shape[1] - b] = True
    mask = zero & strong & ~corner & inside
    return EdgeSelection(mask, zero, strong, corner & zero & strong, float(min_gradient), ratio)
