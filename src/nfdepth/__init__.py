"""nfdepth: passive ranging from relative normal flow.

Depth from the difference of two normal-flow fields of cameras in known
relative motion (dynamic stereo), or of closely spaced static views, after
"Depth from relative normal flows" (the paper in ``shared/paper``). Equation
numbers in docstrings refer to it.

Camera and motion model (paper eq. 1, 3, 4)
    PinholeCamera, RigidMotion, image_flow, image_flow_px, normal_flow_px,
    relative_normal_flow_coefficients
Normal flow (section 3.1)
    normal_flow, gradients, gaussian_smooth, GradientField, estimate_noise_std
Edge points (section 3.2)
    select_edge_points, EdgeSelection, NoEdgePointsWarning
Depth solvers (eq. 4-6) and fusion
    solve_inverse_depth, depth_x_translation, depth_y_translation,
    depth_z_translation, fuse_inverse_depth, InverseDepth, Reason
Pipelines (sections 2.3, 3.2, 3.3)
    dynamic_stereo, static_stereo_edges, EdgeDepth
Real images: coarse-to-fine multi-view static stereo, dense, uncertainty
    static_stereo, StereoResult, fill_background,
    disparity_range_for_depths; x and y baselines
    together: static_stereo_xy, XYStereoResult; a calibrated row of cameras
    that is not rectified: calibrated_row_depth, CalibratedCamera,
    load_cameras; a row and a column of them: calibrated_grid_depth
    (module ``rectify``)
Files
    read_image, write_array, write_colormap_png, read_pfm, write_pfm,
    write_ply, depth_to_points

Behind the ``nfdepth`` commands (each command is a thin layer over these;
imported on first use, so ``import nfdepth`` stays light):

==========================  ================================================
command                     functions
==========================  ================================================
``nfdepth stereo``          static_stereo; with ``--column``:
                            static_stereo_xy; with ``--rig``: load_rig,
                            stereo_options_from_rig; with ``--cameras``:
                            load_cameras, calibrated_row_depth (and
                            ``--column``: calibrated_grid_depth)
``nfdepth dynamic I1..I5``  load_rig, dynamic_stereo_from_rig, edge_depth_maps
``nfdepth dynamic``         load_rig, read_video, dynamic_stereo_from_videos
``--moving-video M``        (:class:`CrossingDepth`), interleaved_frames,
``--reference-video R``     write_crossings_npz
``nfdepth video``           load_rig, read_video, depth_from_video
                            (:class:`VideoDepthFrame`), write_video_npz
``nfdepth evaluate``        evaluate_scene, evaluate_dataset,
                            disparity_errors; the peers sgbm_disparity,
                            waxman_sinha_disparity
``nfdepth reproduce``,      run_paper_experiment
``nfdepth demo``
``nfdepth fetch-data``      fetch_data (needs ``pooch``: ``pip install
                            'nfdepth[data]'``), default_data_dir,
                            DataDownloadError
==========================  ================================================

Rig files: Rig, RigError, load_rig (``docs/rig-format.md``).

Real data sets: fetch_data downloads them (checked by SHA-256) into
default_data_dir, where ``datasets.data_root`` finds them.

Sub-modules with more: ``rig``, ``video``, ``evaluate``, ``baselines``,
``experiments``, ``synthetic`` (scenes), ``datasets`` (real data sets),
``fetch`` (downloading them), ``plot`` (figures), ``fast`` (fused fast path,
streaming), ``bench`` (benchmarks).
"""

from typing import TYPE_CHECKING

from .camera import (
    PinholeCamera,
    RigidMotion,
    image_flow,
    image_flow_px,
    normal_flow_px,
    relative_normal_flow_coefficients,
)
from .depth import (
    InverseDepth,
    Reason,
    depth_x_translation,
    depth_y_translation,
    depth_z_translation,
    fuse_inverse_depth,
    solve_inverse_depth,
)
from .edges import EdgeSelection, NoEdgePointsWarning, select_edge_points
from .normal_flow import GradientField, estimate_noise_std, gaussian_smooth, gradients, normal_flow
from .io import depth_to_points, read_image, read_pfm, write_array, write_colormap_png, write_pfm, write_ply
from .pipelines import EdgeDepth, dynamic_stereo, static_stereo_edges
from .stereo import StereoResult, disparity_range_for_depths, fill_background, static_stereo
from .xy_stereo import XYStereoResult, static_stereo_xy

__version__ = "0.1.0"

#: Public names re-exported lazily (PEP 562): name -> sub-module.
_LAZY = {
    "Rig": "rig",
    "RigError": "rig",
    "load_rig": "rig",
    "stereo_options_from_rig": "rig",
    "dynamic_stereo_from_rig": "rig",
    "edge_depth_maps": "rig",
    "read_video": "video",
    "depth_from_video": "video",
    "VideoDepthFrame": "video",
    "write_video_npz": "video",
    "dynamic_stereo_from_videos": "video",
    "interleaved_frames": "video",
    "CrossingDepth": "video",
    "write_crossings_npz": "video",
    "evaluate_scene": "evaluate",
    "evaluate_dataset": "evaluate",
    "disparity_errors": "evaluate",
    "sgbm_disparity": "baselines",
    "waxman_sinha_disparity": "baselines",
    "run_paper_experiment": "experiments",
    "fetch_data": "fetch",
    "default_data_dir": "fetch",
    "DataDownloadError": "fetch",
    "CalibratedCamera": "rectify",
    "calibrated_row_depth": "rectify",
    "calibrated_grid_depth": "rectify",
    "load_cameras": "rectify",
}

if TYPE_CHECKING:  # pragma: no cover - for type checkers and IDEs
    from .baselines import sgbm_disparity, waxman_sinha_disparity
    from .evaluate import disparity_errors, evaluate_dataset, evaluate_scene
    from .experiments import run_paper_experiment
    from .fetch import DataDownloadError, default_data_dir, fetch_data
    from .rectify import CalibratedCamera, calibrated_grid_depth, calibrated_row_depth, load_cameras
    from .rig import Rig, RigError, dynamic_stereo_from_rig, edge_depth_maps, load_rig, stereo_options_from_rig
    from .video import (
        CrossingDepth,
        VideoDepthFrame,
        depth_from_video,
        dynamic_stereo_from_videos,
        interleaved_frames,
        read_video,
        write_crossings_npz,
        write_video_npz,
    )


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'nfdepth' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "PinholeCamera",
    "RigidMotion",
    "image_flow",
    "image_flow_px",
    "normal_flow_px",
    "relative_normal_flow_coefficients",
    "normal_flow",
    "gradients",
    "gaussian_smooth",
    "GradientField",
    "estimate_noise_std",
    "select_edge_points",
    "EdgeSelection",
    "NoEdgePointsWarning",
    "solve_inverse_depth",
    "depth_x_translation",
    "depth_y_translation",
    "depth_z_translation",
    "fuse_inverse_depth",
    "InverseDepth",
    "Reason",
    "dynamic_stereo",
    "static_stereo_edges",
    "EdgeDepth",
    "static_stereo",
    "static_stereo_xy",
    "fill_background",
    "disparity_range_for_depths",
    "XYStereoResult",
    "StereoResult",
    "read_image",
    "write_array",
    "write_colormap_png",
    "read_pfm",
    "write_pfm",
    "write_ply",
    "depth_to_points",
    *_LAZY,
    "__version__",
]
