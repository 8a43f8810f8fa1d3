"""Input validation shared by the public functions (private).

Every check raises ``ValueError`` or ``TypeError`` with a message that names
the parameter, what arrived and what was expected.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

_FLOAT_DTYPES = (np.float32, np.float64)

#: Largest frame (rows x cols) the pipelines accept, in pixels. Peak working
#: memory on a float32 triple, beyond the input frames: about 105 bytes per
#: pixel for :func:`nfdepth.normal_flow.normal_flow` plus
#: :func:`nfdepth.edges.select_edge_points` (asserted below 128 in
#: ``tests/test_bad_input.py``), about 130 for
#: :func:`nfdepth.pipelines.static_stereo_edges` and about 370 for the dense
#: :func:`nfdepth.stereo.static_stereo` (measured at 4 megapixels), so a
#: 40-megapixel triple needs about 5 GB (15 GB dense). Override with the
#: environment variable ``NFDEPTH_MAX_PIXELS`` (a positive number of pixels).
MAX_PIXELS = 40_000_000

#: Environment variable that overrides :data:`MAX_PIXELS`.
MAX_PIXELS_ENV = "NFDEPTH_MAX_PIXELS"


class NFDepthError(ValueError):
    """Base class of nfdepth's own errors (a ``ValueError``)."""


class ImageTooLargeError(NFDepthError):
    """A frame has more pixels than :func:`max_pixels` allows."""


def max_pixels() -> int:
    """The pixel limit per frame: ``NFDEPTH_MAX_PIXELS`` if set, else :data:`MAX_PIXELS`."""
    text = os.environ.get(MAX_PIXELS_ENV, "").strip()
    if not text:
        return int(MAX_PIXELS)
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not np.isfinite(value) or value < 1:
        msg = f"{MAX_PIXELS_ENV} must be a positive number of pixels (e.g. 60000000), got {text!r}"
        raise ValueError(msg)
    return int(value)


def as_path(name: str, value) -> Path:
    """``value`` (a ``str`` or ``os.PathLike``) as a :class:`~pathlib.Path`; TypeError naming ``name`` otherwise (None, bytes, a number)."""
    if isinstance(value, (str, os.PathLike)):
        try:
            return Path(value)
        except TypeError:  # an os.PathLike whose __fspath__ gives bytes
            pass
    msg = f"{name} must be a file path (str or os.PathLike), got {type(value).__name__}"
    raise TypeError(msg)


def check_frame_size(name: str, shape) -> None:
    """Refuse a frame of ``shape`` (rows, cols, ...) above :func:`max_pixels`."""
    if len(shape) < 2:
        return
    pixels = int(shape[0]) * int(shape[1])
    limit = max_pixels()
    if pixels > limit:
        digits = 1  # enough to tell the two apart (0.11 above 0.1, not 0.1 above 0.1)
        while digits < 7 and f"{pixels / 1e6:.{digits}f}" == f"{limit / 1e6:.{digits}f}":
            digits += 1
        msg = (
            f"{name} has {shape[1]}x{shape[0]} px (width x height) = {pixels / 1e6:.{digits}f} megapixels, above the limit of "
            f"{limit / 1e6:g} megapixels per frame (working memory at such sizes is about 130-290 bytes per pixel: docs/troubleshooting.md); "
            f"downsample the images or raise the limit with the environment variable {MAX_PIXELS_ENV}"
        )
        raise ImageTooLargeError(msg)


def _not_a_number(value) -> str | None:
    """Why ``value`` is no number although ``float(value)`` may accept it, or None.

    Strings and bytes (``float('2')`` parses them), bools (``float(True)`` is
    1.0) and complex numbers are refused, also as NumPy scalars or 0-d arrays.
    """
    item = value
    if isinstance(item, (np.ndarray, np.generic)) and np.ndim(item) == 0:
        item = item.item()
    if isinstance(item, bool):
        return "bool, not a number"
    if isinstance(item, (str, bytes, bytearray)):
        return f"{type(item).__name__}, not a number"
    if isinstance(item, complex):
        return "complex, not a real number"
    return None


def _check_number(name: str, value, what: str, accept, *, refused: str | None = None) -> float:
    """Return ``value`` as float; TypeError if it is not a number, ValueError if ``accept(number)`` is false.

    Both messages read "``name`` must be ``what``, got ``value``" (``refused`` replaces ``what`` in the second);
    a str, bytes, bool or complex ``value`` adds why it is refused, e.g. "got '2' (str, not a number)".
    """
    why = _not_a_number(value)
    if why is not None:
        msg = f"{name} must be {what}, got {value!r} ({why})"
        raise TypeError(msg)
    try:
        number = float(value)
    except (TypeError, ValueError):
        msg = f"{name} must be {what}, got {value!r}"
        raise TypeError(msg) from None
    if not accept(number):
        msg = f"{name} must be {refused or what}, got {value!r}"
        raise ValueError(msg)
    return number


def check_finite(name: str, value, *, unit: str = "") -> float:
    """Return ``value`` as float, or raise if it is not a finite number."""
    return _check_number(name, value, f"a finite number{f' ({unit})' if unit else ''}", np.isfinite)


def check_positive_finite(name: str, value) -> float:
    """Return ``value`` as float, or raise if it is not a finite number > 0."""
    return _check_number(name, value, "a positive finite number", lambda x: np.isfinite(x) and x > 0)


def check_nonnegative_finite(name: str, value) -> float:
    """Return ``value`` as float, or raise if it is not a finite number >= 0."""
    return _check_number(name, value, "a finite number >= 0", lambda x: np.isfinite(x) and x >= 0)


#: Largest |disparity offset| accepted, px per unit of position: a difference of
#: two principal points (each within 1e6 px of its image centre, see
#: :class:`nfdepth.PinholeCamera`); a larger one is another unit or a typo.
MAX_DISPARITY_OFFSET_PX = 1e6
DISPARITY_OFFSET_EXPECTED = (
    f"a finite number of px per unit of position within +-{MAX_DISPARITY_OFFSET_PX:g} (the principal points' difference"
    " along the row, e.g. Middlebury's doffs; a value beyond is another unit or a typo)"
)


def check_disparity_offset(name: str, value) -> float:
    """A disparity offset (px per unit of position) for ``depth = f b / (d + offset)``, within :data:`MAX_DISPARITY_OFFSET_PX`."""
    return _check_number(name, value, DISPARITY_OFFSET_EXPECTED, lambda x: abs(x) <= MAX_DISPARITY_OFFSET_PX)


#: Largest Gaussian scale (sigma or window) accepted, in px: far beyond any image's
#: useful smoothing, and small enough for OpenCV's kernels. ``cv2.getGaussianKernel``
#: (which ``cv2.GaussianBlur`` uses) is a Gaussian only up to 46341 taps (sigma 5792 at
#: a radius of 4 sigma; beyond, its squared offsets overflow a C int: at sigma 1e4 its
#: spread was 24457 px), so 5000.
MAX_SCALE_PX = 5e3


def check_scale_px(name: str, value, *, zero_ok: bool = True) -> float:
    """A Gaussian scale in px: a finite number >= 0 (``> 0`` unless ``zero_ok``) of at most :data:`MAX_SCALE_PX`."""
    x = check_nonnegative_finite(name, value) if zero_ok else check_positive_finite(name, value)
    if x > MAX_SCALE_PX:
        msg = f"{name} = {x:g} px is beyond any image: expected a Gaussian scale of at most {MAX_SCALE_PX:g} px (a few px is usual)"
        raise ValueError(msg)
    return x


#: Time steps, view positions (their distances from the reference) and a rig's
#: lengths, speeds and focal lengths are accepted within these bounds, in their own
#: units: outside them, values per unit overflow or vanish in float arithmetic and
#: in the float32 outputs.
UNIT_SCALE_RANGE = (1e-30, 1e30)


def check_view_distances(pos, reference: int) -> None:
    """Refuse positions (increasing, finite) that put a view nearer than 1e-30 or farther than 1e30 units from the reference.

    Disparities are reported per unit of position, in float32: a unit of
    1e-300 overflows them, one of 1e300 rounds them to 0.
    """
    rel = np.abs(pos - pos[reference])
    lo, hi = UNIT_SCALE_RANGE
    if rel[rel > 0].min() < lo or rel.max() > hi:
        msg = (
            f"positions must keep the views {lo:g} to {hi:g} units from the reference (disparities are reported per unit of "
            f"position, in float32), got {pos.tolist()}: rescale them, e.g. to steps between neighbouring views"
        )
        raise ValueError(msg)


def check_noise_std(name: str, value) -> float:
    """A given image-noise std: finite, >= 0 and at most 1e30 grey levels (beyond any float32 image; its square overflows)."""
    noise = check_nonnegative_finite(name, value)
    if noise > UNIT_SCALE_RANGE[1]:
        msg = f"{name} = {noise:g} is beyond any image's intensities: expected at most {UNIT_SCALE_RANGE[1]:g} (in the views' grey levels)"
        raise ValueError(msg)
    return noise


def check_within(name: str, value, bounds=UNIT_SCALE_RANGE, *, advice: str, unit: str = "") -> float:
    """A positive finite number within ``bounds`` (default :data:`UNIT_SCALE_RANGE`).

    Outside them: "``name`` = value``unit`` is outside lo..hi``unit``: ``advice``".
    """
    x = check_positive_finite(name, value)
    lo, hi = bounds
    if not lo <= x <= hi:
        msg = f"{name} = {x:g}{unit} is outside {lo:g}..{hi:g}{unit}: {advice}"
        raise ValueError(msg)
    return x


def check_frame_interval(name: str, value) -> float:
    """A positive finite time step within :data:`UNIT_SCALE_RANGE` (else rescale the unit of time)."""
    return check_within(name, value, advice="give times in a unit that keeps the frame interval in that range (e.g. frames)")


def check_nonzero_finite(name: str, value, *, what: str = "a non-zero finite number") -> float:
    """Return ``value`` as float, or raise if it is not a finite, non-zero number."""
    return _check_number(name, value, what, lambda x: np.isfinite(x) and x != 0)


def check_reach(name: str, value) -> float:
    """Return ``value`` as float, or raise if it is not a number >= 0 (``inf`` allowed: no limit)."""
    return _check_number(name, value, "a number >= 0 (inf: no limit)", lambda x: x >= 0)


def check_positive_or_inf(name: str, value) -> float:
    """Return ``value`` as float, or raise if it is not a number > 0 (``inf`` allowed: no limit)."""
    return _check_number(name, value, "a number > 0 (inf: no limit)", lambda x: x > 0)


def check_depth_range(name: str, value) -> tuple[float, float]:
    """``(near, far)`` depths: two numbers with ``0 < near < far``, ``near`` finite, ``far`` finite or ``inf`` (no far limit)."""
    expected = "two depths (near, far) with 0 < near < far (far may be inf: no far limit)"
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        msg = f"{name} must be {expected}, got {value!r}"
        raise TypeError(msg)
    near, far = (_check_number(name, v, expected, lambda x: True) for v in value)
    if not (0 < near < far and math.isfinite(near)):
        msg = f"{name} must be {expected}, got ({near:g}, {far:g})"
        raise ValueError(msg)
    return near, far


#: Largest finite threshold, margin or regulariser accepted for an option that is
#: compared with or added to float32 maps: float32 ends at 3.4e38, and long before
#: that such an option already means "never" (or "always").
MAX_THRESHOLD = 1e30


def check_threshold(name: str, value, *, positive: bool = False, inf_ok: bool = False) -> float:
    """A threshold, margin or regulariser applied to float32 maps.

    A number >= 0 (``> 0`` if ``positive``), finite unless ``inf_ok`` (inf: no
    limit), and, when finite, at most :data:`MAX_THRESHOLD`: a larger one
    would overflow the float32 arithmetic it takes part in.
    """
    if inf_ok:
        x = check_positive_or_inf(name, value) if positive else check_reach(name, value)
    else:
        x = check_positive_finite(name, value) if positive else check_nonnegative_finite(name, value)
    if np.isfinite(x) and x > MAX_THRESHOLD:
        msg = f"{name} = {x:g} is beyond the float32 maps it applies to: expected at most {MAX_THRESHOLD:g}"
        raise ValueError(msg + ("; give inf for no limit" if inf_ok else ""))
    return x


#: Most iterations (or rounds) accepted per loop: each is a pass over the image, and
#: the updates settle within a few; a count beyond this is a slip that would run for hours.
MAX_ITERATIONS = 1000


def check_iterations(name: str, value, minimum: int) -> int:
    """An iteration or round count: an integer from ``minimum`` to :data:`MAX_ITERATIONS`."""
    number = check_int(name, value, minimum)
    if number > MAX_ITERATIONS:
        msg = f"{name} = {number} is more iterations than can help (each is a pass over the image; a few suffice): expected {minimum} to {MAX_ITERATIONS}"
        raise ValueError(msg)
    return number


def check_bool(name: str, value) -> bool:
    """Return ``value`` as bool, or raise TypeError if it is not True or False (NumPy's bool too)."""
    if not isinstance(value, (bool, np.bool_)):
        msg = f"{name} must be True or False, got {value!r}"
        raise TypeError(msg)
    return bool(value)


def _as_int(name: str, value, what: str) -> int:
    """``value`` as int (Python or NumPy integer, or a 0-d integer array); TypeError naming ``what`` otherwise.

    Floats are refused even when integral (``2.0``): an integer option given a
    float is more likely a mistake than a convenience.
    """
    why = _not_a_number(value)
    item = value.item() if isinstance(value, np.ndarray) and value.ndim == 0 else value
    if why is None and isinstance(item, (float, np.floating)):
        why = f"float; give an int such as {int(item)}" if np.isfinite(item) and float(item).is_integer() else "not a whole number"
    if why is not None:
        msg = f"{name} must be {what}, got {value!r} ({why})"
        raise TypeError(msg)
    if not isinstance(item, (int, np.integer)):
        msg = f"{name} must be {what}, got {value!r}"
        raise TypeError(msg)
    return int(item)


def check_image_size(owner, names=("width_px", "height_px")) -> None:
    """Raise ValueError unless each of ``owner``'s attributes ``names`` is a positive integer (an image size in pixels)."""
    for name in names:
        value = getattr(owner, name)
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 1:
            msg = f"{name} must be a positive integer, got {value!r}"
            raise ValueError(msg)


def check_int(name: str, value, minimum: int) -> int:
    """Return ``value`` as int, or raise if it is not an integer >= ``minimum``.

    TypeError for a bool, str, float (also ``2.0``) or other non-integer;
    ValueError below ``minimum``.
    """
    number = _as_int(name, value, f"an integer >= {minimum}")
    if number < minimum:
        msg = f"{name} must be an integer >= {minimum}, got {value!r}"
        raise ValueError(msg)
    if number > _MAX_INT:  # beyond what the compiled kernels and OpenCV take (int64, C int sizes)
        msg = f"{name} must be an integer from {minimum} to 2**53, got {value!r}"
        raise ValueError(msg)
    return number


_MAX_INT = 2**53


def check_view_index(name: str, value, count: int) -> int:
    """Return ``value`` as int, or raise if it is not the index of one of ``count`` views (bools, floats refused)."""
    index = _as_int(name, value, "an int view index")
    if not 0 <= index < count:
        msg = f"{name} must be a view index in 0..{count - 1}, got {value!r}"
        raise ValueError(msg)
    return index


def check_fraction(name: str, value) -> float:
    """Return ``value`` as float, or raise if it is not a number within [0, 1]."""
    return _check_number(name, value, "a number within [0, 1]", lambda x: 0 <= x <= 1, refused="within [0, 1]")


def as_vector3(name: str, value) -> np.ndarray:
    """Return ``value`` as a finite float64 vector of length 3."""
    items = list(value) if isinstance(value, (list, tuple)) else [value]
    why = next((w for w in map(_not_a_number, items) if w is not None), None)
    if why is None and isinstance(value, np.ndarray) and value.dtype.kind in "bUSc":
        why = f"array of {value.dtype}, not numbers"
    if why is not None:
        msg = f"{name} must be 3 numbers, got {value!r} ({why})"
        raise TypeError(msg)
    try:
        vec = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        msg = f"{name} must be 3 numbers, got {value!r}"
        raise TypeError(msg) from None
    if vec.shape != (3,):
        msg = f"{name} must have shape (3,), got shape {vec.shape}"
        raise ValueError(msg)
    if not np.all(np.isfinite(vec)):
        msg = f"{name} must be finite, got {vec.tolist()}"
        raise ValueError(msg)
    return vec


def float_dtype(dtype) -> np.dtype:
    """Validate a requested float dtype (float32 or float64)."""
    dt = np.dtype(dtype)
    if dt not in (np.dtype(np.float32), np.dtype(np.float64)):
        msg = f"dtype={dt} is not supported; use float32 or float64"
        raise ValueError(msg)
    return dt


#: Largest |intensity| accepted for float32 work: products of gradients overflow
#: float32 near 1e17 (measured: static stereo warned at 1e17, ran at 3e16).
MAX_FLOAT32_INTENSITY = 1e15

#: Smallest non-zero peak |intensity| accepted where float32 work squares gradients
#: (``as_image(..., min_peak=...)``: the fast path, whose |grad I| is
#: ``sqrt(I_col**2 + I_row**2)`` in float32). A square leaves float32's normal range
#: (1.2e-38) below |grad I| = 1.1e-19 and becomes 0 below about 3e-23, where the
#: reference's ``np.hypot`` is still exact. With the peak at 1e-15 or more, every
#: gradient above 1.1e-4 of the peak (edges far fainter than the default threshold,
#: 10 % of the 99th percentile, keeps) squares to a normal float, and one at the
#: rounding floor (``edges.ROUNDING_GRADIENT``, 1e-6 of the peak) to a non-zero one.
#: Measured on a textured triple scaled down: the fast path's |grad I| matched the
#: reference to 7e-7 relative (as at ordinary scales) down to a peak of 2e-17, to 3e-6
#: at 2e-18; at 2e-20 it was 1.3 % off with NaN flows, at 2e-23 no edge point was left.
#: The bound keeps a margin of about 100 as :data:`MAX_FLOAT32_INTENSITY` does.
MIN_FLOAT32_INTENSITY = 1e-15


def native(arr: np.ndarray) -> np.ndarray:
    """``arr`` in the machine's byte order: a big-endian array (a ``'>f4'`` .npy, FITS data) converted, others as they are.

    OpenCV reads the raw bytes as native numbers, so a byte-swapped float array
    came back as garbage (a constant 100 smoothed to 7e-41) without an error.
    """
    return arr if arr.dtype.isnative else arr.astype(arr.dtype.newbyteorder("="))


def is_real_numeric(arr: np.ndarray) -> bool:
    """True for an array of real numbers or booleans; False for complex, text, objects."""
    return arr.dtype != object and not np.iscomplexobj(arr) and (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool)


def as_real(name: str, values) -> np.ndarray:
    """``values`` as a float64 array; complex, text or objects refused with a TypeError (NumPy would drop an imaginary part with a warning)."""
    arr = np.asarray(values)
    if not is_real_numeric(arr):
        msg = f"{name} must be real numbers, got dtype {arr.dtype}"
        raise TypeError(msg)
    return arr.astype(float, copy=False)


def check_shape_rows_cols(shape) -> tuple[int, int]:
    """``shape`` as two positive ints ``(rows, cols)``: TypeError if it is no pair of integers (floats and text too), ValueError below 1."""
    try:
        rows, cols = (_as_int("shape", s, "(rows, cols) of integers") for s in shape)
    except (TypeError, ValueError):
        msg = f"shape must be (rows, cols) of integers, got {shape!r}"
        raise TypeError(msg) from None
    if rows < 1 or cols < 1:
        msg = f"shape must be positive, got {shape!r}"
        raise ValueError(msg)
    return rows, cols


def as_image(name: str, image, dtype=np.float32, *, min_peak: float = 0.0) -> np.ndarray:
    """Validate one 2-D grey image: real, finite, at least 2x2 (float32: |values| at most 1e15); return as ``dtype``.

    ``min_peak`` (e.g. :data:`MIN_FLOAT32_INTENSITY`): refuse an image whose largest
    ``|value|`` is non-zero but below it (an all-zero image passes); no extra pass.
    """
    arr = np.asarray(image)
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        msg = f"{name} must be a numeric 2-D array, got dtype {arr.dtype}"
        raise TypeError(msg)
    if np.iscomplexobj(arr):
        msg = f"{name} must be real, got complex dtype {arr.dtype}"
        raise TypeError(msg)
    if arr.ndim != 2:
        msg = f"{name} must be a 2-D grey image (rows, cols), got shape {arr.shape}"
        if arr.ndim == 3 and arr.shape[-1] in (3, 4):
            msg += "; convert colour to grey first (nfdepth.io.to_grey)"
        raise ValueError(msg)
    if arr.shape[0] < 2 or arr.shape[1] < 2:
        msg = f"{name} must be at least 2x2 pixels, got shape {arr.shape}"
        raise ValueError(msg)
    with np.errstate(over="ignore"):  # values beyond float32 become inf: reported below
        out = arr.astype(float_dtype(dtype), copy=False)
    # two reductions without a temporary: NaN propagates into both, inf shows in one
    lo, hi = float(out.min()), float(out.max())
    if out.dtype == np.float32 and np.isfinite(lo) and np.isfinite(hi) and max(-lo, hi) > MAX_FLOAT32_INTENSITY:
        msg = (
            f"{name} has intensities up to {max(-lo, hi):.3g}, beyond {MAX_FLOAT32_INTENSITY:g}: the float32 work squares "
            "gradients, which overflow beyond about 1e17; rescale the intensities (e.g. to 0-255 or 0-1)"
        )
        raise ValueError(msg)
    if 0 < max(-lo, hi) < min_peak:  # False for NaN (reported below)
        msg = (
            f"{name} has intensities only up to {max(-lo, hi):.3g}, below {min_peak:g}: the float32 work squares "
            "gradients, which underflow below about 1e-19; rescale the intensities (e.g. to 0-255 or 0-1)"
        )
        raise ValueError(msg)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        bad = int(np.count_nonzero(~np.isfinite(out)))
        if np.issubdtype(arr.dtype, np.floating) and np.all(np.isfinite(arr)):
            msg = (
                f"{name} has {bad} pixel(s) beyond the {out.dtype} range (max |value| "
                f"{float(np.max(np.abs(arr))):.3g}); rescale the intensities or use dtype=float64"
            )
            raise ValueError(msg)
        msg = f"{name} contains {bad} non-finite (NaN or inf) pixel(s); expected finite intensities"
        raise ValueError(msg)
    return out


def as_frames(name: str, frames, count: int | None = None, *, min_count: int = 1, dtype=np.float32, min_peak: float = 0.0) -> list[np.ndarray]:
    """Validate a sequence of same-shape 2-D images (or a 3-D array of them); ``min_peak`` as in :func:`as_image`."""
    if isinstance(frames, np.ndarray):
        if frames.ndim != 3:
            msg = f"{name} must be a sequence of 2-D images or an array of shape (N, rows, cols), got shape {frames.shape}"
            raise ValueError(msg)
        seq: Sequence = list(frames)
    elif isinstance(frames, (list, tuple)):
        seq = frames
    else:
        msg = f"{name} must be a sequence of 2-D arrays, got {type(frames).__name__}"
        raise TypeError(msg)
    if count is not None and len(seq) != count:
        msg = f"{name} must hold exactly {count} frames, got {len(seq)}"
        raise ValueError(msg)
    if len(seq) < min_count:
        msg = f"{name} must hold at least {min_count} frames, got {len(seq)}"
        raise ValueError(msg)
    for i, f in enumerate(seq):
        check_frame_size(f"{name}[{i}]", np.shape(f))
    out = [as_image(f"{name}[{i}]", f, dtype, min_peak=min_peak) for i, f in enumerate(seq)]
    shapes = {f.shape for f in out}
    if len(shapes) > 1:
        listed = ", ".join(str(f.shape) for f in out)
        msg = f"{name} must all have the same shape, got {listed}"
        raise ValueError(msg)
    return out
