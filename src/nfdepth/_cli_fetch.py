"""``nfdepth fetch-data``: download the real data sets, checked by SHA-256 (needs ``pooch``).

A plug-in of :mod:`nfdepth.cli` (listed in ``_PLUGIN_COMMANDS``): ``register``
adds the sub-command to the parser.
"""

from __future__ import annotations

import os
from pathlib import Path

from .fetch import (
    DATA_SETS,
    DataDownloadError,
    data_files,
    default_data_dir,
    fetch_data,
)

EXIT_OK = 0
EXIT_USAGE = 2
EXIT_WRITE = 4
EXIT_DATA = 5

#: set -> a scene name that ``nfdepth evaluate`` accepts, for the usage hint.
_EXAMPLE_SCENE = {
    "tsukuba": "tsukuba",
    "middlebury2003-teddy": "teddy",
    "middlebury2005": "middlebury2005/Art",
    "skimage-motorcycle": "motorcycle",
}


def register(sub, CLIError) -> None:
    """Add ``fetch-data`` to the sub-parsers ``sub``; errors are raised as ``CLIError``."""
    p = sub.add_parser(
        "fetch-data",
        help="download the real data sets with ground truth (checked by SHA-256; needs pooch)",
        description=(
            "Download the Tsukuba, Middlebury 2003 Teddy, Middlebury 2005 and Motorcycle files (about 27 MB) from "
            "pinned upstream URLs, or from a mirror with the same layout, into the folder layout that "
            "'nfdepth evaluate' and nfdepth.datasets read. Every file is checked against its known SHA-256; files "
            "already present are kept. Needs the optional package pooch: pip install 'nfdepth[data]'."
        ),
    )
    p.add_argument("--dest", metavar="DIR", help=f"the data folder (default: {default_data_dir()}, found automatically)")
    p.add_argument(
        "--set", dest="sets", nargs="+", action="extend", choices=DATA_SETS, metavar="NAME",
        help=f"only these sets (default: all; choices: {', '.join(DATA_SETS)})",
    )
    p.add_argument("--mirror", metavar="URL", help="base URL of a server laid out like the data folder (files at URL/<set>/<file>)")
    p.add_argument("--list", action="store_true", help="list the sets, their sizes and where they would go; download nothing")

    def run(args) -> int:
        return _cmd_fetch_data(args, CLIError)

    p.set_defaults(func=run)


def _human_size(n: int) -> str:
    return f"{n / 1e6:.1f} MB" if n >= 1e6 else f"{n / 1e3:.0f} kB"


def _dest(args, CLIError) -> Path:
    dest = Path(args.dest).expanduser() if args.dest else default_data_dir()
    if dest.exists() and not dest.is_dir():
        raise CLIError(f"--dest '{dest}' exists and is not a directory; expected a folder for the data", EXIT_WRITE)
    return dest


def _list(dest: Path, sets, mirror) -> None:
    entries = data_files(sets, mirror=mirror)
    print(f"{'set':<22} {'files':>5} {'size':>8}  state (by size) in {dest}")
    for name in dict.fromkeys(e.dataset for e in entries):
        mine = [e for e in entries if e.dataset == name]
        present = sum((dest / name / e.path).is_file() and (dest / name / e.path).stat().st_size == e.size for e in mine)
        state = "present" if present == len(mine) else ("not downloaded" if present == 0 else f"{present} of {len(mine)} present")
        print(f"{name:<22} {len(mine):>5} {_human_size(sum(e.size for e in mine)):>8}  {state}")
    print(f"{'total':<22} {len(entries):>5} {_human_size(sum(e.size for e in entries)):>8}")
    print(f"source: {'the mirror ' + mirror if mirror else 'pinned upstream URLs (GitHub commits, scikit-image v0.25.2)'}")


def _usage_hint(root: Path, sets) -> str:
    scene = _EXAMPLE_SCENE[sets[0]]
    env = os.environ.get("NFDEPTH_DATA")
    default = default_data_dir()
    if env and Path(env).expanduser().resolve() == root:
        return f"NFDEPTH_DATA points here: nfdepth evaluate {scene}"
    use = f"use it with: NFDEPTH_DATA={root} nfdepth evaluate {scene} (or nfdepth evaluate {scene} --data {root})"
    if root == default.resolve() and not env:
        from .datasets import DataNotFoundError, data_root

        try:
            found = data_root()  # ../shared/data, or one beside the installation, comes first
        except DataNotFoundError:  # pragma: no cover - the folder was just filled
            return use
        if found == root:
            return f"found automatically (from this folder): nfdepth evaluate {scene}"
        return f"{use}; without either, nfdepth finds '{found}' first"
    return use


def _cmd_fetch_data(args, CLIError) -> int:
    dest = _dest(args, CLIError)
    sets = list(dict.fromkeys(args.sets)) if args.sets else list(DATA_SETS)
    if args.list:
        _list(dest, sets, args.mirror)
        return EXIT_OK
    try:
        root = fetch_data(dest, sets=sets, mirror=args.mirror, progress=True)
    except DataDownloadError as exc:
        raise CLIError(str(exc), EXIT_DATA) from exc
    except ModuleNotFoundError as exc:
        raise CLIError(str(exc), EXIT_USAGE) from exc
    count = len(data_files(sets))
    print(f"data ready in {root} ({', '.join(sets)}: {count} files checked by SHA-256)")
    print(_usage_hint(root, [s for s in DATA_SETS if s in sets]))
    return EXIT_OK
