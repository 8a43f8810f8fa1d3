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
    select_edge_points, EdgeSelection
Depth solvers (eq. 4-6) and fusion
    solve_inverse_depth, depth_x_translation, depth_y_translation,
    depth_z_translation, fuse_inverse_depth, InverseDepth, Reason
Pipelines (sections 2.3, 3.2, 3.3)
    dynamic_stereo, static_stereo_edges, EdgeDepth
Real images: coarse-to-fine multi-view static stereo, dense, uncertainty
    static_stereo, StereoResult
Files
    read_image, write_array, read_pfm, write_pfm, write_ply, depth_to_points

Sub-modules not imported here: ``synthetic`` (scenes), ``experiments`` (the
paper's experiments), ``datasets`` (real data sets), ``plot`` (figures),
``fast`` (fused fast path, streaming), ``bench`` (benchmarks).
"""

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
from .edges import EdgeSelection, select_edge_points
from .normal_flow import GradientField, estimate_noise_std, gaussian_smooth, gradients, normal_flow
from .io import depth_to_points, read_image, read_pfm, write_array, write_pfm, write_ply
from .pipelines import EdgeDepth, dynamic_stereo, static_stereo_edges
from .stereo import StereoResult, static_stereo

__version__ = "0.1.0"

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
    "StereoResult",
    "read_image",
    "write_array",
    "read_pfm",
    "write_pfm",
    "write_ply",
    "depth_to_points",
    "__version__",
]
