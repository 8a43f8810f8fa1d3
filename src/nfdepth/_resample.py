"""Bilinear resampling of float32 images at given positions (``cv2.remap``), at any size.

``cv2.remap`` refuses sources and maps of 32767 px or more on a side
(``SHRT_MAX``): a long edge-point list read as a 1 x N map, or a frame that
wide, would fail inside OpenCV. Point lists are laid out in rows of
:data:`_ROW_PX`; images beyond the limit go through
:func:`scipy.ndimage.map_coordinates` (order 1, the same bilinear reads
without OpenCV's 1/32 px quantisation of the position).
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

_CV_LIMIT_PX = 32767  # cv2.remap: source and map sides must be smaller
_ROW_PX = 4096  # point lists are read as maps of rows this long


def remap_linear(image: np.ndarray, map_col: np.ndarray, map_row: np.ndarray) -> np.ndarray:
    """``image`` read at ``(map_row, map_col)`` (pixel centres at integers): bilinear, border replicated, float32 maps."""
    if max(image.shape) < _CV_LIMIT_PX and max(map_col.shape) < _CV_LIMIT_PX:
        return cv2.remap(image, map_col, map_row, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return ndimage.map_coordinates(image, [map_row, map_col], order=1, mode="nearest", output=image.dtype)


def sample_points(image: np.ndarray, rows, cols) -> np.ndarray:
    """Bilinear samples of ``image`` at ``(rows, cols)``, float64, as :func:`remap_linear` reads them."""
    r = np.asarray(rows, np.float32).ravel()
    c = np.asarray(cols, np.float32).ravel()
    n = c.size
    if n == 0:  # cv2.remap refuses an empty map
        return np.zeros(0)
    width = min(n, _ROW_PX)
    pad = -n % width
    shape = ((n + pad) // width, width)
    c = np.concatenate([c, np.zeros(pad, np.float32)]).reshape(shape)
    r = np.concatenate([r, np.zeros(pad, np.float32)]).reshape(shape)
    return remap_linear(image, c, r).ravel()[:n].astype(np.float64)
