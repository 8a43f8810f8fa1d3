"""Normal flow from image sequences (paper section 3.1).

Two steps, as in the paper: Gaussian smoothing of every frame, then the
intensity gradients ``I_col``, ``I_row`` and ``I_t`` from a 2 x 2 x 3 stencil
(three frames; Horn and Schunck's 2 x 2 x 2 cube for two frames). Every
estimate belongs to the **centre of a 2 x 2 pixel cell** -- position
``(row + 0.5, col + 0.5)`` for cell ``[row, col]`` -- and to the time of the
middle frame (the midpoint of the two frames for the two-frame stencil).
Output arrays therefore have shape ``(H - 1, W - 1)``.

Normal flow follows from brightness constancy ``I_col u + I_row v + I_t = 0``:

.. math::
    V_n = -I_t / |\\nabla I|,\\qquad \\alpha = \\operatorname{atan2}(I_{row}, I_{col})

(paper eq. 3 with ``n = (cos alpha, sin alpha)``), in pixels per unit time.

Stencils
--------
``"paper"``
    The printed stencil with consistent normalisation: spatial differences
    averaged over the 2 x 2 cell and the three frames with equal weights,
    ``I_t`` the central difference averaged over the cell's four pixels. A
    linear ramp in space and time gives the exact gradient. (The printed
    ``1/8`` for six differences and the sign of the last ``I_z`` term are
    misprints.)
``"simpson"``
    As ``"paper"`` but the three frames weighted 1:4:1 in the spatial
    gradients. The central difference ``I(t+d) - I(t-d)`` is the integral of
    the spatial derivative along the motion; Simpson's rule integrates it to
    fourth order, which removes the ``d^2 / (6 sigma^2)`` bias that equal
    weights leave when the motion per frame ``d`` is a sizeable fraction of
    the smoothing scale ``sigma``.
``"matched"`` (default)
    As ``"simpson"`` with a four-point difference ``3/4 (I[j+1] - I[j]) +
    1/12 (I[j+2] - I[j-1])`` along each derivative axis, so that the spatial
    derivatives see the same two-pixel averaging as ``I_t`` to second order.
    The two-point difference of the paper leaves a bias of about
    ``-1/(12 sigma^2)`` in every normal flow (3.7 % at sigma = 1.5 px), which
    the matched difference removes. Exact on linear ramps too.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ._quantile import percentile
from ._validate import as_frames, as_image, check_frame_interval, check_int, check_scale_px, float_dtype, is_real_numeric, native

__all__ = [
    "STENCILS",
    "GradientField",
    "gaussian_smooth",
    "gradients",
    "normal_flow",
    "estimate_noise_std",
    "noise_gains",
]

STENCILS = ("matched", "simpson", "paper")


def _check_stencil(stencil) -> str:
    """``stencil`` if it names one of :data:`STENCILS`; ``ValueError`` saying which otherwise."""
    if not isinstance(stencil, str) or stencil not in STENCILS:
        msg = f"stencil must be one of {STENCILS}, got {stencil!r}"
        raise ValueError(msg)
    return stencil


_TEMPORAL_WEIGHTS = {
    "paper": (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0),
    "simpson": (1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0),
    "matched": (1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0),
}


@dataclass(frozen=True)
class GradientField:
    """Intensity gradients at the centres of 2 x 2 pixel cells.

    Attributes
    ----------
    grad_col, grad_row : ndarray, shape (H-1, W-1)
        Spatial derivatives in intensity per pixel at cell centres.
    grad_t : ndarray, shape (H-1, W-1)
        Temporal derivative in intensity per unit time.
    """

    grad_col: np.ndarray
    grad_row: np.ndarray
    grad_t: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        """Shape of the cell grid, ``(H - 1, W - 1)``."""
        return self.grad_col.shape

    @property
    def magnitude(self) -> np.ndarray:
        """Gradient magnitude ``|grad I|`` (intensity per pixel)."""
        return np.hypot(self.grad_col, self.grad_row)

    @property
    def alpha(self) -> np.ndarray:
        """Normal direction ``alpha = atan2(I_row, I_col)`` in radians."""
        return np.arctan2(self.grad_row, self.grad_col)

    @property
    def normal_flow(self) -> np.ndarray:
        """Normal flow ``-I_t / |grad I|`` in px per unit time; NaN where ``grad I = 0``."""
        mag = self.magnitude
        with np.errstate(divide="ignore", invalid="ignore"):
            vn = -self.grad_t / mag
        vn[mag == 0] = np.nan
        return vn

    def normal_flow_along(self, grad_col: np.ndarray, grad_row: np.ndarray) -> np.ndarray:
        """Normal flow measured along a given (shared) gradient direction.

        Two flows are only comparable along the same normal: the relative
        normal flow of two cameras uses one spatial gradient for both.
        """
        mag = np.hypot(grad_col, grad_row)
        with np.errstate(divide="ignore", invalid="ignore"):
            vn = -self.grad_t / mag
        vn[mag == 0] = np.nan
        return vn

    @staticmethod
    def cell_centres(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates ``(rows, cols)`` of the cell centres, each shape ``shape``."""
        rows = np.arange(shape[0], dtype=float)[:, None] + 0.5
        cols = np.arange(shape[1], dtype=float)[None, :] + 0.5
        return np.broadcast_to(rows, shape), np.broadcast_to(cols, shape)


_FLOAT_TYPES = (np.float32, np.float64)


def _real_image(name: str, image) -> np.ndarray:
    """A 2-D, non-empty, real numeric array (no pass over its values: NaN stays NaN); integer or boolean
    images become float64 (smoothing them in their own type would round the result), big-endian floats
    native ones of their precision (OpenCV reads the bytes as native numbers: garbage, silently)."""
    arr = np.asarray(image)
    if not is_real_numeric(arr):
        msg = f"{name} must be a real numeric 2-D array, got dtype {arr.dtype}"
        raise TypeError(msg)
    if arr.ndim != 2 or arr.size == 0:
        msg = f"{name} must be a non-empty 2-D image (rows, cols), got shape {arr.shape}"
        raise ValueError(msg)
    return native(arr) if arr.dtype.type in _FLOAT_TYPES else arr.astype(np.float64)


def gaussian_smooth(image: np.ndarray, *, sigma_px: float) -> np.ndarray:
    """Gaussian smoothing (OpenCV, reflected border); ``sigma_px = 0`` copies.

    The kernel is truncated at 4 sigma on each side (``2 ceil(4 sigma) + 1``
    taps, at least 3), the same along rows and columns; the border is
    OpenCV's ``BORDER_REFLECT`` (the edge pixel repeated: ``cba|abc``). This is
    the smoothing step of paper section 3.1.

    Parameters
    ----------
    image : array_like, shape (H, W)
        A non-empty 2-D array of real numbers (or booleans), in either byte order.
        Its values are not checked: a NaN or inf spreads over the kernel's reach.
    sigma_px : float
        Standard deviation of the Gaussian in pixels: finite, from 0 (no smoothing)
        to 5000.

    Returns
    -------
    ndarray, shape (H, W)
        A new array (never a view of ``image``), in the machine's byte order: float32
        for float32 input, float64 for float64, integer, boolean or other real input.

    Raises
    ------
    TypeError
        ``image`` is not real numbers (complex, text, objects), or ``sigma_px`` is not
        a number (a str or bool too).
    ValueError
        ``image`` is not 2-D or is empty, or ``sigma_px`` is negative, not finite or
        above 5000.
    """
    sigma_px = check_scale_px("sigma_px", sigma_px)
    image = _real_image("image", image)
    if sigma_px == 0:
        return np.array(image, copy=True)
    radius = max(1, int(np.ceil(4.0 * sigma_px)))
    ksize = 2 * radius + 1
    return cv2.GaussianBlur(image, (ksize, ksize), sigmaX=sigma_px, sigmaY=sigma_px, borderType=cv2.BORDER_REFLECT)


#: The matched stencil's four-point difference: ``NEAR (I[j+1] - I[j]) + WIDE (I[j+2] - I[j-1])``.
_MATCHED_NEAR = 0.75
_MATCHED_WIDE = 1.0 / 12.0


def _diff(image: np.ndarray, matched: bool, axis: int) -> np.ndarray:
    """Difference along ``axis`` (1: columns, 0: rows) at its half-integer positions, edge-padded (no transposes)."""

    def cut(start, stop):
        return (slice(None),) * axis + (slice(start, stop),)

    two_point = image[cut(1, None)] - image[cut(None, -1)]
    if not matched:
        return two_point
    pad = [(0, 0), (0, 0)]
    pad[axis] = (1, 1)
    padded = np.pad(image, pad, mode="edge")
    wide = padded[cut(3, None)] - padded[cut(None, -3)]
    return _MATCHED_NEAR * two_point + _MATCHED_WIDE * wide


def _cell_gradient(image: np.ndarray, matched: bool) -> tuple[np.ndarray, np.ndarray]:
    """``(I_col, I_row)`` of one frame at the 2 x 2 cell centres."""
    dc = _diff(image, matched, axis=1)
    grad_col = 0.5 * (dc[:-1] + dc[1:])
    dr = _diff(image, matched, axis=0)
    grad_row = 0.5 * (dr[:, :-1] + dr[:, 1:])
    return grad_col, grad_row


def _cell_mean(image: np.ndarray) -> np.ndarray:
    return 0.25 * (image[:-1, :-1] + image[:-1, 1:] + image[1:, :-1] + image[1:, 1:])


def gradients(smoothed_frames, *, frame_interval: float = 1.0, stencil: str = "matched") -> GradientField:
    """Gradients of 2 or 3 (already smoothed) frames at cell centres.

    Parameters
    ----------
    smoothed_frames : sequence of 2 or 3 ndarray, shape (H, W)
        Equally spaced frames in time order.
    frame_interval : float
        Time between consecutive frames (> 0); ``I_t`` is per unit time.
    stencil : {"matched", "simpson", "paper"}
        Three-frame stencil (module docstring). Two frames use the
        Horn-Schunck cube in time (both frames weighted equally, ``I_t`` at
        the midpoint time); ``stencil`` still picks the spatial difference
        (``matched``'s four-point one, the others' two-point one).

    Returns
    -------
    GradientField
        Gradients at cell centres ``(row + 0.5, col + 0.5)``, shape (H-1, W-1).
    """
    _check_stencil(stencil)
    dt = check_frame_interval("frame_interval", frame_interval)
    if not isinstance(smoothed_frames, (list, tuple, np.ndarray)):
        msg = f"smoothed_frames must be a sequence of 2 or 3 2-D arrays, got {type(smoothed_frames).__name__}"
        raise TypeError(msg)
    n = len(smoothed_frames)
    if n in (2, 3):
        smoothed_frames = [_real_image(f"smoothed_frames[{k}]", f) for k, f in enumerate(smoothed_frames)]
        shapes = [np.shape(f) for f in smoothed_frames]
        if any(len(sh) != 2 or min(sh) < 2 for sh in shapes) or len(set(shapes)) > 1:
            msg = f"smoothed_frames must be 2-D arrays of one shape, at least 2x2, got shapes {shapes}"
            raise ValueError(msg)
    matched = stencil == "matched"
    if n == 3:
        weights = _TEMPORAL_WEIGHTS[stencil]
        grad_col = np.zeros_like(smoothed_frames[0][:-1, :-1])
        grad_row = np.zeros_like(grad_col)
        for w, frame in zip(weights, smoothed_frames):
            gc, gr = _cell_gradient(frame, matched)
            grad_col += w * gc
            grad_row += w * gr
        grad_t = _cell_mean(smoothed_frames[2] - smoothed_frames[0]) / (2.0 * dt)
    elif n == 2:
        gc0, gr0 = _cell_gradient(smoothed_frames[0], matched)
        gc1, gr1 = _cell_gradient(smoothed_frames[1], matched)
        grad_col = 0.5 * (gc0 + gc1)
        grad_row = 0.5 * (gr0 + gr1)
        grad_t = _cell_mean(smoothed_frames[1] - smoothed_frames[0]) / dt
    else:
        msg = f"gradients need 2 or 3 frames, got {n}"
        raise ValueError(msg)
    return GradientField(grad_col, grad_row, grad_t)


def normal_flow(
    frames,
    *,
    sigma_px: float = 2.0,
    frame_interval: float = 1.0,
    stencil: str = "matched",
    dtype=np.float32,
) -> GradientField:
    """Normal flow of a 2- or 3-frame sequence (paper section 3.1).

    Parameters
    ----------
    frames : sequence of 2 or 3 ndarray, shape (H, W), or ndarray (N, H, W)
        Grey frames, equally spaced in time, in time order.
    sigma_px : float
        Standard deviation of the Gaussian smoothing in pixels (0: none).
        Larger values tolerate larger motion per frame (paper: "big values
        should be used if the image motion is large").
    frame_interval : float
        Time between consecutive frames; the flow is per unit time.
    stencil : {"matched", "simpson", "paper"}
        Gradient stencil; see the module docstring.
    dtype : float32 or float64
        Working precision.

    Returns
    -------
    GradientField
        ``.normal_flow``, ``.alpha``, ``.magnitude`` at cell centres
        ``(row + 0.5, col + 0.5)`` of the middle frame, shape (H-1, W-1).

    Examples
    --------
    A ramp ``I = 2 col + 3 row - 5 t`` moving with any flow gives exact gradients:

    >>> import numpy as np
    >>> r, c = np.mgrid[0:8, 0:8]
    >>> frames = [2.0 * c + 3.0 * r - 5.0 * t for t in (-1, 0, 1)]
    >>> g = normal_flow(frames, sigma_px=0, dtype=np.float64)
    >>> [round(float(a[3, 3]), 12) for a in (g.grad_col, g.grad_row, g.grad_t)]
    [2.0, 3.0, -5.0]
    """
    dt = float_dtype(dtype)
    frames = as_frames("frames", frames, dtype=dt)
    if len(frames) not in (2, 3):
        msg = f"frames must hold 2 or 3 frames, got {len(frames)}"
        raise ValueError(msg)
    smoothed = [gaussian_smooth(f, sigma_px=sigma_px) for f in frames]
    return gradients(smoothed, frame_interval=frame_interval, stencil=stencil)


_Z90 = 1.6448536269514722  # 90th percentile of the half-normal |N(0, 1)|
_TRIMMED_HALF_NORMAL_MEAN = 2.0 * (1.0 - np.exp(-0.5 * _Z90**2)) / np.sqrt(2.0 * np.pi) / 0.9


def estimate_noise_std(image: np.ndarray) -> float:
    """Robust estimate of white image-noise standard deviation (grey levels).

    Immerkaer's 3 x 3 operator (the difference of two Laplacians) cancels
    smooth image content. The mean absolute response over the 90 % smallest
    responses, scaled for a normal distribution, ignores the edges that
    inflate the plain mean (up to 10 % of the pixels). Unlike the median it
    sees the quantisation noise of 8-bit frames (std 1/sqrt(12) grey level)
    instead of returning 0. Returns 0 for noise-free piecewise-constant images
    (where fewer than 10 % of the responses lie at an edge).

    Parameters
    ----------
    image : array_like, shape (H, W)
        One grey image, at least 3 x 3, of finite real intensities in any linear
        unit; worked on in float64. Only pixels with all eight neighbours inside the
        image contribute. The noise is assumed independent from pixel to pixel.

    Returns
    -------
    float
        The noise standard deviation in the image's intensity unit (grey levels),
        >= 0. Where edges or fine texture cover more than about 10 % of the pixels,
        they inflate it.

    Raises
    ------
    TypeError
        ``image`` is not numeric or is complex.
    ValueError
        ``image`` is not 2-D (convert colour to grey first,
        :func:`nfdepth.io.to_grey`), is smaller than 3 x 3, or holds NaN or inf.
    """
    img = as_image("image", image, np.float64)
    if min(img.shape) < 3:
        msg = f"image must be 2-D and at least 3x3, got shape {img.shape}"
        raise ValueError(msg)
    kernel = np.array([[1.0, -2.0, 1.0], [-2.0, 4.0, -2.0], [1.0, -2.0, 1.0]])
    response = cv2.filter2D(img, cv2.CV_64F, kernel, borderType=cv2.BORDER_REFLECT)[1:-1, 1:-1]
    # The response to white noise of std s is normal with std s * sqrt(sum(kernel**2)) = 6 s;
    # E[|X| ; |X| below its 90th percentile] / 0.9 = 2 (phi(0) - phi(z90)) / 0.9 for X ~ N(0, 1).
    mag = np.abs(response).ravel()
    cut = percentile(mag, 90.0)
    kept = mag[mag <= cut]
    return float(np.mean(kept) / (6.0 * _TRIMMED_HALF_NORMAL_MEAN)) if kept.size else 0.0


def _gaussian_kernel_1d(sigma_px: float) -> np.ndarray:
    if sigma_px == 0:
        return np.array([1.0])
    radius = max(1, int(np.ceil(4.0 * sigma_px)))
    return cv2.getGaussianKernel(2 * radius + 1, sigma_px, cv2.CV_64F).ravel()


def noise_gains(*, sigma_px: float, stencil: str = "matched", n_frames: int = 3) -> tuple[float, float]:
    """Noise gains of the stencil for white image noise of unit variance.

    Returns ``(temporal, spatial)``: the standard deviation of ``I_t * dt``
    (``dt`` = frame interval) and of each spatial derivative, per unit
    standard deviation of independent white noise in every frame. Computed
    exactly from the effective linear filters (Gaussian, then the stencil).
    ``n_frames``: 3 for a triple, 2 for the two-image variant.
    Noise of std ``s`` grey levels thus gives a normal flow ``Vn = -I_t / |grad I|``
    a standard deviation of about ``s sqrt((temporal / dt)**2 + (Vn spatial)**2) / |grad I|``
    px per unit time, as the pipelines use it.

    Parameters
    ----------
    sigma_px : float
        Standard deviation of the Gaussian smoothing in px, as given to
        :func:`gaussian_smooth` or :func:`normal_flow`: finite, from 0 (none) to 5000.
    stencil : {"matched", "simpson", "paper"}
        Gradient stencil (module docstring); it changes only the spatial gain.
    n_frames : int
        3 for a triple (the three-frame stencil), 2 for the two-image variant
        (Horn and Schunck's cube, :func:`gradients` with two frames).

    Returns
    -------
    temporal : float
        Standard deviation of ``I_t * dt`` per grey level of noise std (dimensionless);
        the same for every stencil.
    spatial : float
        Standard deviation of ``I_col`` and of ``I_row`` (each) per grey level of noise
        std, in 1/px.

    Raises
    ------
    ValueError
        ``stencil`` is not one of :data:`STENCILS` (a non-str too), ``n_frames`` is
        not 2 or 3, or ``sigma_px`` is negative, not finite or above 5000 (:data:`nfdepth._validate.MAX_SCALE_PX`).
    TypeError
        ``n_frames`` is not an integer (a float such as ``3.0`` or a bool too), or
        ``sigma_px`` is not a number (a str or bool too).
    """
    _check_stencil(stencil)
    if check_int("n_frames", n_frames, 2) not in (2, 3):
        msg = f"n_frames must be 2 (the two-image variant) or 3 (a triple), got {n_frames!r}"
        raise ValueError(msg)
    g = _gaussian_kernel_1d(check_scale_px("sigma_px", sigma_px))
    # The effective 2-D filters are separable: the Gaussian is outer(g, g), the cell mean
    # outer(m, m) of the 2-tap mean m, and I_col's stencil outer(m, d) (the mean along rows,
    # the difference d along columns). A sum of squares of an outer product is the product of
    # the factors' sums of squares, so 1-D sums suffice (a dense (8 sigma + 1)**2 kernel
    # took 48 GB at sigma_px = 1e4). Zero padding of 3 taps holds the stencil's full reach.
    pad = np.pad(g, 3)
    mean = 0.5 * (pad[:-1] + pad[1:])
    diff = _diff(pad[None, :], stencil == "matched", axis=1)[0]
    cell_sq = np.sum(mean**2) ** 2  # sum of the squared 2-D cell-mean filter
    if n_frames == 3:
        temporal = np.sqrt(2.0 * cell_sq) / 2.0
        weights = np.asarray(_TEMPORAL_WEIGHTS[stencil])
    else:
        temporal = np.sqrt(2.0 * cell_sq)
        weights = np.array([0.5, 0.5])
    spatial = np.sqrt(np.sum(mean**2) * np.sum(diff**2) * np.sum(weights**2))
    return float(temporal), float(spatial)
