"""Turn a frame to another orientation of the same camera (rotating cameras in the video pipeline).

Paper eq. 1 splits the image flow of a moving camera into a rotational
part, which does not depend on depth, and a translational part ``B / Z``.
Eq. 4 removes the rotational part as the term ``A``, the first-order flow
of the angular velocity, which holds only within the differential method's
1-2 px per frame: a camera turning 1 degree per frame moves the image by
``0.0175 f`` px, 8.7 px at ``f = 500``. Here it is removed exactly, in the
image: a camera that only rotates, from camera-to-world orientation ``R_j``
to ``R_k``, sees two images related by the homography ``K R_j^T R_k K^-1``
whatever the scene's depth. The outer frames ``k-1`` and ``k+1`` of a
triple are resampled as if taken with frame ``k``'s orientation from their
own positions, and the triple becomes one of a translating camera
(:mod:`nfdepth._translating_pyramid`, :func:`nfdepth.pipelines.static_stereo_edges`).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from scipy import ndimage

from .camera import PinholeCamera

#: A turn that moves no pixel by more than this is no turn: the frame is used as taken
#: (orientations that differ by a full turn, or by float rounding, are the same).
STILL_PX = 1e-6


def turn_rays(rotation, x, y) -> list[np.ndarray]:
    """``rotation @ (x, y, 1)`` for normalised coordinates ``x``, ``y`` (any broadcasting shapes).

    Three float64 arrays, the ray's components, built by columns of
    ``rotation`` (no ``(..., 3)`` temporary).
    """
    r = np.asarray(rotation, dtype=np.float64)
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    return [r[i, 0] * x + r[i, 1] * y + r[i, 2] for i in range(3)]


def grid_rays(rotation, x, y) -> list[np.ndarray]:
    """:func:`turn_rays` on the grid of normalised coordinates ``x`` (columns) by ``y`` (rows): three ``(len(y), len(x))`` arrays."""
    return turn_rays(rotation, np.asarray(x, dtype=np.float64)[None, :], np.asarray(y, dtype=np.float64)[:, None])


def derotation_maps(camera: PinholeCamera, rotation, *, grid=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where each pixel of a frame turned to another orientation reads the frame as taken.

    ``rotation`` (3 x 3) is ``R_j^T R_k``: the target orientation's axes
    (camera-to-world ``R_k``) in the camera axes of the frame as taken
    (``R_j``). A ray ``d`` of the target reads the frame at the projection of
    ``R_j^T R_k d``. Returns ``(map_col, map_row, inside)``: float32 maps
    for :func:`derotate` (pixel centres at integers, as the camera's) and
    where the read lies in front of the camera and inside the frame (to
    :data:`STILL_PX`). Reads outside are clamped to the frame's border,
    reads behind the camera go to its corner.

    ``grid``, ``(height, width, cx_px, cy_px)``, gives the turned frame
    another pixel grid of the same focal length (a canvas that holds all of
    a frame turned far, :mod:`nfdepth._dense_video`); default the camera's own.
    """
    h, w = camera.shape
    f = camera.focal_px
    out_h, out_w, out_cx, out_cy = (h, w, camera.cx_px, camera.cy_px) if grid is None else grid
    x = (np.arange(out_w, dtype=np.float64) - out_cx) / f
    y = (np.arange(out_h, dtype=np.float64) - out_cy) / f
    turned = grid_rays(rotation, x, y)
    ahead = turned[2] > 0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        col = np.where(ahead, camera.cx_px + f * turned[0] / turned[2], -1.0)
        row = np.where(ahead, camera.cy_px + f * turned[1] / turned[2], -1.0)
    inside = ahead & (col >= -STILL_PX) & (col <= w - 1 + STILL_PX) & (row >= -STILL_PX) & (row <= h - 1 + STILL_PX)
    return np.clip(col, -1.0, w).astype(np.float32), np.clip(row, -1.0, h).astype(np.float32), inside


def moves_pixels(camera: PinholeCamera, rotation) -> bool:
    """Whether turning by ``rotation`` (as for :func:`derotation_maps`) moves some pixel by more than :data:`STILL_PX`."""
    h, w = camera.shape
    corners = np.array([[0.0, 0.0], [0.0, w - 1.0], [h - 1.0, 0.0], [h - 1.0, w - 1.0], [camera.cy_px, camera.cx_px]])
    x = (corners[:, 1] - camera.cx_px) / camera.focal_px
    y = (corners[:, 0] - camera.cy_px) / camera.focal_px
    d = np.asarray(rotation, dtype=np.float64) @ np.stack([x, y, np.ones_like(x)])
    if np.any(d[2] <= 0):
        return True
    # a rotation fixes at most one image point (where its axis meets the image): the others of these five move
    moved = np.hypot(d[0] / d[2] - x, d[1] / d[2] - y) * camera.focal_px
    return bool(np.max(moved) > STILL_PX)


def derotate(image: np.ndarray, maps) -> np.ndarray:
    """``image`` resampled through ``maps`` (:func:`derotation_maps`): cubic spline, border replicated, float32.

    Bilinear reads blur the turned frame by an amount that varies with the
    fraction of a pixel read, unlike the middle frame, and the blur reads
    as motion at strong edges: on the pyramid turning 5 degrees per frame
    (one triple, 3 seeds) the median error was 2.1-2.5 % and 13 % of the
    points of a diagonal step were off by more than 10 %; with the cubic
    spline 1.3-1.8 % and 0.1 % (a quintic: no better; 15 ms a 640 x 480
    frame against 0.2 ms).
    """
    map_col, map_row, _inside = maps
    return ndimage.map_coordinates(np.asarray(image, np.float32), [map_row, map_col], order=3, mode="nearest", output=np.float32)


def measurable(inside: np.ndarray, *, sigma_px: float) -> np.ndarray:
    """``inside`` shrunk by the reach of the smoothing (4 ``sigma_px``) and the stencil (2 px): where no void read enters a measurement."""
    side = 2 * (math.ceil(4.0 * sigma_px) + 2) + 1
    shrunk = inside.astype(np.uint8)
    for kernel in (np.ones((1, side), np.uint8), np.ones((side, 1), np.uint8)):  # a square, as two lines
        shrunk = cv2.erode(shrunk, kernel, borderType=cv2.BORDER_CONSTANT, borderValue=1)
    return shrunk.astype(bool)
