"""Views taken at different exposures, matched to the reference before static stereo.

Eq. 6 reads every intensity difference between views as motion: a view
whose exposure (gain) or black level (offset) differs from the reference's
adds ``(g - 1) I + o`` to each difference, which the differential
estimate turns into a disparity error of ``((g - 1) I + o) / I_x``, many
pixels where the image is smooth. Measured on the Middlebury rows (three
views, one outer view scaled): a gain of 1.02 already lost 9 % of Books'
edge points (bad-1px 1.36 → 1.92 %), 1.05 two thirds, and 1.25 or an
offset of 20 grey levels 90-95 % of them, with half the dense map. Real
cameras differ by that much (auto exposure; a third of a stop is 26 %).

:func:`match_exposures` fits each view's intensities against the
reference's as ``I_k = g_k I_ref + o_k`` and maps them back, ``(I_k -
o_k) / g_k``. The corresponding pixels come from a first static-stereo
pass on the views reduced to an eighth (cheap: 3-5 % of the full run at
640 x 480), read at whole pixels of the view (a bilinear read between pixels
would smooth its intensities), away from the borders and unsaturated (a
clipped highlight says nothing of the gain); the line runs through the
two samples' quantiles (2nd to 98th percentile), which single misaligned
or occluded pixels move little and whose noise does not shrink the gain
as a least-squares line's would. The fit is undone only where it
explains the corresponding pixels' differences: their median absolute
difference must fall to :data:`MAX_RESIDUAL_RATIO` of what it was, so
views that share one exposure (the Middlebury rows, synthetic scenes:
0.80-1.22) are left exactly as they are. Two rounds: the second pass,
on the corrected views, refines a first correction wherever it lowers
that difference further (a gain of 1.05 found as 1.041, then the rest).
"""

from __future__ import annotations

import warnings

import cv2
import numpy as np

#: A fitted exposure is undone only where it leaves at most this share of the median difference between
#: corresponding pixels (it must explain the rest). Measured: 0.07-0.44 for gains of 1.05 or offsets of 20
#: grey levels on the Middlebury rows and Tsukuba; 0.80-1.22 where the views share one exposure (real and
#: synthetic).
MAX_RESIDUAL_RATIO = 0.7
#: Side of the reduced views of the first pass, px (at least; halved while the shorter side stays above it).
_PASS_MIN_SIDE_PX = 48
#: Largest reduction (an eighth of the size).
_PASS_MAX_DOWN = 3
#: Fewest fitted pixels per view (a smaller sample leaves the view as it is).
_MIN_PAIRS = 200
_ROUNDS = 2
#: Pixels this close to a reduced view's border are not compared (px).
_BORDER_PX = 4


def _reduced(img: np.ndarray, down: int) -> np.ndarray:
    for _ in range(down):
        img = cv2.pyrDown(img)
    return img


def _exposure_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """``y ~ g x + o`` for two images' intensities over the same scene points: the line through their quantiles.

    The least-squares line of ``y`` on ``x`` shrinks ``g`` toward 0 by
    the share of ``x``'s variance that is noise or misalignment (0.96-0.97
    on a synthetic plane whose views share one exposure); the quantiles of
    the two samples (2nd to 98th percentile) do not pair single pixels,
    so neither matters, and a few occluded or wrong pixels move them
    little.
    """
    q = np.linspace(2.0, 98.0, 49)
    qx, qy = np.percentile(x, q), np.percentile(y, q)
    a = np.stack([qx, np.ones_like(qx)], axis=1)
    (g, o), *_ = np.linalg.lstsq(a, qy, rcond=None)
    return float(g), float(o)


def _fit(views, ref, t, disparity_range_px, threads):
    """One round: ``[(g_k, o_k) or None]`` per view from a reduced static-stereo pass (None: reference, or too few pixels)."""
    from .stereo import static_stereo

    side = min(views[0].shape)
    down = 0
    while down < _PASS_MAX_DOWN and (side >> (down + 1)) >= _PASS_MIN_SIDE_PX:
        down += 1
    small = [_reduced(v, down) for v in views]
    options = {"positions": t, "threads": threads}
    if disparity_range_px is not None:
        options["disparity_range_px"] = tuple(v / 2**down for v in disparity_range_px)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the reduced pass's own notes; the full run says what matters
        res = static_stereo(small, reference=ref, match_exposure=False, **options)
    d = res.disparity
    known = np.isfinite(d)
    r = small[ref]
    h, w = r.shape
    rows, cols = np.mgrid[0:h, 0:w]
    # whole pixels (a bilinear read between pixels would smooth the view's intensities against the
    # reference's), away from the borders
    m = _BORDER_PX
    known &= (rows >= m) & (rows <= h - 1 - m) & (cols >= m) & (cols <= w - 1 - m)
    r_lo, r_hi = float(r.min()), float(r.max())
    fits = []
    for k, view in enumerate(small):
        if k == ref:
            fits.append(None)
            continue
        src = np.rint(cols - np.where(known, (t[k] - t[ref]) * d, 0.0)).astype(np.intp)
        ok = known & (src >= m) & (src <= w - 1 - m)
        x = r[ok]
        y = view[rows[ok], src[ok]]
        v_lo, v_hi = float(view.min()), float(view.max())
        # unsaturated on both sides (1 % of each range in from its ends): a clipped highlight says nothing of the gain
        keep = (x > r_lo + 0.01 * (r_hi - r_lo)) & (x < r_hi - 0.01 * (r_hi - r_lo))
        keep &= (y > v_lo + 0.01 * (v_hi - v_lo)) & (y < v_hi - 0.01 * (v_hi - v_lo))
        if np.count_nonzero(keep) < _MIN_PAIRS:
            fits.append(None)
            continue
        x, y = x[keep].astype(np.float64), y[keep].astype(np.float64)
        g, o = _exposure_line(x, y)
        # how much of the corresponding pixels' median difference the fitted exposure explains
        before = float(np.median(np.abs(y - x)))
        after = float(np.median(np.abs(y - (g * x + o))))
        fits.append((g, o, after / before if before > 0 else 1.0))
    return fits


def match_exposures(views, ref: int, t, *, disparity_range_px=None, threads: int | None = None):
    """The views mapped onto the reference's exposure (module docstring), and each view's ``(gain, offset)`` applied.

    ``views``: float32 2-D arrays along the row (axis "x"); ``t``: their
    positions. Returns ``(views, applied)``: the views (the same objects
    where nothing was applied) and, per view, ``(g, o)`` with ``I_k = g
    I_ref + o`` as undone, or None (the reference, an exposure that
    explains too little, or too few pixels to fit).
    """
    views = list(views)
    total = [(1.0, 0.0)] * len(views)
    for _ in range(_ROUNDS):
        fits = _fit(views, ref, t, disparity_range_px, threads)
        moved = False
        for k, fit in enumerate(fits):
            if fit is None:
                continue
            g, o, ratio = fit
            # a new correction must explain the differences; one found in the first round is refined wherever it helps
            if not (np.isfinite(g) and np.isfinite(o) and g > 0) or ratio > (1.0 if total[k] != (1.0, 0.0) else MAX_RESIDUAL_RATIO):
                continue
            views[k] = ((views[k] - np.float32(o)) / np.float32(g)).astype(np.float32)
            g0, o0 = total[k]
            total[k] = (g0 * g, o0 + g0 * o)  # I = g0 (g I_ref + o) + o0
            moved = True
        if not moved:
            break
    applied = [None if k == ref or total[k] == (1.0, 0.0) else total[k] for k in range(len(views))]
    return views, applied
