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

from .camera import PinholeCamera


def derotation_maps(camera: PinholeCamera, rotation) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where each pixel of a frame turned to another orientation reads the frame as taken.

    ``rotation`` (3 x 3) is ``R_j^T R_k``: the target orientation's axes
    (camera-to-world ``R_k``) in the camera axes of the frame as taken
    (``R_j``). A ray ``d`` of the target reads the frame at the projection of
    ``R_j^T R_k d``. Returns ``(map_col, map_row, inside)``: float32 maps
    for ``cv2.remap`` (pixel centres at integers, as the camera's) and
    where the read lies in front of the camera and inside the frame.
    """
    h, w = camera.shape
    f = camera.focal_px
    x = (np.arange(w, dtype=np.float64) - camera.cx_px) / f
    y = (np.arange(h, dtype=np.float64) - camera.cy_px) / f
    r = np.asarray(rotation, dtype=np.float64)
    # R (x, y, 1) for every pixel, by columns of R (no (H, W, 3) temporary)
    turned = [r[i, 0] * x[None, :] + r[i, 1] * y[:, None] + r[i, 2] for i in range(3)]
    ahead = turned[2] > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        col = camera.cx_px + f * turned[0] / turned[2]
        row = camera.cy_px + f * turned[1] / turned[2]
    inside = ahead & (col >= 0) & (col <= w - 1) & (row >= 0) & (row <= h - 1)
    # reads behind the camera or far outside: any finite place (the border is replicated; ``inside`` says they are void)
    col = np.where(inside, col, -1.0).astype(np.float32)
    row = np.where(inside, row, -1.0).astype(np.float32)
    return col, row, inside


def derotate(image: np.ndarray, maps) -> np.ndarray:
    """``image`` resampled through ``maps`` (:func:`derotation_maps`): bilinear, border replicated, same dtype."""
    map_col, map_row, _inside = maps
    return cv2.remap(image, map_col, map_row, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def measurable(inside: np.ndarray, *, sigma_px: float) -> np.ndarray:
    """``inside`` shrunk by the reach of a Gaussian of ``sigma_px`` and the 2 x 2 stencil: where no void read enters a measurement."""
    reach = math.ceil(3.0 * sigma_px) + 1
    kernel = np.ones((2 * reach + 1, 2 * reach + 1), np.uint8)
    return cv2.erode(inside.astype(np.uint8), kernel, borderType=cv2.BORDER_CONSTANT, borderValue=1).astype(bool)
