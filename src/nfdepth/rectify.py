"""Static stereo from a calibrated row of cameras that is not rectified.

:func:`nfdepth.stereo.static_stereo` takes views of one camera orientation
spaced along its X axis (paper section 2.3: static stereo is a camera
translating along X). A real row of cameras is never built that exactly:
each camera has its own intrinsics and lens distortion, turns a little
against the others, and sits a little off the line through the rest.
Given each camera's calibration, :func:`rectify_row` resamples every view
to one common pinhole camera (no distortion) with one common orientation
``R_rect`` whose X axis is the line through the camera centres (a least
squares fit; its Y axis for a column, a line nearer the reference camera's
Y axis) and whose optical axis is the cameras' mean one made
perpendicular to it (the way a stereo pair is rectified, Fusiello et al.
2000, for any number of views). Each view's position along that line is its
position for static stereo. :func:`calibrated_row_depth` runs static stereo
on the rectified row and reads the depth back into the reference camera's
own pixels (nearest pixel, so no depth is averaged across a step), converted
from depth along the rectified optical axis to depth along the reference
camera's.

Conventions (as the poses CSV of ``docs/rig-format.md``): a camera's
``rotation`` is camera-to-world (a camera-frame vector ``v`` is ``R v`` in
the world), its ``position`` the optical centre in world coordinates, in
scene units; camera axes X right, Y down, Z forward. OpenCV's extrinsics
(``X_cam = R X_world + t``) convert with :meth:`CalibratedCamera.from_opencv`.
Distortion coefficients are OpenCV's ``(k1, k2, p1, p2[, k3[, k4, k5, k6]])``.

What the rectification cannot remove: a camera centre off the fitted line
shifts its rectified view across the row by ``f e / Z`` px (``e`` its
distance from the line), which depends on depth; :func:`rectify_row` warns
when ``e`` exceeds :data:`MAX_OFF_LINE` of the smallest spacing of
neighbouring views (then a disparity of ``d`` px per step comes with a
vertical misalignment of up to ``MAX_OFF_LINE d``).
"""

from __future__ import annotations

import copy
import math
import re
import warnings
from collections.abc import Iterable
from dataclasses import dataclass, field
from types import SimpleNamespace

import cv2
import numpy as np

from ._derotation import derotate, grid_rays, turn_rays
from ._validate import (
    as_image,
    as_vector3,
    check_frame_size,
    check_image_size,
    check_positive_or_inf,
    check_view_index,
)

__all__ = [
    "MAX_OFF_LINE",
    "MIN_SIDEWAYS_DEG",
    "CalibratedCamera",
    "CalibratedRowDepth",
    "RectifiedRow",
    "calibrated_grid_depth",
    "calibrated_row_depth",
    "cameras_from_dict",
    "cameras_to_toml",
    "load_cameras",
    "rectify_row",
]

#: A camera centre further than this share of the smallest neighbour spacing off the fitted line warns.
MAX_OFF_LINE = 0.01
#: A row closer than this to the cameras' mean optical axis cannot be rectified into a row of views.
MIN_SIDEWAYS_DEG = 30.0
_FILE_DISTORTION_SIZES = (4, 5, 8)  # a cameras file's distortion: left out for none
_DISTORTION_SIZES = (0, *_FILE_DISTORTION_SIZES)


def _as_matrix(name: str, value, shape) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.shape != shape:
        msg = f"{name} must have shape {shape}, got {a.shape}"
        raise ValueError(msg)
    if not np.all(np.isfinite(a)):
        msg = f"{name} must be finite, got {a.tolist()}"
        raise ValueError(msg)
    return a


@dataclass(frozen=True, eq=False)
class CalibratedCamera:
    """One calibrated camera of a row.

    Parameters
    ----------
    matrix : array_like, (3, 3)
        Intrinsic matrix ``[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`` in pixels
        (``fx, fy > 0``; pixel centres at integers; no skew: OpenCV's lens
        model, which undoes the distortion, has none).
    width_px, height_px : int
        Image size.
    position : array_like, (3,)
        Optical centre in world coordinates, scene units.
    rotation : array_like, (3, 3)
        Camera-to-world rotation (a proper rotation matrix, to 1e-6).
    distortion : array_like or None, optional
        OpenCV's coefficients: 4, 5 or 8 of ``k1, k2, p1, p2, k3, k4, k5, k6``
        (default, empty or None: none).
    """

    matrix: np.ndarray
    width_px: int
    height_px: int
    position: np.ndarray
    rotation: np.ndarray
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        k = _as_matrix("matrix", self.matrix, (3, 3))
        if not (k[0, 0] > 0 and k[1, 1] > 0) or k[1, 0] != 0 or np.any(k[2] != (0.0, 0.0, 1.0)):
            msg = f"matrix must be an intrinsic matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0 px, got {k.tolist()}"
            raise ValueError(msg)
        if k[0, 1] != 0:  # OpenCV's undistortPoints and initUndistortRectifyMap read fx, fy, cx, cy alone
            msg = (
                f"matrix has a skewed pixel grid (matrix[0, 1] = {k[0, 1]:g}): expected 0 (OpenCV's lens model, which undoes the "
                "distortion and rectifies the views, has no skew term: every ray would be off)"
            )
            raise ValueError(msg)
        check_image_size(self)
        r = _as_matrix("rotation", self.rotation, (3, 3))
        if not np.allclose(r.T @ r, np.eye(3), atol=1e-6) or not np.linalg.det(r) > 0:
            msg = f"rotation must be a rotation matrix (orthonormal, determinant +1), got {r.tolist()}"
            raise ValueError(msg)
        dist = np.zeros(0) if self.distortion is None else np.asarray(self.distortion, dtype=np.float64).ravel()  # None: none, as in OpenCV
        if dist.size not in _DISTORTION_SIZES or not np.all(np.isfinite(dist)):
            msg = f"distortion must be 4, 5 or 8 finite OpenCV coefficients (k1, k2, p1, p2[, k3[, k4, k5, k6]]) or none, got {dist.tolist()}"
            raise ValueError(msg)
        object.__setattr__(self, "matrix", k)
        object.__setattr__(self, "rotation", r)
        object.__setattr__(self, "position", as_vector3("position", self.position))
        object.__setattr__(self, "distortion", dist)

    def __eq__(self, other) -> bool:
        if not isinstance(other, CalibratedCamera):
            return NotImplemented
        return (self.width_px, self.height_px) == (other.width_px, other.height_px) and all(
            np.array_equal(getattr(self, k), getattr(other, k)) for k in ("matrix", "position", "rotation", "distortion")
        )

    __hash__ = None  # mutable-looking arrays: no hashing

    @classmethod
    def from_opencv(cls, matrix, distortion, rvec_or_rotation, tvec, size) -> CalibratedCamera:
        """From OpenCV's calibration: ``X_cam = R X_world + t`` (``R`` as a 3 x 3 matrix or a Rodrigues vector), ``size = (width, height)``; ``distortion`` None for none."""
        r = np.asarray(rvec_or_rotation, dtype=np.float64)
        r = cv2.Rodrigues(r.reshape(3, 1))[0] if r.size == 3 else _as_matrix("rotation", r, (3, 3))
        t = as_vector3("tvec", np.asarray(tvec, dtype=np.float64).ravel())
        w, h = size
        return cls(matrix=matrix, width_px=w, height_px=h, position=-r.T @ t, rotation=r.T, distortion=distortion)

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape ``(rows, cols)``."""
        return (int(self.height_px), int(self.width_px))

    def rays(self) -> np.ndarray:
        """Every pixel's ray ``(x, y, 1)`` in camera axes, lens distortion undone: ``(H, W, 2)`` of ``(x, y)``.

        NaN where undoing the distortion does not converge (the pixel's ray,
        distorted again, lands more than 0.01 px away: beyond the range where
        the distortion model can be inverted, e.g. the far corners of a
        strong barrel distortion). Computed once per camera (read-only).
        """
        cached = self.__dict__.get("_rays")
        if cached is not None:
            return cached
        h, w = self.shape
        rows, cols = np.mgrid[0:h, 0:w].astype(np.float64)
        pts = np.stack([cols.ravel(), rows.ravel()], axis=-1)[:, None, :]
        if not self.distortion.size:
            xy = cv2.undistortPoints(pts, self.matrix, self.distortion).reshape(h, w, 2)
        else:
            # to 1e-10 (OpenCV's default stops after 5 iterations; 20 reach it for common lenses, the check below catches the rest)
            criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 20, 1e-10)
            if hasattr(cv2, "undistortPointsIter"):  # OpenCV 4
                xy = cv2.undistortPointsIter(pts, self.matrix, self.distortion, None, None, criteria)
            else:
                xy = cv2.undistortPoints(pts, self.matrix, self.distortion, criteria=criteria)
            xy = xy.reshape(-1, 2)
            back = cv2.projectPoints(np.concatenate([xy, np.ones((xy.shape[0], 1))], axis=1), np.zeros(3), np.zeros(3), self.matrix, self.distortion)[0]
            lost = ~(np.abs(back.reshape(-1, 2) - pts.reshape(-1, 2)).max(axis=1) <= 0.01)
            xy[lost] = np.nan
            xy = xy.reshape(h, w, 2)
        xy.setflags(write=False)
        object.__setattr__(self, "_rays", xy)  # a camera is immutable: computed once
        return xy


@dataclass(frozen=True)
class RectifiedRow:
    """A row of views resampled to one camera and orientation (:func:`rectify_row`).

    ``views``: the rectified views (float32, the reference's size), in their
    order along the row (increasing ``positions``); ``axis``: ``"x"`` for a
    row, ``"y"`` for a column (the centres' line nearer the reference
    camera's Y axis: the line is then the rectified Y axis); ``positions``:
    each view's position along the line relative to the reference, scene
    units; ``reference``: the reference's index among them; ``order``: the
    given index of each; ``inside``: where each view sees its own image;
    ``focal_px``, ``cx_px``, ``cy_px``: the common camera; ``rotation``:
    ``R_rect`` (rectified-to-world); ``off_line``: each camera centre's
    distance from the fitted line, scene units; ``camera``: the reference
    camera as given.
    """

    views: list
    positions: np.ndarray
    reference: int
    order: list
    inside: list
    focal_px: float
    cx_px: float
    cy_px: float
    rotation: np.ndarray
    off_line: np.ndarray
    camera: CalibratedCamera
    axis: str = "x"

    def _turned_rays(self) -> np.ndarray:
        """The reference camera's pixel rays ``(x, y, 1)`` in the rectified axes, shape (3, H, W)."""
        rays = self.camera.rays()
        return turn_rays(self.rotation.T @ self.camera.rotation, rays[..., 0], rays[..., 1])

    def disparity_range(self, depth_range) -> tuple[float, float]:
        """The search range (px per scene unit of position) of the depths ``(near, far)`` along the reference camera's axis.

        A point at depth ``Z`` along the reference's axis lies at ``Z`` times
        its ray's rectified ``z`` along the rectified axis; the range covers
        that factor's extremes over the reference's image (within a few per
        cent of 1 for cameras turned a few degrees). ``far`` may be inf.
        """
        from ._validate import check_depth_range

        near, far = check_depth_range("depth_range", depth_range)
        z = self._turned_rays()[2]
        z = z[np.isfinite(z) & (z > 0)]
        lo_z, hi_z = (float(np.min(z)), float(np.max(z))) if z.size else (1.0, 1.0)
        return self.focal_px / (far * hi_z), self.focal_px / (near * lo_z)

    def to_reference(self, depth, *, std=None):
        """Depth along the rectified optical axis (the rectified reference's pixels) -> depth along the reference camera's, in its own pixels.

        Nearest pixel (no depth averaged across a step); NaN where the
        reference's pixel falls outside the rectified canvas. ``std``, the
        depth's standard deviation, is scaled alike. Returns ``depth`` or
        ``(depth, std)``.
        """
        turned = self._turned_rays()
        h, w = np.asarray(depth).shape
        with np.errstate(divide="ignore", invalid="ignore"):
            col = np.rint(self.cx_px + self.focal_px * turned[0] / turned[2])
            row = np.rint(self.cy_px + self.focal_px * turned[1] / turned[2])
        ok = (turned[2] > 0) & (col >= 0) & (col <= w - 1) & (row >= 0) & (row <= h - 1)
        r = np.where(ok, row, 0).astype(np.intp)
        c = np.where(ok, col, 0).astype(np.intp)
        # the point at depth Z_rect on the reference pixel's ray (x, y, 1): its rectified z is turned[2] per unit of the ray
        scale = np.where(ok, 1.0 / np.where(ok, turned[2], 1.0), np.nan)
        out = np.asarray(depth, dtype=np.float64)[r, c] * scale
        if std is None:
            return out.astype(np.float32)
        return out.astype(np.float32), (np.asarray(std, dtype=np.float64)[r, c] * scale).astype(np.float32)


def _centre_line(centres: np.ndarray) -> np.ndarray:
    """The unit direction (either sign) of the least-squares line through the camera ``centres`` (N, 3)."""
    return np.linalg.svd(centres - centres.mean(axis=0))[2][0]


def _row_line(centres: np.ndarray, reference_rotation: np.ndarray) -> tuple[np.ndarray, str]:
    """The direction of the least-squares line through ``centres`` and the reference camera's axis nearest it ("x" or "y"), the direction pointing along that axis."""
    line = _centre_line(centres)
    along = reference_rotation[:, :2].T @ line  # components along the reference's X and Y
    k = int(np.argmax(np.abs(along)))
    return (line if along[k] >= 0 else -line), "xy"[k]


def _camera_list(name: str, cameras) -> list:
    """``cameras`` as a list; TypeError naming ``name`` where it is no sequence (a single camera, None)."""
    if isinstance(cameras, CalibratedCamera) or not isinstance(cameras, Iterable) or isinstance(cameras, (str, bytes)):
        msg = f"{name} must be a sequence of CalibratedCamera, one per view, got {type(cameras).__name__}"
        raise TypeError(msg)
    return list(cameras)


def _as_views(name: str, views) -> list:
    """``views`` as float32 grey images, each checked as static stereo checks its views (real, finite, 2-D), named by its given index.

    Their sizes may differ (each is its own camera's). Checked before any
    resampling: a cubic spline spreads one NaN pixel over a whole view, and
    a complex view would lose its imaginary part with a mere ComplexWarning.
    """
    if isinstance(views, np.ndarray):
        if views.ndim != 3:
            msg = f"{name} must be a sequence of 2-D images or an array of shape (N, rows, cols), got shape {views.shape}"
            raise ValueError(msg)
    elif isinstance(views, (str, bytes)) or not isinstance(views, Iterable):
        msg = f"{name} must be a sequence of 2-D arrays, one per camera, got {type(views).__name__}"
        raise TypeError(msg)
    out = []
    for k, view in enumerate(views):
        check_frame_size(f"{name}[{k}]", np.shape(view))
        out.append(as_image(f"{name}[{k}]", view, np.float32))
    return out


def rectify_row(views, cameras, *, reference: int) -> RectifiedRow:
    """Resample a calibrated row of views to one camera and orientation, spaced along its X axis.

    Parameters
    ----------
    views : sequence of 2-D arrays
        Grey images, each of its camera's size.
    cameras : sequence of CalibratedCamera
        One per view, in the same order.
    reference : int
        The view whose camera sets the common focal length (its ``fx``),
        image size and the part of the scene kept; the depth is read back
        into its pixels.

    Returns
    -------
    RectifiedRow
        Views sorted along the row (the first at the most negative position
        along the reference camera's X axis; for a column, whose centres'
        line runs nearer the reference's Y axis, along its Y axis).

    Raises
    ------
    TypeError
        ``views`` or ``cameras`` not a sequence, a view that is not real
        numbers, a camera that is not a :class:`CalibratedCamera`, a
        ``reference`` that is not an int.
    ValueError
        A view that is not a finite grey image, checked before any
        resampling and named by its given index (``views[k]``); a count,
        size or index that does not fit; two camera centres at the same
        place; a row within :data:`MIN_SIDEWAYS_DEG` of the cameras' mean
        optical axis (moving toward the scene: no row of views).

    Warns
    -----
    UserWarning
        A camera centre off the fitted line by more than :data:`MAX_OFF_LINE`
        of the smallest neighbour spacing.
    """
    cameras = _camera_list("cameras", cameras)
    views = _as_views("views", views)
    n = len(views)
    if n < 2 or len(cameras) != n:
        msg = f"rectify_row needs at least 2 views and one camera per view, got {n} views and {len(cameras)} cameras"
        raise ValueError(msg)
    reference = check_view_index("reference", reference, n)
    for k, (v, cam) in enumerate(zip(views, cameras)):
        if not isinstance(cam, CalibratedCamera):
            msg = f"cameras[{k}] must be a CalibratedCamera, got {type(cam).__name__}"
            raise TypeError(msg)
        shape = np.shape(v)
        if shape != cam.shape:
            msg = f"views[{k}] is {shape[1] if len(shape) > 1 else '?'}x{shape[0] if shape else '?'} px (shape {shape}), its camera {cam.width_px}x{cam.height_px}: expected a grey image of its camera's size"
            raise ValueError(msg)
    centres = np.stack([c.position for c in cameras])
    ref_cam = cameras[reference]
    spacings = [np.linalg.norm(centres[i] - centres[j]) for i in range(n) for j in range(i + 1, n)]
    if min(spacings) <= 1e-12 * max(max(spacings), 1e-300):
        msg = "two cameras of the row are at the same place: static stereo needs every view at its own position along the row"
        raise ValueError(msg)
    line, axis = _row_line(centres, ref_cam.rotation)
    forward = np.mean([c.rotation[:, 2] for c in cameras], axis=0)
    forward = forward / np.linalg.norm(forward)
    sideways = math.degrees(math.acos(min(1.0, abs(float(line @ forward)))))
    if sideways < MIN_SIDEWAYS_DEG:
        msg = (
            f"the row of camera centres runs {sideways:.1f} degrees from the cameras' mean optical axis: expected at least "
            f"{MIN_SIDEWAYS_DEG:g} (a row across the view; cameras one behind the other give no row of views)"
        )
        raise ValueError(msg)
    z_axis = forward - (forward @ line) * line
    z_axis /= np.linalg.norm(z_axis)
    # the line is the rectified X axis of a row, the Y axis of a column (a right-handed frame either way)
    x_axis, y_axis = (line, np.cross(z_axis, line)) if axis == "x" else (np.cross(line, z_axis), line)
    rect = np.stack([x_axis, y_axis, z_axis], axis=1)  # rectified-to-world
    positions = (centres - centres[reference]) @ line
    across = centres - centres.mean(axis=0)
    off_line = np.linalg.norm(across - np.outer(across @ line, line), axis=1)
    order = [int(k) for k in np.argsort(positions, kind="stable")]
    steps = np.diff(positions[order])
    if np.any(steps <= 1e-12 * np.ptp(positions)):
        msg = "two cameras of the row are at the same position along it: static stereo needs every view at its own position"
        raise ValueError(msg)
    if np.max(off_line) > MAX_OFF_LINE * np.min(steps):
        worst = int(np.argmax(off_line))
        line_name = "row" if axis == "x" else "column"  # (a line of cameras nearer the image's y axis is a column)
        warnings.warn(
            f"camera {worst} is {off_line[worst]:.3g} scene units off the line through the {line_name}, {off_line[worst] / np.min(steps):.1%} of the "
            f"smallest spacing of neighbouring views (at most {MAX_OFF_LINE:.0%} expected): its rectified view is misaligned across the {line_name} by "
            "that share of the disparity, which static stereo does not model",
            UserWarning,
            stacklevel=2,
        )
    # the common camera: the reference's focal length and size, the principal point where the reference's own lands
    f = float(ref_cam.matrix[0, 0])
    h, w = ref_cam.shape
    centre_ray = rect.T @ ref_cam.rotation @ np.linalg.solve(ref_cam.matrix, [ref_cam.matrix[0, 2], ref_cam.matrix[1, 2], 1.0])
    cx = float(ref_cam.matrix[0, 2] - f * centre_ray[0] / centre_ray[2])
    cy = float(ref_cam.matrix[1, 2] - f * centre_ray[1] / centre_ray[2])
    new_matrix = np.array([[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]])
    rect_views, inside = [], []
    for k in order:
        cam = cameras[k]
        same_camera = cam.shape == (h, w) and np.array_equal(cam.matrix, new_matrix) and not np.any(cam.distortion)
        if same_camera and np.allclose(cam.rotation, rect, rtol=0.0, atol=1e-12):
            rect_views.append(views[k].copy())  # rectified as taken: no resampling
            inside.append(np.ones((h, w), bool))
            continue
        # OpenCV's R turns the camera's axes into the rectified ones: R_rect^T R_k
        map_x, map_y = cv2.initUndistortRectifyMap(cam.matrix, cam.distortion, rect.T @ cam.rotation, new_matrix, (w, h), cv2.CV_32FC1)
        ch, cw = cam.shape
        ahead = _ahead(cam, rect, new_matrix, (h, w))
        tol = 1e-3  # px: float32 maps of a pixel on the border
        seen = ahead & (map_x >= -tol) & (map_x <= cw - 1 + tol) & (map_y >= -tol) & (map_y <= ch - 1 + tol)
        rect_views.append(derotate(views[k], (np.clip(map_x, -1, cw), np.clip(map_y, -1, ch), seen)))
        inside.append(seen)
    return RectifiedRow(
        views=rect_views,
        positions=positions[order],
        reference=order.index(reference),
        order=order,
        inside=inside,
        focal_px=f,
        cx_px=cx,
        cy_px=cy,
        rotation=rect,
        off_line=off_line,
        camera=ref_cam,
        axis=axis,
    )


def _ahead(cam: CalibratedCamera, rect, new_matrix, shape) -> np.ndarray:
    """Where the rectified canvas's rays lie in front of ``cam`` (OpenCV's maps do not say)."""
    h, w = shape
    x = (np.arange(w, dtype=np.float64) - new_matrix[0, 2]) / new_matrix[0, 0]
    y = (np.arange(h, dtype=np.float64) - new_matrix[1, 2]) / new_matrix[1, 1]
    return grid_rays(cam.rotation.T @ rect, x, y)[2] > 0


@dataclass(frozen=True)
class CalibratedRowDepth:
    """Depth of a calibrated row (:func:`calibrated_row_depth`).

    ``depth``, ``depth_std``: along the reference camera's optical axis, in
    its own pixels, scene units, NaN where unknown; ``edge_mask``: the
    rectified reference's edge points read back the same way;
    ``disparity``: the rectified reference's disparity behind ``depth``
    (px per scene unit of position, in the rectified reference's pixels;
    NaN where static stereo has no value or the match is seen by no other
    view; not bounded by ``depth_range``: a disparity whose depth lies
    beyond it stays, and ``depth`` and :meth:`filled` drop that depth,
    the fill taking it as a measurement, not a hole); ``row``: the
    :class:`RectifiedRow`; ``result``: static stereo's
    :class:`nfdepth.stereo.StereoResult` on it (as ``disparity``, before
    the test of the other views); ``depth_range``: the ``(near, far)`` that
    bounds ``depth`` and its fill, or None.
    """

    depth: np.ndarray
    depth_std: np.ndarray
    edge_mask: np.ndarray
    disparity: np.ndarray
    row: RectifiedRow
    result: object
    depth_range: tuple | None = None

    def filled(self) -> tuple[np.ndarray, np.ndarray]:
        """The depth with its holes filled from the background, and where it was filled.

        :func:`nfdepth.stereo.fill_background` on ``disparity``, along the
        rectified row (the baseline, where occluded strips lie), read back
        into the reference's pixels as ``depth`` is. The filled values are no
        measurements: ``depth_std`` has none there, and the returned mask
        marks them. Returns float32 depth (NaN where the rectified line has
        no value at all or the reference's pixel lies off the rectified
        canvas, or beyond ``depth_range``) and the bool mask of filled pixels.
        """
        from .stereo import _beyond_depths, fill_background

        d, _ = fill_background(self.disparity, axis=self.row.axis)
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(d > 0, self.row.focal_px / d.astype(np.float64), np.nan)
        depth = self.row.to_reference(z)
        if self.depth_range is not None:  # a fill is no excuse to leave the range
            depth[_beyond_depths(depth, self.depth_range)] = np.nan
        measured = np.isfinite(self.depth)
        depth = np.where(measured, self.depth, depth).astype(np.float32)
        return depth, ~measured & np.isfinite(depth)

    def points(self, *, image=None):
        """The depth as 3-D points in the reference camera's axes (lens distortion undone), as :func:`nfdepth.io.depth_to_points`.

        Returns ``(points, colors)``: float32 ``(N, 3)`` in row-major pixel
        order, and uint8 RGB ``(N, 3)`` from ``image`` (grey or RGB of the
        reference's size; float values rounded and clipped to 0..255) or None.
        """
        return _depth_points(self.row.camera, self.depth, image)


def _depth_points(camera: CalibratedCamera, depth, image):
    """``depth`` (the camera's own pixels) as points in its axes along its rays, with colours from ``image``."""
    from .io import point_colors

    xy = camera.rays()
    with np.errstate(invalid="ignore"):
        keep = np.isfinite(depth) & (depth > 0) & np.isfinite(xy).all(axis=-1)
    rows, cols = np.nonzero(keep)
    z = depth[rows, cols].astype(np.float64)
    pts = np.stack([xy[rows, cols, 0] * z, xy[rows, cols, 1] * z, z], axis=1).astype(np.float32)
    return pts, point_colors(image, rows, cols, depth.shape)


#: Where static stereo's words number the views (its warnings of views that move across the row, do not fit
#: their positions or are the same image; ``views[k]`` of an error): "view 2", "views 0 and 2", "views 0, 1 and
#: 3", "reference view 1", "views[2]".
_VIEW_INDICES = re.compile(r"\b(views?\[|views? |reference view )(\d+(?:(?:, | and )\d+)*)(?![.\d])")
#: The fitted positions of the views, listed in their order.
_LISTED_IN_ORDER = re.compile(r"(at about )((?:[^,()]+, )*[^,()]+)(, in the order given)")


def _given_indices(text: str, order) -> str:
    """``text`` of static stereo on a rectified row (views numbered along it) with each view's given index (``order``).

    A list of the views' fitted positions "in the order given" is put in
    the order given too.
    """
    n = len(order)

    def indices(m):
        return m.group(1) + re.sub(r"\d+", lambda k: str(order[int(k.group())]) if int(k.group()) < n else k.group(), m.group(2))

    def listed(m):
        items = m.group(2).split(", ")
        if len(items) != n:
            return m.group()
        return m.group(1) + ", ".join(items[order.index(k)] for k in range(n)) + m.group(3)

    return _LISTED_IN_ORDER.sub(listed, _VIEW_INDICES.sub(indices, text))


def _with_given_indices(message: Warning, order) -> Warning:
    """The warning ``message`` with :func:`_given_indices` applied to its text: a copy of its class and attributes, or itself when its text names no view."""
    text = _given_indices(str(message), order)
    if text == str(message):
        return message
    out = copy.copy(message)
    out.args = (text,)
    return out


def calibrated_row_depth(views, cameras, *, reference: int, depth_range=None, **stereo_options) -> CalibratedRowDepth:
    """Depth in the reference camera's pixels from a calibrated, unrectified row of views.

    :func:`rectify_row`, then :func:`nfdepth.stereo.static_stereo` on the
    rectified row with its positions (scene units: the disparity is px per
    scene unit, depth ``focal_px / d``), then the depth read back
    (:meth:`RectifiedRow.to_reference`). Pixels where the rectified reference
    does not see its own image are NaN, and so are those whose match lies
    outside every other view. ``depth_range``, ``(near, far)`` in scene
    units along the reference camera's axis (``far`` may be inf), is the
    search range instead of the pyramid's (:meth:`RectifiedRow.disparity_range`,
    static stereo's ``disparity_range_px``) and a bound: depths outside it
    are NaN. ``stereo_options`` go to static stereo (not ``positions``,
    ``axis`` or ``reference``).

    Parameters
    ----------
    views : sequence of 2-D arrays
        Grey images, each of its camera's size (at least 2).
    cameras : sequence of CalibratedCamera
        One per view, in the same order.
    reference : int
        Index of the view in whose camera's pixels, and along whose optical
        axis, the depth is given.
    depth_range : (float, float), optional
        ``(near, far)``, ``0 < near < far``, ``near`` finite (see above).
    **stereo_options
        Keyword arguments of :func:`nfdepth.stereo.static_stereo`, except
        ``positions`` and ``axis`` (set from the cameras) and, with
        ``depth_range``, ``disparity_range_px``.

    Returns
    -------
    CalibratedRowDepth
        ``depth`` and ``depth_std`` float32 of the reference camera's size,
        in scene units (those of the cameras' positions).

    Raises
    ------
    TypeError
        ``cameras`` not a sequence of CalibratedCamera; ``reference`` not an
        int; ``positions`` or ``axis`` in ``stereo_options``, or
        ``disparity_range_px`` together with ``depth_range``; a
        ``depth_range`` that is not two numbers.
        Also what static stereo refuses as such.
    ValueError
        What :func:`rectify_row` refuses (a view that is not a finite grey
        image, a count, size or index that does not fit, two camera centres
        at the same place, a row within :data:`MIN_SIDEWAYS_DEG` of the
        cameras' mean optical axis); a ``depth_range`` not ``0 < near <
        far`` or whose ``near`` is too near for a finite disparity; what
        static stereo refuses (with ``depth_range``, the message names it).

    Warns
    -----
    UserWarning
        A camera centre off the fitted line (:func:`rectify_row`); most
        measured depths beyond ``depth_range``; static stereo's own warnings,
        of their class, whose views are numbered as given (static stereo
        runs on them sorted along the row).
    """
    from ._validate import check_depth_range
    from .stereo import (
        _beyond_depths,
        _checked_depth_disparities,
        _warn_if_mostly_beyond,
        static_stereo,
    )

    clash = sorted(set(stereo_options) & {"positions", "axis"})
    if clash:
        msg = f"calibrated_row_depth sets {', '.join(clash)} from the cameras: do not pass {' or '.join(clash)}"
        raise TypeError(msg)
    if depth_range is not None:
        if "disparity_range_px" in stereo_options:
            msg = "give depth_range or disparity_range_px, not both (depth_range sets the disparities to search)"
            raise TypeError(msg)
        depth_range = check_depth_range("depth_range", depth_range)
    row = rectify_row(views, cameras, reference=reference)
    if depth_range is not None:
        with np.errstate(over="ignore", divide="ignore"):
            searched = _checked_depth_disparities("depth_range", depth_range, row.disparity_range(depth_range))
        stereo_options["disparity_range_px"] = searched
    # static stereo numbers the views along the rectified row: its words are said again with the indices given
    error = None
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = static_stereo(row.views, reference=row.reference, positions=row.positions, axis=row.axis, **stereo_options)
    except (TypeError, ValueError) as exc:
        error = exc
    for said in caught:
        warnings.warn(_with_given_indices(said.message, row.order), stacklevel=2)  # (the warning itself, its class and attributes kept)
    if error is not None:
        text = _given_indices(str(error), row.order)
        if isinstance(error, ValueError) and depth_range is not None:
            msg = f"depth_range ({depth_range[0]:g}, {depth_range[1]:g}) (disparities {searched[0]:.4g}..{searched[1]:.4g} px per scene unit): {text}; widen or move the depth range"
            raise ValueError(msg) from None
        if text == str(error) or type(error) not in (TypeError, ValueError):
            raise error
        raise type(error)(text) from error
    d = np.asarray(res.disparity, dtype=np.float64)
    h, w = d.shape
    rows, cols = np.mgrid[0:h, 0:w]
    seen_elsewhere = np.zeros((h, w), bool)
    for k, (t, inside) in enumerate(zip(row.positions, row.inside)):
        if k == row.reference:
            continue
        # where the point lies in view k: shifted by t d along the line, toward -col (-row for a column)
        along, size = (cols, w) if row.axis == "x" else (rows, h)
        with np.errstate(invalid="ignore"):
            moved = np.rint(along - t * d)
        ok = np.isfinite(moved) & (moved >= 0) & (moved <= size - 1)
        moved = np.where(ok, moved, 0).astype(np.intp)
        seen_elsewhere |= ok & (inside[rows, moved] if row.axis == "x" else inside[moved, cols])
    usable = np.isfinite(d) & (d > 0) & row.inside[row.reference] & seen_elsewhere
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(usable, row.focal_px / d, np.nan)
        z_std = np.where(usable, row.focal_px * np.asarray(res.uncertainty, dtype=np.float64) / d**2, np.nan)
    depth, depth_std = row.to_reference(z, std=z_std)
    if depth_range is not None:  # the search covers the range along every ray: a bound on the depths themselves
        beyond = _beyond_depths(depth, depth_range)
        depth[beyond] = np.nan
        depth_std[beyond] = np.nan
        _warn_if_mostly_beyond(int(np.count_nonzero(beyond)), int(np.count_nonzero(np.isfinite(depth))), f"depth_range ({depth_range[0]:g}, {depth_range[1]:g})")
    edges = row.to_reference(np.where(res.edge_mask & usable, 1.0, np.nan))
    return CalibratedRowDepth(
        depth=depth,
        depth_std=depth_std,
        edge_mask=np.isfinite(edges) & np.isfinite(depth),
        disparity=np.where(usable, d, np.nan).astype(np.float32),
        row=row,
        result=res,
        depth_range=depth_range,
    )


# ----------------------------------------------------------------- files

_CAMERA_KEYS = ("width_px", "height_px", "focal_px", "fx_px", "fy_px", "cx_px", "cy_px", "distortion", "position", "rotation_deg", "rvec", "tvec")


def _parse_camera(table, key: str) -> CalibratedCamera:
    from .rig import (
        RigError,
        _check_keys,
        _exclusive,
        _fail,
        _integer,
        _is_number,
        _number,
        _vector,
    )

    t = _check_keys(table, key, _CAMERA_KEYS)
    width = _integer(t, key, "width_px")
    height = _integer(t, key, "height_px")
    if _exclusive(t, key, ("focal_px", "fx_px"), required=True) == "focal_px":
        if "fy_px" in t:
            raise RigError(f"{key}: focal_px and fy_px contradict each other: give focal_px, or fx_px and fy_px")
        fx = fy = _number(t, key, "focal_px", positive=True)
    else:
        fx = _number(t, key, "fx_px", positive=True)
        fy = _number(t, key, "fy_px", positive=True)
    cx = _number(t, key, "cx_px", required=False, default=(width - 1) / 2.0)
    cy = _number(t, key, "cy_px", required=False, default=(height - 1) / 2.0)
    dist = t.get("distortion", [])  # left out: none; given: 4, 5 or 8 (an empty list is a slip, as in a rig file)
    if "distortion" in t and (not isinstance(dist, list) or len(dist) not in _FILE_DISTORTION_SIZES or not all(_is_number(v) and math.isfinite(v) for v in dist)):
        raise _fail(f"{key}.distortion", dist, "4, 5 or 8 finite numbers, OpenCV's [k1, k2, p1, p2, k3, k4, k5, k6]")
    matrix = [[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]
    if "rvec" in t or "tvec" in t:
        for name in ("position", "rotation_deg"):
            if name in t:
                raise RigError(f"{key}: {name} and rvec/tvec contradict each other: give position and rotation_deg, or OpenCV's rvec and tvec")
        rvec = _vector(t, key, "rvec", required=True)
        tvec = _vector(t, key, "tvec", required=True)
        return CalibratedCamera.from_opencv(matrix, dist, rvec, tvec, (width, height))
    position = _vector(t, key, "position", required=True)
    rot = _vector(t, key, "rotation_deg", default=np.zeros(3))
    if not np.linalg.norm(rot) <= 1e6:
        raise _fail(f"{key}.rotation_deg", t["rotation_deg"], "a rotation vector of at most 1e6 degrees (give it modulo 360)")
    rotation = cv2.Rodrigues(np.radians(rot).reshape(3, 1))[0]
    return CalibratedCamera(matrix=np.array(matrix), width_px=width, height_px=height, position=position, rotation=rotation, distortion=np.array(dist, float))


def cameras_from_dict(data: dict) -> list:
    """The cameras of a parsed cameras file (a dict with a ``camera`` array of tables), in order.

    Each table: ``width_px``, ``height_px``; ``focal_px`` or ``fx_px`` and
    ``fy_px``; ``cx_px``, ``cy_px`` (default the image centre);
    ``distortion`` (4, 5 or 8 of OpenCV's coefficients; left out: none); the pose as
    ``position`` (optical centre, world, scene units) and ``rotation_deg``
    (camera-to-world rotation vector, degrees; default none), or as OpenCV's
    ``rvec`` (radians) and ``tvec`` (``X_cam = R X_world + t``).

    Parameters
    ----------
    data : dict
        A parsed TOML document (``tomllib.loads``) whose only key is
        ``camera``: a non-empty list of tables, one per view.

    Returns
    -------
    list of CalibratedCamera
        One per table, in order.

    Raises
    ------
    nfdepth.rig.RigError
        With the key path, the value and what was expected: ``data`` not a
        dict, an unknown key, no ``camera`` list, a missing, wrong or
        contradictory key of a table (``focal_px`` with ``fy_px``,
        ``position`` or ``rotation_deg`` with ``rvec`` / ``tvec``), or a
        camera :class:`CalibratedCamera` refuses.
    """
    from .rig import RigError, _check_keys

    if not isinstance(data, dict):
        raise RigError(f"cameras: expected a table with a [[camera]] array, got {type(data).__name__}")
    _check_keys(data, "cameras", ("camera",))
    tables = data.get("camera")
    if isinstance(tables, dict):  # [camera] written for [[camera]]
        raise RigError("camera is a single [camera] table: expected one [[camera]] table (double brackets) per view, in the order of the views")
    if tables is not None and not isinstance(tables, list):
        raise RigError(f"camera = {tables!r}: expected one [[camera]] table per view, in the order of the views")
    if not tables:
        raise RigError("camera is missing: expected one [[camera]] table per view, in the order of the views")
    cameras = []
    for k, table in enumerate(tables):
        try:
            cameras.append(_parse_camera(table, f"camera[{k}]"))
        except ValueError as exc:
            if isinstance(exc, RigError):
                raise
            raise RigError(f"camera[{k}]: {exc}") from None
    return cameras


def load_cameras(path) -> list:
    """Read a cameras file (TOML, :func:`cameras_from_dict`; ``docs/rig-format.md``, "Calibrated cameras").

    Parameters
    ----------
    path : str or os.PathLike
        The cameras file, UTF-8 TOML: one ``[[camera]]`` table per view, in
        the order of the views.

    Returns
    -------
    list of CalibratedCamera
        One per ``[[camera]]`` table, in order.

    Raises
    ------
    TypeError
        If ``path`` is not a str or os.PathLike.
    FileNotFoundError
        If the file does not exist (or is a directory).
    nfdepth.io.InputReadError
        If it cannot be read (e.g. no read permission).
    nfdepth.rig.RigError
        For invalid TOML or an invalid camera; the message starts with the file name.
        Also a file that is not UTF-8.
    """
    from .rig import RigError, _read_toml

    path, data = _read_toml(path, "cameras")
    try:
        return cameras_from_dict(data)
    except RigError as exc:
        raise RigError(f"cameras '{path}': {exc}") from None


def cameras_to_toml(cameras) -> str:
    """A cameras file for :func:`load_cameras` (``nfdepth stereo --cameras``): one ``[[camera]]`` per camera, in order.

    Intrinsics as ``fx_px``, ``fy_px``, ``cx_px``, ``cy_px``, the pose as
    ``position`` and ``rotation_deg``; numbers written to round-trip
    (the rotation through its rotation vector, to about 1e-14). From
    OpenCV's calibration: ``cameras_to_toml([CalibratedCamera.from_opencv(K,
    dist, rvec, tvec, (w, h)), ...])``.

    Parameters
    ----------
    cameras : iterable of CalibratedCamera
        The cameras, in the order of their views.

    Returns
    -------
    str
        The TOML text, the tables separated by blank lines, ending in a
        newline.

    Raises
    ------
    TypeError
        An item that is not a :class:`CalibratedCamera`.
    ValueError
        No camera (a file :func:`load_cameras` would refuse).
    """

    def numbers(values) -> str:
        return "[" + ", ".join(repr(float(v) + 0.0) for v in np.ravel(values)) + "]"

    lines = []
    for k, cam in enumerate(cameras):
        if not isinstance(cam, CalibratedCamera):
            msg = f"cameras[{k}] must be a CalibratedCamera, got {type(cam).__name__}"
            raise TypeError(msg)
        m = cam.matrix  # (no skew: a CalibratedCamera refuses it)
        lines += ["[[camera]]", f"width_px = {cam.width_px}", f"height_px = {cam.height_px}"]
        lines += [f"{key} = {float(v)!r}" for key, v in (("fx_px", m[0, 0]), ("fy_px", m[1, 1]), ("cx_px", m[0, 2]), ("cy_px", m[1, 2]))]
        if cam.distortion.size:
            lines.append(f"distortion = {numbers(cam.distortion)}")
        lines.append(f"position = {numbers(cam.position)}")
        lines.append(f"rotation_deg = {numbers(np.degrees(cv2.Rodrigues(cam.rotation)[0]))}")
        lines.append("")
    if not lines:
        msg = "cameras must hold at least one CalibratedCamera, got none (load_cameras refuses a file without a [[camera]] table)"
        raise ValueError(msg)
    return "\n".join(lines)


# ----------------------------------------------------------------- two lines


#: A row and a column of cameras whose lines run closer than this are refused. The column is there to measure the
#: edges parallel to the row, which the row cannot (B = 0): a line at an angle a to the row measures them with the
#: weight sin^2 a of a column at right angles, a quarter at 30 degrees; and at 0 the two are one line (the same
#: cameras given twice, their measurements counted twice: a std sqrt(2) too small). The bound of MIN_SIDEWAYS_DEG.
_MIN_LINES_DEG = 30.0


def _line_direction(cameras) -> np.ndarray | None:
    """The direction of the least-squares line through the cameras' centres, or None where there is none (fewer than two cameras, or all at one place; :func:`rectify_row` says why)."""
    if len(cameras) < 2 or not all(isinstance(c, CalibratedCamera) for c in cameras):
        return None
    centres = np.stack([c.position for c in cameras])
    if not np.max(np.abs(centres - centres.mean(axis=0))) > 0:
        return None
    return _centre_line(centres)


def _check_lines_apart(row_cameras, column_cameras) -> None:
    """Refuse a row and a column whose lines of centres run within ``_MIN_LINES_DEG`` of each other."""
    row, column = _line_direction(row_cameras), _line_direction(column_cameras)
    if row is None or column is None:
        return
    angle = math.degrees(math.acos(min(1.0, abs(float(row @ column)))))
    if angle < _MIN_LINES_DEG:
        msg = (
            f"the row's cameras (row_cameras / --cameras, along {(np.round(row, 3) + 0.0).tolist()}) and the column's (column_cameras / "
            f"--column-cameras, along {(np.round(column, 3) + 0.0).tolist()}) lie on lines {angle:.1f} degrees apart: expected at least "
            f"{_MIN_LINES_DEG:g} (a column across the row; the same line given twice would count each measurement twice)"
        )
        raise ValueError(msg)


@dataclass(frozen=True)
class CalibratedGridDepth:
    """Depth of a row and a column of calibrated cameras through one reference camera, fused (:func:`calibrated_grid_depth`).

    ``depth``, ``depth_std``, ``edge_mask`` as :class:`CalibratedRowDepth`
    (the reference camera's own pixels); ``line_count``: how many of the two
    lines' values the fused depth holds (0 wherever it is NaN, also at a
    ``conflict``); ``conflict``: pixels both gave values too far apart to
    fuse (NaN); ``row``, ``column``: each line's
    :class:`CalibratedRowDepth`.
    """

    depth: np.ndarray
    depth_std: np.ndarray
    edge_mask: np.ndarray
    line_count: np.ndarray
    conflict: np.ndarray
    row: CalibratedRowDepth
    column: CalibratedRowDepth

    def points(self, *, image=None):
        """The fused depth as 3-D points in the reference camera's axes (:meth:`CalibratedRowDepth.points`)."""
        return _depth_points(self.row.row.camera, self.depth, image)

    def filled(self) -> tuple[np.ndarray, np.ndarray]:
        """The fused depth with its holes filled from the background, and where it was filled.

        A pixel neither line measured (or whose two values conflict) takes the
        farther of the row's and the column's filled depths
        (:meth:`CalibratedRowDepth.filled`, each along its own baseline).
        ``depth_std`` has no value there; the mask marks them.
        """
        row, _ = self.row.filled()
        column, _ = self.column.filled()
        measured = np.isfinite(self.depth)
        depth = np.where(measured, self.depth, np.fmax(row, column)).astype(np.float32)
        return depth, ~measured & np.isfinite(depth)


def calibrated_grid_depth(
    row_views,
    row_cameras,
    column_views,
    column_cameras,
    *,
    row_reference: int,
    column_reference: int,
    max_line_disagreement_px: float = 0.5,
    depth_range=None,
    **stereo_options,
) -> CalibratedGridDepth:
    """Depth from two lines of calibrated cameras through the same reference camera, fused per pixel.

    Each line runs :func:`calibrated_row_depth` on its own (a line along
    the reference's X axis, one along its Y axis, or any two); the paper's
    suggested fix for edges parallel to one baseline. The two depths of a
    pixel are fused by weighted least squares on inverse depth, the variance
    widened by their reduced chi^2 when above 1 (as
    :func:`nfdepth.xy_stereo.fuse_axes` does for rectified rows); a pixel
    whose two values differ by more than ``max_line_disagreement_px`` px of
    disparity at the nearest neighbour spacing and by more than 3 standard
    deviations is NaN (``conflict``). ``depth_range`` and ``stereo_options``
    go to each line's :func:`calibrated_row_depth` (the depths are the
    reference camera's, so one range serves both lines).

    Parameters
    ----------
    row_views, column_views : sequence of 2-D arrays
        Each line's grey images, each of its camera's size.
    row_cameras, column_cameras : sequence of CalibratedCamera
        One per view of the line, in the same order.
    row_reference, column_reference : int
        Index of the shared reference view in each line: the same camera
        (an equal :class:`CalibratedCamera`) and the same image.
    max_line_disagreement_px : float
        Conflict threshold, px of disparity at the nearest neighbour spacing
        (see above); > 0, ``inf`` for no limit.
    depth_range : (float, float), optional
        ``(near, far)`` in scene units along the reference camera's axis
        (:func:`calibrated_row_depth`).
    **stereo_options
        As for :func:`calibrated_row_depth`.

    Returns
    -------
    CalibratedGridDepth
        ``depth`` and ``depth_std`` float32 of the reference camera's size,
        in scene units.

    Raises
    ------
    TypeError
        A camera or view list that is not a sequence, a view that is not
        real (``row_views[k]``, ``column_views[k]``), a reference index
        that is not an int, a ``max_line_disagreement_px`` that is not a
        number; what :func:`calibrated_row_depth` refuses as such (the
        message starts with "row: " or "column: ").
    ValueError
        The two lines' reference cameras or images differ, or their lines
        of camera centres run within 30 degrees of each other (the same
        line given twice; the column is there to measure the edges
        parallel to the row). Also a view that is not a finite grey image,
        a reference index out of range, a ``max_line_disagreement_px`` that
        is not > 0, and what :func:`calibrated_row_depth` refuses on either
        line (the message starts with "row: " or "column: ").

    Warns
    -----
    UserWarning
        Those of :func:`calibrated_row_depth` on either line; and where the
        two lines' depths differ by a median scale or mostly conflict (their
        positions in two units?).
    """
    from .depth import Reason
    from .xy_stereo import _warn_if_axes_disagree, fuse_axes

    limit = check_positive_or_inf("max_line_disagreement_px", max_line_disagreement_px)
    row_cameras, column_cameras = _camera_list("row_cameras", row_cameras), _camera_list("column_cameras", column_cameras)
    row_views, column_views = _as_views("row_views", row_views), _as_views("column_views", column_views)
    row_reference = check_view_index("row_reference", row_reference, len(row_cameras))
    column_reference = check_view_index("column_reference", column_reference, len(column_cameras))
    if row_cameras[row_reference] != column_cameras[column_reference]:
        msg = "the row's and the column's reference cameras must be the same camera: both lines pass through it"
        raise ValueError(msg)
    counted = row_reference < len(row_views) and column_reference < len(column_views)  # (else a line says its count does not fit)
    if counted and not np.array_equal(row_views[row_reference], column_views[column_reference]):
        msg = "the row's and the column's reference views must be the same image: both lines pass through the reference camera"
        raise ValueError(msg)
    _check_lines_apart(row_cameras, column_cameras)
    lines = {}
    for which, views, cameras, reference in (("row", row_views, row_cameras, row_reference), ("column", column_views, column_cameras, column_reference)):
        try:
            lines[which] = calibrated_row_depth(views, cameras, reference=reference, depth_range=depth_range, **stereo_options)
        except (TypeError, ValueError) as exc:
            if type(exc) not in (TypeError, ValueError):
                raise
            raise type(exc)(f"{which}: {exc}") from exc  # (its views[k] and cameras[k] are that line's)
    a, b = lines["row"], lines["column"]
    # each line's inverse depth as a disparity in px at the nearest neighbour spacing of either line
    # (f rho b: the unit of max_line_disagreement_px), fused as two rectified axes are
    scale = a.row.focal_px * min(float(np.min(np.diff(r.row.positions))) for r in (a, b))
    lines = []
    for r in (a, b):
        with np.errstate(divide="ignore", invalid="ignore"):
            rho = 1.0 / np.asarray(r.depth, np.float64)
            rho_std = np.asarray(r.depth_std, np.float64) * rho**2
        ok = np.isfinite(rho) & np.isfinite(rho_std) & (rho_std > 0)
        lines.append(SimpleNamespace(disparity=scale * rho, uncertainty=scale * rho_std, reason=np.where(ok, Reason.OK, Reason.NO_DATA).astype(np.uint8)))
    disparity, std, _reason, count, conflict = fuse_axes(*lines, max_axis_disagreement_px=limit)
    _warn_if_axes_disagree(*lines, count == 2, conflict, positions="the cameras' positions of the row and of the column, --cameras / --column-cameras")
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = scale / disparity.astype(np.float64)
        depth_std = scale * std.astype(np.float64) / disparity.astype(np.float64) ** 2
    good = np.isfinite(depth)
    edges = (a.edge_mask | b.edge_mask) & good
    return CalibratedGridDepth(
        depth=depth.astype(np.float32),
        depth_std=depth_std.astype(np.float32),
        edge_mask=edges,
        line_count=np.where(good, count, 0).astype(np.uint8),
        conflict=conflict,
        row=a,
        column=b,
    )
