"""``nfdepth stereo --cameras FILE``: depth from a calibrated row of cameras that is not rectified (:mod:`nfdepth.rectify`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Options of ``nfdepth stereo`` that the cameras file replaces or that a rectified row does not take, and why.
_REFUSED = {
    "rig": "the cameras file gives the whole geometry",
    "positions": "the positions come from the cameras' centres",
    "column": "a column needs its own rectification (run the row and the column separately)",
    "column_reference": "a column needs its own rectification",
    "column_positions": "a column needs its own rectification",
    "focal_px": "the cameras give the focal lengths",
    "baseline": "the cameras' centres give the baseline",
    "disparity_offset_px": "the rectified views share one principal point",
    "cx_px": "the cameras give the principal points",
    "cy_px": "the cameras give the principal points",
    "disparity_range": "the rectified row's disparities are px per scene unit of position; leave the range to the pyramid",
    "fill": "filling runs along the rectified row, not the reference's own pixels",
    "fill_mask": "filling runs along the rectified row",
}


def run_calibrated_stereo(args, CLIError, *, check_output, figure_outputs, write_figures) -> int:
    """The ``--cameras`` branch of ``nfdepth stereo``: depth (scene units) in the reference camera's own pixels."""
    from .io import (
        read_image,
        to_float32_map,
        to_rgb8,
        write_array,
        write_colormap_png,
        write_ply,
    )
    from .rectify import calibrated_row_depth, load_cameras

    for key, why in _REFUSED.items():
        value = getattr(args, key, None)
        if value not in (None, False, []):
            raise CLIError(f"--{key.replace('_', '-')} does not go with --cameras: {why}")
    if args.axis != "x":
        raise CLIError("--axis does not go with --cameras: the row's direction comes from the cameras' centres")
    if args.threads is not None and args.threads < 1:
        raise CLIError(f"--threads must be an integer >= 1, got {args.threads}")
    reference = len(args.views) // 2 if args.reference is None else args.reference
    if not 0 <= reference < len(args.views):
        raise CLIError(f"--reference must index one of the {len(args.views)} views (0..{len(args.views) - 1}), got {reference}")
    cameras = load_cameras(args.cameras)
    if len(cameras) != len(args.views):
        raise CLIError(f"cameras '{args.cameras}' has {len(cameras)} [[camera]] tables for {len(args.views)} views: expected one per view, in the order of the views")
    inputs = [*args.views, args.cameras]
    outputs = [check_output(args.out, force=args.force, inputs=inputs)]
    if args.uncertainty:
        outputs.append(check_output(args.uncertainty, force=args.force, what="--uncertainty", inputs=inputs))
    if args.preview:
        outputs.append(check_output(args.preview, force=args.force, exts=(".png",), what="--preview", inputs=inputs))
    if args.ply:
        outputs.append(check_output(args.ply, force=args.force, exts=(".ply",), what="--ply", inputs=inputs))
    figures = figure_outputs(args, with_std=bool(args.uncertainty), inputs=inputs)
    every = outputs + list(figures.values())
    if len({str(p.resolve()) for p in every}) != len(every):
        raise CLIError("output paths must differ from each other")
    views = [read_image(v) for v in args.views]
    for k, (path, view, cam) in enumerate(zip(args.views, views, cameras)):
        if view.shape != cam.shape:
            raise CLIError(
                f"view {k} '{Path(path).name}' is {view.shape[1]}x{view.shape[0]} px, its camera (camera[{k}] of '{args.cameras}') "
                f"{cam.width_px}x{cam.height_px}: expected the size the camera was calibrated at"
            )
    options = {"edges_only": args.edges_only}
    for key, name in (("sigma_px", "sigma_px"), ("levels", "levels"), ("threads", "threads"), ("cost_step_px", "cost_step_px")):
        value = getattr(args, key)
        if value is not None:
            options[name] = value
    res = calibrated_row_depth(views, cameras, reference=reference, **options)
    hint = "give the cameras' positions in a unit that keeps depths in that range"
    depth = to_float32_map(res.depth, what="a depth", hint=hint)
    std = to_float32_map(res.depth_std, what="a standard deviation", hint=hint)
    write_array(outputs[0], depth, force=args.force)
    k = 1
    if args.uncertainty:
        write_array(outputs[k], std, force=args.force)
        k += 1
    if args.preview:
        write_colormap_png(outputs[k], depth, force=args.force)
        k += 1
    if args.ply:
        pts, cols = res.points(image=to_rgb8(read_image(args.views[reference], grey=False, dtype=None)))
        write_ply(outputs[k], pts, colors=cols, force=args.force)
    name = Path(args.views[reference]).name
    write_figures(figures, depth, std, title=f"view {reference} ({name})", unit="scene units", quantity="depth")
    valid = np.isfinite(depth)
    finite = depth[valid]
    rng_txt = f"{np.min(finite):.3g}..{np.max(finite):.3g} scene units" if finite.size else "none"
    spacing = np.diff(res.row.positions)
    print(
        f"depth for view {reference} ({name}), rectified row of {len(views)} cameras (spacing {np.min(spacing):.3g}..{np.max(spacing):.3g} scene units, "
        f"farthest centre {np.max(res.row.off_line):.2g} off the line): {int(valid.sum())} of {valid.size} pixels ({100.0 * valid.mean():.1f} %), "
        f"range {rng_txt}, {res.result.runtime_s:.2f} s, {res.result.levels} levels -> {outputs[0]}"
    )
    return 0
