"""A real row of views as filmed by a camera that also turns (test helper).

Each view ``k`` is resampled as the camera turned ``(k - reference) *
turn_deg`` degrees about Y would see it (a homography, exact for a
rotation), and all are cropped to what every turned view sees.
``benchmarks/video_rows.py`` does the same (tests do not import the
benchmarks).
"""

import numpy as np
from scipy.spatial.transform import Rotation

from nfdepth._derotation import derotate, derotation_maps
from nfdepth.camera import PinholeCamera


def turned_row(scene, turn_deg, *, views=None):
    """Frames ``0 .. views - 1`` (default: to one past the reference), their camera, orientations (rad) and the crop."""
    h, w = scene.shape
    full = PinholeCamera(scene.focal_px or float(w), w, h)
    ref = scene.reference_index
    angles = np.deg2rad(turn_deg) * (np.arange(ref + 2 if views is None else views) - ref)
    maps = [derotation_maps(full, Rotation.from_rotvec((0.0, a, 0.0)).as_matrix()) for a in angles]
    inside = np.logical_and.reduce([m[2] for m in maps])
    margin = next(m for m in range(min(h, w) // 2) if inside[m : h - m, m : w - m].all())
    crop = (slice(margin, h - margin), slice(margin, w - margin))
    frames = [derotate(np.asarray(v, np.float32), m)[crop] for v, m in zip(scene.views, maps)]
    cam = PinholeCamera(full.focal_px, w - 2 * margin, h - 2 * margin)
    orientations = np.stack([np.zeros_like(angles), angles, np.zeros_like(angles)], axis=1)
    return frames, cam, orientations, crop
