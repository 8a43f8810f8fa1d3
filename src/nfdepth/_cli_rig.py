"""``nfdepth dynamic`` and ``nfdepth video``: commands driven by a rig file.

Each command is a thin layer over public functions:

* ``dynamic I1 .. I5`` -> :func:`nfdepth.rig.load_rig`, :func:`nfdepth.io.read_image`,
  :func:`nfdepth.rig.dynamic_stereo_from_rig`, :func:`nfdepth.rig.edge_depth_maps`.
* ``dynamic --moving-video M --reference-video R`` -> :func:`nfdepth.rig.load_rig`,
  :func:`nfdepth.video.read_video`, :func:`nfdepth.video.dynamic_stereo_from_videos`,
  :func:`nfdepth.video.write_crossings_npz` / :func:`nfdepth.video.write_video_frame`.
* ``video`` -> :func:`nfdepth.rig.load_rig`, :func:`nfdepth.video.read_video`,
  :func:`nfdepth.video.depth_from_video`, :func:`nfdepth.video.write_video_npz`
  / :func:`nfdepth.video.write_video_frame`.

``--figure PNG`` (both commands) -> :func:`nfdepth.plot.colormap_panel`,
:func:`nfdepth.plot.save_figure`: the depth map with a colour bar, and the
depth standard deviation next to it as ``PNG`` with ``_std`` before the
extension, whenever the command writes a standard deviation.
"""

from __future__ import annotations

import dataclasses
import itertools
import re
import sys
import time
from pathlib import Path

import numpy as np

__all__ = ["register"]

_CLIError = Exception  # replaced by register()


def figure_std_path(path) -> Path:
    """Where ``--figure PNG`` puts the standard-deviation figure: ``PNG`` with ``_std`` before ``.png``."""
    path = Path(path)
    return path.with_name(f"{path.stem}_std{path.suffix}")


def figure_outputs(args, *, with_std: bool, inputs=()) -> dict:
    """Validate ``--figure`` (and, ``with_std``, its ``_std`` sibling) before any work.

    Shared by the commands that draw figures (``args.figure``, ``args.force``);
    neither may be one of ``inputs``. Returns ``{"figure": Path[, "figure_std": Path]}`` or ``{}``.
    """
    from .cli import _check_output

    if not getattr(args, "figure", None):
        return {}
    outs = {"figure": _check_output(args.figure, force=args.force, exts=(".png",), what="--figure", inputs=inputs)}
    if with_std:
        outs["figure_std"] = _check_output(
            str(figure_std_path(args.figure)), force=args.force, exts=(".png",), what="--figure's std figure", inputs=inputs
        )
    return outs


def write_figures(outs: dict, values, std, *, title: str, unit: str, quantity: str = "depth") -> list:
    """Write the figures :func:`figure_outputs` validated: ``values`` (and ``std``) with a colour bar in ``unit``."""
    from . import plot

    written = []
    if "figure" in outs:
        fig = plot.colormap_panel(values, title=f"{quantity}: {title}", unit=f"{quantity} ({unit})")
        written.append(plot.save_figure(fig, outs["figure"]))
    if "figure_std" in outs and std is not None:
        fig = plot.colormap_panel(std, title=f"{quantity} std: {title}", unit=f"{quantity} standard deviation ({unit})")
        written.append(plot.save_figure(fig, outs["figure_std"]))
    return written


def _distinct(outs: dict, CLIError) -> dict:
    """``outs`` (``{"out": path, "figure_std": path, ...}``), refused where two options name one file."""
    from .cli import EXIT_USAGE

    seen = {}
    for key, path in outs.items():
        option = "--figure's std figure" if key == "figure_std" else "--" + key.replace("_", "-")
        resolved = str(Path(path).resolve())
        if resolved in seen:
            raise CLIError(f"{seen[resolved]} and {option} name the same file '{path}'; expected a different path for each output", EXIT_USAGE)
        seen[resolved] = option
    return outs


def _check_sigma(args, CLIError) -> dict:
    if args.sigma_px is not None and (not np.isfinite(args.sigma_px) or args.sigma_px < 0):
        raise CLIError(f"--sigma-px must be a finite number >= 0, got {args.sigma_px:g}")
    if args.unit is not None and not args.figure:  # it labels nothing else
        raise CLIError("--unit labels the colour bar of --figure: give --figure too")
    options = {} if args.sigma_px is None else {"sigma_px": args.sigma_px}
    if args.noise_std is not None:
        if not (np.isfinite(args.noise_std) and args.noise_std > 0):
            raise CLIError(f"--noise-std must be a positive number of grey levels, got {args.noise_std:g}")
        options["noise_std"] = args.noise_std
    return options


def _unit(args) -> str:
    """The colour bar's unit of depth (``--unit``; default: scene units)."""
    return args.unit if args.unit is not None else "scene units"


def _outputs(args, CLIError):
    from .cli import _check_output

    inputs = [*args.images, args.rig]
    outs = {"out": _check_output(args.out, force=args.force, inputs=inputs)}
    if args.uncertainty:
        outs["uncertainty"] = _check_output(args.uncertainty, force=args.force, what="--uncertainty", inputs=inputs)
    if args.preview:
        outs["preview"] = _check_output(args.preview, force=args.force, exts=(".png",), what="--preview", inputs=inputs)
    if args.ply:
        outs["ply"] = _check_output(args.ply, force=args.force, exts=(".ply",), what="--ply", inputs=inputs)
    if args.csv:
        outs["csv"] = _check_output(args.csv, force=args.force, exts=(".csv",), what="--csv", inputs=inputs)
    outs.update(figure_outputs(args, with_std=bool(args.uncertainty), inputs=inputs))
    return _distinct(outs, CLIError)


#: The option that names each output of :func:`_outputs` and :func:`figure_outputs`.
_OUTPUT_OPTIONS = {"out": "--out", "figure": "--figure", "figure_std": "--figure's std figure"}


def _check_not_inputs(outs: dict, sources, extra=()) -> None:
    """Refuse outputs that are one of the inputs: the ``sources`` (FrameSource) with their frames, and ``extra`` paths."""
    from .cli import _check_not_input

    inputs = [*extra]
    for source in sources:
        inputs.extend(source.paths or ())
    for key, out in outs.items():
        _check_not_input(out, inputs, _OUTPUT_OPTIONS.get(key, f"--{key}"))


#: What each reason code of an edge point without depth means, for the run's line.
_REASON_WORDS = {
    3: "undeterminable (edges along the relative flow)",
    4: "behind the camera or at infinity",
    5: "uncertain",
    6: "without data",
}


def _images_matched(exposure) -> str:
    """``"I2 gain 1.2 offset +10; I4 ..."`` for the images of dynamic stereo whose exposure was matched to I3 (``EdgeDepth.exposure``)."""
    from .cli import _exposure_text

    return "; ".join(f"I{k} {_exposure_text(fit)}" for k, fit in enumerate(exposure or (), 1) if fit is not None)


def _reasons_text(reasons) -> str:
    """``"; 20 undeterminable (...), 5 uncertain"`` for the edge points without depth, by reason code; ``""`` for none."""
    codes, counts = np.unique(np.asarray(reasons), return_counts=True)
    parts = [f"{n} {_REASON_WORDS.get(int(c), f'reason {int(c)}')}" for c, n in sorted(zip(codes, counts), key=lambda cn: -cn[1])]
    return f"; {', '.join(parts)}" if parts else ""


def undistorted_colours(rig, image: np.ndarray) -> np.ndarray:
    """``image`` (grey or colour, as read) on the undistorted pixel grid of ``rig``'s camera, each channel as a grey
    view is undistorted, in its own dtype (integers rounded and clipped); as it is where the rig has no distortion."""
    if rig is None or not any(rig.distortion):
        return image
    planes = image.reshape(*image.shape[:2], -1)
    planes = np.stack([rig.undistort(planes[..., c]) for c in range(planes.shape[-1])], axis=-1)
    if image.dtype.kind in "iu":
        info = np.iinfo(image.dtype)
        planes = np.clip(np.rint(planes), info.min, info.max).astype(image.dtype)
    return planes.reshape(image.shape)


def _cmd_dynamic(args) -> int:
    from .cli import _check_finite
    from .io import (
        atomic_write,
        read_image,
        to_float32_map,
        to_rgb8,
        write_array,
        write_colormap_png,
        write_ply,
    )
    from .rig import dynamic_stereo_from_rig, edge_depth_maps, load_rig

    CLIError = _CLIError
    videos = [v for v in (args.moving_video, args.reference_video) if v is not None]
    if videos:
        return _cmd_dynamic_videos(args)
    if args.crossings is not None or args.shared is not None:
        raise CLIError("--crossings and --shared go with --moving-video and --reference-video")
    if len(args.images) != 5:
        raise CLIError(
            f"dynamic needs exactly 5 images I1 I2 I3 I4 I5 (I1, I3, I5 moving camera; I2, I3, I4 reference)"
            f" or --moving-video and --reference-video, got {len(args.images)} images"
        )
    options = _check_sigma(args, CLIError)
    outs = _outputs(args, CLIError)
    rig = load_rig(args.rig)
    rig.relative_motion()  # a missing [motion] fails before any image is read
    frames = [read_image(p) for p in args.images]
    _check_finite(args.images, frames, label=lambda k, path: f"I{k + 1} '{Path(path).name}'")
    for k, (p, f) in enumerate(zip(args.images, frames), 1):
        rig.check_image_shape(f.shape, what=f"I{k} '{Path(p).name}'")
    result = dynamic_stereo_from_rig(frames, rig, match_exposure=not args.no_match_exposure, **options)
    hint = "give the rig's focal length and speeds in units that keep depths in that range"
    to_float32_map(result.depth[result.valid], what="a depth", hint=hint)  # the maps, the point cloud
    to_float32_map(result.depth_std[result.valid], what="a depth standard deviation", hint=hint)
    ok = result.valid
    if "ply" in outs:  # X = x Z and Y = y Z may overflow float32 where Z does not (points far off the axis)
        ply_hint = "a .ply file stores float32: give the rig's speeds (motion.velocity) in a unit that keeps the points in that range"
        points = to_float32_map(result.points[ok], what="a point coordinate", hint=ply_hint)
    depth, std = edge_depth_maps(result)
    write_array(outs["out"], depth, force=args.force)
    if "uncertainty" in outs:
        write_array(outs["uncertainty"], std, force=args.force)
    if "preview" in outs:
        write_colormap_png(outs["preview"], depth, force=args.force)
    write_figures(outs, depth, std, title=f"edge points of I3 ({Path(args.images[2]).name})", unit=_unit(args))
    if "ply" in outs:
        # colours on the undistorted grid of the points, as the depths; 16-bit or float input stretched to 8 bits
        img = to_rgb8(undistorted_colours(rig, read_image(args.images[2], grey=False, dtype=None)))
        ii = np.floor(result.rows[ok]).astype(int)
        jj = np.floor(result.cols[ok]).astype(int)
        write_ply(outs["ply"], points, colors=img[ii, jj], force=args.force)
    if "csv" in outs:
        lines = ["row,col,depth,depth_std"]
        lines += [f"{r:.2f},{c:.2f},{z:.6g},{s:.6g}" for r, c, z, s in zip(result.rows[ok], result.cols[ok], result.depth[ok], result.depth_std[ok])]
        text = "\n".join(lines) + "\n"
        atomic_write(outs["csv"], lambda fh: fh.write(text.encode()), force=args.force)
    z = result.depth[ok]
    rng_txt = f"{np.min(z):.4g}..{np.max(z):.4g}" if z.size else "none"
    without = _reasons_text(result.reason[~ok])
    matched = _images_matched(result.exposure)
    matched = f", exposure matched to I3 ({matched})" if matched else ""
    print(f"depth at {int(ok.sum())} of {len(result)} edge points of I3 ({Path(args.images[2]).name}{without}), range {rng_txt}{matched} -> {outs['out']}")
    return 0


def _cmd_dynamic_videos(args) -> int:
    """``nfdepth dynamic --moving-video M --reference-video R``: depth at each crossing instant."""
    from .cli import _exposure_text
    from .io import make_output_folder
    from .rig import check_crossings, load_rig
    from .video import (
        dynamic_stereo_from_videos,
        read_video,
        write_crossings_npz,
        write_video_frame,
    )

    CLIError = _CLIError
    if args.moving_video is None or args.reference_video is None:
        raise CLIError("two synchronised videos need both --moving-video and --reference-video")
    if args.images:
        if len(args.images) not in (1, 5) and all(Path(a).exists() for a in args.images):  # an unquoted glob after a video option
            from .cli import _glob_advice

            raise CLIError(f"files beside --moving-video and --reference-video: {_glob_advice(args.images)}")
        raise CLIError("give either five images or --moving-video and --reference-video, not both")
    for flag in ("uncertainty", "preview", "ply", "csv"):
        if getattr(args, flag):
            raise CLIError(
                f"--{flag} is for five images; with two videos --out holds depth and depth_std per crossing (.npz or a folder)"
            )
    options = _check_sigma(args, CLIError)
    kind, out = _video_output(args, CLIError)
    outs = _distinct({"out": out, **figure_outputs(args, with_std=True)}, CLIError)
    crossings = None
    if args.crossings is not None:
        try:
            crossings = check_crossings(args.crossings)
        except (TypeError, ValueError) as exc:
            raise CLIError(f"--crossings {' '.join(str(c) for c in args.crossings)}: expected {exc}") from None
    rig = load_rig(args.rig)
    rig.relative_motion()  # a missing [motion] fails before any frame is read
    if crossings is None and rig.motion.crossings is None:
        raise CLIError(f"rig '{args.rig}' has no motion.crossings: give --crossings K [K ...] (frames at which the cameras coincide)")
    moving, reference = read_video(args.moving_video), read_video(args.reference_video)
    _check_not_inputs(outs, (moving, reference), (args.moving_video, args.reference_video, args.rig))
    if moving.paths is not None and reference.paths is not None and len(moving) != len(reference):
        raise CLIError(
            f"the videos must be synchronised frame by frame: '{args.moving_video}' has {len(moving)} frames,"
            f" '{args.reference_video}' {len(reference)}"
        )
    if moving.paths is not None and reference.paths is not None:
        n = len(moving)
        late = [c for c in (crossings or rig.motion.crossings) if c + 2 >= n]
        if late:
            raise CLIError(f"crossing {late[0]} needs frames {late[0] - 2}..{late[0] + 2}, but the videos have {n} frames (0..{n - 1})")
    results = []
    last = None
    options["match_exposure"] = not args.no_match_exposure
    for res in dynamic_stereo_from_videos(moving, reference, rig=rig, crossings=crossings, shared=args.shared or "mean", **options):
        if kind == "npz":
            results.append(res)
        else:
            make_output_folder(out)
            write_video_frame(res, out, force=args.force)
        n = int(res.valid.sum())
        z = res.depth[res.valid]
        rng_txt = f"{np.min(z):.4g}..{np.max(z):.4g}" if z.size else "none"
        matched = "" if res.exposure is None else f", the reference camera's exposure matched ({_exposure_text(res.exposure)})"
        images = _images_matched(res.result.exposure)
        matched += f", images matched to I3 ({images})" if images else ""
        print(f"crossing {res.index}: depth at {n} of {len(res.result)} edge points, range {rng_txt}{matched}")
        last = res
    if kind == "npz":
        write_crossings_npz(results, out, camera=rig.camera, force=args.force)
    if last is not None:
        write_figures(outs, last.depth, last.depth_std, title=f"crossing {last.index}", unit=_unit(args))
    count = len(crossings or rig.motion.crossings)
    print(f"depth at {count} crossing{'s' if count != 1 else ''} -> {out}")
    return 0


class _Progress:
    """A one-line progress bar with frames per second on stderr."""

    def __init__(self, total: int | None, *, quiet: bool, stream=None):
        self.total = total if total else None
        self.quiet = quiet
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.start = time.perf_counter()
        self.done = 0
        self._last = -1.0
        self._every = max(1, (self.total or 100) // 10)

    def _line(self) -> str:
        elapsed = max(time.perf_counter() - self.start, 1e-9)
        fps = self.done / elapsed
        if self.total:
            frac = min(self.done / self.total, 1.0)
            bar = "#" * int(24 * frac) + "-" * (24 - int(24 * frac))
            eta = (self.total - self.done) / fps if fps > 0 else float("nan")
            return f"video [{bar}] {self.done}/{self.total} frames, {fps:.1f} frames/s, ETA {eta:.0f} s"
        return f"video: {self.done} frames, {fps:.1f} frames/s"

    def step(self, n: int = 1) -> None:
        self.done += n
        if self.quiet:
            return
        now = time.perf_counter()
        if self.tty:
            if now - self._last >= 0.1:
                self._last = now
                self.stream.write("\r" + self._line())
                self.stream.flush()
        elif self.done % self._every == 0 and now - max(self._last, self.start) >= 5.0:
            self._last = now  # not a terminal (a log): a line every 10 % at most every 5 s
            self.stream.write(self._line() + "\n")
            self.stream.flush()

    def abort(self) -> None:
        """End a terminal progress line so that an error message starts on its own line."""
        if self.tty and not self.quiet and self._last >= 0:
            self.stream.write("\n")
            self.stream.flush()

    def close(self) -> None:
        if self.quiet:
            return
        self.stream.write(("\r" if self.tty else "") + self._line() + "\n")
        self.stream.flush()


def _video_output(args, CLIError):
    from .cli import EXIT_USAGE, EXIT_WRITE, _check_output
    from .io import parent_folder_problem

    out = Path(args.out)
    if out.suffix.lower() == ".npz":
        return "npz", _check_output(args.out, force=args.force, exts=(".npz",))
    if out.suffix and not out.is_dir():
        raise CLIError(f"--out '{out}' must be a .npz file or a folder (no extension)", EXIT_USAGE)
    if out.exists() and not out.is_dir():
        raise CLIError(f"--out '{out}' exists and is not a folder", EXIT_WRITE)
    problem = parent_folder_problem(out)
    if problem:
        raise CLIError(f"--out '{out}': {problem}", EXIT_WRITE)
    if out.is_dir() and not args.force:
        for pattern in ("depth_*.tif", "dense_depth_*.tif"):
            if any(out.glob(pattern)):
                raise CLIError(f"--out '{out}' already holds {pattern} files; use --force to overwrite them", EXIT_WRITE)
    return "dir", out


def _cmd_video(args) -> int:
    from .io import make_output_folder
    from .rig import RigError, VideoSpec, load_poses, load_rig
    from .video import depth_from_video, read_video, write_video_frame, write_video_npz

    CLIError = _CLIError
    kind, out = _video_output(args, CLIError)
    options = _check_sigma(args, CLIError)
    if args.levels is not None:
        options["levels"] = args.levels
    # the dense maps' options: (flag, what it is for, what 1 means)
    for key, flag, what, one in (("threads", "--threads", "the dense maps' cost volume", ""), ("dense_frames_before", "--dense-frames-before", "the frames of each dense map", " (1: the triple)")):
        value = getattr(args, key)
        if value is None:
            continue
        if not args.dense:
            raise CLIError(f"{flag} goes with --dense ({what})")
        if value < 1:
            raise CLIError(f"{flag} must be an integer >= 1{one}, got {value}")
        options[key] = value
    if args.dense:
        options["dense"] = True
    if args.no_match_exposure:
        options["match_exposure"] = False
    figures = _distinct({"out": out, **figure_outputs(args, with_std=True)}, CLIError)
    rig = load_rig(args.rig)
    if args.poses:
        rig = dataclasses.replace(rig, video=VideoSpec(poses=load_poses(args.poses)))
    elif rig.video is None:
        raise CLIError(f"rig '{args.rig}' has no [video] section: give video.velocity, video.positions or video.poses there, or --poses CSV")
    source = read_video(args.source)
    _check_not_inputs(figures, (source,), (args.source, args.rig, args.poses))
    total = len(source)
    if source.paths is not None and total < 3:
        raise CLIError(f"video needs at least 3 frames, '{args.source}' has {total}")
    frames_iter = iter(source)
    first = next(frames_iter, None)
    if first is None:
        raise CLIError(f"video needs at least 3 frames, '{args.source}' has none")
    rig.check_image_shape(first.shape, what=f"frame 0 of '{args.source}'")  # before any work or output
    progress = _Progress(total, quiet=args.quiet)
    frames_seen = [0]

    source_ended = [False]

    def counted():
        for f in itertools.chain([first], frames_iter):
            frames_seen[0] += 1
            progress.step()
            yield f
        source_ended[0] = True

    results = []
    written = 0
    last = None
    matched = []  # (frame, fits) of the triples whose outer frames' exposures were undone
    empty = []  # frames with no depth at all
    try:
        for res in depth_from_video(counted(), rig=rig, **options):
            last = res
            if not np.isfinite(res.depth).any() and (res.dense_inverse_depth is None or not np.isfinite(res.dense_depth).any()):
                empty.append(res.index)  # no depth at its edge points, nor (--dense) in its dense map
            if res.exposure is not None:
                matched.append((res.index, [fit for fit in res.exposure if fit is not None]))
            if kind == "npz":
                results.append(res)
            else:
                make_output_folder(out)
                write_video_frame(res, out, force=args.force)
                written += 1
    except BaseException as exc:
        progress.abort()
        if isinstance(exc, ValueError) and source_ended[0] and frames_seen[0] < 3:  # the library's own refusal, told with the file
            raise CLIError(f"video needs at least 3 frames, '{args.source}' gave {frames_seen[0]}") from None
        named = _frame_named(str(exc), source) if isinstance(exc, (ValueError, RigError)) else None
        if named is not None:  # the library knows no files: "frame 4 ..." is told with its file
            raise CLIError(named) from None
        raise
    progress.close()
    if kind == "npz":
        write_video_npz(results, out, camera=rig.camera, force=args.force)
        written = len(results)
    if last is not None:
        write_figures(figures, last.depth, last.depth_std, title=f"frame {last.index} (fused)", unit=_unit(args))
    note = ""
    if matched:
        from .cli import _offset_text

        gains = [fit[0] for _, fits in matched for fit in fits]
        offsets = [fit[1] for _, fits in matched for fit in fits]
        shown = f", offsets {_offset_text(min(offsets))}..{_offset_text(max(offsets))}" if max(abs(o) for o in offsets) >= 0.005 else ""
        note = (
            f", exposure matched in {len(matched)} triple{'s' if len(matched) > 1 else ''} (frames"
            f" {', '.join(str(k) for k, _ in matched[:8])}{', ...' if len(matched) > 8 else ''}; gains {min(gains):.3g}..{max(gains):.3g}{shown})"
        )
    if empty:
        listed = ", ".join(str(k) for k in empty[:8]) + (", ..." if len(empty) > 8 else "")
        note = f", {len(empty)} of them without any (frame{'s' if len(empty) > 1 else ''} {listed})" + note
    print(f"depth for {written} frames (of {frames_seen[0]}; the first and last have no triple){note} -> {out}")
    return 0


def _frame_named(message: str, source) -> str | None:
    """The library's refusal of a frame (``as_image``'s "frame K ...", the size's "does not match frame K (...)") named by its file.

    The frame's file in a folder of frames, or the video file; None for a message about no frame's pixels (a pose's frame, say).
    """
    found = re.match(r"(?:frame|.* does not match frame) (\d+)\b", message, re.DOTALL)
    if found is None:
        return None
    k, rest = int(found.group(1)), message[found.end() :]
    head = message[: found.start(1) - len("frame ")]
    if source.paths is None:
        return f"{head}frame {k} of '{source.video}'{rest}"
    if k >= len(source.paths):
        return None
    said = re.match(r" \(([^()]*)\)", rest)  # "frame 3 (60x50)": one parenthesis, "frame 3 ('f3.png', 60x50)"
    if said is not None:
        return f"{head}frame {k} ('{source.paths[k]}', {said.group(1)}){rest[said.end() :]}"
    return f"{head}frame {k} ('{source.paths[k]}'){rest}"


_NOISE_STD_HELP = (
    "the images' noise std in grey levels, for the error bar (default: estimated from the images;"
    " compressed video and JPEG hide most of it, which makes the error bar too narrow: give it here)"
)


def register(sub, CLIError) -> None:
    """Add the ``dynamic`` and ``video`` sub-commands to ``sub``."""
    global _CLIError
    _CLIError = CLIError

    p = sub.add_parser(
        "dynamic",
        help="dynamic stereo: depth at edge points from five images, or two synchronised videos, and a rig file (paper eq. 4)",
    )
    p.add_argument("images", nargs="*", metavar="IMAGE", help="I1 I2 I3 I4 I5: I1, I3, I5 from the moving camera, I2, I3, I4 from the reference")
    p.add_argument("--moving-video", metavar="VIDEO", help="instead of images: the moving camera's video (file, image folder or glob)")
    p.add_argument("--reference-video", metavar="VIDEO", help="the reference camera's video, frame k taken with frame k of --moving-video")
    p.add_argument("--crossings", type=int, nargs="+", metavar="K", help="with videos: frames at which the two cameras coincide (default: the rig's motion.crossings)")
    p.add_argument("--shared", choices=("mean", "reference", "moving"), help="with videos: I3 from M[K] and R[K]: their mean (default) or one of them")
    p.add_argument(
        "--no-match-exposure",
        action="store_true",
        help="take the images' intensities as they are (default: an image whose exposure differs from I3's is mapped onto it first;"
        " with videos the reference camera's frames onto the moving camera's exposure, from M[K] and R[K], as well)",
    )
    p.add_argument("--rig", required=True, metavar="TOML", help="rig file with [camera] and [motion] (docs/rig-format.md)")
    p.add_argument("--out", required=True, metavar="OUT", help="depth at the edge points of I3: .pfm, .tif or .npy, NaN elsewhere;"
                   " with videos OUT.npz or a folder (depth_NNNNNN.tif, depth_std_NNNNNN.tif per crossing)")
    p.add_argument("--uncertainty", metavar="FILE", help="also write the depth standard deviation here")
    p.add_argument("--preview", metavar="PNG", help="also write a bare colour-mapped PNG: turbo from the map's minimum (blue) to its maximum (red), unknown pixels black, no legend (--figure has a colour bar)")
    p.add_argument("--figure", metavar="PNG", help="also write a figure with a colour bar and, where the run writes the std (five images: --uncertainty; videos: always, in the NPZ), PNG_std.png; videos: the last crossing")
    p.add_argument("--unit", help="with --figure: unit of depth for the colour bar (default: scene units)")
    p.add_argument("--ply", metavar="FILE", help="also write the edge points as a point cloud")
    p.add_argument("--csv", metavar="FILE", help="also write the points as CSV: row,col,depth,depth_std (sub-pixel positions)")
    p.add_argument("--sigma-px", type=float, help="Gaussian smoothing (px, default 3)")
    p.add_argument("--noise-std", type=float, metavar="GREY", help=_NOISE_STD_HELP)
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=_cmd_dynamic)

    p = sub.add_parser("video", help="depth per frame of a camera moving (and turning) through a static scene, fused over time")
    p.add_argument("source", metavar="VIDEO", help="a video file, a folder of images, or a glob such as 'frames/*.png'")
    p.add_argument("--rig", required=True, metavar="TOML", help="rig file with [camera] and [video] (docs/rig-format.md)")
    p.add_argument("--out", required=True, metavar="OUT", help="OUT.npz (all frames, written at the end) or a folder (depth_NNNNNN.tif per frame)")
    p.add_argument("--poses", metavar="CSV", help="camera poses per frame (frame,x,y,z[,rx,ry,rz]); replaces the rig's [video]")
    p.add_argument("--figure", metavar="PNG", help="also write figures with a colour bar of the last frame's fused depth (PNG) and std (PNG_std.png)")
    p.add_argument("--unit", help="with --figure: unit of depth for the colour bar (default: scene units)")
    p.add_argument("--sigma-px", type=float, help="Gaussian smoothing (px, default 2)")
    p.add_argument("--noise-std", type=float, metavar="GREY", help=_NOISE_STD_HELP)
    p.add_argument(
        "--levels",
        type=int,
        help="pyramid levels of each triple's coarse-to-fine prior, for motions beyond 1-2 px per frame (default: from the frame size; 1: the paper's single level)",
    )
    p.add_argument(
        "--dense",
        action="store_true",
        help="also a dense depth map of every frame's triple (rectified static stereo; not fused over time): arrays dense_depth,"
        " dense_depth_std in OUT.npz, or dense_depth_NNNNNN.tif, dense_depth_std_NNNNNN.tif in a folder",
    )
    p.add_argument(
        "--dense-frames-before",
        type=int,
        metavar="N",
        help="with --dense: frames before each frame that its dense map uses (default 1: the triple); more for a camera that moves"
        " little per frame (a longer row, at no delay)",
    )
    p.add_argument("--threads", type=int, metavar="N", help="with --dense: threads of the cost volume (default: all cores, as OpenCV)")
    p.add_argument(
        "--no-match-exposure",
        action="store_true",
        help="take the frames' intensities as they are (default: each triple's outer frames are mapped onto the middle frame's exposure)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=_cmd_video)
