"""The library mirrors the command line: every ``nfdepth`` command is a thin layer over public functions."""

from __future__ import annotations

import argparse
import ast
import importlib
import inspect
from pathlib import Path

import pytest

import nfdepth
from nfdepth.cli import build_parser

SRC = Path(nfdepth.__file__).resolve().parent

#: command -> the public functions that do its work. Top-level names must be in
#: ``nfdepth.__all__``; dotted ones in their sub-module's ``__all__``.
COMMANDS = {
    "demo": ["run_paper_experiment", "static_stereo", "write_array", "write_ply", "depth_to_points", "plot.colormap_panel"],
    "reproduce": ["run_paper_experiment", "plot.save_figure"],
    "stereo": [
        "static_stereo",
        "load_rig",
        "stereo_options_from_rig",
        "load_cameras",
        "calibrated_row_depth",
        "calibrated_grid_depth",
        "read_image",
        "write_array",
        "write_colormap_png",
        "write_ply",
        "plot.colormap_panel",
    ],
    "dynamic": [
        "load_rig",
        "read_image",
        "dynamic_stereo_from_rig",
        "edge_depth_maps",
        "read_video",
        "dynamic_stereo_from_videos",
        "write_crossings_npz",
        "plot.colormap_panel",
    ],
    "video": ["load_rig", "read_video", "depth_from_video", "write_video_npz", "video.write_video_frame", "plot.colormap_panel"],
    "evaluate": ["evaluate_scene", "evaluate_dataset", "disparity_errors", "sgbm_disparity", "waxman_sinha_disparity"],
    "view": ["read_image", "write_colormap_png", "plot.colormap_panel"],
    "bench": ["bench.bench_main"],
    "fetch-data": ["fetch_data", "default_data_dir", "fetch.data_files"],
}

#: Modules of the command line itself (their helpers are CLI glue, not library).
CLI_MODULES = ("cli", "_cli_rig", "_cli_evaluate", "_cli_fetch", "_cli_calibrated")

#: Library names a command imports that are not (yet) in their module's __all__.
#: Each entry is a known gap, to be removed once the module exports the name.
KNOWN_GAPS: set = set()


def _subcommands() -> set:
    parser = build_parser()
    actions = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return set(actions[0].choices)


def _resolve(name: str):
    if "." in name:
        module, attr = name.rsplit(".", 1)
        mod = importlib.import_module(f"nfdepth.{module}")
        assert attr in mod.__all__, f"{name}: not in nfdepth.{module}.__all__"
        return getattr(mod, attr)
    assert name in nfdepth.__all__, f"{name}: not in nfdepth.__all__"
    return getattr(nfdepth, name)


def test_table_covers_every_command():
    assert set(COMMANDS) == _subcommands()


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_command_functions_are_public_and_documented(command):
    for name in COMMANDS[command]:
        obj = _resolve(name)
        assert callable(obj), name
        doc = inspect.getdoc(obj) or ""
        assert len(doc) > 20, f"{name} has no docstring"


def test_top_level_exports_resolve():
    for name in nfdepth.__all__:
        assert getattr(nfdepth, name) is not None, name
    # the module docstring indexes the command functions
    for name in ("load_rig", "dynamic_stereo_from_videos", "depth_from_video", "evaluate_scene", "run_paper_experiment", "sgbm_disparity"):
        assert name in nfdepth.__doc__, name
    ns: dict = {}
    exec("from nfdepth import *", ns)  # noqa: S102 - star import resolves the lazy names
    assert {"load_rig", "RigError", "waxman_sinha_disparity"} <= set(ns)


def _library_imports(module: str):
    """(source module, name) of every relative import in a CLI module."""
    tree = ast.parse((SRC / f"{module}.py").read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            for alias in node.names:
                yield node.module, alias.name


@pytest.mark.parametrize("module", CLI_MODULES)
def test_commands_import_only_public_api(module):
    bad = []
    for source, name in _library_imports(module):
        if source is None:  # ``from . import plot``: a public sub-module or a package attribute
            assert not name.startswith("_") or name == "__version__", f"{module}: from . import {name}"
            continue
        if source in CLI_MODULES:
            continue
        mod = importlib.import_module(f"nfdepth.{source}")
        if name not in getattr(mod, "__all__", ()) and (source, name) not in KNOWN_GAPS:
            bad.append(f"from .{source} import {name}")
    assert not bad, f"{module} uses non-public library names: {bad}"
