"""Image and array I/O at the edge of the library.

Reading
    :func:`read_image` reads PNG, PPM/PGM (binary P5/P6, 8 or 16 bit), TIFF,
    JPEG, PFM and NPY files and returns a float array. Colour is converted to
    grey once, here, with :func:`to_grey` (ITU-R BT.601 luma on the stored
    values). Intensities stay in their stored unit: 0..255 for 8-bit files,
    0..65535 for 16-bit files, as stored for float files.

Writing
    Every writer goes through :func:`atomic_write`: the data are written to a
    temporary file in the target's directory and moved into place with
    :func:`os.replace`, so a reader never sees a half-written file. An existing
    target is kept unless ``force=True`` (:class:`OutputExistsError`).

    * :func:`write_array` -- a 2-D float map (depth, disparity), ``.pfm``,
      ``.tif``/``.tiff`` (float32) or ``.npy``; NaN marks unknown values.
    * :func:`write_pfm` / :func:`read_pfm` -- Middlebury PFM.
    * :func:`write_colormap_png` -- a quick-look false-colour PNG.
    * :func:`write_ply` and :func:`depth_to_points` -- point clouds;
      :func:`to_rgb8` turns any image into their 8-bit colours.

All errors are ``ValueError`` subclasses (:class:`ImageReadError` and its
:class:`ImageRangeError`, :class:`OutputExistsError`, :class:`OutputWriteError`)
or ``TypeError``.
"""

from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

import cv2
import numpy as np

from ._validate import (
    NFDepthError,
    as_path,
    check_bool,
    check_finite,
    check_positive_finite,
    float_dtype,
    is_real_numeric,
)

__all__ = [
    "InputReadError",
    "ImageReadError",
    "ImageRangeError",
    "OutputExistsError",
    "OutputWriteError",
    "READ_EXTENSIONS",
    "ARRAY_EXTENSIONS",
    "LUMA_WEIGHTS",
    "read_image",
    "make_output_folder",
    "parent_folder_problem",
    "require_extension",
    "to_float32_map",
    "to_grey",
    "read_pfm",
    "write_pfm",
    "write_array",
    "atomic_write",
    "write_colormap_png",
    "write_ply",
    "depth_to_points",
    "point_colors",
    "to_rgb8",
]

#: ITU-R BT.601 luma weights for (R, G, B).
LUMA_WEIGHTS = (0.299, 0.587, 0.114)

_CV2_EXTENSIONS = (".png", ".ppm", ".pgm", ".pnm", ".pbm", ".jpg", ".jpeg", ".bmp")
_TIFF_EXTENSIONS = (".tif", ".tiff")
#: File extensions :func:`read_image` understands (lower case).
READ_EXTENSIONS = _CV2_EXTENSIONS + _TIFF_EXTENSIONS + (".pfm", ".npy")
#: File extensions :func:`write_array` understands (lower case).
ARRAY_EXTENSIONS = (".pfm", ".tif", ".tiff", ".npy")


class InputReadError(NFDepthError):
    """An input file or folder could not be read (an image, a rig, a poses file, a folder of frames)."""


class ImageReadError(InputReadError):
    """An image file could not be read (missing, a directory, unsupported, broken)."""


class ImageRangeError(ImageReadError):
    """An image file holds finite values beyond the requested float type (float64 data read as float32)."""


class OutputExistsError(NFDepthError):
    """The output file exists and ``force`` was not given (``path``: that file, when known)."""

    def __init__(self, message: str, path=None):
        super().__init__(message)
        self.path = path


def _exists_error(path: Path) -> OutputExistsError:
    return OutputExistsError(f"'{path}' exists; pass force=True (--force on the command line) to replace it", path)


class OutputWriteError(NFDepthError):
    """The output file could not be written (missing or unwritable directory, ...)."""


def _read_error(path, reason: str) -> ImageReadError:
    return ImageReadError(f"cannot read image '{path}': {reason}")


# ------------------------------------------------------------------ reading


def to_grey(array, *, dtype=None) -> np.ndarray:
    """Convert an RGB(A) image to grey with the ITU-R BT.601 luma weights.

    Parameters
    ----------
    array : array_like, shape (H, W), (H, W, 1), (H, W, 2), (H, W, 3) or (H, W, 4)
        A grey image (returned as float, unchanged in value), grey + alpha,
        RGB or RGBA, channels in **R, G, B** order. Alpha is dropped.
    dtype : numpy dtype or None, keyword-only
        ``float32`` or ``float64`` for the result (and the arithmetic); by
        default float64 for float64 input, else float32.

    Returns
    -------
    ndarray, shape (H, W)
        ``0.299 R + 0.587 G + 0.114 B`` on the stored values (no gamma
        handling, no rescaling).

    Raises
    ------
    TypeError
        If ``array`` is not real numeric.
    ValueError
        If its shape is not one of the above.
    """
    arr = np.asarray(array)
    if not is_real_numeric(arr):
        msg = f"array must be a real numeric image, got dtype {arr.dtype}"
        raise TypeError(msg)
    if dtype is not None:
        out_dtype = float_dtype(dtype)
    else:
        out_dtype = np.float64 if arr.dtype == np.float64 else np.float32
    if arr.ndim == 2:
        return arr.astype(out_dtype, copy=False)
    if arr.ndim != 3 or arr.shape[-1] not in (1, 2, 3, 4):
        msg = f"array must have shape (H, W) or (H, W, C) with C in 1..4, got shape {arr.shape}"
        raise ValueError(msg)
    if arr.shape[-1] <= 2:  # grey, grey + alpha
        return arr[..., 0].astype(out_dtype)
    rgb = arr[..., :3].astype(out_dtype, copy=False)
    r, g, b = LUMA_WEIGHTS
    return (r * rgb[..., 0] + g * rgb[..., 1] + b * rgb[..., 2]).astype(out_dtype, copy=False)


def read_pfm(path) -> np.ndarray:
    """Read a PFM file (Middlebury / Debevec portable float map).

    Parameters
    ----------
    path : str or os.PathLike
        The file. ``Pf`` (grey) and ``PF`` (RGB) are understood, both byte
        orders (negative scale = little-endian).

    Returns
    -------
    ndarray, float32, shape (H, W) or (H, W, 3)
        Row 0 is the **top** row (PFM stores rows bottom to top; this is
        undone here). NaN and inf are preserved.

    Raises
    ------
    ImageReadError
        If the file is missing, a directory, not PFM, or truncated.
    """
    path = as_path("path", path)
    data = _read_bytes(path)
    return _decode_pfm(path, data)


# the scale ends with one whitespace byte (a line end; CR LF from Windows writers counts as one)
_PFM_HEADER = re.compile(rb"\A(P[Ff])\s+(\d+)\s+(\d+)\s+([-+0-9.eE]+)(?:\r\n|\s)")


def _decode_pfm(path, data: bytes) -> np.ndarray:
    m = _PFM_HEADER.match(data)
    if m is None:
        raise _read_error(path, "not a PFM file (expected a 'Pf' or 'PF' header, width, height and scale)")
    channels = 3 if m.group(1) == b"PF" else 1
    width, height = int(m.group(2)), int(m.group(3))
    try:
        scale = float(m.group(4))
    except ValueError:
        raise _read_error(path, f"bad PFM scale {m.group(4)!r}") from None
    if scale == 0 or width == 0 or height == 0:
        raise _read_error(path, f"bad PFM header (width {width}, height {height}, scale {scale})")
    dtype = np.dtype("<f4") if scale < 0 else np.dtype(">f4")
    count = width * height * channels
    body = data[m.end() :]
    if len(body) < count * 4:
        raise _read_error(path, f"truncated PFM: expected {count * 4} bytes of pixel data, found {len(body)}")
    if len(body) > count * 4:  # a header read one byte short or long would shift every value
        raise _read_error(path, f"expected {count * 4} bytes of pixel data after the header ({width} x {height} x {channels} float32), found {len(body)}")
    arr = np.frombuffer(body, dtype=dtype, count=count).astype(np.float32)
    shape = (height, width) if channels == 1 else (height, width, 3)
    return np.ascontiguousarray(arr.reshape(shape)[::-1])


def _read_bytes(path: Path) -> bytes:
    if not path.exists():
        raise _read_error(path, "no such file")
    if path.is_dir():
        raise _read_error(path, "it is a directory, not a file")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise _read_error(path, exc.strerror or str(exc)) from None
    if not data:
        raise _read_error(path, "the file is empty")
    return data


@contextlib.contextmanager
def _decoder_messages(lines: list):
    """Collect what C libraries (libjpeg, libpng) print on file descriptor 2 meanwhile into ``lines``.

    OpenCV's decoders report damage there, not to the caller: a JPEG whose data
    end early still decodes (the rest of the image grey) with only libjpeg's
    "Corrupt JPEG data: premature end of data segment" on stderr. Lines that
    are no decoder's go back to stderr. Without a file descriptor 2 nothing
    is collected.
    """
    try:
        saved = os.dup(2)
    except OSError:  # pragma: no cover - no stderr (a windowed process)
        yield
        return
    try:
        with tempfile.TemporaryFile() as tmp:
            with contextlib.suppress(Exception):
                sys.stderr.flush()
            os.dup2(tmp.fileno(), 2)
            try:
                yield
            finally:
                os.dup2(saved, 2)
                tmp.seek(0)
                text = tmp.read().decode("utf-8", errors="replace")
    finally:
        os.close(saved)
    others = []
    for line in text.splitlines():
        line = line.strip()
        if line.startswith(_DECODER_PREFIXES):
            lines.append(line)
        elif line:
            others.append(line)
    if others:  # pragma: no cover - another thread's output meanwhile
        print("\n".join(others), file=sys.stderr)


# what libjpeg, libpng and OpenCV's own decoders print (OpenCV's log level is lowered meanwhile)
_DECODER_PREFIXES = ("Corrupt JPEG data", "Premature end of JPEG file", "libpng", "Invalid SOS", "Bogus", "Unsupported", "[ WARN", "[ERROR", "[ INFO")
# libjpeg's warnings that leave the image as encoded (stray bytes between segments)
_HARMLESS_JPEG = ("extraneous bytes before marker",)


def _jpeg_complete(data: bytes) -> bool:
    """Whether a JPEG's marker structure (ITU T.81, annex B) reaches its end-of-image marker.

    Walks the segments from the start-of-image marker; inside a scan's
    entropy-coded data ``FF 00`` (a stuffed byte) and ``FF D0`` .. ``FF D7``
    (restarts) are data, any other ``FF xx`` is the next marker. Bytes after
    the end-of-image marker (phones' motion photos append a video there,
    some writers metadata or padding) are not the image's: a complete image
    with them is complete, a cut one (even if its trailer happens to hold
    ``FF D9``) is not.
    """
    n, i = len(data), 2
    if not data.startswith(b"\xff\xd8"):
        return False
    while i + 1 < n:
        if data[i] != 0xFF:
            return False  # not a marker where one belongs: damaged
        marker = data[i + 1]
        if marker == 0xFF:  # fill byte before a marker
            i += 1
            continue
        if marker == 0xD9:
            return True
        if 0xD0 <= marker <= 0xD7 or marker == 0x01:  # no length
            i += 2
            continue
        if i + 3 >= n:
            return False
        i += 2 + int.from_bytes(data[i + 2 : i + 4], "big")
        if marker == 0xDA:  # entropy-coded data up to the next marker
            while True:
                j = data.find(b"\xff", i)
                if j < 0 or j + 1 >= n:
                    return False
                following = data[j + 1]
                if following == 0x00 or 0xD0 <= following <= 0xD7 or following == 0xFF:
                    i = j + 1 if following == 0xFF else j + 2
                    continue
                i = j
                break
    return False


def _decode_cv2(path: Path, data: bytes, ext: str) -> np.ndarray:
    if ext in (".jpg", ".jpeg") and not _jpeg_complete(data):
        raise _read_error(path, "truncated JPEG (no end-of-image marker)")
    previous = None
    # keep OpenCV's own log quiet; the error below says what went wrong
    # (cv2.setLogLevel in OpenCV 4, cv2.utils.logging.setLogLevel in OpenCV 5)
    set_level = getattr(cv2, "setLogLevel", None) or getattr(getattr(getattr(cv2, "utils", None), "logging", None), "setLogLevel", None)
    try:
        previous = set_level(0) if set_level is not None else None
    except Exception:  # pragma: no cover - an OpenCV without either
        previous = None
    messages: list[str] = []
    try:
        with _decoder_messages(messages):
            arr = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    except cv2.error as exc:  # pragma: no cover - imdecode usually returns None
        raise _read_error(path, f"OpenCV could not decode it ({exc})") from None
    finally:
        if previous is not None:
            set_level(previous)
    if arr is None:
        said = f"({messages[0]})" if messages else "(broken or truncated file?)"
        raise _read_error(path, f"OpenCV could not decode it as {ext[1:].upper()} {said}")
    damage = [m for m in messages if m.startswith(("Corrupt JPEG data", "Premature end of JPEG file")) and not any(h in m for h in _HARMLESS_JPEG)]
    if damage:  # decoded, but part of the image is made up
        raise _read_error(path, f"damaged JPEG (libjpeg: {damage[0]}); part of the image would be made up")
    if arr.ndim == 3 and arr.shape[-1] == 3:
        arr = arr[..., ::-1]  # BGR -> RGB
    elif arr.ndim == 3 and arr.shape[-1] == 4:
        arr = arr[..., [2, 1, 0, 3]]  # BGRA -> RGBA
    return np.ascontiguousarray(arr)


def _decode_tiff(path: Path) -> np.ndarray:
    """One image of a TIFF file as stored values: grey (0 black), RGB(A) or grey + alpha, (H, W) or (H, W, C).

    The colour type (photometric tag) is honoured: a palette becomes RGB, MinIsWhite is inverted, 1-bit
    images are 0/255 (as OpenCV reads 1-bit PNG and PBM). CMYK, CIELab and uncompressed YCbCr are
    refused, and so is a file with more than one full-size image (page).
    """
    import logging

    import tifffile

    log = logging.getLogger("tifffile")  # it logs broken offsets; the error below says it in one line
    level = log.level
    log.setLevel(logging.CRITICAL + 1)
    try:
        with tifffile.TiffFile(path) as tif:
            pages = [p for p in tif.pages if not int(getattr(p, "subfiletype", 0) or 0) & 1]  # not the thumbnails
            if len(pages) > 1:
                raise _read_error(path, f"holds {len(pages)} images (pages); expected one image per file (save each view as its own file)")
            page = pages[0] if pages else tif.pages[0]
            arr = _tiff_colours(path, page)
    except ImageReadError:
        raise
    except Exception as exc:  # tifffile raises several types on broken files
        reason = f"{type(exc).__name__}: {exc}"
        data = _read_bytes(path)  # a file that cannot be read (permissions) is said as such
        try:  # a compression tifffile reads only with the optional imagecodecs (LZW, OpenCV's own default): OpenCV reads it
            return _decode_cv2(path, data, ".tif")
        except ImageReadError:
            pass
        hint = "; `pip install imagecodecs` lets tifffile read its compression" if "imagecodecs" in reason else ""
        raise _read_error(path, f"not a readable TIFF ({reason}){hint}") from None
    finally:
        log.setLevel(level)
    if arr.size == 0:
        raise _read_error(path, f"not a readable TIFF (no image data; array of shape {arr.shape})")
    return arr


# TIFF photometric interpretations (TIFF 6.0, section 8 and 21-23)
_MINISWHITE, _MINISBLACK, _RGB, _PALETTE, _YCBCR = 0, 1, 2, 3, 6
_TIFF_JPEG = (6, 7)  # old- and new-style JPEG compression: the decoder returns RGB
_PHOTOMETRIC_NAMES = {4: "a transparency mask", 5: "CMYK (separated)", 6: "YCbCr", 8: "CIELab", 9: "ICCLab", 10: "ITULab", 32803: "a colour filter array (raw)", 32844: "LogL", 32845: "LogLuv", 34892: "linear raw"}


def _tiff_colours(path: Path, page) -> np.ndarray:
    """A TIFF page's pixels in the colours :func:`read_image` expects (see :func:`_decode_tiff`)."""
    photometric = int(page.photometric)
    jpeg_rgb = photometric == _YCBCR and int(page.compression) in _TIFF_JPEG
    if photometric not in (_MINISWHITE, _MINISBLACK, _RGB, _PALETTE) and not jpeg_rgb:
        kind = _PHOTOMETRIC_NAMES.get(photometric, f"photometric {photometric}")
        raise _read_error(path, f"holds {kind} colour; expected a grey, RGB or palette TIFF (convert it to one of those first)")
    arr = np.asarray(page.asarray())
    if arr.ndim == 3 and int(page.planarconfig) == 2 and int(page.samplesperpixel) == arr.shape[0]:
        arr = np.moveaxis(arr, 0, -1)  # planar (C, H, W) -> (H, W, C)
    if photometric == _PALETTE:
        cmap = np.asarray(page.colormap)
        if cmap.ndim != 2 or cmap.shape[0] != 3 or arr.ndim != 2 or not np.issubdtype(arr.dtype, np.integer):
            raise _read_error(path, "a palette TIFF without a usable colour map")
        if int(arr.max(initial=0)) >= cmap.shape[1]:
            raise _read_error(path, f"palette index {int(arr.max())} beyond its colour map of {cmap.shape[1]} entries")
        if int(cmap.max(initial=0)) > 255:  # 16-bit entries (the TIFF norm): the 8-bit colour is the high byte
            cmap = cmap >> 8
        return np.ascontiguousarray(cmap.astype(np.uint8)[:, arr].transpose(1, 2, 0))
    if arr.dtype == bool:  # 1 bit: 0/255, as OpenCV reads 1-bit PNG and PBM
        arr = arr.astype(np.uint8) * np.uint8(255)
        if photometric == _MINISWHITE:
            arr = np.uint8(255) - arr
        return arr
    if photometric == _MINISWHITE:
        if not np.issubdtype(arr.dtype, np.unsignedinteger):
            raise _read_error(path, f"a MinIsWhite (inverted) TIFF of {arr.dtype} values; expected it of unsigned integers, or a MinIsBlack TIFF")
        bits = int(page.bitspersample)
        top = (1 << bits) - 1 if bits < arr.dtype.itemsize * 8 else np.iinfo(arr.dtype).max
        arr = arr.dtype.type(top) - arr
    return arr


def _decode_npy(path: Path) -> np.ndarray:
    try:
        return np.load(path, allow_pickle=False)
    except MemoryError:
        raise _read_error(path, "its NPY header asks for more memory than is available (broken header?)") from None
    except Exception as exc:  # a broken header raises ValueError, EOFError, tokenize errors, ...
        raise _read_error(path, f"not a readable NPY file ({type(exc).__name__}: {exc})") from None


def read_image(path, *, grey: bool = True, dtype=np.float32) -> np.ndarray:
    """Read an image file into an array.

    Parameters
    ----------
    path : str or os.PathLike
        PNG, PPM/PGM/PNM (binary P5/P6, 8 or 16 bit), BMP, JPEG, TIFF, PFM
        or NPY, chosen by the extension (case-insensitive).
    grey : bool, keyword-only
        Convert colour to grey with :func:`to_grey` (BT.601 luma, alpha
        dropped). With ``False`` colour comes back as (H, W, 3) or (H, W, 4)
        in **R, G, B(, A)** order (OpenCV's BGR is undone).
    dtype : numpy dtype or None, keyword-only
        ``float32`` (default) or ``float64``; ``None`` keeps the stored
        dtype (e.g. ``uint8`` for an 8-bit grey PNG) and, with
        ``grey=False``, the stored values exactly; colour converted to grey
        comes back as float32 (the luma is not a whole number).

    Returns
    -------
    ndarray
        (H, W) when ``grey``; else (H, W) or (H, W, C). Intensities are in
        their stored unit: 0..255 for 8-bit, 0..65535 for 16-bit files.

    Raises
    ------
    ImageReadError
        "cannot read image 'PATH': reason" for a missing file, a directory,
        an empty, broken or truncated file, or an unsupported extension.
    ImageRangeError
        "cannot read image 'PATH': N pixel(s) beyond the float32 range ..."
        for a float64 file with finite values beyond float32 when ``dtype``
        is float32 (an :class:`ImageReadError`).
    ValueError
        If ``dtype`` is not float32, float64 or None.

    Notes
    -----
    JPEG EXIF orientation is ignored (pixels as stored).
    """
    grey = check_bool("grey", grey)
    out_dtype = None if dtype is None else float_dtype(dtype)
    path = as_path("path", path)
    ext = path.suffix.lower()
    if path.is_dir():
        raise _read_error(path, "it is a directory, not a file")
    if ext not in READ_EXTENSIONS:
        if not path.exists():
            raise _read_error(path, "no such file")
        listed = ", ".join(READ_EXTENSIONS)
        raise _read_error(path, f"unsupported extension {path.suffix!r}; expected one of {listed}")
    if ext in _TIFF_EXTENSIONS or ext == ".npy":
        _check_is_file(path)
        arr = _decode_tiff(path) if ext in _TIFF_EXTENSIONS else _decode_npy(path)
    else:
        data = _read_bytes(path)
        arr = _decode_pfm(path, data) if ext == ".pfm" else _decode_cv2(path, data, ext)
    if not is_real_numeric(arr):
        raise _read_error(path, f"holds dtype {arr.dtype}, expected real numbers")
    if not (arr.ndim == 2 or (arr.ndim == 3 and arr.shape[-1] in (1, 2, 3, 4))):
        raise _read_error(path, f"holds an array of shape {arr.shape}, expected (H, W) or (H, W, C) with C in 1..4")
    if arr.dtype == bool:
        arr = arr.astype(np.uint8)
    if arr.ndim == 3 and arr.shape[-1] == 1:
        arr = arr[..., 0]
    stored = arr
    with np.errstate(over="ignore"):  # float64 beyond float32 becomes inf: reported below
        if grey and arr.ndim == 3:
            arr = to_grey(arr, dtype=out_dtype)
        if out_dtype is not None:
            arr = arr.astype(out_dtype, copy=False)
    if out_dtype is not None and stored.dtype.kind == "f" and stored.dtype.itemsize > out_dtype.itemsize:
        _check_no_overflow(path, stored, arr)
    return arr


def _check_no_overflow(path: Path, stored: np.ndarray, converted: np.ndarray) -> None:
    """Refuse finite stored values that became inf in the narrower float type (not NaN or inf in the file)."""
    finite = np.isfinite(stored)
    if converted.ndim < stored.ndim:  # colour to grey: a pixel is finite if all its channels are
        finite = np.all(finite, axis=-1)
    over = finite & ~np.isfinite(converted)
    if over.any():
        peak = float(np.max(np.abs(stored[np.isfinite(stored)])))
        raise ImageRangeError(
            f"cannot read image '{path}': {int(np.count_nonzero(over))} pixel(s) beyond the {converted.dtype} range "
            f"(max |value| {peak:.3g}, {converted.dtype} reaches {float(np.finfo(converted.dtype).max):.3g}); "
            "rescale the intensities, or read it with dtype=float64 in Python"
        )


def _check_is_file(path: Path) -> None:
    if not path.exists():
        raise _read_error(path, "no such file")
    if path.is_dir():
        raise _read_error(path, "it is a directory, not a file")
    if path.stat().st_size == 0:
        raise _read_error(path, "the file is empty")


# ------------------------------------------------------------------ writing


def _current_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


#: During a command-line run (else None): the files :func:`atomic_write` has
#: completed, each with whether it replaced an existing file. An interrupted
#: or failed run removes its new files, so that it leaves no part of its
#: outputs behind.
COMPLETED_WRITES: list[tuple[Path, bool]] | None = None


@contextlib.contextmanager
def _kept_on_failure():
    """Writes that outlive a failed or interrupted run (a download cache's completed sets): not in :data:`COMPLETED_WRITES`."""
    global COMPLETED_WRITES  # the run's record, set by the command line
    saved, COMPLETED_WRITES = COMPLETED_WRITES, None
    try:
        yield
    finally:
        COMPLETED_WRITES = saved


def parent_folder_problem(path) -> str | None:
    """Why ``path`` cannot be made in its folder (``"'f' is not a directory"``, ``"directory 'x' does not exist"``), or None."""
    path = as_path("path", path)
    parent = path.parent  # (Path(".") for a bare name)
    if parent.is_dir():
        return None
    return f"'{parent}' is not a directory" if parent.exists() else f"directory '{parent}' does not exist"


def make_output_folder(path, *, parents: bool = False) -> Path:
    """The output folder ``path``, created if missing (its parent must exist, unless ``parents``: then made too).

    During a command-line run a folder it creates is recorded in
    :data:`COMPLETED_WRITES` with the files, so that a failed or
    interrupted run removes it again once its own files are gone.
    """
    path = as_path("path", path)
    if not path.is_dir():
        if parents and path.parent != path and not path.parent.is_dir():
            make_output_folder(path.parent, parents=True)
        problem = parent_folder_problem(path)
        if problem:
            raise OutputWriteError(f"cannot write '{path}': {problem}")
        try:
            path.mkdir()
        except FileExistsError:  # made meanwhile (another thread's figure): it is not this run's to remove
            if not path.is_dir():
                raise OutputWriteError(f"cannot write '{path}': it exists and is not a directory") from None
            return path
        except OSError as exc:  # a read-only or virtual parent (/proc)
            raise OutputWriteError(f"cannot write '{path}': {exc.strerror or exc}") from None
        if COMPLETED_WRITES is not None:
            COMPLETED_WRITES.append((path, False))
    return path


def atomic_write(path, writer_fn: Callable[[BinaryIO], object], *, force: bool = False) -> Path:
    """Write a file atomically through ``writer_fn``.

    ``writer_fn`` receives a binary file object open for writing on a
    temporary file in the target's directory; when it returns, the file is
    flushed, synced and moved onto ``path`` with :func:`os.replace`. If
    ``writer_fn`` raises, the temporary file is removed and the target is
    untouched.

    Parameters
    ----------
    path : str or os.PathLike
        The target file. Its directory must exist.
    writer_fn : callable
        ``writer_fn(fh)`` writes the whole content to ``fh``.
    force : bool, keyword-only
        Replace an existing target. Without it an existing target raises
        :class:`OutputExistsError` (checked race-free with a hard link where
        the file system supports it).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    OutputExistsError
        If ``path`` exists and ``force`` is false.
    OutputWriteError
        If the directory is missing or not writable, ``path`` is a directory,
        or the write fails.
    """
    if not callable(writer_fn):
        msg = f"writer_fn must be callable, got {type(writer_fn).__name__}"
        raise TypeError(msg)
    path = as_path("path", path)
    parent = path.parent  # (Path(".") for a bare name)
    if path.is_dir():
        raise OutputWriteError(f"cannot write '{path}': it is a directory")
    if not parent.is_dir():
        raise OutputWriteError(f"cannot write '{path}': directory '{parent}' does not exist")
    if os.path.lexists(path) and not force:  # (a link to a missing file too: os.link would refuse it)
        raise _exists_error(path)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=parent)
    except OSError as exc:
        raise OutputWriteError(f"cannot write '{path}': {exc.strerror or exc} (directory '{parent}')") from None
    tmp = Path(tmp_name)
    existed = os.path.lexists(path)
    try:
        with os.fdopen(fd, "wb") as fh:
            writer_fn(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_current_umask())
        if force:
            os.replace(tmp, path)
        else:
            try:
                os.link(tmp, path)  # fails if the target appeared meanwhile
            except FileExistsError:
                raise _exists_error(path) from None
            except OSError:  # no hard links on this file system
                if os.path.lexists(path):
                    raise _exists_error(path) from None
                os.replace(tmp, path)
    except OSError as exc:
        raise OutputWriteError(f"cannot write '{path}': {exc.strerror or exc}") from None
    finally:
        try:
            tmp.unlink()
        except FileNotFoundError:
            pass
        except OSError:  # pragma: no cover
            pass
    if COMPLETED_WRITES is not None:
        COMPLETED_WRITES.append((path, existed))
    return path


def require_extension(path, ext: str, *, hint: str = "") -> None:
    """Refuse a ``path`` that does not end in ``ext`` (case-insensitive): a file's bytes under another format's name mislead every reader."""
    if as_path("path", path).suffix.lower() != ext:
        msg = f"path must end in {ext}, got {str(path)!r}{hint}"
        raise ValueError(msg)


def _as_map(name: str, array, *, allow_colour: bool = False) -> np.ndarray:
    arr = np.asarray(array)
    if not is_real_numeric(arr):
        msg = f"{name} must be a real numeric array, got dtype {arr.dtype}"
        raise TypeError(msg)
    ok = arr.ndim == 2 or (allow_colour and arr.ndim == 3 and arr.shape[-1] == 3)
    if not ok or arr.size == 0:
        expected = "(H, W) or (H, W, 3)" if allow_colour else "(H, W)"
        msg = f"{name} must be a non-empty array of shape {expected}, got shape {arr.shape}"
        raise ValueError(msg)
    return arr


def _float32_payload(arr: np.ndarray, ext: str) -> np.ndarray:
    """``arr`` as float32 for a ``.pfm`` or ``.tif`` file; a finite value it cannot hold is refused (:func:`to_float32_map`)."""
    return to_float32_map(arr, what="a value", hint=f"a {ext} file stores float32: rescale the map, or write .npy (float64 kept)")


def _pfm_bytes(arr: np.ndarray) -> bytes:
    tag = b"PF" if arr.ndim == 3 else b"Pf"
    h, w = arr.shape[:2]
    header = tag + b"\n" + f"{w} {h}\n-1.0\n".encode("ascii")
    body = np.ascontiguousarray(_float32_payload(arr, ".pfm")[::-1], dtype="<f4").tobytes()
    return header + body


def write_pfm(path, array, *, force: bool = False) -> Path:
    """Write a PFM file (Middlebury convention), atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target file.
    array : array_like, shape (H, W) or (H, W, 3)
        Stored as little-endian float32 (header ``Pf`` or ``PF``, scale
        -1.0), rows bottom to top as PFM requires; NaN and inf are kept.
    force : bool, keyword-only
        Replace an existing file.

    Returns
    -------
    pathlib.Path
    """
    require_extension(path, ".pfm", hint=" (write_array picks the format from the extension)")
    arr = _as_map("array", array, allow_colour=True)
    payload = _pfm_bytes(arr)
    return atomic_write(path, lambda fh: fh.write(payload), force=force)


def to_float32_map(values, *, what: str = "a value", hint: str = "rescale it") -> np.ndarray:
    """``values`` as float32 for an output file; ``ValueError`` if a finite value would become inf or 0 there.

    ``what`` names a value in the message (``"a depth"``), ``hint`` says what
    to do about it.

    Depths in extreme units (a focal length or baseline of 1e300) are finite
    in float64 but not in a float32 map: written as they are, they would be
    silently infinite.
    """
    v = np.asarray(values)
    with np.errstate(over="ignore", under="ignore"):
        out = v.astype(np.float32)
    finite = np.isfinite(v)
    lost = finite & (~np.isfinite(out) | ((out == 0) & (v != 0)))
    if np.any(lost):
        worst = float(np.max(np.abs(v[lost])))
        msg = f"{what} of {worst:.3g} does not fit a float32 output (about 1e-45 to 3.4e38): {hint}"
        raise ValueError(msg)
    return out


def write_array(path, array, *, force: bool = False) -> Path:
    """Write a 2-D float map (depth, disparity, ...) by extension, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        ``.pfm`` (float32, Middlebury PFM), ``.tif``/``.tiff`` (float32
        TIFF) or ``.npy`` (float32 unless the array is float64 or wider,
        which is stored as float64). A finite value the stored type cannot
        hold is refused, not written as inf or 0.
    array : array_like, shape (H, W)
        The map; NaN marks unknown values and is stored as NaN.
    force : bool, keyword-only
        Replace an existing file.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        For an unsupported extension or a non-2-D array.
    OutputExistsError, OutputWriteError
        See :func:`atomic_write`.
    """
    path = as_path("path", path)
    ext = path.suffix.lower()
    if ext not in ARRAY_EXTENSIONS:
        msg = f"path must end in one of {', '.join(ARRAY_EXTENSIONS)}, got {str(path)!r}"
        raise ValueError(msg)
    arr = _as_map("array", array)
    if ext == ".pfm":
        payload = _pfm_bytes(arr)
        return atomic_write(path, lambda fh: fh.write(payload), force=force)
    if ext == ".npy":
        # float64 kept (native byte order); a wider or non-native float stored as float64, the rest as float32
        wide = arr.dtype.kind == "f" and arr.dtype.itemsize >= 8
        with np.errstate(over="ignore"):
            out = arr.astype(np.float64) if wide else _float32_payload(arr, ext)
        lost = np.isfinite(arr) & ~np.isfinite(out) if wide else None
        if lost is not None and lost.any():  # a long double beyond float64's range
            worst = np.format_float_scientific(np.max(np.abs(arr[lost])), precision=2, unique=False)
            msg = f"a value of {worst} does not fit a float64 output (about 1e-308 to 1.8e308): rescale the map"
            raise ValueError(msg)
        return atomic_write(path, lambda fh: np.save(fh, out, allow_pickle=False), force=force)
    import io as _io

    import tifffile

    buf = _io.BytesIO()  # tifffile wants a named file or a buffer, not an os.fdopen object
    tifffile.imwrite(buf, np.ascontiguousarray(_float32_payload(arr, ext)))
    payload = buf.getvalue()
    return atomic_write(path, lambda fh: fh.write(payload), force=force)


def _encode_png(rgb: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".png", np.ascontiguousarray(rgb[..., ::-1]))
    if not ok:  # pragma: no cover
        raise OutputWriteError("OpenCV could not encode the PNG")
    return buf.tobytes()


def write_colormap_png(path, array, *, vmin=None, vmax=None, cmap: str = "turbo", force: bool = False) -> Path:
    """Write a false-colour quick-look PNG of a 2-D map, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target ``.png`` file.
    array : array_like, shape (H, W)
        The map. NaN and +-inf are drawn black.
    vmin, vmax : float, optional, keyword-only
        Values mapped to the ends of the colour map; default the finite
        minimum and maximum (an end not given never crosses the one given:
        ``vmin=20`` on values 0..10 draws all of them at the low end).
        Values outside are clipped; with ``vmin == vmax``, values below are
        the low end, above the high end, equal the middle colour.
    cmap : str, keyword-only
        A Matplotlib colour map name (``matplotlib.colormaps``).
    force : bool, keyword-only
        Replace an existing file.

    Returns
    -------
    pathlib.Path
    """
    from matplotlib import colormaps

    require_extension(path, ".png")
    arr = _as_map("array", array).astype(np.float64)
    if cmap not in colormaps:
        msg = f"cmap must be a Matplotlib colour map name such as 'turbo', 'viridis' or 'gray', got {cmap!r}"
        raise ValueError(msg)
    finite = np.isfinite(arr)
    lo = check_finite("vmin", vmin) if vmin is not None else (float(arr[finite].min()) if finite.any() else 0.0)
    hi = check_finite("vmax", vmax) if vmax is not None else (float(arr[finite].max()) if finite.any() else 1.0)
    if vmin is not None and vmax is not None and hi < lo:
        msg = f"vmax must be >= vmin, got vmin={lo!r}, vmax={hi!r}"
        raise ValueError(msg)
    # one end given beyond the data's other end: the default end follows it (as plot.colormap_panel does)
    lo, hi = (min(lo, hi), hi) if vmin is None else (lo, max(lo, hi))
    with np.errstate(invalid="ignore"):
        if hi == lo:  # one value: below it the low end, above it the high end, at it the middle
            norm = np.where(arr < lo, 0.0, np.where(arr > hi, 1.0, 0.5))
        else:
            norm = np.clip((arr - lo) / (hi - lo), 0.0, 1.0)
    norm[~finite] = 0.0
    rgb = colormaps[cmap](norm, bytes=True)[..., :3].copy()
    rgb[~finite] = 0
    payload = _encode_png(rgb)
    return atomic_write(path, lambda fh: fh.write(payload), force=force)


def write_ply(path, points_xyz, *, colors=None, force: bool = False) -> Path:
    """Write a point cloud as binary little-endian PLY, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target ``.ply`` file.
    points_xyz : array_like, shape (N, 3)
        Point coordinates, stored as float32 ``x, y, z``. Rows with any
        non-finite coordinate are skipped.
    colors : array_like, shape (N, 3), optional, keyword-only
        Integer RGB in 0..255, stored as uchar ``red, green, blue``.
    force : bool, keyword-only
        Replace an existing file.

    Returns
    -------
    pathlib.Path
    """
    require_extension(path, ".ply")
    pts = np.asarray(points_xyz)
    if pts.dtype == object or not np.issubdtype(pts.dtype, np.number) or np.iscomplexobj(pts):
        msg = f"points_xyz must be a real numeric array, got dtype {pts.dtype}"
        raise TypeError(msg)
    if pts.ndim != 2 or pts.shape[1] != 3:
        msg = f"points_xyz must have shape (N, 3), got shape {pts.shape}"
        raise ValueError(msg)
    keep = np.all(np.isfinite(pts), axis=1)
    xyz = to_float32_map(pts[keep], what="a coordinate", hint="a .ply file stores float32: rescale the points (another unit)")
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    col = None
    if colors is not None:
        col = np.asarray(colors)
        if col.shape != pts.shape:
            msg = f"colors must have shape {pts.shape} like points_xyz, got shape {col.shape}"
            raise ValueError(msg)
        if not np.issubdtype(col.dtype, np.integer):
            msg = f"colors must be integers 0..255 (uint8), got dtype {col.dtype}"
            raise TypeError(msg)
        if col.size and (col.min() < 0 or col.max() > 255):
            msg = f"colors must lie in 0..255, got range {col.min()}..{col.max()}"
            raise ValueError(msg)
        fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    n = int(keep.sum())
    rec = np.empty(n, dtype=np.dtype(fields))
    rec["x"], rec["y"], rec["z"] = (xyz[:, i] for i in range(3))
    if col is not None:
        rec["red"], rec["green"], rec["blue"] = (col[keep, i] for i in range(3))
    lines = ["ply", "format binary_little_endian 1.0", "comment written by nfdepth", f"element vertex {n}"]
    lines += ["property float x", "property float y", "property float z"]
    if col is not None:
        lines += ["property uchar red", "property uchar green", "property uchar blue"]
    lines.append("end_header")
    payload = ("\n".join(lines) + "\n").encode("ascii") + rec.tobytes()
    return atomic_write(path, lambda fh: fh.write(payload), force=force)


def depth_to_points(depth, *, focal_px, cx_px=None, cy_px=None, image=None):
    """Back-project a depth map to 3-D points in the camera frame.

    ``X = (col - cx) Z / f``, ``Y = (row - cy) Z / f`` (X right, Y down, Z
    forward; see docs/how-it-works.md, "Conventions").

    Parameters
    ----------
    depth : array_like, shape (H, W)
        Depth Z (any length unit; the points come out in the same unit).
        Pixels that are not finite or not > 0 are skipped.
    focal_px : float, keyword-only
        Focal length in pixels.
    cx_px, cy_px : float, optional, keyword-only
        Principal point in pixels; default the image centre ``(W-1)/2``,
        ``(H-1)/2``.
    image : array_like, shape (H, W) or (H, W, 3), optional, keyword-only
        Colour (RGB) or grey image for point colours; float values are
        rounded and clipped to 0..255 (pass ``to_rgb8(image)`` for a 16-bit
        or float image in another range).

    Returns
    -------
    points : ndarray, float32, shape (N, 3)
        One row per kept pixel, in row-major pixel order.
    colors : ndarray, uint8, shape (N, 3), or None
        RGB per point when ``image`` is given.
    """
    z = _as_map("depth", depth).astype(np.float64)
    f = check_positive_finite("focal_px", focal_px)
    h, w = z.shape
    cx = (w - 1) / 2.0 if cx_px is None else check_finite("cx_px", cx_px)
    cy = (h - 1) / 2.0 if cy_px is None else check_finite("cy_px", cy_px)
    with np.errstate(invalid="ignore"):
        keep = np.isfinite(z) & (z > 0)
    rows, cols = np.nonzero(keep)
    zz = z[rows, cols]
    pts = np.stack([(cols - cx) * zz / f, (rows - cy) * zz / f, zz], axis=1).astype(np.float32)
    return pts, point_colors(image, rows, cols, z.shape)


def point_colors(image, rows, cols, shape):
    """RGB (uint8, ``(N, 3)``) of ``image`` at the pixels ``rows, cols`` of a ``shape`` map, as :func:`depth_to_points` colours its points; None without an image."""
    if image is None:
        return None
    img = np.asarray(image)
    shape = tuple(shape)
    if img.shape[:2] != shape or not (img.ndim == 2 or (img.ndim == 3 and img.shape[-1] in (3, 4))):
        msg = f"image must have shape {shape} or {shape + (3,)} like depth, got shape {img.shape}"
        raise ValueError(msg)
    if img.ndim == 2:
        img = np.repeat(img[..., None], 3, axis=2)
    img = img[..., :3]
    if img.dtype != np.uint8:
        img = np.clip(np.rint(np.nan_to_num(img.astype(np.float64))), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(img[rows, cols])


def to_rgb8(image) -> np.ndarray:
    """An image as 8-bit RGB, shape (H, W, 3), for point colours (:func:`write_ply`).

    Grey is repeated into three channels and alpha dropped. ``uint8`` values
    are kept; any other dtype (16-bit, float) is scaled by 255 over its
    largest finite value (at least 1), so colours follow the intensities
    whatever the bit depth. NaN and negative values become 0, +inf 255.

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, C) with C in 1..4
        Grey, grey + alpha, RGB or RGBA (R, G, B order, as :func:`read_image`
        with ``grey=False``).

    Returns
    -------
    ndarray, uint8, shape (H, W, 3)
    """
    arr = np.asarray(image)
    if not is_real_numeric(arr):
        msg = f"image must be a real numeric image, got dtype {arr.dtype}"
        raise TypeError(msg)
    if not (arr.ndim == 2 or (arr.ndim == 3 and arr.shape[-1] in (1, 2, 3, 4))):
        msg = f"image must have shape (H, W) or (H, W, C) with C in 1..4, got shape {arr.shape}"
        raise ValueError(msg)
    if arr.ndim == 3:
        arr = arr[..., :3] if arr.shape[-1] >= 3 else arr[..., 0]
    if arr.ndim == 2:
        arr = np.repeat(arr[..., None], 3, axis=2)
    if arr.dtype == np.uint8:
        return np.ascontiguousarray(arr)
    values = arr.astype(np.float64)
    finite = values[np.isfinite(values)]
    scale = 255.0 / max(float(finite.max()) if finite.size else 0.0, 1.0)
    return np.clip(np.rint(np.nan_to_num(values * scale, nan=0.0)), 0, 255).astype(np.uint8)
