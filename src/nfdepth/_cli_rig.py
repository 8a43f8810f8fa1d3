"""``nfdepth dynamic`` and ``nfdepth video``: commands driven by a rig file.

Each command is a thin layer over public functions:

* ``dynamic`` -> :func:`nfdepth.rig.load_rig`, :func:`nfdepth.io.read_image`,
  :func:`nfdepth.rig.dynamic_stereo_from_rig`, :func:`nfdepth.rig.edge_depth_maps`.
* ``video`` -> :func:`nfdepth.rig.load_rig`, :func:`nfdepth.video.read_video`,
  :func:`nfdepth.video.depth_from_video`, :func:`nfdepth.video.write_video_npz`
  / :func:`nfdepth.video.write_video_frame`.
"""

from __future__ import annotations

import dataclasses
import itertools
import sys
import time
from pathlib import Path

import numpy as np

__all__ = ["register"]

_CLIError = Exception  # replaced by register()


def _outputs(args, CLIError):
    from .cli import EXIT_USAGE, _check_output

    outs = {"out": _check_output(args.out, force=args.force)}
    if args.uncertainty:
        outs["uncertainty"] = _check_output(args.uncertainty, force=args.force, what="--uncertainty")
    if args.preview:
        outs["preview"] = _check_output(args.preview, force=args.force, exts=(".png",), what="--preview")
    if args.ply:
        outs["ply"] = _check_output(args.ply, force=args.force, exts=(".ply",), what="--ply")
    if args.csv:
        outs["csv"] = _check_output(args.csv, force=args.force, exts=(".csv",), what="--csv")
    if len({str(p.resolve()) for p in outs.values()}) != len(outs):
        raise CLIError("output paths must differ from each other", EXIT_USAGE)
    return outs


def _cmd_dynamic(args) -> int:
    from .io import atomic_write, read_image, write_array, write_colormap_png, write_ply
    from .rig import dynamic_stereo_from_rig, edge_depth_maps, load_rig

    CLIError = _CLIError
    if len(args.images) != 5:
        raise CLIError(f"dynamic needs exactly 5 images I1 I2 I3 I4 I5 (I1, I3, I5 moving camera; I2, I3, I4 reference), got {len(args.images)}")
    if args.sigma_px is not None and (not np.isfinite(args.sigma_px) or args.sigma_px < 0):
        raise CLIError(f"--sigma-px must be a finite number >= 0, got {args.sigma_px:g}")
    outs = _outputs(args, CLIError)
    rig = load_rig(args.rig)
    rig.relative_motion()  # a missing [motion] fails before any image is read
    frames = [read_image(p) for p in args.images]
    for k, (p, f) in enumerate(zip(args.images, frames), 1):
        rig.check_image_shape(f.shape, what=f"I{k} '{Path(p).name}'")
    options = {} if args.sigma_px is None else {"sigma_px": args.sigma_px}
    result = dynamic_stereo_from_rig(frames, rig, **options)
    depth, std = edge_depth_maps(result)
    write_array(outs["out"], depth, force=args.force)
    if "uncertainty" in outs:
        write_array(outs["uncertainty"], std, force=args.force)
    if "preview" in outs:
        write_colormap_png(outs["preview"], depth, force=args.force)
    ok = result.valid
    if "ply" in outs:
        grey = read_image(args.images[2], grey=False, dtype=None)
        img = grey if grey.ndim == 3 else np.repeat(grey[..., None], 3, axis=2)
        img = img[..., :3]
        if img.dtype != np.uint8:
            scale = 255.0 / max(float(np.nanmax(img)), 1.0)  # 16-bit or float input: stretch to 8 bits
            img = np.clip(np.rint(img.astype(float) * scale), 0, 255).astype(np.uint8)
        ii = np.floor(result.rows[ok]).astype(int)
        jj = np.floor(result.cols[ok]).astype(int)
        write_ply(outs["ply"], result.points[ok].astype(np.float32), colors=img[ii, jj], force=args.force)
    if "csv" in outs:
        lines = ["row,col,depth,depth_std"]
        lines += [f"{r:.2f},{c:.2f},{z:.6g},{s:.6g}" for r, c, z, s in zip(result.rows[ok], result.cols[ok], result.depth[ok], result.depth_std[ok])]
        text = "\n".join(lines) + "\n"
        atomic_write(outs["csv"], lambda fh: fh.write(text.encode()), force=args.force)
    z = result.depth[ok]
    rng_txt = f"{np.min(z):.4g}..{np.max(z):.4g}" if z.size else "none"
    print(f"depth at {int(ok.sum())} of {len(result)} edge points of I3 ({Path(args.images[2]).name}), range {rng_txt} -> {outs['out']}")
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

    out = Path(args.out)
    if out.suffix.lower() == ".npz":
        return "npz", _check_output(args.out, force=args.force, exts=(".npz",))
    if out.suffix and not out.is_dir():
        raise CLIError(f"--out '{out}' must be a .npz file or a folder (no extension)", EXIT_USAGE)
    if out.exists() and not out.is_dir():
        raise CLIError(f"--out '{out}' exists and is not a folder", EXIT_WRITE)
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise CLIError(f"--out '{out}': directory '{parent}' does not exist", EXIT_WRITE)
    if out.is_dir() and not args.force and any(out.glob("depth_*.tif")):
        raise CLIError(f"--out '{out}' already holds depth_*.tif files; use --force to overwrite them", EXIT_WRITE)
    return "dir", out


def _cmd_video(args) -> int:
    from .rig import VideoSpec, load_poses, load_rig
    from .video import depth_from_video, read_video, write_video_frame, write_video_npz

    CLIError = _CLIError
    kind, out = _video_output(args, CLIError)
    if args.sigma_px is not None and (not np.isfinite(args.sigma_px) or args.sigma_px < 0):
        raise CLIError(f"--sigma-px must be a finite number >= 0, got {args.sigma_px:g}")
    rig = load_rig(args.rig)
    if args.poses:
        rig = dataclasses.replace(rig, video=VideoSpec(poses=load_poses(args.poses)))
    elif rig.video is None:
        raise CLIError(f"rig '{args.rig}' has no [video] section: give video.velocity, video.positions or video.poses there, or --poses CSV")
    source = read_video(args.source)
    total = len(source)
    if source.paths is not None and total < 3:
        raise CLIError(f"video needs at least 3 frames, '{args.source}' has {total}")
    options = {} if args.sigma_px is None else {"sigma_px": args.sigma_px}
    frames_iter = iter(source)
    first = next(frames_iter, None)
    if first is None:
        raise CLIError(f"video needs at least 3 frames, '{args.source}' has none")
    rig.check_image_shape(first.shape, what=f"frame 0 of '{args.source}'")  # before any work or output
    progress = _Progress(total, quiet=args.quiet)
    frames_seen = [0]

    def counted():
        for f in itertools.chain([first], frames_iter):
            frames_seen[0] += 1
            progress.step()
            yield f

    results = []
    written = 0
    try:
        for res in depth_from_video(counted(), rig=rig, **options):
            if kind == "npz":
                results.append(res)
            else:
                out.mkdir(exist_ok=True)
                write_video_frame(res, out, force=args.force)
                written += 1
    except BaseException:
        progress.abort()
        raise
    progress.close()
    if frames_seen[0] < 3:
        raise CLIError(f"video needs at least 3 frames, '{args.source}' gave {frames_seen[0]}")
    if kind == "npz":
        write_video_npz(results, out, camera=rig.camera, force=args.force)
        written = len(results)
    print(f"depth for {written} frames (of {frames_seen[0]}; the first and last have no triple) -> {out}")
    return 0


def register(sub, CLIError) -> None:
    """Add the ``dynamic`` and ``video`` sub-commands to ``sub``."""
    global _CLIError
    _CLIError = CLIError

    p = sub.add_parser("dynamic", help="dynamic stereo: depth at edge points from five images and a rig file (paper eq. 4)")
    p.add_argument("images", nargs="+", metavar="IMAGE", help="I1 I2 I3 I4 I5: I1, I3, I5 from the moving camera, I2, I3, I4 from the reference")
    p.add_argument("--rig", required=True, metavar="TOML", help="rig file with [camera] and [motion] (docs/rig-format.md)")
    p.add_argument("--out", required=True, metavar="FILE", help="depth at the edge points of I3: .pfm, .tif or .npy, NaN elsewhere")
    p.add_argument("--uncertainty", metavar="FILE", help="also write the depth standard deviation here")
    p.add_argument("--preview", metavar="PNG", help="also write a colour-mapped PNG")
    p.add_argument("--ply", metavar="FILE", help="also write the edge points as a point cloud")
    p.add_argument("--csv", metavar="FILE", help="also write the points as CSV: row,col,depth,depth_std (sub-pixel positions)")
    p.add_argument("--sigma-px", type=float, help="Gaussian smoothing (px, default 3)")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=_cmd_dynamic)

    p = sub.add_parser("video", help="depth per frame of a camera translating through a static scene, fused over time")
    p.add_argument("source", metavar="VIDEO", help="a video file, a folder of images, or a glob such as 'frames/*.png'")
    p.add_argument("--rig", required=True, metavar="TOML", help="rig file with [camera] and [video] (docs/rig-format.md)")
    p.add_argument("--out", required=True, metavar="OUT", help="OUT.npz (all frames, written at the end) or a folder (depth_NNNNNN.tif per frame)")
    p.add_argument("--poses", metavar="CSV", help="camera poses per frame (frame,x,y,z[,rx,ry,rz]); replaces the rig's [video]")
    p.add_argument("--sigma-px", type=float, help="Gaussian smoothing (px, default 2)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=_cmd_video)
