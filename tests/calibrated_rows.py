"""A slanted, sinusoid-textured plane seen by a calibrated row of cameras that is not rectified (test helper).

Each camera has its own intrinsics, lens distortion, a small turn and an
offset from the line; every pixel's ray (distortion undone by OpenCV) meets
the plane ``Z = z0 + slope * X`` (world axes) at a point whose texture, a sum
of sinusoids in world ``X, Y``, is evaluated exactly, so no resampling enters
the images or the truth.
"""

import cv2
import numpy as np

from nfdepth.rectify import CalibratedCamera

SHAPE = (120, 180)


def rotation_deg(rx, ry, rz):
    return cv2.Rodrigues(np.radians([rx, ry, rz]).reshape(3, 1))[0]


def camera(fx, cx, cy, position, turn_deg=(0.0, 0.0, 0.0), distortion=(), fy=None, shape=SHAPE):
    k = np.array([[fx, 0.0, cx], [0.0, fx if fy is None else fy, cy], [0.0, 0.0, 1.0]])
    return CalibratedCamera(matrix=k, width_px=shape[1], height_px=shape[0], position=np.asarray(position, float), rotation=rotation_deg(*turn_deg), distortion=np.asarray(distortion, float))


def default_row(baseline=0.1, off_line=(0.0, 0.0, 0.0)):
    """Three cameras about ``baseline`` apart along world X, the middle one the reference."""
    return [
        camera(400.0, 92.0, 58.0, (-baseline, 0.0, 0.0), turn_deg=(0.8, -1.5, 0.6), distortion=(-0.08, 0.02, 0.0, 0.0)),
        camera(410.0, 89.5, 60.5, (0.0, 0.0, 0.0), turn_deg=(-0.4, 0.7, -0.3), distortion=(0.05, 0.0, 0.001, -0.001, 0.0), fy=411.0),
        camera(395.0, 90.0, 59.0, np.add((baseline, 0.0, 0.0), off_line), turn_deg=(0.3, 1.2, 0.9)),
    ]


def _texture(seed):
    rng = np.random.default_rng(seed)
    n = 40
    wavelength = rng.uniform(0.11, 0.45, n)  # world units: 7-30 px at Z = 6, f = 400
    angle = rng.uniform(0.0, np.pi, n)
    ky, kx = 2 * np.pi * np.sin(angle) / wavelength, 2 * np.pi * np.cos(angle) / wavelength
    phase = rng.uniform(0.0, 2 * np.pi, n)

    def texture(x, y):
        return 100.0 + 40.0 / np.sqrt(n / 2) * np.sin(ky * y[..., None] + kx * x[..., None] + phase).sum(-1)

    return texture


def render(cameras, *, z0=6.0, slope=0.15, noise=1.0, seed=4):
    """The views and, per camera, its true depth (along its own optical axis) at every pixel."""
    texture = _texture(seed)
    rng = np.random.default_rng(seed + 1)
    views, depths = [], []
    for cam in cameras:
        xy = cam.rays()
        ray = np.einsum("ij,hwj->hwi", cam.rotation, np.concatenate([xy, np.ones(xy.shape[:2] + (1,))], axis=-1))
        c = cam.position
        s = (z0 + slope * c[0] - c[2]) / (ray[..., 2] - slope * ray[..., 0])
        p = c + s[..., None] * ray
        img = texture(p[..., 0], p[..., 1]) + rng.normal(0.0, noise, s.shape)
        views.append(img.astype(np.float32))
        depths.append(s)  # the ray's z in camera axes is 1: s is the depth along the optical axis
    return views, depths


def cameras_toml(cameras, *, opencv=False) -> str:
    """A cameras file for ``nfdepth stereo --cameras`` (pose as position and rotation_deg, or as OpenCV's rvec and tvec)."""
    lines = []
    for cam in cameras:
        k = cam.matrix
        lines += ["[[camera]]", f"width_px = {cam.width_px}", f"height_px = {cam.height_px}", f"fx_px = {float(k[0, 0])!r}", f"fy_px = {float(k[1, 1])!r}", f"cx_px = {float(k[0, 2])!r}", f"cy_px = {float(k[1, 2])!r}"]
        if cam.distortion.size:
            lines.append("distortion = [" + ", ".join(repr(float(v)) for v in cam.distortion) + "]")
        if opencv:
            r = cam.rotation.T  # world-to-camera
            rvec = cv2.Rodrigues(r)[0].ravel()
            tvec = -r @ cam.position
            lines += ["rvec = [" + ", ".join(repr(float(v)) for v in rvec) + "]", "tvec = [" + ", ".join(repr(float(v)) for v in tvec) + "]"]
        else:
            rot = np.degrees(cv2.Rodrigues(cam.rotation)[0].ravel())
            lines += ["position = [" + ", ".join(repr(float(v)) for v in cam.position) + "]", "rotation_deg = [" + ", ".join(repr(float(v)) for v in rot) + "]"]
        lines.append("")
    return "\n".join(lines)


def turned_view(image, cam, *, focal_px):
    """What ``cam`` sees from the centre of a rectified view ``image`` taken with orientation I, focal length
    ``focal_px`` and its principal point at the image centre: the rectified view read (cubic spline) where each of
    the camera's pixels' rays (its turn and lens distortion undone) meets it; exact for any depth (a pure turn)."""
    from scipy import ndimage

    h, w = image.shape
    xy = cam.rays()
    ray = np.einsum("ij,hwj->hwi", cam.rotation, np.concatenate([xy, np.ones(xy.shape[:2] + (1,))], axis=-1))
    col = (w - 1) / 2 + focal_px * ray[..., 0] / ray[..., 2]
    row = (h - 1) / 2 + focal_px * ray[..., 1] / ray[..., 2]
    return ndimage.map_coordinates(np.asarray(image, np.float32), [row, col], order=3, mode="nearest").astype(np.float32)
