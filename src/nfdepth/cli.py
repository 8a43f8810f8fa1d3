"""The ``nfdepth`` command line: a thin layer over the library.

Errors are one line on stderr and a distinct exit code (``--debug`` shows
the traceback):

====  ==========================================================
code  meaning
====  ==========================================================
0     success
1     unexpected internal error (a bug: please report it)
2     bad argument or bad input value
3     an input file could not be read (or a data set's file is broken)
4     an output could not be written, or exists (use ``--force``)
5     data set not found, or its download failed (``fetch-data``)
130   interrupted (Ctrl-C, SIGINT); no partial output is left behind (the
      outputs the run had already completed are removed)
143   terminated (SIGTERM); the same
====  ==========================================================

Standard output closed early (``nfdepth evaluate ... | head -1``) is not an
error: the run goes on without printing and writes its files.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import re
import signal
import sys
import threading
import traceback
import warnings
from pathlib import Path

import numpy as np

__all__ = ["main", "build_parser"]

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_USAGE = 2
EXIT_READ = 3
EXIT_WRITE = 4
EXIT_DATA = 5
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143


#: Modules that add sub-commands: each has ``register(subparsers, CLIError)``
#: adding its parser with ``set_defaults(func=...)``; ``func(args)`` returns
#: an exit code and raises ``CLIError(message, code)`` or the library's own
#: errors, which :func:`main` turns into one line on stderr.
_PLUGIN_COMMANDS: tuple[str, ...] = ("_cli_evaluate", "_cli_rig", "_cli_fetch")


class CLIError(Exception):
    """An error with its exit code, reported as one line."""

    def __init__(self, message: str, code: int = EXIT_USAGE):
        super().__init__(message)
        self.code = code


class _Terminated(KeyboardInterrupt):
    """Raised by the SIGTERM handler so that clean-up (temporary files) runs."""


class _PipeGuard:
    """Standard output that outlives a closed pipe: writes after the reader has gone are dropped.

    ``nfdepth evaluate tsukuba --json r.json | head -1`` closes the pipe after
    one line; the run still finishes and writes ``r.json`` (a failed write
    to stdout used to abort the run and roll back its outputs).
    """

    def __init__(self, stream):
        self._stream = stream
        self.closed = False  # the reader has gone

    def write(self, text):
        if not self.closed:
            try:
                return self._stream.write(text)
            except BrokenPipeError:
                self._reader_gone()
        return len(text)

    def flush(self):
        if not self.closed:
            try:
                self._stream.flush()
            except BrokenPipeError:
                self._reader_gone()

    def _reader_gone(self):
        self.closed = True
        try:  # what the stream still buffers would fail again when Python flushes it at exit
            devnull = os.open(os.devnull, os.O_WRONLY)
            try:
                os.dup2(devnull, self._stream.fileno())
            finally:
                os.close(devnull)
        except (OSError, ValueError, AttributeError):  # not a file descriptor (a test's capture)
            pass

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _on_sigterm(signum, frame):  # pragma: no cover - exercised in a subprocess test
    raise _Terminated()


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    text = " ".join(str(message).split())
    print(f"nfdepth: warning: {text}", file=sys.stderr if file is None else file)


def _check_out_dir(path: str, what: str = "--out") -> Path:
    """An output folder: it may exist as a folder or not exist (it is made, its missing parents too); never a file, nor inside one."""
    from .io import parent_folder_problem

    out = Path(path)
    if os.path.lexists(out) and not out.is_dir():
        link = " (a link to a missing folder)" if not out.exists() else ""
        raise CLIError(f"{what} '{out}' exists and is not a directory{link}; expected a folder for the output files", EXIT_WRITE)
    first = out  # the first folder the run makes: its parent must be a folder (not a file, found only once the work is done)
    while not os.path.lexists(first.parent) and first.parent != first:
        first = first.parent
    problem = None if out.is_dir() else parent_folder_problem(first)
    if problem:
        raise CLIError(f"{what} '{out}': {problem}", EXIT_WRITE)
    return out


def _check_json_apart(js: str, folder: str, what: str = "--out") -> None:
    """Refuse a ``--json`` file that is the output folder ``what`` or would hold it: the run would fail only at its end."""
    file, out = Path(js).resolve(), Path(folder).resolve()
    if file == out:
        raise CLIError(f"--json and {what} name the same path '{js}'; expected a different path for each output (--json a file, {what} a folder)", EXIT_USAGE)
    if file in out.parents:
        raise CLIError(f"{what} '{folder}' lies inside --json '{js}' (a file); expected a different path for each output, the folder outside the JSON file", EXIT_USAGE)


#: A negative number as an option's value: argparse's own pattern knows only "-2" and
#: "-2.5", so "-1e-3" read as an unknown option ("expected 2 arguments").
_NEGATIVE_NUMBER = re.compile(r"^-((\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|inf|infinity|nan)$", re.IGNORECASE)  # -inf reaches the finite-number checks


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER  # (argparse's private hook; none of our options looks like a number)

    def error(self, message):  # one line, exit code 2, no usage dump
        prefix = "unrecognized arguments: "
        if message.startswith(prefix):
            extra = message[len(prefix) :].split()
            if len(extra) > 1 and all(Path(a).exists() for a in extra):  # an unquoted glob, expanded by the shell
                message = f"{prefix}{_glob_advice(extra)}"
        raise CLIError(f"{self.prog}: {message}", EXIT_USAGE)


def _glob_advice(files) -> str:
    """``files`` (the first three) and the advice for a glob the shell expanded into them."""
    listed = " ".join(files[:3]) + (f" ... ({len(files)} files)" if len(files) > 3 else "")
    return f"{listed}: quote a glob such as 'frames/*.png', or the shell expands it into files"


def _classify(exc: BaseException) -> int:
    name = type(exc).__name__
    if name == "ImageRangeError":  # the file was read; its values do not fit float32
        return EXIT_USAGE
    if name in ("ImageReadError", "InputReadError", "DataFileError"):  # a file there, but broken
        return EXIT_READ
    if name in ("OutputExistsError", "OutputWriteError"):
        return EXIT_WRITE
    if name == "DataNotFoundError":
        return EXIT_DATA
    if isinstance(exc, (ValueError, TypeError)):
        return EXIT_USAGE
    if isinstance(exc, FileNotFoundError):
        return EXIT_READ
    if isinstance(exc, PermissionError):
        return EXIT_WRITE
    if isinstance(exc, OSError):
        return EXIT_WRITE
    return EXIT_INTERNAL


# ----------------------------------------------------------------- reproduce


def _fmt(value: float) -> str:
    return "   nan" if not np.isfinite(value) else f"{value:6.4f}"


def _reproduce_table(results, literal=None) -> str:
    from .experiments import PAPER_REPORTED

    head = f"{'experiment':<10} {'points':>6} {'paper max':>9} | {'flow max':>8} {'p95':>6} {'median':>6} | {'depth max':>9} {'median':>6}"
    if literal is not None:
        head += f" | {'literal-stencil max':>19} {'median':>6}"
    lines = [head, "-" * len(head)]
    for name, res in results.items():
        s = res.summary()
        f, d = s["flow_rel_error"], s["depth_rel_error"]
        paper = PAPER_REPORTED[name]
        paper_txt = f"<{paper:.2f}" if name == "static" else f"{paper:.2f}"
        line = (
            f"{name:<10} {s['points']:>6} {paper_txt:>9} | {_fmt(f['max']):>8} {_fmt(f['p95'])} {_fmt(f['median'])} |"
            f" {_fmt(d['max']):>9} {_fmt(d['median'])}"
        )
        if literal is not None:
            lf = literal[name].summary()["flow_rel_error"]
            line += f" | {_fmt(lf['max']):>19} {_fmt(lf['median'])}"
        lines.append(line)
    return "\n".join(lines)


def _write_paper_figures(out_dir: Path, res) -> list[Path]:
    from . import plot

    scene, r = res.scene, res.result
    shape = r.selection.mask.shape
    frames = scene.frames
    name = res.name
    written = []
    if name == "static":
        ref = scene.reference_index
        written.append(plot.save_figure(plot.image_panel(frames[ref], title=f"{name}: I{ref + 1}"), out_dir / f"{name}_a_image.png"))
        written.append(plot.save_figure(plot.difference_panel(frames[ref - 1], frames[ref + 1], title=f"{name}: dp (I{ref + 2} - I{ref})"), out_dir / f"{name}_a_dp.png"))
        flows = {"Vn": r.delta_vn}
    else:
        written.append(plot.save_figure(plot.image_panel(frames[2], title=f"{name}: I3"), out_dir / f"{name}_a_I3.png"))
        written.append(plot.save_figure(plot.difference_panel(frames[1], frames[3], title=f"{name}: dps (I4 - I2)"), out_dir / f"{name}_a_dps.png"))
        written.append(plot.save_figure(plot.difference_panel(frames[0], frames[4], title=f"{name}: dpm (I5 - I1)"), out_dir / f"{name}_a_dpm.png"))
        m = r.selection.mask
        flows = {"Vnr": r.delta_vn, "Vns": r.flows["stationary"][m], "Vnm": r.flows["moving"][m]}
    scale = plot.needle_scale_px(*flows.values())  # one scale: the panels compare
    for key, flow in flows.items():
        fig = plot.needle_panel(r.rows, r.cols, r.alpha, flow, shape=shape, title=f"{name}: {key}", scale_px=scale)
        written.append(plot.save_figure(fig, out_dir / f"{name}_b_{key}.png"))
    fig = plot.edge_points_panel(r.rows, r.cols, shape=shape, valid=r.valid, title=f"{name}: edge points")
    written.append(plot.save_figure(fig, out_dir / f"{name}_c_edges.png"))
    true_pts = r.camera.back_project(r.rows, r.cols, res.true_depth)
    fig = plot.yz_projection_panel(r.points, true_points=true_pts[r.valid], title=f"{name}: depth on the Y-Z plane")
    written.append(plot.save_figure(fig, out_dir / f"{name}_d_yz.png"))
    return written


def _jsonable(obj):
    """``obj`` as JSON takes it: NaN and inf (statistics of no point) as null, every key kept.

    The numbers go through :func:`nfdepth.evaluate.to_jsonable`; its dicts drop
    the bulky keys of an evaluation ("edge_points" among them), here a count.
    """
    from .evaluate import to_jsonable

    if isinstance(obj, dict):
        return {key: _jsonable(value) for key, value in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(value) for value in obj]
    return to_jsonable(obj)


def _cmd_reproduce(args) -> int:
    from .experiments import DEFAULT_SIGMA_PX, EXPERIMENTS, run_paper_experiment

    if args.seed < 0:
        raise CLIError(f"--seed must be an integer >= 0 (the noise generator's seed), got {args.seed}")
    if args.noise < 0 or not np.isfinite(args.noise):
        raise CLIError(f"--noise must be a finite number >= 0, got {args.noise}")
    if args.json and args.out:
        _check_json_apart(args.json, args.out)
    if args.json:
        _check_output(args.json, force=True, exts=(".json",), what="--json")
    if args.out:
        _check_out_dir(args.out)
    names = EXPERIMENTS if not args.only else tuple(args.only)
    if args.sigma_px is not None and (not np.isfinite(args.sigma_px) or args.sigma_px <= 0):
        raise CLIError(f"--sigma-px must be a positive number, got {args.sigma_px}")
    if args.max_rel_std is not None and (not np.isfinite(args.max_rel_std) or args.max_rel_std <= 0):
        raise CLIError(f"--max-rel-std must be a positive number, got {args.max_rel_std}")
    common = {"noise_std": args.noise, "seed": args.seed, "sigma_px": args.sigma_px, "max_rel_std": args.max_rel_std}
    results = {n: run_paper_experiment(n, stencil=args.stencil, **common) for n in names}
    literal = None
    if args.stencil != "paper" and not args.no_compare:
        literal = {n: run_paper_experiment(n, stencil="paper", **common) for n in names}
    print(f"Paper experiments (stencil={args.stencil}, noise std={args.noise:g}, seed={args.seed}); relative errors, corners excluded")
    print(_reproduce_table(results, literal))
    honest = ", ".join(f"{n} {res.median_error_over_std:.2f}" for n, res in results.items())
    print(f"error bar, median |depth error| / std (0.67 when calibrated): {honest}")
    if args.json:
        from . import __version__

        payload = {}
        for n, res in results.items():
            entry = res.summary()
            entry["stencil"] = args.stencil
            # what made these figures (two runs with other seeds must be told apart)
            sigma = DEFAULT_SIGMA_PX[n] if args.sigma_px is None else args.sigma_px
            entry["settings"] = {"nfdepth_version": __version__, **common, "sigma_px": sigma, "stencil": args.stencil}
            if literal is not None:
                entry["literal_stencil"] = literal[n].summary()
            payload[n] = _jsonable(entry)
        from .io import atomic_write

        text = json.dumps(payload, indent=2, allow_nan=False)
        atomic_write(Path(args.json), lambda fh: fh.write(text.encode()), force=True)
        print(f"wrote {args.json}")
    if args.out:
        out = Path(args.out)
        count = sum(len(_write_paper_figures(out, res)) for res in results.values())
        print(f"wrote {count} figures to {out}/")
    return EXIT_OK


def _cmd_demo(args) -> int:
    import cv2

    from . import plot
    from .experiments import run_paper_experiment
    from .io import atomic_write, depth_to_points, make_output_folder, write_array, write_ply
    from .stereo import static_stereo
    from .rectify import cameras_to_toml
    from .synthetic import calibrated_plane_row, paper_pyramid, static_sequence

    out = _check_out_dir(args.out)
    make_output_folder(out, parents=True)  # removed again if the run fails or is interrupted (its parents it made too)
    print("nfdepth demo: the paper's pyramid, dynamic stereo (experiment 1) and static stereo")
    results = {}
    for name in ("exp1", "static"):
        res = run_paper_experiment(name)
        results[name] = res
        s = res.summary()
        z = res.result.depth[res.result.valid]
        print(
            f"  {name:<6}: {s['points']} edge points with depth in {s['runtime_s'] * 1000:.0f} ms; "
            f"depth {np.nanmin(z):.0f}..{np.nanmax(z):.0f} (true 200..400); "
            f"median depth error {100 * s['depth_rel_error']['median']:.2f} %, max {100 * s['depth_rel_error']['max']:.2f} %"
        )
        _write_paper_figures(out, res)
    # The bundled example: the static row as 16-bit PNG files, then the same
    # job as `nfdepth stereo --edges-only` on them: a depth map and a point cloud.
    scene = results["static"].scene
    example = out / "example"
    make_output_folder(example / "rail", parents=True)

    def write_png16(path, frame):
        data = np.round(np.clip(frame, 0, 255) * 256.0).astype(np.uint16)
        ok, buf = cv2.imencode(".png", data)
        atomic_write(path, lambda fh: fh.write(buf.tobytes()), force=True)
        return path

    names = [write_png16(example / f"pyramid_view{k}.png", f) for k, f in enumerate(scene.frames)]
    # A column through the same reference camera (moving toward +Y): with the
    # row, x and y baselines together (`nfdepth stereo ... --column`).
    column = static_sequence(paper_pyramid(), scene.camera, n_views=3, camera_step=(0.0, 2.0, 0.0))
    for k in (0, 2):
        write_png16(example / f"pyramid_column{k}.png", column.frames[k])
    for k, frame in enumerate(results["exp1"].scene.frames, 1):
        write_png16(example / f"dynamic_I{k}.png", frame)
    # A camera on a rail passing the still pyramid, 1 unit per frame along +X
    # (the [video] section of examples/paper_pyramid_rig.toml).
    rail = static_sequence(paper_pyramid(), scene.camera, n_views=8, camera_step=(1.0, 0.0, 0.0))
    for k, frame in enumerate(rail.frames):
        write_png16(example / "rail" / f"frame_{k:03d}.png", frame)
    # A calibrated row of three cameras that is not rectified (`nfdepth stereo ... --cameras`).
    calibrated = calibrated_plane_row()
    for k, frame in enumerate(calibrated.views):
        write_png16(example / f"calibrated_view{k}.png", frame)
    atomic_write(example / "calibrated_cameras.toml", lambda fh: fh.write(cameras_to_toml(calibrated.cameras).encode()), force=True)
    views = [np.asarray(f, dtype=np.float32) for f in scene.frames]
    stereo = static_stereo(views, reference=scene.reference_index, edges_only=True)
    depth = stereo.depth(focal_px=scene.camera.focal_px, baseline=2.0)
    write_array(out / "depth.pfm", depth.astype(np.float32), force=True)
    plot.save_figure(plot.colormap_panel(depth, title="depth at edge points (static stereo)", unit="scene units", vmin=200, vmax=400), out / "depth.png")
    pts, cols = depth_to_points(depth, focal_px=scene.camera.focal_px, image=np.clip(scene.frames[scene.reference_index], 0, 255).astype(np.uint8))
    write_ply(out / "points.ply", pts, colors=cols, force=True)
    finite = depth[np.isfinite(depth)]
    print(
        f"  example: {finite.size} edge points, depth {finite.min():.0f}..{finite.max():.0f} -> {out / 'depth.pfm'}, "
        f"{out / 'depth.png'}, {out / 'points.ply'} ({len(pts)} points)"
    )
    print(f"  the same from the files: nfdepth stereo {' '.join(str(n) for n in names)} --edges-only --focal-px 100 --baseline 2 --out depth.pfm --ply points.ply")
    calibrated_names = " ".join(str(example / f"calibrated_view{k}.png") for k in range(len(calibrated.views)))
    print(f"  a calibrated row that is not rectified: nfdepth stereo {calibrated_names} --cameras {example / 'calibrated_cameras.toml'} --out calibrated_depth.pfm")
    print(f"figures written to {out}/")
    return EXIT_OK


# -------------------------------------------------------------------- stereo

_ARRAY_EXTS = (".pfm", ".tif", ".tiff", ".npy")


def _path_keys(path) -> set:
    """What identifies ``path`` on disk: its resolved name and, if it exists, its (device, inode)."""
    keys: set = {os.path.realpath(path)}
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return keys
    if st.st_ino:  # 0 where the file system has no inode numbers
        keys.add((st.st_dev, st.st_ino))
    return keys


def _check_finite(paths, images, label=lambda k, path: f"view '{Path(path).name}'") -> None:
    """Refuse an image holding NaN or inf (a float TIFF, PFM or NPY), naming its file: the library names only its index."""
    for k, (path, img) in enumerate(zip(paths, images)):
        bad = int(np.count_nonzero(~np.isfinite(img)))
        if bad:
            raise CLIError(f"{label(k, path)} contains {bad} non-finite (NaN or inf) pixel(s); expected finite intensities")


def _check_not_input(out, inputs, what: str = "--out") -> None:
    """Refuse, even with ``--force``, an output path that is one of the command's inputs (the same file or folder)."""
    if not inputs:
        return
    mine = _path_keys(out)
    for inp in inputs:
        if inp is not None and mine & _path_keys(inp):
            raise CLIError(
                f"{what} '{out}' is the input '{inp}'; expected an output path that is not one of the inputs (--force never overwrites an input)",
                EXIT_USAGE,
            )


def _check_output(path: str, *, force: bool, exts=_ARRAY_EXTS, what: str = "--out", inputs=()) -> Path:
    """Validate an output path before any work is done (no partial results); never one of ``inputs``."""
    from .io import parent_folder_problem

    out = Path(path)
    if exts and out.suffix.lower() not in exts:
        folder = "; it is a directory, expected a file path" if out.is_dir() else ""
        raise CLIError(f"{what} '{out}' must end in one of {', '.join(exts)}{folder}", EXIT_USAGE)
    if out.is_dir():
        raise CLIError(f"{what} '{out}' is a directory; expected a file path", EXIT_WRITE)
    _check_not_input(out, inputs, what)
    if os.path.lexists(out) and not force:
        link = " (a link to a missing file)" if not out.exists() else ""
        raise CLIError(f"{what} '{out}' exists{link}; use --force to overwrite it", EXIT_WRITE)
    problem = parent_folder_problem(out)
    if problem:
        raise CLIError(f"{what} '{out}': {problem}", EXIT_WRITE)
    return out


def _positive(name: str, value):
    if value is None:
        return None
    if not np.isfinite(value) or value <= 0:
        raise CLIError(f"{name} must be a positive number, got {value:g}")
    return float(value)


def _as_option(exc: ValueError, parameter: str, option: str, *, value: str | None = None, within=()) -> ValueError:
    """A library error that opens with ``parameter = ...``, told as the command line's ``option`` (else ``exc`` itself).

    A ``row: `` / ``column: `` before it (:func:`nfdepth.xy_stereo.static_stereo_xy`) stays. ``value``: the
    value as the command line gave it (``"0 0.5"`` for the library's ``(0, 0.5)``), in place of the
    library's ("" drops it); ``within``: ``(parameter, option)`` pairs that the rest of the message names
    as ``parameter = ...``, told as their options too.
    """
    text = str(exc)
    head = re.match(rf"^((?:row|column): )?{re.escape(parameter)} = ", text)
    if head is None:
        return exc
    rest = text[head.end() :]
    if value is not None:  # the library's value: a number, or a tuple or list of them
        rest = re.sub(r"^(\([^)]*\)|\[[^\]]*\]|\S+) ?", "", rest, count=1)
    for name, told in within:
        rest = re.sub(rf"\b{re.escape(name)} = ", f"{told} ", rest)
    said = " ".join(part for part in (option, value, rest) if part)
    return CLIError(f"{head.group(1) or ''}{said}", EXIT_USAGE)


def _depth_range(value):
    """``--depth-range NEAR FAR``, checked: ``0 < NEAR < FAR``, ``FAR`` may be inf; None if not given."""
    if value is None:
        return None
    near, far = value
    if not (np.isfinite(near) and 0 < near < far):
        raise CLIError(f"--depth-range must be two depths NEAR FAR with 0 < NEAR < FAR (FAR may be inf: no far limit), got {near:g} {far:g}")
    return float(near), float(far)


def _offset_text(o: float) -> str:
    """An exposure's offset in grey levels: whole ones from 100 up (16-bit images), ``+0`` below 0.005 (not ``-3.02e-12``)."""
    return f"{o:+.0f}" if abs(o) >= 100.0 else "+0" if abs(o) < 0.005 else f"{o:+.3g}"


def _exposure_text(fit) -> str:
    """``"gain 1.2 offset +10"`` for an undone ``(gain, offset)`` (:func:`_offset_text`)."""
    return f"gain {fit[0]:.3g} offset {_offset_text(fit[1])}"


def _exposure_note(results) -> str:
    """``", exposure matched to the reference (...)"`` for the views whose exposure static stereo undid (``StereoResult.exposure``), or ``""``.

    ``results``: ``(label, result, names)``, ``names`` the files of the result's views in its order.
    """
    parts = []
    for label, result, names in results:
        for fit, name in zip(result.exposure or (), names):
            if fit is not None:
                parts.append(f"{label}{Path(name).name} {_exposure_text(fit)}")
    return f", exposure matched to the reference ({'; '.join(parts)})" if parts else ""


def _stereo_outputs(args, inputs) -> tuple[list, dict]:
    """``nfdepth stereo``'s output paths, checked before any work: ``[--out, --uncertainty, --fill-mask, --preview, --ply]`` (those given) and the figures."""
    from ._cli_rig import _distinct, figure_outputs

    named = {"out": _check_output(args.out, force=args.force, inputs=inputs)}
    if args.fill_mask and not args.fill:
        raise CLIError("--fill-mask needs --fill")
    if args.fill and args.edges_only:
        raise CLIError("--fill fills the holes of the dense map: it does not go with --edges-only (a map filled from the edge points alone would be mostly guesses)")
    for key, exts in (("uncertainty", _ARRAY_EXTS), ("fill_mask", _ARRAY_EXTS), ("preview", (".png",)), ("ply", (".ply",))):
        if getattr(args, key):
            named[key] = _check_output(getattr(args, key), force=args.force, exts=exts, what="--" + key.replace("_", "-"), inputs=inputs)
    figures = figure_outputs(args, with_std=bool(args.uncertainty), inputs=inputs)
    _distinct({**named, **figures}, CLIError)
    return list(named.values()), figures


def _write_stereo_maps(args, outputs, values, std, filled) -> int:
    """Write the maps of :func:`_stereo_outputs`' paths but the point cloud: ``--out``, ``--uncertainty``, ``--fill-mask``, ``--preview``.

    ``filled``: the mask of filled pixels (with ``--fill``). Returns the index of the next path (``--ply``'s, if given).
    """
    from .io import write_array, write_colormap_png

    write_array(outputs[0], values, force=args.force)
    k = 1
    if args.uncertainty:
        write_array(outputs[k], std, force=args.force)
        k += 1
    if args.fill_mask:
        write_array(outputs[k], np.where(np.isfinite(values), filled.astype(np.float32), np.nan).astype(np.float32), force=args.force)
        k += 1
    if args.preview:
        write_colormap_png(outputs[k], values, force=args.force)
        k += 1
    return k


def _cmd_stereo(args) -> int:
    from .io import depth_to_points, read_image, to_float32_map, to_rgb8, write_ply
    from .stereo import check_depth_scale, check_disparity_offset, disparity_range_for_depths, static_stereo

    if len(args.views) < 2:
        raise CLIError(f"stereo needs at least 2 views (3 or more recommended), got {len(args.views)}")
    if args.column_cameras and not args.cameras:
        raise CLIError("--column-cameras needs --cameras (the row's calibrated cameras); a rectified column takes --column alone")
    if args.cameras:
        from ._cli_calibrated import run_calibrated_stereo

        return run_calibrated_stereo(args, CLIError)  # (--axis, x or y, is refused there: the cameras give the row)
    principal_point_given = [f"--{k.replace('_', '-')}" for k in ("cx_px", "cy_px") if getattr(args, k) is not None]
    rig = None
    if args.rig:
        from .rig import load_rig, stereo_options_from_rig

        rig = load_rig(args.rig)
        opts = stereo_options_from_rig(rig, n_views=len(args.views), n_column_views=len(args.column) if args.column else None)
        # the rig's value where the file gives none: what it means, and where to set it instead
        defaults = {"cx_px": "the image centre", "cy_px": "the image centre", "disparity_offset_px": "0"}
        sections = {"cx_px": "[camera]", "cy_px": "[camera]", "disparity_offset_px": "[stereo]"}
        for key in ("focal_px", "baseline", "axis", "positions", "column_positions", "disparity_offset_px", "cx_px", "cy_px"):
            if key == "column_positions" and not args.column:
                if opts.get(key) is not None:  # the rig's column is not in use: said, as a run that fuses nothing
                    warnings.warn(
                        "the rig file's column_positions are for a column of views, and no --column is given: the row is measured alone",
                        UserWarning,
                        stacklevel=2,
                    )
                continue
            given = getattr(args, key)  # (None: not given, the rig decides; --axis has no default until after the rig)
            if given is not None and opts.get(key) is not None and given != opts[key]:
                if key in defaults:
                    where = f"{defaults[key]} unless the file gives it; set it in the file's {sections[key]}"
                    raise CLIError(f"--{key.replace('_', '-')} {given:g} contradicts the rig file's {key} = {opts[key]:g} ({where})")
                raise CLIError(f"--{key.replace('_', '-')} {given} contradicts the rig file's {key} = {opts[key]}")
            if given is None and opts.get(key) is not None:
                setattr(args, key, opts[key])
        rig_range = opts.get("disparity_range_px")
        if rig_range is not None:
            if args.disparity_range is not None and list(args.disparity_range) != rig_range:
                given = " ".join(f"{v:g}" for v in args.disparity_range)
                in_rig = ", ".join(f"{v:g}" for v in rig_range)
                raise CLIError(f"--disparity-range {given} contradicts the rig file's disparity_range_px = [{in_rig}]")
            args.disparity_range = rig_range
    if args.axis is None:  # neither --axis nor the rig file's: a row along x
        args.axis = "x"
    focal = _positive("--focal-px", args.focal_px)
    baseline = _positive("--baseline", args.baseline)
    if (focal is None) != (baseline is None):
        raise CLIError("--focal-px and --baseline go together: give both for depth output, or neither for disparity")
    if focal is not None:
        try:
            check_depth_scale(focal, baseline, names=("--focal-px", "--baseline"))
        except ValueError as exc:
            raise CLIError(str(exc)) from None
    if args.ply and focal is None:
        raise CLIError("--ply needs --focal-px and --baseline (a point cloud needs metric depth)")
    offset = 0.0
    if args.disparity_offset_px is not None:
        try:
            offset = check_disparity_offset("--disparity-offset-px", args.disparity_offset_px)
        except ValueError as exc:
            raise CLIError(str(exc)) from None
    if offset != 0 and focal is None:
        raise CLIError("--disparity-offset-px changes depth only: give --focal-px and --baseline too (the disparity output is as measured)")
    depth_range = _depth_range(args.depth_range)
    if depth_range is not None:
        if args.disparity_range is not None:
            source = "the rig file's disparity_range_px" if rig is not None and opts.get("disparity_range_px") is not None else "--disparity-range"
            raise CLIError(f"--depth-range and {source} both set the search range: give one")
        if focal is None:
            raise CLIError("--depth-range needs --focal-px and --baseline (to turn the depths into disparities); or give --disparity-range")
        try:
            lo, hi = disparity_range_for_depths(depth_range, focal_px=focal, baseline=baseline, disparity_offset_px=offset)
        except ValueError as exc:
            raise CLIError(str(exc).replace("depth_range", "--depth-range", 1)) from None
        args.disparity_range = [lo, hi]
    if offset != 0 and args.column:
        raise CLIError("--disparity-offset-px applies to one row: with --column the row and the column would each need their own offset")
    if principal_point_given and not args.ply:
        verb = "place" if len(principal_point_given) > 1 else "places"
        raise CLIError(f"{' and '.join(principal_point_given)} {verb} the points of --ply: give --ply too (depth itself does not use them)")
    for key in ("cx_px", "cy_px"):
        value = getattr(args, key)
        if value is not None and not np.isfinite(value):
            raise CLIError(f"--{key.replace('_', '-')} must be a finite number of pixels, got {value:g}")
    if args.threads is not None and args.threads < 1:
        raise CLIError(f"--threads must be an integer >= 1, got {args.threads}")
    cost_step = _positive("--cost-step-px", args.cost_step_px)
    reference = len(args.views) // 2 if args.reference is None else args.reference
    if not 0 <= reference < len(args.views):
        raise CLIError(f"--reference must index one of the {len(args.views)} views (0..{len(args.views) - 1}), got {reference}")
    column = args.column or []
    if not column and (args.column_reference is not None or args.column_positions is not None):
        raise CLIError("--column-reference and --column-positions need --column (the views of the vertical line)")
    column_reference = None
    if column:
        if args.axis != "x":
            raise CLIError("--column needs the main views to be the horizontal row (--axis x); the column is the vertical line")
        if len(column) < 2:
            raise CLIError(f"--column needs at least 2 views (3 or more recommended), got {len(column)}")
        column_reference = len(column) // 2 if args.column_reference is None else args.column_reference
        if not 0 <= column_reference < len(column):
            raise CLIError(f"--column-reference must index one of the {len(column)} column views (0..{len(column) - 1}), got {column_reference}")
    if args.disparity_range is not None:
        lo, hi = args.disparity_range
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise CLIError(f"--disparity-range must be two finite numbers MIN < MAX, got {lo:g} {hi:g}")
    outputs, figures = _stereo_outputs(args, [*args.views, *column, args.rig])
    from ._cli_rig import write_figures

    views = [read_image(v) for v in args.views]
    column_views = [read_image(v) for v in column]
    _check_finite([*args.views, *column], [*views, *column_views])
    shapes = {v.shape for v in views + column_views}
    if len(shapes) > 1:
        listed = ", ".join(f"{Path(p).name} {v.shape[1]}x{v.shape[0]}" for p, v in zip(args.views + column, views + column_views))
        raise CLIError(f"all views must have the same size, got {listed}")
    if column and not np.array_equal(views[reference], column_views[column_reference]):
        raise CLIError(
            f"the row's reference view ({Path(args.views[reference]).name}) and the column's ({Path(column[column_reference]).name}) "
            "must be the same image: both lines pass through the reference camera"
        )
    if rig is not None:
        rig.check_image_shape(views[0].shape)
        if any(rig.distortion):  # the row's views as the rig's pinhole camera sees them
            views = [rig.undistort(v) for v in views]
            column_views = [rig.undistort(v) for v in column_views]
    if args.ply:
        from .camera import PinholeCamera

        try:  # the camera's own check of the principal point against these images
            PinholeCamera(focal, views[0].shape[1], views[0].shape[0], args.cx_px, args.cy_px)
        except ValueError as exc:
            raise CLIError(f"--{exc}".replace("--cx_px", "--cx-px").replace("--cy_px", "--cy-px")) from None
    options = {}
    if args.sigma_px is not None:
        options["sigma_px"] = args.sigma_px
    if args.levels is not None:
        options["levels"] = args.levels
    if args.threads is not None:
        options["threads"] = args.threads
    if args.disparity_range is not None:
        options["disparity_range_px"] = tuple(args.disparity_range)
    if cost_step is not None:
        options["cost_step_px"] = cost_step
    if args.no_match_exposure:
        options["match_exposure"] = False
    try:
        if column:
            from .xy_stereo import static_stereo_xy

            result = static_stereo_xy(
                views,
                column_views,
                row_reference=reference,
                column_reference=column_reference,
                row_positions=args.positions,
                column_positions=args.column_positions,
                edges_only=args.edges_only,
                **options,
            )
        else:
            result = static_stereo(
                views, reference=reference, positions=args.positions, axis=args.axis, edges_only=args.edges_only, **options
            )
    except ValueError as exc:
        # the library knows no files: "views[1] has ..." (size, intensities) is told with the file's name
        named = re.match(r"^(column_views|views)\[(\d+)\] (.*)$", str(exc), re.DOTALL)
        files = (column if named and named.group(1) == "column_views" else args.views) if named else ()
        if named and int(named.group(2)) < len(files):
            raise CLIError(f"view '{files[int(named.group(2))]}' {named.group(3)}", EXIT_USAGE) from None
        # the search range and the step as the command line gave them, not the library's parameters
        step = [("cost_step_px", "--cost-step-px")]
        lo, hi = args.disparity_range if args.disparity_range is not None else (np.nan, np.nan)
        if depth_range is not None:
            told = _as_option(exc, "disparity_range_px", "that range", value="", within=step)
            if told is not exc:  # (any other error is not the depth range's)
                raise CLIError(f"--depth-range {depth_range[0]:g} {depth_range[1]:g} (disparities {lo:.4g}..{hi:.4g} px): {told}; widen or move the depth range") from None
        elif rig is not None and opts.get("disparity_range_px") is not None:
            exc = _as_option(exc, "disparity_range_px", "the rig file's disparity_range_px =", value=f"[{lo:g}, {hi:g}]", within=step)
        else:
            exc = _as_option(exc, "disparity_range_px", "--disparity-range", value=f"{lo:g} {hi:g}", within=step)
        raise _as_option(exc, "cost_step_px", "--cost-step-px") from None
    filled = None
    if args.fill:
        from dataclasses import replace

        disparity, filled = result.filled()
        result = replace(result, disparity=disparity)  # its uncertainty stays NaN where filled
    values = result.disparity
    std = result.uncertainty
    # disparities are per unit of position: px per view step only where the views are a step of 1 apart
    stepped = args.positions is None or bool(np.all(np.diff(np.asarray(args.positions, float)) == 1.0))
    unit = per_unit = "px" if stepped else "px per unit of position"
    if focal is not None:
        # the disparities are bounded to 0.1 px; the depths written, exactly (filled ones too)
        values = result.depth(focal_px=focal, baseline=baseline, disparity_offset_px=offset, depth_range=depth_range)
        unbounded = values if depth_range is None else result.depth(focal_px=focal, baseline=baseline, disparity_offset_px=offset)
        if offset:
            _warn_offset_losses(result, unbounded, offset)
        with np.errstate(divide="ignore", invalid="ignore"):
            std = values**2 / (focal * baseline) * result.uncertainty
        std = np.where(np.isfinite(values), std, np.nan)
        unit = "scene units"
    hint = "give --focal-px and --baseline (or the rig's) in units that keep depths in that range"
    values = to_float32_map(values, what=f"a {'depth' if focal is not None else 'disparity'}", hint=hint)
    std = to_float32_map(std, what="a standard deviation", hint=hint)
    k = _write_stereo_maps(args, outputs, values, std, filled)
    if args.ply:
        from ._cli_rig import undistorted_colours

        cam_ref = undistorted_colours(rig, read_image(args.views[reference], grey=False, dtype=None))  # on the depth's grid
        pts, cols = depth_to_points(values, focal_px=focal, cx_px=args.cx_px, cy_px=args.cy_px, image=to_rgb8(cam_ref))  # 16-bit, float: scaled to 0..255
        write_ply(outputs[k], pts, colors=cols, force=args.force)
    valid = np.isfinite(values)
    kind = "depth" if focal is not None else "disparity"
    write_figures(figures, values, std, title=f"view {reference} ({Path(args.views[reference]).name})", unit=unit, quantity=kind)
    finite = values[valid]
    rng_txt = f"{np.min(finite):.3g}..{np.max(finite):.3g} {unit}" if finite.size else "none"
    notes = ""
    if filled is not None:
        notes += f", {int(np.count_nonzero(filled & valid))} filled"
        if focal is not None:
            infinite = int(np.count_nonzero(filled & np.isfinite(result.disparity) & ~np.isfinite(unbounded)))
            outside = int(np.count_nonzero(filled & np.isfinite(unbounded) & ~valid))
            if infinite:  # a fill from a background at zero disparity (or measured just below it) has no finite depth
                notes += f" ({infinite} more filled at a disparity of 0 or less: no finite depth, NaN)"
            if outside:
                notes += f" ({outside} more filled beyond --depth-range: NaN)"
    if result.search_range_px is not None:
        notes += f", searched {result.search_range_px[0]:g}..{result.search_range_px[1]:g} {per_unit}"
    if column:
        both = int(np.count_nonzero(valid & (result.axis_count == 2)))
        notes += f", row and column fused ({both} pixels from both)"
        notes += _exposure_note([("row ", result.row, args.views), ("column ", result.column, column)])
    else:
        notes += _exposure_note([("", result, args.views)])
    print(
        f"{kind} for view {reference} ({Path(args.views[reference]).name}): {int(valid.sum())} of {valid.size} pixels"
        f" ({100.0 * valid.mean():.1f} %), range {rng_txt}, {result.runtime_s:.2f} s, {result.levels} level{'s' if result.levels != 1 else ''}{notes} -> {outputs[0]}"
    )
    return EXIT_OK


def _warn_offset_losses(result, depth, offset: float) -> None:
    """Warn when ``--disparity-offset-px`` leaves measured pixels at a disparity of 0 or less (no depth there)."""
    measured = np.isfinite(result.disparity) & (result.disparity > 0)
    lost = int(np.count_nonzero(measured & ~np.isfinite(depth)))
    if lost:
        warnings.warn(
            f"--disparity-offset-px {offset:g} leaves {lost} of {int(measured.sum())} measured pixels ({100.0 * lost / measured.sum():.1f} %) "
            "at a disparity of 0 or less: they have no depth (NaN); check the offset's sign and size",
            UserWarning,
            stacklevel=1,
        )


def _cmd_view(args) -> int:
    from .io import read_image, write_colormap_png
    from . import plot

    if args.out is None:  # the default output: the input's name with .png, the input itself for a .png (told as no --out given)
        default = Path(args.file).with_suffix(".png")
        if _path_keys(default) & _path_keys(args.file):
            raise CLIError(f"the default output '{default}' (the input's name with .png) is the input itself; give --out (--force never overwrites an input)")
    out = _check_output(args.out or str(Path(args.file).with_suffix(".png")), force=args.force, exts=(".png",), inputs=[args.file])
    for name, value in (("--vmin", args.vmin), ("--vmax", args.vmax)):
        if value is not None and not np.isfinite(value):
            raise CLIError(f"{name} must be a finite number, got {value:g}")
    if args.vmin is not None and args.vmax is not None and args.vmax < args.vmin:
        raise CLIError(f"--vmax must be >= --vmin, got --vmin {args.vmin:g} --vmax {args.vmax:g}")
    if args.unit is not None and not args.colorbar:  # the bare PNG has no label
        raise CLIError("--unit labels the colour bar: give --colorbar too")
    data = read_image(args.file, dtype=np.float64)
    if not np.isfinite(data).any():
        warnings.warn(f"'{args.file}' holds no finite value (all unknown): the PNG is all black", UserWarning, stacklevel=1)
    if args.colorbar:
        fig = plot.colormap_panel(data, title=Path(args.file).name, unit=args.unit or "value", vmin=args.vmin, vmax=args.vmax)
        plot.save_figure(fig, out, force=args.force)
    else:
        write_colormap_png(out, data, vmin=args.vmin, vmax=args.vmax, force=args.force)
    print(f"wrote {out}")
    return EXIT_OK


def _cmd_bench(args) -> int:
    from .bench import bench_main, check_bench_threads

    if args.json:
        _check_output(args.json, force=True, exts=(".json",), what="--json")
    try:
        check_bench_threads(args.threads, name="--threads")
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    return int(bench_main(json_path=args.json, quick=args.quick, threads=args.threads))


# ---------------------------------------------------------------- the parser


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``nfdepth`` (all sub-commands)."""
    from . import __version__

    parser = _Parser(prog="nfdepth", description="Depth from relative normal flow (dynamic and static stereo).")
    parser.add_argument("--version", action="version", version=f"nfdepth {__version__}")
    parser.add_argument("--debug", action="store_true", help="show the full traceback on errors (anywhere on the line)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    p = sub.add_parser("demo", help="render the paper's pyramid scenes, recover depth, write figures")
    p.add_argument("--out", default="nfdepth-demo", help="output folder for the figures (default ./nfdepth-demo)")
    p.set_defaults(func=_cmd_demo)

    p = sub.add_parser("reproduce", help="the paper's experiments 1-4 and static stereo, next to its numbers")
    p.add_argument("--json", metavar="FILE", help="write the numbers of the table (and the settings that made them) as JSON")
    p.add_argument("--out", metavar="DIR", help="write the paper's figures as PNG files here")
    p.add_argument("--stencil", choices=("matched", "simpson", "paper"), default="matched", help="gradient stencil (default matched)")
    p.add_argument("--noise", type=float, default=0.0, metavar="STD", help="Gaussian image noise, grey levels")
    p.add_argument("--seed", type=int, default=0, help="seed of the noise generator")
    p.add_argument("--sigma-px", type=float, help="Gaussian smoothing for every experiment (default 4 px)")
    p.add_argument("--max-rel-std", type=float, metavar="R", help="refuse points whose predicted relative depth std exceeds R")
    p.add_argument("--only", nargs="+", choices=("exp1", "exp2", "exp3", "exp4", "static"), help="run only these")
    p.add_argument("--no-compare", action="store_true", help="skip the literal-stencil comparison column")
    p.set_defaults(func=_cmd_reproduce)

    p = sub.add_parser("stereo", help="depth/disparity from a row of static views (coarse-to-fine, multi-view; --column adds a y baseline)")
    p.add_argument("views", nargs="+", metavar="VIEW", help="image files, ordered so the camera moves toward +X (or +Y) first to last")
    p.add_argument("--reference", type=int, default=None, metavar="K", help="0-based index of the view to compute (default: the middle one)")
    p.add_argument("--out", required=True, metavar="FILE", help="output .pfm, .tif or .npy (NaN where unknown)")
    p.add_argument("--positions", type=float, nargs="+", metavar="P", help="camera positions in units of the baseline (default 0 1 2 ...)")
    p.add_argument("--axis", choices=("x", "y"), default=None, help="direction of the row (default: the rig file's axis, else x)")
    p.add_argument(
        "--column",
        nargs="+",
        metavar="VIEW",
        help="x and y baselines together: views along a vertical line through the same reference camera, ordered so the camera moves toward +Y (down) first to last; fused with the row per pixel",
    )
    p.add_argument("--column-reference", type=int, default=None, metavar="K", help="0-based index of the reference view in --column (default: the middle one)")
    p.add_argument("--column-positions", type=float, nargs="+", metavar="P", help="camera positions along the column, in the unit of --positions (default 0 1 2 ...)")
    p.add_argument("--focal-px", type=float, metavar="F", help="focal length in pixels (with --baseline: output depth)")
    p.add_argument("--baseline", type=float, metavar="B", help="distance between neighbouring views (scene units)")
    offset_help = "with --focal-px and --baseline: depth = F B / (disparity + D), D in px per unit of position, for cameras whose principal points differ along the row (Middlebury's doffs; default 0)"
    p.add_argument("--disparity-offset-px", type=float, metavar="D", help=offset_help)
    p.add_argument("--cx-px", type=float, metavar="CX", help="principal point column for --ply (default: the image centre)")
    p.add_argument("--cy-px", type=float, metavar="CY", help="principal point row for --ply (default: the image centre)")
    p.add_argument("--edges-only", action="store_true", help="the paper's sparse output: edge points only")
    p.add_argument(
        "--fill",
        action="store_true",
        help="fill the unknown pixels from the background (the farther of the nearest values along the baseline); filled pixels have no uncertainty (NaN)",
    )
    p.add_argument("--fill-mask", metavar="FILE", help="with --fill: also write where it filled (1 filled, 0 measured, NaN none; .pfm, .tif or .npy)")
    p.add_argument("--uncertainty", metavar="FILE", help="also write the per-pixel standard deviation here")
    p.add_argument("--preview", metavar="PNG", help="also write a bare colour-mapped PNG: turbo from the map's minimum (blue) to its maximum (red), unknown pixels black, no legend (the range is in the run's line; --figure has a colour bar)")
    p.add_argument("--ply", metavar="FILE", help="also write a coloured point cloud (needs --focal-px, --baseline)")
    p.add_argument("--figure", metavar="PNG", help="also write a figure with a colour bar (px or scene units); with --uncertainty also PNG_std.png")
    p.add_argument("--sigma-px", type=float, help="Gaussian smoothing (px)")
    p.add_argument("--levels", type=int, help="pyramid levels (default: from the image size)")
    p.add_argument(
        "--disparity-range",
        nargs=2,
        type=float,
        metavar=("MIN", "MAX"),
        help="disparities to search, px between neighbouring views (as StereoSGBM's range; default: found coarse to fine); skips the pyramid",
    )
    p.add_argument(
        "--depth-range",
        nargs=2,
        type=float,
        metavar=("NEAR", "FAR"),
        help="depths to search, in the unit of --baseline or of the --cameras positions (FAR may be inf); "
        "the disparity range they give (needs --focal-px and --baseline, or --cameras); skips the pyramid",
    )
    p.add_argument(
        "--cost-step-px",
        type=float,
        metavar="PX",
        help="spacing of the cost volume's candidate disparities, px between neighbouring views (default 0.5); 1 is 15-25 %% faster "
        "at 640x480, same edge precision, coarser dense values (README: 'Faster, with coarser candidates')",
    )
    p.add_argument("--threads", type=int, metavar="N", help="threads of the cost volume (default: all cores, as OpenCV; the result does not depend on it)")
    p.add_argument(
        "--no-match-exposure",
        action="store_true",
        help="take the views' intensities as they are (default: a view whose exposure differs from the reference's is mapped onto it first)",
    )
    p.add_argument("--rig", metavar="TOML", help="rig file: focal length, principal point, lens distortion, baseline, axis, positions, disparity range and offset (docs/rig-format.md)")
    p.add_argument(
        "--cameras",
        metavar="TOML",
        help="calibrated cameras, one [[camera]] per view (intrinsics, lens distortion, pose): the views need not be rectified; "
        "output is depth in the reference camera's own pixels (docs/rig-format.md, 'Calibrated cameras')",
    )
    p.add_argument("--column-cameras", metavar="TOML", help="with --cameras and --column: the column's calibrated cameras, one [[camera]] per column view")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=_cmd_stereo)

    p = sub.add_parser("view", help="turn a .pfm/.tif/.npy map (or any image) into a colour PNG")
    p.add_argument("file", help="the map to show")
    p.add_argument("--out", metavar="PNG", help="output PNG (default: FILE with .png)")
    p.add_argument("--vmin", type=float, metavar="V", help="value drawn at the colour map's low end (default: the map's minimum; with --colorbar its 1st percentile)")
    p.add_argument("--vmax", type=float, metavar="V", help="value drawn at the high end (default: the maximum; with --colorbar the 99th percentile)")
    p.add_argument("--colorbar", action="store_true", help="draw a figure with a colour bar (an arrow at an end marks values beyond it)")
    p.add_argument("--unit", default=None, help="colour-bar label with --colorbar, e.g. 'disparity (px)' or 'depth (m)' (default: value)")
    p.add_argument("--force", action="store_true", help="overwrite an existing PNG")
    p.set_defaults(func=_cmd_view)

    p = sub.add_parser("bench", help="benchmarks against OpenCV (SGBM, BM, DIS) and the memory floor")
    p.add_argument("--json", metavar="FILE", help="write the records as JSON")
    p.add_argument("--quick", action="store_true", help="small sizes, fewer repeats (< 1 min)")
    p.add_argument("--threads", type=int, default=1, metavar="N", help="cv2.setNumThreads while timing; static stereo's cost volume follows it (default 1)")
    p.set_defaults(func=_cmd_bench)

    for module in _PLUGIN_COMMANDS:
        importlib.import_module(f"nfdepth.{module}").register(sub, CLIError)
    for command in sub.choices.values():  # the library's parameter names, told as each command's options
        names = {a.dest: max(a.option_strings, key=len) for a in command._actions if a.option_strings and a.dest != "help"}
        command.set_defaults(_option_names={**names, **_PARAMETER_OPTIONS})
    return parser


def main(argv=None) -> int:
    """Entry point of the ``nfdepth`` command; returns the exit code."""
    argv = sys.argv[1:] if argv is None else list(argv)
    debug = "--debug" in argv
    previous_sigterm = None
    from . import io

    io.COMPLETED_WRITES = []  # this run's outputs, removed if it is interrupted or fails
    if threading.current_thread() is threading.main_thread():
        previous_sigterm = signal.signal(signal.SIGTERM, _on_sigterm)
    stdout = sys.stdout
    if stdout is not None:
        sys.stdout = _PipeGuard(stdout)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            warnings.showwarning = _one_line_warning
            return _main(argv, debug)
    finally:
        sys.stdout = stdout
        io.COMPLETED_WRITES = None  # recorded during a run only
        if previous_sigterm is not None:
            signal.signal(signal.SIGTERM, previous_sigterm)


def _roll_back_outputs(event: str = "the interruption") -> str:
    """Remove the files this interrupted or failed run completed (the new ones); say what was done, for the one-line message."""
    from . import io

    removed, replaced, folders = [], [], []
    for path, existed in reversed(io.COMPLETED_WRITES or ()):  # a folder's files before the folder
        if existed:
            replaced.append(str(path))  # the old content is gone (--force): nothing to restore
            continue
        try:
            if path.is_dir():  # one this run made (io.make_output_folder): removed once empty
                path.rmdir()
                folders.append(str(path))
            else:
                path.unlink()
                removed.append(str(path))
        except OSError:
            replaced.append(str(path))
    replaced.reverse()
    note = f"; removed the {len(removed)} output(s) it had completed" if removed else ""
    if folders:
        note += f"{' and' if removed else '; removed'} the folder{'s' if len(folders) > 1 else ''} it made ({', '.join(reversed(folders))})"
    if replaced:
        note += f"; already written before {event}: {', '.join(replaced)}"
    return note


#: Library parameters whose option has another name (the rest are their option's dest).
_PARAMETER_OPTIONS = {"noise_std": "--noise"}


def _option_text(text: str, args) -> str:
    """A library message that opens with a parameter's name (``sigma_px must ...``, ``noise_std = 1e9 ...``), told with its option's."""
    names = getattr(args, "_option_names", None) or {}
    first = re.match(r"^([a-z][a-z0-9_]*)(?= = | must | should )", text)  # a check on the value, not a file it names
    if first and first.group(1) in names:
        option = names[first.group(1)]
        rest = text[first.end() :]
        return option + (rest[2:] if rest.startswith(" = ") else rest)
    return text


#: OSErrors as the system raises them (the library's own errors carry their message)
_RAW_OS_ERRORS = (OSError, PermissionError, FileNotFoundError, FileExistsError, NotADirectoryError, IsADirectoryError)


def _refuse_empty(argv) -> None:
    """An empty argument (``--out ""``, an unset shell variable) is refused: ``Path("")`` is the current folder."""
    for i, arg in enumerate(argv):
        if arg.strip() == "" or (arg.startswith("--") and arg.endswith("=")):
            if arg.startswith("--"):
                name = arg[:-1]
            elif i > 0 and argv[i - 1].startswith("-") and not _NEGATIVE_NUMBER.match(argv[i - 1]):
                name = argv[i - 1]
            else:
                name = f"argument {i + 1}"
            raise CLIError(f"{name} is empty ({arg!r}); expected a value (an unset shell variable?)")


def _main(argv, debug: bool) -> int:
    args = None
    try:
        parser = build_parser()
        _refuse_empty(argv)
        args = parser.parse_args([a for a in argv if a != "--debug"])  # taken anywhere on the line (main reads it)
        if not getattr(args, "func", None):
            parser.print_help()
            return EXIT_USAGE
        return int(args.func(args))
    except SystemExit as exc:  # --help / --version
        return int(exc.code or 0)
    except KeyboardInterrupt as exc:
        note = _roll_back_outputs()
        if isinstance(exc, _Terminated):
            print(f"nfdepth: terminated (SIGTERM); no partial output written{note}", file=sys.stderr)
            return EXIT_TERMINATED
        print(f"nfdepth: interrupted; no partial output written{note}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except CLIError as exc:
        if debug:
            traceback.print_exc(file=sys.stderr)
        text = " ".join(str(exc).split())
        for prefix in ("nfdepth: ", "nfdepth "):  # argparse's "PROG: message"
            if text.startswith(prefix):
                text = text[len(prefix) :]
                break
        print(f"nfdepth: error: {text}{_roll_back_outputs('the error')}", file=sys.stderr)
        return exc.code
    except Exception as exc:  # noqa: BLE001 - the CLI's single error boundary
        if debug:  # the traceback, then the same line and exit code as without --debug
            traceback.print_exc(file=sys.stderr)
        code = _classify(exc)
        text = " ".join(str(exc).split()) or type(exc).__name__
        if type(exc) in _RAW_OS_ERRORS and exc.filename and exc.strerror:  # not "[Errno 1] Operation not permitted: 'x'"
            text = f"cannot {'read' if code == EXIT_READ else 'write'} '{exc.filename}': {exc.strerror}"
        if getattr(exc, "path", None) is not None and type(exc).__name__ == "OutputExistsError":  # a file that appeared during the run
            text = f"'{exc.path}' exists; use --force to overwrite it"
        if type(exc).__name__ == "ImageRangeError":  # no dtype to choose here: nfdepth works in float32
            text = text.split(", or read it with dtype=")[0] + " (to 0-255 or 0-1, say): nfdepth works in float32"
        if code == EXIT_USAGE:
            text = _option_text(text, args)
        if code == EXIT_INTERNAL:
            text = f"internal error ({type(exc).__name__}): {text}; rerun with --debug and report it"
        # a failed run leaves none of its outputs, as an interrupted one
        print(f"nfdepth: error: {text}{_roll_back_outputs('the error')}", file=sys.stderr)
        return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
