"""``nfdepth stereo --cameras FILE [--column ... --column-cameras FILE]``: depth from a calibrated row (and column) of cameras that is not rectified (:mod:`nfdepth.rectify`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Options of ``nfdepth stereo`` that the cameras file replaces or that a rectified row does not take, and why.
_REFUSED = {
    "rig": "the cameras file gives the whole geometry",
    "positions": "the positions come from the cameras' centres",
    "column_positions": "the column's positions come from its cameras' centres (--column-cameras)",
    "focal_px": "the cameras give the focal lengths",
    "baseline": "the cameras' centres give the baseline",
    "disparity_offset_px": "the rectified views share one principal point",
    "cx_px": "the cameras give the principal points",
    "cy_px": "the cameras give the principal points",
    "disparity_range": "the rectified row's disparities are px per scene unit of position; give the depths to search with --depth-range NEAR FAR",
}


def run_calibrated_stereo(args, CLIError) -> int:
    """The ``--cameras`` branch of ``nfdepth stereo``: depth (scene units) in the reference camera's own pixels."""
    from ._cli_rig import write_figures
    from .cli import (
        _check_finite,
        _depth_range,
        _exposure_note,
        _positive,
        _stereo_outputs,
        _write_stereo_maps,
    )
    from .io import read_image, to_float32_map, to_rgb8, write_ply
    from .rectify import calibrated_grid_depth, calibrated_row_depth, load_cameras

    for key, why in _REFUSED.items():
        value = getattr(args, key, None)
        if value not in (None, False, []):
            raise CLIError(f"--{key.replace('_', '-')} does not go with --cameras: {why}")
    if args.axis is not None:  # (also an explicit x: the row may run along any direction)
        raise CLIError("--axis does not go with --cameras: the row's direction comes from the cameras' centres")
    if args.threads is not None and args.threads < 1:
        raise CLIError(f"--threads must be an integer >= 1, got {args.threads}")
    _positive("--cost-step-px", args.cost_step_px)
    depth_range = _depth_range(args.depth_range)
    reference = len(args.views) // 2 if args.reference is None else args.reference
    if not 0 <= reference < len(args.views):
        raise CLIError(f"--reference must index one of the {len(args.views)} views (0..{len(args.views) - 1}), got {reference}")
    column = args.column or []
    if bool(column) != bool(args.column_cameras):
        raise CLIError("--column and --column-cameras go together with --cameras: the column's views and their calibrated cameras")
    if args.column_reference is not None and not column:
        raise CLIError("--column-reference needs --column (the views of the second line)")
    column_reference = None
    if column:
        if len(column) < 2:
            raise CLIError(f"--column needs at least 2 views (3 or more recommended), got {len(column)}")
        column_reference = len(column) // 2 if args.column_reference is None else args.column_reference
        if not 0 <= column_reference < len(column):
            raise CLIError(f"--column-reference must index one of the {len(column)} column views (0..{len(column) - 1}), got {column_reference}")
    cameras = load_cameras(args.cameras)
    if len(cameras) != len(args.views):
        raise CLIError(f"cameras '{args.cameras}' has {len(cameras)} [[camera]] tables for {len(args.views)} views: expected one per view, in the order of the views")
    column_cameras = load_cameras(args.column_cameras) if column else []
    if len(column_cameras) != len(column):
        raise CLIError(f"cameras '{args.column_cameras}' has {len(column_cameras)} [[camera]] tables for {len(column)} column views: expected one per view, in their order")
    outputs, figures = _stereo_outputs(args, [*args.views, *column, args.cameras, args.column_cameras])
    views = [read_image(v) for v in args.views]
    column_views = [read_image(v) for v in column]
    _check_finite([*args.views, *column], [*views, *column_views])
    for what, paths, imgs, cams, source in (("view", args.views, views, cameras, args.cameras), ("column view", column, column_views, column_cameras, args.column_cameras)):
        for k, (path, view, cam) in enumerate(zip(paths, imgs, cams)):
            if view.shape != cam.shape:
                raise CLIError(
                    f"{what} {k} '{Path(path).name}' is {view.shape[1]}x{view.shape[0]} px, its camera (camera[{k}] of '{source}') "
                    f"{cam.width_px}x{cam.height_px}: expected the size the camera was calibrated at"
                )
    options = {"edges_only": args.edges_only, "depth_range": depth_range}
    if args.no_match_exposure:
        options["match_exposure"] = False
    for key, name in (("sigma_px", "sigma_px"), ("levels", "levels"), ("threads", "threads"), ("cost_step_px", "cost_step_px")):
        value = getattr(args, key)
        if value is not None:
            options[name] = value
    try:
        if column:
            res = calibrated_grid_depth(views, cameras, column_views, column_cameras, row_reference=reference, column_reference=column_reference, **options)
            line = res.row
        else:
            res = line = calibrated_row_depth(views, cameras, reference=reference, **options)
    except ValueError as exc:  # the library names its keyword; the user gave the option
        if depth_range is None or "depth_range (" not in str(exc):
            raise
        raise CLIError(str(exc).replace("depth_range (", "--depth-range (", 1)) from None
    filled = None
    if args.fill:  # along each line's rectified baseline (CalibratedRowDepth.filled); no std where filled
        from dataclasses import replace

        filled_depth, filled = res.filled()
        res = replace(res, depth=filled_depth)
    hint = "give the cameras' positions in a unit that keeps depths in that range"
    depth = to_float32_map(res.depth, what="a depth", hint=hint)
    std = to_float32_map(res.depth_std, what="a standard deviation", hint=hint)
    k = _write_stereo_maps(args, outputs, depth, std, filled)
    if args.ply:
        pts, cols = res.points(image=to_rgb8(read_image(args.views[reference], grey=False, dtype=None)))
        write_ply(outputs[k], pts, colors=cols, force=args.force)
    name = Path(args.views[reference]).name
    write_figures(figures, depth, std, title=f"view {reference} ({name})", unit="scene units", quantity="depth")
    valid = np.isfinite(depth)
    finite = depth[valid]
    rng_txt = f"{np.min(finite):.3g}..{np.max(finite):.3g} scene units" if finite.size else "none"
    spacing = np.diff(line.row.positions)
    notes = ""
    if filled is not None:
        notes += f", {int(np.count_nonzero(filled & valid))} filled"
    lines = [("", line, args.views)] + ([("column ", res.column, column)] if column else [])
    notes += _exposure_note([(label, ln.result, [paths[j] for j in ln.row.order]) for label, ln, paths in lines])
    if column:
        notes += f", fused with a column of {len(column_views)} cameras ({int(np.count_nonzero(res.line_count == 2))} pixels from both, {int(np.count_nonzero(res.conflict))} refused for disagreeing)"
    print(
        f"depth for view {reference} ({name}), rectified row of {len(views)} cameras (spacing {np.min(spacing):.3g}..{np.max(spacing):.3g} scene units, "
        f"farthest centre {np.max(line.row.off_line):.2g} off the line){notes}: {int(valid.sum())} of {valid.size} pixels ({100.0 * valid.mean():.1f} %), "
        f"range {rng_txt}, {line.result.runtime_s:.2f} s, {line.result.levels} level{'s' if line.result.levels != 1 else ''} -> {outputs[0]}"
    )
    return 0
