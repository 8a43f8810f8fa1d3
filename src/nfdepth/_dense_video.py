"""Dense depth of a video triple (or a longer row of frames): its frames rectified into a row of static-stereo views.

A triple of a camera translating through a still scene is static stereo
(paper section 2.3), and :func:`nfdepth.stereo.static_stereo` gives a dense
map for views spaced along its X axis (coarse to fine, cost volume, per-pixel
std). A video's triple is turned into such a row the way stereo pairs are
rectified: all three frames are resampled (:mod:`nfdepth._derotation`, the
homography ``K R_j^T R_rect K^-1``, cubic spline) to one common orientation
``R_rect`` whose X axis is the camera's path from frame ``k-1`` to ``k+1``
and whose optical axis is the one nearest frame ``k``'s. Their positions
along that path are the views' positions. The dense inverse depth of the
rectified middle view is read back into frame ``k``'s own pixels (nearest
pixel, so no depth is averaged across a step) and converted from depth
along the rectified optical axis to depth along frame ``k``'s: ``rho_k =
(R_rect^T R_k (x, y, 1))_z rho_rect``.

A camera whose path runs sideways and that does not turn needs no
resampling at all (``R_rect = R_k``): the triple goes to static stereo as
taken. The more its path points along the optical axis, the larger the
rectified view of frame ``k`` (it is stretched away from the centre): the
canvas is limited to :data:`MAX_CANVAS` times the frame's width and height,
and pixels of frame ``k`` beyond it get no dense depth. Moving straight
ahead (path within :data:`MIN_SIDEWAYS_DEG` of the optical axis) none do:
epipolar lines radiate from the focus of expansion, which no row of views
reproduces. The edge points (eq. 4, any direction of motion) are measured
as before.

A longer row (``dense_frames_before`` of :func:`nfdepth.video.depth_from_video`:
frames ``k - N .. k + 1``) is rectified the same way, with the path from
its first frame to its last, for a camera that moves little per frame:
static stereo's precision follows the farthest view.

The views go to static stereo in their order along the path, whatever
their order in time: a camera that reverses within the triple (the middle
frame beyond one of its neighbours) has the middle view at an end of the
row, and an outer frame taken where the middle one was (the camera paused)
is left out, leaving two views.

The dense map is pixel-centred (pixel ``(r, c)`` at its centre, as
:class:`nfdepth.stereo.StereoResult`), unlike the edge-point and fused maps
of :mod:`nfdepth.video`, which are on the stencil's cell grid.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from ._derotation import derotate, derotation_maps, grid_rays, moves_pixels
from .camera import PinholeCamera
from .stereo import static_stereo

#: The rectified canvas spans at most this many frame widths and heights.
MAX_CANVAS = 2.0
#: A path closer than this to the optical axis gives no dense map (no row of views from it).
MIN_SIDEWAYS_DEG = 5.0
#: An outer frame nearer the middle one than this share of the path is taken where the middle one was.
_SAME_PLACE = 1e-6


@dataclass(frozen=True)
class DenseRow:
    """Dense inverse depth of the middle frame of a row of frames (:func:`dense_row`).

    ``rho`` and ``rho_std`` (H x W float64, pixel-centred, NaN where
    unknown); ``covered``: the fraction of the middle frame's pixels the
    rectified canvas holds (1 unless the path points near the optical
    axis); ``off_line``: how far the frames' positions lie off the line
    through the first and last, the farthest of them, relative to the
    mean step along it (for a triple: the middle one, relative to half
    the outer two's distance); ``off_line_ahead``: the part of that along
    the rectified optical axis (it changes a view's scale; the rest,
    across the path in the image plane, misaligns the rectified views
    vertically). 0 without a rectification.
    """

    rho: np.ndarray
    rho_std: np.ndarray
    covered: float
    off_line: float
    off_line_ahead: float = 0.0


def rectifying_orientation(mid_rotation, path) -> np.ndarray | None:
    """Camera-to-world orientation with X along ``path`` (world axes) and Z nearest ``mid_rotation``'s optical axis.

    ``None`` when ``path`` is within :data:`MIN_SIDEWAYS_DEG` of the optical axis.
    """
    x = np.asarray(path, dtype=float) / np.linalg.norm(path)
    optical = np.asarray(mid_rotation, dtype=float)[:, 2]
    z = optical - (optical @ x) * x
    if np.linalg.norm(z) < math.sin(math.radians(MIN_SIDEWAYS_DEG)):
        return None
    z /= np.linalg.norm(z)
    return np.stack([x, np.cross(z, x), z], axis=1)  # right-handed: x cross y = z


def _rays(camera: PinholeCamera, rotation, rows, cols) -> list:
    """``rotation @ (x, y, 1)`` for the normalised image coordinates of ``rows`` x ``cols`` (three arrays)."""
    x = (np.asarray(cols, dtype=float) - camera.cx_px) / camera.focal_px
    y = (np.asarray(rows, dtype=float) - camera.cy_px) / camera.focal_px
    return grid_rays(rotation, x, y)


def _canvas(camera: PinholeCamera, to_rect) -> tuple[int, int, float, float]:
    """Pixel grid ``(height, width, cx, cy)`` of the rectified view that holds the middle frame, within :data:`MAX_CANVAS`."""
    h, w = camera.shape
    f = camera.focal_px
    corners = _rays(camera, to_rect, [0.0, h - 1.0], [0.0, w - 1.0])
    centre = [float(v[0, 0]) for v in _rays(camera, to_rect, [camera.cy_px], [camera.cx_px])]
    # positions on the frame's own pixel grid, extended (the rectified view has the same focal length)
    mid_col, mid_row = camera.cx_px + f * centre[0] / centre[2], camera.cy_px + f * centre[1] / centre[2]
    half_w, half_h = MAX_CANVAS * w / 2.0, MAX_CANVAS * h / 2.0
    if np.all(corners[2] > 0):
        cols, rows = camera.cx_px + f * corners[0] / corners[2], camera.cy_px + f * corners[1] / corners[2]
        c0 = max(float(cols.min()), mid_col - half_w)
        c1 = min(float(cols.max()), mid_col + half_w)
        r0 = max(float(rows.min()), mid_row - half_h)
        r1 = min(float(rows.max()), mid_row + half_h)
    else:  # part of the frame looks behind the rectified view: the largest canvas
        c0, c1, r0, r1 = mid_col - half_w, mid_col + half_w, mid_row - half_h, mid_row + half_h
    # whole pixels, with float rounding (1e-6 px) of a canvas that is the frame itself forgiven
    c0, r0 = math.floor(c0 + 1e-6), math.floor(r0 + 1e-6)
    c1, r1 = math.ceil(c1 - 1e-6), math.ceil(r1 - 1e-6)
    return r1 - r0 + 1, c1 - c0 + 1, camera.cx_px - c0, camera.cy_px - r0


def _static_stereo(views, reference, positions, noise_std, threads, match_exposure=True):
    with warnings.catch_warnings():
        # static stereo's own notes (few edge points, behind the camera) say nothing a video run does not report
        warnings.simplefilter("ignore", UserWarning)
        return static_stereo(views, reference=reference, positions=positions, noise_std=noise_std, threads=threads, match_exposure=match_exposure)


def dense_row(frames, camera: PinholeCamera, rotations, positions, *, middle: int, noise_std, threads: int | None = None, match_exposure: bool = True) -> DenseRow:
    """Dense inverse depth (and its std) of frame ``middle`` of a row of frames taken along a path (module docstring).

    ``frames`` in the order taken (a triple, or more frames before the
    middle one: a longer row, :func:`nfdepth.video.depth_from_video`'s
    ``dense_frames_before``); ``rotations``: their camera-to-world
    matrices; ``positions``: their optical centres (world). The path runs
    from the first frame's position to the last's. ``noise_std`` is the
    image noise of the frames as taken (resampling smooths it away; None:
    estimated); ``threads`` and ``match_exposure`` as
    :func:`nfdepth.stereo.static_stereo`, whose pyramid depth follows the
    canvas size.
    """
    h, w = camera.shape
    nan = np.full((h, w), np.nan)
    pos = [np.asarray(p, dtype=float) for p in positions]
    n = len(pos)
    path = pos[-1] - pos[0]
    length = float(np.linalg.norm(path))
    along = path / length
    along_path = [0.0, *(float(along @ (p - pos[0])) for p in pos[1:-1]), length]
    offsets = [p - pos[0] - a * along for p, a in zip(pos, along_path)]
    step = length / (n - 1)  # the mean step along the path
    off_line = max(float(np.linalg.norm(o)) for o in offsets) / step
    rect = rectifying_orientation(rotations[middle], path)
    if rect is None:
        return DenseRow(nan, nan.copy(), 0.0, off_line)
    off_ahead = max(abs(float(rect[:, 2] @ o)) for o in offsets) / step
    # the views in their order along the path; a frame where the middle one (or an earlier kept one) is adds nothing
    order = [middle]
    for j in range(n):
        if j != middle and all(abs(along_path[j] - along_path[i]) > _SAME_PLACE * length for i in order):
            order.append(j)
    order.sort(key=along_path.__getitem__)
    to_rect = rect.T @ np.asarray(rotations[middle], dtype=float)  # a middle-frame ray in rectified axes
    grid = _canvas(camera, to_rect)
    as_taken = grid == (h, w, camera.cx_px, camera.cy_px)
    views, seen = [], None
    for j in order:
        frame = frames[j]
        turn = np.asarray(rotations[j], dtype=float).T @ rect
        if as_taken and not moves_pixels(camera, turn):
            views.append(np.asarray(frame, dtype=np.float32))
            continue
        maps = derotation_maps(camera, turn, grid=grid)
        views.append(derotate(frame, maps))
        if j == middle:
            seen = maps[2]
    res = _static_stereo(views, order.index(middle), [along_path[j] for j in order], noise_std, threads, match_exposure)
    f = camera.focal_px
    rho_rect = res.disparity.astype(np.float64) / f  # px per unit of position = f / Z
    std_rect = res.uncertainty.astype(np.float64) / f
    if seen is not None:
        rho_rect[~seen] = np.nan
    # back into the middle frame: each pixel takes the rectified pixel nearest to where it lies there
    ray = _rays(camera, to_rect, np.arange(h), np.arange(w))
    with np.errstate(divide="ignore", invalid="ignore"):
        col = np.rint(grid[2] + f * ray[0] / ray[2])
        row = np.rint(grid[3] + f * ray[1] / ray[2])
    on = (ray[2] > 0) & (col >= 0) & (col < grid[1]) & (row >= 0) & (row < grid[0])
    rr, cc = row[on].astype(np.int64), col[on].astype(np.int64)
    rho, std = nan, nan.copy()
    rho[on] = rho_rect[rr, cc] * ray[2][on]
    std[on] = std_rect[rr, cc] * ray[2][on]
    std[np.isnan(rho)] = np.nan
    return DenseRow(rho, std, float(on.mean()), off_line, off_ahead)
