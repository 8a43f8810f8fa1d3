"""Noisy views of a slanted, sinusoid-textured plane with exact truth (test helper).

The plane has disparity ``d(c) = d0 + slope * c`` (px per view step) at the
reference's column ``c``; its texture, a sum of 40 sinusoids, is evaluated
exactly at every pixel of every view, so no resampling error enters the truth.
"""

import numpy as np


def _texture(rng, *, min_wavelength_px, angles_rad):
    n = 40
    wavelength = rng.uniform(min_wavelength_px, 30.0, n)
    angle = rng.uniform(angles_rad[0], angles_rad[1], n)
    ky, kx = 2.0 * np.pi * np.sin(angle) / wavelength, 2.0 * np.pi * np.cos(angle) / wavelength
    phase = rng.uniform(0.0, 2.0 * np.pi, n)

    def texture(r, c):
        return 100.0 + 40.0 / np.sqrt(n / 2) * np.sin(ky * r[..., None] + kx * c[..., None] + phase).sum(-1)

    return texture


def slanted_plane_views(d0, slope, *, shape=(96, 160), noise=2.0, seed=3, min_wavelength_px=6.0, angles_rad=(0.0, np.pi), column=False):
    """Three views along a row (reference the middle) and the truth ``d0 + slope * col``.

    Texture wavelengths ``min_wavelength_px``-30 px, wave normals at angles in
    ``angles_rad`` from the column axis (``(pi/2 - a, pi/2 + a)``: edges
    within ``a`` of horizontal, parallel to the row's baseline). View ``s =
    -1, 0, 1`` at column ``c'`` sees reference column ``c`` with ``c' = c - s
    d(c)``. With ``column=True`` also three views along a column through the
    same reference (camera moving toward +Y): view ``s`` at row ``r'`` sees
    reference row ``r = r' + s d(c)``; returns ``(row, column, truth)`` with
    ``column[1] is row[1]``.
    """
    rng = np.random.default_rng(seed)
    texture = _texture(rng, min_wavelength_px=min_wavelength_px, angles_rad=angles_rad)
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    truth = d0 + slope * cols
    views = []
    for s in (-1, 0, 1):
        c_ref = (cols + s * d0) / (1.0 - s * slope)
        views.append((texture(rows, c_ref) + rng.normal(0.0, noise, shape)).astype(np.float32))
    if not column:
        return views, truth
    col = [views[1] if s == 0 else (texture(rows + s * truth, cols) + rng.normal(0.0, noise, shape)).astype(np.float32) for s in (-1, 0, 1)]
    return views, col, truth
