"""Rig description files: cameras, their poses and motions, in TOML.

A rig file replaces long option lists on the command line (``nfdepth
dynamic``, ``nfdepth video``, ``nfdepth stereo --rig``). The format is
documented in ``docs/rig-format.md``; in short::

    [camera]                      # required
    focal_px  = 100.0             # focal length, pixels (> 0)
    width_px  = 200               # image size, pixels
    height_px = 200
    # cx_px = 99.5                # principal point (default: image centre)
    # cy_px = 99.5
    # distortion = [-0.1, 0.02, 0.0, 0.0]   # OpenCV's k1, k2, p1, p2(, k3...): undone in every image first

    [motion]                      # dynamic stereo (nfdepth dynamic)
    velocity       = [2.0, 0.0, 0.0]   # moving camera rel. to the reference, units / unit time
    rotation_deg   = [0.0, 0.0, 0.0]   # its angular velocity, degrees / unit time (at most 90 per frame interval)
    frame_interval = 1.0               # time between consecutive images
    # crossings    = [12, 40]          # two synchronised videos: frames at which the cameras coincide

    [stereo]                      # static rows (nfdepth stereo)
    baseline  = 2.0               # spacing of neighbouring views (scene units)
    axis      = "x"               # or direction = [1, 0, 0]
    # positions = [0, 1, 2.5]     # in units of the baseline
    # disparity_offset_px = 31.1  # principal points differ along the row: depth = f b / (d + offset)

    [video]                       # single moving camera (nfdepth video)
    velocity = [0.5, 0.0, 0.0]    # camera translation per frame (scene units)
    # or: positions = [[0,0,0], [0.5,0,0], ...]   one per frame
    # or: poses = "poses.csv"     # frame,x,y,z[,rx,ry,rz]; relative to this file

Everything inside the library is in radians and in the conventions of
docs/how-it-works.md ("Conventions"): the rig gives the *camera's* motion ``T``, ``w``; the
scene moves relative to it as ``V = -T``, ``Omega = -w``
(:meth:`Rig.relative_motion`).

Errors are :class:`RigError` (a ``ValueError``) naming the key path, the
value found and what was expected.
"""

from __future__ import annotations

import csv
import inspect
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from ._validate import (
    DISPARITY_OFFSET_EXPECTED,
    UNIT_SCALE_RANGE,
    NFDepthError,
    as_image,
    as_path,
    check_disparity_offset,
    check_frame_size,
    check_int,
    float_dtype,
)
from .camera import (
    MAX_ROTATION_PER_FRAME_DEG,
    PinholeCamera,
    RigidMotion,
    _magnitude,
    _principal_point_expected,
    _principal_point_reach,
)
from .io import InputReadError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "RigError",
    "MotionSpec",
    "StereoSpec",
    "VideoSpec",
    "Poses",
    "Rig",
    "load_rig",
    "rig_from_dict",
    "rig_to_toml",
    "load_poses",
    "check_crossings",
    "stereo_options_from_rig",
    "dynamic_stereo_from_rig",
    "edge_depth_maps",
]


class RigError(NFDepthError):
    """A rig description is missing a field, has a wrong value, or contradicts itself (a ``ValueError``)."""


# ----------------------------------------------------------------- helpers


def _show(value: Any) -> str:
    if isinstance(value, np.ndarray) and (value.ndim > 1 or value.dtype.kind not in "iuf"):  # given as a NumPy array: as given
        return _show(value.tolist())
    if isinstance(value, np.ndarray):  # computed vectors (a unit direction): plain numbers, [0, 0, 1]
        return "[" + ", ".join(f"{float(v) + 0.0:g}" for v in value.ravel()) + "]"
    if isinstance(value, np.generic):
        return _show(value.item())
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, float) and value.is_integer():
        return repr(value)
    return str(value) if not isinstance(value, (list, tuple)) else "[" + ", ".join(_show(v) for v in value) + "]"


def _fail(key: str, value: Any, expected: str) -> RigError:
    return RigError(f"{key} = {_show(value)}: expected {expected}")


def _is_number(value: Any) -> bool:
    """A real number, Python's or NumPy's (a dict built from a calibration holds NumPy scalars); no bool."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _number(table: dict, section: str, name: str, *, required: bool = True, positive: bool = False, default=None):
    key = f"{section}.{name}"
    if name not in table:
        if required:
            raise RigError(f"{key} is missing: expected {'a positive number' if positive else 'a number'}")
        return default
    value = table[name]
    if not _is_number(value) or not math.isfinite(value):
        raise _fail(key, value, "a finite number")
    if positive and value <= 0:
        raise _fail(key, value, "a number > 0")
    return float(value)


def _integer(table: dict, section: str, name: str) -> int:
    key = f"{section}.{name}"
    if name not in table:
        raise RigError(f"{key} is missing: expected a positive integer (pixels)")
    value = table[name]
    if isinstance(value, (float, np.floating)) and float(value).is_integer() or isinstance(value, np.integer):
        value = int(value)
    if not isinstance(value, int) or isinstance(value, bool) or value < 1:
        raise _fail(key, value, "a positive integer (pixels)")
    return value


def _entries(value: Any, ndim: int = 1) -> list | None:
    """The entries of a sequence: a list or tuple (a TOML array, or a dict built in Python), or a NumPy array of ``ndim``
    dimensions (a calibration's); None for anything else (a str, a dict, a number)."""
    if isinstance(value, (list, tuple)):
        return list(value)
    if isinstance(value, np.ndarray) and value.ndim == ndim:
        return list(value)
    return None


def _not_a_sequence(value: Any) -> str:
    """`` (a str, not a list)``: what a value that is no list, tuple or array is, for the end of a message refusing it."""
    if isinstance(value, np.ndarray):
        return f" (an array of shape {value.shape}, not a list)"
    name = type(value).__name__
    return f" ({'an' if name[0] in 'aeiou' else 'a'} {name}, not a list)"


def _finite_numbers(values: list | None) -> bool:
    return values is not None and all(_is_number(v) and math.isfinite(v) for v in values)


def _vector(table: dict, section: str, name: str, *, required: bool = False, default=None):
    key = f"{section}.{name}"
    if name not in table:
        if required:
            raise RigError(f"{key} is missing: expected 3 numbers [x, y, z]")
        return default
    value = table[name]
    items = _entries(value)
    if items is None or len(items) != 3 or not _finite_numbers(items):
        raise _fail(key, value, "3 finite numbers [x, y, z]" + ("" if items is not None else _not_a_sequence(value)))
    return np.array([float(v) for v in items])


def _check_scale(key: str, raw: Any, magnitude: float, what: str) -> None:
    """Refuse a length, speed or focal length outside :data:`UNIT_SCALE_RANGE`: depths in float32 outputs overflow or vanish beyond it."""
    lo, hi = UNIT_SCALE_RANGE
    if not lo <= magnitude <= hi:
        raise _fail(key, raw, f"{what} of {lo:g} to {hi:g} (give it in a unit that keeps it there: depths are written as float32)")


def _point(p) -> str:
    return "(" + ", ".join(f"{float(x) + 0.0:g}" for x in p) + ")"


def _check_steps(positions, what: str, *, frames=None, error: type[ValueError] = RigError) -> None:
    """Refuse a camera step between consecutive positions (N, 3) outside :data:`UNIT_SCALE_RANGE`, as a speed.

    A step is measured by its largest component, as ``video.velocity`` is; zero steps (a camera standing
    still) are left to the callers. ``frames`` are the frame numbers of the rows (default 0, 1, ...).
    """
    p = np.asarray(positions, dtype=float)
    if len(p) < 2:
        return
    with np.errstate(over="ignore"):  # a step beyond the float range is inf: refused below
        steps = np.max(np.abs(np.diff(p, axis=0)), axis=1)
    lo, hi = UNIT_SCALE_RANGE
    bad = np.flatnonzero((steps != 0) & ~((steps >= lo) & (steps <= hi)))
    if bad.size:
        i = int(bad[0])
        a, b = (int(frames[i]), int(frames[i + 1])) if frames is not None else (i, i + 1)
        raise error(
            f"{what}: the camera moves from {_point(p[i])} at frame {a} to {_point(p[i + 1])} at frame {b}, a step of"
            f" {float(steps[i]):g}: expected a speed of {lo:g} to {hi:g} per frame, or 0 where it stands still (give the"
            " positions in a unit that keeps the steps there: depths are written as float32)"
        )


def _check_keys(table: Any, section: str, allowed: tuple[str, ...]) -> dict:
    if not isinstance(table, dict):
        raise _fail(section, table, f"a table [{section}]")
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise RigError(f"{section}.{unknown[0]}: unknown key (expected one of {', '.join(allowed)})")
    return table


def _exclusive(table: dict, section: str, names: tuple[str, ...], *, required: bool) -> str | None:
    given = [n for n in names if n in table]
    if len(given) > 1:
        raise RigError(f"{section}: {' and '.join(given)} contradict each other: give only one of {', '.join(names)}")
    if not given:
        if required:
            raise RigError(f"{section}: expected one of {', '.join(names)}")
        return None
    return given[0]


_AXES = {"x": np.array([1.0, 0.0, 0.0]), "y": np.array([0.0, 1.0, 0.0])}


def _unit(vec) -> np.ndarray | None:
    """``vec`` (finite) scaled to length 1, or None for a zero (or non-finite) vector.

    Scaled by its largest component first: ``vec / np.linalg.norm(vec)`` made [1e-170, 0, 0] [inf, nan, nan]
    (its square underflows) and [1e200, 1e200, 0] [0, 0, 0] (it overflows).
    """
    vec = np.asarray(vec, dtype=float)
    m = float(np.max(np.abs(vec))) if vec.size else 0.0
    if not (m > 0 and math.isfinite(m)):
        return None
    vec = vec / m
    return vec / np.linalg.norm(vec)


# ----------------------------------------------------------------- poses


#: A poses file's frame indices lie below this (2**53): every whole number below it is exact as a float (an
#: index is read as one, "12" or "1.2e1"), and it is far beyond any video's length.
FRAME_LIMIT = 2**53

#: Largest orientation (rotation-vector length, degrees) a poses file or ``orientations_rad``
#: may give: float64 keeps about 1e-10 degrees there; far beyond, the rotation is lost to rounding.
MAX_TURN_DEG = 1e6


@dataclass(frozen=True, eq=False)
class Poses:
    """Camera poses per frame, from a CSV file (``frame,x,y,z[,rx,ry,rz]``).

    Attributes
    ----------
    frames : ndarray of int, shape (N,)
        Frame indices (0-based, strictly increasing).
    positions : ndarray, shape (N, 3)
        Optical centre of each frame in world coordinates (scene units).
    rotations_deg : ndarray, shape (N, 3)
        Camera-to-world orientation as a rotation vector in degrees (zeros
        when the file has no ``rx, ry, rz`` columns).
    source : Path or None
        The file read.
    """

    frames: np.ndarray
    positions: np.ndarray
    rotations_deg: np.ndarray
    source: Path | None = None

    def position(self, frame: int) -> np.ndarray:
        """Optical centre of ``frame`` (:class:`RigError` if the file has no such row)."""
        idx = np.searchsorted(self.frames, frame)
        if idx >= self.frames.size or self.frames[idx] != frame:
            where = f" in '{self.source}'" if self.source else ""
            raise RigError(f"poses{where}: no row for frame {frame} (the file covers frames {self.frames[0]}..{self.frames[-1]})")
        return self.positions[idx]

    def rotation(self, frame: int) -> np.ndarray:
        """Orientation (rotation vector, degrees) of ``frame``."""
        self.position(frame)
        return self.rotations_deg[np.searchsorted(self.frames, frame)]


def load_poses(path) -> Poses:
    """Read a poses CSV: header ``frame,x,y,z`` and optionally ``rx,ry,rz`` (degrees).

    ``frame`` is the 0-based frame index (integers, strictly increasing);
    ``x, y, z`` the camera's optical centre in world coordinates (scene
    units); ``rx, ry, rz`` its camera-to-world orientation as a rotation
    vector in degrees. Raises :class:`RigError` naming the line and column.
    Blank lines and lines starting with ``#`` are skipped; the header is
    read case-insensitively.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file, UTF-8 (a byte-order mark is allowed).

    Returns
    -------
    Poses
        One entry per data row, in file order; ``rotations_deg`` zeros
        without ``rx, ry, rz`` columns; ``source`` the path read.

    Raises
    ------
    TypeError
        If ``path`` is not a str or os.PathLike.
    FileNotFoundError
        If the file does not exist or is a directory.
    nfdepth.io.InputReadError
        If it cannot be read (e.g. no read permission).
    RigError
        A file that is not UTF-8 text or is empty, a header other than
        ``frame,x,y,z[,rx,ry,rz]``, no data rows, a row with another number
        of columns, a frame that is not a whole number >= 0 and below
        :data:`FRAME_LIMIT` (2**53) or not strictly increasing, a value that
        is not a finite number, or an orientation of more than
        :data:`MAX_TURN_DEG` (1e6) degrees.
    """
    path = as_path("path", path)
    if not path.is_file():
        raise FileNotFoundError(f"cannot read poses file '{path}': {'it is a directory' if path.is_dir() else 'no such file'}")
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:  # (-sig: Excel's "CSV UTF-8" opens with a byte-order mark)
            reader = csv.reader(fh)  # each row with its line in the file (comment and blank lines count)
            numbered = [(reader.line_num, r) for r in reader if r and not r[0].lstrip().startswith("#")]
    except UnicodeDecodeError:
        raise RigError(f"poses '{path}': not a UTF-8 text file") from None
    except OSError as exc:  # e.g. no read permission
        raise InputReadError(f"cannot read poses file '{path}': {exc.strerror or exc}") from None
    if not numbered:
        raise RigError(f"poses '{path}': the file is empty; expected a header frame,x,y,z[,rx,ry,rz]")
    (header_line, header), *rows = numbered
    header = [h.strip().lower() for h in header]
    if header not in (["frame", "x", "y", "z"], ["frame", "x", "y", "z", "rx", "ry", "rz"]):
        raise RigError(f"poses '{path}' line {header_line}: header {','.join(header)!r}: expected 'frame,x,y,z' or 'frame,x,y,z,rx,ry,rz'")
    n_cols = len(header)
    frames, values = [], []
    for line_no, row in rows:
        if len(row) != n_cols:
            raise RigError(f"poses '{path}' line {line_no}: {len(row)} columns: expected {n_cols} ({','.join(header)})")
        try:
            frame_val = float(row[0])
        except ValueError:
            raise RigError(f"poses '{path}' line {line_no}: frame = {row[0]!r}: expected an integer frame index") from None
        if not frame_val.is_integer() or frame_val < 0:
            raise RigError(f"poses '{path}' line {line_no}: frame = {row[0]!r}: expected an integer frame index >= 0")
        if frame_val >= FRAME_LIMIT:
            raise RigError(
                f"poses '{path}' line {line_no}: frame = {row[0]!r}: expected a frame index below {FRAME_LIMIT}"
                " (2**53, where whole numbers stop being exact in floating point)"
            )
        vals = []
        for name, text in zip(header[1:], row[1:]):
            try:
                v = float(text)
            except ValueError:
                v = math.nan
            if not math.isfinite(v):
                raise RigError(f"poses '{path}' line {line_no}: {name} = {text.strip()!r}: expected a finite number")
            vals.append(v)
        frames.append(int(frame_val))
        values.append(vals)
    if not frames:
        raise RigError(f"poses '{path}': no data rows after the header")
    frames_arr = np.asarray(frames, dtype=np.int64)
    if np.any(np.diff(frames_arr) <= 0):
        bad = rows[int(np.argmax(np.diff(frames_arr) <= 0)) + 1][0]
        raise RigError(f"poses '{path}' line {bad}: frame indices must be strictly increasing")
    arr = np.asarray(values, dtype=float)
    rot = arr[:, 3:6] if n_cols == 7 else np.zeros((arr.shape[0], 3))
    angles = np.hypot(np.hypot(rot[:, 0], rot[:, 1]), rot[:, 2])  # (no overflow short of the float range)
    if np.any(angles > MAX_TURN_DEG):
        bad = int(np.argmax(angles > MAX_TURN_DEG))
        raise RigError(
            f"poses '{path}' line {rows[bad][0]}: rx, ry, rz = {_point(rot[bad])}, a turn of {angles[bad]:g} degrees: expected at most"
            f" {MAX_TURN_DEG:g} (give the orientation modulo 360 degrees: beyond that float64 loses its fractions of a degree)"
        )
    return Poses(frames_arr, arr[:, :3], rot, source=path)


# ----------------------------------------------------------------- specs


#: Largest ``motion.frame_interval``: the moving camera's images are two frame intervals apart, and
#: :func:`nfdepth.pipelines.dynamic_stereo` takes their time step up to :data:`UNIT_SCALE_RANGE`'s end, so
#: the interval up to half of it (as it checks ``frame_interval`` itself).
MAX_FRAME_INTERVAL = 0.5 * UNIT_SCALE_RANGE[1]


@dataclass(frozen=True, eq=False)
class MotionSpec:
    """``[motion]``: the moving camera relative to the reference camera (dynamic stereo).

    Attributes
    ----------
    velocity : ndarray, shape (3,)
        Translation ``T`` of the moving camera relative to the reference
        camera, scene units per unit time, in the reference camera's frame.
    rotation_deg : ndarray, shape (3,)
        Its angular velocity ``w``, degrees per unit time.
    frame_interval : float
        Time between consecutive images ``I_k``, ``I_k+1`` (for two
        synchronised videos: between consecutive frames).
    crossings : tuple of int or None
        Two synchronised videos (``nfdepth dynamic --moving-video``): the
        0-based frame indices at which the two cameras coincide, strictly
        increasing, each >= 2 (the five-image sequence needs two frames
        before it). None when not given.
    """

    velocity: np.ndarray
    rotation_deg: np.ndarray = field(default_factory=lambda: np.zeros(3))
    frame_interval: float = 1.0
    crossings: tuple | None = None

    def relative_motion(self) -> RigidMotion:
        """``(dV, dOmega) = (-T, -w)`` in radians (docs/how-it-works.md, "Conventions": a camera moving by T sees V = -T)."""
        return RigidMotion(translation=0.0 - self.velocity + 0.0, rotation=0.0 - np.deg2rad(self.rotation_deg) + 0.0)

    def __eq__(self, other) -> bool:
        return (
            isinstance(other, MotionSpec)
            and np.array_equal(self.velocity, other.velocity)
            and np.array_equal(self.rotation_deg, other.rotation_deg)
            and self.frame_interval == other.frame_interval
            and self.crossings == other.crossings
        )


@dataclass(frozen=True, eq=False)
class StereoSpec:
    """``[stereo]``: a row of static views.

    Attributes
    ----------
    baseline : float
        Spacing of neighbouring views (scene units, > 0).
    direction : ndarray, shape (3,)
        Unit direction of travel from the first view to the last.
    axis : str or None
        ``"x"`` or ``"y"`` when given as ``axis`` (else None).
    positions : tuple of float or None
        View positions in units of the baseline (strictly increasing).
    column_positions : tuple of float or None
        Positions of a column of views through the same reference camera
        (``nfdepth stereo --column``), in the same unit.
    disparity_range_px : tuple of (float, float) or None
        Smallest and largest disparity to search, in px per unit position
        (``disparity_range_px`` of :func:`nfdepth.stereo.static_stereo`,
        ``nfdepth stereo --disparity-range``).
    disparity_offset_px : float
        Added to the measured disparity before depth, in px per unit
        position (``disparity_offset_px`` of
        :meth:`nfdepth.stereo.StereoResult.depth`, ``nfdepth stereo
        --disparity-offset-px``): where the row's cameras' principal points
        differ along it, as in Middlebury's ``doffs`` (default 0).
    """

    baseline: float
    direction: np.ndarray
    axis: str | None = None
    positions: tuple | None = None
    column_positions: tuple | None = None
    disparity_range_px: tuple | None = None
    disparity_offset_px: float = 0.0

    def __eq__(self, other) -> bool:
        return (
            isinstance(other, StereoSpec)
            and self.baseline == other.baseline
            and np.array_equal(self.direction, other.direction)
            and self.axis == other.axis
            and self.positions == other.positions
            and self.column_positions == other.column_positions
            and self.disparity_range_px == other.disparity_range_px
            and self.disparity_offset_px == other.disparity_offset_px
        )


@dataclass(frozen=True, eq=False)
class VideoSpec:
    """``[video]``: one camera moving through a static scene.

    Exactly one of the three is set.

    Attributes
    ----------
    velocity : ndarray (3,) or None
        Camera translation per frame (scene units), constant.
    positions : ndarray (N, 3) or None
        Camera optical centre of each frame (world = camera axes).
    poses : Poses or None
        Loaded from a CSV (path relative to the rig file's folder).
    orientations_deg : ndarray (N, 3) or None
        With ``positions``: the camera-to-world orientation of each frame as
        a rotation vector in degrees (default: constant, the world axes).
    """

    velocity: np.ndarray | None = None
    positions: np.ndarray | None = None
    poses: Poses | None = None
    orientations_deg: np.ndarray | None = None

    def camera_position(self, frame: int) -> np.ndarray:
        """Optical centre of ``frame`` in world coordinates (frame 0 at the origin for ``velocity``)."""
        if self.velocity is not None:
            return frame * self.velocity
        if self.positions is not None:
            if not 0 <= frame < len(self.positions):
                raise RigError(f"video.positions has {len(self.positions)} entries: no position for frame {frame}")
            return self.positions[frame]
        assert self.poses is not None
        return self.poses.position(frame)

    def orientation_deg(self, frame: int) -> np.ndarray:
        """Camera-to-world rotation vector (degrees) of ``frame``; zeros unless poses or ``orientations_deg`` give it."""
        if self.poses is not None:
            return self.poses.rotation(frame)
        if self.orientations_deg is not None:
            return self.orientations_deg[frame]
        return np.zeros(3)

    def __eq__(self, other) -> bool:
        def same(a, b):
            return (a is None and b is None) or (a is not None and b is not None and np.array_equal(a, b))

        return (
            isinstance(other, VideoSpec)
            and same(self.velocity, other.velocity)
            and same(self.positions, other.positions)
            and same(self.orientations_deg, other.orientations_deg)
            and ((self.poses is None) == (other.poses is None))
            and (self.poses is None or (
                np.array_equal(self.poses.positions, other.poses.positions)
                and np.array_equal(self.poses.frames, other.poses.frames)
                and np.array_equal(self.poses.rotations_deg, other.poses.rotations_deg)
            ))
        )


@dataclass(frozen=True, eq=False)
class Rig:
    """A camera rig: intrinsics plus the motions the commands need.

    Attributes
    ----------
    camera : PinholeCamera
        Intrinsics shared by the rig's cameras.
    motion : MotionSpec or None
        ``[motion]`` (needed by :func:`nfdepth.pipelines.dynamic_stereo`).
    stereo : StereoSpec or None
        ``[stereo]`` (static rows).
    video : VideoSpec or None
        ``[video]`` (:func:`nfdepth.video.depth_from_video`).
    source : Path or None
        The file it was read from.
    distortion : tuple
        ``[camera] distortion``: OpenCV's lens distortion coefficients
        (empty: none). The commands undo it in every image first
        (:meth:`undistort`); their outputs lie on the undistorted pixel grid.
    """

    camera: PinholeCamera
    motion: MotionSpec | None = None
    stereo: StereoSpec | None = None
    video: VideoSpec | None = None
    source: Path | None = None
    distortion: tuple = ()

    def undistort(self, image) -> np.ndarray:
        """``image`` with ``[camera] distortion`` undone, on the same pinhole camera (focal length, principal point, size).

        Float32; read with a cubic spline (as turned frames are,
        :func:`nfdepth._derotation.derotate`); pixels whose undistorted
        position falls outside the image take the border's value. ``image``
        itself (as float32) without distortion.
        """
        img = np.asarray(image, dtype=np.float32)
        if not any(self.distortion):
            return img
        if img.ndim != 2:
            msg = f"image must be a 2-D grey image (rows, cols), got shape {img.shape}" + ("; convert colour to grey first (nfdepth.io.to_grey)" if img.ndim == 3 else "")
            raise ValueError(msg)
        self.check_image_shape(img.shape, what="the image")
        maps = self.__dict__.get("_undistort_maps")
        if maps is None:
            cam = self.camera
            map_x, map_y = cv2.initUndistortRectifyMap(cam.matrix, np.array(self.distortion), None, cam.matrix, (cam.width_px, cam.height_px), cv2.CV_32FC1)
            maps = (map_x, map_y, None)
            object.__setattr__(self, "_undistort_maps", maps)  # a rig is immutable: computed once
        from ._derotation import derotate

        return derotate(img, maps)

    def _need(self, section: str):
        spec = getattr(self, section)
        if spec is None:
            where = f"rig '{self.source}'" if self.source else "the rig"
            raise RigError(f"{where} has no [{section}] section, which this command needs")
        return spec

    def relative_motion(self) -> RigidMotion:
        """Relative motion ``(V_m - V_s, Omega_m - Omega_s)`` of ``[motion]`` (radians)."""
        return self._need("motion").relative_motion()

    @property
    def frame_interval(self) -> float:
        """``[motion].frame_interval``."""
        return self._need("motion").frame_interval

    def check_image_shape(self, shape, what: str = "the images") -> None:
        """Raise :class:`RigError` unless ``shape`` (rows, cols) matches ``[camera]`` (``ValueError`` for a shape of fewer than 2 sizes)."""
        if len(shape) < 2:
            msg = f"{what} must be a 2-D grey image (rows, cols), got shape {tuple(shape)}"
            raise ValueError(msg)
        rows, cols = int(shape[0]), int(shape[1])
        if (rows, cols) != self.camera.shape:
            src = f" ({self.source.name})" if self.source else ""
            raise RigError(
                f"camera.width_px x camera.height_px = {self.camera.width_px}x{self.camera.height_px}{src}"
                f" does not match {what} ({cols}x{rows})"
            )

    def __eq__(self, other) -> bool:
        return (
            isinstance(other, Rig)
            and self.camera == other.camera
            and self.motion == other.motion
            and self.stereo == other.stereo
            and self.video == other.video
            and tuple(self.distortion) == tuple(other.distortion)
        )


# ----------------------------------------------------------------- parsing


def _parse_distortion(table, camera: PinholeCamera) -> tuple:
    if not isinstance(table, dict) or "distortion" not in table:
        return ()
    raw = d = table["distortion"]
    if isinstance(d, np.ndarray) and d.ndim == 2 and 1 in d.shape:  # cv2.calibrateCamera's (1, N) row (or a column)
        d = d.ravel()
    items = _entries(d)
    if items is None or len(items) not in (4, 5, 8) or not _finite_numbers(items):
        expected = "4, 5 or 8 finite numbers, OpenCV's [k1, k2, p1, p2, k3, k4, k5, k6]"
        raise _fail("camera.distortion", raw, expected + ("" if items is not None else _not_a_sequence(raw)))
    d = items
    fold = _radial_fold_px(d, camera)
    if fold is not None:
        reach = _corner_radius_px(camera)
        raise _fail(
            "camera.distortion",
            d,
            f"a lens model that maps the image one to one: its radial term turns back {fold:.0f} px from the principal point,"
            f" inside the image ({reach:.0f} px to its farthest corner), so undoing it would fold the image over (coefficients"
            " from another image size or focal length, or a fit that did not converge?)",
        )
    return tuple(float(v) for v in d)


def _corner_radius_px(camera: PinholeCamera) -> float:
    """Distance from the principal point to the image's farthest corner, px."""
    return max(math.hypot(x - camera.cx_px, y - camera.cy_px) for x in (0.0, camera.width_px - 1.0) for y in (0.0, camera.height_px - 1.0))


def _radial_fold_px(d, camera: PinholeCamera) -> float | None:
    """Where OpenCV's radial model ``r (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)`` stops growing
    within the image (px from the principal point), or None: a model that folds the image back on itself there."""
    k = [float(v) for v in d] + [0.0] * (8 - len(d))
    r = np.linspace(0.0, _corner_radius_px(camera) / camera.focal_px, 2049)
    r2 = r * r
    radial = (1.0 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]))) / (1.0 + r2 * (k[5] + r2 * (k[6] + r2 * k[7])))
    grows = np.diff(r * radial) > 0
    return None if grows.all() else float(r[int(np.argmin(grows))] * camera.focal_px)


def _parse_camera(table) -> PinholeCamera:
    t = _check_keys(table, "camera", ("focal_px", "width_px", "height_px", "cx_px", "cy_px", "distortion"))
    focal = _number(t, "camera", "focal_px", positive=True)
    _check_scale("camera.focal_px", t["focal_px"], focal, "a focal length")
    width = _integer(t, "camera", "width_px")
    height = _integer(t, "camera", "height_px")
    cx = _number(t, "camera", "cx_px", required=False)
    cy = _number(t, "camera", "cy_px", required=False)
    reach = _principal_point_reach(width, height)
    for name, value, size in (("cx_px", cx, width), ("cy_px", cy, height)):
        centre = (size - 1) / 2.0
        if value is not None and not abs(value - centre) <= reach:
            raise _fail(f"camera.{name}", t[name], _principal_point_expected(centre, reach))
    return PinholeCamera(focal, width, height, cx, cy)


def _parse_motion(table) -> MotionSpec:
    t = _check_keys(table, "motion", ("velocity", "rotation_deg", "frame_interval", "crossings"))
    velocity = _vector(t, "motion", "velocity", required=True)
    if not np.any(velocity):
        raise _fail("motion.velocity", t["velocity"], "a non-zero translation (depth needs a baseline between the cameras)")
    _check_scale("motion.velocity", t["velocity"], float(np.max(np.abs(velocity))), "a speed")
    rotation = _vector(t, "motion", "rotation_deg", default=np.zeros(3))
    interval = _number(t, "motion", "frame_interval", required=False, positive=True, default=1.0)
    lo, hi = UNIT_SCALE_RANGE
    if not lo <= interval <= MAX_FRAME_INTERVAL:
        raise _fail(
            "motion.frame_interval",
            t["frame_interval"],
            f"a time step within {lo:g}..{MAX_FRAME_INTERVAL:g} (the moving camera's images I1, I3, I5 are two intervals apart;"
            " give times in a unit that keeps it there, e.g. frames)",
        )
    turn = _magnitude(rotation) * interval
    if turn > MAX_ROTATION_PER_FRAME_DEG:
        raise _fail(
            "motion.rotation_deg",
            t["rotation_deg"],
            f"an angular velocity of at most {MAX_ROTATION_PER_FRAME_DEG:g} degrees per frame interval, got {turn:.4g} degrees per"
            f" frame_interval = {_show(interval)} (the moving camera's images are two intervals apart, and a turn of 180 degrees"
            " between two images cannot be told from a smaller one the other way; this small-motion method needs a few degrees"
            " per frame at most)",
        )
    if _magnitude(np.deg2rad(rotation)) > hi:  # as RigidMotion requires (the speeds' bound, in rad per unit time)
        raise _fail(
            "motion.rotation_deg",
            t["rotation_deg"],
            f"an angular velocity of at most {hi:g} rad ({np.rad2deg(hi):.4g} degrees) per unit time (give times in a unit that keeps it there, e.g. frames)",
        )
    crossings = None
    if "crossings" in t:
        try:
            crossings = check_crossings(t["crossings"])
        except (TypeError, ValueError) as exc:
            raise _fail("motion.crossings", t["crossings"], str(exc)) from None
    return MotionSpec(velocity, rotation, interval, crossings)


def check_crossings(crossings, *, name: str | None = None) -> tuple:
    """Validate crossing instants: a non-empty list of frame indices >= 2, strictly increasing.

    Returns them as a tuple of int; raises ``ValueError`` (``TypeError`` for
    non-integers) saying what was expected, as ``"{name} = [...]: expected
    ..."`` when ``name`` is given, else the bare ``"a non-empty list ..."``
    for a caller that names the value itself.
    """
    expected = "a non-empty list of frame indices (integers >= 2), strictly increasing"

    def refused(error, detail=""):
        return error(expected + detail if name is None else f"{name} = {shown!r}: expected {expected}{detail}")

    shown = crossings
    if isinstance(crossings, (str, bytes)) or not hasattr(crossings, "__iter__"):
        raise refused(TypeError)
    values = shown = list(crossings)
    if not values:
        raise refused(ValueError)
    out = []
    for v in values:
        if isinstance(v, (float, np.floating)) and float(v).is_integer():
            v = int(v)
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
            raise refused(TypeError)
        out.append(int(v))
    if min(out) < 2:
        raise refused(ValueError, f": frame {min(out)} has no two frames before it")
    if any(b <= a for a, b in zip(out, out[1:])):
        raise refused(ValueError)
    return tuple(out)


def _parse_stereo(table) -> StereoSpec:
    t = _check_keys(table, "stereo", ("baseline", "axis", "direction", "positions", "column_positions", "disparity_range_px", "disparity_offset_px"))
    baseline = _number(t, "stereo", "baseline", positive=True)
    _check_scale("stereo.baseline", t["baseline"], baseline, "a baseline")
    which = _exclusive(t, "stereo", ("axis", "direction"), required=False)
    axis = None
    if which == "direction":
        direction = _unit(_vector(t, "stereo", "direction"))
        if direction is None:
            raise _fail("stereo.direction", t["direction"], "a non-zero direction of travel")
    else:
        axis = t.get("axis", "x")
        if axis not in _AXES:
            raise _fail("stereo.axis", axis, '"x" or "y"')
        direction = _AXES[axis].copy()
    positions = _stereo_positions(t, "positions")
    column_positions = _stereo_positions(t, "column_positions")
    if column_positions is not None and not np.allclose(direction, _AXES["x"], atol=1e-9):
        raise _fail("stereo.column_positions", t["column_positions"], 'a row along x (axis = "x"): the column is the vertical line through its reference')
    disparity_range = None
    if "disparity_range_px" in t:
        r = t["disparity_range_px"]
        items = _entries(r)
        ok = items is not None and len(items) == 2 and _finite_numbers(items)
        if not ok or not items[0] < items[1]:
            expected = "[smallest, largest] disparity in px per unit position, two finite numbers, smallest first"
            raise _fail("stereo.disparity_range_px", r, expected + ("" if items is not None else _not_a_sequence(r)))
        r = items
        disparity_range = (float(r[0]), float(r[1]))
    offset = 0.0
    if "disparity_offset_px" in t:
        v = t["disparity_offset_px"]
        try:
            offset = check_disparity_offset("stereo.disparity_offset_px", v)
        except (TypeError, ValueError):
            raise _fail("stereo.disparity_offset_px", v, DISPARITY_OFFSET_EXPECTED) from None
        if column_positions is not None and offset != 0:
            raise _fail("stereo.disparity_offset_px", v, "0 with column_positions (the row and the column would each need their own offset)")
    return StereoSpec(baseline, direction, axis, positions, column_positions, disparity_range, offset)


def _stereo_positions(t: dict, key: str):
    if key not in t:
        return None
    p = t[key]
    items = _entries(p)
    if items is None or len(items) < 2 or not _finite_numbers(items):
        raise _fail(f"stereo.{key}", p, "a list of 2 or more finite numbers (units of the baseline)" + ("" if items is not None else _not_a_sequence(p)))
    p = items
    if not all(b > a for a, b in zip(p, p[1:])):
        raise _fail(f"stereo.{key}", p, "strictly increasing positions (views ordered along the baseline)")
    return tuple(float(v) for v in p)


def _parse_video(table, base: Path | None) -> VideoSpec:
    t = _check_keys(table, "video", ("velocity", "positions", "poses"))
    which = _exclusive(t, "video", ("velocity", "positions", "poses"), required=True)
    if which == "velocity":
        v = _vector(t, "video", "velocity")
        if not np.any(v):
            raise _fail("video.velocity", t["velocity"], "a non-zero camera translation per frame")
        _check_scale("video.velocity", t["velocity"], float(np.max(np.abs(v))), "a speed")
        return VideoSpec(velocity=v)
    if which == "positions":
        p = t["positions"]
        outer = _entries(p, ndim=2)
        rows = [_entries(r) for r in outer or ()]
        if outer is None or len(rows) < 3 or not all(r is not None and len(r) == 3 and _finite_numbers(r) for r in rows):
            expected = "a list of 3 or more [x, y, z] camera positions, one per frame"
            raise _fail("video.positions", p, expected + ("" if outer is not None else _not_a_sequence(p)))
        positions = np.array([[float(v) for v in r] for r in rows])
        _check_steps(positions, "video.positions")
        return VideoSpec(positions=positions)
    path = t["poses"]
    if not isinstance(path, str) or not path:
        raise _fail("video.poses", path, "a path to a CSV file (frame,x,y,z[,rx,ry,rz])")
    full = Path(path)
    if not full.is_absolute() and base is not None:
        full = base / full
    try:
        return VideoSpec(poses=load_poses(full))
    except (FileNotFoundError, InputReadError) as exc:  # (a RigError names the poses file and its line)
        raise type(exc)(f"video.poses = {_show(path)}: {exc}") from None


def rig_from_dict(data: dict, *, base_dir=None, source=None) -> Rig:
    """Build a :class:`Rig` from a parsed TOML document (a dict).

    Parameters
    ----------
    data : dict
        With a ``camera`` table and optionally ``motion``, ``stereo``,
        ``video`` tables (see the module docstring).
    base_dir : path, optional
        Folder against which ``video.poses`` is resolved (the rig file's).
    source : path, optional
        Recorded in :attr:`Rig.source` for messages.

    Raises
    ------
    RigError
        With the key path, the value and what was expected; also an
        invalid ``video.poses`` CSV (:func:`load_poses`).
    FileNotFoundError, nfdepth.io.InputReadError
        If the ``video.poses`` CSV is missing (or a directory) or cannot be
        read; the message starts with ``video.poses = 'its value'``.
    """
    if not isinstance(data, dict):
        raise RigError(f"rig: expected a table of sections, got {type(data).__name__}")
    _check_keys(data, "rig", ("camera", "motion", "stereo", "video"))
    if "camera" not in data:
        raise RigError("camera is missing: expected a [camera] table with focal_px, width_px, height_px")
    base = Path(base_dir) if base_dir is not None else None
    camera = _parse_camera(data["camera"])
    return Rig(
        camera=camera,
        distortion=_parse_distortion(data["camera"], camera),
        motion=_parse_motion(data["motion"]) if "motion" in data else None,
        stereo=_parse_stereo(data["stereo"]) if "stereo" in data else None,
        video=_parse_video(data["video"], base) if "video" in data else None,
        source=Path(source) if source is not None else None,
    )


def _read_toml(path, kind: str) -> tuple[Path, dict]:
    """``(path, parsed document)`` of a TOML file; errors name the ``kind`` of file ("rig", "cameras")."""
    path = as_path("path", path)
    if not path.is_file():
        raise FileNotFoundError(f"cannot read {kind} file '{path}': {'it is a directory' if path.is_dir() else 'no such file'}")
    try:
        return path, tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise RigError(f"{kind} '{path}': not valid TOML: {exc}") from None
    except UnicodeDecodeError:
        raise RigError(f"{kind} '{path}': not a UTF-8 text file") from None
    except OSError as exc:  # e.g. no read permission
        raise InputReadError(f"cannot read {kind} file '{path}': {exc.strerror or exc}") from None


def load_rig(path) -> Rig:
    """Read and validate a rig TOML file.

    Parameters
    ----------
    path : str or os.PathLike
        The rig file, UTF-8 TOML (``docs/rig-format.md``); a relative
        ``video.poses`` path in it is read from the file's folder.

    Returns
    -------
    Rig
        With :attr:`Rig.source` set to ``path`` (as a Path).

    Raises
    ------
    TypeError
        If ``path`` is not a str or os.PathLike.
    FileNotFoundError
        If the file does not exist (or is a directory); also for a missing
        ``video.poses`` CSV (:func:`load_poses`): then the message starts
        with the rig file's name and ``video.poses = 'its value'``.
    nfdepth.io.InputReadError
        If the file or its poses CSV cannot be read (e.g. no read permission);
        for the CSV, named as for a missing one.
    RigError
        For invalid TOML or an invalid rig; the message starts with the file name.
        Also a file that is not UTF-8, and an invalid poses CSV.
    """
    path, data = _read_toml(path, "rig")
    try:
        return rig_from_dict(data, base_dir=path.parent, source=path)
    except (RigError, FileNotFoundError, InputReadError) as exc:  # the last two: its video.poses CSV
        raise type(exc)(f"rig '{path}': {exc}") from None


# ----------------------------------------------------------------- writing


def _toml_value(v) -> str:
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return repr(float(v))


def rig_to_toml(rig: Rig) -> str:
    """TOML text of ``rig``; :func:`rig_from_dict` of its parse gives back an equal rig.

    A ``video.poses`` section is written as the absolute path of its CSV.
    The round trip holds for the rigs :func:`rig_from_dict` builds; a rig built by
    hand may hold what a file cannot: ``VideoSpec.orientations_deg`` is
    refused (a file gives turning frames as ``video.poses``), and a
    ``StereoSpec.direction`` that is not a unit vector reads back normalised.

    Parameters
    ----------
    rig : Rig
        E.g. from :func:`load_rig` or :func:`rig_from_dict`.

    Returns
    -------
    str
        ``[camera]`` (with its principal point ``cx_px``, ``cy_px``), then
        ``[motion]``, ``[stereo]`` and ``[video]`` where the rig has them,
        ending in a newline. :attr:`Rig.source` is not written.

    Raises
    ------
    ValueError
        A video with per-frame orientations (``VideoSpec.orientations_deg``
        not all zero), or with poses that were not read from a file: a rig
        file cannot hold them.
    """
    video = rig.video
    if video is not None and video.orientations_deg is not None and np.any(video.orientations_deg != 0):
        msg = (
            "rig.video has per-frame orientations (orientations_deg), which a rig file cannot hold:"
            " write positions and orientations as a poses CSV (frame,x,y,z,rx,ry,rz in degrees) and give it as video.poses"
        )
        raise ValueError(msg)
    if video is not None and video.velocity is None and video.positions is None and (video.poses is None or video.poses.source is None):
        msg = "rig.video has poses that were not read from a file: a rig file names the poses CSV (video.poses), so save them as one first"
        raise ValueError(msg)
    cam = rig.camera
    lines = ["[camera]", f"focal_px = {_toml_value(cam.focal_px)}", f"width_px = {cam.width_px}", f"height_px = {cam.height_px}"]
    lines += [f"cx_px = {_toml_value(cam.cx_px)}", f"cy_px = {_toml_value(cam.cy_px)}"]
    if rig.distortion:
        lines.append(f"distortion = {_toml_value(list(rig.distortion))}")
    if rig.motion is not None:
        m = rig.motion
        lines += ["", "[motion]", f"velocity = {_toml_value(m.velocity)}", f"rotation_deg = {_toml_value(m.rotation_deg)}"]
        lines.append(f"frame_interval = {_toml_value(m.frame_interval)}")
        if m.crossings is not None:
            lines.append(f"crossings = {_toml_value(list(m.crossings))}")
    if rig.stereo is not None:
        s = rig.stereo
        lines += ["", "[stereo]", f"baseline = {_toml_value(s.baseline)}"]
        lines.append(f"axis = {_toml_value(s.axis)}" if s.axis else f"direction = {_toml_value(s.direction)}")
        if s.positions is not None:
            lines.append(f"positions = {_toml_value(s.positions)}")
        if s.column_positions is not None:
            lines.append(f"column_positions = {_toml_value(s.column_positions)}")
        if s.disparity_range_px is not None:
            lines.append(f"disparity_range_px = {_toml_value(s.disparity_range_px)}")
        if s.disparity_offset_px:
            lines.append(f"disparity_offset_px = {_toml_value(s.disparity_offset_px)}")
    if rig.video is not None:
        v = rig.video
        lines += ["", "[video]"]
        if v.velocity is not None:
            lines.append(f"velocity = {_toml_value(v.velocity)}")
        elif v.positions is not None:
            lines.append(f"positions = {_toml_value([list(p) for p in v.positions])}")
        else:
            lines.append(f"poses = {_toml_value(str(Path(v.poses.source).resolve()))}")
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------- adapters


def stereo_options_from_rig(rig: Rig, *, n_views: int | None = None, n_column_views: int | None = None) -> dict:
    """Options of ``nfdepth stereo`` from ``[camera]`` and ``[stereo]``.

    :func:`nfdepth.stereo.static_stereo` handles rows along +x or +y only, so
    a ``direction`` must be one of those.

    Parameters
    ----------
    rig : Rig
        A rig with a ``[stereo]`` section.
    n_views, n_column_views : int, optional
        ``n_views`` / ``n_column_views``, when given, are the numbers of views of
        the row / column the options are for (integers >= 1): ``stereo.positions`` /
        ``stereo.column_positions`` must then hold one entry per view.

    Returns
    -------
    dict
        ``dict(focal_px=..., baseline=..., axis="x"|"y", positions=list|None,
        column_positions=list|None, disparity_range_px=list|None,
        disparity_offset_px=float, cx_px=float, cy_px=float)`` (the principal
        point is the camera's, the image centre where the file gives none).
        ``focal_px``, ``cx_px``, ``cy_px`` in px; ``baseline`` in scene units;
        positions in units of the baseline; ``disparity_range_px`` and
        ``disparity_offset_px`` in px per unit position.

    Raises
    ------
    RigError
        (starting ``rig 'FILE':`` when the rig was read from a file) naming
        the key, its value and what was expected: a ``stereo.direction`` not
        along ``[1, 0, 0]`` or ``[0, 1, 0]`` (of any length), or positions whose count is not
        ``n_views`` / ``n_column_views``. Also for a rig without ``[stereo]``.
    TypeError, ValueError
        If ``n_views`` or ``n_column_views`` is given and is not an integer
        >= 1 (a bool, a str or a float is refused as well); how many views
        stereo needs is :func:`nfdepth.stereo.static_stereo`'s to check.
    """
    n_views = None if n_views is None else check_int("n_views", n_views, 1)
    n_column_views = None if n_column_views is None else check_int("n_column_views", n_column_views, 1)
    s = rig._need("stereo")
    where = f"rig '{rig.source}': " if rig.source is not None else ""
    axis = s.axis
    if axis is None:
        unit = _unit(s.direction)  # (a hand-built spec: a file's is normalised)
        for name, vec in _AXES.items():
            if unit is not None and np.allclose(unit, vec, atol=1e-9):
                axis = name
        if axis is None:
            expected = "[1, 0, 0] or [0, 1, 0] for nfdepth stereo (order the views so the camera moves toward +x or +y)"
            raise RigError(f"{where}{_fail('stereo.direction', s.direction, expected)}")
    for key, values, count, views in (("positions", s.positions, n_views, "view"), ("column_positions", s.column_positions, n_column_views, "column view")):
        if values is not None and count is not None and len(values) != count:
            raise RigError(f"{where}stereo.{key} has {len(values)} entries, expected one per {views} ({count})")
    return {
        "focal_px": float(rig.camera.focal_px),
        "baseline": float(s.baseline),
        "axis": axis,
        "positions": list(s.positions) if s.positions is not None else None,
        "column_positions": list(s.column_positions) if s.column_positions is not None else None,
        "disparity_range_px": list(s.disparity_range_px) if s.disparity_range_px is not None else None,
        "disparity_offset_px": float(s.disparity_offset_px),
        "cx_px": float(rig.camera.cx_px),
        "cy_px": float(rig.camera.cy_px),
    }


#: What a rig gives :func:`nfdepth.pipelines.dynamic_stereo`, and from which of its keys: no option of :func:`dynamic_stereo_from_rig`.
_RIG_GIVEN = {"camera": "[camera]", "relative_motion": "[motion]", "frame_interval": "[motion] frame_interval"}


def _check_dynamic_options(options) -> None:
    """Refuse what ``options`` for :func:`~nfdepth.pipelines.dynamic_stereo` cannot hold beside a rig: what the rig gives, unknown names."""
    from .pipelines import dynamic_stereo

    for name in options:
        if name in _RIG_GIVEN:
            msg = f"{name} comes from the rig ({_RIG_GIVEN[name]}), not from an option: edit the rig file or give the rig object another one"
            raise TypeError(msg)
    takes = [p for p in inspect.signature(dynamic_stereo).parameters if p != "frames" and p not in _RIG_GIVEN]
    unknown = [name for name in options if name not in takes]
    if unknown:
        msg = f"unknown option{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))} for dynamic stereo: expected some of {', '.join(takes)}"
        raise TypeError(msg)


def dynamic_stereo_from_rig(frames, rig: Rig, **options):
    """:func:`nfdepth.pipelines.dynamic_stereo` with the camera, relative motion and frame interval of ``rig``.

    ``frames`` are ``I1 .. I5`` (see :func:`nfdepth.pipelines.dynamic_stereo`);
    their size is checked against ``[camera]`` (:class:`RigError`), and its
    lens distortion undone first (:meth:`Rig.undistort`).
    ``options`` go to :func:`~nfdepth.pipelines.dynamic_stereo` (``sigma_px``, ...);
    one the rig gives (``camera``, ``relative_motion``, ``frame_interval``) or
    an unknown name is a ``TypeError`` that says so.
    This is the library form of ``nfdepth dynamic``.

    Parameters
    ----------
    frames : iterable of 5 array_like, shape (H, W)
        Grey images ``I1 .. I5`` of ``[camera]``'s size (``height_px`` rows,
        ``width_px`` columns).
    rig : Rig
        A rig with a ``[motion]`` section.
    **options
        Further keyword arguments of :func:`~nfdepth.pipelines.dynamic_stereo`.

    Returns
    -------
    nfdepth.pipelines.EdgeDepth
        As :func:`~nfdepth.pipelines.dynamic_stereo` returns it, on the
        undistorted pixel grid; depth in the scene units of ``motion.velocity``.

    Raises
    ------
    TypeError
        An option the rig gives or an unknown option; a frame that is not
        numbers (None, a path, text), named ``frames[k]`` (0-based) as
        :func:`~nfdepth.pipelines.dynamic_stereo` names it.
    ValueError
        Not exactly 5 frames, or frames that
        :func:`~nfdepth.pipelines.dynamic_stereo` refuses (not 2-D, ...),
        checked before their size.
    RigError
        A frame whose size is not ``[camera]``'s, or a rig without ``[motion]``.
    """
    from .pipelines import dynamic_stereo

    _check_dynamic_options(options)
    frames = list(frames)
    if len(frames) != 5:
        raise ValueError(f"dynamic stereo needs exactly 5 images I1..I5, got {len(frames)}")
    dtype = float_dtype(options.get("dtype", np.float32))
    checked = []
    for k, f in enumerate(frames):  # checked as dynamic_stereo checks them (a 1-D, None or text frame), then their size
        check_frame_size(f"frames[{k}]", np.shape(f))
        checked.append(as_image(f"frames[{k}]", f, dtype))
        rig.check_image_shape(checked[-1].shape, what=f"image I{k + 1}")
    frames = checked
    if any(rig.distortion):  # the undistortion reads grey images only
        frames = [rig.undistort(f) for f in frames]
    return dynamic_stereo(frames, camera=rig.camera, relative_motion=rig.relative_motion(), frame_interval=rig.frame_interval, **options)


def edge_depth_maps(result) -> tuple[np.ndarray, np.ndarray]:
    """Depth and its std at the edge points of an :class:`~nfdepth.pipelines.EdgeDepth`, as images.

    Returns two float32 ``(H, W)`` maps, NaN off the edge points (and where a
    point has no depth). Map pixel ``[i, j]`` holds the point at the cell
    centre ``(i + 0.5, j + 0.5)`` (:mod:`nfdepth.normal_flow`); the exact
    sub-pixel positions are ``result.rows``, ``result.cols``.
    """
    h, w = result.camera.shape
    depth = np.full((h, w), np.nan, dtype=np.float32)
    std = np.full((h, w), np.nan, dtype=np.float32)
    from .pipelines import _point_pixels

    ok = result.valid
    ii, jj = _point_pixels(result.rows[ok], result.cols[ok], (h, w))
    depth[ii, jj] = result.depth[ok]
    std[ii, jj] = result.depth_std[ok]
    return depth, std
