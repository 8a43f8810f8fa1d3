"""Robustness: every bad input gets a specific error, never a wrong number.

Library functions: the exact exception type and a fragment of its message
(naming the parameter, the value and what was expected). The command line:
the exit code of ``nfdepth.cli``, one line on stderr, no traceback (``--debug``
shows it). Also: undeterminable points are NaN with a reason code; textureless
input gives an empty result and a warning; interrupted runs leave no file
behind; the same input gives bit-identical output; the per-frame pixel limit
and the memory use of a 4-megapixel triple.
"""

from __future__ import annotations

import os
import pickle
import re
import signal
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_runner import run_cli

import nfdepth as nf
from nfdepth import _validate, fast, io, stereo, synthetic
from nfdepth.cli import main
from nfdepth.depth import Reason
from nfdepth.io import ImageReadError, OutputExistsError, OutputWriteError
from nfdepth.normal_flow import noise_gains

RIGHT = nf.RigidMotion(translation=(-1.0, 0.0, 0.0))
CAM32 = nf.PinholeCamera(100.0, 32, 32)


def _texture(shape=(32, 32), seed=0, shift=0.0):
    """Smooth random texture, shifted ``shift`` px toward -col (camera moving toward +X)."""
    rng = np.random.default_rng(seed)
    h, w = shape
    base = cv2.GaussianBlur(rng.random((h, w + 16)).astype(np.float64), (0, 0), 2.0) * 255.0
    cols = np.arange(w, dtype=np.float64) + shift
    out = np.empty((h, w))
    for r in range(h):
        out[r] = np.interp(cols, np.arange(w + 16), base[r])
    return out


TEX = _texture()
FRAMES5 = [TEX] * 5
VIEWS3 = [TEX] * 3
#: three distinct views of a camera stepping 1 px toward +x (dense stereo warns about identical views)
STEREO3 = [_texture(shift=s) for s in (0.0, 1.0, 2.0)]


# ------------------------------------------------------------------ library


def _call(fn, *args, **kwargs):
    return lambda: fn(*args, **kwargs)


BAD_LIBRARY_CALLS = [
    # camera: zero, negative, NaN, inf, non-numeric focal length; bad sizes
    ("focal 0", _call(nf.PinholeCamera, 0, 32, 32), ValueError, "focal_px must be a positive finite number, got 0"),
    ("focal -1", _call(nf.PinholeCamera, -1.0, 32, 32), ValueError, "focal_px must be a positive finite number, got -1.0"),
    ("focal nan", _call(nf.PinholeCamera, float("nan"), 32, 32), ValueError, "focal_px must be a positive finite number, got nan"),
    ("focal inf", _call(nf.PinholeCamera, float("inf"), 32, 32), ValueError, "focal_px must be a positive finite number, got inf"),
    ("focal str", _call(nf.PinholeCamera, "f", 32, 32), TypeError, "focal_px must be a positive finite number, got 'f'"),
    ("width 0", _call(nf.PinholeCamera, 1.0, 0, 32), ValueError, "width_px must be a positive integer, got 0"),
    ("width float", _call(nf.PinholeCamera, 1.0, 2.5, 32), ValueError, "width_px must be a positive integer, got 2.5"),
    ("width bool", _call(nf.PinholeCamera, 1.0, True, 32), ValueError, "width_px must be a positive integer, got True"),
    ("cx nan", _call(nf.PinholeCamera, 1.0, 4, 4, cx_px=float("nan")), ValueError, "cx_px must be a finite number (pixels), got nan"),
    ("cy str", _call(nf.PinholeCamera, 1.0, 4, 4, cy_px="c"), TypeError, "cy_px must be a finite number (pixels), got 'c'"),
    # motion
    ("motion len 2", _call(nf.RigidMotion, (1.0, 2.0)), ValueError, "translation must have shape (3,), got shape (2,)"),
    ("motion nan", _call(nf.RigidMotion, (0.0, 0.0, 0.0), (0.0, np.nan, 0.0)), ValueError, "rotation must be finite, got [0.0, nan, 0.0]"),
    ("motion str", _call(nf.RigidMotion, "abc"), TypeError, "translation must be 3 numbers, got 'abc'"),
    # frames: count, shape, dtype, values
    ("nf 1 frame", _call(nf.normal_flow, [TEX]), ValueError, "frames must hold 2 or 3 frames, got 1"),
    ("nf 4 frames", _call(nf.normal_flow, [TEX] * 4), ValueError, "frames must hold 2 or 3 frames, got 4"),
    ("nf no frames", _call(nf.normal_flow, []), ValueError, "frames must hold at least 1 frames, got 0"),
    ("nf shapes", _call(nf.normal_flow, [TEX, TEX, TEX[:-1]]), ValueError, "frames must all have the same shape, got (32, 32), (32, 32), (31, 32)"),
    ("nf nan", _call(nf.normal_flow, [TEX, np.where(TEX > 100, np.nan, TEX), TEX]), ValueError, "frames[1] contains"),
    ("nf inf", _call(nf.normal_flow, [TEX, TEX, np.full((32, 32), np.inf)]), ValueError, "frames[2] contains 1024 non-finite (NaN or inf) pixel(s)"),
    ("nf 1x1", _call(nf.normal_flow, [np.zeros((1, 1))] * 3), ValueError, "frames[0] must be at least 2x2 pixels, got shape (1, 1)"),
    ("nf empty", _call(nf.normal_flow, [np.zeros((0, 5))] * 3), ValueError, "frames[0] must be at least 2x2 pixels, got shape (0, 5)"),
    ("nf colour", _call(nf.normal_flow, [np.zeros((4, 4, 3))] * 3), ValueError, "convert colour to grey first"),
    ("nf rgba", _call(nf.normal_flow, [np.zeros((4, 4, 4))] * 3), ValueError, "must be a 2-D grey image (rows, cols), got shape (4, 4, 4)"),
    ("nf 1-D", _call(nf.normal_flow, np.zeros((3, 4))), ValueError, "array of shape (N, rows, cols), got shape (3, 4)"),
    ("nf str", _call(nf.normal_flow, "frames"), TypeError, "frames must be a sequence of 2-D arrays, got str"),
    ("nf complex", _call(nf.normal_flow, [np.zeros((4, 4), complex)] * 3), TypeError, "frames[0] must be real, got complex dtype complex128"),
    ("nf object", _call(nf.normal_flow, [np.array([[None, 1], [2, 3]])] * 3), TypeError, "frames[0] must be a numeric 2-D array, got dtype object"),
    ("nf text", _call(nf.normal_flow, [np.array([["a", "b"], ["c", "d"]])] * 3), TypeError, "got dtype <U1"),
    ("nf float32 overflow", _call(nf.normal_flow, [np.full((4, 4), 1e300)] * 3), ValueError, "beyond the float32 range"),
    ("nf sigma", _call(nf.normal_flow, VIEWS3, sigma_px=-1.0), ValueError, "sigma_px must be a finite number >= 0, got -1.0"),
    ("nf interval", _call(nf.normal_flow, VIEWS3, frame_interval=0), ValueError, "frame_interval must be a positive finite number, got 0"),
    ("nf stencil", _call(nf.normal_flow, VIEWS3, stencil="sobel"), ValueError, "stencil must be one of ('matched', 'simpson', 'paper'), got 'sobel'"),
    ("nf dtype", _call(nf.normal_flow, VIEWS3, dtype=np.int32), ValueError, "dtype=int32 is not supported; use float32 or float64"),
    ("gradients shapes", _call(nf.gradients, [TEX, TEX, TEX[:, :-1]]), ValueError, "smoothed_frames must be 2-D arrays of one shape"),
    ("gradients 4", _call(nf.gradients, [TEX] * 4), ValueError, "gradients need 2 or 3 frames, got 4"),
    ("gradients type", _call(nf.gradients, 3), TypeError, "smoothed_frames must be a sequence of 2 or 3 2-D arrays, got int"),
    ("noise 2x2", _call(nf.estimate_noise_std, np.zeros((2, 2))), ValueError, "image must be 2-D and at least 3x3, got shape (2, 2)"),
    ("noise nan", _call(nf.estimate_noise_std, np.full((5, 5), np.nan)), ValueError, "image contains 25 non-finite"),
    # depth solvers
    ("solve camera", _call(nf.solve_inverse_depth, [1.0], camera=None, rows=[1.0], cols=[1.0], alpha=[0.0], relative_motion=RIGHT), TypeError, "camera must be a nfdepth.PinholeCamera, got NoneType"),
    ("solve motion", _call(nf.solve_inverse_depth, [1.0], camera=CAM32, rows=[1.0], cols=[1.0], alpha=[0.0], relative_motion=(1, 0, 0)), TypeError, "relative_motion must be a nfdepth.RigidMotion (e.g. RigidMotion.camera_translation((1, 0, 0))), got tuple"),
    ("solve min_cos", _call(nf.solve_inverse_depth, [1.0], camera=CAM32, rows=[1.0], cols=[1.0], alpha=[0.0], relative_motion=RIGHT, min_cos=2), ValueError, "min_cos must be within [0, 1], got 2"),
    ("solve min_cos neg", _call(nf.solve_inverse_depth, [1.0], camera=CAM32, rows=[1.0], cols=[1.0], alpha=[0.0], relative_motion=RIGHT, min_cos=-0.1), ValueError, "min_cos must be within [0, 1], got -0.1"),
    ("solve max_rel_std no std", _call(nf.solve_inverse_depth, [1.0], camera=CAM32, rows=[1.0], cols=[1.0], alpha=[0.0], relative_motion=RIGHT, max_rel_std=0.1), ValueError, "max_rel_std needs delta_vn_std"),
    ("x zero baseline", _call(nf.depth_x_translation, [1.0], [0.0], focal_px=100.0, delta_vx=0.0), ValueError, "delta_vx must be a non-zero finite translation, got 0.0"),
    ("x focal 0", _call(nf.depth_x_translation, [1.0], [0.0], focal_px=0.0, delta_vx=1.0), ValueError, "focal_px must be a positive finite number, got 0.0"),
    ("y nan", _call(nf.depth_y_translation, [1.0], [0.0], focal_px=1.0, delta_vy=np.nan), ValueError, "delta_vy must be a non-zero finite translation, got nan"),
    ("z str", _call(nf.depth_z_translation, [1.0], [0.0], camera=CAM32, rows=[1], cols=[1], delta_vz="v"), TypeError, "delta_vz must be a non-zero finite translation, got 'v'"),
    # pipelines
    ("dyn 4 frames", _call(nf.dynamic_stereo, [TEX] * 4, camera=CAM32, relative_motion=RIGHT), ValueError, "frames must hold exactly 5 frames, got 4"),
    ("dyn 6 frames", _call(nf.dynamic_stereo, [TEX] * 6, camera=CAM32, relative_motion=RIGHT), ValueError, "frames must hold exactly 5 frames, got 6"),
    ("dyn camera size", _call(nf.dynamic_stereo, FRAMES5, camera=nf.PinholeCamera(100.0, 16, 32), relative_motion=RIGHT), ValueError, "camera image size (32, 16) (rows, cols) does not match the frames' shape (32, 32)"),
    ("dyn camera type", _call(nf.dynamic_stereo, FRAMES5, camera="cam", relative_motion=RIGHT), TypeError, "camera must be a nfdepth.PinholeCamera, got str"),
    ("dyn motion type", _call(nf.dynamic_stereo, FRAMES5, camera=CAM32, relative_motion=(1.0, 0.0, 0.0)), TypeError, "relative_motion must be a nfdepth.RigidMotion (e.g. RigidMotion.camera_translation((1, 0, 0))), got tuple"),
    ("dyn pure rotation", _call(nf.dynamic_stereo, FRAMES5, camera=CAM32, relative_motion=nf.RigidMotion(rotation=(0.0, 0.0, 0.01))), ValueError, "relative_motion has no translation"),
    ("dyn interval", _call(nf.dynamic_stereo, FRAMES5, camera=CAM32, relative_motion=RIGHT, frame_interval=-1.0), ValueError, "frame_interval must be a positive finite number, got -1.0"),
    ("dyn noise", _call(nf.dynamic_stereo, FRAMES5, camera=CAM32, relative_motion=RIGHT, noise_std=-1.0), ValueError, "noise_std must be a finite number >= 0, got -1.0"),
    ("dyn 2x2", _call(nf.dynamic_stereo, [np.zeros((2, 2))] * 5, camera=nf.PinholeCamera(1.0, 2, 2), relative_motion=RIGHT), ValueError, "frames must be at least 3x3 pixels, got shape (2, 2)"),
    ("static 2 views", _call(nf.static_stereo_edges, [TEX] * 2, camera=CAM32, baseline=1.0), ValueError, "views must hold at least 3 frames, got 2"),
    ("static baseline 0", _call(nf.static_stereo_edges, VIEWS3, camera=CAM32, baseline=0.0), ValueError, "baseline must be a positive finite number, got 0.0"),
    ("static baseline neg", _call(nf.static_stereo_edges, VIEWS3, camera=CAM32, baseline=-2.0), ValueError, "baseline must be a positive finite number, got -2.0"),
    ("static direction", _call(nf.static_stereo_edges, VIEWS3, camera=CAM32, baseline=1.0, direction=(0, 0, 0)), ValueError, "direction must be 3 finite numbers, not all zero, got [0.0, 0.0, 0.0]"),
    ("static reference 0", _call(nf.static_stereo_edges, VIEWS3, camera=CAM32, baseline=1.0, reference=0), ValueError, "reference must index a view with a neighbour on each side (1..1), got 0"),
    ("static reference str", _call(nf.static_stereo_edges, VIEWS3, camera=CAM32, baseline=1.0, reference="1"), TypeError, "reference must be an int view index (1..1) or None, got '1'"),
    ("static max_span", _call(nf.static_stereo_edges, VIEWS3, camera=CAM32, baseline=1.0, max_span=0), ValueError, "max_span must be >= 1, got 0"),
    ("static colour", _call(nf.static_stereo_edges, [np.zeros((32, 32, 3))] * 3, camera=CAM32, baseline=1.0), ValueError, "views[0] must be a 2-D grey image"),
    # edge points
    ("edges field", _call(nf.select_edge_points, "field", TEX), TypeError, "field must be a nfdepth.GradientField (from normal_flow), got str"),
    ("edges shape", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX[:-1]), ValueError, "smoothed_middle must have shape (32, 32), got (31, 32)"),
    ("edges corner", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX, max_corner_ratio=np.nan), ValueError, "max_corner_ratio must be within [0, 1], got nan"),
    ("edges corner str", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX, max_corner_ratio="x"), TypeError, "max_corner_ratio must be a number within [0, 1], got 'x'"),
    ("edges corner window", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX, corner_window_px=0), ValueError, "corner_window_px must be a positive finite number, got 0"),
    ("dyn corner str", _call(nf.dynamic_stereo, FRAMES5, camera=CAM32, relative_motion=RIGHT, max_corner_ratio="x"), TypeError, "max_corner_ratio must be a number within [0, 1], got 'x'"),
    ("edges gradient", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX, min_gradient=-1.0), ValueError, "min_gradient must be a finite number >= 0, got -1.0"),
    ("edges border", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX, border_px=-1), ValueError, "border_px must be an integer >= 0, got -1"),
    # dense stereo (public API)
    ("stereo 1 view", _call(stereo.static_stereo, [TEX], reference=0), ValueError, "views must hold at least 2 frames, got 1"),
    ("stereo reference", _call(stereo.static_stereo, STEREO3, reference=3), ValueError, "reference must be a view index in 0..2, got 3"),
    ("stereo reference bool", _call(stereo.static_stereo, STEREO3, reference=True), TypeError, "reference must be an int view index, got True"),
    ("stereo wrong order", _call(stereo.static_stereo, STEREO3, reference=1, positions=[2, 1, 0]), ValueError, "positions must be strictly increasing"),
    ("stereo positions len", _call(stereo.static_stereo, STEREO3, reference=1, positions=[0, 1]), ValueError, "positions must hold one number per view (3), got shape (2,)"),
    ("stereo positions nan", _call(stereo.static_stereo, STEREO3, reference=1, positions=[0, 1, np.nan]), ValueError, "positions must be finite"),
    ("stereo axis", _call(stereo.static_stereo, STEREO3, reference=1, axis="z"), ValueError, "axis must be 'x' or 'y', got 'z'"),
    ("stereo threads", _call(stereo.static_stereo, STEREO3, reference=1, threads=0), ValueError, "threads must be an integer >= 1, got 0"),
    ("stereo threads float", _call(stereo.static_stereo, STEREO3, reference=1, threads=1.5), TypeError, "threads must be an integer >= 1, got 1.5"),
    ("stereo cost step", _call(stereo.static_stereo, STEREO3, reference=1, cost_step_px=0.0), ValueError, "cost_step_px must be a positive finite number, got 0.0"),
    ("stereo cost step nan", _call(stereo.static_stereo, STEREO3, reference=1, cost_step_px=np.nan), ValueError, "cost_step_px must be a positive finite number, got nan"),
    ("stereo cost radius", _call(stereo.static_stereo, STEREO3, reference=1, cost_radius=0), ValueError, "cost_radius must be an integer >= 1, got 0"),
    ("stereo cost radius float", _call(stereo.static_stereo, STEREO3, reference=1, cost_radius=2.5), TypeError, "cost_radius must be an integer >= 1, got 2.5"),
    ("stereo cost alpha", _call(stereo.static_stereo, STEREO3, reference=1, cost_alpha=2), ValueError, "cost_alpha must be within [0, 1], got 2"),
    ("stereo cost tau", _call(stereo.static_stereo, STEREO3, reference=1, cost_tau_i=0.0), ValueError, "cost_tau_i must be a positive finite number, got 0.0"),
    ("stereo cost eps", _call(stereo.static_stereo, STEREO3, reference=1, cost_eps=-1e-4), ValueError, "cost_eps must be a positive finite number, got -0.0001"),
    ("stereo cost median", _call(stereo.static_stereo, STEREO3, reference=1, cost_median_px=4), ValueError, "cost_median_px must be 0, 1, 3 or 5, got 4"),
    ("stereo cost margin", _call(stereo.static_stereo, STEREO3, reference=1, min_cost_margin=-1), ValueError, "min_cost_margin must be a finite number >= 0, got -1"),
    ("stereo edge step", _call(stereo.static_stereo, STEREO3, reference=1, edge_step_px=-1), ValueError, "edge_step_px must be a finite number >= 0, got -1"),
    ("stereo disagreement", _call(stereo.static_stereo, STEREO3, reference=1, max_edge_disagreement_px=0), ValueError, "max_edge_disagreement_px must be a number > 0 (inf: no limit), got 0"),
    ("stereo edge std nan", _call(stereo.static_stereo, STEREO3, reference=1, max_edge_std_px=float("nan")), ValueError, "max_edge_std_px must be a number > 0 (inf: no limit), got nan"),
    ("stereo edge std str", _call(stereo.static_stereo, STEREO3, reference=1, max_edge_std_px="wide"), TypeError, "max_edge_std_px must be a number > 0 (inf: no limit), got 'wide'"),
    ("stereo iterations", _call(stereo.static_stereo, STEREO3, reference=1, iterations_per_level=2.5), TypeError, "iterations_per_level must be an integer >= 1, got 2.5"),
    ("stereo edge iterations", _call(stereo.static_stereo, STEREO3, reference=1, edge_iterations=-1), ValueError, "edge_iterations must be an integer >= 0, got -1"),
    ("stereo schedule", _call(stereo.static_stereo, STEREO3, reference=1, view_schedule="yes"), TypeError, "view_schedule must be True or False, got 'yes'"),
    ("stereo guided eps", _call(stereo.static_stereo, STEREO3, reference=1, guided_eps=-1.0), ValueError, "guided_eps must be a positive finite number, got -1.0"),
    ("stereo polish radius", _call(stereo.static_stereo, STEREO3, reference=1, polish_radius=0), ValueError, "polish_radius must be an integer >= 1, got 0"),
    ("stereo select window", _call(stereo.static_stereo, STEREO3, reference=1, select_window_px=0), ValueError, "select_window_px must be a positive finite number, got 0"),
    ("stereo min_cos", _call(stereo.static_stereo, STEREO3, reference=1, min_cos=2), ValueError, "min_cos must be within [0, 1], got 2"),
    ("stereo corner ratio", _call(stereo.static_stereo, STEREO3, reference=1, max_corner_ratio=-0.1), ValueError, "max_corner_ratio must be within [0, 1], got -0.1"),
    ("stereo levels", _call(stereo.static_stereo, STEREO3, reference=1, levels=99), ValueError, "levels must be >= 1 and leave at least 4 px at the coarsest level, got 99"),
    # thresholds and ridges meet float32 maps; counts are passes over the image
    ("edges gradient huge", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX, min_gradient=1e300), ValueError, "min_gradient = 1e+300 is beyond the float32 maps it applies to: expected at most 1e+30"),
    ("edges relative huge", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX, relative_gradient=1e300), ValueError, "relative_gradient = 1e+300 is beyond the float32 maps"),
    ("fast gradient huge", _call(fast.normal_flow_edges, VIEWS3, sigma_px=1.0, min_gradient=1e300), ValueError, "min_gradient = 1e+300 is beyond the float32 maps"),
    ("fast relative huge", _call(fast.normal_flow_edges, VIEWS3, sigma_px=1.0, relative_gradient=1e300), ValueError, "relative_gradient = 1e+300 is beyond the float32 maps"),
    ("noise gains frames", _call(noise_gains, sigma_px=2.0, n_frames=5), ValueError, "n_frames must be 2 (the two-image variant) or 3 (a triple), got 5"),
    ("noise gains frames bool", _call(noise_gains, sigma_px=2.0, n_frames=True), TypeError, "n_frames must be an integer >= 2, got True (bool, not a number)"),
    ("dyn noise huge", _call(nf.dynamic_stereo, FRAMES5, camera=CAM32, relative_motion=RIGHT, noise_std=1e300), ValueError, "noise_std = 1e+300 is beyond any image's intensities: expected at most 1e+30"),
    ("dyn interval huge", _call(nf.dynamic_stereo, FRAMES5, camera=CAM32, relative_motion=RIGHT, frame_interval=1e30), ValueError, "frame_interval = 1e+30 is outside 1e-30..5e+29 (the moving camera's frames 1, 3, 5 are two intervals apart)"),
    ("static noise huge", _call(nf.static_stereo_edges, VIEWS3, camera=CAM32, baseline=1.0, noise_std=1e300), ValueError, "noise_std = 1e+300 is beyond any image's intensities"),
    ("static baseline huge", _call(nf.static_stereo_edges, VIEWS3, camera=CAM32, baseline=1e300), ValueError, "baseline = 1e+300 is outside 1e-30..1e+30: give it in a unit that keeps it there"),
    ("static baseline tiny", _call(nf.static_stereo_edges, VIEWS3, camera=CAM32, baseline=1e-300), ValueError, "baseline = 1e-300 is outside 1e-30..1e+30"),
    ("stereo gradient huge", _call(stereo.static_stereo, STEREO3, reference=1, min_gradient=1e300), ValueError, "min_gradient = 1e+300 is beyond the float32 maps it applies to: expected at most 1e+30"),
    ("stereo std huge", _call(stereo.static_stereo, STEREO3, reference=1, max_std_px=1e39), ValueError, "max_std_px = 1e+39 is beyond the float32 maps it applies to: expected at most 1e+30"),
    ("stereo edge std huge", _call(stereo.static_stereo, STEREO3, reference=1, max_edge_std_px=1e300), ValueError, "max_edge_std_px = 1e+300 is beyond the float32 maps it applies to: expected at most 1e+30; give inf for no limit"),
    ("stereo guided eps huge", _call(stereo.static_stereo, STEREO3, reference=1, guided_eps=1e300), ValueError, "guided_eps = 1e+300 is beyond the float32 maps"),
    ("stereo cost eps huge", _call(stereo.static_stereo, STEREO3, reference=1, cost_eps=1e300), ValueError, "cost_eps = 1e+300 is beyond the float32 maps"),
    ("stereo cost tau huge", _call(stereo.static_stereo, STEREO3, reference=1, cost_tau_g=1e300), ValueError, "cost_tau_g = 1e+300 is beyond the float32 maps"),
    ("stereo margin huge", _call(stereo.static_stereo, STEREO3, reference=1, edge_cost_margin=1e300), ValueError, "edge_cost_margin = 1e+300 is beyond the float32 maps"),
    ("stereo edge step huge", _call(stereo.static_stereo, STEREO3, reference=1, edge_step_px=1e300), ValueError, "edge_step_px = 1e+300 is beyond the float32 maps"),
    ("stereo iterations huge", _call(stereo.static_stereo, STEREO3, reference=1, iterations_per_level=10**9), ValueError, "iterations_per_level = 1000000000 is more iterations than can help (each is a pass over the image; a few suffice): expected 1 to 1000"),
    ("stereo rounds huge", _call(stereo.static_stereo, STEREO3, reference=1, propagate_rounds=1001), ValueError, "propagate_rounds = 1001 is more iterations than can help"),
    ("stereo polish huge", _call(stereo.static_stereo, STEREO3, reference=1, polish_iterations=10**6), ValueError, "polish_iterations = 1000000 is more iterations than can help"),
    ("stereo edge iterations huge", _call(stereo.static_stereo, STEREO3, reference=1, edge_iterations=10**9), ValueError, "edge_iterations = 1000000000 is more iterations than can help"),
    ("stereo nan pixel", _call(stereo.static_stereo, [TEX, TEX, np.full((32, 32), np.nan)], reference=1), ValueError, "views[2] contains 1024 non-finite"),
    ("stereo depth focal", _call(lambda: stereo.static_stereo(STEREO3, reference=1).depth(focal_px=0.0, baseline=1.0)), ValueError, "focal_px must be a positive finite number, got 0.0"),
    ("stereo depth baseline", _call(lambda: stereo.static_stereo(STEREO3, reference=1).depth(focal_px=1.0, baseline=0.0)), ValueError, "baseline must be a positive finite number, got 0.0"),
    # synthetic scenes
    ("synthetic size", _call(synthetic.paper_camera, image_size_px=0), ValueError, "image_size_px must be an integer >= 2, got 0"),
    ("synthetic views", _call(synthetic.paper_static_sequence, n_views=1), ValueError, "n_views must be an integer >= 2, got 1"),
    ("synthetic noise", _call(synthetic.paper_static_sequence, noise_std=-1.0), ValueError, "noise_std must be a finite number >= 0, got -1.0"),
    ("synthetic rng", _call(synthetic.paper_static_sequence, noise_std=1.0, rng=5), TypeError, "rng must be a numpy.random.Generator, got int"),
    ("synthetic experiment", _call(synthetic.paper_dynamic_sequence, 7), ValueError, "experiment must be one of [1, 2, 3, 4], got 7"),
    ("synthetic huge", _call(synthetic.paper_static_sequence, image_size_px=10**6), _validate.ImageTooLargeError, "above the limit of 40 megapixels"),
    # writers
    ("write ext", _call(io.write_array, "out.png", np.zeros((2, 2))), ValueError, "path must end in one of .pfm, .tif, .tiff, .npy, got 'out.png'"),
    ("write 3-D", _call(io.write_array, "out.pfm", np.zeros((2, 2, 2))), ValueError, "array must be a non-empty array of shape (H, W), got shape (2, 2, 2)"),
    ("write empty", _call(io.write_array, "out.pfm", np.zeros((0, 3))), ValueError, "got shape (0, 3)"),
    ("to_grey shape", _call(io.to_grey, np.zeros((2, 2, 5))), ValueError, "with C in 1..4, got shape (2, 2, 5)"),
    ("points focal", _call(io.depth_to_points, np.ones((2, 2)), focal_px=-5.0), ValueError, "focal_px must be a positive finite number, got -5.0"),
]


@pytest.mark.parametrize(("fn", "exc", "fragment"), [c[1:] for c in BAD_LIBRARY_CALLS], ids=[c[0] for c in BAD_LIBRARY_CALLS])
def test_library_rejects_bad_input(fn, exc, fragment):
    with pytest.raises(exc) as info:
        fn()
    assert fragment in str(info.value)
    assert type(info.value) is exc  # the documented type itself, not a subclass


#: Numbers given as text, bools or fractions where an integer is expected:
#: refused with the whole message (float('2') and int(2.5) would accept them).
NOT_NUMBERS = [
    ("stereo sigma str", _call(nf.static_stereo, STEREO3, reference=1, sigma_px="2"), "sigma_px must be a finite number >= 0, got '2' (str, not a number)"),
    ("stereo sigma bytes", _call(nf.static_stereo, STEREO3, reference=1, sigma_px=b"2"), "sigma_px must be a finite number >= 0, got b'2' (bytes, not a number)"),
    ("stereo sigma bool", _call(nf.static_stereo, STEREO3, reference=1, sigma_px=True), "sigma_px must be a finite number >= 0, got True (bool, not a number)"),
    ("stereo sigma 0-d str", _call(nf.static_stereo, STEREO3, reference=1, sigma_px=np.array("2")), "sigma_px must be a finite number >= 0, got array('2', dtype='<U1') (str, not a number)"),
    ("stereo cost alpha numpy bool", _call(nf.static_stereo, STEREO3, reference=1, cost_alpha=np.True_), "cost_alpha must be a number within [0, 1], got np.True_ (bool, not a number)"),
    ("stereo reach complex", _call(nf.static_stereo, STEREO3, reference=1, dense_reach_px=1j), "dense_reach_px must be a number >= 0 (inf: no limit), got 1j (complex, not a real number)"),
    ("stereo iterations fraction", _call(nf.static_stereo, STEREO3, reference=1, iterations_per_level=2.5), "iterations_per_level must be an integer >= 1, got 2.5 (not a whole number)"),
    ("stereo iterations integral float", _call(nf.static_stereo, STEREO3, reference=1, iterations_per_level=2.0), "iterations_per_level must be an integer >= 1, got 2.0 (float; give an int such as 2)"),
    ("stereo rounds bool", _call(nf.static_stereo, STEREO3, reference=1, propagate_rounds=True), "propagate_rounds must be an integer >= 0, got True (bool, not a number)"),
    ("stereo threads str", _call(nf.static_stereo, STEREO3, reference=1, threads="2"), "threads must be an integer >= 1, got '2' (str, not a number)"),
    ("stereo reference float", _call(nf.static_stereo, STEREO3, reference=1.0), "reference must be an int view index, got 1.0 (float; give an int such as 1)"),
    ("nf sigma str", _call(nf.normal_flow, VIEWS3, sigma_px="1.5"), "sigma_px must be a finite number >= 0, got '1.5' (str, not a number)"),
    ("nf interval bool", _call(nf.normal_flow, VIEWS3, frame_interval=True), "frame_interval must be a positive finite number, got True (bool, not a number)"),
    ("edges border float", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX, border_px=np.float64(3.0)), "border_px must be an integer >= 0, got np.float64(3.0) (float; give an int such as 3)"),
    ("edges gradient str", _call(nf.select_edge_points, nf.normal_flow(VIEWS3), TEX, min_gradient="5"), "min_gradient must be a finite number >= 0, got '5' (str, not a number)"),
    ("synthetic views fraction", _call(synthetic.paper_static_sequence, n_views=3.5), "n_views must be an integer >= 2, got 3.5 (not a whole number)"),
    ("camera focal str", _call(nf.PinholeCamera, "100", 32, 32), "focal_px must be a positive finite number, got '100' (str, not a number)"),
    ("motion str", _call(nf.RigidMotion, translation=["1", "0", "0"]), "translation must be 3 numbers, got ['1', '0', '0'] (str, not a number)"),
    ("motion bool", _call(nf.RigidMotion, translation=[True, 0, 0]), "translation must be 3 numbers, got [True, 0, 0] (bool, not a number)"),
]


@pytest.mark.parametrize(("fn", "message"), [c[1:] for c in NOT_NUMBERS], ids=[c[0] for c in NOT_NUMBERS])
def test_library_refuses_text_bools_and_fractions_as_numbers(fn, message):
    with pytest.raises(TypeError) as info:
        fn()
    assert str(info.value) == message
    assert type(info.value) is TypeError


def test_numpy_scalars_and_0d_arrays_are_still_numbers():
    """NumPy integer / floating scalars and 0-d numeric arrays pass where Python ints / floats do."""
    views = STEREO3
    options = {"reference": np.int64(1), "sigma_px": np.float32(1.0), "cost_alpha": np.array(0.5), "iterations_per_level": np.int32(2), "threads": np.array(1)}
    got = nf.static_stereo(views, **options)
    want = nf.static_stereo(views, reference=1, sigma_px=1.0, cost_alpha=0.5, iterations_per_level=2, threads=1)
    assert np.count_nonzero(np.isfinite(want.disparity)) > 100
    np.testing.assert_array_equal(got.disparity, want.disparity)
    flow = nf.normal_flow(views, sigma_px=np.float64(1.0), frame_interval=np.int64(2))
    want_flow = nf.normal_flow(views, sigma_px=1.0, frame_interval=2.0)
    assert np.any(want_flow.grad_t != 0)
    np.testing.assert_array_equal(flow.grad_t, want_flow.grad_t)


def test_integer_images_do_not_overflow():
    """uint8/int16 frames are converted before any difference: no wrap-around."""
    r, c = np.mgrid[0:16, 0:16]
    ramp = [np.clip(10 * c + 20 * t, 0, 255) for t in (-1, 0, 1)]  # crosses 255 - 0 in uint8 differences
    as_float = nf.normal_flow([f.astype(np.float64) for f in ramp], sigma_px=0, dtype=np.float64)
    as_uint8 = nf.normal_flow([f.astype(np.uint8) for f in ramp], sigma_px=0, dtype=np.float64)
    np.testing.assert_array_equal(as_uint8.grad_t, as_float.grad_t)
    np.testing.assert_array_equal(as_uint8.grad_col, as_float.grad_col)
    big = [np.full((4, 4), v, np.int16) for v in (-32768, 0, 32767)]
    g = nf.normal_flow(big, sigma_px=0, dtype=np.float64)
    assert np.all(g.grad_t == (32767.0 + 32768.0) / 2.0)
    u16 = [np.full((4, 4), v, np.uint16) for v in (0, 65535, 65535)]
    assert np.all(np.isfinite(nf.normal_flow(u16, sigma_px=0).grad_t))


# ------------------------------------------------------------ no wrong numbers


def test_undeterminable_points_are_nan_with_reason():
    cam = nf.PinholeCamera(100.0, 64, 64)
    rows = np.full(5, 31.5)
    cols = np.full(5, 31.5)
    alpha = np.array([0.0, 0.0, np.pi / 2, 0.0, 0.0])  # third: edge parallel to the x translation, B = 0
    dvn = np.array([1.0, -1.0, 1.0, np.nan, 1e-300])  # second: wrong sign; fourth: no data
    inv = nf.solve_inverse_depth(dvn, camera=cam, rows=rows, cols=cols, alpha=alpha, relative_motion=nf.RigidMotion((1.0, 0.0, 0.0)), delta_vn_std=np.full(5, 0.5), max_rel_std=0.6)
    assert inv.reason.tolist() == [Reason.OK, Reason.NOT_POSITIVE, Reason.UNDETERMINABLE, Reason.NO_DATA, Reason.UNCERTAIN]
    assert np.isfinite(inv.rho[0]) and inv.rho[0] > 0
    assert np.all(np.isnan(inv.rho[1:])) and np.all(np.isnan(inv.depth[1:]))
    rot = nf.solve_inverse_depth(dvn, camera=cam, rows=rows, cols=cols, alpha=alpha, relative_motion=nf.RigidMotion(rotation=(0.0, 0.01, 0.0)))
    assert np.all(rot.reason[np.isfinite(dvn)] == Reason.UNDETERMINABLE) and np.all(np.isnan(rot.rho))
    z = nf.depth_x_translation([1.0, -1.0, 0.0], [0.0, 0.0, 0.0], focal_px=100.0, delta_vx=2.0)
    assert z[0] == 200.0 and np.isnan(z[1]) and np.isnan(z[2])  # behind the camera, at infinity


def test_views_in_the_wrong_order_warn_and_give_no_negative_depth():
    scene = synthetic.paper_static_sequence(n_views=3, image_size_px=120)
    good = nf.static_stereo_edges(scene.frames, camera=scene.camera, baseline=2.0, noise_std=0.0)
    assert good.valid.sum() > 50
    with pytest.warns(UserWarning, match="are the views in the wrong order"):
        bad = nf.static_stereo_edges(scene.frames[::-1], camera=scene.camera, baseline=2.0, noise_std=0.0)
    assert bad.valid.sum() < good.valid.sum() / 4
    assert np.all(bad.depth[bad.valid] > 0)
    assert np.all(np.isnan(bad.depth[~bad.valid]))


def test_dynamic_stereo_with_the_wrong_motion_sign_warns():
    scene = synthetic.paper_dynamic_sequence(1, image_size_px=120)
    with pytest.warns(UserWarning, match="is relative_motion's sign right"):
        res = nf.dynamic_stereo(scene.frames, camera=scene.camera, relative_motion=-scene.relative_motion, noise_std=0.0)
    assert np.all(res.depth[res.valid] > 0)


# ------------------------------------------------------------ textureless input

TEXTURELESS = "no edge points: the images are textureless"


@pytest.mark.parametrize("value", [0.0, 128.0])
def test_constant_frames_give_empty_result_and_warning(value):
    flat = np.full((32, 32), value)
    with pytest.warns(UserWarning, match=TEXTURELESS):
        res = nf.static_stereo_edges([flat] * 3, camera=CAM32, baseline=1.0)
    assert len(res) == 0 and res.depth.shape == (0,)
    with pytest.warns(UserWarning, match=TEXTURELESS):
        res = nf.dynamic_stereo([flat] * 5, camera=CAM32, relative_motion=RIGHT)
    assert len(res) == 0


def test_dense_stereo_on_constant_views_warns():
    flat = np.full((32, 32), 100.0)
    with pytest.warns(UserWarning, match=TEXTURELESS):
        stereo.static_stereo([flat] * 3, reference=1)


def test_dense_stereo_on_constant_views_gives_no_numbers():
    flat = np.full((32, 32), 100.0)
    with pytest.warns(UserWarning, match=TEXTURELESS):
        res = stereo.static_stereo([flat] * 3, reference=1)
    assert not res.edge_mask.any()
    assert not np.isfinite(res.disparity).any() and not np.isfinite(res.uncertainty).any()


def test_dense_stereo_takes_extreme_but_valid_options_quietly():
    """Limits of the expert options: the largest accepted threshold, the smallest window and step, no limit.

    pytest turns warnings into errors here, so NumPy's overflow or division
    warnings (float32 casts of 1e300) would fail these calls.
    """
    for options in ({"max_std_px": 1e30, "guided_eps": 1e30, "cost_eps": 1e30, "edge_step_px": 1e30}, {"max_edge_std_px": np.inf, "max_edge_disagreement_px": np.inf}, {"dense_window_px": 1e-300, "select_window_px": 1e-300}):
        res = stereo.static_stereo(STEREO3, reference=1, **options)
        assert np.isfinite(res.disparity).any(), options
        assert np.all(res.uncertainty[np.isfinite(res.disparity)] > 0), options
    # a step of 1e-300 px is searched at the widest step 512 candidates allow, as the warning says
    with pytest.warns(UserWarning, match=r"holds more than 512 candidates at cost_step_px = 1e-300 px: searched in"):
        res = stereo.static_stereo(STEREO3, reference=1, cost_step_px=1e-300)
    assert np.isfinite(res.disparity).any()
    # a given min_gradient above every edge is named in the warning
    with pytest.warns(UserWarning, match=r"^no edge points: the images are textureless \(no zero crossing reaches the gradient threshold 1e\+30 nor float32 rounding's; lower min_gradient if that is too high\); the dense map is measured without them$"):
        res = stereo.static_stereo(STEREO3, reference=1, min_gradient=1e30)
    assert not res.edge_mask.any() and np.isfinite(res.disparity).any()
    with pytest.warns(UserWarning, match=r"^no edge points: .*; no depth can be measured$"):
        res = stereo.static_stereo(STEREO3, reference=1, min_gradient=1e30, edges_only=True)
    assert not np.isfinite(res.disparity).any()


def test_edge_pipelines_say_which_rule_left_no_edge_points():
    """The warning names the rule that left no edge point, not "textureless" when an option rejected them all."""
    scene = synthetic.paper_dynamic_sequence(1, image_size_px=120)
    run = {"camera": scene.camera, "relative_motion": scene.relative_motion, "noise_std": 0.0}
    with pytest.warns(nf.NoEdgePointsWarning, match=r"^no edge points: all \d+ strong zero crossings in the reference image of shape \(120, 120\) are corners \(raise max_corner_ratio to keep some\); the result is empty$") as said:
        assert len(nf.dynamic_stereo(scene.frames, max_corner_ratio=0.0, **run)) == 0
    # the rule and the message's parts, for a program (nfdepth's video run rewrites the hint from them)
    (w,) = said.list
    assert (w.message.rule, w.message.hint, w.message.consequence) == ("corner", "(raise max_corner_ratio to keep some)", "the result is empty")
    assert re.fullmatch(r"all \d+ strong zero crossings in the reference image of shape \(120, 120\) are corners", w.message.reason)
    assert issubclass(nf.NoEdgePointsWarning, UserWarning)
    with pytest.warns(nf.NoEdgePointsWarning, match=r"^no edge points: the images are textureless \(no zero crossing in the reference image of shape \(120, 120\) reaches the gradient threshold 1e\+30") as said:
        assert len(nf.dynamic_stereo(scene.frames, min_gradient=1e30, **run)) == 0
    assert [w.message.rule for w in said.list] == ["gradient"]
    with pytest.warns(nf.NoEdgePointsWarning) as said:
        nf.static_stereo([np.full((60, 80), 0.5)] * 3, reference=1)
    assert [(w.message.rule, w.message.consequence) for w in said.list] == [("zero crossing", "the dense map is measured without them")]
    # a copy (pickle: a warning sent from a worker process) keeps the attributes
    copied = pickle.loads(pickle.dumps(said.list[0].message))
    assert (type(copied), str(copied), copied.rule, copied.reason) == (nf.NoEdgePointsWarning, str(said.list[0].message), "zero crossing", said.list[0].message.reason)
    from nfdepth.edges import _no_edge_points_warning

    field = nf.normal_flow(scene.frames[1:4], sigma_px=2.0)
    middle = nf.gaussian_smooth(scene.frames[2], sigma_px=2.0)
    inside_only = nf.select_edge_points(field, middle, border_px=60)  # 119 x 119 cells: no cell is 60 from every side
    assert not inside_only.mask.any()
    border = _no_edge_points_warning(inside_only)
    assert str(border).endswith("strong zero crossings all lie within border_px of the border") and border.rule == "border"


def test_edge_pipelines_take_extreme_but_valid_scales():
    """A frame interval of 1e-30 (flows of ~1e30 px per unit time) and a direction of 1e-300 or 1e300 run without NumPy warnings."""
    scene = synthetic.paper_dynamic_sequence(1, image_size_px=120)
    ref = nf.dynamic_stereo(scene.frames, camera=scene.camera, relative_motion=scene.relative_motion, noise_std=0.5)
    fast_clock = nf.dynamic_stereo(scene.frames, camera=scene.camera, relative_motion=scene.relative_motion, noise_std=0.5, frame_interval=1e-30)
    # the same points; a motion per 1e-30 time units is 1e30 times faster, so inverse depth scales by 1e-30
    np.testing.assert_array_equal(fast_clock.rows, ref.rows)
    ok = ref.valid & fast_clock.valid
    assert ok.sum() > 0.9 * ref.valid.sum()
    np.testing.assert_allclose(fast_clock.inverse_depth.rho[ok] * 1e-30, ref.inverse_depth.rho[ok], rtol=1e-4)
    views = synthetic.paper_static_sequence(n_views=3, image_size_px=120)
    along_x = nf.static_stereo_edges(views.frames, camera=views.camera, baseline=2.0, noise_std=0.0)
    for direction in [(1e-300, 0.0, 0.0), (1e300, 0.0, 0.0), (5e-324, 0.0, 0.0)]:
        res = nf.static_stereo_edges(views.frames, camera=views.camera, baseline=2.0, noise_std=0.0, direction=direction)
        np.testing.assert_array_equal(res.depth, along_x.depth)


# ----------------------------------------------------------------- file input


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _png_bytes(array) -> bytes:
    ok, buf = cv2.imencode(".png", array)
    assert ok
    return buf.tobytes()


def test_read_image_errors(tmp_path):
    good = _write(tmp_path / "good.png", _png_bytes(np.zeros((8, 8), np.uint8)))
    cases = [
        (tmp_path / "missing.png", "no such file"),
        (tmp_path, "it is a directory, not a file"),
        (_write(tmp_path / "empty.png", b""), "the file is empty"),
        (_write(tmp_path / "trunc.png", good.read_bytes()[:40]), "OpenCV could not decode it as PNG"),
        (_write(tmp_path / "trunc.pfm", b"Pf\n4 4\n-1.0\n" + b"\0" * 10), "truncated PFM: expected 64 bytes of pixel data, found 10"),
        (_write(tmp_path / "bad.pfm", b"P6\n4 4\n255\n"), "not a PFM file"),
        (_write(tmp_path / "bad.tif", b"II*\0garbage"), "not a readable TIFF"),
        (_write(tmp_path / "bad.npy", b"\x93NUMPY garbage"), "not a readable NPY file"),
        (_write(tmp_path / "x.gif", b"GIF89a"), "unsupported extension '.gif'"),
    ]
    (tmp_path / "dir.png").mkdir()
    cases.append((tmp_path / "dir.png", "it is a directory, not a file"))
    for path, fragment in cases:
        with pytest.raises(ImageReadError, match="cannot read image") as info:
            io.read_image(path)
        assert fragment in str(info.value), (path, str(info.value))
        assert str(path) in str(info.value)


def test_broken_png_leaves_stderr_quiet(tmp_path, capfd):
    """OpenCV's own log ('[ WARN:0@...] ...') must not add lines to stderr."""
    data = _png_bytes((np.arange(64 * 64) % 251).reshape(64, 64).astype(np.uint8))
    path = _write(tmp_path / "trunc.png", data[: len(data) // 2])
    with pytest.raises(ImageReadError):
        io.read_image(path)
    out, err = capfd.readouterr()
    assert err == ""


def test_colour_alpha_and_16_bit_files_are_read_as_grey(tmp_path):
    rgb = np.zeros((4, 4, 3), np.uint8)
    rgb[..., 0] = 100  # R
    rgba = np.dstack([rgb, np.full((4, 4), 7, np.uint8)])
    cv2.imwrite(str(tmp_path / "rgb.png"), rgb[..., ::-1])
    cv2.imwrite(str(tmp_path / "rgba.png"), rgba[..., [2, 1, 0, 3]])
    cv2.imwrite(str(tmp_path / "deep.png"), np.full((4, 4), 60000, np.uint16))
    assert np.allclose(io.read_image(tmp_path / "rgb.png"), 29.9)
    assert np.allclose(io.read_image(tmp_path / "rgba.png"), 29.9)
    assert np.all(io.read_image(tmp_path / "deep.png") == 60000.0)


def test_output_paths(tmp_path):
    target = tmp_path / "d.pfm"
    io.write_array(target, np.ones((2, 2)))
    with pytest.raises(OutputExistsError, match="exists; pass force=True"):
        io.write_array(target, np.zeros((2, 2)))
    assert io.read_image(target)[0, 0] == 1.0
    io.write_array(target, np.zeros((2, 2)), force=True)
    assert io.read_image(target)[0, 0] == 0.0
    with pytest.raises(OutputWriteError, match="it is a directory"):
        io.atomic_write(tmp_path, lambda fh: None)
    with pytest.raises(OutputWriteError, match="directory .* does not exist"):
        io.write_array(tmp_path / "nope" / "d.pfm", np.ones((2, 2)))
    (tmp_path / "afile").write_text("x")
    with pytest.raises(OutputWriteError, match="does not exist"):
        io.write_array(tmp_path / "afile" / "d.pfm", np.ones((2, 2)))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile", "d.pfm"]


@pytest.mark.parametrize("exc", [KeyboardInterrupt, OSError, RuntimeError])
def test_interrupted_write_leaves_no_file(tmp_path, exc):
    def writer(fh):
        fh.write(b"half a file")
        raise exc("stop")

    with pytest.raises(OutputWriteError if exc is OSError else exc):
        io.atomic_write(tmp_path / "out.pfm", writer)
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "keep.pfm").write_bytes(b"old")
    with pytest.raises(OutputWriteError if exc is OSError else exc):
        io.atomic_write(tmp_path / "keep.pfm", writer, force=True)
    assert [p.name for p in tmp_path.iterdir()] == ["keep.pfm"]
    assert (tmp_path / "keep.pfm").read_bytes() == b"old"


# ---------------------------------------------------------------- size limits


def test_frames_above_the_pixel_limit_are_refused(monkeypatch):
    monkeypatch.delenv(_validate.MAX_PIXELS_ENV, raising=False)
    huge = np.broadcast_to(np.float32(0), (7072, 7072))  # 50 megapixels, no memory
    with pytest.raises(_validate.ImageTooLargeError) as info:
        nf.normal_flow([huge] * 3)
    msg = str(info.value)
    assert "frames[0] has 7072x7072 px (width x height) = 50.0 megapixels, above the limit of 40 megapixels per frame" in msg
    assert "NFDEPTH_MAX_PIXELS" in msg
    assert isinstance(info.value, ValueError)
    with pytest.raises(_validate.ImageTooLargeError, match="views\\[0\\] has 7072x7072"):
        stereo.static_stereo([huge] * 3, reference=1)
    monkeypatch.setenv(_validate.MAX_PIXELS_ENV, "1000")
    with pytest.raises(_validate.ImageTooLargeError, match=r"= 0\.00102 megapixels, above the limit of 0.001 megapixels"):
        nf.normal_flow(VIEWS3)  # as many digits as tell the two apart
    monkeypatch.setenv(_validate.MAX_PIXELS_ENV, "100000")
    with pytest.raises(_validate.ImageTooLargeError, match=r"= 0\.11 megapixels, above the limit of 0.1 megapixels"):
        nf.normal_flow([np.broadcast_to(np.float32(0), (288, 384))] * 3)
    monkeypatch.setenv(_validate.MAX_PIXELS_ENV, "1024")
    nf.normal_flow(VIEWS3)  # exactly at the limit
    monkeypatch.setenv(_validate.MAX_PIXELS_ENV, "lots")
    with pytest.raises(ValueError, match="NFDEPTH_MAX_PIXELS must be a positive number of pixels .*, got 'lots'"):
        nf.normal_flow(VIEWS3)


@pytest.mark.slow
def test_memory_of_a_4_megapixel_triple():
    """Peak memory of normal_flow + select_edge_points on a 2000 x 2000 float32 triple.

    The working set is float32 smoothed frames (3 x 4 B), the per-frame
    gradients and their sums (about 6 x 4 B), the gradient field (3 x 4 B),
    magnitude and percentile copies (about 3 x 4 B), the float64 structure
    tensor and its eigenvalues (about 8 x 8 B) and boolean masks: about
    105 bytes per pixel measured (tracemalloc agrees with the RSS growth).
    The bound, 128 B/px, is what _validate.MAX_PIXELS is documented with.
    """
    h = w = 2000
    rng = np.random.default_rng(0)
    base = (cv2.GaussianBlur(rng.random((h, w + 2), dtype=np.float32), (0, 0), 2.0) * 255.0).astype(np.float32)
    frames = [np.ascontiguousarray(base[:, k : k + w]) for k in range(3)]
    del base
    tracemalloc.start()
    try:
        field = nf.normal_flow(frames, sigma_px=2.0)
        smoothed = nf.gaussian_smooth(frames[1], sigma_px=2.0)
        selection = nf.select_edge_points(field, smoothed)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert selection.mask.sum() > 1000
    per_pixel = peak / (h * w)
    assert per_pixel < 128, f"{per_pixel:.1f} bytes per pixel"


# ---------------------------------------------------------------- determinism


def _pipeline_outputs():
    dyn = synthetic.paper_dynamic_sequence(2, noise_std=1.0, rng=np.random.default_rng(1), image_size_px=160)
    sta = synthetic.paper_static_sequence(n_views=5, noise_std=1.0, rng=np.random.default_rng(2), image_size_px=160)
    a = nf.dynamic_stereo(dyn.frames, camera=dyn.camera, relative_motion=dyn.relative_motion)
    b = nf.static_stereo_edges(sta.frames, camera=sta.camera, baseline=2.0)
    c = stereo.static_stereo([f.astype(np.float32) for f in sta.frames], reference=2)
    return {
        "dynamic rho": a.inverse_depth.rho, "dynamic std": a.inverse_depth.rho_std, "dynamic rows": a.rows,
        "static rho": b.inverse_depth.rho, "static dvn": b.delta_vn,
        "dense disparity": c.disparity, "dense uncertainty": c.uncertainty, "dense reason": c.reason,
    }


def test_same_input_gives_bit_identical_output_across_runs_and_threads():
    first = _pipeline_outputs()
    second = _pipeline_outputs()
    threads = cv2.getNumThreads()
    try:
        cv2.setNumThreads(1)
        single = _pipeline_outputs()
        cv2.setNumThreads(max(threads, 4))
        many = _pipeline_outputs()
    finally:
        cv2.setNumThreads(threads)
    for key, value in first.items():
        for other in (second, single, many):
            assert value.dtype == other[key].dtype and value.shape == other[key].shape, key
            assert value.tobytes() == other[key].tobytes(), key


def test_cli_output_is_bit_identical(tmp_path, views_on_disk, capsys):
    outs = []
    for k in range(2):
        out = tmp_path / f"d{k}.pfm"
        assert main(["stereo", *map(str, views_on_disk), "--out", str(out)]) == 0
        outs.append(out.read_bytes())
    capsys.readouterr()
    assert outs[0] == outs[1]


# ------------------------------------------------------------------------ CLI


@pytest.fixture
def views_on_disk(tmp_path):
    paths = []
    for k in range(3):
        p = tmp_path / f"v{k}.png"
        cv2.imwrite(str(p), np.clip(_texture((48, 64), shift=float(k)), 0, 255).astype(np.uint8))
        paths.append(p)
    return paths


def test_cli_stereo_threads_do_not_change_the_output(tmp_path, capfd):
    """--threads sets the cost volume's threads; its row strips (two at 300 rows) are fixed, so the bytes are the same."""
    from nfdepth._cost_volume import _row_strips

    assert len(_row_strips(300, 9)) == 2
    views = []
    for k in range(3):
        p = tmp_path / f"t{k}.png"
        cv2.imwrite(str(p), np.clip(_texture((300, 96), shift=1.5 * k), 0, 255).astype(np.uint8))
        views.append(p)
    outs = []
    for threads in ("1", "2"):
        out = tmp_path / f"d{threads}.pfm"
        code, _, err = run_cli(capfd, "stereo", *views, "--out", out, "--threads", threads)
        assert code == 0, err
        outs.append(out.read_bytes())
    assert outs[0] == outs[1]


def _cli_cases(tmp: Path, v):
    """(id, argv, exit code, stderr fragment) for each bad command line."""
    v0, v1, v2 = (str(p) for p in v)
    (tmp / "exists.pfm").write_bytes(b"x")
    (tmp / "adir").mkdir()
    (tmp / "afile").write_text("x")
    _write(tmp / "empty.png", b"")
    _write(tmp / "trunc.png", Path(v1).read_bytes()[:60])
    cv2.imwrite(str(tmp / "small.png"), np.zeros((16, 16), np.uint8))
    np.save(tmp / "map.npy", np.ones((4, 4)))
    holed = cv2.imread(v1, cv2.IMREAD_GRAYSCALE).astype(np.float32)
    holed[3:5, 2:7] = np.nan
    np.save(tmp / "holed.npy", holed)
    np.save(tmp / "hot.npy", np.where(np.isfinite(holed), holed, 2e22).astype(np.float32))
    out = str(tmp / "o.pfm")
    return [
        # the library names only its index (views[1], frames[3]): the command line names the file
        ("view with NaN", ["stereo", v0, str(tmp / "holed.npy"), v2, "--out", out], 2, "view 'holed.npy' contains 10 non-finite (NaN or inf) pixel(s); expected finite intensities"),
        ("view too bright", ["stereo", v0, str(tmp / "hot.npy"), v2, "--out", out], 2, "view '" + str(tmp / "hot.npy") + "' has intensities up to 2e+22, beyond 1e+15"),
        ("one view", ["stereo", v0, "--out", out], 2, "stereo needs at least 2 views"),
        ("focal zero", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "0", "--baseline", "1"], 2, "--focal-px must be a positive number, got 0"),
        ("focal negative", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "-10", "--baseline", "1"], 2, "--focal-px must be a positive number, got -10"),
        ("baseline zero", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "10", "--baseline", "0"], 2, "--baseline must be a positive number, got 0"),
        ("focal without baseline", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "10"], 2, "--focal-px and --baseline go together"),
        ("focal baseline overflow", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "1e300", "--baseline", "1e300"], 2, "--focal-px = 1e+300 is outside 1e-30..1e+30: give it in a unit that keeps it there (depths are written as float32)"),
        ("focal overflow alone", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "1e300", "--baseline", "2"], 2, "--focal-px = 1e+300 is outside 1e-30..1e+30"),  # printed an overflow warning first
        ("baseline overflow alone", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "100", "--baseline", "1e300"], 2, "--baseline = 1e+300 is outside 1e-30..1e+30"),
        ("depth beyond float32", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "1e20", "--baseline", "1e20"], 2, "does not fit a float32 output (about 1e-45 to 3.4e38): give --focal-px and --baseline"),
        ("focal baseline underflow", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "1e-300", "--baseline", "1e-300"], 2, "--focal-px = 1e-300 is outside 1e-30..1e+30"),
        ("ply without depth", ["stereo", v0, v1, v2, "--out", out, "--ply", str(tmp / "p.ply")], 2, "--ply needs --focal-px and --baseline"),
        ("offset without depth", ["stereo", v0, v1, v2, "--out", out, "--disparity-offset-px", "4"], 2, "--disparity-offset-px changes depth only: give --focal-px and --baseline too"),
        ("offset nan", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "10", "--baseline", "1", "--disparity-offset-px", "nan"], 2, "--disparity-offset-px must be a finite number of px per unit of position within +-1e+06"),
        ("offset huge", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "10", "--baseline", "1", "--disparity-offset-px", "1e300"], 2, "a value beyond is another unit or a typo), got 1e+300"),
        ("offset with a column", ["stereo", v0, v1, v2, "--column", v0, v1, v2, "--out", out, "--focal-px", "10", "--baseline", "1", "--disparity-offset-px", "4"], 2, "--disparity-offset-px applies to one row"),
        ("principal point without ply", ["stereo", v0, v1, v2, "--out", out, "--cx-px", "3", "--cy-px", "4"], 2, "--cx-px and --cy-px place the points of --ply: give --ply too"),
        ("principal point inf", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "10", "--baseline", "1", "--ply", str(tmp / "p.ply"), "--cy-px", "inf"], 2, "--cy-px must be a finite number of pixels, got inf"),
        ("principal point far", ["stereo", v0, v1, v2, "--out", out, "--focal-px", "10", "--baseline", "1", "--ply", str(tmp / "p.ply"), "--cx-px", "1e9"], 2, "--cx-px = 1e+09 px: expected a principal point within 1e+06 px of the image centre 31.5"),
        ("reference range", ["stereo", v0, v1, v2, "--out", out, "--reference", "3"], 2, "--reference must index one of the 3 views (0..2), got 3"),
        ("stereo threads", ["stereo", v0, v1, v2, "--out", out, "--threads", "0"], 2, "--threads must be an integer >= 1, got 0"),
        ("reference text", ["stereo", v0, v1, v2, "--out", out, "--reference", "x"], 2, "argument --reference: invalid int value: 'x'"),
        ("positions count", ["stereo", v0, v1, v2, "--out", out, "--positions", "0", "1"], 2, "positions must hold one number per view (3)"),
        ("views wrong order", ["stereo", v0, v1, v2, "--out", out, "--positions", "2", "1", "0"], 2, "positions must be strictly increasing"),
        ("positions nan", ["stereo", v0, v1, v2, "--out", out, "--positions", "0", "1", "nan"], 2, "positions must be finite"),
        # argparse took "-inf" for an unknown option ("expected at least one argument")
        ("positions -inf", ["stereo", v0, v1, v2, "--out", out, "--positions", "-inf", "0", "1"], 2, "--positions must be finite, got [-inf, 0.0, 1.0]"),
        ("range -inf", ["stereo", v0, v1, v2, "--out", out, "--disparity-range", "-inf", "5"], 2, "--disparity-range"),
        ("positions tiny unit", ["stereo", v0, v1, v2, "--out", out, "--positions", "0", "1e-300", "2e-300"], 2, "positions must keep the views 1e-30 to 1e+30 units from the reference"),
        ("positions huge unit", ["stereo", v0, v1, v2, "--out", out, "--positions", "0", "1e300", "2e300"], 2, "rescale them, e.g. to steps between neighbouring views"),
        ("sigma negative", ["stereo", v0, v1, v2, "--out", out, "--sigma-px", "-1"], 2, "--sigma-px must be a finite number >= 0, got -1.0"),
        ("sigma huge", ["stereo", v0, v1, v2, "--out", out, "--sigma-px", "1e300"], 2, "--sigma-px 1e+300 px is beyond any image"),
        ("levels", ["stereo", v0, v1, v2, "--out", out, "--levels", "0"], 2, "levels must be >= 1"),
        ("cost step zero", ["stereo", v0, v1, v2, "--out", out, "--cost-step-px", "0"], 2, "--cost-step-px must be a positive number, got 0"),
        ("cost step nan", ["stereo", v0, v1, v2, "--out", out, "--cost-step-px", "nan"], 2, "--cost-step-px must be a positive number, got nan"),
        ("cost step wider than the range", ["stereo", v0, v1, v2, "--out", out, "--cost-step-px", "1e300"], 2, "--cost-step-px 1e+300 px is wider than half the search range the pyramid found"),
        ("sizes differ", ["stereo", v0, str(tmp / "small.png"), v2, "--out", out], 2, "all views must have the same size, got v0.png 64x48, small.png 16x16, v2.png 64x48"),
        ("missing view", ["stereo", v0, str(tmp / "nope.png"), v2, "--out", out], 3, "nope.png': no such file"),
        ("directory view", ["stereo", v0, str(tmp / "adir"), v2, "--out", out], 3, "adir': it is a directory, not a file"),
        ("empty view", ["stereo", v0, str(tmp / "empty.png"), v2, "--out", out], 3, "empty.png': the file is empty"),
        ("truncated view", ["stereo", v0, str(tmp / "trunc.png"), v2, "--out", out], 3, "trunc.png': OpenCV could not decode it as PNG"),
        ("output exists", ["stereo", v0, v1, v2, "--out", str(tmp / "exists.pfm")], 4, "exists.pfm' exists; use --force to overwrite it"),
        ("output extension", ["stereo", v0, v1, v2, "--out", str(tmp / "o.png")], 2, "must end in one of .pfm, .tif, .tiff, .npy"),
        ("output folder missing", ["stereo", v0, v1, v2, "--out", str(tmp / "nodir" / "o.pfm")], 4, "directory '" + str(tmp / "nodir") + "' does not exist"),
        ("output folder is a file", ["stereo", v0, v1, v2, "--out", str(tmp / "afile" / "o.pfm")], 4, "o.pfm': '" + str(tmp / "afile") + "' is not a directory"),
        ("demo out inside a file", ["demo", "--out", str(tmp / "afile" / "sub")], 4, f"--out '{tmp / 'afile' / 'sub'}': '{tmp / 'afile'}' is not a directory"),
        ("empty --out", ["demo", "--out", ""], 2, "--out is empty (''); expected a value (an unset shell variable?)"),
        ("empty --json=", ["reproduce", "--json=", "--only", "exp1"], 2, "--json is empty ('--json='); expected a value"),
        ("empty positional", ["view", ""], 2, "argument 2 is empty ('')"),
        ("outputs clash", ["stereo", v0, v1, v2, "--out", out, "--uncertainty", out], 2, "--out and --uncertainty name the same file"),
        ("view missing", ["view", str(tmp / "nope.pfm")], 3, "nope.pfm': no such file"),
        ("view output is a directory", ["view", str(tmp / "map.npy"), "--out", str(tmp / "adir")], 2, "must end in one of .png"),
        ("view output exists", ["view", str(tmp / "map.npy"), "--out", v0], 4, "v0.png' exists; use --force"),
        ("view vmin", ["view", str(tmp / "map.npy"), "--out", str(tmp / "m.png"), "--vmin", "nan"], 2, "vmin must be a finite number, got nan"),
        ("view range", ["view", str(tmp / "map.npy"), "--out", str(tmp / "m.png"), "--vmin", "5", "--vmax", "1"], 2, "--vmax must be >= --vmin, got --vmin 5 --vmax 1"),
        ("view unit, no colour bar", ["view", str(tmp / "map.npy"), "--out", str(tmp / "m.png"), "--unit", "mm"], 2, "--unit labels the colour bar: give --colorbar too"),
        ("view range, colour bar", ["view", str(tmp / "map.npy"), "--colorbar", "--out", str(tmp / "m.png"), "--vmin", "5", "--vmax", "1"], 2, "--vmax must be >= --vmin"),
        ("bench json", ["bench", "--json", str(tmp / "b.txt")], 2, "--json '" + str(tmp / "b.txt") + "' must end in one of .json"),
        ("bench threads", ["bench", "--threads", "0"], 2, "--threads must be an integer >= 1, got 0"),
        # OpenCV starts as many workers as asked for: 10**9 ran the machine out of processes
        ("bench threads huge", ["bench", "--threads", "1000000000"], 2, "--threads = 1000000000 is more than this machine's"),
        ("reproduce noise", ["reproduce", "--noise", "-1"], 2, "--noise must be a finite number >= 0"),
        ("levels zero", ["stereo", v0, v1, v2, "--out", out, "--levels", "0"], 2, "--levels must be >= 1"),
        ("positions too few", ["stereo", v0, v1, v2, "--out", out, "--positions", "0", "1"], 2, "--positions must hold one number per view (3), got shape (2,)"),
        ("reproduce noise huge", ["reproduce", "--only", "exp1", "--noise", "1e300"], 2, "--noise 1e+300 grey levels is beyond any image: expected at most 1e+06"),
        ("reproduce json folder", ["reproduce", "--only", "exp1", "--json", str(tmp / "nodir" / "r.json")], 4, "does not exist"),
        ("reproduce out is a file", ["reproduce", "--only", "exp1", "--out", str(tmp / "afile")], 4, "afile' exists and is not a directory"),
        ("demo out is a file", ["demo", "--out", str(tmp / "afile")], 4, "afile' exists and is not a directory"),
        ("unknown command", ["frobnicate"], 2, "invalid choice"),
        ("unknown option", ["stereo", v0, v1, "--out", out, "--bogus"], 2, "nfdepth: error: unrecognized arguments: --bogus"),
        # `nfdepth video frames/*.png` unquoted: the shell hands over the files, the first taken as the video
        ("unquoted glob", ["view", str(tmp / "map.npy"), v1, v2, "--out", str(tmp / "m2.png")], 2, f"unrecognized arguments: {v1} {v2}: quote a glob such as 'frames/*.png', or the shell expands it into files"),
        ("bad option value", ["stereo", v0, v1, "--out", out, "--axis", "z"], 2, "nfdepth: error: stereo: argument --axis: invalid choice: 'z'"),
    ]


def test_cli_bad_input_one_line_and_exit_code(tmp_path, views_on_disk, capfd):
    failures = []
    for name, argv, code, fragment in _cli_cases(tmp_path, views_on_disk):
        before = set(tmp_path.rglob("*"))
        got, out, err = run_cli(capfd, *argv)
        lines = err.strip().splitlines()
        ok = got == code and len(lines) == 1 and fragment in err and "Traceback" not in err and lines[0].startswith("nfdepth: error: ")
        ok = ok and set(tmp_path.rglob("*")) == before  # no output, no temporary file
        if not ok:
            failures.append(f"{name}: exit {got} (want {code}), stderr {err!r}")
    assert not failures, "\n".join(failures)


def test_cli_reads_negative_numbers_in_exponent_form():
    """argparse took "-1e1" for an unknown option ("expected 2 arguments"); a negative value may be written in any float form."""
    from nfdepth.cli import build_parser

    parser = build_parser()
    args = parser.parse_args(["stereo", "a.png", "b.png", "c.png", "--out", "o.pfm", "--disparity-range", "-1e1", "8", "--positions", "-1e30", "0", "1.5E+30"])
    assert args.disparity_range == [-10.0, 8.0] and args.positions == [-1e30, 0.0, 1.5e30]
    args = parser.parse_args(["stereo", "a.png", "b.png", "--out", "o.pfm", "--disparity-range", "-.5", "-2."])
    assert args.disparity_range == [-0.5, -2.0]
    assert main(["stereo", "a.png", "b.png", "--out", "o.pfm", "--disparity-range", "-e1", "8"]) == 2  # no number: still an unknown option


def test_cli_image_too_large(tmp_path, views_on_disk, capfd, monkeypatch):
    monkeypatch.setenv("NFDEPTH_MAX_PIXELS", "1000")
    code, out, err = run_cli(capfd, "stereo", *views_on_disk, "--out", tmp_path / "o.pfm")
    assert code == 2
    assert err.strip().splitlines() == [err.strip()]
    # the file, where the library can only say views[0]
    assert err.startswith(f"nfdepth: error: view '{views_on_disk[0]}' has 64x48 px (width x height) = 0.003 megapixels, above the limit of 0.001 megapixels per frame")
    assert not (tmp_path / "o.pfm").exists()


def test_cli_colour_and_16_bit_views_work(tmp_path, capfd):
    paths = []
    for k in range(3):
        grey = _texture((48, 64), shift=float(k))
        p = tmp_path / f"c{k}.png"
        if k == 1:
            cv2.imwrite(str(p), np.dstack([grey, grey, grey, np.full_like(grey, 255)]).astype(np.uint8))  # RGBA
        else:
            cv2.imwrite(str(p), (np.dstack([grey] * 3) * 256).astype(np.uint16))  # 16-bit RGB
        paths.append(p)
    code, out, err = run_cli(capfd, "stereo", *paths, "--out", tmp_path / "o.pfm")
    assert code == 0, err
    assert (tmp_path / "o.pfm").exists()


def test_cli_force_replaces(tmp_path, views_on_disk, capfd):
    target = tmp_path / "o.pfm"
    target.write_bytes(b"old")
    code, out, err = run_cli(capfd, "stereo", *views_on_disk, "--out", target, "--force")
    assert code == 0, err
    assert target.read_bytes().startswith(b"Pf")


def test_cli_debug_shows_the_traceback(tmp_path, capfd):
    """--debug adds the traceback; the last line and the exit code stay those of a plain run."""
    code = main(["--debug", "view", str(tmp_path / "nope.pfm")])
    assert code == 3
    assert "Traceback" in capfd.readouterr().err
    res = subprocess.run(
        [sys.executable, "-m", "nfdepth", "--debug", "view", str(tmp_path / "nope.pfm")], capture_output=True, text=True, check=False
    )
    assert res.returncode == 3
    assert "Traceback" in res.stderr and "ImageReadError: cannot read image" in res.stderr
    assert res.stderr.strip().splitlines()[-1] == f"nfdepth: error: cannot read image '{tmp_path / 'nope.pfm'}': no such file"
    res = subprocess.run([sys.executable, "-m", "nfdepth", "view", str(tmp_path / "nope.pfm")], capture_output=True, text=True, check=False)
    assert res.returncode == 3
    assert res.stderr.strip().splitlines() == [f"nfdepth: error: cannot read image '{tmp_path / 'nope.pfm'}': no such file"]


def test_cli_warnings_are_one_line(capfd, monkeypatch):
    import warnings

    from nfdepth import cli

    def _warn(args):
        warnings.warn("no edge points: the images are textureless\n(second line)", UserWarning, stacklevel=1)
        return 0

    monkeypatch.setattr(cli, "_cmd_view", _warn)
    code, out, err = run_cli(capfd, "view", "x.npy")
    assert code == 0
    assert err == "nfdepth: warning: no edge points: the images are textureless (second line)\n"


# ------------------------------------------------- interrupted command lines

_RUNNER = """
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)  # even when started with SIGINT ignored
if sys.argv[1] in ("slow-write", "second-write"):
    import nfdepth.io as io
    real = io.atomic_write
    calls = []
    def slow(path, writer_fn, *, force=False):
        calls.append(path)
        if sys.argv[1] == "second-write" and len(calls) == 1:
            return real(path, writer_fn, force=force)  # the first output completes
        def writer(fh):
            fh.write(b"Pf\\n partial")
            fh.flush()
            print("WRITING", flush=True)
            time.sleep(60)
            writer_fn(fh)
        return real(path, writer, force=force)
    io.atomic_write = slow
else:
    print("WRITING", flush=True)
from nfdepth.cli import main
sys.exit(main(sys.argv[2:]))
"""


def _big_views(folder: Path, shape=(1600, 2400)) -> list[Path]:
    paths = []
    base = _texture((shape[0], shape[1] // 4), seed=3)
    tile = np.tile(base, (1, 4))
    for k in range(3):
        p = folder / f"big{k}.png"
        cv2.imwrite(str(p), np.clip(np.roll(tile, -k, axis=1), 0, 255).astype(np.uint8))
        paths.append(p)
    return paths


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
@pytest.mark.parametrize(
    ("mode", "sig", "code"),
    [
        ("compute", signal.SIGINT, 130),
        ("compute", signal.SIGTERM, 143),
        ("slow-write", signal.SIGINT, 130),
        ("slow-write", signal.SIGTERM, 143),
        ("second-write", signal.SIGTERM, 143),  # --out complete, --uncertainty being written
    ],
)
def test_interrupted_stereo_leaves_no_file(tmp_path, mode, sig, code):
    views = _big_views(tmp_path) if mode == "compute" else _big_views(tmp_path, (48, 64))
    out = tmp_path / "out" / "depth.pfm"
    out.parent.mkdir()
    script = tmp_path / "runner.py"
    script.write_text(_RUNNER)
    proc = subprocess.Popen(
        [sys.executable, str(script), mode, "stereo", *map(str, views), "--out", str(out), "--uncertainty", str(out.with_name("std.pfm"))],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline().strip() == "WRITING"
        time.sleep(1.5 if mode == "compute" else 0.3)  # compute: into the stereo estimate
        assert proc.poll() is None, "finished before the signal: make the input larger"
        proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == code, stderr
    assert "Traceback" not in stderr
    assert len(stderr.strip().splitlines()) == 1 and "no partial output written" in stderr
    assert list(out.parent.iterdir()) == []  # no output, no temporary file
    # an output the run had completed is removed too (it said "no partial output" and left it)
    assert ("removed the 1 output(s) it had completed" in stderr) == (mode == "second-write"), stderr


# ------------------------------------------- interrupted and failed runs, in process


def _stop_at_write(monkeypatch, n: int, exc: BaseException) -> list:
    """The ``n``-th output file of a run raises ``exc`` half way through its write; the earlier ones complete."""
    real = io.atomic_write
    calls: list = []

    def write(path, writer_fn, *, force=False):
        calls.append(Path(path).name)
        if len(calls) != n:
            return real(path, writer_fn, force=force)

        def half(fh):
            fh.write(b"Pf\n half a file")
            raise exc

        return real(path, half, force=force)

    monkeypatch.setattr(io, "atomic_write", write)
    return calls


@pytest.mark.parametrize(
    ("exc", "code", "said"),
    [(KeyboardInterrupt(), 130, "interrupted"), (None, 143, "terminated (SIGTERM)")],
)
def test_interrupt_removes_the_outputs_the_run_completed(tmp_path, views_on_disk, capfd, monkeypatch, exc, code, said):
    from nfdepth import cli

    exc = exc if exc is not None else cli._Terminated()
    out = tmp_path / "out"
    out.mkdir()
    calls = _stop_at_write(monkeypatch, 3, exc)
    got, stdout, err = run_cli(
        capfd, "stereo", *views_on_disk, "--out", out / "d.pfm", "--uncertainty", out / "s.pfm", "--preview", out / "p.png"
    )
    assert calls == ["d.pfm", "s.pfm", "p.png"]
    assert got == code and stdout == ""
    assert err == f"nfdepth: {said}; no partial output written; removed the 2 output(s) it had completed\n"
    assert list(out.iterdir()) == []  # neither the completed outputs nor a temporary file
    assert io.COMPLETED_WRITES is None  # recorded during a command-line run only


def test_interrupt_names_the_outputs_it_replaced_with_force(tmp_path, views_on_disk, capfd, monkeypatch):
    """A file replaced with --force cannot be restored: it stays (new content) and is named; a new one is removed."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "d.pfm").write_bytes(b"old")
    _stop_at_write(monkeypatch, 3, KeyboardInterrupt())
    got, _, err = run_cli(
        capfd, "stereo", *views_on_disk, "--out", out / "d.pfm", "--uncertainty", out / "s.pfm", "--preview", out / "p.png", "--force"
    )
    assert got == 130
    assert err == (
        f"nfdepth: interrupted; no partial output written; removed the 1 output(s) it had completed;"
        f" already written before the interruption: {out / 'd.pfm'}\n"
    )
    assert [p.name for p in out.iterdir()] == ["d.pfm"]
    assert io.read_pfm(out / "d.pfm").shape == (48, 64)  # the new, complete map
    # interrupted at the first write: nothing completed, nothing to say about it
    _stop_at_write(monkeypatch, 1, KeyboardInterrupt())
    got, _, err = run_cli(capfd, "stereo", *views_on_disk, "--out", out / "e.pfm")
    assert got == 130 and err == "nfdepth: interrupted; no partial output written\n"
    assert [p.name for p in out.iterdir()] == ["d.pfm"]


def test_disk_full_is_one_line_exit_4(tmp_path, views_on_disk, capfd, monkeypatch):
    import errno

    out = tmp_path / "out"
    out.mkdir()
    _stop_at_write(monkeypatch, 2, OSError(errno.ENOSPC, "No space left on device"))
    got, stdout, err = run_cli(capfd, "stereo", *views_on_disk, "--out", out / "d.pfm", "--uncertainty", out / "s.pfm")
    assert got == 4 and stdout == ""
    assert err == f"nfdepth: error: cannot write '{out / 's.pfm'}': No space left on device; removed the 1 output(s) it had completed\n"
    assert not (out / "s.pfm").exists() and not list(out.glob(".*"))  # no half-written file, no temporary file


def test_a_failed_write_leaves_none_of_the_runs_outputs(tmp_path, views_on_disk, capfd, monkeypatch):
    import errno

    out = tmp_path / "out"
    out.mkdir()
    _stop_at_write(monkeypatch, 2, OSError(errno.ENOSPC, "No space left on device"))
    got, _, _ = run_cli(capfd, "stereo", *views_on_disk, "--out", out / "d.pfm", "--uncertainty", out / "s.pfm")
    assert got == 4
    assert list(out.iterdir()) == []  # was: d.pfm, complete, next to the missing s.pfm


@pytest.mark.parametrize(
    ("exc", "code", "line"),
    [
        (RuntimeError("boom\n  second line"), 1, "internal error (RuntimeError): boom second line; rerun with --debug and report it"),
        (RuntimeError(), 1, "internal error (RuntimeError): RuntimeError; rerun with --debug and report it"),
        (ZeroDivisionError("division by zero"), 1, "internal error (ZeroDivisionError): division by zero; rerun with --debug and report it"),
        (TypeError("bad type"), 2, "bad type"),
        (FileNotFoundError("cannot read rig file 'r.toml': no such file"), 3, "cannot read rig file 'r.toml': no such file"),
        (ImageReadError("cannot read image 'a.png': the file is empty"), 3, "cannot read image 'a.png': the file is empty"),
        (OutputExistsError("'d.pfm' exists; pass force=True"), 4, "'d.pfm' exists; pass force=True"),
        (OutputWriteError("cannot write 'd.pfm': Read-only file system"), 4, "cannot write 'd.pfm': Read-only file system"),
        (OSError(28, "No space left on device"), 4, "[Errno 28] No space left on device"),
    ],
)
def test_cli_error_boundary_exit_codes(capfd, monkeypatch, exc, code, line):
    """What reaches the command line's single error boundary: the exit code by kind, one line, no traceback."""
    from nfdepth import cli

    def fail(args):
        raise exc

    monkeypatch.setattr(cli, "_cmd_view", fail)
    got, stdout, err = run_cli(capfd, "view", "x.npy")
    assert (got, stdout, err) == (code, "", f"nfdepth: error: {line}\n")


def test_cli_data_not_found_is_exit_5(capfd, monkeypatch):
    from nfdepth import cli
    from nfdepth.datasets import DataNotFoundError

    def fail(args):
        raise DataNotFoundError("data folder not found; tried NFDEPTH_DATA (not set)")

    monkeypatch.setattr(cli, "_cmd_view", fail)
    got, _, err = run_cli(capfd, "view", "x.npy")
    assert got == 5 and err == "nfdepth: error: data folder not found; tried NFDEPTH_DATA (not set)\n"


def test_cli_debug_shows_the_traceback_of_an_argument_error(tmp_path, capfd):
    """--debug with a refused argument: the traceback, then the plain run's line and exit code."""
    code = main(["--debug", "reproduce", "--seed", "-1"])
    err = capfd.readouterr().err
    assert code == 2
    assert err.startswith("Traceback") and "CLIError: --seed must be an integer >= 0" in err
    assert err.strip().splitlines()[-1] == "nfdepth: error: --seed must be an integer >= 0 (the noise generator's seed), got -1"
    assert main(["reproduce", "--seed", "-1"]) == 2
    assert "Traceback" not in capfd.readouterr().err


def test_cli_runs_outside_the_main_thread(capfd):
    """main() from a worker thread: no SIGTERM handler (Python allows one in the main thread only), same result."""
    import threading

    before = signal.getsignal(signal.SIGTERM)
    got = []
    worker = threading.Thread(target=lambda: got.append(main(["reproduce", "--noise", "-1"])))
    worker.start()
    worker.join()
    assert got == [2]
    assert capfd.readouterr().err == "nfdepth: error: --noise must be a finite number >= 0, got -1.0\n"
    assert signal.getsignal(signal.SIGTERM) is before
    main(["reproduce", "--noise", "-1"])  # from the main thread: the handler is installed for the run and restored
    assert signal.getsignal(signal.SIGTERM) is before


def test_an_unreadable_rig_file_is_an_input_error(tmp_path, views_on_disk, capfd, monkeypatch):
    """Exit 3 is "an input file could not be read"; an image without read permission gets it, so should a rig file."""
    import errno

    rig = tmp_path / "r.toml"
    rig.write_text("[camera]\nfocal_px = 100\nwidth_px = 64\nheight_px = 48\n")
    real = Path.read_text

    def refused(self, *args, **kwargs):  # what the OS says to a user without read permission (root ignores file modes)
        if self == rig:
            raise PermissionError(errno.EACCES, "Permission denied", str(self))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Path, "read_text", refused)
    got, _, err = run_cli(capfd, "stereo", *views_on_disk, "--rig", rig, "--out", tmp_path / "d.pfm")
    assert err.count("\n") == 1 and "Traceback" not in err and not (tmp_path / "d.pfm").exists()
    assert got == 3, err  # was 4: "an output could not be written"
    assert err.startswith(f"nfdepth: error: cannot read rig file '{rig}'"), err


# ------------------------------------------- standard output closed early (| head -1)


class _ClosedPipe:
    """A stdout whose reader has gone after ``lines`` writes."""

    def __init__(self, lines: int):
        self.lines, self.written = lines, []

    def write(self, text):
        if len(self.written) >= self.lines:
            raise BrokenPipeError(32, "Broken pipe")
        self.written.append(text)
        return len(text)

    def flush(self):
        if len(self.written) >= self.lines:
            raise BrokenPipeError(32, "Broken pipe")


def test_a_closed_stdout_keeps_the_run_and_its_outputs(tmp_path, views_on_disk, capsys, monkeypatch):
    """``nfdepth stereo ... | head -1``: the reader goes; the run still ends with exit 0 and every file it was asked for."""
    closed = _ClosedPipe(0)
    monkeypatch.setattr(sys, "stdout", closed)
    got = main(["stereo", *map(str, views_on_disk), "--out", str(tmp_path / "d.pfm"), "--uncertainty", str(tmp_path / "s.pfm")])
    assert sys.stdout is closed  # restored after the run
    monkeypatch.undo()
    assert got == 0 and capsys.readouterr().err == ""
    assert io.read_pfm(tmp_path / "d.pfm").shape == io.read_pfm(tmp_path / "s.pfm").shape == (48, 64)


def test_a_stdout_closed_before_the_first_line_is_not_an_error():
    """The same in a real process: no 'Broken pipe' line, no 'Exception ignored' at exit, exit 0."""
    proc = subprocess.Popen([sys.executable, "-m", "nfdepth", "fetch-data", "--list"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # before the command prints anything (importing takes far longer)
    with proc.stderr:
        err = proc.stderr.read()
    assert proc.wait(timeout=60) == 0
    assert err == b""


def test_view_of_a_map_with_no_value_says_so(tmp_path, capfd):
    np.save(tmp_path / "nan.npy", np.full((8, 10), np.nan, np.float32))
    for extra in ([], ["--colorbar"]):
        out = tmp_path / f"v{len(extra)}.png"
        got, stdout, err = run_cli(capfd, "view", tmp_path / "nan.npy", "--out", out, *extra)
        assert got == 0 and stdout == f"wrote {out}\n"
        assert err == f"nfdepth: warning: '{tmp_path / 'nan.npy'}' holds no finite value (all unknown): the PNG is all black\n"
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_edge_points_and_static_stereo_name_their_own_parameters():
    g = nf.normal_flow([np.ones((8, 8))] * 3)
    from nfdepth.edges import select_edge_points

    with pytest.raises(ValueError, match=r"^smoothed_middle must be a real 2-D image"):
        select_edge_points(g, np.ones((8, 8), complex))
    with pytest.raises(TypeError, match=r"^edges_only must be True or False, got 1$"):
        stereo.static_stereo(VIEWS3, reference=1, edges_only=1)


def test_writers_readers_and_options_refuse_what_they_would_misread(tmp_path):
    """PFM bytes under a .png name, grey='no', a direction of bools or text, and fuse_axes of numbers were
    taken (or failed deep inside)."""
    from nfdepth.xy_stereo import fuse_axes

    with pytest.raises(ValueError, match=r"^path must end in .pfm, got '.*x.png'"):
        io.write_pfm(tmp_path / "x.png", np.ones((2, 2)))
    assert not list(tmp_path.iterdir())
    io.write_pfm(tmp_path / "x.PFM", np.ones((2, 2)))  # any case
    cv2.imwrite(str(tmp_path / "c.png"), np.zeros((6, 7), np.uint8))
    with pytest.raises(TypeError, match=r"^grey must be True or False, got 'no'$"):
        io.read_image(tmp_path / "c.png", grey="no")
    cam = nf.PinholeCamera(focal_px=10.0, width_px=8, height_px=8)
    for bad in ((True, False, False), (1j, 0, 0), ("a", 0, 0)):
        with pytest.raises(TypeError, match=r"^direction must be 3 numbers"):
            nf.static_stereo_edges([np.ones((8, 8))] * 3, camera=cam, baseline=1.0, direction=bad)
    with pytest.raises(TypeError, match=r"^row must be a StereoResult .*got int$"):
        fuse_axes(1, 2)
