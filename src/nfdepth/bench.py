"""Speed benchmarks: nfdepth's fast paths against OpenCV baselines and a floor.

Everything runs in one process, OpenCV on one thread (``cv2.setNumThreads(1)``)
unless ``threads`` says otherwise, the cases *interleaved*: each round runs
every case once (in a rotating order), after one warm-up round, and a case's
figure is the median over rounds. Ratios compare figures from the same run.

Cases (per image size and scene):

``nf_edges``            :func:`nfdepth.fast.normal_flow_edges` on a triple
``nf_edges_reference``  the plain reference (``normal_flow`` + ``select_edge_points``)
``nf_stream_frame``     :class:`nfdepth.fast.StreamingNormalFlow`, cost per pushed frame
``nf_static_stereo``    ``nfdepth.stereo.static_stereo`` on three views, dense (skipped
                        if the call fails)
``nf_static_stereo_edges`` the same with ``edges_only=True`` (the paper's sparse output)
``cv_sgbm``             ``cv2.StereoSGBM`` (64 disparities, block 5) on a uint8 pair
``cv_sgbm_covering``    the same with the disparities a user would set for this scene: the
                        multiple of 16 above the largest disparity nfdepth found (skipped
                        with static stereo); upscaled scenes outgrow 64
``cv_bm``               ``cv2.StereoBM`` (64 disparities, block 15) on a uint8 pair
``cv_dis_fast/medium``  ``cv2.DISOpticalFlow`` presets on a uint8 pair
``floor_blur3``         three ``cv2.GaussianBlur`` (sigma as nfdepth's) of the float32 frames
``floor_copy3``         a copy of the three float32 frames

``ratio_to_sgbm`` is a case's median over ``cv_sgbm``'s (64 disparities, the issue's
yardstick); ``ratio_to_sgbm_covering`` over ``cv_sgbm_covering``'s (its record gives
``disparities``; None where it was skipped).
``ratio_to_floor`` is a case's median over ``floor_blur3``'s; ``ratio_to_nf_edges``
over ``nf_edges``'s (for ``nf_stream_frame``: streaming cost per frame ÷ from scratch).
The fast path runs on the fused numba kernels when numba is installed (the
environment record says which backend ran). ``threads`` sets
``cv2.setNumThreads``; static stereo's cost volume and the edge fast path
(one triple and streaming) run on that many threads (their defaults follow
``cv2.getNumThreads()``).

Peak memory is measured with :mod:`tracemalloc` in a separate, untimed call:
it counts every NumPy array (including the arrays OpenCV returns, which
NumPy allocates) and Python objects, not OpenCV's internal scratch buffers.
The nfdepth fast path's cached workspace is dropped first so that it counts.
For ``nf_stream_frame`` the peak is that of a new stream over five pushes: it
includes everything the stream retains (smoothed-frame ring, workspace, output
pool). ``bytes_per_px`` is the peak divided by the pixels of one frame;
``bytes_per_px_per_frame_held`` divides by three frames (a triple's inputs, the
stream's ring).
"""

from __future__ import annotations

import json
import os
import platform
import time
import tracemalloc
import warnings
from pathlib import Path

import cv2
import numpy as np

from ._validate import check_int, check_positive_or_inf
from .io import atomic_write

__all__ = ["DEFAULT_SIZES", "run_benchmarks", "render_markdown", "bench_main", "check_bench_threads"]

DEFAULT_SIZES = ((480, 640), (960, 1280), (1920, 2560))
SIGMA_PX = 2.0
_ART_HINT = "set NFDEPTH_DATA to the data folder, or download it with `nfdepth fetch-data --set middlebury2005`"


def _art_views() -> list[Path] | str:
    """The Art views 0..6 under the data root that ``nfdepth evaluate`` finds (:func:`nfdepth.datasets.data_root`), or why there are none."""
    from .datasets import DataNotFoundError, data_root

    try:
        root = data_root() / "middlebury2005" / "Art"
    except DataNotFoundError as exc:  # its own reason: NFDEPTH_DATA set to a missing folder is not NFDEPTH_DATA unset
        return f"the Middlebury 2005 Art views were not found ({_ART_HINT}; {exc})"
    paths = [root / f"view{i}.png" for i in range(7)]
    if not all(p.is_file() for p in paths):
        return f"the Middlebury 2005 Art views were not found in '{root}' ({_ART_HINT})"
    return paths


# ------------------------------------------------------------------ scenes


def _rendered(shape, n=3, shift=0.8, seed=0):
    """A rendered-like scene: smoothed random regions moving by sub-pixel steps."""
    H, W = shape
    rng = np.random.default_rng(seed)
    pad = 16
    small = rng.random(((H + 2 * pad) // 8 + 1, (W + 2 * pad) // 8 + 1)).astype(np.float32)
    base = cv2.resize(small, (W + 2 * pad, H + 2 * pad), interpolation=cv2.INTER_CUBIC)
    base = np.where(base > 0.5, 200.0, 60.0).astype(np.float32)
    base = cv2.GaussianBlur(base, (0, 0), 1.0)
    frames = []
    for k in range(n):
        t = k - (n - 1) / 2
        # content moves toward -col from frame to frame: a camera moving toward +X
        M = np.float32([[1, 0, -shift * t], [0, 1, 0]])
        warped = cv2.warpAffine(base, M, (W + 2 * pad, H + 2 * pad), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        frames.append(np.ascontiguousarray(warped[pad : pad + H, pad : pad + W]))
    return frames


def _middlebury(shape):
    """Art views 2..4 scaled to cover ``shape`` and centre-cropped (grey float32), or None (:func:`_art_problem` says why)."""
    paths = _art_views()
    if isinstance(paths, str):
        return None
    H, W = shape
    out = []
    for p in paths[2:5]:  # three neighbouring views
        img = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
        if img is None:
            return None
        s = max(H / img.shape[0], W / img.shape[1])
        size = (max(W, int(round(img.shape[1] * s))), max(H, int(round(img.shape[0] * s))))
        img = cv2.resize(img, size, interpolation=cv2.INTER_CUBIC if s > 1 else cv2.INTER_AREA)
        r0, c0 = (img.shape[0] - H) // 2, (img.shape[1] - W) // 2
        out.append(np.ascontiguousarray(img[r0 : r0 + H, c0 : c0 + W]).astype(np.float32))
    return out


def _art_problem() -> str:
    """Why :func:`_middlebury` gave no views: not found (where, or the data root's own error), or not readable."""
    paths = _art_views()
    if isinstance(paths, str):
        return paths
    return f"the Middlebury 2005 Art views in '{paths[0].parent}' could not be read as images (are the files intact?)"


# ------------------------------------------------------------------- cases


def _cases(frames, *, include_reference: bool, include_stereo: bool = True):
    from . import fast
    from .edges import select_edge_points
    from .normal_flow import gaussian_smooth, normal_flow

    f32 = frames
    u8 = [np.clip(f, 0, 255).astype(np.uint8) for f in frames]
    radius = max(1, int(np.ceil(4.0 * SIGMA_PX)))
    ks = (2 * radius + 1, 2 * radius + 1)
    cases = {}

    cases["nf_edges"] = lambda: fast.normal_flow_edges(f32, sigma_px=SIGMA_PX)

    if include_reference:

        def reference():
            g = normal_flow(f32, sigma_px=SIGMA_PX)
            return select_edge_points(g, gaussian_smooth(f32[1], sigma_px=SIGMA_PX), corner_window_px=max(SIGMA_PX, 1.0))

        cases["nf_edges_reference"] = reference

    stream = fast.StreamingNormalFlow(sigma_px=SIGMA_PX)
    for f in f32[:2]:
        stream.push(f)
    counter = [0]

    def stream_push():
        counter[0] += 1
        return stream.push(f32[counter[0] % 3])

    cases["nf_stream_frame"] = stream_push

    covering = None  # SGBM's disparities for this scene, from static stereo's map
    if not include_stereo:
        cases["nf_static_stereo"] = "skipped: quick mode runs it at the smallest size only"
        cases["nf_static_stereo_edges"] = cases["nf_static_stereo"]
    else:
        try:
            from .stereo import static_stereo

            probe = static_stereo(f32, reference=1).disparity  # probe once (also warms up)
            cases["nf_static_stereo"] = lambda: static_stereo(f32, reference=1)
            cases["nf_static_stereo_edges"] = lambda: static_stereo(f32, reference=1, edges_only=True)
            if np.isfinite(probe).any():
                covering = 16 * max(1, int(np.ceil((float(np.nanmax(probe)) + 1.0) / 16.0)))
        except Exception as exc:  # noqa: BLE001 - any failure means "skip this case"
            cases["nf_static_stereo"] = f"skipped: {type(exc).__name__}: {exc}"[:200]
            cases["nf_static_stereo_edges"] = cases["nf_static_stereo"]

    sgbm = cv2.StereoSGBM_create(minDisparity=0, numDisparities=64, blockSize=5)
    bm = cv2.StereoBM_create(numDisparities=64, blockSize=15)
    # Views run left to right along +X: the right image of a pair is the later view.
    cases["cv_sgbm"] = lambda: sgbm.compute(u8[0], u8[1])
    if covering is not None and covering < u8[0].shape[1]:
        sgbm_covering = cv2.StereoSGBM_create(minDisparity=0, numDisparities=covering, blockSize=5)

        def sgbm_covering_case():
            return sgbm_covering.compute(u8[0], u8[1])

        sgbm_covering_case.disparities = covering  # recorded with the case
        cases["cv_sgbm_covering"] = sgbm_covering_case
    else:
        cases["cv_sgbm_covering"] = "skipped: it searches the disparities static stereo found, and static stereo did not run here (or found more than the image width)"
    cases["cv_bm"] = lambda: bm.compute(u8[0], u8[1])
    dis_fast = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_FAST)
    dis_medium = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
    cases["cv_dis_fast"] = lambda: dis_fast.calc(u8[0], u8[1], None)
    cases["cv_dis_medium"] = lambda: dis_medium.calc(u8[0], u8[1], None)
    cases["floor_blur3"] = lambda: [cv2.GaussianBlur(f, ks, SIGMA_PX, sigmaY=SIGMA_PX, borderType=cv2.BORDER_REFLECT) for f in f32]
    cases["floor_copy3"] = lambda: [f.copy() for f in f32]
    return cases


def _peak_bytes(fn) -> int:
    from . import _scratch, fast

    fast._local.ws = None  # count the workspace too
    _scratch.STEREO.forget()  # and static stereo's kept scratch
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        result = fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    del result
    return int(peak)


def _stream_peak_bytes(frames) -> int:
    """Peak traced memory of a new :class:`~nfdepth.fast.StreamingNormalFlow` over five pushes.

    Counts what the stream retains (smoothed-frame ring, workspace, recycled
    output sets) and the transient peak of a push, with one result held by
    the caller while the next is computed.
    """
    from . import fast

    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        stream = fast.StreamingNormalFlow(sigma_px=SIGMA_PX)
        result = None
        for t in range(5):
            result = stream.push(frames[t % len(frames)])
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    del result, stream
    return int(peak)


def check_bench_threads(threads, *, name: str = "threads") -> int:
    """``threads`` for the benchmark: an integer from 1 to this machine's cores (``name`` names it in the messages).

    OpenCV starts as many workers as ``cv2.setNumThreads`` asks for (10**9 ran
    the machine out of processes), and timings on more threads than cores
    measure the scheduler, not the method.
    """
    n = check_int(name, threads, 1)
    cores = max(1, os.cpu_count() or 1)
    if n > cores:
        msg = f"{name} = {n} is more than this machine's {cores} cores (timings on more threads than cores measure the scheduler): expected 1 to {cores}"
        raise ValueError(msg)
    return n


def run_benchmarks(
    *,
    quick: bool = False,
    sizes=None,
    repeats: int | None = None,
    threads: int = 1,
    scenes=("rendered", "middlebury-art"),
    time_budget_s: float | None = None,
) -> list[dict]:
    """Run the benchmark cases; one record (dict) per case, size and scene.

    Parameters
    ----------
    quick : bool
        Fewer sizes (0.3 and 1.2 Mpx), 5 rounds, no reference path and no
        static stereo above 0.35 Mpx.
    sizes : sequence of (rows, cols), optional
        Image sizes; default 0.3, 1.2 and 4.9 Mpx (quick: the first two).
    repeats : int, optional
        Timed rounds per size (default 20; quick 5).
    threads : int
        ``cv2.setNumThreads`` while timing (restored afterwards); at most
        this machine's cores (``os.cpu_count()``).
    time_budget_s : float, optional
        Per size and scene: rounds stop early (but after at least 3) once
        this much time is spent.
    """
    threads = check_bench_threads(threads)
    if sizes is None:
        sizes = DEFAULT_SIZES[:2] if quick else DEFAULT_SIZES
    repeats = (5 if quick else 20) if repeats is None else check_int("repeats", repeats, 1)
    time_budget_s = (8.0 if quick else 60.0) if time_budget_s is None else check_positive_or_inf("time_budget_s", time_budget_s)
    old_threads = cv2.getNumThreads()
    cv2.setNumThreads(int(threads))
    records: list[dict] = []
    missing: set = set()
    try:
        for H, W in sizes:
            H, W = int(H), int(W)
            for scene in scenes:
                frames = _rendered((H, W)) if scene == "rendered" else _middlebury((H, W))
                if frames is None:  # said in the records (and the table), and once as a warning
                    why = f"skipped: {_art_problem()}"
                    records.append({"name": "all cases", "scene": scene, "height": H, "width": W, "megapixels": round(H * W / 1e6, 3), "threads": int(threads), "median_ms": None, "skipped": why})
                    if scene not in missing:
                        missing.add(scene)
                        warnings.warn(f"the {scene} scene is {why}; only the rendered scene is timed", UserWarning, stacklevel=2)
                    continue
                include_reference = H * W <= (0.35e6 if quick else 1.3e6)
                # static stereo takes seconds per call: in quick mode only at the smallest size
                cases = _cases(frames, include_reference=include_reference, include_stereo=include_reference or not quick)
                timed = {k: v for k, v in cases.items() if callable(v)}
                times: dict = {k: [] for k in timed}
                for fn in timed.values():  # warm-up round
                    fn()
                names = list(timed)
                start = time.perf_counter()
                for rnd in range(repeats):
                    order = names[rnd % len(names) :] + names[: rnd % len(names)]
                    for name in order:
                        t0 = time.perf_counter()
                        timed[name]()
                        times[name].append(time.perf_counter() - t0)
                    if rnd >= 2 and time.perf_counter() - start > time_budget_s:
                        break
                med = {k: float(np.median(v)) * 1e3 for k, v in times.items()}
                for name, case in cases.items():
                    rec = {
                        "name": name,
                        "scene": scene,
                        "height": H,
                        "width": W,
                        "megapixels": round(H * W / 1e6, 3),
                        "threads": int(threads),
                    }
                    if not callable(case):
                        rec.update({"median_ms": None, "skipped": case})
                        records.append(rec)
                        continue
                    ms = med[name]
                    # the stream: everything it retains (ring, workspace, output pool) plus a push's peak
                    peak = _stream_peak_bytes(frames) if name == "nf_stream_frame" else _peak_bytes(case)
                    rec.update(
                        {
                            "median_ms": ms,
                            "runs": len(times[name]),
                            "fps": 1e3 / ms if ms > 0 else None,
                            "ns_per_px": ms * 1e6 / (H * W),
                            "peak_bytes": peak,
                            "bytes_per_px": peak / (H * W),
                            # a triple holds 3 frames (the inputs; the stream's ring of 3)
                            "bytes_per_px_per_frame_held": peak / (3 * H * W),
                            "ratio_to_sgbm": ms / med["cv_sgbm"],
                            # against SGBM searching this scene's disparities (None where that case was skipped)
                            "ratio_to_sgbm_covering": ms / med["cv_sgbm_covering"] if "cv_sgbm_covering" in med else None,
                            "ratio_to_floor": ms / med["floor_blur3"],
                            # per-frame cost relative to the same triple from scratch
                            "ratio_to_nf_edges": ms / med["nf_edges"],
                        }
                    )
                    if hasattr(case, "disparities"):
                        rec["disparities"] = case.disparities
                    records.append(rec)
    finally:
        cv2.setNumThreads(old_threads)
    _add_scaling(records)
    return records


def _add_scaling(records):
    """ns/px relative to the smallest size of the same case and scene (1.0 = linear)."""
    base: dict = {}
    for r in sorted(records, key=lambda r: r["height"] * r["width"]):
        if r.get("median_ms") is None:
            continue
        key = (r["name"], r["scene"])
        base.setdefault(key, r["ns_per_px"])
        r["ns_per_px_vs_smallest"] = r["ns_per_px"] / base[key]


def render_markdown(records) -> str:
    """A markdown table of the records."""
    head = "| case | scene | size | Mpx | median ms | fps | ns/px | ns/px vs smallest | peak MB | B/px | × SGBM | × floor | × nf_edges |"
    lines = [head, "|" + "---|" * 13]
    for r in records:
        size = f"{r['width']}×{r['height']}"
        if r.get("median_ms") is None:
            lines.append(f"| {r['name']} | {r['scene']} | {size} | {r['megapixels']:.1f} | {r.get('skipped', 'skipped')} |  |  |  |  |  |  |  |  |")
            continue
        name = f"{r['name']} ({r['disparities']} disparities)" if "disparities" in r else r["name"]
        lines.append(
            f"| {name} | {r['scene']} | {size} | {r['megapixels']:.1f} | {r['median_ms']:.2f} | {r['fps']:.1f} | "
            f"{r['ns_per_px']:.1f} | {r.get('ns_per_px_vs_smallest', 1.0):.2f} | {r['peak_bytes'] / 1e6:.1f} | "
            f"{r['bytes_per_px']:.1f} | {r['ratio_to_sgbm']:.3f} | {r['ratio_to_floor']:.2f} | {r['ratio_to_nf_edges']:.2f} |"
        )
    return "\n".join(lines)


def _environment() -> dict:
    from . import fast

    try:
        import numba
    except ImportError:  # pragma: no cover - optional
        numba = None
    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "machine": platform.machine(),
        "processor": platform.processor(),
        "cpu_count": os.cpu_count(),
        "nfdepth_fast_backend": "numba" if fast.USE_NUMBA else "numpy/OpenCV",
        "numba": getattr(numba, "__version__", None),
    }


def bench_main(*, json_path=None, quick: bool = False, threads: int = 1) -> int:
    """Run the benchmarks, print the markdown table, write JSON atomically; return 0."""
    records = run_benchmarks(quick=quick, threads=threads)
    print(render_markdown(records))
    if json_path is not None:
        payload = {"environment": _environment(), "sigma_px": SIGMA_PX, "records": records}
        text = json.dumps(payload, indent=2) + "\n"
        # atomically, with the mode of every other output (umask), replacing an older run's file
        atomic_write(json_path, lambda fh: fh.write(text.encode()), force=True)
    return 0
