"""A calibrated row of cameras that is not rectified (test helper, over :mod:`nfdepth.synthetic`'s plane).

Each camera has its own intrinsics, lens distortion, a small turn and an
offset from the line; every pixel's ray (distortion undone by OpenCV) meets
the plane ``Z = z0 + slope * X`` (world axes) at a point whose texture is
evaluated exactly, so no resampling enters the images or the truth.
"""

import cv2
import numpy as np

from nfdepth.rectify import CalibratedCamera, cameras_to_toml
from nfdepth.synthetic import calibrated_plane_row, example_calibrated_cameras

SHAPE = (120, 180)


def rotation_deg(rx, ry, rz):
    return cv2.Rodrigues(np.radians([rx, ry, rz]).reshape(3, 1))[0]


def camera(fx, cx, cy, position, turn_deg=(0.0, 0.0, 0.0), distortion=(), fy=None, shape=SHAPE):
    k = np.array([[fx, 0.0, cx], [0.0, fx if fy is None else fy, cy], [0.0, 0.0, 1.0]])
    return CalibratedCamera(matrix=k, width_px=shape[1], height_px=shape[0], position=np.asarray(position, float), rotation=rotation_deg(*turn_deg), distortion=np.asarray(distortion, float))


def default_row(baseline=0.1, off_line=(0.0, 0.0, 0.0)):
    """Three cameras about ``baseline`` apart along world X, the middle one the reference
    (:func:`nfdepth.synthetic.example_calibrated_cameras`, the last one moved by ``off_line``)."""
    cams = example_calibrated_cameras()
    return [
        CalibratedCamera(
            matrix=c.matrix,
            width_px=c.width_px,
            height_px=c.height_px,
            position=c.position * (baseline / 0.1) + (np.asarray(off_line, float) if k == 2 else 0.0),
            rotation=c.rotation,
            distortion=c.distortion,
        )
        for k, c in enumerate(cams)
    ]


def render(cameras, *, z0=6.0, slope=0.15, noise=1.0, seed=4):
    """The views and, per camera, its true depth (along its own optical axis) at every pixel (:func:`nfdepth.synthetic.calibrated_plane_row`)."""
    scene = calibrated_plane_row(cameras, depth=z0, slope=slope, noise_std=noise, seed=seed)
    return scene.views, scene.depths


def cameras_toml(cameras, *, opencv=False) -> str:
    """A cameras file for ``nfdepth stereo --cameras``: :func:`nfdepth.rectify.cameras_to_toml`, or with the pose as OpenCV's rvec and tvec."""
    if not opencv:
        return cameras_to_toml(cameras)
    lines = []
    for cam in cameras:
        k = cam.matrix
        lines += ["[[camera]]", f"width_px = {cam.width_px}", f"height_px = {cam.height_px}", f"fx_px = {float(k[0, 0])!r}", f"fy_px = {float(k[1, 1])!r}", f"cx_px = {float(k[0, 2])!r}", f"cy_px = {float(k[1, 2])!r}"]
        if cam.distortion.size:
            lines.append("distortion = [" + ", ".join(repr(float(v)) for v in cam.distortion) + "]")
        r = cam.rotation.T  # world-to-camera
        rvec = cv2.Rodrigues(r)[0].ravel()
        tvec = -r @ cam.position
        lines += ["rvec = [" + ", ".join(repr(float(v)) for v in rvec) + "]", "tvec = [" + ", ".join(repr(float(v)) for v in tvec) + "]", ""]
    return "\n".join(lines)


def turned_view(image, cam, *, focal_px):
    """What ``cam`` sees from the centre of a rectified view ``image`` taken with orientation I, focal length
    ``focal_px`` and its principal point at the image centre: the rectified view read (cubic spline) where each of
    the camera's pixels' rays (its turn and lens distortion undone) meets it; exact for any depth (a pure turn)."""
    from scipy import ndimage

    from nfdepth._derotation import turn_rays

    h, w = image.shape
    xy = cam.rays()
    rx, ry, rz = turn_rays(cam.rotation, xy[..., 0], xy[..., 1])
    col = (w - 1) / 2 + focal_px * rx / rz
    row = (h - 1) / 2 + focal_px * ry / rz
    return ndimage.map_coordinates(np.asarray(image, np.float32), [row, col], order=3, mode="nearest").astype(np.float32)
