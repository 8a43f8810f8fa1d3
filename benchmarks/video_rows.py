"""The real rows of views as videos: ``python benchmarks/video_rows.py [--data DIR]``.

Each row of the Middlebury and Tsukuba sets (the views, in order) is read
as the frames of a camera moving +X by one view step per frame
(``depth_from_video(views, velocity=(1, 0, 0))`` with a focal length of
100 px, so that 100 times the inverse depth is the disparity per view step,
the truth's unit). The fused inverse depth at the view with ground truth is
scored at its edge points, with the coarse-to-fine prior (the default) and
on the paper's single level (``levels=1``). These rows move 5-20 px per
frame, far beyond the differential method's 1-2 px. Prints a markdown
table; the near-step split is :func:`nfdepth.evaluate.depth_step_mask`.

``--turn-deg-per-frame D`` makes the camera turn as well: frame ``k`` is
the view resampled as a camera at the same place turned about its Y axis
by ``(k - reference) D`` degrees would see it (a homography, exact for a
rotation, with the published focal length, or the image width where none
is published) and cropped to what every turned frame sees; the poses give
the pipeline positions and orientations, and the score is that of the
cropped truth. Only the frames up to the one after the reference are used
(the reference's depth does not depend on later frames).

``--drop-frame`` leaves out the frame after the reference, as a video that
dropped it: the reference's triple has steps of one and two views (each
outer frame is warped by its own step, :mod:`nfdepth._translating_pyramid`).

``--dense`` scores the dense map of the reference's triple instead
(``depth_from_video(..., dense=True)``, :mod:`nfdepth._dense_video`): the
share of the pixels with truth it covers, bad-1px and the median relative
error over them, the median ``|error| / std`` (0.67 for an honest Gaussian
std) and the seconds per frame of the whole pipeline.

``--dense --frames-before N`` scores the dense maps of longer rows
(``depth_from_video(..., dense_frames_before=N)``) at the last view with
ground truth instead, whose own truth the sets also publish (Middlebury
2005: view 5, ``disp5.png``; Teddy: view 6, ``disp6.pgm``; Tsukuba has
none), for 1 frame before (the triple) and for N: the frames from the
first up to the one after that view.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings

import numpy as np
from scipy.spatial.transform import Rotation

from nfdepth import datasets
from nfdepth._derotation import derotate, derotation_maps
from nfdepth.camera import PinholeCamera
from nfdepth.evaluate import depth_step_mask
from nfdepth.video import depth_from_video

SCENES = [f"middlebury2005/{s}" for s in datasets.MIDDLEBURY2005_SCENES] + ["middlebury2003-teddy", "tsukuba"]


def turned_row(scene, turn_deg):
    """Frames ``0 .. reference + 1`` turned about Y by ``(k - reference) turn_deg`` degrees, cropped; their camera, orientations, crop."""
    h, w = scene.shape
    full = PinholeCamera(scene.focal_px or float(w), w, h)
    ref = scene.reference_index
    angles = np.deg2rad(turn_deg) * (np.arange(ref + 2) - ref)
    maps = [derotation_maps(full, Rotation.from_rotvec((0.0, a, 0.0)).as_matrix()) for a in angles]
    inside = np.logical_and.reduce([m[2] for m in maps])
    margin = 0  # a centred crop that every turned frame sees whole
    while not inside[margin : h - margin, margin : w - margin].all():
        margin += 1
    crop = (slice(margin, h - margin), slice(margin, w - margin))
    frames = [derotate(np.asarray(v, np.float32), m)[crop] for v, m in zip(scene.views, maps)]
    cam = PinholeCamera(full.focal_px, w - 2 * margin, h - 2 * margin)
    orientations = np.stack([np.zeros_like(angles), angles, np.zeros_like(angles)], axis=1)
    return frames, cam, orientations, crop


def row_video(scene, turn_deg, drop_frame=False):
    """The row's frames, camera, motion (``depth_from_video`` keywords) and the crop of its truth; turned when ``turn_deg``.

    ``drop_frame`` leaves out the frame after the reference (the positions say so).
    """
    if turn_deg:
        frames, cam, orientations, crop = turned_row(scene, turn_deg)
        motion = {"orientations_rad": orientations}
    else:
        frames, cam, crop = list(scene.views), PinholeCamera(100.0, scene.shape[1], scene.shape[0]), (slice(None), slice(None))
        motion = {}
    if not turn_deg and not drop_frame:
        return frames, cam, {"velocity": (1.0, 0.0, 0.0)}, crop
    keep = [k for k in range(len(frames)) if not (drop_frame and k == scene.reference_index + 1)]
    motion = {name: value[keep] for name, value in motion.items()}
    motion["positions"] = np.asarray(keep, dtype=float)[:, None] * np.array([1.0, 0.0, 0.0])
    return [frames[k] for k in keep], cam, motion, crop


def score(scene, levels, turn_deg=0.0, drop_frame=False):
    """Points, median relative error, bad-1px (all, off the depth steps) and ms per frame at the reference view."""
    frames, cam, motion, crop = row_video(scene, turn_deg, drop_frame)
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # behind-camera points at the borders of the single level's wrong answers
        out = {r.index: r for r in depth_from_video(frames, camera=cam, levels=levels, **motion)}
    ms = 1e3 * (time.perf_counter() - start) / max(len(out), 1)
    rho = out[scene.reference_index].inverse_depth  # a dropped frame comes after it: the reference keeps its index
    disparity, valid = scene.disparity[crop], scene.valid[crop]
    m = np.isfinite(rho) & valid
    err = np.abs(cam.focal_px * rho[m] - disparity[m])  # a unit step per frame: f rho is the disparity
    off = ~depth_step_mask(disparity)[m]
    return m.sum(), np.median(err / disparity[m]), np.mean(err > 1.0), np.mean(err[off] > 1.0), ms


def score_dense(scene, turn_deg=0.0, drop_frame=False):
    """Dense map of the reference's triple: cover, bad-1px, median relative error, median |error| / std, s per frame."""
    ref = scene.reference_index
    frames, cam, motion, crop = row_video(scene, turn_deg, drop_frame)
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the edge points' own notes
        (out,) = depth_from_video(frames[ref - 1 : ref + 2], camera=cam, first_frame=ref - 1, dense=True, **motion)
    seconds = time.perf_counter() - start
    d, sd = cam.focal_px * out.dense_inverse_depth, cam.focal_px * out.dense_inverse_depth_std
    disparity, valid = scene.disparity[crop], scene.valid[crop]
    m = np.isfinite(d) & valid
    err = np.abs(d[m] - disparity[m])
    return m.sum() / valid.sum(), np.mean(err > 1.0), np.median(err / disparity[m]), np.median(err / sd[m]), seconds


#: The second view with its own ground truth, and that truth's file and scale (px per stored unit).
SECOND_TRUTH = {f"middlebury2005/{s}": (5, f"middlebury2005/{s}/disp5.png", 8.0) for s in datasets.MIDDLEBURY2005_SCENES}
SECOND_TRUTH["middlebury2003-teddy"] = (6, "middlebury2003-teddy/disp6.pgm", 16.0)


def score_longer_rows(scene, root, frames_before):
    """Dense map at the second truth view from 1 frame before and from ``frames_before``: cover, bad-1px, median rel, median |z|, s/frame each."""
    from nfdepth.datasets import _read_coded_disparity

    view, path, scale = SECOND_TRUTH[scene.name if scene.name != "teddy" else "middlebury2003-teddy"]
    truth = _read_coded_disparity(root / path, scale)
    cam = PinholeCamera(100.0, scene.shape[1], scene.shape[0])
    rows = []
    for before in (1, frames_before):
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the edge points' own notes
            out = list(depth_from_video(list(scene.views)[: view + 2], camera=cam, velocity=(1.0, 0.0, 0.0), dense=True, dense_frames_before=before))
        seconds = (time.perf_counter() - start) / len(out)
        d, sd = cam.focal_px * out[-1].dense_inverse_depth, cam.focal_px * out[-1].dense_inverse_depth_std
        valid = np.isfinite(truth)
        m = np.isfinite(d) & valid
        err = np.abs(d[m] - truth[m])
        rows.append((m.sum() / valid.sum(), np.mean(err > 1.0), np.median(err / truth[m]), np.median(err / sd[m]), seconds))
    return view, rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", metavar="DIR", help="data root (default: $NFDEPTH_DATA, ../shared/data, ...)")
    parser.add_argument("--turn-deg-per-frame", type=float, default=0.0, metavar="D", help="the camera turns about Y by D degrees per frame as well")
    parser.add_argument("--drop-frame", action="store_true", help="leave out the frame after the reference (steps of one and two views)")
    parser.add_argument("--dense", action="store_true", help="score the dense map of the reference's triple instead")
    parser.add_argument("--frames-before", type=int, metavar="N", help="with --dense: longer rows, at the second view with ground truth (module docstring)")
    args = parser.parse_args(argv)
    if args.frames_before is not None and (not args.dense or args.turn_deg_per_frame or args.drop_frame or args.frames_before < 1):
        parser.error("--frames-before N (N >= 1) goes with --dense alone")
    if args.drop_frame and args.turn_deg_per_frame:
        parser.error("--drop-frame and --turn-deg-per-frame do not go together (a turned row ends at the frame after the reference)")
    if not (np.isfinite(args.turn_deg_per_frame) and abs(args.turn_deg_per_frame) <= 10):
        parser.error(f"--turn-deg-per-frame must be a number of degrees within +-10 (the rows turn it for every view), got {args.turn_deg_per_frame:g}")
    try:
        root = datasets.data_root(args.data)
    except datasets.DataNotFoundError as exc:
        parser.error(str(exc))
    if args.frames_before is not None:
        print("| scene | view | frames before | dense cover | bad-1px | median rel | median abs(error) / std | s/frame |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        for name in SECOND_TRUTH:
            view, rows = score_longer_rows(datasets.load_scene(name, root), root, args.frames_before)
            for before, (cover, bad, med, z, seconds) in zip((1, args.frames_before), rows):
                print(f"| {name} | {view} | {before} | {100 * cover:.1f} % | {100 * bad:.2f} % | {100 * med:.2f} % | {z:.2f} | {seconds:.2f} |", flush=True)
        return 0
    if args.dense:
        print("| scene | dense cover | bad-1px | median rel | median abs(error) / std | s/frame |")
        print("| --- | --- | --- | --- | --- | --- |")
        for name in SCENES:
            cover, bad, med, z, seconds = score_dense(datasets.load_scene(name, root), args.turn_deg_per_frame, args.drop_frame)
            print(f"| {name} | {100 * cover:.1f} % | {100 * bad:.2f} % | {100 * med:.2f} % | {z:.2f} | {seconds:.2f} |", flush=True)
        return 0
    print("| scene | views | truth median px/frame | levels | points | median rel | bad-1px | bad-1px off steps | ms/frame |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in SCENES:
        scene = datasets.load_scene(name, root)
        views = (scene.reference_index + 2 if args.turn_deg_per_frame else len(scene.views)) - args.drop_frame
        for levels, label in ((None, "auto"), (1, "1 (paper)")):
            n, med, bad, bad_off, ms = score(scene, levels, args.turn_deg_per_frame, args.drop_frame)
            motion = np.median(scene.disparity[scene.valid])
            print(f"| {name} | {views} | {motion:.1f} | {label} | {n} | {100 * med:.2f} % | {100 * bad:.1f} % | {100 * bad_off:.1f} % | {ms:.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
