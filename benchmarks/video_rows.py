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
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings

import numpy as np

from nfdepth import datasets
from nfdepth.camera import PinholeCamera
from nfdepth.evaluate import depth_step_mask
from nfdepth.video import depth_from_video

SCENES = [f"middlebury2005/{s}" for s in datasets.MIDDLEBURY2005_SCENES] + ["middlebury2003-teddy", "tsukuba"]


def score(scene, levels):
    """Points, median relative error, bad-1px (all, off the depth steps) and ms per frame at the reference view."""
    cam = PinholeCamera(100.0, scene.shape[1], scene.shape[0])
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # behind-camera points at the borders of the single level's wrong answers
        frames = {r.index: r for r in depth_from_video(list(scene.views), camera=cam, velocity=(1.0, 0.0, 0.0), levels=levels)}
    ms = 1e3 * (time.perf_counter() - start) / max(len(frames), 1)
    rho = frames[scene.reference_index].inverse_depth
    m = np.isfinite(rho) & scene.valid
    err = np.abs(100.0 * rho[m] - scene.disparity[m])
    off = ~depth_step_mask(scene.disparity)[m]
    return m.sum(), np.median(err / scene.disparity[m]), np.mean(err > 1.0), np.mean(err[off] > 1.0), ms


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", metavar="DIR", help="data root (default: $NFDEPTH_DATA, ../shared/data, ...)")
    args = parser.parse_args(argv)
    root = datasets.data_root(args.data)
    print("| scene | views | truth median px/frame | levels | points | median rel | bad-1px | bad-1px off steps | ms/frame |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in SCENES:
        scene = datasets.load_scene(name, root)
        for levels, label in ((None, "auto"), (1, "1 (paper)")):
            n, med, bad, bad_off, ms = score(scene, levels)
            motion = np.median(scene.disparity[scene.valid])
            print(f"| {name} | {len(scene.views)} | {motion:.1f} | {label} | {n} | {100 * med:.2f} % | {100 * bad:.1f} % | {100 * bad_off:.1f} % | {ms:.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
