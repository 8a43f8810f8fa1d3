"""Depth from a single camera moving through a static scene (video).

Each triple of successive frames ``(k-1, k, k+1)`` is static stereo (paper
section 2.3): the stationary partner's normal flow is zero, so the relative
normal flow is the sequence's own, with relative motion ``dV = -T`` where
``T = R_k^T (P_k+1 - P_k-1) / 2`` is the camera's translation per frame
(central difference of the known positions, in frame ``k``'s camera axes;
``R_k`` is its camera-to-world orientation). Inverse depth and its standard
deviation come from :func:`nfdepth.pipelines.static_stereo_edges` at the
strong zero-crossing edge points of frame ``k`` (paper eq. 4, general
translation direction, so forward motion works as well as lateral).

A camera that also turns (poses whose orientation changes) has its outer
frames turned to frame ``k``'s orientation first (:mod:`nfdepth._derotation`,
the homography ``K R_j^T R_k K^-1``): eq. 4's rotational term ``A`` removed
exactly, at any rotation, instead of to first order. Edge points where a
turned frame has nothing to read (it looked elsewhere) are ``NO_DATA``.

Temporal fusion (a per-pixel Kalman filter on inverse depth)
-------------------------------------------------------------
The state is a map of inverse depth ``rho`` and variance on the cell grid of
the frame: map pixel ``[i, j]`` holds the estimate at the cell centre
``(i + 0.5, j + 0.5)`` (:mod:`nfdepth.normal_flow`). From frame ``k-1`` to
``k``:

1. *Predict*: every state point is back-projected with its depth, moved by
   the camera's displacement ``-(P_k - P_k-1)``, turned by its rotation
   ``R_k-1^T R_k`` if it turned, and re-projected
   (:meth:`PinholeCamera.project`); its inverse depth becomes ``1/Z'`` and
   its std scales by ``(Z/Z')**2``. Where two points land on one pixel the
   nearer wins. Process noise inflates the variance:
   ``var += (process_noise * rho)**2`` per frame.
2. *Associate*: a new edge measurement takes the prior at its own pixel or,
   failing that, the one with the smallest variance in its 3 x 3
   neighbourhood (edges move by sub-pixel amounts and zero crossings snap to
   cells). A prior more than ``gate`` combined standard deviations away is
   dropped (occlusion, a new surface) and the measurement starts afresh.
3. *Update*: ``rho = (rho_p / var_p + rho_n / var_n) / (1/var_p + 1/var_n)``,
   ``var = 1 / (1/var_p + 1/var_n)``.
4. Points not measured for more than ``max_age`` frames are dropped.

Measurement standard deviations are floored at ``min_std_px`` of disparity
(``rho_std >= min_std_px / (f |T|)``): the noise model does not see the
stencil's discretisation error, and noise-free frames would otherwise get
infinite weight.

The differential method measures motions of up to about 1-2 px per frame
(``f |T| / Z``). Faster cameras are handled coarse to fine: every triple
first gets a dense inverse-depth prior from a Gaussian pyramid, and the
paper's measurement runs on the triple warped by it
(:mod:`nfdepth._translating_pyramid`; ``levels``, default from the frame
size; ``levels=1`` is the paper's single level). Unequal steps (a camera
that speeds up or slows down, a dropped frame) are warped each by its own
step ``R_k^T (P_j - P_k)``; the single level takes the frames as equally
spaced.

Two synchronised videos (dynamic stereo)
----------------------------------------
:func:`dynamic_stereo_from_videos` is the paper's dynamic stereo (Fig. 3,
eq. 4) on two synchronised videos: frame ``k`` of the moving camera's video
``M`` and of the reference camera's video ``R`` are taken at the same
instant. The relative normal flow is only defined where the two image planes
coincide (the paper: "the two cameras come so close to each other at the
time of consideration that correspondence between the two image planes is
easy to establish"), so depth is computed at *crossing instants* ``c``, the
frames at which the moving camera passes through the reference camera's
position and orientation, from the interleaved five-image sequence::

    I1 = M[c-2], I2 = R[c-1], I3 = M[c] and R[c], I4 = R[c+1], I5 = M[c+2]

(:func:`interleaved_frames`). Away from a crossing the two cameras see
different image planes and the flows cannot be subtracted pixel by pixel;
no depth is produced there. ``[motion]`` gives the moving camera's motion
relative to the reference one at the crossings (the same at every crossing),
``frame_interval`` the time between consecutive video frames. See
``docs/rig-format.md`` for the rigs this fits.
"""

from __future__ import annotations

import glob as _glob
import inspect
import math
import os
import re
import reprlib
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from ._dense_video import MIN_SIDEWAYS_DEG, dense_row
from ._derotation import derotate, derotation_maps, measurable, moves_pixels
from ._exposure import clipped_apart, match_camera_exposure, match_frame_exposures
from ._translating_pyramid import (
    coarse_motion_px,
    edge_depth_coarse_to_fine,
    outer_reach,
)
from ._validate import (
    UNIT_SCALE_RANGE,
    as_image,
    as_path,
    check_bool,
    check_fraction,
    check_int,
    check_noise_std,
    check_scale_px,
    check_threshold,
    is_real_numeric,
)
from .camera import PinholeCamera
from .depth import Reason
from .edges import NoEdgePointsWarning, _no_edge_points
from .io import READ_EXTENSIONS, ImageReadError, read_image, to_float32_map, to_grey
from .normal_flow import _check_stencil, estimate_noise_std
from .pipelines import (
    _DIFFERENTIAL_RANGE_PX,
    _DISPLACEMENT_WARNING,
    _ORDER_CHECK_MIN_POINTS,
    EdgeDepth,
    _check_sigma_fits,
    _depth_bearing_mask,
    _median_displacement,
    _point_pixels,
    _void_points,
    dynamic_stereo,
    static_stereo_edges,
)
from .rig import (
    MAX_TURN_DEG,
    Rig,
    RigError,
    VideoSpec,
    _check_dynamic_options,
    _check_steps,
    check_crossings,
    dynamic_stereo_from_rig,
    edge_depth_maps,
)
from .stereo import auto_levels

# FFmpeg logs a video it cannot open on stderr ("moov atom not found"), ahead of
# nfdepth's own one-line error. OpenCV reads this once, when it opens its first
# video in the process, so it is set when this module is imported, before any
# read_video; a level the user set wins.
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

_UNITS_HINT = "give the rig's focal length and camera positions or speed in units that keep depths in that range"

__all__ = [
    "VideoDepthFrame",
    "FrameSource",
    "read_video",
    "depth_from_video",
    "VIDEO_EXTENSIONS",
    "NPZ_ARRAYS",
    "NPZ_DENSE_ARRAYS",
    "write_video_npz",
    "write_video_frame",
    "video_frame_names",
    "CrossingDepth",
    "SHARED_FRAME_CHOICES",
    "interleaved_frames",
    "dynamic_stereo_from_videos",
    "write_crossings_npz",
]

#: Extensions :func:`read_video` opens with ``cv2.VideoCapture``.
VIDEO_EXTENSIONS = (".mp4", ".avi", ".mov", ".mkv", ".m4v", ".webm", ".mpg", ".mpeg", ".wmv")


# ------------------------------------------------------------------ reading


def _natural_key(path: Path):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", path.name)]


def _no_edge_points_in_frames(first: NoEdgePointsWarning, frames: list, triples: int, dense: bool) -> NoEdgePointsWarning:
    """One warning for the frames with no edge point, in the words of the ``first`` one's; a run's own hint for corners
    (the edge rules' hint names max_corner_ratio, an option of the pipelines that depth_from_video does not take)."""
    hint = first.hint
    if first.rule == "corner":
        hint = f"(a texture of blobs rather than edges: {'the dense maps measure it' if dense else 'dense=True / --dense measures it'})"
    return _no_edge_points(
        f"in {len(frames)} of {triples} frames ({_frame_list(frames)}), e.g. frame {frames[0]}: {first.reason}",
        first.rule,
        hint,
        "" if dense else "those frames have no depth of their own",
    )


#: A video file that decodes fewer than this share of the frames its container declares is reported (a truncated file).
_DECODED_SHARE = 0.9

#: FFmpeg's tag of 16-bit little-endian grey (``CAP_PROP_CODEC_PIXEL_FORMAT``, e.g. a 16-bit FFV1 video): the one
#: format deeper than 8 bits that OpenCV hands over as decoded (uint16) when told not to convert it to 8-bit BGR.
_GRAY16LE = int.from_bytes(b"Y1\x00\x10", "little")


def _stored_bits(tag: int) -> int:
    """Bits per sample of a decoded video's pixel format, from FFmpeg's tag of it (``CAP_PROP_CODEC_PIXEL_FORMAT``); 8 where
    it is 8 or less, or unknown.

    Reads the tags of FFmpeg's raw formats (libavcodec/raw.c) deeper than 8 bits: grey, YUV(A) and planar RGB(A)
    (``'Y1' 0 16``: gray16le, ``'Y3' 11 10``: yuv420p10le, ``'G3' 0 12``, ...; big-endian: the bytes reversed), and packed
    48-bit RGB and 64-bit RGBA (``'RGB' 48``, ``'RBA' 64``; big-endian: the bits first, ``48 'RGB'``).
    """
    if not 0 < tag < 1 << 32:  # (0 or -1: the backend does not say)
        return 8
    b = int(tag).to_bytes(4, "little")
    for planar in (b, b[::-1]):
        if planar[:2] in (b"Y1", b"Y2", b"Y3", b"Y4", b"G3", b"G4") and planar[2] in (0, 10, 11) and 8 < planar[3] <= 16:
            return planar[3]
    for letters, bits in ((b[:3], b[3]), (b[1:], b[0])):
        if (letters in (b"RGB", b"BGR") and bits == 48) or (letters in (b"RBA", b"BRA") and bits == 64):
            return 16
    return 8


class FrameSource:
    """Grey float32 frames of a video file or an image sequence, iterable once per ``iter``.

    Attributes
    ----------
    paths : list of Path or None
        The image files (image sequences), in natural sort order.
    video : Path or None
        The video file.
    """

    def __init__(self, *, paths=None, video=None):
        self.paths = paths
        self.video = video

    def __len__(self) -> int:
        if self.paths is not None:
            return len(self.paths)
        cap = cv2.VideoCapture(str(self.video))
        try:
            return max(int(cap.get(cv2.CAP_PROP_FRAME_COUNT)), 0)
        finally:
            cap.release()

    def __iter__(self) -> Iterator[np.ndarray]:
        if self.paths is not None:
            for p in self.paths:
                yield read_image(p, dtype=np.float32)
            return
        cap = cv2.VideoCapture(str(self.video))
        if not cap.isOpened():
            raise ImageReadError(f"cannot read video '{self.video}': OpenCV could not open it")
        try:
            tag = int(cap.get(cv2.CAP_PROP_CODEC_PIXEL_FORMAT))
            if tag == _GRAY16LE:  # its values as stored (0..65535, as a 16-bit PNG's), not OpenCV's 8-bit BGR of them
                cap.set(cv2.CAP_PROP_CONVERT_RGB, 0)
            elif _stored_bits(tag) > 8:
                warnings.warn(
                    f"video '{self.video}' stores {_stored_bits(tag)}-bit samples, which OpenCV reads at 8 bits: the frames"
                    " lose their finer intensity steps; a 16-bit grey video (FFV1) or 16-bit PNG frames keep them",
                    UserWarning,
                    stacklevel=2,
                )
            count = 0
            while True:
                ok, frame = cap.read()
                if not ok:
                    break
                count += 1
                if frame.ndim == 3:
                    frame = to_grey(frame[..., ::-1], dtype=np.float32)
                yield frame.astype(np.float32, copy=False)
            if count == 0:
                raise ImageReadError(f"cannot read video '{self.video}': no frames could be decoded")
            declared = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
            if declared - count >= 2 and count < _DECODED_SHARE * declared:  # (containers that estimate the count err by less)
                warnings.warn(
                    f"video '{self.video}' declares {declared} frames, but only the first {count} could be decoded "
                    "(a truncated or damaged file?): the results end there",
                    UserWarning,
                    stacklevel=2,
                )
        finally:
            cap.release()


def read_video(path) -> FrameSource:
    """Frames of a video file, an image folder or a glob pattern, as grey float32.

    Parameters
    ----------
    path : str or os.PathLike
        A video file (:data:`VIDEO_EXTENSIONS`, read with ``cv2.VideoCapture``,
        colour converted with BT.601 luma; a 16-bit grey stream, e.g. FFV1,
        keeps its values 0..65535 as a 16-bit PNG does, other streams deeper
        than 8 bits are read at 8 bits with a ``UserWarning``), a folder of images
        (:data:`nfdepth.io.READ_EXTENSIONS`), or a glob such as
        ``"frames/*.png"`` (only where no file or folder has that name:
        ``clip[1].avi`` is read as itself). Image sequences are sorted
        naturally (``f2.png`` before ``f10.png``).

    Returns
    -------
    FrameSource
        Iterable of ``(H, W)`` float32 frames, with ``len()``.

    FFmpeg's own log lines about a file it cannot decode are silenced
    (``OPENCV_FFMPEG_LOGLEVEL=-8``, set when this module is imported unless
    already set): the error is nfdepth's one line.

    Raises
    ------
    ImageReadError
        Nothing matched, or an unsupported file type.
    """
    text = str(as_path("path", path))
    p = Path(text)
    if p.is_dir():
        try:
            # not hidden files (macOS's ._*.png resource forks, editors' backups), as the glob form leaves them out
            files = [f for f in p.iterdir() if f.is_file() and f.suffix.lower() in READ_EXTENSIONS and not f.name.startswith(".")]
        except OSError as exc:  # e.g. no read permission
            raise ImageReadError(f"cannot read frames from '{p}': {exc.strerror or exc}") from None
        if not files:
            raise ImageReadError(f"cannot read frames from '{p}': the folder has no image files ({', '.join(READ_EXTENSIONS)})")
        return FrameSource(paths=sorted(files, key=_natural_key))
    if not p.exists() and any(ch in text for ch in "*?["):  # a file named 'clip[1].avi' is itself, not a pattern
        files = [Path(f) for f in _glob.glob(text) if Path(f).is_file()]
        if not files:
            raise ImageReadError(f"cannot read frames from '{text}': the pattern matches no files")
        return FrameSource(paths=sorted(files, key=_natural_key))
    if not p.exists():
        raise ImageReadError(f"cannot read video '{p}': no such file")
    if p.suffix.lower() in VIDEO_EXTENSIONS:
        return FrameSource(video=p)
    raise ImageReadError(
        f"cannot read video '{p}': unsupported extension {p.suffix!r}; give a video ({', '.join(VIDEO_EXTENSIONS)}),"
        " a folder of images or a glob pattern"
    )


# ------------------------------------------------------------------ results


@dataclass(frozen=True, eq=False)
class VideoDepthFrame:
    """Fused inverse depth of one frame (the middle of a triple).

    Maps have the frame's shape ``(H, W)``; pixel ``[i, j]`` holds the
    estimate at the cell centre ``(i + 0.5, j + 0.5)``; NaN where unknown.

    Attributes
    ----------
    index : int
        Frame index (0-based) in the input.
    inverse_depth, inverse_depth_std : ndarray, float32
        Fused (filtered) inverse depth and its standard deviation.
    measured_inverse_depth, measured_inverse_depth_std : ndarray, float32
        This triple's own measurement (edge points of this frame only).
    count : ndarray, uint16
        Measurements fused into each state pixel so far.
    camera_position : ndarray, shape (3,)
        Optical centre of the frame (world coordinates).
    baseline : float
        ``|T|``: the camera's translation per frame around this frame.
    dense_inverse_depth, dense_inverse_depth_std : ndarray, float32, or None
        With ``depth_from_video(..., dense=True)``: this triple's dense
        inverse depth and its std at every pixel static stereo measures
        (NaN elsewhere; not fused over time). Pixel-centred, unlike the
        maps above (:mod:`nfdepth._dense_video`). None without ``dense``.
    exposure : tuple or None
        The exposures undone before this frame's triple was measured
        (``match_exposure``): ``(before, after)``, each the outer frame's
        ``(gain, offset)`` against this frame (``I_outer = gain I + offset``)
        or None where it was taken as it is; None where neither was changed.
    """

    index: int
    inverse_depth: np.ndarray
    inverse_depth_std: np.ndarray
    measured_inverse_depth: np.ndarray
    measured_inverse_depth_std: np.ndarray
    count: np.ndarray
    camera_position: np.ndarray
    baseline: float
    dense_inverse_depth: np.ndarray | None = None
    dense_inverse_depth_std: np.ndarray | None = None
    exposure: tuple | None = None

    @property
    def depth(self) -> np.ndarray:
        """Fused depth ``1 / rho`` (NaN where unknown)."""
        return _depth(self.inverse_depth)

    @property
    def depth_std(self) -> np.ndarray:
        """First-order std of the fused depth, ``rho_std / rho**2``."""
        return _depth_std(self.inverse_depth, self.inverse_depth_std)

    @property
    def measured(self) -> np.ndarray:
        """Pixels with a measurement from this frame's triple."""
        return np.isfinite(self.measured_inverse_depth)

    @property
    def dense_depth(self) -> np.ndarray | None:
        """Dense depth ``1 / rho`` of this triple (NaN where unknown), None without ``dense``."""
        return None if self.dense_inverse_depth is None else _depth(self.dense_inverse_depth)

    @property
    def dense_depth_std(self) -> np.ndarray | None:
        """First-order std of the dense depth, ``rho_std / rho**2``; None without ``dense``."""
        return None if self.dense_inverse_depth is None else _depth_std(self.dense_inverse_depth, self.dense_inverse_depth_std)


def _depth(rho) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(rho > 0, 1.0 / rho, np.nan).astype(np.float32)


def _depth_std(rho, rho_std) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(rho > 0, rho_std / rho**2, np.nan).astype(np.float32)


# ------------------------------------------------------------------ fusion


class _State:
    def __init__(self, shape):
        self.rho = np.full(shape, np.nan)
        self.var = np.full(shape, np.nan)
        self.age = np.zeros(shape, dtype=np.int32)
        self.count = np.zeros(shape, dtype=np.int32)


def _predict(state: _State, camera: PinholeCamera, displacement_cam: np.ndarray, process_noise: float, *, rotation=None) -> _State:
    """Move the state to the next frame: reproject with depth, inflate variance.

    ``displacement_cam`` is the camera's move in the previous frame's axes,
    ``rotation`` (3 x 3, default none) the new frame's axes in the previous
    one's (``R_prev^T R_new`` of camera-to-world rotations).
    """
    out = _State(state.rho.shape)
    ii, jj = np.nonzero(np.isfinite(state.rho))
    if ii.size == 0:
        return out
    rho = state.rho[ii, jj]
    pts = camera.back_project(ii + 0.5, jj + 0.5, 1.0 / rho) - displacement_cam
    if rotation is not None:
        pts = pts @ np.asarray(rotation)  # rows of R^T (P - d)
    r, c, z = camera.project(pts)
    ti = np.floor(r).astype(np.int64)
    tj = np.floor(c).astype(np.int64)
    h, w = state.rho.shape
    keep = (z > 0) & (ti >= 0) & (ti < h) & (tj >= 0) & (tj < w)
    if not np.any(keep):
        return out
    zz = z[keep]
    rho_new = 1.0 / zz
    scale = (rho_new / rho[keep]) ** 2  # d rho' / d rho = (Z / Z')^2
    var_new = state.var[ii, jj][keep] * scale**2 + (process_noise * rho_new) ** 2
    lin = ti[keep] * w + tj[keep]
    order = np.argsort(-rho_new, kind="stable")  # nearest first: it occludes the rest
    lin_sorted = lin[order]
    _, first = np.unique(lin_sorted, return_index=True)
    pick = order[first]
    flat = lin[pick]
    out.rho.flat[flat] = rho_new[pick]
    out.var.flat[flat] = var_new[pick]
    out.age.flat[flat] = state.age[ii, jj][keep][pick] + 1
    out.count.flat[flat] = state.count[ii, jj][keep][pick]
    return out


def _neighbour_prior(prior: _State, rows: np.ndarray, cols: np.ndarray):
    """Prior of each measured pixel ``(rows, cols)``: its own pixel's, else the lowest-variance 3 x 3 neighbour's.

    Returns ``(rho, var, count, source)`` per measured pixel: ``var`` is inf
    and ``source`` (the flat index of the prior's pixel) -1 where no pixel
    has a prior. Neighbours in a fixed order; the first of equal variances
    wins. Only the measured pixels are visited (edge points: a few percent
    of the frame).
    """
    h, w = prior.rho.shape
    n = rows.size
    var = np.where(np.isfinite(prior.var), prior.var, np.inf)
    best_var = var[rows, cols]  # the own pixel wins outright whenever it has a prior
    src = np.where(np.isfinite(best_var), rows * w + cols, -1)
    lone = ~np.isfinite(best_var)
    r_lone, c_lone = rows[lone], cols[lone]
    v_lone, s_lone = best_var[lone], src[lone]
    for di, dj in ((di, dj) for di in (-1, 0, 1) for dj in (-1, 0, 1) if (di, dj) != (0, 0)):
        r, c = r_lone + di, c_lone + dj
        inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        v = np.full(r.size, np.inf)
        v[inside] = var[r[inside], c[inside]]
        better = v < v_lone
        v_lone = np.where(better, v, v_lone)
        s_lone = np.where(better, r * w + c, s_lone)
    best_var[lone] = v_lone
    src[lone] = s_lone
    known = src >= 0
    best_rho = np.full(n, np.nan)
    best_count = np.zeros(n, dtype=np.int32)
    best_rho[known] = prior.rho.flat[src[known]]
    best_count[known] = prior.count.flat[src[known]]
    return best_rho, best_var, best_count, src


def _update(prior: _State, rho_m: np.ndarray, var_m: np.ndarray, *, gate: float, max_age: int) -> _State:
    """The state after this frame's measurements ``rho_m``, ``var_m`` (NaN where none).

    A measurement is fused with its prior (:func:`_neighbour_prior`;
    inverse-variance weights) where the two agree within ``gate`` standard
    deviations, and taken as it is elsewhere. Unmeasured prior points
    survive up to ``max_age`` frames unless a measurement took them over.
    """
    measured = np.isfinite(rho_m)
    rows, cols = np.nonzero(measured)
    p_rho, p_var, p_count, src = _neighbour_prior(prior, rows, cols)
    r_m, v_m = rho_m[rows, cols], var_m[rows, cols]
    has_prior = np.isfinite(p_var)
    with np.errstate(invalid="ignore"):
        consistent = has_prior & (np.abs(p_rho - r_m) <= gate * np.sqrt(p_var + v_m))
    out = _State(prior.rho.shape)
    consumed = np.zeros(prior.rho.size, dtype=bool)
    consumed[src[has_prior]] = True
    survive = np.isfinite(prior.rho) & ~measured & ~consumed.reshape(prior.rho.shape) & (prior.age <= max_age)
    out.rho[survive] = prior.rho[survive]
    out.var[survive] = prior.var[survive]
    out.age[survive] = prior.age[survive]
    out.count[survive] = prior.count[survive]
    k = consistent
    info = 1.0 / p_var[k] + 1.0 / v_m[k]
    rho_new = r_m.astype(np.float64)  # (copies) taken as measured where no prior agrees
    var_new = v_m.astype(np.float64)
    rho_new[k] = (p_rho[k] / p_var[k] + r_m[k] / v_m[k]) / info
    var_new[k] = 1.0 / info
    out.rho[rows, cols] = rho_new
    out.var[rows, cols] = var_new
    out.count[rows, cols] = np.where(k, p_count + 1, 1)
    out.age[rows, cols] = 0
    return out


# ------------------------------------------------------------------ the pipeline


def _positions_from(rig: Rig | None, velocity, positions, orientations_rad=None) -> VideoSpec:
    if orientations_rad is not None and positions is None:
        msg = "orientations_rad needs positions (one orientation per position); a rig's poses CSV gives both"
        raise ValueError(msg)
    given = [n for n, v in (("rig", rig), ("velocity", velocity), ("positions", positions)) if v is not None]
    if len(given) != 1:
        msg = f"give exactly one of rig, velocity, positions (camera motion per frame); got {', '.join(given) or 'none'}"
        raise TypeError(msg) if not given else ValueError(msg)
    if rig is not None:
        if rig.video is None:
            where = f"rig '{rig.source}'" if rig.source else "the rig"
            raise RigError(f"{where} has no [video] section: expected video.velocity, video.positions or video.poses")
        _check_spec_moves(rig.video, rig)
        return rig.video
    if velocity is not None:
        v = _numbers("velocity", velocity, "the camera translation per frame, x y z")
        if v.shape != (3,) or not np.all(np.isfinite(v)) or not np.any(v):
            msg = f"velocity must be 3 finite numbers, not all zero (camera translation per frame), got {np.asarray(velocity).tolist()}"
            raise ValueError(msg)
        lo, hi = UNIT_SCALE_RANGE
        if not lo <= float(np.max(np.abs(v))) <= hi:
            msg = (
                f"velocity = {_vec(v)}: expected a speed of {lo:g} to {hi:g} per frame in its largest component (camera"
                " translation per frame; give it in a unit that keeps it there: depths are written as float32)"
            )
            raise ValueError(msg)
        return VideoSpec(velocity=v)
    p = _numbers("positions", positions, "the camera's optical centre at every frame, shape (N, 3)")
    if p.ndim != 2 or p.shape[1] != 3 or not np.all(np.isfinite(p)):
        msg = f"positions must have shape (N, 3) with finite values, got shape {p.shape}"
        raise ValueError(msg)
    _refuse_static(p, "positions", ValueError)
    _check_steps(p, "positions", error=ValueError)
    if orientations_rad is None:
        return VideoSpec(positions=p)
    expected = f"{p.shape[0]} camera-to-world rotation vectors in radians, shape {p.shape} as positions"
    o = _numbers("orientations_rad", orientations_rad, expected)
    if o.shape != p.shape or not np.all(np.isfinite(o)):
        msg = f"orientations_rad must have the shape of positions, {p.shape}, with finite values ({expected}), got shape {o.shape}"
        raise ValueError(msg)
    turn = np.hypot(np.hypot(o[:, 0], o[:, 1]), o[:, 2])  # (no overflow short of the float range)
    if np.any(turn > np.deg2rad(MAX_TURN_DEG)):
        k = int(np.argmax(turn > np.deg2rad(MAX_TURN_DEG)))
        msg = (
            f"orientations_rad[{k}] = {_vec(o[k])}, a turn of {turn[k]:g} rad: expected at most"
            f" {np.deg2rad(MAX_TURN_DEG):g} (give it modulo 2 pi: beyond that float64 loses the rotation's fractions)"
        )
        raise ValueError(msg)
    return VideoSpec(positions=p, orientations_deg=np.rad2deg(o))


def _numbers(name: str, value, expected: str) -> np.ndarray:
    """``value`` as a float64 array; a TypeError naming ``name`` and what was ``expected`` for text, objects, complex numbers or ragged rows."""
    shown = "an array" if isinstance(value, np.ndarray) else reprlib.repr(value)
    try:
        arr = np.asarray(value)
    except ValueError:  # NumPy's "inhomogeneous shape"
        raise TypeError(f"{name} must be numbers ({expected}), got {shown} (rows of unequal length)") from None
    if not is_real_numeric(arr):  # (NumPy would drop an imaginary part with a warning)
        raise TypeError(f"{name} must be numbers ({expected}), got {shown} (dtype {arr.dtype})")
    return arr.astype(float)


#: A triple whose step (half the distance between the positions one frame before and
#: after) is at most this many float64 ulps of the positions' largest coordinate does
#: not move: such a step is rounding noise of equal positions (each position carries
#: up to half an ulp, their difference up to about one).
_ROUNDING_ULPS = 4
_MIN_LEVEL_SIZE_PX = 8  # the coarsest level of a given ``levels`` keeps this many px on its smaller side


def _check_levels(levels, shape) -> int:
    """``levels`` of :func:`depth_from_video`: default :func:`~nfdepth.stereo.auto_levels`, else 1 .. as many as halve the frame to 8 px."""
    most = auto_levels(shape, min_size_px=_MIN_LEVEL_SIZE_PX)
    if levels is None:
        return auto_levels(shape)
    levels = check_int("levels", levels, 1)
    if levels > most:
        msg = (
            f"levels = {levels} halves a {shape[1]}x{shape[0]} frame below {_MIN_LEVEL_SIZE_PX} px: expected 1 to {most}"
            " (default: down to 24 px)"
        )
        raise ValueError(msg)
    return levels


#: What a camera without motion is told (no baseline, no depth).
_MOVE_HINT = "expected camera positions that change from frame to frame (depth needs a baseline between frames)"

#: The pipeline's per-triple ordering warning, replaced by one summary per run.
_BEHIND_WARNING = r"\d+ of \d+ determinable edge points have a negative inverse depth"


def _vec(v) -> str:
    return "(" + ", ".join(f"{float(x) + 0.0:g}" for x in v) + ")"


def _off_line_effect(off: float, ahead: float) -> str:
    """What a middle position ``off`` (share of the step) off the line does to a dense map, ``ahead`` of it along the optical axis."""
    across = math.sqrt(max(off * off - ahead * ahead, 0.0))
    parts = []
    if across >= 0.25 * off:
        parts.append("across the path, it misaligns the rectified views vertically")
    if ahead >= 0.25 * off:
        parts.append("along the optical axis, it changes the middle view's scale")
    return "; ".join(parts)


def _frame_list(frames: list[int], most: int = 6) -> str:
    """``[1, 2, 3, 7]`` -> ``"1-3, 7"`` (at most ``most`` runs, then ``...``)."""
    runs: list[list[int]] = []
    for f in frames:
        if runs and f == runs[-1][1] + 1:
            runs[-1][1] = f
        else:
            runs.append([f, f])
    text = [str(a) if a == b else f"{a}-{b}" for a, b in runs[:most]]
    return ", ".join(text) + (", ..." if len(runs) > most else "")


def _spec_name(spec: VideoSpec, rig: Rig | None) -> str:
    """How messages name the camera motion of ``spec``: the poses file, or the rig key / parameter."""
    if spec.poses is not None:
        return f"poses '{spec.poses.source}'" if spec.poses.source is not None else "poses"
    key = "velocity" if spec.velocity is not None else "positions"
    if rig is None:
        return key
    return f"rig '{rig.source}': video.{key}" if rig.source else f"video.{key}"


def _position(spec: VideoSpec, frame: int, name: str, rig: Rig | None) -> np.ndarray:
    """The camera's position at ``frame``; positions that run out are named as :func:`_spec_name` names them (the rig file)."""
    if spec.positions is not None and not 0 <= frame < len(spec.positions):
        raise (ValueError if rig is None else RigError)(
            f"{name} has {len(spec.positions)} entries: no position for frame {frame} (one per frame, from first_frame)"
        )
    return spec.camera_position(frame)


def _check_spec_moves(spec: VideoSpec, rig: Rig | None) -> None:
    """Refuse a rig's positions / poses in which the camera never moves, or moves by steps outside the speed range."""
    if spec.poses is not None:
        p, frames = spec.poses.positions, spec.poses.frames
    elif spec.positions is not None:
        p, frames = spec.positions, None
    else:
        return  # a velocity is checked non-zero and within range where it is read
    what = _spec_name(spec, rig)
    _refuse_static(p, what, RigError)
    _check_steps(p, what, frames=frames)


def _refuse_static(p, what: str, error) -> None:
    """Raise ``error`` when every camera position in ``p`` (N, 3) is the same."""
    if len(p) and np.all(p == p[0]):
        raise error(f"{what}: the camera does not move: all {len(p)} positions are {_vec(p[0])}; {_MOVE_HINT}")


def _camera_rotation(spec: VideoSpec, frame: int) -> np.ndarray:
    """Camera-to-world rotation matrix of ``frame`` (identity unless poses give an orientation)."""
    return Rotation.from_rotvec(np.deg2rad(spec.orientation_deg(frame))).as_matrix()


#: A turning triple whose outer frames both see less than this fraction of the middle one is reported
#: (with ``dense``: also one whose rectified canvas holds less than this fraction of it).
_LEAST_SEEN = 0.5
#: With ``dense``: a middle position further than this (relative to half the outer two's distance)
#: from the line through the outer two is reported (with ``dense_frames_before`` > 1: any position of
#: the dense map's frames, relative to their mean step, from the line through the first and last).
_MAX_OFF_LINE = 0.02


#: With ``levels=1``: a median edge-point motion this many px larger one way than the other
#: (unequal steps) warns; at 0.39 px the synthetic pyramid's median error rose from 0.5 to 2.4 %.
_UNEVEN_PX = 0.25
#: Outer steps that differ from the central one by less than this share of it are equal steps
#: (rounding of the positions); beyond it each outer frame is warped by its own step.
_EQUAL_STEPS = 1e-6


def _outer_steps(rotation: np.ndarray, positions, step_cam: np.ndarray):
    """The outer frames' displacements from the middle one (middle camera axes), or None for equal steps (``-/+ step_cam``)."""
    p_prev, p_mid, p_next = (np.asarray(p, dtype=float) for p in positions)
    before, after = rotation.T @ (p_prev - p_mid), rotation.T @ (p_next - p_mid)
    uneven = max(float(np.linalg.norm(before + step_cam)), float(np.linalg.norm(after - step_cam)))
    return None if uneven <= _EQUAL_STEPS * float(np.linalg.norm(step_cam)) else (before, after)


def _turned_triple(window: list[np.ndarray], cam: PinholeCamera, rotations, *, sigma_px: float):
    """The outer frames turned to the middle one's orientation (:mod:`nfdepth._derotation`), and where a measurement is whole.

    A frame whose turn moves no pixel (by more than ``STILL_PX``: a full
    turn, float rounding) is used as taken; ``None`` for the mask when
    neither turns.
    """
    triple, inside = list(window), None
    for j in (0, 2):
        turn = rotations[j].T @ rotations[1]
        if moves_pixels(cam, turn):
            maps = derotation_maps(cam, turn)
            triple[j] = derotate(window[j], maps)
            inside = maps[2] if inside is None else inside & maps[2]
    return triple, None if inside is None else measurable(inside, sigma_px=sigma_px)


def depth_from_video(
    frames: Iterable,
    *,
    rig: Rig | None = None,
    camera: PinholeCamera | None = None,
    velocity=None,
    positions=None,
    orientations_rad=None,
    first_frame: int = 0,
    sigma_px: float = 2.0,
    process_noise: float = 0.01,
    gate: float = 4.0,
    max_age: int = 2,
    min_std_px: float = 0.01,
    min_cos: float = 0.25,
    noise_std: float | None = None,
    stencil: str = "matched",
    levels: int | None = None,
    max_residual_px: float = 1.0,
    edge_step_px: float = 1.0,
    dense: bool = False,
    dense_frames_before: int = 1,
    threads: int | None = None,
    match_exposure: bool = True,
) -> Iterator[VideoDepthFrame]:
    """Depth per frame of a camera moving (translating, and turning if its poses say so) through a static scene, fused over time.

    Parameters
    ----------
    frames : iterable of ndarray, shape (H, W)
        Grey frames in order (e.g. :func:`read_video`). Consumed lazily.
    rig : Rig, optional
        Gives the camera (``[camera]``, whose lens distortion is undone in
        every frame first: :meth:`nfdepth.rig.Rig.undistort`) and the motion
        per frame (``[video]``). Without it, give ``camera`` and one of
        ``velocity`` / ``positions``.
    camera : PinholeCamera, optional
        Intrinsics (overrides the rig's, and then no distortion is undone).
    velocity : 3 floats, optional
        Camera translation per frame (scene units, camera axes).
    positions : array_like, shape (N, 3), optional
        Camera optical centre of every frame (world axes: the camera axes
        unless ``orientations_rad`` or a rig's poses CSV give its
        orientation).
    orientations_rad : array_like, shape (N, 3), optional
        With ``positions``: the camera-to-world orientation of every frame
        as a rotation vector (radians; a poses CSV gives it in degrees).
        A camera that turns has the outer frames of each triple turned to
        the middle frame's orientation before the measurement (module
        docstring). Default: it does not turn.
    first_frame : int
        Index of the first element of ``frames`` in the positions / poses.
    sigma_px : float
        Gaussian smoothing (px) of the normal-flow estimate.
    process_noise : float
        Relative std of inverse depth added per frame in the prediction.
    gate : float
        Measurements further than ``gate`` combined stds from their prior
        restart that pixel.
    max_age : int
        Frames a state point survives without a new measurement.
    min_std_px : float
        Floor of a measurement's std, in px of disparity.
    min_cos, noise_std, stencil
        As in :func:`nfdepth.pipelines.static_stereo_edges`.
    levels : int, optional
        Pyramid levels of the coarse-to-fine prior of every triple
        (:mod:`nfdepth._translating_pyramid`), for image motions beyond the
        differential method's 1-2 px per frame. Default: halve the frame
        until its smaller side would drop below 24 px
        (:func:`nfdepth.stereo.auto_levels`). ``1`` is the paper's
        single-level measurement, with no prior and no warping.
    max_residual_px : float
        With ``levels > 1``: edge points whose motion left after warping by
        the prior exceeds this (px per frame of normal flow) are
        ``UNCERTAIN`` (the prior failed there, e.g. at an occlusion
        boundary). At most 2 px, the differential method's range.
    edge_step_px : float
        With ``levels > 1``: edge points where the prior's motion varies by
        more than this (px per frame) within 4 px are ``UNCERTAIN``: a depth
        step, where one side of the edge is hidden in an outer frame, or a
        plane slanted by more than 1/8 px per px (0: no test).
    dense : bool
        Also a dense map of every triple: its frames rectified into a row
        of views along the camera's path and measured by
        :func:`nfdepth.stereo.static_stereo` (:mod:`nfdepth._dense_video`;
        about 0.1-0.2 s a 640 x 480 frame). A camera moving within 5
        degrees of its optical axis gets none (NaN maps and a warning).
    dense_frames_before : int
        With ``dense``: frames before the middle one that its dense map
        uses (1: the triple). More make a longer row along the path,
        reaching further back, for a camera that moves little per frame
        (its precision follows the farthest view), at no delay: frame
        ``k``'s map still comes when frame ``k + 1`` arrives. The first
        frames use what came before them.
    threads : int, optional
        Threads of the dense map's cost volume (as ``static_stereo``).
    match_exposure : bool
        Map each triple's outer frames onto the middle frame's exposure
        before the edge points are measured (gain and offset from a dense
        map of the frames reduced to an eighth, undone where they explain
        the differences between corresponding pixels;
        :func:`nfdepth._exposure.match_frame_exposures`): eq. 4 reads an
        exposure change between frames (auto exposure) as motion. The dense
        maps match their own (``static_stereo``'s ``match_exposure``).

    Yields
    ------
    VideoDepthFrame
        One per frame that has a neighbour on each side (frames
        ``1 .. N-2``), each yielded once the following frame has arrived.
        Maps are in the camera's image at that frame (its own orientation).
        A triple in which the camera does not move (the positions one frame
        before and after coincide) gives no measurement; the state is
        carried over (predicted) instead. Frames before the first triple
        that moves are held back (they are empty) until it arrives, so a
        run in which no triple moves yields nothing.

    Raises
    ------
    TypeError
        At the call: no camera, no motion (none of ``rig``, ``velocity``,
        ``positions``), an option of the wrong type (``velocity``,
        ``positions`` or ``orientations_rad`` that are not real numbers).
    RigError, ValueError
        At the call (the frames are not read yet): more than one motion,
        ``orientations_rad`` without ``positions`` or of another shape,
        positions / poses that never change, a velocity outside
        1e-30..1e30 per frame (the rig's speed range), an option out of
        range, a ``sigma_px`` that leaves no edge point (2.5 sigma from the
        border) in the camera's frames without ``dense``. While the frames
        are read: a frame whose size differs from the camera's, one with
        NaN, positions that run out or a step between them outside the
        speed range, and (at the end of the frames) no triple in which the
        camera moves. A step of at most 4 float64 ulps of the positions'
        largest coordinate is rounding noise: that triple does not move.

    Warns
    -----
    UserWarning
        Once per run, at its end: when some triples do not move (how many,
        which frames), and when in some triples most edge points come out
        behind the camera (the camera moves opposite to its given positions:
        a sign or ordering mistake in the poses / velocity / positions), and
        when in some triples the edge points move a median of more than 2 px
        per frame across the stencil (with ``levels=1``, or where the
        pyramid's prior failed): their depths are wrong by up to tens of
        percent, and, with ``levels=1``, when in some triples the steps
        before and after the middle frame differ so much that the edge
        points move more than 0.25 px further one way than the other, and
        when in some triples the camera turns so far that
        less than half of the middle frame is seen by both of its
        neighbours (the rest has no depth), and, with ``dense``, when in
        some triples the camera moves so nearly along its optical axis
        that less than half of the frame has a dense map, or the middle
        position lies more than 2 % of the step off the line through the
        other two (the dense map takes them as on it).
    """
    spec = _positions_from(rig, velocity, positions, orientations_rad)
    cam = camera if camera is not None else (rig.camera if rig is not None else None)
    if not isinstance(cam, PinholeCamera):
        msg = "depth_from_video needs a camera: pass rig=... or camera=PinholeCamera(...)"
        raise TypeError(msg)
    sigma_px = check_scale_px("sigma_px", sigma_px)
    dense = check_bool("dense", dense)
    if not dense:  # (the dense maps have no such border)
        _check_sigma_fits(sigma_px, cam.shape)
    stencil = _check_stencil(stencil)
    min_cos = check_fraction("min_cos", min_cos)
    process_noise = check_threshold("process_noise", process_noise)
    gate = check_threshold("gate", gate, positive=True)
    min_std_px = check_threshold("min_std_px", min_std_px, positive=True)
    if noise_std is not None:
        noise_std = check_noise_std("noise_std", noise_std)
    max_age = check_int("max_age", max_age, 0)
    first = check_int("first_frame", first_frame, 0)
    levels = _check_levels(levels, cam.shape)
    max_residual_px = check_threshold("max_residual_px", max_residual_px, positive=True)
    edge_step_px = check_threshold("edge_step_px", edge_step_px)
    match_exposure = check_bool("match_exposure", match_exposure)
    dense_frames_before = check_int("dense_frames_before", dense_frames_before, 1)
    if dense_frames_before > 1 and not dense:
        msg = f"dense_frames_before = {dense_frames_before} is for the dense maps: give dense=True too"
        raise ValueError(msg)
    if threads is not None:
        threads = check_int("threads", threads, 1)
    if max_residual_px > _DIFFERENTIAL_RANGE_PX:
        msg = (
            f"max_residual_px = {max_residual_px:g} px is beyond the differential method's range: expected at most"
            f" {_DIFFERENTIAL_RANGE_PX:g} px of motion per frame left after warping (default 1)"
        )
        raise ValueError(msg)
    return _video_depths(
        frames, spec=spec, rig=rig, camera=camera, cam=cam, first=first, levels=levels, sigma_px=sigma_px, stencil=stencil, min_cos=min_cos,
        noise_std=noise_std, process_noise=process_noise, gate=gate, min_std_px=min_std_px, max_age=max_age, max_residual_px=max_residual_px,
        edge_step_px=edge_step_px, dense=dense, dense_frames_before=dense_frames_before, match_exposure=match_exposure, threads=threads,
    )  # fmt: skip


def _video_depths(
    frames, *, spec, rig, camera, cam, first, levels, sigma_px, stencil, min_cos, noise_std, process_noise, gate, min_std_px, max_age,
    max_residual_px, edge_step_px, dense, dense_frames_before, match_exposure, threads,
) -> Iterator[VideoDepthFrame]:  # fmt: skip
    """:func:`depth_from_video`'s frames, from its checked arguments (a generator: the checks run at the call, not at the first frame)."""
    motion_name = _spec_name(spec, rig)
    lo, hi = UNIT_SCALE_RANGE
    window: list[np.ndarray] = []
    noises: list[float] = []  # the window's frames' noise estimates (each frame's once: it serves three triples)
    blanks: list[bool] = []  # whether each of the window's frames holds one value throughout (blank, dropped), likewise
    history: list[np.ndarray] = []  # dense: the last dense_frames_before + 2 frames
    state: _State | None = None
    prev_pos = prev_orientation = prev_rotation = None
    moved = False
    held: list[tuple[int, np.ndarray, float]] = []  # static frames before the first one that moves
    static: list[int] = []
    blank_frames: set[int] = set()  # frames of one value throughout (blank, dropped)
    blank_triples: list[int] = []  # the frames whose triple holds one
    rounded: list[int] = []  # static frames whose step is not zero but lost to rounding
    largest = 0.0  # their largest coordinate
    behind_frames: list[int] = []
    dense_behind_frames: list[int] = []  # frames whose dense map lies mostly behind the camera
    no_edge_frames: list[int] = []  # frames with no edge point (one warning per run)
    no_edge_warning = None  # why, in the first of them
    fast_frames: list[int] = []  # frames whose edge points moved beyond the stencil's range
    blind_frames: list[int] = []  # frames of which the turned outer frames see less than half
    seen = 1.0  # the least of it
    ahead_frames: list[int] = []  # dense: frames whose path points so nearly ahead that less than half has a dense map
    covered = 1.0  # the least of it
    bent_frames: list[int] = []  # dense: frames off the line through their neighbours
    bent = 0.0  # the most
    bent_ahead = 0.0  # the most of it along the optical axis
    fastest = 0.0
    uneven_frames: list[int] = []  # levels=1: frames whose steps before and after differ by more than _UNEVEN_PX of motion
    unevenest = 0.0
    behind_points = determinable_points = 0
    triples = 0
    for n, frame in enumerate(frames):
        img = _own_image(f"frame {first + n}", frame)
        if img.shape != cam.shape:
            if rig is not None and camera is None:
                rig.check_image_shape(img.shape, what=f"frame {first + n}")
            msg = f"frame {first + n} has size {img.shape[1]}x{img.shape[0]}, the camera {cam.width_px}x{cam.height_px}"
            raise ValueError(msg)
        if rig is not None and camera is None and any(rig.distortion):
            img = rig.undistort(img)
        window.append(img)
        blanks.append(float(img.max()) == float(img.min()))
        if noise_std is None:
            noises.append(estimate_noise_std(img))
        if dense:
            history.append(img)
            if len(history) > dense_frames_before + 2:
                history.pop(0)
        if len(window) < 3:
            continue
        if len(window) > 3:
            window.pop(0)
            noises = noises[-3:]
        blanks = blanks[-3:]
        k = first + n - 1
        triples += 1
        p_prev, p_mid, p_next = (_position(spec, i, motion_name, rig) for i in (k - 1, k, k + 1))
        orientations = [spec.orientation_deg(i) for i in (k - 1, k, k + 1)]
        turns = not all(np.array_equal(o, orientations[1]) for o in orientations)
        rotations = [_camera_rotation(spec, i) for i in (k - 1, k, k + 1)]
        rmat = rotations[1]
        step_cam = rmat.T @ ((p_next - p_prev) / 2.0)  # world -> camera axes
        baseline = float(np.linalg.norm(step_cam))
        # no baseline: zero, or a step lost to float64 rounding of the positions (a few ulps of their largest coordinate)
        coordinate = max(float(np.max(np.abs(p_prev))), float(np.max(np.abs(p_next))))
        moves = baseline > _ROUNDING_ULPS * float(np.spacing(coordinate))
        if moves and not lo <= baseline <= hi:
            raise (ValueError if rig is None else RigError)(
                f"{motion_name}: the camera's step around frame {k} (half the distance from frame {k - 1} to frame {k + 1}) is"
                f" {baseline!r}: expected a step of {lo:g} to {hi:g} per frame (give the positions in a unit that keeps it"
                " there: depths are written as float32)"
            )
        if not moves and baseline > 0:
            rounded.append(k)
            largest = max(largest, coordinate)

        shape = cam.shape
        rho_m = np.full(shape, np.nan)
        exposure = None
        var_m = np.full(shape, np.nan)
        dense_maps = (np.full(shape, np.nan, np.float32), np.full(shape, np.nan, np.float32)) if dense else (None, None)
        blank = [i for i, one in zip((k - 1, k, k + 1), blanks) if one]
        if moves and not blank:
            with warnings.catch_warnings(record=True) as heard:
                warnings.simplefilter("always")  # (heard, then passed on below: "no edge points" once per run)
                warnings.filterwarnings("ignore", message=_BEHIND_WARNING, category=UserWarning)
                warnings.filterwarnings("ignore", message=_DISPLACEMENT_WARNING, category=UserWarning)  # one summary per run, below
                # the noise of the frames as taken (turning or warping resamples the outer ones and hides part of it)
                edge_options = {"sigma_px": sigma_px, "stencil": stencil, "min_cos": min_cos, "noise_std": noise_std if noise_std is not None else float(np.median(noises))}
                # the outer frames on the middle one's exposure (the same frames where they share it)
                matched, undone = match_frame_exposures(window, cam, rotations, (p_prev, p_mid, p_next), middle=1, threads=threads) if match_exposure else (window, [None] * 3)
                exposure = None if undone[0] is None and undone[2] is None else (undone[0], undone[2])
                # a turning camera's outer frames are first turned to the middle one's orientation: a translating triple
                triple, whole = _turned_triple(matched, cam, rotations, sigma_px=sigma_px) if turns else (matched, None)
                outer = _outer_steps(rmat, (p_prev, p_mid, p_next), step_cam)
                if levels == 1:
                    res = static_stereo_edges(triple, camera=cam, baseline=baseline, direction=step_cam, **edge_options)
                else:
                    res = edge_depth_coarse_to_fine(
                        triple,
                        camera=cam,
                        baseline=baseline,
                        direction=step_cam / baseline,
                        levels=levels,
                        outer_steps=outer,
                        max_residual_px=max_residual_px,
                        edge_step_px=edge_step_px,
                        **edge_options,
                    )
            for heard_one in heard:
                if isinstance(heard_one.message, NoEdgePointsWarning):
                    no_edge_warning = no_edge_warning or heard_one.message
                    no_edge_frames.append(k)
                else:
                    warnings.warn(heard_one.message, stacklevel=2)
            # the points that carry a depth: edges along the motion do not move and would hide a motion beyond range
            mask = _depth_bearing_mask(res)
            if whole is not None:
                _void_points(res, ~whole, Reason.NO_DATA)  # a turned outer frame had nothing to read there
                if whole.mean() < _LEAST_SEEN:
                    blind_frames.append(k)
                    seen = min(seen, float(whole.mean()))
                mask = mask & whole[: mask.shape[0], : mask.shape[1]]
            # the motion the triple's stencil saw (after warping by the prior, with levels > 1), in the outer frame
            # farthest from the middle one (the flow is per central step: a reversing camera moves farther)
            median = _median_displacement(mask, res.flows["relative" if levels == 1 else "residual"])
            moved_px = median
            if levels == 1:  # that flow aliases beyond the range and reads a fast motion as slow: the pyramid's prior says
                moved_px = max(median, coarse_motion_px(triple, cam, -step_cam, mask, outer_steps=outer))
            shift = moved_px * outer_reach(-step_cam, outer)
            if shift > _DIFFERENTIAL_RANGE_PX:
                fast_frames.append(k)
                fastest = max(fastest, shift)
            if levels == 1 and outer is not None:
                # the single level's stencil takes the frames as equally spaced: its temporal derivative
                # sits half the steps' difference away from the middle frame's gradient
                lopsided = median * float(np.linalg.norm(outer[0] + outer[1])) / (2.0 * baseline)
                if lopsided > _UNEVEN_PX:
                    uneven_frames.append(k)
                    unevenest = max(unevenest, lopsided)
            behind = int(np.count_nonzero(res.inverse_depth.reason == Reason.NOT_POSITIVE))
            ahead = int(np.count_nonzero(res.inverse_depth.reason == Reason.OK))
            if behind + ahead >= _ORDER_CHECK_MIN_POINTS and behind > ahead:
                behind_frames.append(k)
                behind_points += behind
                determinable_points += behind + ahead
            ok = res.valid
            ii, jj = _point_pixels(res.rows[ok], res.cols[ok], shape)
            rho = res.inverse_depth.rho[ok]
            std = res.inverse_depth.rho_std[ok]
            # the frames are float32: depths and inverse depths beyond it would come out inf or 0
            to_float32_map(rho, what="an inverse depth", hint=_UNITS_HINT)
            to_float32_map(1.0 / rho[rho != 0], what="a depth", hint=_UNITS_HINT)
            floor = min_std_px / (cam.focal_px * baseline)
            std = np.where(np.isfinite(std), np.maximum(std, floor), floor)
            rho_m[ii, jj] = rho
            var_m[ii, jj] = std**2
            if dense:
                back = len(history) - 2  # frames before the middle one
                row = range(k - back, k + 2)
                dt = dense_row(
                    history,
                    cam,
                    [*(_camera_rotation(spec, i) for i in row[:-3]), *rotations],
                    [*(_position(spec, i, motion_name, rig) for i in row[:-3]), p_prev, p_mid, p_next],
                    middle=back,
                    noise_std=edge_options["noise_std"],
                    threads=threads,
                    match_exposure=match_exposure,
                )
                known = dt.rho[np.isfinite(dt.rho) & (dt.rho != 0)]
                to_float32_map(known, what="an inverse depth", hint=_UNITS_HINT)
                to_float32_map(1.0 / known, what="a depth", hint=_UNITS_HINT)
                dense_maps = (dt.rho.astype(np.float32), dt.rho_std.astype(np.float32))
                with np.errstate(invalid="ignore"):
                    behind, ahead = (int(np.count_nonzero(side * dt.rho > 2.0 * dt.rho_std)) for side in (-1.0, 1.0))
                if behind + ahead >= _ORDER_CHECK_MIN_POINTS and behind > ahead:  # beyond 2 std of 0: no far point's noise
                    dense_behind_frames.append(k)
                if dt.covered < _LEAST_SEEN:
                    ahead_frames.append(k)
                    covered = min(covered, dt.covered)
                if dt.off_line > _MAX_OFF_LINE:
                    bent_frames.append(k)
                    bent = max(bent, dt.off_line)
                    bent_ahead = max(bent_ahead, dt.off_line_ahead)
        elif blank:
            blank_frames.update(blank)
            blank_triples.append(k)
        else:
            static.append(k)

        if state is None:
            state = _State(shape)
        else:
            turned = not np.array_equal(prev_orientation, orientations[1])  # since the previous frame
            rotation = prev_rotation.T @ rmat if turned else None
            state = _predict(state, cam, prev_rotation.T @ (p_mid - prev_pos), process_noise, rotation=rotation)
        state = _update(state, rho_m, var_m, gate=gate, max_age=max_age)
        prev_pos, prev_orientation, prev_rotation = p_mid, orientations[1], rmat
        if not moves and not moved:
            held.append((k, np.asarray(p_mid, dtype=float).copy(), baseline))  # empty so far: no state yet
            continue
        if not moved:
            moved = True
            for hk, hpos, hbase in held:
                yield _empty_frame(shape, hk, hpos, hbase, dense=dense)
            held = []
        yield VideoDepthFrame(
            index=k,
            inverse_depth=state.rho.astype(np.float32),
            inverse_depth_std=np.sqrt(state.var).astype(np.float32),
            measured_inverse_depth=rho_m.astype(np.float32),
            measured_inverse_depth_std=np.sqrt(var_m).astype(np.float32),
            count=np.minimum(state.count, np.iinfo(np.uint16).max).astype(np.uint16),
            camera_position=np.asarray(p_mid, dtype=float).copy(),
            baseline=baseline,
            dense_inverse_depth=dense_maps[0],
            dense_inverse_depth_std=dense_maps[1],
            exposure=exposure,
        )

    rounding = (
        f"; around frame{'s' if len(rounded) > 1 else ''} {_frame_list(rounded)} the positions differ by no more than float64 rounding ({_ROUNDING_ULPS} ulps"
        f" of coordinates up to {largest:g}): give them relative to a nearby origin"
        if rounded
        else ""
    )
    if not triples:  # (the command line refuses such a source before; a library caller gets no silent nothing)
        got = len(window)
        msg = f"depth_from_video needs at least 3 frames, got {got}" + ("" if got else " (an empty iterable; a video file or folder: pass read_video(path))")
        raise ValueError(msg)
    if triples and not moved:
        raise ValueError(
            f"the camera does not move in any of the {triples} frame triples (frames {_frame_list(static)} have the same position"
            f" one frame before and after), so no depth can be measured: {_MOVE_HINT}{rounding}"
        )
    if blank_frames:
        warnings.warn(
            f"frame{'s' if len(blank_frames) > 1 else ''} {_frame_list(sorted(blank_frames))} hold{'' if len(blank_frames) > 1 else 's'}"
            f" one value throughout (a blank or dropped frame?): the triples of {len(blank_triples)} of {triples} frames"
            f" ({_frame_list(blank_triples)}) are not measured and carry the fused depth of the frames before for up to"
            f" {max_age} frame{'s' if max_age != 1 else ''} (max_age)",
            UserWarning,
            stacklevel=2,
        )
    if static:
        warnings.warn(
            f"the camera does not move around {len(static)} of {triples} frames ({_frame_list(static)}: the same position one frame"
            f" before and after): they have no measurement of their own and carry the fused depth of the frames before{rounding}",
            UserWarning,
            stacklevel=2,
        )
    if fast_frames:
        advice = (
            "leave levels (--levels) at its default: coarse to fine"
            if levels == 1
            else "the pyramid's prior failed there; use frames closer together or more pyramid levels"
        )
        warnings.warn(
            f"in {len(fast_frames)} of {triples} frames ({_frame_list(fast_frames)}) the edge points move a median of up to"
            f" {fastest:.1f} px per frame{'' if levels == 1 else ' after warping by the prior'}, beyond the differential"
            f" method's range of about 2 px: their depths are wrong by up to tens of percent; {advice}",
            UserWarning,
            stacklevel=2,
        )
    if uneven_frames:
        warnings.warn(
            f"in {len(uneven_frames)} of {triples} frames ({_frame_list(uneven_frames)}) the steps before and after the"
            f" frame differ (the camera sped up or slowed down, or a frame is missing): the edge points move up to"
            f" {unevenest:.2f} px more one way than the other, and the single level takes the frames as equally spaced,"
            " so their depths are off by several percent; leave levels (--levels) at its default: coarse to fine warps"
            " each frame by its own step",
            UserWarning,
            stacklevel=2,
        )
    if blind_frames:
        warnings.warn(
            f"in {len(blind_frames)} of {triples} frames ({_frame_list(blind_frames)}) the camera turned so far that both of"
            f" its neighbours see as little as {100 * seen:.0f} % of the frame: edge points elsewhere have no depth (NO_DATA);"
            " use frames closer together in time, or check the orientations' unit (degrees in a poses CSV, radians in"
            " orientations_rad)",
            UserWarning,
            stacklevel=2,
        )
    if ahead_frames:
        warnings.warn(
            f"in {len(ahead_frames)} of {triples} frames ({_frame_list(ahead_frames)}) the camera moves so nearly along its"
            f" optical axis that as little as {100 * covered:.0f} % of the frame has a dense map (it needs a row of views"
            f" across the path, more than {MIN_SIDEWAYS_DEG:g} degrees from straight ahead); the edge points are measured"
            " in any direction",
            UserWarning,
            stacklevel=2,
        )
    if bent_frames:
        warnings.warn(
            f"in {len(bent_frames)} of {triples} frames ({_frame_list(bent_frames)}) the middle position lies up to"
            f" {100 * bent:.0f} % of the step off the line through its neighbours' positions: their dense maps take it as on"
            f" that line ({_off_line_effect(bent, bent_ahead)})"
            if dense_frames_before == 1
            else f"in {len(bent_frames)} of {triples} frames ({_frame_list(bent_frames)}) the positions of a dense map's"
            f" frames (up to {dense_frames_before + 2}; fewer at the start) lie up to {100 * bent:.0f} % of the mean step off the line through the first"
            f" and last of them: the dense maps take them as on that line ({_off_line_effect(bent, bent_ahead)});"
            " fewer frames (dense_frames_before) follow a curved path better",
            UserWarning,
            stacklevel=2,
        )
    if no_edge_frames:
        warnings.warn(_no_edge_points_in_frames(no_edge_warning, no_edge_frames, triples, dense), stacklevel=2)
    if dense_behind_frames and not behind_frames:  # (with edge points the warning below says it)
        warnings.warn(
            f"in {len(dense_behind_frames)} of {triples} frames ({_frame_list(dense_behind_frames)}) most of the dense map lies behind"
            " the camera (a negative inverse depth beyond 2 std; no depth there): the camera moves opposite to its given positions;"
            " check the sign of the poses' x, y, z (or of [video] velocity / positions) and that frames and poses are in the same order",
            UserWarning,
            stacklevel=2,
        )
    if behind_frames:
        warnings.warn(
            f"in {len(behind_frames)} of {triples} frames ({_frame_list(behind_frames)}) most edge points came out behind the camera"
            f" ({behind_points} of {determinable_points} determinable points, dropped): the camera moves opposite to its given"
            " positions; check the sign of the poses' x, y, z (or of [video] velocity / positions) and that frames and poses"
            " are in the same order",
            UserWarning,
            stacklevel=2,
        )


def _own_image(name: str, frame) -> np.ndarray:
    """:func:`as_image` of ``frame`` (float32), copied where it is the caller's own memory, to be kept for later frames.

    A reader may hand every frame in one buffer (``cv2.VideoCapture.read(buf)``):
    a window holding the caller's arrays would see all its frames turn into the
    newest one (no motion). Where the conversion to float32 made a copy, that
    copy is kept as it is.
    """
    given = np.asarray(frame)
    img = as_image(name, given, dtype=np.float32)
    return img.copy() if np.may_share_memory(img, given) else img


def _empty_frame(shape, index: int, position: np.ndarray, baseline: float, *, dense: bool) -> VideoDepthFrame:
    """A frame with no estimate yet (a static triple before the camera first moves)."""
    nan = np.full(shape, np.nan, dtype=np.float32)
    return VideoDepthFrame(
        index=index,
        inverse_depth=nan,
        inverse_depth_std=nan.copy(),
        measured_inverse_depth=nan.copy(),
        measured_inverse_depth_std=nan.copy(),
        count=np.zeros(shape, dtype=np.uint16),
        camera_position=position,
        baseline=baseline,
        dense_inverse_depth=nan.copy() if dense else None,
        dense_inverse_depth_std=nan.copy() if dense else None,
    )


# ------------------------------------------------------------------ writing

#: Arrays stored by :func:`write_video_npz`, each stacked over the frames.
NPZ_ARRAYS = (
    "depth",
    "depth_std",
    "inverse_depth",
    "inverse_depth_std",
    "measured_inverse_depth",
    "measured_inverse_depth_std",
)
#: Arrays :func:`write_video_npz` adds when the frames have dense maps (``depth_from_video(..., dense=True)``).
NPZ_DENSE_ARRAYS = ("dense_depth", "dense_depth_std", "dense_inverse_depth", "dense_inverse_depth_std")


def write_video_npz(results, path, *, camera: PinholeCamera | None = None, force: bool = False) -> Path:
    """Write per-frame results to one ``.npz``, atomically (nothing is left on failure).

    Holds ``index`` (N,), ``camera_position`` (N, 3), ``baseline`` (N,) and
    the float32 ``(N, H, W)`` stacks of :data:`NPZ_ARRAYS` (NaN where
    unknown), and of :data:`NPZ_DENSE_ARRAYS` when the frames have dense
    maps; with ``camera`` also ``focal_px``, ``cx_px``, ``cy_px``.
    """
    from .io import atomic_write, require_extension

    require_extension(path, ".npz")

    results = list(results)
    payload = {
        "index": np.array([r.index for r in results], dtype=np.int64),
        "camera_position": np.array([r.camera_position for r in results], dtype=float).reshape(-1, 3),
        "baseline": np.array([r.baseline for r in results], dtype=float),
    }
    dense = bool(results) and all(r.dense_inverse_depth is not None for r in results)
    for name in NPZ_ARRAYS + (NPZ_DENSE_ARRAYS if dense else ()):
        payload[name] = np.stack([np.asarray(getattr(r, name), dtype=np.float32) for r in results]) if results else np.zeros((0, 0, 0), np.float32)
    if camera is not None:
        payload.update(focal_px=np.float64(camera.focal_px), cx_px=np.float64(camera.cx_px), cy_px=np.float64(camera.cy_px))
    return atomic_write(path, lambda fh: np.savez_compressed(fh, **payload), force=force)


def video_frame_names(index: int, *, dense: bool = False) -> tuple[str, str]:
    """File names of one frame's depth and std maps in an output folder (``dense``: of its dense maps)."""
    prefix = "dense_" if dense else ""
    return f"{prefix}depth_{index:06d}.tif", f"{prefix}depth_std_{index:06d}.tif"


def write_video_frame(result: VideoDepthFrame, folder, *, force: bool = False) -> tuple[Path, ...]:
    """Write one frame's fused depth and std as float32 TIFFs (NaN unknown), each atomically; its dense maps too when it has them."""
    from .io import write_array

    folder = as_path("folder", folder)
    maps = [(video_frame_names(result.index), result.depth, result.depth_std)]
    if getattr(result, "dense_inverse_depth", None) is not None:
        maps.append((video_frame_names(result.index, dense=True), result.dense_depth, result.dense_depth_std))
    return tuple(write_array(folder / name, values, force=force) for names, depth, std in maps for name, values in zip(names, (depth, std)))


# ------------------------------------------------------------------ two synchronised videos

#: How :func:`interleaved_frames` forms the shared image ``I3`` from ``M[c]`` and ``R[c]``.
SHARED_FRAME_CHOICES = ("mean", "reference", "moving")

#: A crossing whose ``M[c]`` and ``R[c]`` differ at the edge points by more than
#: this many times the image noise (plus one grey level) is reported (UserWarning).
_MISMATCH_FACTOR = 3.0


@dataclass(frozen=True, eq=False)
class CrossingDepth:
    """Depth at one crossing instant of two synchronised videos.

    Attributes
    ----------
    index : int
        The crossing: 0-based frame index ``c`` of both videos.
    result : EdgeDepth
        Depth at the edge points of ``I3`` (:func:`nfdepth.pipelines.dynamic_stereo`).
    depth, depth_std : ndarray, float32, shape (H, W)
        The same as maps (:func:`nfdepth.rig.edge_depth_maps`), NaN off the
        edge points.
    registration_residual : float
        RMS of ``M[c] - R[c]`` at the edge points (grey levels): about
        ``sqrt(2)`` times the image noise when the cameras coincide at ``c``,
        larger when they do not (then a ``UserWarning`` is issued).
    noise_std : float
        Image noise of ``M[c]`` and ``R[c]`` combined, ``hypot(n_M, n_R)``.
    exposure : (float, float) or None
        ``(gain, offset)`` of the reference camera's frames against the
        moving camera's, ``R = gain M + offset`` at ``c``, undone before the
        measurement (``match_exposure``); None when they share one exposure.
    """

    index: int
    result: EdgeDepth
    depth: np.ndarray
    depth_std: np.ndarray
    registration_residual: float
    noise_std: float
    exposure: tuple | None = None

    @property
    def valid(self) -> np.ndarray:
        """Pixels of the maps that have a depth."""
        return np.isfinite(self.depth)


def _shared(moving_c: np.ndarray, reference_c: np.ndarray, shared: str) -> np.ndarray:
    if shared == "mean":
        return 0.5 * (moving_c + reference_c)
    return reference_c if shared == "reference" else moving_c


def _check_shared(shared) -> str:
    if shared not in SHARED_FRAME_CHOICES:
        msg = f"shared must be one of {', '.join(SHARED_FRAME_CHOICES)}, got {shared!r}"
        raise ValueError(msg)
    return shared


def interleaved_frames(moving, reference, crossing: int, *, shared: str = "mean") -> list:
    """The paper's five-image sequence at crossing ``c`` of two synchronised videos.

    Parameters
    ----------
    moving, reference : sequence of ndarray, shape (H, W)
        Frames of the moving and the reference camera; frame ``k`` of both
        taken at the same instant (indexable, e.g. lists).
    crossing : int
        Frame index ``c`` at which the two cameras coincide (``2 <= c <= N-3``).
    shared : {"mean", "reference", "moving"}
        ``I3``: the mean of ``M[c]`` and ``R[c]`` (default; halves the noise
        variance when the cameras coincide), or either one.

    Returns
    -------
    list of 5 ndarray
        ``[M[c-2], R[c-1], I3, R[c+1], M[c+2]]``: ``I1, I3, I5`` from the
        moving camera, ``I2, I3, I4`` from the reference one, at equal time
        steps (one video frame), as :func:`nfdepth.pipelines.dynamic_stereo`
        expects.
    """
    shared = _check_shared(shared)
    c = check_int("crossing", crossing, 2)  # (two frames before it)
    n = min(len(moving), len(reference))
    if c + 2 >= n:
        msg = f"crossing {c} needs frames {c - 2}..{c + 2}, but the videos have {n} frames (0..{n - 1})"
        raise ValueError(msg)
    m = [as_image(f"moving frame {k}", moving[k], dtype=np.float32) for k in (c - 2, c, c + 2)]
    r = [as_image(f"reference frame {k}", reference[k], dtype=np.float32) for k in (c - 1, c, c + 1)]
    return [m[0], r[0], _shared(m[1], r[1], shared), r[2], m[2]]


#: dynamic_stereo's own smoothing (the reach around a clipped plateau is twice it)
_DYNAMIC_SIGMA_PX = float(inspect.signature(dynamic_stereo).parameters["sigma_px"].default)


def _registration_residual(moving_c, reference_c, result: EdgeDepth, clipped=None) -> tuple[float, float]:
    """RMS difference of the two cameras' frames at the crossing at the edge points (not those near ``clipped`` pixels), and the noise."""
    noise = float(np.hypot(estimate_noise_std(moving_c), estimate_noise_std(reference_c)))
    ii = np.floor(result.rows).astype(np.int64)
    jj = np.floor(result.cols).astype(np.int64)
    if clipped is not None:  # a clipped highlight differs between exposures whatever the poses
        keep = ~clipped[ii, jj]
        ii, jj = ii[keep], jj[keep]
    if ii.size == 0:
        return 0.0, noise
    diff = moving_c.astype(np.float64)[ii, jj] - reference_c.astype(np.float64)[ii, jj]
    return float(np.sqrt(np.mean(diff**2))), noise


def dynamic_stereo_from_videos(
    moving: Iterable,
    reference: Iterable,
    *,
    rig: Rig,
    crossings=None,
    shared: str = "mean",
    match_exposure: bool = True,
    **options,
) -> Iterator[CrossingDepth]:
    """Dynamic stereo (paper eq. 4) at the crossing instants of two synchronised videos.

    At each crossing ``c`` the five images ``M[c-2], R[c-1], M[c]|R[c],
    R[c+1], M[c+2]`` (:func:`interleaved_frames`) go to
    :func:`nfdepth.rig.dynamic_stereo_from_rig`. The frames are read in
    lockstep and only five of each video are kept, so the videos may be long.
    This is the library form of ``nfdepth dynamic --moving-video M
    --reference-video R``.

    Parameters
    ----------
    moving, reference : iterable of ndarray, shape (H, W)
        Grey frames of the moving and the reference camera (e.g.
        :func:`read_video`), frame ``k`` of both at the same instant.
    rig : Rig
        ``[camera]`` (both cameras' intrinsics) and ``[motion]``: the moving
        camera's motion relative to the reference at the crossings, with
        ``frame_interval`` the time between consecutive frames.
    crossings : list of int, optional
        Frame indices at which the cameras coincide (default:
        ``[motion].crossings``); each needs two frames on either side.
    shared : {"mean", "reference", "moving"}
        How ``I3`` is formed from ``M[c]`` and ``R[c]``.
    match_exposure : bool
        Map the reference camera's frames onto the moving camera's exposure
        first, from ``M[c]`` and ``R[c]`` (the same pose: every pixel a
        pair; the line through their quantiles, undone where it explains at
        least 30 % of their median difference, :mod:`nfdepth._exposure`):
        eq. 4 reads two cameras' exposure difference as motion.
    **options
        Passed to :func:`nfdepth.pipelines.dynamic_stereo` (``sigma_px``, ...).

    Yields
    ------
    CrossingDepth
        One per crossing, in order, as soon as frame ``c + 2`` has been read.

    Raises
    ------
    RigError
        No ``[motion]``, no crossings (at the call), a frame size that differs from ``[camera]``.
    TypeError
        At the call: an option :func:`nfdepth.pipelines.dynamic_stereo` does not
        take, or one the rig gives (``camera``, ``relative_motion``, ``frame_interval``).
    ValueError
        A crossing the videos do not cover (too short).

    Warns
    -----
    UserWarning
        When ``M[c]`` and ``R[c]`` differ at the edge points by more than
        three times the noise plus one grey level: the cameras do not
        coincide at ``c`` (wrong crossing index, or the rig is not one this
        method fits) and the depths are biased.
    """
    motion = rig._need("motion")
    shared = _check_shared(shared)
    match_exposure = check_bool("match_exposure", match_exposure)
    if crossings is None:
        if motion.crossings is None:
            where = f"rig '{rig.source}'" if rig.source else "the rig"
            raise RigError(f"{where}: motion.crossings is missing and no crossings were given: expected the frame indices at which the cameras coincide")
        wanted = motion.crossings
    else:
        wanted = check_crossings(crossings, name="crossings")
    _check_dynamic_options(options)
    return _crossing_depths(moving, reference, rig=rig, wanted=wanted, shared=shared, match_exposure=match_exposure, options=options)


def _crossing_depths(moving, reference, *, rig, wanted, shared, match_exposure, options) -> Iterator[CrossingDepth]:
    """:func:`dynamic_stereo_from_videos`' crossings, from its checked arguments (a generator: the checks run at the call)."""
    pending = list(wanted)
    keep = 5
    m_win: list = []
    r_win: list = []
    n = 0
    for n, (m, r) in enumerate(zip(moving, reference)):
        for what, f, win in (("moving", m, m_win), ("reference", r, r_win)):
            win.append(_own_image(f"{what} frame {n}", f))  # a 2-D array of finite numbers first: its size is read next
            rig.check_image_shape(win[-1].shape, what=f"{what} frame {n}")
        m_win, r_win = m_win[-keep:], r_win[-keep:]
        while pending and pending[0] + 2 == n:
            c = pending.pop(0)
            r_used, exposure = match_camera_exposure(m_win[2], r_win, at=2) if match_exposure else (r_win, None)  # R[c] against M[c]
            frames = interleaved_frames(m_win, r_used, 2, shared=shared)  # window index 2 is frame c
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                result = dynamic_stereo_from_rig(frames, rig, match_exposure=match_exposure, **options)  # and each frame onto I3's
            for w in caught:  # as raised, named by crossing; for two videos a sign mistake may be the videos swapped
                message = str(w.message)
                if re.match(_BEHIND_WARNING, message) and "NOT_POSITIVE)" in message:
                    message = message[: message.index("NOT_POSITIVE)") + len("NOT_POSITIVE)")] + (
                        "; are the moving and the reference videos swapped, or is the rig's motion of the wrong sign (V = -T"
                        " for a camera moving by T)?"
                    )
                named = w.category(f"crossing {c}: {message}")
                vars(named).update(vars(w.message))  # (a NoEdgePointsWarning's rule and reason)
                warnings.warn(named, stacklevel=2)
            reach = int(np.ceil(2.0 * float(options.get("sigma_px", _DYNAMIC_SIGMA_PX))))  # the smoothing spreads a plateau's edge this far
            apart = clipped_apart(m_win[2], r_win[2], exposure, reach)
            if apart.any():  # the edge points beside one camera's clipped highlights: wrong flows, UNCERTAIN
                _void_points(result, apart, Reason.UNCERTAIN, determinable_only=True)
            residual, noise = _registration_residual(m_win[2], r_used[2], result, apart)
            if residual > _MISMATCH_FACTOR * noise + 1.0:
                warnings.warn(
                    f"crossing {c}: the two cameras' frames {c} differ by {residual:.3g} grey levels (RMS at the edge points; "
                    f"image noise {noise:.3g}): the cameras do not coincide at frame {c}, so the depths are biased; "
                    "check the crossing index and that the videos are synchronised",
                    UserWarning,
                    stacklevel=2,
                )
            depth, std = edge_depth_maps(result)
            yield CrossingDepth(c, result, depth, std, residual, noise, exposure)
        if not pending:
            return
    count = n + 1 if (m_win or r_win) else 0
    msg = (
        f"crossing {pending[0]} needs frames {pending[0] - 2}..{pending[0] + 2}, but the videos end after {count} frames"
        + (f" (0..{count - 1})" if count else "")
    )
    raise ValueError(msg)


def write_crossings_npz(results, path, *, camera: PinholeCamera | None = None, force: bool = False) -> Path:
    """Write :class:`CrossingDepth` results to one ``.npz``, atomically.

    Holds ``crossing`` (N,), ``registration_residual`` (N,), ``noise_std``
    (N,) and float32 ``(N, H, W)`` stacks ``depth`` and ``depth_std`` (NaN
    off the edge points); with ``camera`` also ``focal_px``, ``cx_px``,
    ``cy_px``.
    """
    from .io import atomic_write, require_extension

    require_extension(path, ".npz")

    results = list(results)
    payload = {
        "crossing": np.array([r.index for r in results], dtype=np.int64),
        "registration_residual": np.array([r.registration_residual for r in results], dtype=float),
        "noise_std": np.array([r.noise_std for r in results], dtype=float),
    }
    for name in ("depth", "depth_std"):
        payload[name] = np.stack([np.asarray(getattr(r, name), dtype=np.float32) for r in results]) if results else np.zeros((0, 0, 0), np.float32)
    if camera is not None:
        payload.update(focal_px=np.float64(camera.focal_px), cx_px=np.float64(camera.cx_px), cy_px=np.float64(camera.cy_px))
    return atomic_write(path, lambda fh: np.savez_compressed(fh, **payload), force=force)
