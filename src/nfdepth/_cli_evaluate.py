"""``nfdepth evaluate``: nfdepth and its peers against the ground truth of the real data sets.

A plug-in of :mod:`nfdepth.cli` (listed in ``_PLUGIN_COMMANDS``): ``register``
adds the sub-command to the parser.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from .evaluate import DEFAULT_METHODS, METHODS, evaluation_rows, view_size_problems

EXIT_OK = 0
EXIT_USAGE = 2
EXIT_WRITE = 4
EXIT_DATA = 5


def register(sub, CLIError) -> None:
    """Add ``evaluate`` to the sub-parsers ``sub``; errors are raised as ``CLIError``."""
    p = sub.add_parser(
        "evaluate",
        help="nfdepth vs SGBM and Waxman-Sinha (relative optical flow) against ground truth",
        description=(
            "Run nfdepth's static stereo and its peers on real scenes with ground truth and print, per scene, "
            "points, density, median and p90 relative disparity error, bad >1 px and >0.5 px, bias, runtime and, for "
            "nfdepth, how honest its error bar is (err/std: the median of |error| / std with the truth's rounding in "
            "quadrature; 0.67 when calibrated, more when too narrow): "
            "nfdepth at its edge points and dense, each peer at the same edge points and dense."
        ),
    )
    p.add_argument(
        "dataset",
        metavar="DATASET",
        help="a scene (tsukuba, teddy, middlebury2005/Art, motorcycle), a group (middlebury2005, all) or a data folder",
    )
    p.add_argument("--data", metavar="DIR", help="the data folder (default: NFDEPTH_DATA, ../shared/data or the fetch-data folder)")
    p.add_argument("--views", default="all", metavar="three|all", help="views to use: all (default) or three around the reference")
    p.add_argument("--methods", nargs="+", choices=METHODS, default=list(DEFAULT_METHODS), metavar="M",
                   help=f"methods (default: {' '.join(DEFAULT_METHODS)}; choices: {', '.join(METHODS)})")
    p.add_argument("--downsample", type=int, default=1, metavar="K", help="area-downsample by K first (default 1: full size)")
    p.add_argument(
        "--json", metavar="FILE",
        help="write the results as JSON: a list, one entry per scene (its fields: help(nfdepth.evaluate.evaluate_scene) and disparity_errors; rates as fractions, px and s)",
    )
    p.add_argument("--maps", metavar="DIR", help="write |error| maps (PNG, one per scene and method) here")
    p.add_argument("--cost-step-px", type=float, metavar="PX", help="nfdepth's cost-volume candidate spacing (as nfdepth stereo --cost-step-px; default 0.5)")

    def run(args) -> int:
        return _cmd_evaluate(args, CLIError)

    p.set_defaults(func=run)


def _check_downsample(factor: int, scene, CLIError, methods=("nfdepth",)) -> None:
    """Refuse a ``--downsample`` factor that leaves views too small for one of ``methods`` (names the largest usable factor)."""
    h, w = scene.shape

    def fails(k):
        return view_size_problems((h // k, w // k), methods)

    if not fails(factor):
        return
    # every factor beyond the longer side leaves 0 x 0 px views (which fail): start the scan below it
    largest = next((k for k in range(min(factor - 1, max(h, w)), 0, -1) if not fails(k)), None)
    expected = f"an integer from 1 to {largest}" if largest else "1 (no downsampling: the views are too small already)"
    raise CLIError(
        f"--downsample {factor} is too large for {scene.name} ({w}x{h} px): expected {expected} ({'; '.join(fails(factor))})",
        EXIT_USAGE,
    )


def _fmt_table(res) -> str:
    def pct(x, digits=1):
        return "     -" if x is None or x != x else f"{100 * x:5.{digits}f}%"

    share = res.get("near_steps_share")
    rows = [(f"{method} ({label})", e, runtime_s) for method, label, e, runtime_s in evaluation_rows(res)]
    width = max([34, *(len(label) for label, _, _ in rows)])  # the columns stay aligned with a long method name
    lines = [
        f"{res['scene']}: {res['view_count']} views {res['views']}, reference view {res['reference_index']}, "
        f"{res['shape'][1]}x{res['shape'][0]} px" + (f" (downsampled {res['downsample']}x)" if res["downsample"] > 1 else "")
        + f", {res['truth_points']} ground-truth pixels"
        + (f" stored in steps of {res['truth_step_px']:g} px" if res.get("truth_step_px") else "")
        + (f"; {pct(share).strip()} of them near a depth step" if share is not None and math.isfinite(share) else "")
        + "".join(f"; nfdepth {key} = {value:g}" for key, value in sorted(res.get("stereo_options", {}).items())),
        (
            f"  {'method':<{width}} {'points':>7} {'density':>7} {'med rel':>7} {'rounding':>8} {'p90 rel':>7} {'bad>1':>6} {'bad>.5':>6} "
            f"{'bias px':>7} {'err/std':>7} {'rms e/s':>7} {'near step':>9} {'bad>1 off':>9} {'runtime':>8}"
        ),
    ]
    for label, e, runtime_s in rows:
        bias = e.get("bias_px", float("nan"))
        z, rms = (float("nan") if e.get(key) is None else e[key] for key in ("median_z", "rms_ratio"))
        lines.append(
            f"  {label:<{width}} {e['points']:>7d} {pct(e['density']):>7} {pct(e['median_rel'], 2):>7} {pct(e.get('truth_rounding_rel'), 2):>8} "
            f"{pct(e['p90_rel'], 2):>7} {pct(e['bad_1px']):>6} {pct(e['bad_0_5px']):>6} "
            f"{'      -' if math.isnan(bias) else format(bias, '+7.3f')} {'      -' if math.isnan(z) else format(z, '7.2f')} {'      -' if math.isnan(rms) else format(rms, '7.2f')} {pct(e.get('near_steps_share')):>9} {pct(e.get('bad_1px_off_steps')):>9} "
            f"{runtime_s:>7.3f}s"
        )
    return "\n".join(lines)


def _cmd_evaluate(args, CLIError) -> int:
    from . import datasets
    from .evaluate import error_map_png, evaluate_scene, resolve_dataset, select_views, to_jsonable
    from .io import atomic_write, make_output_folder

    views = args.views.strip().lower()
    if views not in ("all", "three"):
        raise CLIError(f"--views must be 'three' or 'all', got {args.views!r}", EXIT_USAGE)
    if args.downsample < 1:
        raise CLIError(f"--downsample must be a positive integer, got {args.downsample}", EXIT_USAGE)
    from .cli import (
        _as_option,
        _check_json_apart,
        _check_out_dir,
        _check_output,
        _positive,
    )

    if args.cost_step_px is not None and "nfdepth" not in args.methods:  # the peers have no cost volume: it would be reported, not applied
        raise CLIError(f"--cost-step-px spaces nfdepth's cost volume: add nfdepth to --methods (now {' '.join(args.methods)}), or leave --cost-step-px out", EXIT_USAGE)
    cost_step = _positive("--cost-step-px", args.cost_step_px)
    stereo_options = {} if cost_step is None else {"cost_step_px": cost_step}
    if args.json and args.maps:
        _check_json_apart(args.json, args.maps, "--maps")
    js = _check_output(args.json, force=True, exts=(".json",), what="--json") if args.json else None
    maps = _check_out_dir(args.maps, "--maps") if args.maps else None
    select_views(3, 1, views)
    if args.data is not None and not Path(args.data).expanduser().is_dir():
        raise CLIError(f"--data '{args.data}' is not a directory; expected the data folder (as filled by `nfdepth fetch-data --dest DIR`)", EXIT_DATA)
    root, names = resolve_dataset(args.dataset, args.data)
    loaded = {}
    if args.downsample > 1 and len(names) > 1:  # before any output: the factor must fit every scene (kept, not read twice)
        for name in names:
            loaded[name] = datasets.load_scene(name, root)
            _check_downsample(args.downsample, loaded[name], CLIError, args.methods)
    results = []
    for name in names:
        scene = loaded.pop(name) if name in loaded else datasets.load_scene(name, root)
        _check_downsample(args.downsample, scene, CLIError, args.methods)
        try:
            res = evaluate_scene(scene, views=views, methods=args.methods, downsample=args.downsample, keep_maps=maps is not None, stereo_options=stereo_options)
        except ValueError as exc:  # the step is checked against the range each scene's pyramid finds
            raise _as_option(exc, "cost_step_px", "--cost-step-px") from None
        print(_fmt_table(res), flush=True)
        if maps is not None:
            make_output_folder(maps, parents=True)  # removed again if the run fails
            stem = f"{res['scene'].replace('/', '_')}_{res['view_count']}views"
            for method, disp in res["maps"].items():
                error_map_png(maps / f"{stem}_{method}.png", disp, res["truth"], title=f"{res['scene']} {method}: |d - d_true|")
        results.append(to_jsonable(res))
    if js is not None:
        text = json.dumps(results, indent=2)
        atomic_write(js, lambda fh: fh.write(text.encode()), force=True)
        print(f"wrote {js}")
    if maps is not None:
        print(f"wrote error maps to {maps}/")
    return EXIT_OK
