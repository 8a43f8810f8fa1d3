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


def _world_texture(seed, min_wavelength, max_wavelength):
    rng = np.random.default_rng(seed)
    n = 40
    wavelength = rng.uniform(min_wavelength, max_wavelength, n)
    angle = rng.uniform(0.0, np.pi, n)
    kx, ky = 2.0 * np.pi * np.cos(angle) / wavelength, 2.0 * np.pi * np.sin(angle) / wavelength
    phase = rng.uniform(0.0, 2.0 * np.pi, n)
    return lambda x, y: 100.0 + 40.0 / np.sqrt(n / 2) * np.sin(kx * x[..., None] + ky * y[..., None] + phase).sum(-1)


#: The world of :func:`textured_world_frame`: a textured wall at Z = 60 and, in front of it, a
#: textured board at Z = 40 over |X| <= 8, |Y| <= 6 (scene units).
WALL_Z, BOARD_Z, BOARD_HALF = 60.0, 40.0, (8.0, 6.0)


def textured_world_frame(camera, rotation, position, *, noise=1.0, rng=None, supersample=3):
    """A frame of the textured wall-and-board world, and its true depth (pixel centres).

    ``rotation`` is the camera-to-world matrix, ``position`` the optical
    centre. Textures are sums of sinusoids in world units (wavelengths of
    6 px or more seen from the origin with ``f = 100``), integrated over
    ``supersample**2`` points per pixel so the board's outline is anti-aliased.
    """
    wall = _world_texture(11, 4.0, 18.0)
    board = _world_texture(12, 2.5, 12.0)
    h, w = camera.shape
    rotation, position = np.asarray(rotation, float), np.asarray(position, float)

    def hit(rows, cols):
        x = (cols - camera.cx_px) / camera.focal_px
        y = (rows - camera.cy_px) / camera.focal_px
        d = [rotation[i, 0] * x + rotation[i, 1] * y + rotation[i, 2] for i in range(3)]  # world ray per unit camera depth
        t_board = (BOARD_Z - position[2]) / d[2]
        bx, by = position[0] + t_board * d[0], position[1] + t_board * d[1]
        on_board = (t_board > 0) & (np.abs(bx) <= BOARD_HALF[0]) & (np.abs(by) <= BOARD_HALF[1])
        t_wall = (WALL_Z - position[2]) / d[2]
        wx, wy = position[0] + t_wall * d[0], position[1] + t_wall * d[1]
        value = np.where(on_board, board(bx, by), wall(wx, wy))
        return value, np.where(on_board, t_board, t_wall)  # t is the camera depth (d has camera z = 1)

    rows, cols = np.mgrid[0:h, 0:w].astype(float)
    offsets = (np.arange(supersample) + 0.5) / supersample - 0.5
    image = np.mean([hit(rows + dr, cols + dc)[0] for dr in offsets for dc in offsets], axis=0)
    if noise:
        image = image + (rng if rng is not None else np.random.default_rng(0)).normal(0.0, noise, image.shape)
    return image.astype(np.float32), hit(rows, cols)[1]
