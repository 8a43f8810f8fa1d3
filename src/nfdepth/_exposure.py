"""Views (and video frames) taken at different exposures, matched to the reference before the measurement.

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
Views that differ grossly (:data:`GROSS_GAIN`, :data:`GROSS_OFFSET`: a
gain of 3, an 8-bit view beside 16-bit ones) give the reduced pass no
match at all, so they are first matched by the whole images' quantiles
(:func:`_gross_prematch`), which views of one scene share closely.

:func:`match_frame_exposures` does the same for a video triple (eq. 4 at
the edge points of :func:`nfdepth.video.depth_from_video`), the
corresponding pixels from a dense map of the middle frame on the frames
reduced to an eighth, each point projected into the outer frames with
the known poses. On the Books row as a video, one frame 5 % brighter took
the edge points from 7.8 to 24.1 % bad-1px; matched, 7.5 %.

:func:`match_nearby_exposures` does it for dynamic stereo's five images,
which lie within a pixel or two of each other: no disparity is needed,
each image is paired with the middle one pixel by pixel where both are
flattest. :func:`match_camera_exposure` pairs two cameras' frames taken
from one pose (two videos' crossing), and :func:`clipped_apart` finds the
pixels beside a highlight that one exposure clipped and the other did not.
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
#: A view whose whole-image quantiles differ from the reference's by a gain beyond this factor (either way),
#: or by more than GROSS_OFFSET of the reference's 2-98 % intensity spread at its median, is first matched by
#: those quantiles: the reduced pass finds no match between views that far apart (a gain of 3 with a third
#: of the view clipped; an 8-bit view beside a 16-bit one).
GROSS_GAIN = 1.5
GROSS_OFFSET = 0.25
#: The whole-image quantiles of that test are taken on every _SAMPLE_STEP-th pixel of every _SAMPLE_STEP-th row.
_SAMPLE_STEP = 4
#: Side of the reduced views of the first pass, px (at least; halved while the shorter side stays above it).
_PASS_MIN_SIDE_PX = 48
#: Largest reduction (an eighth of the size).
_PASS_MAX_DOWN = 3
#: Fewest fitted pixels per view (a smaller sample leaves the view as it is).
_MIN_PAIRS = 200
_ROUNDS = 2
#: Pixels this close to a reduced view's border are not compared (px).
_BORDER_PX = 4

#: A video's frames (:func:`match_frame_exposures`) are fitted through their flatter half of the pairs (by the
#: larger gradient magnitude of the two at _FLAT_SIGMA_PX), which the pairs' misplacement by the reduced dense map
#: and the scene's motion change least; the test of the fit takes every pair. On the rendered rail with every other
#: frame 8 grey levels brighter, the fits through every pair were up to half a grey level off, a single triple's
#: median depth error 2.1-5.3 % against 1.8-2.5 % with the frames taken as they are; through the flatter half,
#: 1.8-2.6 %. Teddy's row (black levels 1-3 grey levels apart): 2192 points at 2.11 % / 11.3 % bad-1px before,
#: 2182 at 1.61 % / 11.8 %.
_FRAME_FLAT_SHARE = 0.5
#: Frames taken a pixel or two apart (:func:`match_nearby_exposures`) are compared at the pixels where both are
#: flattest: this share of the frame, by the larger of the two gradient magnitudes at _FLAT_SIGMA_PX (px), whose
#: intensities such a motion changes least. Measured on Tsukuba reduced to a quarter (1.25 px between views):
#: gains of 1.05 found as 1.047-1.050, equal views left alone (ratios 0.97-1.02, also 2.5 px apart); with half
#: the frame, 1.040-1.056 at ratios of 0.75-0.78, close to MAX_RESIDUAL_RATIO.
_FLAT_SHARE = 0.2
_FLAT_SIGMA_PX = 1.0
#: Those frames are compared halved (``cv2.pyrDown``, which also halves the motion) while at least this many
#: pixels remain (every pixel of a 640 x 480 frame cost 8 ms a frame).
_NEARBY_SAMPLE = 40_000


def _gradient_magnitude(img: np.ndarray) -> np.ndarray:
    """The gradient magnitude of the float32 image ``img`` smoothed by :data:`_FLAT_SIGMA_PX`: low where it is flat."""
    s = cv2.GaussianBlur(img, (0, 0), _FLAT_SIGMA_PX)
    return cv2.magnitude(cv2.Sobel(s, cv2.CV_32F, 1, 0), cv2.Sobel(s, cv2.CV_32F, 0, 1))


def _reduction(shape) -> int:
    """How many ``cv2.pyrDown`` halvings the first pass takes: up to :data:`_PASS_MAX_DOWN`, the shorter side kept at :data:`_PASS_MIN_SIDE_PX` or more."""
    side = min(shape)
    down = 0
    while down < _PASS_MAX_DOWN and (side >> (down + 1)) >= _PASS_MIN_SIDE_PX:
        down += 1
    return down


def _reduced(img: np.ndarray, down: int) -> np.ndarray:
    for _ in range(down):
        img = cv2.pyrDown(img)
    return img


#: The quantiles of the exposure lines (percent).
_QUANTILES = np.linspace(2.0, 98.0, 49)


def _quantiles(values, q=_QUANTILES) -> np.ndarray:
    """``np.percentile(values, q)`` over all of ``values``, bit for bit: the same order statistics, taken from a
    sorted copy (NumPy's vectorised sort), 4-5 times faster than the partition at 49 quantiles of 20-80 thousand values."""
    return np.percentile(np.sort(values, axis=None), q)


def _line(qx, qy) -> tuple[float, float]:
    """The least-squares line ``qy ~ g qx + o`` through paired quantiles."""
    a = np.stack([qx, np.ones_like(qx)], axis=1)
    (g, o), *_ = np.linalg.lstsq(a, qy, rcond=None)
    return float(g), float(o)


def _unclipped(values, image) -> np.ndarray:
    """Where ``values`` (intensities of ``image``) lie more than 1 % of its range from either end: not saturated."""
    lo, hi = float(image.min()), float(image.max())
    return (values > lo + 0.01 * (hi - lo)) & (values < hi - 0.01 * (hi - lo))


def _exposure_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """``y ~ g x + o`` for two images' intensities over the same scene points: the line through their quantiles.

    The least-squares line of ``y`` on ``x`` shrinks ``g`` toward 0 by
    the share of ``x``'s variance that is noise or misalignment (0.96-0.97
    on a synthetic plane whose views share one exposure); the quantiles of
    the two samples (2nd to 98th percentile) do not pair single pixels,
    so neither matters, and a few occluded or wrong pixels move them
    little.
    """
    return _line(_quantiles(x), _quantiles(y))


def _fit(views, ref, t, disparity_range_px, threads):
    """One round: ``[(g_k, o_k) or None]`` per view from a reduced static-stereo pass (None: reference, or too few pixels)."""
    from .stereo import static_stereo

    down = _reduction(views[0].shape)
    small = [_reduced(v, down) for v in views]
    options = {"positions": t, "threads": threads}
    if disparity_range_px is not None:
        # the range at the reduced size, at least 2 px wide (four candidate steps): a narrow range would be refused there
        lo, hi = (v / 2**down for v in disparity_range_px)
        mid, half = 0.5 * (lo + hi), max(0.5 * (hi - lo), 1.0)
        options["disparity_range_px"] = (mid - half, mid + half)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the reduced pass's own notes; the full run says what matters
            res = static_stereo(small, reference=ref, match_exposure=False, **options)
    except ValueError:  # the reduced views cannot be measured (the full run says why, if it cannot either)
        return [None] * len(views)
    d = res.disparity
    known = np.isfinite(d)
    r = small[ref]
    h, w = r.shape
    rows, cols = np.mgrid[0:h, 0:w]
    # whole pixels (a bilinear read between pixels would smooth the view's intensities against the
    # reference's), away from the borders
    m = _BORDER_PX
    known &= (rows >= m) & (rows <= h - 1 - m) & (cols >= m) & (cols <= w - 1 - m)
    fits = []
    for k, view in enumerate(small):
        if k == ref:
            fits.append(None)
            continue
        src = np.rint(cols - np.where(known, (t[k] - t[ref]) * d, 0.0)).astype(np.intp)
        ok = known & (src >= m) & (src <= w - 1 - m)
        fits.append(_checked_fit(r[ok], view[rows[ok], src[ok]], r, view))
    return fits


def _checked_fit(x, y, ref_image, image, line_from=None):
    """``(g, o, ratio)`` of the pairs ``(x, y)`` (the reference's and the other image's intensities), or None with too few.

    Pairs where either image is saturated (within 1 % of its own range's
    ends) are left out: a clipped highlight says nothing of the gain.
    ``ratio``: the pairs' median absolute difference after the fit against
    before (how much of it the fitted exposure leaves). ``line_from``: the
    pairs (a mask) the line is fitted through, where there are enough of
    them (default: all); the ratio is always taken over all.
    """
    keep = _unclipped(x, ref_image) & _unclipped(y, image)
    if np.count_nonzero(keep) < _MIN_PAIRS:
        return None
    chosen = keep & line_from if line_from is not None else keep
    if np.count_nonzero(chosen) < _MIN_PAIRS:
        chosen = keep
    g, o = _exposure_line(x[chosen].astype(np.float64), y[chosen].astype(np.float64))
    x, y = x[keep].astype(np.float64), y[keep].astype(np.float64)
    if not (np.isfinite(g) and np.isfinite(o) and g > 0):
        return None
    before = float(np.median(np.abs(y - x)))
    after = float(np.median(np.abs(y - (g * x + o))))
    return g, o, after / before if before > 0 else 1.0


def _global_line(ref_image, image):
    """``image ~ g ref_image + o`` from the two whole images' quantiles (no pixel pairs), or None.

    The quantiles (2nd to 98th percentile) within 1 % of either image's
    range ends are left out (clipped highlights and shadows, and a scene's
    own brightest or darkest plateau: a white background); at least a
    quarter must remain (the rendered rail's frames, dimmed, keep 21-22 of 49).
    """
    qx, qy = _quantiles(ref_image), _quantiles(image)
    keep = _unclipped(qx, ref_image) & _unclipped(qy, image)
    if np.count_nonzero(keep) < _QUANTILES.size // 4 or np.ptp(qx[keep]) <= 0:
        return None
    g, o = _line(qx[keep], qy[keep])
    return (g, o) if np.isfinite(g) and np.isfinite(o) and g > 0 else None


def _gross_prematch(images, ref: int, total) -> None:
    """Undo, in place, the exposures that differ grossly from the reference's (:data:`GROSS_GAIN`, :data:`GROSS_OFFSET`).

    Found from the whole images' quantiles (:func:`_global_line`): views of
    one scene share their histograms closely, and a difference that large
    (a gain of 3, an 8-bit view beside a 16-bit one) leaves the reduced
    pass no match to fit from. The rounds of pairs refine what remains.
    """
    # every 4th pixel of every 4th row: the quantiles of a grossly different exposure need no more (and the
    # full frames' 49 quantiles cost a video 10-20 ms a triple)
    sample = [np.asarray(img)[::_SAMPLE_STEP, ::_SAMPLE_STEP] for img in images]
    ref_image = sample[ref]
    ordered = np.sort(ref_image, axis=None)  # (the order statistics below are np.percentile's and np.median's of ref_image)
    spread = float(np.percentile(ordered, 98.0) - np.percentile(ordered, 2.0))
    median = float(np.median(ordered))
    for k, image in enumerate(sample):
        if k == ref:
            continue
        line = _global_line(ref_image, image)
        if line is None:
            continue
        g, o = line
        if not (1.0 / GROSS_GAIN <= g <= GROSS_GAIN) or abs(o + (g - 1.0) * median) > GROSS_OFFSET * spread:
            images[k] = _undone(images[k], g, o)
            total[k] = (g, o)


def _undone(image, g: float, o: float) -> np.ndarray:
    """``image`` (``g I + o`` of another exposure) on that exposure: ``(image - o) / g``, float32."""
    return ((image - np.float32(o)) / np.float32(g)).astype(np.float32)


def _undo(images, total, k, fit) -> bool:
    """Undo ``fit`` (``(g, o, ratio)`` or None) on ``images[k]`` if it explains enough, composing ``total[k]``; whether it did.

    A new correction must leave at most :data:`MAX_RESIDUAL_RATIO` of the
    pairs' median difference; one found in an earlier round is refined
    wherever it lowers it at all.
    """
    if fit is None:
        return False
    g, o, ratio = fit
    if ratio > (1.0 if total[k] != (1.0, 0.0) else MAX_RESIDUAL_RATIO):
        return False
    images[k] = _undone(images[k], g, o)
    g0, o0 = total[k]
    total[k] = (g0 * g, o0 + g0 * o)  # I = g0 (g I_ref + o) + o0
    return True


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
    _gross_prematch(views, ref, total)
    for _ in range(_ROUNDS):
        fits = _fit(views, ref, t, disparity_range_px, threads)
        moved = False
        for k, fit in enumerate(fits):
            moved |= _undo(views, total, k, fit)
        if not moved:
            break
    applied = [None if k == ref or total[k] == (1.0, 0.0) else total[k] for k in range(len(views))]
    return views, applied


def match_frame_exposures(frames, camera, rotations, positions, *, middle: int, threads: int | None = None):
    """Video frames mapped onto the middle frame's exposure, and each frame's ``(gain, offset)`` undone (or None).

    As :func:`match_exposures`, for frames of a camera that moves (and
    turns) along a path: the corresponding pixels come from a dense map of
    the middle frame on the frames reduced to an eighth
    (:func:`nfdepth._dense_video.dense_row`), each middle pixel's point
    projected into the other frames. ``rotations``: camera-to-world
    matrices; ``positions``: optical centres (world). Frames whose path
    gives no dense map (along the optical axis) are left as they are.
    """
    from ._dense_video import dense_row

    frames = [np.asarray(f, np.float32) for f in frames]
    total = [(1.0, 0.0)] * len(frames)
    _gross_prematch(frames, middle, total)
    down = _reduction(frames[0].shape)
    scale = 2.0**down
    for _ in range(_ROUNDS):
        small = [_reduced(f, down) for f in frames]
        h, w = small[middle].shape
        cam = camera.reduced(scale, (h, w))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                row = dense_row(small, cam, rotations, positions, middle=middle, noise_std=None, threads=threads, match_exposure=False)
        except ValueError:  # the reduced frames cannot be measured: left as they are
            break
        rho = row.rho
        m = _BORDER_PX
        rows, cols = np.mgrid[0:h, 0:w]
        known = np.isfinite(rho) & (rho > 0) & (rows >= m) & (rows <= h - 1 - m) & (cols >= m) & (cols <= w - 1 - m)
        if np.count_nonzero(known) < _MIN_PAIRS:
            break
        r_i, c_i = rows[known], cols[known]
        points = cam.back_project(r_i, c_i, 1.0 / rho[known])  # middle camera axes
        world = points @ np.asarray(rotations[middle], float).T + np.asarray(positions[middle], float)
        middle_flatness = _gradient_magnitude(small[middle])
        moved = False
        for k, frame in enumerate(small):
            if k == middle:
                continue
            rk, ck, zk = cam.project((world - np.asarray(positions[k], float)) @ np.asarray(rotations[k], float))
            with np.errstate(invalid="ignore"):
                ok = (zk > 0) & (rk >= m) & (rk <= h - 1 - m) & (ck >= m) & (ck <= w - 1 - m)
            if np.count_nonzero(ok) < _MIN_PAIRS:
                continue
            ri, ci = np.rint(rk[ok]).astype(np.intp), np.rint(ck[ok]).astype(np.intp)
            x, y = small[middle][r_i[ok], c_i[ok]], frame[ri, ci]
            # the line through the flatter half (:data:`_FRAME_FLAT_SHARE`), the test over all pairs
            flatness = np.maximum(middle_flatness[r_i[ok], c_i[ok]], _gradient_magnitude(frame)[ri, ci])
            flat = flatness <= np.percentile(np.sort(flatness), 100.0 * _FRAME_FLAT_SHARE)
            moved |= _undo(frames, total, k, _checked_fit(x, y, small[middle], frame, line_from=flat))
        if not moved:
            break
    return frames, [None if k == middle or total[k] == (1.0, 0.0) else total[k] for k in range(len(frames))]


def match_camera_exposure(first, frames, *, at: int):
    """A second camera's ``frames`` mapped onto the first camera's exposure, and the ``(gain, offset)`` undone or None.

    ``first`` and ``frames[at]`` are taken from one pose (dynamic stereo's
    crossing), so every pixel is a pair: the same quantile line and test as
    :func:`match_exposures` (``frames[k] = gain first + offset``).
    """
    images, total = [frames[at]], [(1.0, 0.0)]
    if not _undo(images, total, 0, _checked_fit(first.ravel(), frames[at].ravel(), first, frames[at])):
        return frames, None
    g, o = total[0]
    return [images[0] if k == at else _undone(f, g, o) for k, f in enumerate(frames)], (g, o)


def match_nearby_exposures(frames, *, middle: int):
    """Frames taken a pixel or two apart mapped onto ``frames[middle]``'s exposure, and each one's ``(gain, offset)`` undone (or None).

    For dynamic stereo's five images (:func:`nfdepth.pipelines.dynamic_stereo`),
    which move by no more than the differential range between them, so
    that no disparity is needed to pair their pixels: each frame is paired
    with the middle one pixel by pixel where both are flattest
    (:data:`_FLAT_SHARE`; on the frames halved down to
    :data:`_NEARBY_SAMPLE` pixels), and the same quantile line and test as
    :func:`match_exposures` decide (``frames[k] = gain frames[middle] +
    offset``, undone where it explains the pairs' differences). Pixel
    pairs need no first match, so grossly different exposures (a gain of 3,
    an 8-bit frame beside 16-bit ones) are found the same way. Frames of
    one exposure are returned as they are (the same objects).
    """
    frames = list(frames)
    total = [(1.0, 0.0)] * len(frames)
    down = 0
    while down < _PASS_MAX_DOWN and frames[middle].size >= _NEARBY_SAMPLE * 4 ** (down + 1):
        down += 1
    small = [_reduced(np.asarray(f, np.float32), down) for f in frames]
    h, w = small[middle].shape
    m = _BORDER_PX if min(h, w) > 4 * _BORDER_PX else 0
    inner = (slice(m, h - m), slice(m, w - m))
    flatness = [_gradient_magnitude(f)[inner] for f in small]

    for k in range(len(frames)):
        if k != middle:
            both = np.maximum(flatness[middle], flatness[k])
            flat = both <= np.percentile(np.sort(both, axis=None), 100.0 * _FLAT_SHARE)
            _undo(frames, total, k, _checked_fit(small[middle][inner][flat], small[k][inner][flat], small[middle], small[k]))
    return frames, [None if k == middle or total[k] == (1.0, 0.0) else total[k] for k in range(len(frames))]


_PLATEAU_TOLERANCE = 1e-6  # of an image's range: rounding, far below a grey level of 8 or 16 bits


def _plateaus(img) -> tuple[np.ndarray, np.ndarray]:
    """The pixels at ``img``'s own highest and lowest value, each where at least 0.1 % of them hold it (a clipped plateau), else none.

    "At" is within ``_PLATEAU_TOLERANCE`` of the range: float images rendered
    or converted in float64 hold their white as 255 and 255.0000000000029
    side by side. A constant image is one plateau (all of it at its bottom).
    """
    lo, hi = float(img.min()), float(img.max())
    none = np.zeros(np.shape(img), bool)
    if not hi > lo:
        return none, np.ones(np.shape(img), bool)
    tol = _PLATEAU_TOLERANCE * (hi - lo)
    top, bottom = img >= hi - tol, img <= lo + tol
    return (top if top.mean() >= 1e-3 else none), (bottom if bottom.mean() >= 1e-3 else none)


def clipped_apart(moving_c, reference_c, exposure, reach_px: int) -> np.ndarray:
    """Pixels within ``reach_px`` of a plateau that one camera's exposure clipped and the other's did not.

    ``exposure``: ``(g, o)`` with ``R = g M + o`` (None: equal). A pixel on
    one frame's top (bottom) plateau is clipped there when the other frame,
    mapped to its exposure, lies above (below) that plateau by more than a
    grey level: its intensities are not the other camera's, matched or
    not, and the normal flows of its frames are wrong. Plateaus both
    cameras share at one exposure (a white background) are the scene's.
    """
    g, o = exposure if exposure is not None else (1.0, 0.0)
    m = moving_c.astype(np.float64)
    r = reference_c.astype(np.float64)
    (m_top, m_bottom), (r_top, r_bottom) = _plateaus(m), _plateaus(r)
    r_seen, m_seen = g * m + o, (r - o) / g  # each frame as the other camera would have taken it
    out = (r_top & (r_seen > r.max() + 1.0)) | (r_bottom & (r_seen < r.min() - 1.0))
    out |= (m_top & (m_seen > m.max() + 1.0)) | (m_bottom & (m_seen < m.min() - 1.0))
    if out.any() and reach_px > 0:
        out = cv2.dilate(out.astype(np.uint8), np.ones((2 * reach_px + 1, 2 * reach_px + 1), np.uint8)).astype(bool)
    return out
