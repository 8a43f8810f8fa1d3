"""A camera that turns while it moves: ``python benchmarks/video_turning.py [--seeds N]``.

The paper's pyramid (f = 100 px, 200 x 200, noise 1 grey level) filmed by a
camera that translates and turns at a constant rate
(:class:`nfdepth.synthetic.CameraMotion`), its poses given to
:func:`nfdepth.video.depth_from_video` as positions and orientations. Two
tables of median relative depth errors at the edge points of the middle
frame, against the rendered truth, averaged over the seeds:

1. One triple on the paper's single level: eq. 4 with its rotational term
   ``A`` (the paper's way, first order in the rotation) against the
   video pipeline, which turns the outer frames to the middle one's
   orientation (:mod:`nfdepth._derotation`).
2. Seven frames with the default pyramid: the single triples' median and
   the fused depth at the last frame, with its median ``|error| / std``.
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

from nfdepth import synthetic
from nfdepth.camera import PinholeCamera, RigidMotion
from nfdepth.depth import Reason, solve_inverse_depth
from nfdepth.pipelines import static_stereo_edges
from nfdepth.video import depth_from_video

CAMERA = PinholeCamera(focal_px=100.0, width_px=200, height_px=200)


def film(step, turn_deg, *, n_frames, seed):
    """Frames, positions, orientations (rad) and the camera's motion; the middle frame at t = 0."""
    motion = synthetic.CameraMotion(velocity_per_t=step, rotation_rad_per_t=np.deg2rad(np.asarray(turn_deg, dtype=float)))
    scene = synthetic.video_sequence(
        synthetic.paper_pyramid(), CAMERA, camera_motion=motion, n_frames=n_frames, noise_std=1.0, rng=np.random.default_rng(seed)
    )
    return list(scene.frames), scene.positions, scene.orientations_rad, motion, list(scene.times)


def relative_errors(rho, rows, cols, motion, time):
    z = synthetic.surface_depth_at(synthetic.paper_pyramid(), CAMERA, rows, cols, camera_motion=motion, time=time)
    return np.abs(1.0 / rho - z) / z, z


def first_order_against_turned(turn_deg, seed):
    """One triple, single level: (eq. 4 with A, turned frames) median relative errors."""
    step = np.array([2.0, 0.0, 0.0])
    frames, positions, orientations, motion, _ = film(step, turn_deg, n_frames=3, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the raw triple's rotational flow can push points behind the camera
        res = static_stereo_edges(frames, camera=CAMERA, baseline=2.0, direction=step / 2.0)
    relative = RigidMotion(translation=-step, rotation=-np.deg2rad(np.asarray(turn_deg, dtype=float)))
    inv = solve_inverse_depth(
        res.delta_vn, camera=CAMERA, rows=res.rows, cols=res.cols, alpha=res.alpha, relative_motion=relative, delta_vn_std=res.delta_vn_std
    )
    ok = inv.reason == Reason.OK
    first_order, _ = relative_errors(inv.rho[ok], res.rows[ok], res.cols[ok], motion, 0.0)
    (out,) = depth_from_video(frames, camera=CAMERA, positions=positions, orientations_rad=orientations, levels=1)
    ii, jj = np.nonzero(np.isfinite(out.measured_inverse_depth))
    turned, _ = relative_errors(out.measured_inverse_depth[ii, jj], ii + 0.5, jj + 0.5, motion, 0.0)
    return np.median(first_order), np.median(turned)


def fused(step, turn_deg, seed):
    """Seven frames, default pyramid: (median single-triple error, fused error at the last frame, fused median |z|, points)."""
    frames, positions, orientations, motion, times = film(np.asarray(step, dtype=float), turn_deg, n_frames=7, seed=seed)
    out = list(depth_from_video(frames, camera=CAMERA, positions=positions, orientations_rad=orientations))
    singles = []
    for r in out:
        ii, jj = np.nonzero(np.isfinite(r.measured_inverse_depth))
        singles.append(np.median(relative_errors(r.measured_inverse_depth[ii, jj], ii + 0.5, jj + 0.5, motion, times[r.index])[0]))
    last = out[-1]
    ii, jj = np.nonzero(np.isfinite(last.inverse_depth))
    rho = last.inverse_depth[ii, jj]
    err, z = relative_errors(rho, ii + 0.5, jj + 0.5, motion, times[last.index])
    score = np.abs(rho - 1.0 / z) / last.inverse_depth_std[ii, jj]
    return np.median(singles), np.median(err), np.median(score), ii.size


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=4, help="noise seeds to average (default 4)")
    count = parser.parse_args(argv).seeds
    if count < 1:
        parser.error(f"--seeds must be at least 1, got {count}")
    seeds = range(count)
    print("| turn per frame | rotational flow at the centre | eq. 4 with `A` | turned frames |")
    print("| --- | --- | --- | --- |")
    for deg in (0.1, 0.3, 1.0, 2.0):
        a, t = np.mean([first_order_against_turned((0.0, deg, 0.0), s) for s in seeds], axis=0)
        print(f"| {deg:g}° about Y | {CAMERA.focal_px * np.deg2rad(deg):.2f} px | {100 * a:.2f} % | {100 * t:.2f} % |")
    print()
    print("| translation per frame | turn per frame (deg) | single triples | fused, last frame | fused median abs(z) | points |")
    print("| --- | --- | --- | --- | --- | --- |")
    for step, turn in (
        ((2, 0, 0), (0, 0, 0)),
        ((2, 0, 0), (0, 0, 1)),
        ((2, 0, 0), (0, 1, 0)),
        ((2, 0, 0), (1, 1, 1)),
        ((2, 0, 0), (0, 5, 0)),
        ((8, 0, 0), (0, 3, 0)),
        ((0, 0, 8), (0, 2, 0)),
        ((0.5, 1, 1.5), (0.5, 0.5, 0.5)),
    ):
        single, fused_err, score, points = np.mean([fused(step, turn, s) for s in seeds], axis=0)
        print(f"| {step} | {turn} | {100 * single:.2f} % | {100 * fused_err:.2f} % | {score:.2f} | {points:.0f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
