"""Download the real data sets with ground truth, checked by SHA-256 (needs ``pooch``).

:func:`fetch_data` fetches the original third-party files into the layout
that :mod:`nfdepth.datasets` reads (the layout of ``shared/data``), one
folder per set, each with a generated ``SHA256SUMS`` (``sha256sum -c
SHA256SUMS``) and a short ``SOURCE.md`` (origin, citation, terms). Every
file is pinned: a GitHub commit or a scikit-image release tag, and a known
SHA-256. ``pooch`` (``pip install 'nfdepth[data]'``) does the download; a
file reaches its final name only after its hash matched.

=========================  =====  ==================================================
set                        files  origin
=========================  =====  ==================================================
``tsukuba``                    6  PaleCosmos/Multimedia_Lab (Middlebury 2001 files)
``middlebury2003-teddy``      11  norishigefukushima/ViewSynthesis, xland16/disparitymapping
``middlebury2005``            50  norishigefukushima/ViewSynthesis (5 scenes)
``skimage-motorcycle``         3  scikit-image v0.25.2, ``skimage/data``
=========================  =====  ==================================================

The default destination is :func:`default_data_dir`, which
:func:`nfdepth.datasets.data_root` searches last, so that after
``nfdepth fetch-data`` the loaders and ``nfdepth evaluate`` find the data by
themselves.
"""

from __future__ import annotations

import ftplib
import hashlib
import os
import re
import sys
from pathlib import Path
from typing import NamedTuple
from urllib.parse import urlsplit, urlunsplit

__all__ = [
    "DATA_SETS",
    "DataDownloadError",
    "DataFile",
    "data_files",
    "default_data_dir",
    "fetch_data",
]

#: Names of the data sets, in the order they are fetched (each a folder).
DATA_SETS = ("tsukuba", "middlebury2003-teddy", "middlebury2005", "skimage-motorcycle")

_INSTALL_HINT = "pip install 'nfdepth[data]'"
_MIRROR_SCHEMES = ("http://", "https://", "ftp://")

_RAW = "https://raw.githubusercontent.com"
_TSUKUBA_BASE = f"{_RAW}/PaleCosmos/Multimedia_Lab/601fe2e7c85bac98def8c6038a404af6b40bae86/image/tsukuba"
_VIEWSYNTHESIS_BASE = f"{_RAW}/norishigefukushima/ViewSynthesis/d503b7822e655103c50a74f27c02ea4a4adbe6e1/ViewSynthesis/img/stereo"
_DISPARITYMAPPING_BASE = f"{_RAW}/xland16/disparitymapping/de5c48ec8f9e5893f324d9068372bd1a7c16b46c/teddy"
_SKIMAGE_BASE = "https://github.com/scikit-image/scikit-image/raw/v0.25.2/skimage/data"

#: set -> ((path in the set folder, sha256, size in bytes), ...), sorted by path
#: as in the set's SHA256SUMS. The hashes are those of ``shared/data/*/SHA256SUMS``.
_REGISTRY = {
    "tsukuba": (
        ("scene1.row3.col1.ppm", "64383935cb3035345a237f1dd1ea1c4ca12ad1aa611a8bd40226e168e4ac0fc4", 331791),
        ("scene1.row3.col2.ppm", "3f2317b3f569a4388657d24a49358ce394c31eda7feaeda5103d8586fa380ba9", 331791),
        ("scene1.row3.col3.ppm", "1d326401c70e4bce95f0415a612dd00fa2984db89754f28d490b816aa731361a", 331791),
        ("scene1.row3.col4.ppm", "c8048c2e0d834488adfae1c2525f4c004907b369dc90730ca11bf1f6dd8d925d", 331791),
        ("scene1.row3.col5.ppm", "12fe4462944ecc291faf5f1ca9970250ff53a084c1d9bd146fa0f510c4ff8512", 331791),
        ("truedisp.row3.col3.pgm", "3192e1b8a1ad50fa6ac743cbe93aea54066bc93d2ebee432a04e7cd759450296", 110607),
    ),
    "middlebury2003-teddy": (
        ("disp2.pgm", "b223e7e7f3338d82938088f8ccd6ecc5e5893706ccd4d926ec291d29d0e2e08b", 168765),
        ("disp6.pgm", "51bad1f837279215115547b8bb6f097c7b8ef54336fd7c7e23b866e0e22658cd", 168765),
        ("im0.png", "20133591b83895b7c33cc24410493a92cf404f2fbe2ec24773be5a8e9b71fa1c", 305416),
        ("im1.png", "31c7e1231658634dd6f472403102b9ad6bf7f80835920f2731af55b7433819a5", 314938),
        ("im2.png", "21b65a3410cad806e69821613ec2acc313ec1ed08f997bf5cb5652c2e75469fb", 322010),
        ("im3.png", "98d98747f29c002419d6cac35928c7f0b519fd4ac8ed19ca677f2b66cafa4680", 323152),
        ("im4.png", "01dcc77105d21956a0c4cc9bbfde2ea8afc6597d79b153fefdf47a2c8581aff7", 322985),
        ("im5.png", "7ecf933efcef20b8f52f36ec4e90be6db4228ac66aaff2772bea40c6f9585624", 323559),
        ("im6.png", "d466909c774cb7e97143b9bcae70bd382c07da805ca930187f223bfc23c3a2d3", 323683),
        ("im7.png", "ed660007711d89e9b33e86011df2674ecd91e6a2501fcd4ccb286e2d72f6d81f", 315933),
        ("im8.png", "f079e3241986e541c8ee6232902bc88433a730bbf2aec3f052df8029c57732ba", 306366),
    ),
    "middlebury2005": (
        ("Art/disp1.png", "be77555d6abe82ba1c80bdb0b374136591538faccb7c09d18fd67872740d8abb", 44669),
        ("Art/disp5.png", "9ee57a1ebddda1286e26bb0d21806d1fc951041fd5169268aff2f42658b26bf5", 43978),
        ("Art/dmin.txt", "27badc983df1780b60c2b3fa9d3a19a00e46aac798451f0febdca52920faaddf", 3),
        ("Art/view0.png", "35ad1b192afd5eac4725e2456789ac18bcb8b8a828a94793d46a6d939dcf6b1c", 540958),
        ("Art/view1.png", "10fff49b19d9ee47a28308d10c15fc82dd4ad2d15780f23362a414a987cfeeae", 541879),
        ("Art/view2.png", "4e5766bba238afee9f2ad4d0ae6a9519e10843045b4e04ef85f9e8bca820e06c", 540039),
        ("Art/view3.png", "1e0e78206f391c7d3a1174e4b8450b8b5fecfa8495dc19c7e52d0062f7525321", 540373),
        ("Art/view4.png", "08d7d449f56ad3bccf20386f0665c436c79e77163a382154d99e0bc2d16e4649", 540241),
        ("Art/view5.png", "6c09083456dc3859e7d737a22cb5b8512ab76ab65aab3e0d2d9f957dea7b0b1e", 538910),
        ("Art/view6.png", "35279c47b024222710eb57183c2a3651fd96a8cd315664d861151b430c5d2861", 537781),
        ("Books/disp1.png", "4cb22f0cc30b98d9271faff160c07031cd531ff33f85176848ee155abcfd3391", 36112),
        ("Books/disp5.png", "85c1aa0ec17804e26503c8e9ba7f73d6d0651c25525fb1147de4fe82477bd0a1", 36691),
        ("Books/dmin.txt", "c11e3f4837efde2441e23a7b9da02131f53bf59fddeb7147c4ab81afe400460f", 4),
        ("Books/view0.png", "87273b82e3818a3d836fa04e936292d0c3fe8e040044b07a38ecaa3565ba0949", 517006),
        ("Books/view1.png", "72a983bcff4710a3a282f64c072d7204f0703d27b28fcea4ed1995e84a7df459", 515377),
        ("Books/view2.png", "8a33e16b045d9c1ceae52a2bd1f28f815286b26856ee2399e4c60bbf1a73af29", 515405),
        ("Books/view3.png", "3decaab115535c6c54faf5f91a7c37bc98d9abece1f8de75480537f9839f5c32", 512170),
        ("Books/view4.png", "ee8dd8abf30b9f2a8d5ba7b9eb84ab081153bdd6756478aa8f13abfec0eb22ad", 510630),
        ("Books/view5.png", "fd18f2d889bf244ee171e15376049c6703a16e1ea5a01a13718bc604699aacd8", 508950),
        ("Books/view6.png", "45651776f8819463589f474b7b6a381bdb6fd47098077b7a68b7b7db19403450", 508709),
        ("Dolls/disp1.png", "5c3bc84a8fd09be8df99d2438001636b3786fe813d915259dd9b8afcd0a5e3ef", 61928),
        ("Dolls/disp5.png", "9530947042418d2122c840ea1d77b976466ccf0a992167731b2ead25f1b9defb", 60703),
        ("Dolls/dmin.txt", "c11e3f4837efde2441e23a7b9da02131f53bf59fddeb7147c4ab81afe400460f", 4),
        ("Dolls/view0.png", "d64b249e42160029b878057a2354c9ca565e3239e648ee778e0cb3cee4ab9b33", 595702),
        ("Dolls/view1.png", "3fff08dc0a581f829e0739ac2fed433000d9e186a1575ba8a69897bc39473c31", 594557),
        ("Dolls/view2.png", "0554a42b3e1039f19e81c70fcb693ade107a9cb16bc29fa93fc4ef16f953bd04", 593435),
        ("Dolls/view3.png", "080dd2a53faa14f8e62f396007dbb476b7d1bdf5a60fd0a858c6bda2dcc15968", 593153),
        ("Dolls/view4.png", "78aa230992c5bacdd560bb34cae736e6b785fc22dd2f370851ef4730035b8810", 591489),
        ("Dolls/view5.png", "2288f5144d3f9b04fd8e0976b1a0caba5fda7e060551b8877edd24cfa450b905", 588104),
        ("Dolls/view6.png", "096cfbd0d96bc1fd5f18bcf5cbf7490ab4cb1773c41b9722fd15122371fe56a3", 584471),
        ("Moebius/disp1.png", "cb74a25b5a70a70257dd4cf28dda746645cd84e82c6121f6ac1de6461db1629b", 43677),
        ("Moebius/disp5.png", "045b854891790db2cabd5ea9aaf382a449b3fbee527fba31df8af78e3497c2a5", 43818),
        ("Moebius/dmin.txt", "c11e3f4837efde2441e23a7b9da02131f53bf59fddeb7147c4ab81afe400460f", 4),
        ("Moebius/view0.png", "aee7fd6eed81cb2f7845d619645ebd2a192f53c7e6ef35fbd9c4d5a220cf65f4", 552374),
        ("Moebius/view1.png", "c4dfe2f0688e11ed7a40493b00c3b5d038165a4d26b8c20a57f5cfbd5bf6032d", 552472),
        ("Moebius/view2.png", "00c56145d07f6b1a23248308b1e20e645d4f948b8ab5446b86c22bd356c396ac", 552624),
        ("Moebius/view3.png", "d29b0fa268d84e631d27377740e7136ca073c3c3eb193340a321662535b5f5f7", 551929),
        ("Moebius/view4.png", "f6d0261bb15a87e1dd6e3ac83dcf965f8d387e6410402465122206d13cc7b925", 552810),
        ("Moebius/view5.png", "de92d65af3be23e2fa96177086077fae2d762cd04a75912a6a5ba7816b205c76", 552908),
        ("Moebius/view6.png", "a3bac9d968028ed5142f7460a68715bbef96e9e17820ccbdc19e22916660d0d5", 555287),
        ("Reindeer/disp1.png", "0d2b8a1725006b47f42b28393ccc58ceafb68aa246e21b51456f8a696a8baa88", 43532),
        ("Reindeer/disp5.png", "0587dcf399fd13757a4dd0a172cb2017d5c4bc20e5cc3700690d018bf0b50d7f", 42409),
        ("Reindeer/dmin.txt", "94ea0504da906138495e412400707ebec1f315c58330820504f132152150f828", 4),
        ("Reindeer/view0.png", "3fe7316957eecf698ee29604215a640b201aee82a74494c5b8d07a6a872d9fe5", 526224),
        ("Reindeer/view1.png", "5ea5e4a8d8a75973d4d2159866c94f2e22580b70e280a801381d1389afea5d09", 521272),
        ("Reindeer/view2.png", "c7c81e4ed1f14bf9826ae62485323225f908ecdbf47b5d5d61bae93c325529d6", 516116),
        ("Reindeer/view3.png", "0874814b7fbce309f99b1e825f9709d2ee6ce678e04e7c00ff9b4348e8f7a430", 512353),
        ("Reindeer/view4.png", "83adc197df3af62213702007be969352e9210592c206adf00345f00601509fe5", 510702),
        ("Reindeer/view5.png", "ffa20d76a2afe7f56a29f6b165d3486b2290dfa896b3954ac5f671d64bec518c", 508717),
        ("Reindeer/view6.png", "867e3b51de27d5a2028b0d23936214c1e48a1751f8ae62f3f35f47210bab69f4", 504816),
    ),
    "skimage-motorcycle": (
        ("motorcycle_disp.npz", "2e49c8cebff3fa20359a0cc6880c82e1c03bbb106da81a177218281bc2f113d7", 1146173),
        ("motorcycle_left.png", "db18e9c4157617403c3537a6ba355dfeafe9a7eabb6b9b94cb33f6525dd49179", 644701),
        ("motorcycle_right.png", "5fc913ae870e42a4b662314bc904d1786bcad8e2f0b9b67dba5a229406357797", 640373),
    ),
}

_MIDDLEBURY_TERMS = (
    "Middlebury grants permission to use and publish all images and disparity maps "
    "and asks users to cite the paper(s) named above."
)

#: set -> (title, origin lines, creators and citation, terms, ground truth), for SOURCE.md.
_SOURCES = {
    "tsukuba": (
        'Tsukuba "head and lamp", row 3 (Middlebury 2001 distribution)',
        [
            (
                "https://github.com/PaleCosmos/Multimedia_Lab/tree/601fe2e7c85bac98def8c6038a404af6b40bae86/image/tsukuba"
                " (byte-identical to the Middlebury 2001 files, vision.middlebury.edu/stereo/data/scenes2001/)"
            ),
        ],
        (
            "University of Tsukuba: Y. Nakamura, T. Matsuura, K. Satoh, Y. Ohta, \"Occlusion detectable stereo\", CVPR 1996. "
            "Cite: D. Scharstein, R. Szeliski, \"A taxonomy and evaluation of dense two-frame stereo correspondence "
            "algorithms\", IJCV 47, 2002."
        ),
        _MIDDLEBURY_TERMS,
        "`truedisp.row3.col3.pgm` for col3; neighbour-view disparity = v / 16 px, v = 0 unknown; f and b unpublished.",
    ),
    "middlebury2003-teddy": (
        'Middlebury 2003 "Teddy", nine views, quarter size',
        [
            (
                "im0..im8.png: https://github.com/norishigefukushima/ViewSynthesis/tree/"
                "d503b7822e655103c50a74f27c02ea4a4adbe6e1/ViewSynthesis/img/stereo/teddy/backup"
            ),
            (
                "disp2.pgm, disp6.pgm: https://github.com/xland16/disparitymapping/tree/"
                "de5c48ec8f9e5893f324d9068372bd1a7c16b46c/teddy"
            ),
            "upstream: vision.middlebury.edu/stereo/data/scenes2003/",
        ],
        "D. Scharstein, R. Szeliski, \"High-accuracy stereo depth maps using structured light\", CVPR 2003.",
        _MIDDLEBURY_TERMS,
        "`disp2.pgm` for im2 (`disp6.pgm` for im6); im2-im6 disparity = v / 4, neighbour-view = v / 16 px, v = 0 unknown.",
    ),
    "middlebury2005": (
        "Middlebury 2005, seven views, half size: Art, Books, Dolls, Moebius, Reindeer",
        [
            (
                "https://github.com/norishigefukushima/ViewSynthesis/tree/"
                "d503b7822e655103c50a74f27c02ea4a4adbe6e1/ViewSynthesis/img/stereo/<Scene>"
            ),
            "upstream: vision.middlebury.edu/stereo/data/scenes2005/ (HalfSize)",
        ],
        (
            "Middlebury College. Cite: D. Scharstein, C. Pal, \"Learning conditional random fields for stereo\", CVPR 2007; "
            "or H. Hirschmüller, D. Scharstein, \"Evaluation of cost functions for stereo matching\", CVPR 2007."
        ),
        _MIDDLEBURY_TERMS,
        (
            "`<Scene>/disp1.png` for view1; neighbour-view disparity = v / 8 px, v = 0 unknown; `dmin.txt` in full-size px; "
            "Z = 1870 px * 40 mm / (d + dmin / 8) with the f and B that several code bases use."
        ),
    ),
    "skimage-motorcycle": (
        'Middlebury 2014 "Motorcycle" pair as shipped in scikit-image (downsampled 4x)',
        [
            (
                "https://github.com/scikit-image/scikit-image/tree/v0.25.2/skimage/data (the same files and hashes as in "
                "scikit-image's data registry)"
            ),
            "upstream: vision.middlebury.edu/stereo/data/scenes2014/",
        ],
        (
            "N. Nesic, P. Westling, X. Wang, Y. Kitajima, G. Krathwohl, D. Scharstein (Middlebury College). Cite: "
            "D. Scharstein et al., \"High-resolution stereo datasets with subpixel-accurate ground truth\", GCPR 2014."
        ),
        _MIDDLEBURY_TERMS + " scikit-image's code is BSD-3-Clause; it states no separate terms for these files.",
        (
            "`motorcycle_disp.npz` (`arr_0`, float px, +inf unknown) for the left view; f = 994.978 px, B = 193.001 mm, "
            "doffs = 31.086 px, Z = f B / (d + doffs)."
        ),
    ),
}


class DataFile(NamedTuple):
    """One file of a data set: where it goes, its known hash and where it comes from.

    Attributes
    ----------
    dataset : str
        The set (one of :data:`DATA_SETS`), also its folder name.
    path : str
        Path inside the set's folder, ``/``-separated (``"Art/view0.png"``).
    sha256 : str
        Known SHA-256, 64 lower-case hex digits.
    size : int
        Size in bytes.
    url : str
        Where it is downloaded from: the pinned upstream URL, or the mirror's.
    """

    dataset: str
    path: str
    sha256: str
    size: int
    url: str


class DataDownloadError(OSError):
    """A data file could not be downloaded, or the download did not match its known SHA-256.

    Nothing is left under the file's name when this is raised. ``file`` is
    the file's path relative to the data folder, ``url`` its source.
    """

    def __init__(self, message: str, *, file: str | None = None, url: str | None = None):
        super().__init__(message)
        self.file = file
        self.url = url


# ------------------------------------------------------------------ registry


def _upstream_url(dataset: str, path: str) -> str:
    if dataset == "tsukuba":
        return f"{_TSUKUBA_BASE}/{path}"
    if dataset == "middlebury2003-teddy":
        if path.startswith("disp"):
            return f"{_DISPARITYMAPPING_BASE}/{path}"
        return f"{_VIEWSYNTHESIS_BASE}/teddy/backup/{path}"
    if dataset == "middlebury2005":
        return f"{_VIEWSYNTHESIS_BASE}/{path}"
    return f"{_SKIMAGE_BASE}/{path}"


def _check_sets(sets) -> tuple:
    if sets is None:
        return DATA_SETS
    if isinstance(sets, str):
        sets = [sets]
    try:
        wanted = list(sets)
    except TypeError:
        msg = f"sets must be a set name or a list of them ({', '.join(DATA_SETS)}), got {type(sets).__name__}"
        raise TypeError(msg) from None
    if not wanted:
        msg = f"sets must name at least one of {', '.join(DATA_SETS)}, got an empty list"
        raise ValueError(msg)
    for name in wanted:
        if name not in DATA_SETS:
            msg = f"sets must be among {', '.join(DATA_SETS)}, got {name!r}"
            raise ValueError(msg)
    return tuple(s for s in DATA_SETS if s in wanted)


def _check_mirror(mirror) -> str | None:
    if mirror is None:
        return None
    if not isinstance(mirror, str):
        msg = f"mirror must be a URL string such as 'https://data.example.org/nfdepth', got {type(mirror).__name__}"
        raise TypeError(msg)
    text = mirror.strip().rstrip("/")
    if not text.lower().startswith(_MIRROR_SCHEMES) or len(text) <= len(text.split("://", 1)[0]) + 3:
        msg = f"mirror must be an http://, https:// or ftp:// URL of a folder laid out like the data folder, got {mirror!r}"
        raise ValueError(msg)
    try:
        urlsplit(text).port  # noqa: B018 - parsed for its check
    except ValueError as exc:
        msg = f"mirror {mirror!r} has a bad port ({exc}); expected a URL such as 'http://host:8080/data'"
        raise ValueError(msg) from None
    return text


def data_files(sets=None, *, mirror=None) -> list:
    """The files of the data sets with their known hashes, sizes and download URLs.

    Parameters
    ----------
    sets : str or sequence of str, optional
        Set names from :data:`DATA_SETS` (default: all).
    mirror : str, keyword-only, optional
        Base URL of a server holding the data folder's layout; each file's URL
        becomes ``mirror + "/" + dataset + "/" + path``. Default: the pinned
        upstream URLs (GitHub commits, a scikit-image release tag).

    Returns
    -------
    list of DataFile
        In set order, then by path (the order of each ``SHA256SUMS``).

    Raises
    ------
    ValueError
        For an unknown set name or a mirror that is not an http(s)/ftp URL.
    """
    names = _check_sets(sets)
    base = _check_mirror(mirror)
    out = []
    for name in names:
        for path, sha, size in _REGISTRY[name]:
            url = f"{base}/{name}/{path}" if base else _upstream_url(name, path)
            out.append(DataFile(name, path, sha, size, url))
    return out


def default_data_dir() -> Path:
    """The per-user folder that :func:`fetch_data` downloads into by default.

    ``$XDG_CACHE_HOME/nfdepth/data`` (``~/.cache/nfdepth/data`` when unset)
    on Linux and other POSIX systems, ``~/Library/Caches/nfdepth/data`` on
    macOS, ``%LOCALAPPDATA%\\nfdepth\\data`` on Windows. It need not exist.
    :func:`nfdepth.datasets.data_root` looks here last.

    Returns
    -------
    pathlib.Path
    """
    if sys.platform == "win32":
        local = os.environ.get("LOCALAPPDATA")
        base = Path(local) if local else Path.home() / "AppData" / "Local"
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    else:
        xdg = os.environ.get("XDG_CACHE_HOME", "")
        base = Path(xdg) if xdg and Path(xdg).is_absolute() else Path.home() / ".cache"
    return base / "nfdepth" / "data"


# ------------------------------------------------------------------ download


def _import_pooch():
    """``pooch`` (and its HTTP client), or an error naming the missing package and the install command."""
    try:
        import pooch
        import requests  # noqa: F401 - pooch's HTTP downloader needs it
    except ImportError as exc:
        name = getattr(exc, "name", None) or "pooch"
        msg = f"downloading the data needs the optional package '{name}', which is not installed; install it with: {_INSTALL_HINT}"
        raise ModuleNotFoundError(msg, name=name) from None
    return pooch


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _is_intact(path: Path, entry: DataFile) -> bool:
    return path.is_file() and path.stat().st_size == entry.size and _sha256(path) == entry.sha256


def _human_size(n: int) -> str:
    return f"{n / 1e6:.1f} MB" if n >= 1e6 else f"{n / 1e3:.0f} kB"


def _network_reason(exc) -> str:
    import requests

    if isinstance(exc, requests.exceptions.HTTPError) and exc.response is not None:
        exc.response.close()
        return f"HTTP {exc.response.status_code} {exc.response.reason or ''}".strip()
    if isinstance(exc, requests.exceptions.Timeout):
        return "the connection timed out"
    found = re.search(r"\[Errno -?\d+\] [^'\")\]]+", str(exc))
    ftp = isinstance(exc, OSError) and not isinstance(exc, requests.exceptions.RequestException)  # (requests' errors are OSErrors)
    if ftp or isinstance(exc, requests.exceptions.ConnectionError):  # ftp: an ftp:// mirror's socket error (ftplib)
        return f"connection failed ({found.group(0).strip()})" if found else "connection failed"
    return " ".join(str(exc).split())[:200] or type(exc).__name__


def _download(pooch, entry: DataFile, target: Path) -> None:
    """Download one file to ``target`` through pooch, which checks the hash before the final rename."""
    import requests

    name = f"{entry.dataset}/{entry.path}"
    logger = pooch.get_logger()
    level = logger.level
    logger.setLevel("WARNING")  # pooch logs every download at INFO level on stderr
    url, options = entry.url, {}
    parts = urlsplit(url)
    if parts.scheme.lower() == "ftp" and parts.port is not None:  # pooch connects to the netloc with its downloader's port
        url = urlunsplit(parts._replace(netloc=parts.hostname))
        options["downloader"] = pooch.FTPDownloader(port=parts.port, progressbar=False)
    network_errors = (requests.exceptions.RequestException, *(ftplib.all_errors if parts.scheme.lower() == "ftp" else ()))
    try:
        pooch.retrieve(url, known_hash=f"sha256:{entry.sha256}", fname=target.name, path=target.parent, progressbar=False, **options)
    except ValueError as exc:  # pooch: hash mismatch; it has deleted the download
        found = re.search(r"but got ([0-9a-fA-F]+)", str(exc))
        got = found.group(1).lower() if found else "a different hash"
        msg = (
            f"downloaded '{name}' from {entry.url} does not match its known SHA-256: expected {entry.sha256}, got {got}; "
            "the download was deleted. The server holds a different file: try again later or from another mirror, "
            "and report it if it persists"
        )
        raise DataDownloadError(msg, file=name, url=entry.url) from exc
    except network_errors as exc:
        msg = (
            f"could not download '{name}' from {entry.url}: {_network_reason(exc)}; nothing was written for it. "
            "Check the network connection (or the mirror URL) and run the fetch again: the files already checked are kept"
        )
        raise DataDownloadError(msg, file=name, url=entry.url) from exc
    finally:
        logger.setLevel(level)
    _usual_permissions(target)


def _usual_permissions(path: Path) -> None:
    """Give a downloaded file the mode of a newly created file (pooch's temporary file is owner-only)."""
    if os.name != "posix":
        return
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(path, 0o666 & ~mask)


def _write_text(path: Path, text: str) -> None:
    if path.is_file() and path.read_text(encoding="utf-8") == text:
        return
    from .io import _kept_on_failure, atomic_write

    with _kept_on_failure():  # a completed set stays complete if a later one fails
        atomic_write(path, lambda fh: fh.write(text.encode("utf-8")), force=True)


def _sums_text(entries) -> str:
    return "".join(f"{e.sha256}  {e.path}\n" for e in entries)


#: The line that opens the body of a SOURCE.md :func:`fetch_data` wrote (and may write again).
_SOURCE_MARK = "Downloaded by `nfdepth fetch-data` "


def _written_here(path: Path) -> bool:
    """Whether ``path`` is a SOURCE.md that :func:`fetch_data` wrote (its third line opens with :data:`_SOURCE_MARK`)."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return False
    return len(lines) > 2 and lines[2].startswith(_SOURCE_MARK)


def _source_text(name: str, mirror: str | None) -> str:
    title, origins, creators, terms, truth = _SOURCES[name]
    fetched = f"from the mirror {mirror}/{name}/" if mirror else "from the pinned origin below"
    lines = [
        f"# {title}",
        "",
        f"{_SOURCE_MARK}{fetched}; every file matched its known SHA-256",
        "(check again with `sha256sum -c SHA256SUMS`). The project's own copies carry a longer SOURCE.md.",
        "",
        "- Origin: " + "; ".join(origins),
        f"- Creators and citation: {creators}",
        f"- Terms: {terms}",
        f"- Ground truth: {truth}",
        "",
    ]
    return "\n".join(lines)


def fetch_data(dest=None, *, sets=None, mirror=None, progress=False) -> Path:
    """Download the real data sets into ``dest``, checking every file's SHA-256.

    The layout is that of ``shared/data`` (one folder per set, see
    :mod:`nfdepth.datasets`), so the result can be passed as ``root=`` to the
    loaders, as ``--data`` or ``NFDEPTH_DATA`` to ``nfdepth evaluate``; in
    the default folder they find it by themselves (after the folders
    :func:`nfdepth.datasets.data_root` tries first). Files already present
    with the right hash are not downloaded again; a present file with another
    hash is replaced. Each set folder also gets ``SHA256SUMS`` and a short
    ``SOURCE.md`` (origin, citation, terms), written once all its files are
    in place; a ``SOURCE.md`` already there is kept, unless this function
    wrote it and downloaded files now (a copy's own, longer ``SOURCE.md`` is
    never replaced).

    Parameters
    ----------
    dest : str or os.PathLike, optional
        The data folder (created if missing). Default:
        :func:`default_data_dir`.
    sets : str or sequence of str, keyword-only, optional
        Which sets, from :data:`DATA_SETS` (default: all, about 27 MB).
    mirror : str, keyword-only, optional
        Base URL of a server with the data folder's layout (a lab mirror):
        each file is fetched from ``mirror/<set>/<path>``, still checked
        against the known hash. Default: the pinned upstream URLs.
    progress : bool, keyword-only
        Print a line per downloaded file and per set on standard output.

    Returns
    -------
    pathlib.Path
        The data folder (absolute).

    Raises
    ------
    ValueError
        For an unknown set name or a malformed mirror URL.
    ModuleNotFoundError
        If ``pooch`` is missing and something must be downloaded (the
        message says ``pip install 'nfdepth[data]'``).
    DataDownloadError
        If a download fails or does not match its known hash; nothing is
        left under that file's name, files checked before it are kept (the
        folders this call made and left empty are removed).
    OSError
        If ``dest`` is not a folder or cannot be written.

    Examples
    --------
    >>> root = nfdepth.fetch_data(sets=["tsukuba"])  # doctest: +SKIP
    >>> scene = nfdepth.datasets.load_tsukuba(root=root)  # doctest: +SKIP
    """
    names = _check_sets(sets)
    base = _check_mirror(mirror)
    if dest is not None and not isinstance(dest, (str, os.PathLike)):
        msg = f"dest must be a folder path (str or os.PathLike), got {type(dest).__name__}"
        raise TypeError(msg)
    root = default_data_dir() if dest is None else Path(dest).expanduser()
    if root.exists() and not root.is_dir():
        raise NotADirectoryError(f"cannot fetch the data into '{root}': it exists and is not a folder; give a folder")

    def say(text: str) -> None:
        if progress:
            print(text, flush=True)

    made: list = []  # the folders this call creates, outermost first: removed again, if left empty, when it fails

    def make(folder: Path) -> None:
        missing = []
        while not folder.exists():
            missing.append(folder)
            folder = folder.parent
        for f in reversed(missing):
            f.mkdir()
            made.append(f)

    pooch = None
    try:
        for name in names:
            entries = data_files(name, mirror=base)
            folder = root / name
            fetched = 0
            for entry in entries:
                target = folder / entry.path
                if target.is_dir():
                    raise IsADirectoryError(f"cannot write '{target}': it is a folder; remove it and fetch again")
                if _is_intact(target, entry):
                    continue
                if pooch is None:
                    pooch = _import_pooch()
                make(target.parent)
                if target.exists():
                    target.unlink()  # another hash: a corrupt or outdated copy, replaced below
                say(f"  downloading {name}/{entry.path} ({_human_size(entry.size)}) from {entry.url}")
                _download(pooch, entry, target)
                fetched += 1
            make(folder)
            _write_text(folder / "SHA256SUMS", _sums_text(entries))
            source = folder / "SOURCE.md"
            if not source.exists() or (fetched and _written_here(source)):  # a curated SOURCE.md (the project's) is never replaced
                _write_text(source, _source_text(name, base))
            total = _human_size(sum(e.size for e in entries))
            say(f"{name}: {len(entries)} files ({total}) in {folder}: {fetched} downloaded, {len(entries) - fetched} already there")
    except BaseException:
        for f in reversed(made):  # innermost first; a folder holding a checked file stays
            try:
                f.rmdir()
            except OSError:
                pass
        raise
    return root.resolve()
