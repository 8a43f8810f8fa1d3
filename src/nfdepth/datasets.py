"""The real multi-view data sets with ground truth (third-party, see shared/data).

Each loader returns a :class:`MultiViewScene`: grey float32 views ordered so
the camera moves toward +X from the first to the last (scene points shift
toward -col), the index of the view that has ground truth, and the
ground-truth **neighbour-step** disparity ``d`` at that view, in pixels: pixel
``(row, col)`` of the reference view is seen at ``(row, col - k d)`` in view
``reference_index + k``. Where focal length and baseline are published,
``Z = f b / (d + offset)``.

The data live outside the package; :func:`data_root` finds them (argument,
``NFDEPTH_DATA``, ``../shared/data``, the folder that ``nfdepth fetch-data``
downloads into: :func:`nfdepth.fetch.fetch_data`). Sets and their ``SOURCE.md``:

=====================  ===================  ==========  ======================
name                   views (reference)    disparity   depth
=====================  ===================  ==========  ======================
``tsukuba``            col1..col5 (col3)    v / 16      up to scale
``teddy``              im0..im8 (im2)       v / 16      up to scale
``middlebury2005/S``   view0..view6 (view1) v / 8       1870 px, 40 mm, dmin/8
``motorcycle``         left, right (left)   float       994.978 px, 193.001 mm
=====================  ===================  ==========  ======================

``S`` is one of Art, Books, Dolls, Moebius, Reindeer.
"""

from __future__ import annotations

import dataclasses
import math
import os
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from . import fetch as _fetch
from ._validate import NFDepthError
from .io import ImageReadError, read_image

__all__ = [
    "DataNotFoundError",
    "DataFileError",
    "MultiViewScene",
    "MIDDLEBURY2005_SCENES",
    "data_root",
    "list_scenes",
    "missing_scene_files",
    "load_scene",
    "load_tsukuba",
    "load_teddy",
    "load_middlebury2005",
    "load_motorcycle",
    "downsample_scene",
    "view_subset",
]

ENV_VAR = "NFDEPTH_DATA"
MIDDLEBURY2005_SCENES = ("Art", "Books", "Dolls", "Moebius", "Reindeer")

_TSUKUBA_SOURCE = (
    "Tsukuba 'head and lamp' (University of Tsukuba; Nakamura et al., CVPR 1996), Middlebury 2001 distribution "
    "(Scharstein & Szeliski, IJCV 2002)"
)
_TEDDY_SOURCE = "Middlebury 2003 'Teddy', quarter size (Scharstein & Szeliski, CVPR 2003)"
_MB2005_SOURCE = (
    "Middlebury 2005 '{scene}', half size (Scharstein & Pal, CVPR 2007; Hirschmüller & Scharstein, CVPR 2007)"
)
_MOTORCYCLE_SOURCE = (
    "Middlebury 2014 'Motorcycle' as shipped in scikit-image, downsampled 4x (Scharstein et al., GCPR 2014)"
)


class DataNotFoundError(NFDepthError):
    """The real data (or one of its files) could not be found."""


class DataFileError(DataNotFoundError):
    """A data set's file is there but unusable (unreadable, another size than the views, no known disparity)."""


# ------------------------------------------------------------------ the root


def _repo_candidate() -> Path | None:
    here = Path(__file__).resolve()
    for parent in here.parents:
        cand = parent / "shared" / "data"
        if cand.is_dir():
            return cand
    return None


def _download_candidate() -> Path | None:
    """The default download folder of ``nfdepth fetch-data`` if it holds at least one complete set.

    A set counts once its ``SHA256SUMS`` is written (after all its files
    matched their hashes). Tests replace this function (or
    :func:`nfdepth.fetch.default_data_dir`) to stay hermetic.
    """
    try:
        folder = _fetch.default_data_dir()
    except (OSError, RuntimeError):  # no home directory
        return None
    if any((folder / name / "SHA256SUMS").is_file() for name in _fetch.DATA_SETS):
        return folder
    return None


def data_root(path=None) -> Path:
    """Find the folder holding the real data sets.

    Tried in order: ``path`` if given (only it); else the environment
    variable ``NFDEPTH_DATA`` if set (only it); else ``../shared/data``
    relative to the current working directory; else a ``shared/data`` folder
    beside one of the folders above this file (the repository's sibling);
    else the default download folder of ``nfdepth fetch-data``
    (:func:`nfdepth.fetch.default_data_dir`) if it holds at least one set.

    Parameters
    ----------
    path : str or os.PathLike, optional
        An explicit data folder.

    Returns
    -------
    pathlib.Path
        The resolved folder.

    Raises
    ------
    DataNotFoundError
        Naming every place tried, how to set ``NFDEPTH_DATA`` and how to
        download the data (``nfdepth fetch-data``).
    """
    hint = f"set {ENV_VAR}=/path/to/shared/data or pass the folder (--data DIR; root=... in Python), or download the data with `nfdepth fetch-data`"
    if path is not None:
        p = Path(path).expanduser()
        if p.is_dir():
            return p.resolve()
        raise DataNotFoundError(f"data folder not found: root={str(p)!r} is not a directory ({hint})")
    env = os.environ.get(ENV_VAR)
    if env:
        p = Path(env).expanduser()
        if p.is_dir():
            return p.resolve()
        raise DataNotFoundError(f"data folder not found: {ENV_VAR}={env!r} is not a directory; point {ENV_VAR} at the shared/data folder (or at a folder filled by `nfdepth fetch-data --dest DIR`)")
    tried = []
    cwd_cand = Path.cwd() / ".." / "shared" / "data"
    tried.append(str(cwd_cand.resolve()))
    if cwd_cand.is_dir():
        return cwd_cand.resolve()
    repo = _repo_candidate()
    if repo is not None:
        return repo.resolve()
    tried.append(f"a shared/data folder beside any parent of {Path(__file__).resolve().parent}")
    downloaded = _download_candidate()
    if downloaded is not None:
        return downloaded.resolve()
    try:
        tried.append(f"the download folder {_fetch.default_data_dir()} (no data set there)")
    except (OSError, RuntimeError):
        tried.append("the download folder (no home directory)")
    raise DataNotFoundError(f"data folder not found; tried {ENV_VAR} (not set), " + ", ".join(tried) + f"; {hint}")


# ------------------------------------------------------------------ the scene


@dataclass
class MultiViewScene:
    """Rectified views along +X with ground-truth disparity at one of them.

    Attributes
    ----------
    name : str
        E.g. ``"tsukuba"``, ``"middlebury2005/Art"``.
    views : list of ndarray, float32, shape (H, W)
        Grey views (BT.601 luma, 0..255), ordered so that the camera moves
        toward +X from first to last, equally spaced.
    reference_index : int
        Index into ``views`` of the view with ground truth.
    disparity : ndarray, float32, shape (H, W)
        Neighbour-step disparity at the reference view in pixels (NaN where
        unknown): pixel ``(row, col)`` is seen at ``(row, col - k d)`` in
        view ``reference_index + k``.
    focal_px : float or None
        Focal length in pixels, None where unpublished.
    baseline : float or None
        Spacing of neighbouring views, in ``baseline_unit``; None where
        unpublished.
    baseline_unit : str or None
        Unit of ``baseline`` (``"mm"``), and of :meth:`depth`.
    disparity_offset_px : float
        Added to ``disparity`` before depth: ``Z = f b / (d + offset)``
        (``dmin/8`` for Middlebury 2005 half size, ``doffs`` for Motorcycle,
        0 otherwise).
    colour_reference : ndarray, uint8, shape (H, W, 3)
        The reference view in colour (RGB), for point-cloud colours.
    source : str
        Citation line.
    principal_point_px : tuple of float or None
        ``(cx, cy)`` where published, else None (image centre).
    truth_step_px : float or None
        Resolution of ``disparity``: the step in which its values are
        stored or labelled, in neighbour-step px (1/8 for Middlebury 2005
        half size, 1/16 for Teddy, 1 for Tsukuba's whole-pixel labels);
        None where the truth is stored as floats. Rounding to it alone
        gives a perfect estimate an error of up to half a step
        (:func:`nfdepth.evaluate.disparity_errors` reports that floor).
    """

    name: str
    views: list
    reference_index: int
    disparity: np.ndarray
    focal_px: float | None
    baseline: float | None
    baseline_unit: str | None
    disparity_offset_px: float
    colour_reference: np.ndarray
    source: str
    principal_point_px: tuple | None = field(default=None)
    truth_step_px: float | None = field(default=None)

    @property
    def reference(self) -> np.ndarray:
        """The reference view (grey float32)."""
        return self.views[self.reference_index]

    @property
    def shape(self) -> tuple:
        """(H, W) of every view."""
        return self.views[0].shape

    @property
    def valid(self) -> np.ndarray:
        """Boolean mask of pixels with known disparity."""
        return np.isfinite(self.disparity)

    @property
    def has_metric_depth(self) -> bool:
        """True when focal length and baseline are known."""
        return self.focal_px is not None and self.baseline is not None

    def depth(self) -> np.ndarray:
        """Depth ``Z = f b / (d + offset)`` at the reference view, in ``baseline_unit``.

        Returns
        -------
        ndarray, float32, shape (H, W)
            NaN where the disparity is unknown (or ``d + offset <= 0``).

        Raises
        ------
        ValueError
            If focal length or baseline is not published for this scene.
        """
        if not self.has_metric_depth:
            msg = (
                f"scene {self.name!r} has no published focal length and baseline "
                f"(focal_px={self.focal_px!r}, baseline={self.baseline!r}); depth is known only up to scale, "
                "use the disparity (Z is proportional to 1/d)"
            )
            raise ValueError(msg)
        denom = self.disparity.astype(np.float64) + self.disparity_offset_px
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(denom > 0, self.focal_px * self.baseline / denom, np.nan)
        return z.astype(np.float32)

    def __repr__(self) -> str:  # arrays would flood the console
        h, w = self.shape
        return (
            f"MultiViewScene(name={self.name!r}, views={len(self.views)} x {h}x{w}, "
            f"reference_index={self.reference_index}, focal_px={self.focal_px!r}, "
            f"baseline={self.baseline!r} {self.baseline_unit or ''}, disparity_offset_px={self.disparity_offset_px!r})"
        )


# ------------------------------------------------------------------ loaders


def _require(name: str, paths) -> None:
    """Every file of scene ``name`` there: :class:`DataNotFoundError` for a missing one, :class:`DataFileError` for a directory (or another non-file) in its place."""
    for p in paths:
        if p.is_file():
            continue
        if not p.exists():
            raise DataNotFoundError(f"data file missing: '{p}' (check the data folder or set {ENV_VAR})")
        what = "it is a directory, not a file" if p.is_dir() else "it is not a regular file"
        raise DataFileError(f"scene {name!r}: cannot read '{p}': {what}; is the data folder intact?")


def _read_image(name: str, path: Path, **kwargs) -> np.ndarray:
    """:func:`nfdepth.io.read_image`, an unreadable file a :class:`DataFileError` of scene ``name`` (with the reader's reason)."""
    try:
        return read_image(path, **kwargs)
    except ImageReadError as exc:
        raise DataFileError(f"scene {name!r}: {exc}") from None


def _read_views(name: str, paths) -> list:
    return [_read_image(name, p, grey=True, dtype=np.float32) for p in paths]


def _read_colour(name: str, path: Path) -> np.ndarray:
    img = _read_image(name, path, grey=False, dtype=None)
    if img.ndim == 2:
        img = np.repeat(img[..., None], 3, axis=2)
    img = img[..., :3]
    if img.dtype != np.uint8:
        img = np.clip(np.rint(img.astype(np.float64)), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(img)


def _read_coded_disparity(name: str, path: Path, divisor: float) -> np.ndarray:
    v = _read_image(name, path, grey=False, dtype=None)
    if v.ndim == 3:
        if not all(np.array_equal(v[..., 0], v[..., c]) for c in range(1, min(v.shape[-1], 3))):
            raise DataFileError(f"scene {name!r}: cannot read image '{path}': expected a grey disparity map, got colour")
        v = v[..., 0]
    d = v.astype(np.float32) / np.float32(divisor)
    d[v == 0] = np.nan
    return d


def _size(shape) -> str:
    return f"{shape[1]}x{shape[0]} px"


def _check_shapes(name: str, views, disparity, paths, disparity_path) -> None:
    """The views of one size and the ground truth of theirs, with at least one known disparity (else :class:`DataFileError`)."""
    first = views[0].shape
    for view, path in zip(views, paths):
        if view.shape != first:
            raise DataFileError(f"scene {name!r}: view '{path}' is {_size(view.shape)}, '{paths[0]}' {_size(first)}; are the files intact?")
    if disparity.shape != first:
        raise DataFileError(
            f"scene {name!r}: ground truth '{disparity_path}' is {_size(disparity.shape)} but the views are {_size(first)}; are the files intact?"
        )
    if not np.isfinite(disparity).any():
        raise DataFileError(f"scene {name!r}: ground truth '{disparity_path}' holds no known disparity (every pixel is coded unknown); is the file intact?")


def load_tsukuba(root=None) -> MultiViewScene:
    """Tsukuba: 5 views ``scene1.row3.col1..5``, ground truth at col3 (index 2).

    Disparity ``d = v / 16`` px between neighbours (5..14 px), ``v = 0``
    (20.7 %, a border band) is NaN. Focal length and baseline unpublished.

    Parameters
    ----------
    root : str or os.PathLike, optional
        Data folder; see :func:`data_root`. The files are read from its
        ``tsukuba`` folder.

    Returns
    -------
    MultiViewScene
        Named ``"tsukuba"``: 5 views ``col1 .. col5``, ``reference_index`` 2,
        ``truth_step_px`` 1 (hand-labelled whole-pixel layers); ``focal_px``,
        ``baseline`` None and ``disparity_offset_px`` 0 (depth only up to scale).

    Raises
    ------
    DataNotFoundError
        If the data root or one of the scene's files (``scene1.row3.col1.ppm``
        .. ``col5.ppm``, ``truedisp.row3.col3.pgm``) is missing.
    DataFileError
        (a DataNotFoundError) If a file is there but unreadable (a
        directory, broken, not an image: the message names the scene, the
        file and the reason), the ground truth is in colour, the views
        differ in size, or the ground truth is of another size or holds no
        known disparity.
    """
    folder = data_root(root) / "tsukuba"
    views_p = [folder / f"scene1.row3.col{k}.ppm" for k in range(1, 6)]
    disp_p = folder / "truedisp.row3.col3.pgm"
    _require("tsukuba", [*views_p, disp_p])
    views = _read_views("tsukuba", views_p)
    disp = _read_coded_disparity("tsukuba", disp_p, 16.0)
    _check_shapes("tsukuba", views, disp, views_p, disp_p)
    # hand-labelled whole-pixel layers: every v is a multiple of 16
    colour = _read_colour("tsukuba", views_p[2])
    return MultiViewScene("tsukuba", views, 2, disp, None, None, None, 0.0, colour, _TSUKUBA_SOURCE, truth_step_px=1.0)


def load_teddy(root=None) -> MultiViewScene:
    """Middlebury 2003 Teddy: 9 views ``im0..im8``, ground truth at im2 (index 2).

    Disparity ``d = v / 16`` px between neighbours (3.1..13.2 px) from
    ``disp2.pgm``; ``v = 0`` (2.0 %) is NaN. Focal length and baseline
    unpublished.

    Parameters
    ----------
    root : str or os.PathLike, optional
        Data folder; see :func:`data_root`. The files are read from its
        ``middlebury2003-teddy`` folder.

    Returns
    -------
    MultiViewScene
        Named ``"teddy"``: 9 views ``im0 .. im8``, ``reference_index`` 2,
        ``truth_step_px`` 1/16 (``v``, a whole number, is 4 times the
        disparity between im2 and im6, 4 view steps apart); ``focal_px``,
        ``baseline`` None and ``disparity_offset_px`` 0 (depth only up to scale).

    Raises
    ------
    DataNotFoundError
        If the data root or one of the scene's files (``im0.png`` ..
        ``im8.png``, ``disp2.pgm``) is missing.
    DataFileError
        (a DataNotFoundError) If a file is there but unreadable (a
        directory, broken, not an image: the message names the scene, the
        file and the reason), the ground truth is in colour, the views
        differ in size, or the ground truth is of another size or holds no
        known disparity.
    """
    folder = data_root(root) / "middlebury2003-teddy"
    views_p = [folder / f"im{k}.png" for k in range(9)]
    disp_p = folder / "disp2.pgm"
    _require("teddy", [*views_p, disp_p])
    views = _read_views("teddy", views_p)
    disp = _read_coded_disparity("teddy", disp_p, 16.0)
    _check_shapes("teddy", views, disp, views_p, disp_p)
    colour = _read_colour("teddy", views_p[2])
    return MultiViewScene("teddy", views, 2, disp, None, None, None, 0.0, colour, _TEDDY_SOURCE, truth_step_px=1.0 / 16.0)


def _scene_name_2005(scene) -> str:
    if not isinstance(scene, str):
        msg = f"scene must be a str, one of {', '.join(MIDDLEBURY2005_SCENES)}; got {type(scene).__name__}"
        raise TypeError(msg)
    for s in MIDDLEBURY2005_SCENES:
        if s.lower() == scene.lower():
            return s
    msg = f"scene must be one of {', '.join(MIDDLEBURY2005_SCENES)}, got {scene!r}"
    raise ValueError(msg)


def load_middlebury2005(scene: str, root=None) -> MultiViewScene:
    """Middlebury 2005 half size: 7 views ``view0..view6``, ground truth at view1 (index 1).

    Disparity ``d = v / 8`` px between neighbours from ``disp1.png``
    (``v = 0`` is NaN); ``dmin`` from ``dmin.txt`` (full-size px) gives
    ``disparity_offset_px = dmin / 8``; ``f = 1870`` px, neighbour spacing
    ``b = 40`` mm (values used by several code bases; see SOURCE.md caveat).

    Parameters
    ----------
    scene : str
        One of Art, Books, Dolls, Moebius, Reindeer (case-insensitive).
    root : str or os.PathLike, optional
        Data folder; see :func:`data_root`.

    Raises
    ------
    TypeError, ValueError
        If ``scene`` is not one of the five names.
    DataNotFoundError
        If the data root or one of the scene's files (``view0.png`` ..
        ``view6.png``, ``disp1.png``, ``dmin.txt``) is missing.
    DataFileError
        (a DataNotFoundError) If a file is there but unreadable (a
        directory, a broken image, a ``dmin.txt`` that is not UTF-8 text or
        holds no number: the message names the scene, the file and the
        reason), the ground truth is in colour, the views differ in size,
        or the ground truth is of another size or holds no known disparity.
    """
    scene = _scene_name_2005(scene)
    folder = data_root(root) / "middlebury2005" / scene
    views_p = [folder / f"view{k}.png" for k in range(7)]
    disp_p = folder / "disp1.png"
    dmin_p = folder / "dmin.txt"
    name = f"middlebury2005/{scene}"
    _require(name, [*views_p, disp_p, dmin_p])
    try:
        text = dmin_p.read_text(encoding="utf-8").strip()
    except (OSError, UnicodeDecodeError) as exc:
        reason = (exc.strerror or exc) if isinstance(exc, OSError) else f"not UTF-8 text ({exc})"
        raise DataFileError(f"scene {name!r}: cannot read '{dmin_p}': {reason}; expected one number (dmin in full-size px)") from None
    try:
        dmin = float(text.split()[0])
        if not math.isfinite(dmin):  # nan or inf: every depth of the scene would be NaN
            raise ValueError
    except (ValueError, IndexError):
        raise DataFileError(f"scene {name!r}: '{dmin_p}' should hold one finite number (dmin in full-size px), got {text!r}") from None
    views = _read_views(name, views_p)
    disp = _read_coded_disparity(name, disp_p, 8.0)
    _check_shapes(name, views, disp, views_p, disp_p)
    return MultiViewScene(
        name, views, 1, disp, 1870.0, 40.0, "mm", dmin / 8.0, _read_colour(name, views_p[1]), _MB2005_SOURCE.format(scene=scene),
        truth_step_px=1.0 / 8.0,
    )


def load_motorcycle(root=None) -> MultiViewScene:
    """Middlebury 2014 Motorcycle (scikit-image copy): 2 views, ground truth at the left (index 0).

    Disparity from ``motorcycle_disp.npz`` (``arr_0``, px; ``+inf`` is NaN),
    ``f = 994.978`` px, ``b = 193.001`` mm, ``doffs = 31.086`` px, principal
    point ``(311.193, 254.877)`` px.

    Parameters
    ----------
    root : str or os.PathLike, optional
        Data folder; see :func:`data_root`. The files are read from its
        ``skimage-motorcycle`` folder.

    Returns
    -------
    MultiViewScene
        Named ``"motorcycle"``: views ``[left, right]``, ``reference_index`` 0,
        the disparity as stored (float32 px, every non-finite value NaN),
        ``focal_px`` 994.978, ``baseline`` 193.001, ``baseline_unit``
        ``"mm"``, ``disparity_offset_px`` 31.086, ``principal_point_px``
        ``(311.193, 254.877)``, ``truth_step_px`` None: :meth:`MultiViewScene.depth`
        in mm.

    Raises
    ------
    DataNotFoundError
        If the data root or one of the scene's files (``motorcycle_left.png``,
        ``motorcycle_right.png``, ``motorcycle_disp.npz``) is missing.
    DataFileError
        (a DataNotFoundError) If a file is there but unreadable (a
        directory, a view that cannot be decoded, an ``.npz`` that cannot
        be read or has no ``arr_0``: the message names the scene, the file
        and the reason), the views differ in size, or the disparity is of
        another size or holds no known value.
    """
    folder = data_root(root) / "skimage-motorcycle"
    views_p = [folder / "motorcycle_left.png", folder / "motorcycle_right.png"]
    disp_p = folder / "motorcycle_disp.npz"
    _require("motorcycle", [*views_p, disp_p])
    views = _read_views("motorcycle", views_p)
    reason = None
    try:
        with open(disp_p, "rb") as fh:  # np.load would leave its own handle open on a broken zip
            z = np.load(fh, allow_pickle=False)
            if isinstance(z, np.lib.npyio.NpzFile):
                with z:
                    disp = np.asarray(z["arr_0"], dtype=np.float32).copy()
            else:
                reason = "expected an .npz archive holding arr_0, got a single .npy array"
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        reason = str(exc)
    if reason is not None:
        raise DataFileError(f"scene 'motorcycle': cannot read disparity '{disp_p}': {reason}")
    disp[~np.isfinite(disp)] = np.nan
    _check_shapes("motorcycle", views, disp, views_p, disp_p)
    return MultiViewScene(
        "motorcycle", views, 0, disp, 994.978, 193.001, "mm", 31.086, _read_colour("motorcycle", views_p[0]), _MOTORCYCLE_SOURCE,
        principal_point_px=(311.193, 254.877),
    )


_SCENE_FILES = {
    "tsukuba": ("tsukuba", ["truedisp.row3.col3.pgm"] + [f"scene1.row3.col{k}.ppm" for k in range(1, 6)]),
    "teddy": ("middlebury2003-teddy", ["disp2.pgm"] + [f"im{k}.png" for k in range(9)]),
    **{
        f"middlebury2005/{s}": (f"middlebury2005/{s}", ["disp1.png", "dmin.txt"] + [f"view{k}.png" for k in range(7)])
        for s in MIDDLEBURY2005_SCENES
    },
    "motorcycle": ("skimage-motorcycle", ["motorcycle_left.png", "motorcycle_right.png", "motorcycle_disp.npz"]),
}


def list_scenes(root=None) -> list:
    """Names of the scenes whose files are all present under the data root.

    The files are only looked for, not read: :func:`load_scene` may still
    refuse a scene listed here.

    Parameters
    ----------
    root : str or os.PathLike, optional
        Data folder; see :func:`data_root`.

    Returns
    -------
    list of str
        E.g. ``["tsukuba", "teddy", "middlebury2005/Art", ..., "motorcycle"]``.

    Raises
    ------
    DataNotFoundError
        If no data root is found.
    """
    base = data_root(root)
    return [name for name, (sub, files) in _SCENE_FILES.items() if all((base / sub / f).is_file() for f in files)]


def missing_scene_files(name: str, root=None) -> list:
    """The files of scene ``name`` (as :func:`list_scenes` names it) absent under the data root; empty when it is complete.

    Raises
    ------
    ValueError
        For an unknown name.
    DataNotFoundError
        If no data root is found.
    """
    if name not in _SCENE_FILES:
        msg = f"name must be one of {', '.join(_SCENE_FILES)}, got {name!r}"
        raise ValueError(msg)
    sub, files = _SCENE_FILES[name]
    folder = data_root(root) / sub
    return [folder / f for f in files if not (folder / f).is_file()]


def load_scene(name: str, root=None) -> MultiViewScene:
    """Load a scene by name (see :func:`list_scenes`; case-insensitive).

    Parameters
    ----------
    name : str
        ``"tsukuba"``, ``"teddy"`` (also ``"middlebury2003/teddy"``,
        ``"middlebury2003-teddy"``), ``"middlebury2005/S"`` with ``S`` one of
        :data:`MIDDLEBURY2005_SCENES`, or ``"motorcycle"`` (also
        ``"skimage-motorcycle"``); surrounding spaces are ignored.
    root : str or os.PathLike, optional
        Data folder; see :func:`data_root`.

    Returns
    -------
    MultiViewScene
        As :func:`load_tsukuba`, :func:`load_teddy`,
        :func:`load_middlebury2005` or :func:`load_motorcycle` load it.

    Raises
    ------
    TypeError
        If ``name`` is not a str.
    ValueError
        For an unknown name (the message lists the known ones).
    DataNotFoundError
        If the data root or one of the scene's files is missing.
    DataFileError
        (a DataNotFoundError) If a file is there but unusable: unreadable
        (a directory, an image that cannot be decoded, a ``dmin.txt`` that
        is not UTF-8 text or holds no number, a broken Motorcycle ``.npz``;
        the message names the scene, the file and the reason), a
        ground-truth image in colour, views of different sizes, or a ground
        truth of another size than the views or with no known disparity.
    """
    if not isinstance(name, str):
        msg = f"name must be a str such as 'tsukuba', got {type(name).__name__}"
        raise TypeError(msg)
    key = name.strip().lower()
    if key == "tsukuba":
        return load_tsukuba(root)
    if key in ("teddy", "middlebury2003/teddy", "middlebury2003-teddy"):
        return load_teddy(root)
    if key in ("motorcycle", "skimage-motorcycle"):
        return load_motorcycle(root)
    if key.startswith("middlebury2005/"):
        sub = key.split("/", 1)[1]
        if sub in (s.lower() for s in MIDDLEBURY2005_SCENES):
            return load_middlebury2005(sub, root)
    msg = f"name must be one of {', '.join(_SCENE_FILES)}, got {name!r}"
    raise ValueError(msg)


# ------------------------------------------------------------------ transforms


def _check_factor(factor, name: str = "factor") -> int:
    """A downsampling factor: a positive integer (an integral float such as 2.0 too); TypeError for a bool or text."""
    msg = f"{name} must be a positive integer, got {factor!r}"
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer, float, np.floating)):
        raise TypeError(msg)
    if not np.isfinite(factor) or float(factor) != int(factor) or int(factor) < 1:
        raise ValueError(msg)
    return int(factor)


def _block_view(a: np.ndarray, k: int) -> np.ndarray:
    h, w = a.shape[0] // k, a.shape[1] // k
    return a[: h * k, : w * k].reshape(h, k, w, k, *a.shape[2:])


def downsample_scene(scene: MultiViewScene, factor, *, min_valid_fraction: float = 0.5) -> MultiViewScene:
    """Downsample a scene by an integer factor (area averaging).

    Views and the colour reference are cropped to a multiple of ``factor``
    at the bottom and right and averaged over ``factor x factor`` blocks
    (``cv2.INTER_AREA``). The disparity is averaged the same way and divided
    by ``factor``, NaN-aware: a block's value is the mean of its valid
    (finite) pixels if at least ``min_valid_fraction`` of the block is
    valid, else NaN (``min_valid_fraction=1`` makes any NaN in a block give
    NaN). ``focal_px`` and ``disparity_offset_px`` are divided by
    ``factor``; the baseline is unchanged, so :meth:`MultiViewScene.depth`
    is preserved. ``truth_step_px`` is divided by ``factor`` too (a bound:
    averaging a block's rounded values can only shrink its rounding error). A principal point maps as ``c' = (c + 0.5) / factor - 0.5``
    (pixel centres).

    Parameters
    ----------
    scene : MultiViewScene
    factor : int
        Positive integer; 1 returns an equal copy.
    min_valid_fraction : float, keyword-only
        In (0, 1]; see above.

    Returns
    -------
    MultiViewScene
    """
    if not isinstance(scene, MultiViewScene):
        msg = f"scene must be a MultiViewScene, got {type(scene).__name__}"
        raise TypeError(msg)
    k = _check_factor(factor)
    frac = float(min_valid_fraction)
    if not 0 < frac <= 1:
        msg = f"min_valid_fraction must be in (0, 1], got {min_valid_fraction!r}"
        raise ValueError(msg)
    h, w = scene.shape
    if h // k < 2 or w // k < 2:
        msg = f"factor={k} is too large for a {h}x{w} scene; the result would be smaller than 2x2"
        raise ValueError(msg)
    size = (w // k, h // k)

    def area(img):
        cropped = np.ascontiguousarray(img[: size[1] * k, : size[0] * k])
        return cv2.resize(cropped, size, interpolation=cv2.INTER_AREA)

    views = [area(v).astype(np.float32) for v in scene.views]
    colour = area(scene.colour_reference)
    blocks = _block_view(scene.disparity.astype(np.float64), k)
    ok = np.isfinite(blocks)
    count = ok.sum(axis=(1, 3))
    total = np.where(ok, blocks, 0.0).sum(axis=(1, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = total / count
    disp = np.where(count >= frac * k * k, mean / k, np.nan).astype(np.float32)
    pp = None
    if scene.principal_point_px is not None:
        pp = tuple((c + 0.5) / k - 0.5 for c in scene.principal_point_px)
    return dataclasses.replace(
        scene,
        views=views,
        disparity=disp,
        colour_reference=colour,
        focal_px=None if scene.focal_px is None else scene.focal_px / k,
        disparity_offset_px=scene.disparity_offset_px / k,
        principal_point_px=pp,
        truth_step_px=None if scene.truth_step_px is None else scene.truth_step_px / k,
    )


def view_subset(scene: MultiViewScene, indices) -> MultiViewScene:
    """Keep some of the views, equally spaced and in increasing order.

    With a spacing of ``s`` original steps, the neighbour-step disparity,
    the baseline, the disparity offset and the truth's step are multiplied by ``s`` so that
    the scene's invariants (``d`` per view step, depth) still hold.

    Parameters
    ----------
    scene : MultiViewScene
    indices : sequence of int
        At least two strictly increasing, equally spaced view indices that
        include ``scene.reference_index`` (e.g. ``[1, 2, 3]`` or ``[0, 2, 4]``).

    Returns
    -------
    MultiViewScene
        With ``reference_index`` re-indexed into the new list.

    Raises
    ------
    ValueError
        If the indices are out of range, not increasing and equally spaced,
        fewer than two, or do not include the reference view.
    """
    if not isinstance(scene, MultiViewScene):
        msg = f"scene must be a MultiViewScene, got {type(scene).__name__}"
        raise TypeError(msg)
    try:
        raw = list(indices)
        idx = [int(i) for i in raw]
        if any(isinstance(i, bool) or int(i) != i for i in raw):
            raise TypeError
    except (TypeError, ValueError):
        msg = f"indices must be a sequence of integers, got {indices!r}"
        raise TypeError(msg) from None
    n = len(scene.views)
    if len(idx) < 2:
        msg = f"indices must hold at least two views, got {idx}"
        raise ValueError(msg)
    bad = [i for i in idx if not 0 <= i < n]
    if bad:
        msg = f"indices must lie in 0..{n - 1} for scene {scene.name!r}, got {idx}"
        raise ValueError(msg)
    steps = {b - a for a, b in zip(idx, idx[1:])}
    if len(steps) != 1 or min(steps) <= 0:
        msg = f"indices must be strictly increasing and equally spaced (camera toward +X), got {idx}"
        raise ValueError(msg)
    if scene.reference_index not in idx:
        msg = f"indices must include the reference view {scene.reference_index} of scene {scene.name!r}, got {idx}"
        raise ValueError(msg)
    s = steps.pop()
    return dataclasses.replace(
        scene,
        views=[scene.views[i] for i in idx],
        reference_index=idx.index(scene.reference_index),
        disparity=(scene.disparity * np.float32(s)).astype(np.float32),
        baseline=None if scene.baseline is None else scene.baseline * s,
        disparity_offset_px=scene.disparity_offset_px * s,
        truth_step_px=None if scene.truth_step_px is None else scene.truth_step_px * s,
    )
