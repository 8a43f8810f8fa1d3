"""Rig files: parsing, round trips, validation messages, and ``nfdepth dynamic``."""

from __future__ import annotations

import copy
import dataclasses
import re
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_runner import run_cli

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

import nfdepth.cli
from nfdepth import synthetic
from nfdepth.camera import RigidMotion
from nfdepth.rig import (
    Rig,
    RigError,
    dynamic_stereo_from_rig,
    edge_depth_maps,
    load_poses,
    load_rig,
    rig_from_dict,
    rig_to_toml,
    stereo_options_from_rig,
)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
PAPER_RIG = EXAMPLES / "paper_pyramid_rig.toml"
RAIL_RIG = EXAMPLES / "rail_camera_rig.toml"

BASE = {
    "camera": {"focal_px": 100.0, "width_px": 200, "height_px": 200},
    "motion": {"velocity": [2.0, 0.0, 0.0], "rotation_deg": [0.0, 0.0, 0.0], "frame_interval": 1.0},
    "stereo": {"baseline": 2.0, "axis": "x"},
    "video": {"velocity": [1.0, 0.0, 0.0]},
}


@pytest.fixture(autouse=True)
def plugin(monkeypatch):
    monkeypatch.setattr(nfdepth.cli, "_PLUGIN_COMMANDS", ("_cli_rig",))


# ------------------------------------------------------------------ parsing


def test_paper_example_rig():
    rig = load_rig(PAPER_RIG)
    assert rig.camera.focal_px == 100.0 and rig.camera.shape == (200, 200)
    assert rig.camera.cx_px == 99.5 and rig.camera.cy_px == 99.5
    # a camera moving with T = (2, 0, 0) sees the scene move with V = -T
    np.testing.assert_array_equal(rig.relative_motion().translation, [-2.0, 0.0, 0.0])
    np.testing.assert_array_equal(rig.relative_motion().rotation, [0.0, 0.0, 0.0])
    assert rig.frame_interval == 1.0
    assert stereo_options_from_rig(rig) == {
        "focal_px": 100.0, "baseline": 2.0, "axis": "x", "positions": None, "column_positions": None, "disparity_range_px": None,
        "disparity_offset_px": 0.0, "cx_px": 99.5, "cy_px": 99.5,
    }
    # the example matches the renderer's paper scene
    scene = synthetic.paper_dynamic_sequence(1)
    np.testing.assert_allclose(rig.relative_motion().translation, scene.relative_motion.translation)
    assert rig.camera == scene.camera


def test_rail_example_rig():
    rig = load_rig(RAIL_RIG)
    assert rig.camera.shape == (480, 640)
    np.testing.assert_array_equal(rig.video.camera_position(3), [0.006, 0.0, 0.0])
    assert rig.motion is None
    with pytest.raises(RigError, match=r"no \[motion\] section"):
        rig.relative_motion()


def test_rotation_degrees_converted_to_radians():
    d = copy.deepcopy(BASE)
    d["motion"]["rotation_deg"] = [0.0, 0.0, 0.5]
    m = rig_from_dict(d).relative_motion()
    assert isinstance(m, RigidMotion)
    np.testing.assert_allclose(m.rotation, [0.0, 0.0, -np.deg2rad(0.5)])


@pytest.mark.parametrize("path", [PAPER_RIG, RAIL_RIG, EXAMPLES / "passing_cameras_rig.toml", EXAMPLES / "rectified_pair_rig.toml"])
def test_round_trip_examples(path):
    rig = load_rig(path)
    again = rig_from_dict(tomllib.loads(rig_to_toml(rig)))
    assert again == rig


def test_a_rig_file_refuses_what_it_cannot_hold():
    """Per-frame orientations given in code (depth_from_video's orientations_rad) and poses not read from a file
    have no place in a rig file: writing the rest would read back as a rig that does not turn (it was dropped
    without a word) or fail on a bare assert."""

    from nfdepth.rig import Poses, VideoSpec

    rig = rig_from_dict(copy.deepcopy(BASE))
    positions = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]])
    turning = dataclasses.replace(rig, video=VideoSpec(positions=positions, orientations_deg=np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.0]])))
    with pytest.raises(ValueError, match=r"^rig.video has per-frame orientations \(orientations_deg\), which a rig file cannot hold: .* video.poses$"):
        rig_to_toml(turning)
    # orientations of zero are the file's own default: written as positions, they read back the same motion
    still = dataclasses.replace(rig, video=VideoSpec(positions=positions, orientations_deg=np.zeros((3, 3))))
    again = rig_from_dict(tomllib.loads(rig_to_toml(still)))
    np.testing.assert_array_equal(again.video.positions, positions)
    assert np.all(again.video.orientation_deg(2) == 0)
    unsaved = dataclasses.replace(rig, video=VideoSpec(poses=Poses(np.arange(3), positions, np.zeros((3, 3)))))
    with pytest.raises(ValueError, match=r"^rig.video has poses that were not read from a file"):
        rig_to_toml(unsaved)


def test_round_trip_all_sections(tmp_path):
    d = copy.deepcopy(BASE)
    d["camera"].update(cx_px=101.25, cy_px=98.0)
    d["stereo"] = {"baseline": 0.5, "direction": [0.0, 2.0, 0.0], "positions": [0.0, 1.0, 2.5]}
    d["video"] = {"positions": [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.25, 0.0, 0.0]]}
    rig = rig_from_dict(d)
    np.testing.assert_array_equal(rig.stereo.direction, [0.0, 1.0, 0.0])
    assert stereo_options_from_rig(rig) == {
        "focal_px": 100.0, "baseline": 0.5, "axis": "y", "positions": [0.0, 1.0, 2.5], "column_positions": None, "disparity_range_px": None,
        "disparity_offset_px": 0.0, "cx_px": 101.25, "cy_px": 98.0,
    }
    assert rig_from_dict(tomllib.loads(rig_to_toml(rig))) == rig
    # a row along x with a column through its reference (x and y baselines)
    cross = copy.deepcopy(d)
    cross["stereo"] = {"baseline": 0.5, "axis": "x", "column_positions": [-1.0, 0.0, 2.0]}
    rig = rig_from_dict(cross)
    assert stereo_options_from_rig(rig)["column_positions"] == [-1.0, 0.0, 2.0]
    assert rig_from_dict(tomllib.loads(rig_to_toml(rig))) == rig
    assert rig != rig_from_dict(d)
    # a disparity range to search, as nfdepth stereo --disparity-range
    ranged = copy.deepcopy(d)
    ranged["stereo"]["disparity_range_px"] = [2, 40.5]
    rig = rig_from_dict(ranged)
    assert rig.stereo.disparity_range_px == (2.0, 40.5)
    assert stereo_options_from_rig(rig)["disparity_range_px"] == [2.0, 40.5]
    assert rig_from_dict(tomllib.loads(rig_to_toml(rig))) == rig
    assert rig != rig_from_dict(d)
    # principal points that differ along the row (Middlebury's doffs), as nfdepth stereo --disparity-offset-px
    shifted = copy.deepcopy(d)
    shifted["stereo"]["disparity_offset_px"] = -31.086
    rig = rig_from_dict(shifted)
    assert rig.stereo.disparity_offset_px == -31.086
    assert stereo_options_from_rig(rig)["disparity_offset_px"] == -31.086
    assert "disparity_offset_px = -31.086" in rig_to_toml(rig)
    assert rig_from_dict(tomllib.loads(rig_to_toml(rig))) == rig
    assert rig != rig_from_dict(d)
    assert "disparity_offset_px" not in rig_to_toml(rig_from_dict(d))  # 0 is the default: not written
    (tmp_path / "p.csv").write_text("frame,x,y,z\n0,0,0,0\n1,0.5,0,0\n2,1.0,0,0\n")
    d["video"] = {"poses": "p.csv"}
    rig = rig_from_dict(d, base_dir=tmp_path)
    assert rig_from_dict(tomllib.loads(rig_to_toml(rig))) == rig


def test_crossings_round_trip():
    d = copy.deepcopy(BASE)
    d["motion"]["crossings"] = [4, 12.0]
    rig = rig_from_dict(d)
    assert rig.motion.crossings == (4, 12)
    assert rig_from_dict(tomllib.loads(rig_to_toml(rig))) == rig
    assert load_rig(PAPER_RIG).motion.crossings is None


def test_poses_relative_to_rig_folder(tmp_path):
    sub = tmp_path / "rig"
    sub.mkdir()
    (sub / "poses.csv").write_text("frame,x,y,z,rx,ry,rz\n# comment\n0,0,0,0,0,0,0\n1,0.5,0,0,0,0,0\n2,1.0,0.1,0,0,0,0\n")
    (sub / "rig.toml").write_text('[camera]\nfocal_px = 50\nwidth_px = 20\nheight_px = 10\n[video]\nposes = "poses.csv"\n')
    rig = load_rig(sub / "rig.toml")
    np.testing.assert_array_equal(rig.video.camera_position(2), [1.0, 0.1, 0.0])
    with pytest.raises(RigError, match=r"no row for frame 3"):
        rig.video.camera_position(3)


def test_missing_poses_file_names_the_rig(tmp_path, capsys):
    """A rig whose video.poses names no file: the message names the rig file, its value and the CSV looked for (exit code 3 as before)."""
    sub = tmp_path / "rig"
    sub.mkdir()
    rig = sub / "rig.toml"
    rig.write_text('[camera]\nfocal_px = 50\nwidth_px = 20\nheight_px = 10\n[video]\nposes = "poses.csv"\n')
    message = f"rig '{rig}': video.poses = 'poses.csv': cannot read poses file '{sub / 'poses.csv'}': no such file"
    with pytest.raises(FileNotFoundError) as info:
        load_rig(rig)
    assert str(info.value) == message
    code, out, err = run_cli(capsys, "video", tmp_path / "frames", "--rig", rig, "--out", tmp_path / "depth.npz")
    assert (code, out, err) == (3, "", f"nfdepth: error: {message}\n")
    (sub / "poses.csv").mkdir()
    with pytest.raises(FileNotFoundError) as info:
        load_rig(rig)
    assert str(info.value) == f"rig '{rig}': video.poses = 'poses.csv': cannot read poses file '{sub / 'poses.csv'}': it is a directory"
    with pytest.raises(FileNotFoundError) as info:  # without a file: the key and its value
        rig_from_dict({"camera": {"focal_px": 50, "width_px": 20, "height_px": 10}, "video": {"poses": "p.csv"}}, base_dir=sub)
    assert str(info.value) == f"video.poses = 'p.csv': cannot read poses file '{sub / 'p.csv'}': no such file"


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda d: d.pop("camera"), r"camera is missing"),
        (lambda d: d["camera"].pop("focal_px"), r"camera\.focal_px is missing"),
        (lambda d: d["camera"].update(focal_px=-100.0), r"camera\.focal_px = -100\.0: expected a number > 0"),
        (lambda d: d["camera"].update(focal_px="100"), r"camera\.focal_px = '100': expected a finite number"),
        (lambda d: d["camera"].update(width_px=200.5), r"camera\.width_px = 200\.5: expected a positive integer"),
        (lambda d: d["camera"].pop("width_px"), r"^camera\.width_px is missing: expected a positive integer \(pixels\)$"),
        (lambda d: d["video"].pop("velocity") and d["video"].update(poses=5), r"^video\.poses = 5: expected a path to a CSV file \(frame,x,y,z\[,rx,ry,rz\]\)$"),
        (lambda d: d["video"].pop("velocity") and d["video"].update(poses=""), r"^video\.poses = '': expected a path to a CSV file"),
        (lambda d: d["camera"].update(height_px=0), r"camera\.height_px = 0: expected a positive integer"),
        (lambda d: d["camera"].update(focal=100), r"camera\.focal: unknown key"),
        (lambda d: d.update(extra={}), r"rig\.extra: unknown key"),
        (lambda d: d.update(camera=5), r"camera = 5: expected a table"),
        (lambda d: d["motion"].pop("velocity"), r"motion\.velocity is missing"),
        (lambda d: d["motion"].update(velocity=[0.0, 0.0, 0.0]), r"motion\.velocity = \[0\.0, 0\.0, 0\.0\]: expected a non-zero translation"),
        (lambda d: d["motion"].update(velocity=[1.0, 2.0]), r"motion\.velocity = \[1\.0, 2\.0\]: expected 3 finite numbers"),
        (lambda d: d["motion"].update(rotation_deg="fast"), r"motion\.rotation_deg = 'fast': expected 3 finite numbers"),
        (lambda d: d["motion"].update(frame_interval=0), r"motion\.frame_interval = 0: expected a number > 0"),
        (lambda d: d["motion"].update(frame_interval=1e-300), r"motion\.frame_interval = 1e-300: expected a time step within 1e-30\.\.5e\+29"),
        # dynamic_stereo's bound (I1, I3, I5 two intervals apart): 6e29 passed the parser, then was refused without the key
        (lambda d: d["motion"].update(frame_interval=6e29),
         r"^motion\.frame_interval = 6e\+29: expected a time step within 1e-30\.\.5e\+29 \(the moving camera's images I1, I3, I5 are two intervals apart; give times"),
        (lambda d: d["camera"].update(focal_px=1e300), r"camera\.focal_px = 1e\+300: expected a focal length of 1e-30 to 1e\+30 \(give it in a unit"),
        (lambda d: d["motion"].update(velocity=[1e300, 0.0, 0.0]), r"motion\.velocity = \[1e\+300, 0\.0, 0\.0\]: expected a speed of 1e-30 to 1e\+30"),
        (lambda d: d["stereo"].update(baseline=1e-300), r"stereo\.baseline = 1e-300: expected a baseline of 1e-30 to 1e\+30"),
        (lambda d: d["stereo"].update(baseline=0.0), r"stereo\.baseline = 0\.0: expected a number > 0"),
        (lambda d: d["stereo"].pop("baseline"), r"stereo\.baseline is missing"),
        (lambda d: d["stereo"].update(axis="z"), r"stereo\.axis = 'z': expected \"x\" or \"y\""),
        (lambda d: d["stereo"].update(direction=[1, 0, 0]), r"stereo: axis and direction contradict each other"),
        (lambda d: d["stereo"].update(axis=None) or d["stereo"].pop("axis") or d["stereo"].update(direction=[0, 0, 0]), r"stereo\.direction = \[0, 0, 0\]: expected a non-zero"),
        (lambda d: d["stereo"].update(positions=[0, 2, 1]), r"stereo\.positions = \[0, 2, 1\]: expected strictly increasing"),
        (lambda d: d["stereo"].update(positions=[0]), r"stereo\.positions = \[0\]: expected a list of 2 or more"),
        (lambda d: d["stereo"].update(column_positions=[1, 0]), r"stereo\.column_positions = \[1, 0\]: expected strictly increasing"),
        (lambda d: d["stereo"].update(column_positions="0 1"), r"stereo\.column_positions = '0 1': expected a list of 2 or more"),
        (lambda d: d["stereo"].update(axis="y", column_positions=[0, 1]), r"stereo\.column_positions = \[0, 1\]: expected a row along x"),
        (lambda d: d["stereo"].update(disparity_range_px=[40, 2]), r"stereo\.disparity_range_px = \[40, 2\]: expected \[smallest, largest\] disparity .* smallest first"),
        (lambda d: d["stereo"].update(disparity_range_px=[5, 5]), r"stereo\.disparity_range_px = \[5, 5\]: expected \[smallest, largest\]"),
        (lambda d: d["stereo"].update(disparity_range_px=[0, float("inf")]), r"stereo\.disparity_range_px = \[0, inf\]: expected .*two finite numbers"),
        (lambda d: d["stereo"].update(disparity_range_px=[0, 8, 16]), r"stereo\.disparity_range_px = \[0, 8, 16\]: expected"),
        (lambda d: d["stereo"].update(disparity_range_px=64), r"stereo\.disparity_range_px = 64: expected"),
        (lambda d: d["stereo"].update(disparity_offset_px="31"), r"stereo\.disparity_offset_px = '31': expected a finite number of px per unit of position within \+-1e\+06"),
        (lambda d: d["stereo"].update(disparity_offset_px=float("nan")), r"stereo\.disparity_offset_px = nan: expected a finite number"),
        (lambda d: d["stereo"].update(disparity_offset_px=1e300), r"stereo\.disparity_offset_px = 1e\+300: expected .*a value beyond is another unit or a typo"),
        (lambda d: d["stereo"].update(disparity_offset_px=True), r"stereo\.disparity_offset_px = True: expected a finite number"),
        (lambda d: d["stereo"].update(disparity_offset_px=2.0, column_positions=[0, 1, 2]), r"stereo\.disparity_offset_px = 2\.0: expected 0 with column_positions"),
        (lambda d: d["video"].update(positions=[[0, 0, 0]] * 3), r"video: velocity and positions contradict each other"),
        (lambda d: d["video"].update(poses="p.csv"), r"video: velocity and poses contradict each other"),
        (lambda d: d["video"].pop("velocity"), r"video: expected one of velocity, positions, poses"),
        (lambda d: d["video"].update(velocity=[0, 0, 0]), r"video\.velocity = \[0, 0, 0\]: expected a non-zero camera translation"),
        (lambda d: d["video"].update(velocity=[0, 1e-300, 0]), r"video\.velocity = \[0, 1e-300, 0\]: expected a speed of 1e-30 to 1e\+30"),
        (lambda d: d["video"].pop("velocity") and d["video"].update(positions=[[0, 0]]), r"video\.positions = \[\[0, 0\]\]: expected a list of 3 or more"),
        (lambda d: d["motion"].update(crossings=[1, 5]), r"motion\.crossings = \[1, 5\]: expected .*frame 1 has no two frames before it"),
        (lambda d: d["motion"].update(crossings=[5, 5]), r"motion\.crossings = \[5, 5\]: expected .*strictly increasing"),
        (lambda d: d["motion"].update(crossings=[]), r"motion\.crossings = \[\]: expected a non-empty list"),
        (lambda d: d["motion"].update(crossings=4), r"motion\.crossings = 4: expected a non-empty list"),
        (lambda d: d["motion"].update(crossings=[4.5]), r"motion\.crossings = \[4\.5\]: expected a non-empty list of frame indices"),
        # beyond the float range (were accepted: overflow warnings, then wrong messages or an empty map)
        (lambda d: d["camera"].update(cx_px=1e300), r"^camera\.cx_px = 1e\+300: expected a principal point within 1e\+06 px of the image centre 99\.5 \(the larger of"),
        (lambda d: d["camera"].update(cy_px=-2e6), r"^camera\.cy_px = -2000000\.0: expected a principal point within 1e\+06 px of the image centre 99\.5"),
        (lambda d: d["motion"].update(rotation_deg=[0.0, 0.0, 1e300]),
         r"^motion\.rotation_deg = \[0\.0, 0\.0, 1e\+300\]: expected an angular velocity of at most 90 degrees per frame interval, got 1e\+300 degrees per frame_interval = 1\.0 \(the moving camera's images"),
        (lambda d: d["motion"].update(rotation_deg=[0.0, 0.0, 1e30]), r"^motion\.rotation_deg = \[0\.0, 0\.0, 1e\+30\]: expected an angular velocity of at most 90 degrees per frame interval"),
        (lambda d: d["motion"].update(rotation_deg=[0.0, 0.0, 9e31], frame_interval=1e-30),  # 90 degrees per frame, but beyond RigidMotion's range
         r"^motion\.rotation_deg = \[0\.0, 0\.0, 9e\+31\]: expected an angular velocity of at most 1e\+30 rad \(5\.73e\+31 degrees\) per unit time"),
        (lambda d: d["motion"].update(rotation_deg=[70.0, 70.0, 0.0]), r"^motion\.rotation_deg = \[70\.0, 70\.0, 0\.0\]: expected .* got 98\.99 degrees per"),
        (lambda d: d["motion"].update(rotation_deg=[0.0, 60.0, 0.0], frame_interval=2.0), r"^motion\.rotation_deg = \[0\.0, 60\.0, 0\.0\]: expected .* got 120 degrees per frame_interval = 2\.0"),
        (lambda d: d["video"].pop("velocity") and d["video"].update(positions=[[0, 0, 0], [1e300, 0, 0], [2e300, 0, 0]]),
         r"^video\.positions: the camera moves from \(0, 0, 0\) at frame 0 to \(1e\+300, 0, 0\) at frame 1, a step of 1e\+300: expected a speed of 1e-30 to 1e\+30 per frame, or 0 where it stands still"),
    ],
)
def test_validation_errors(edit, match):
    d = copy.deepcopy(BASE)
    edit(d)
    with pytest.raises(RigError, match=match):
        rig_from_dict(d)


def test_rotation_and_principal_point_range_ends_accepted():
    d = copy.deepcopy(BASE)
    d["motion"].update(rotation_deg=[60.0, 60.0, 0.0])  # 84.85 degrees per frame interval, under 90 (the norm counts, not a component)
    np.testing.assert_allclose(rig_from_dict(d).relative_motion().rotation, -np.deg2rad([60.0, 60.0, 0.0]), rtol=1e-15)
    d["motion"].update(rotation_deg=[0.0, 0.0, 45.0], frame_interval=2.0)  # 90 degrees per frame interval
    assert rig_from_dict(d).motion.rotation_deg.tolist() == [0.0, 0.0, 45.0]
    d["camera"].update(cx_px=99.5 + 1e6, cy_px=99.5 - 1e6)
    assert rig_from_dict(d).camera.cx_px == 99.5 + 1e6


def test_stereo_direction_must_be_axis_for_stereo_command():
    d = copy.deepcopy(BASE)
    d["stereo"] = {"baseline": 1.0, "direction": [1.0, 1.0, 0.0]}
    rig = rig_from_dict(d)
    with pytest.raises(RigError, match=r"stereo\.direction = .*expected \[1, 0, 0\] or \[0, 1, 0\]"):
        stereo_options_from_rig(rig)
    with pytest.raises(RigError, match=r"no \[stereo\] section"):
        stereo_options_from_rig(rig_from_dict({"camera": BASE["camera"]}))


@pytest.mark.parametrize(
    ("direction", "shown"),
    [([0, 0, 1], "[0, 0, 1]"), ([0.0, 0.0, -3.0], "[0, 0, -1]"), ([1, 1, 0], "[0.707107, 0.707107, 0]")],
)
def test_stereo_direction_message_names_the_file_and_plain_numbers(tmp_path, direction, shown):
    path = tmp_path / "tilted.toml"
    path.write_text(f"[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[stereo]\nbaseline = 1\ndirection = {direction}\n")
    rig = load_rig(path)
    with pytest.raises(RigError) as info:
        stereo_options_from_rig(rig)
    assert str(info.value) == (
        f"rig '{path}': stereo.direction = {shown}: expected [1, 0, 0] or [0, 1, 0] for nfdepth stereo "
        "(order the views so the camera moves toward +x or +y)"
    )
    assert "np." not in str(info.value)


def test_stereo_direction_message_without_a_file():
    d = copy.deepcopy(BASE)
    d["stereo"] = {"baseline": 1.0, "direction": [0, 0, 1]}
    with pytest.raises(RigError, match=r"^stereo\.direction = \[0, 0, 1\]: expected \[1, 0, 0\] or \[0, 1, 0\]"):
        stereo_options_from_rig(rig_from_dict(d))


@pytest.mark.parametrize(
    ("stereo", "counts", "message"),
    [
        ("positions = [0, 1]", {"n_views": 3}, "stereo.positions has 2 entries, expected one per view (3)"),
        ("positions = [0, 1, 2, 4]", {"n_views": 3}, "stereo.positions has 4 entries, expected one per view (3)"),
        (
            "positions = [0, 1, 2]\ncolumn_positions = [0, 1, 2]",
            {"n_views": 3, "n_column_views": 2},
            "stereo.column_positions has 3 entries, expected one per column view (2)",
        ),
    ],
)
def test_stereo_positions_count_names_the_file_and_key(tmp_path, stereo, counts, message):
    path = tmp_path / "x.toml"
    path.write_text(f"[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[stereo]\nbaseline = 1\n{stereo}\n")
    rig = load_rig(path)
    with pytest.raises(RigError) as info:
        stereo_options_from_rig(rig, **counts)
    assert str(info.value) == f"rig '{path}': {message}"
    # without the numbers of views (the default) the counts are not checked
    assert stereo_options_from_rig(rig)["positions"] == [float(v) for v in tomllib.loads(path.read_text())["stereo"]["positions"]]


def test_stereo_positions_count_that_matches_passes():
    d = copy.deepcopy(BASE)
    d["stereo"].update(positions=[0, 1, 2.5], column_positions=[0, 2])
    opts = stereo_options_from_rig(rig_from_dict(d), n_views=3, n_column_views=2)
    assert opts["positions"] == [0.0, 1.0, 2.5] and opts["column_positions"] == [0.0, 2.0]
    with pytest.raises(RigError, match=r"^stereo\.positions has 3 entries, expected one per view \(4\)$"):
        stereo_options_from_rig(rig_from_dict(d), n_views=4)


@pytest.mark.parametrize(
    ("counts", "error", "message"),
    [
        ({"n_views": 0}, ValueError, "n_views must be an integer >= 1, got 0"),
        ({"n_views": -3}, ValueError, "n_views must be an integer >= 1, got -3"),
        ({"n_views": "3"}, TypeError, "n_views must be an integer >= 1, got '3' (str, not a number)"),
        ({"n_views": 3.0}, TypeError, "n_views must be an integer >= 1, got 3.0 (float; give an int such as 3)"),
        ({"n_views": True}, TypeError, "n_views must be an integer >= 1, got True (bool, not a number)"),
        ({"n_views": 3, "n_column_views": 0}, ValueError, "n_column_views must be an integer >= 1, got 0"),
    ],
)
def test_stereo_options_refuse_a_view_count_that_is_no_count(counts, error, message):
    """Without positions in the rig nothing was compared, so any n_views passed; with them, '3' read as a mismatch."""
    for stereo in ({"baseline": 2.0}, {"baseline": 2.0, "positions": [0, 1, 2.5], "column_positions": [0, 2]}):
        d = copy.deepcopy(BASE)
        d["stereo"] = stereo
        with pytest.raises(error) as info:
            stereo_options_from_rig(rig_from_dict(d), **counts)
        assert type(info.value) is error and str(info.value) == message


def test_load_rig_file_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        load_rig(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[camera\nfocal_px = 1\n")
    with pytest.raises(RigError, match=r"bad\.toml'?: not valid TOML"):
        load_rig(bad)
    neg = tmp_path / "neg.toml"
    neg.write_text("[camera]\nfocal_px = -100\nwidth_px = 200\nheight_px = 200\n")
    with pytest.raises(RigError, match=r"neg\.toml': camera\.focal_px = -100: expected a number > 0"):
        load_rig(neg)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", r"the file is empty"),
        ("frame,x,y\n0,0,0\n", r"line 1: header 'frame,x,y'"),
        ("frame,x,y,z\n0,0,0\n", r"line 2: 3 columns: expected 4"),
        ("frame,x,y,z\n0.5,0,0,0\n", r"line 2: frame = '0.5': expected an integer"),
        ("frame,x,y,z\nfirst,0,0,0\n", r"line 2: frame = 'first': expected an integer frame index$"),
        ("frame,x,y,z\n-1,0,0,0\n", r"line 2: frame = '-1': expected an integer frame index >= 0$"),
        ("frame,x,y,z\n0,0,abc,0\n", r"line 2: y = 'abc': expected a finite number"),
        ("frame,x,y,z\n1,0,0,0\n0,1,0,0\n", r"line 3: frame indices must be strictly increasing"),
        # beyond int64: was an OverflowError (an internal error in the CLI); from 2**53 whole numbers are no longer exact as floats
        ("frame,x,y,z\n0,0,0,0\n9223372036854775808,0.1,0,0\n",
         r"line 3: frame = '9223372036854775808': expected a frame index below 9007199254740992 \(2\*\*53, where whole numbers stop being exact in floating point\)$"),
        ("frame,x,y,z\n9007199254740992,0,0,0\n", r"line 2: frame = '9007199254740992': expected a frame index below 9007199254740992"),
        ("frame,x,y,z\n1e300,0,0,0\n", r"line 2: frame = '1e300': expected a frame index below"),
        ("frame,x,y,z\n", r"no data rows"),
    ],
)
def test_poses_errors(tmp_path, text, match):
    p = tmp_path / "p.csv"
    p.write_text(text)
    with pytest.raises(RigError, match=match):
        load_poses(p)


def test_image_size_checked_at_use():
    rig = rig_from_dict(BASE)
    rig.check_image_shape((200, 200))
    with pytest.raises(RigError, match=r"camera\.width_px x camera\.height_px = 200x200 does not match image I1 \(160x120\)"):
        dynamic_stereo_from_rig([np.zeros((120, 160))] * 5, rig)
    with pytest.raises(ValueError, match="exactly 5 images"):
        dynamic_stereo_from_rig([np.zeros((200, 200))] * 4, rig)


# ------------------------------------------------------------------ nfdepth dynamic


@pytest.fixture(scope="module")
def paper_scene():
    return synthetic.paper_dynamic_sequence(1)


@pytest.fixture
def paper_pngs(tmp_path, paper_scene):
    paths = []
    for k, frame in enumerate(paper_scene.frames, 1):
        p = tmp_path / f"I{k}.png"
        assert cv2.imwrite(str(p), np.round(frame * 256).astype(np.uint16))  # 16-bit: no 8-bit quantisation
        paths.append(p)
    return paths


def test_library_matches_truth(paper_scene):
    rig = load_rig(PAPER_RIG)
    res = dynamic_stereo_from_rig(list(paper_scene.frames), rig)
    ok = res.valid
    err = np.abs(res.depth[ok] - paper_scene.depth_at(res.rows[ok], res.cols[ok])) / paper_scene.depth_at(res.rows[ok], res.cols[ok])
    assert ok.sum() > 300 and np.max(err) < 0.02
    depth, std = edge_depth_maps(res)
    assert depth.shape == (200, 200) and np.isfinite(depth).sum() == ok.sum()
    assert np.all(np.isfinite(std[np.isfinite(depth)]))


def test_dynamic_cli_end_to_end(tmp_path, capsys, paper_scene, paper_pngs):
    out, unc, csv, ply, png = (tmp_path / n for n in ("z.tif", "s.tif", "z.csv", "z.ply", "z.png"))
    code, stdout, err = run_cli(
        capsys, "dynamic", *paper_pngs, "--rig", PAPER_RIG, "--out", out, "--uncertainty", unc, "--csv", csv, "--ply", ply, "--preview", png
    )
    assert code == 0, err
    assert "edge points of I3" in stdout
    # the points without depth, by reason (the paper's pyramid: edges along the relative flow)
    assert re.search(r"depth at \d+ of \d+ edge points of I3 \(I3\.png; \d+ undeterminable \(edges along the relative flow\)\), range ", stdout), stdout
    pts = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert pts.shape[0] > 300
    true = paper_scene.depth_at(pts[:, 0], pts[:, 1])
    rel = np.abs(pts[:, 2] - true) / true
    assert np.median(rel) < 0.01 and np.max(rel) < 0.03  # measured: median 0.3 %, max 0.7 %
    assert np.all(pts[:, 3] >= 0)
    import tifffile

    z = tifffile.imread(out)
    assert z.shape == (200, 200) and z.dtype == np.float32
    assert np.isfinite(z).sum() == pts.shape[0]
    ii, jj = np.floor(pts[:, 0]).astype(int), np.floor(pts[:, 1]).astype(int)
    np.testing.assert_allclose(z[ii, jj], pts[:, 2], rtol=1e-5)
    assert ply.read_bytes().startswith(b"ply") and png.read_bytes()[:4] == b"\x89PNG"
    # an existing output is kept without --force
    code, _, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", PAPER_RIG, "--out", out)
    assert code == 4 and "--force" in err and err.count("\n") == 1


def test_dynamic_cli_matches_the_other_cameras_exposure(tmp_path, capsys, paper_scene):
    """I2 and I4 (the reference camera) at ``0.8 I + 10``, as 16-bit PNGs: the run says what it matched (the offset in
    the files' grey levels, 2560) and its depths are the equal cameras' (measured median 0.29 %, max 0.68 %; equal: 0.3 %, 0.7 %);
    ``--no-match-exposure`` takes them as they are (median 1.7 %, max 5.1 %)."""
    paths = []
    for k, frame in enumerate(paper_scene.frames, 1):
        lit = 0.8 * frame + 10.0 if k in (2, 4) else frame
        paths.append(tmp_path / f"I{k}.png")
        assert cv2.imwrite(str(paths[-1]), np.round(lit * 256).astype(np.uint16))

    def errors(out, *extra):
        csv = tmp_path / f"{out}.csv"
        code, stdout, err = run_cli(capsys, "dynamic", *paths, "--rig", PAPER_RIG, "--out", tmp_path / f"{out}.tif", "--csv", csv, *extra)
        assert code == 0, err
        pts = np.loadtxt(csv, delimiter=",", skiprows=1)
        true = paper_scene.depth_at(pts[:, 0], pts[:, 1])
        return stdout, np.abs(pts[:, 2] - true) / true

    stdout, rel = errors("matched")
    assert re.search(r", exposure matched to I3 \(I2 gain 0\.8 offset \+25[56]\d; I4 gain 0\.8 offset \+25[56]\d\) -> ", stdout), stdout
    assert rel.size > 300 and np.median(rel) < 0.005 and np.max(rel) < 0.02
    stdout, raw = errors("raw", "--no-match-exposure")
    assert "exposure matched" not in stdout and np.median(raw) > 0.01


def _write_rig(tmp_path, text, name="rig.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("rig_text", "n_images", "code", "fragment"),
    [
        ("[camera]\nfocal_px = -100\nwidth_px = 200\nheight_px = 200\n[motion]\nvelocity = [2, 0, 0]\n", 5, 2, "camera.focal_px = -100: expected a number > 0"),
        ("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[motion]\nvelocity = [2, 0, 0]\nposition = [0, 0, 0]\n", 5, 2, "motion.position: unknown key"),
        ("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n", 5, 2, "no [motion] section"),
        ("[camera]\nfocal_px = 100\nwidth_px = 320\nheight_px = 200\n[motion]\nvelocity = [2, 0, 0]\n", 5, 2, "= 320x200 (rig.toml) does not match I1 'I1.png' (200x200)"),
        (PAPER_RIG.read_text(), 4, 2, "dynamic needs exactly 5 images"),
        ("not = [toml", 5, 2, "not valid TOML"),
        # were: overflow warnings and exit 0 with an empty map; a negative-inverse-depth warning and a message blaming focal length and speeds
        ("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\ncx_px = 1e300\n[motion]\nvelocity = [2, 0, 0]\n", 5, 2,
         "camera.cx_px = 1e+300: expected a principal point within 1e+06 px of the image centre 99.5"),
        ("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[motion]\nvelocity = [2, 0, 0]\nrotation_deg = [0, 0, 1e300]\n", 5, 2,
         "motion.rotation_deg = [0, 0, 1e+300]: expected an angular velocity of at most 90 degrees per frame interval"),
        ("[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n[motion]\nvelocity = [2, 0, 0]\nrotation_deg = [0, 0, 1e30]\n", 5, 2,
         "motion.rotation_deg = [0, 0, 1e+30]: expected an angular velocity of at most 90 degrees per frame interval"),
    ],
)
def test_dynamic_cli_errors(tmp_path, capsys, paper_pngs, rig_text, n_images, code, fragment):
    rig = _write_rig(tmp_path, rig_text)
    got, out, err = run_cli(capsys, "dynamic", *paper_pngs[:n_images], "--rig", rig, "--out", tmp_path / "z.tif")
    assert got == code, err
    assert fragment in err and err.startswith("nfdepth: error:") and err.count("\n") == 1
    assert not (tmp_path / "z.tif").exists()


def test_dynamic_cli_names_an_image_with_nan(tmp_path, capsys, paper_pngs):
    holed = cv2.imread(str(paper_pngs[3]), cv2.IMREAD_UNCHANGED).astype(np.float32)
    holed[10:20, 10:20] = np.nan
    np.save(tmp_path / "I4.npy", holed)
    images = [*paper_pngs[:3], tmp_path / "I4.npy", paper_pngs[4]]
    code, _, err = run_cli(capsys, "dynamic", *images, "--rig", PAPER_RIG, "--out", tmp_path / "z.tif")
    assert code == 2 and err.strip() == "nfdepth: error: I4 'I4.npy' contains 100 non-finite (NaN or inf) pixel(s); expected finite intensities", err  # was: frames[3] ...
    assert not (tmp_path / "z.tif").exists()


def test_dynamic_cli_missing_rig(tmp_path, capsys, paper_pngs):
    code, _, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", tmp_path / "nope.toml", "--out", tmp_path / "z.tif")
    assert code == 3 and "nope.toml" in err and err.count("\n") == 1


def test_dynamic_cli_figure(tmp_path, capsys, paper_pngs):
    out, unc, fig = tmp_path / "z.tif", tmp_path / "s.tif", tmp_path / "fig.png"
    code, _, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", PAPER_RIG, "--out", out, "--figure", fig)
    assert code == 0, err
    assert fig.read_bytes()[:4] == b"\x89PNG" and not (tmp_path / "fig_std.png").exists()  # no --uncertainty: no std figure
    code, _, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", PAPER_RIG, "--out", out, "--uncertainty", unc, "--figure", fig, "--force")
    assert code == 0, err
    assert (tmp_path / "fig_std.png").read_bytes()[:4] == b"\x89PNG"
    code, _, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", PAPER_RIG, "--out", tmp_path / "y.tif", "--figure", tmp_path / "z.tif")
    assert code == 2 and "--figure" in err and ".png" in err


def test_rig_from_dict_top_level_and_whole_number_sizes():
    with pytest.raises(RigError, match=r"^rig: expected a table of sections, got list$"):
        rig_from_dict([BASE])
    d = copy.deepcopy(BASE)
    d["camera"].update(width_px=320.0, height_px=240.0)  # TOML floats with a whole value: sizes in pixels
    cam = rig_from_dict(d).camera
    assert (cam.width_px, cam.height_px) == (320, 240) and type(cam.width_px) is int
    assert cam.cx_px == 159.5 and cam.cy_px == 119.5


def test_rig_from_dict_takes_numpy_scalars():
    """The library takes NumPy scalars where it takes Python numbers (test_bad_input); a dict built from a calibration holds them."""
    d = copy.deepcopy(BASE)
    d["camera"].update(focal_px=np.float32(100.0), width_px=np.int64(200), height_px=np.int32(200))
    d["motion"].update(velocity=[np.float32(2.0), 0.0, 0.0])
    assert rig_from_dict(d) == rig_from_dict(BASE)  # was: RigError "camera.focal_px = 100.0: expected a finite number"


def test_load_rig_that_is_not_utf8(tmp_path, capsys, paper_pngs):
    rig = tmp_path / "latin1.toml"
    rig.write_bytes("# caméra\n[camera]\nfocal_px = 100\nwidth_px = 200\nheight_px = 200\n".encode("latin-1"))
    with pytest.raises(RigError, match=rf"^rig '{re.escape(str(rig))}': not a UTF-8 text file$"):
        load_rig(rig)
    code, out, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", rig, "--out", tmp_path / "z.tif")
    assert (code, out, err) == (2, "", f"nfdepth: error: rig '{rig}': not a UTF-8 text file\n")
    with pytest.raises(FileNotFoundError, match=rf"^cannot read rig file '{re.escape(str(tmp_path))}': it is a directory$"):
        load_rig(tmp_path)
    with pytest.raises(FileNotFoundError, match=rf"^cannot read poses file '{re.escape(str(tmp_path / 'p.csv'))}': no such file$"):
        load_poses(tmp_path / "p.csv")
    with pytest.raises(FileNotFoundError, match=rf"^cannot read poses file '{re.escape(str(tmp_path))}': it is a directory$"):
        load_poses(tmp_path)


def test_dynamic_cli_ply_colours_with_lens_distortion(tmp_path, capsys, paper_scene):
    """With ``[camera] distortion`` the points lie on the undistorted grid of I3: their colours are the undistorted I3's
    there. They were the distorted I3's, read where the lens had moved the scene: a mean 33 grey levels from the pinhole
    camera's I3 at the points (measured; 4.7 now, the resampling's blur of the edges the points lie on)."""
    from scipy import ndimage

    from nfdepth.io import read_image
    from nfdepth.rectify import CalibratedCamera

    text = PAPER_RIG.read_text().replace("height_px = 200\n", "height_px = 200\ndistortion = [-0.1, 0.02, 0.0005, -0.0005]\n")
    rig_file = tmp_path / "lens.toml"
    rig_file.write_text(text)
    rig = load_rig(rig_file)
    assert any(rig.distortion)
    cam = rig.camera
    matrix = np.array([[cam.focal_px, 0.0, cam.cx_px], [0.0, cam.focal_px, cam.cy_px], [0.0, 0.0, 1.0]])
    lens = CalibratedCamera(matrix=matrix, width_px=200, height_px=200, position=np.zeros(3), rotation=np.eye(3), distortion=np.array(rig.distortion))
    xy = lens.rays()  # where the barrel lens sees each pixel of the pinhole camera's image
    paths = []
    for k, frame in enumerate(paper_scene.frames, 1):
        seen = ndimage.map_coordinates(np.asarray(frame, np.float32), [cam.cy_px + cam.focal_px * xy[..., 1], cam.cx_px + cam.focal_px * xy[..., 0]], order=3, mode="nearest")
        paths.append(tmp_path / f"I{k}.png")
        assert cv2.imwrite(str(paths[-1]), np.clip(np.rint(seen), 0, 255).astype(np.uint8))
    csv, ply = tmp_path / "z.csv", tmp_path / "z.ply"
    code, _, err = run_cli(capsys, "dynamic", *paths, "--rig", rig_file, "--out", tmp_path / "z.tif", "--csv", csv, "--ply", ply)
    assert code == 0, err
    data = ply.read_bytes()
    body = data[data.index(b"end_header\n") + len(b"end_header\n") :]
    rec = np.frombuffer(body, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    pts = np.loadtxt(csv, delimiter=",", skiprows=1)  # the same points, in the same order, at cell centres
    assert len(rec) == len(pts) > 300
    ii, jj = np.floor(pts[:, 0]).astype(int), np.floor(pts[:, 1]).astype(int)
    undone = np.clip(np.rint(rig.undistort(read_image(paths[2], dtype=None))), 0, 255).astype(np.uint8)
    for channel in ("red", "green", "blue"):
        np.testing.assert_array_equal(rec[channel], undone[ii, jj])
    # the pinhole camera's I3 at the points
    pinhole = np.asarray(paper_scene.frames[2], float)[ii, jj]
    assert np.mean(np.abs(rec["red"] - pinhole)) < 8.0


def test_dynamic_cli_refused_before_any_work(tmp_path, capsys, paper_pngs):
    """Clashing outputs, a negative --sigma-px, images and videos at once: one line, exit 2, nothing written."""
    out = tmp_path / "z.tif"
    cases = [
        (["--out", out, "--uncertainty", tmp_path / "." / "z.tif"],
         f"--out and --uncertainty name the same file '{tmp_path / '.' / 'z.tif'}'; expected a different path for each output"),
        (["--out", out, "--csv", tmp_path / "p.csv", "--ply", tmp_path / "p.ply", "--preview", tmp_path / "z.png", "--figure", tmp_path / "z.png"],
         f"--preview and --figure name the same file '{tmp_path / 'z.png'}'; expected a different path for each output"),
        (["--out", out, "--sigma-px", "-1"], "--sigma-px must be a finite number >= 0, got -1"),
        (["--out", out, "--sigma-px", "nan"], "--sigma-px must be a finite number >= 0, got nan"),
        (["--out", tmp_path / "c.npz", "--moving-video", tmp_path, "--reference-video", tmp_path, "--crossings", "2"],
         "give either five images or --moving-video and --reference-video, not both"),
        (["--out", tmp_path / "c.npz", "--reference-video", tmp_path], "two synchronised videos need both --moving-video and --reference-video"),
    ]
    before = sorted(tmp_path.rglob("*"))
    for extra, line in cases:
        code, stdout, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", PAPER_RIG, *extra)
        assert (code, stdout, err) == (2, "", f"nfdepth: error: {line}\n"), extra
    assert sorted(tmp_path.rglob("*")) == before


def test_a_distortion_that_folds_the_image_is_refused():
    """k1 = -15 at f = 100 px: r (1 + k1 r^2) stops growing at r = 1 / sqrt(3 * 15), 14.9 px from the principal point,
    inside the 200 x 200 image (140.7 px to its corners); undistortion folded the image over (a helper's row: 11.6 %
    covered, 74 % more than 5 % off, without a word). Models that keep growing across the image are taken."""
    import copy

    d = copy.deepcopy(BASE)
    d["camera"]["distortion"] = [-15.0, 0.0, 0.0, 0.0]
    with pytest.raises(RigError, match=r"^camera\.distortion = \[-15\.0, 0\.0, 0\.0, 0\.0\]: expected a lens model that maps the image one to one: its radial term turns back 15 px from the principal point, inside the image \(141 px to its farthest corner\)"):
        rig_from_dict(d)
    for ok in ([-0.3, 0.1, 0.0, 0.0], [0.2, 0.0, 0.001, -0.001, 0.0], [-0.1, 0.02, 0.0, 0.0, 0.0, 0.1, 0.01, 0.0]):
        d["camera"]["distortion"] = ok
        assert rig_from_dict(d).distortion == tuple(ok)


def test_stereo_options_take_a_hand_built_direction_of_any_length():
    """A rig file's direction [2, 0, 0] is read as x (normalised); a StereoSpec built by hand with it was refused as
    'not [1, 0, 0] or [0, 1, 0]'. Its direction, not its length, decides the axis."""
    from nfdepth.rig import StereoSpec

    rig = rig_from_dict(copy.deepcopy(BASE))
    for direction, axis in (([2.0, 0.0, 0.0], "x"), ([0.0, 0.5, 0.0], "y")):
        built = dataclasses.replace(rig, stereo=StereoSpec(baseline=1.0, direction=np.array(direction)))
        assert stereo_options_from_rig(built)["axis"] == axis
    for direction in ([1.0, 1.0, 0.0], [0.0, 0.0, 0.0], [-1.0, 0.0, 0.0]):
        built = dataclasses.replace(rig, stereo=StereoSpec(baseline=1.0, direction=np.array(direction)))
        with pytest.raises(RigError, match=r"^stereo\.direction = .*: expected \[1, 0, 0\] or \[0, 1, 0\] for nfdepth stereo"):
            stereo_options_from_rig(built)


def test_poses_frame_indices_up_to_the_bound(tmp_path, capsys, paper_pngs):
    """The largest frame index kept exact is read; one beyond int64 in a rig's poses stops ``nfdepth dynamic`` with one line
    naming the rig, the CSV, its line and the value (was: internal error (OverflowError), exit 1)."""
    p = tmp_path / "p.csv"
    p.write_text("frame,x,y,z\n0,0,0,0\n9007199254740991,0.1,0,0\n")
    assert load_poses(p).frames.tolist() == [0, 2**53 - 1]
    p.write_text("frame,x,y,z\n0,0,0,0\n9223372036854775808,0.1,0,0\n")
    rig = tmp_path / "r.toml"
    rig.write_text('[camera]\nfocal_px = 100.0\nwidth_px = 200\nheight_px = 200\n[motion]\nvelocity = [2.0, 0, 0]\n[video]\nposes = "p.csv"\n')
    code, out, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", rig, "--out", tmp_path / "z.npy")
    assert (code, out) == (2, "")
    assert err == (
        f"nfdepth: error: rig '{rig}': poses '{p}' line 3: frame = '9223372036854775808': expected a frame index below"
        " 9007199254740992 (2**53, where whole numbers stop being exact in floating point)\n"
    )
    assert not (tmp_path / "z.npy").exists()


def test_frame_interval_bound_is_dynamic_stereos(paper_scene):
    """The parser takes the intervals :func:`nfdepth.pipelines.dynamic_stereo` takes: up to 5e29, not 1e30."""
    from nfdepth.pipelines import dynamic_stereo
    from nfdepth.rig import MAX_FRAME_INTERVAL

    d = copy.deepcopy(BASE)
    d["motion"]["frame_interval"] = MAX_FRAME_INTERVAL
    assert rig_from_dict(d).frame_interval == 5e29
    beyond = float(np.nextafter(MAX_FRAME_INTERVAL, np.inf))
    d["motion"]["frame_interval"] = beyond
    with pytest.raises(RigError, match=r"^motion\.frame_interval = 5\.000000000000001e\+29: expected a time step within 1e-30\.\.5e\+29"):
        rig_from_dict(d)
    rig = rig_from_dict(BASE)
    with pytest.raises(ValueError, match=r"^frame_interval = 5e\+29 is outside 1e-30\.\.5e\+29"):
        dynamic_stereo(list(paper_scene.frames), camera=rig.camera, relative_motion=rig.relative_motion(), frame_interval=beyond)


def test_rig_from_dict_takes_tuples_and_arrays():
    """A dict built in Python holds tuples and NumPy arrays (cv2.calibrateCamera's distortion is a (1, 5) array): they were
    refused as "motion.velocity = [2.0, 0.0, 0.0]: expected 3 finite numbers [x, y, z]", the very value shown as a list."""
    d = copy.deepcopy(BASE)
    d["camera"]["distortion"] = [-0.1, 0.01, 0.0, 0.0, 0.0]
    d["stereo"].update(positions=[0.0, 1.0, 2.5], column_positions=[0.0, 1.0], disparity_range_px=[0.0, 8.0])
    d["video"] = {"positions": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]}
    expected = rig_from_dict(d)
    e = copy.deepcopy(d)
    e["camera"]["distortion"] = np.array([[-0.1, 0.01, 0.0, 0.0, 0.0]])
    e["motion"].update(velocity=(2.0, 0.0, 0.0), rotation_deg=np.zeros(3))
    e["stereo"].update(positions=(0.0, 1.0, 2.5), column_positions=np.array([0, 1]), disparity_range_px=(0.0, 8.0))
    e["video"] = {"positions": np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])}
    assert rig_from_dict(e) == expected
    e["camera"]["distortion"] = np.array([[-0.1], [0.01], [0.0], [0.0], [0.0]])  # a column
    e["video"] = {"positions": ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), np.array([2.0, 0.0, 0.0]))}
    assert rig_from_dict(e) == expected
    assert rig_from_dict(tomllib.loads(rig_to_toml(rig_from_dict(e)))) == expected


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        ("motion", "velocity", "2, 0, 0", r"^motion\.velocity = '2, 0, 0': expected 3 finite numbers \[x, y, z\] \(a str, not a list\)$"),
        ("motion", "velocity", {"x": 2.0}, r"^motion\.velocity = \{'x': 2\.0\}: expected 3 finite numbers \[x, y, z\] \(a dict, not a list\)$"),
        ("motion", "velocity", np.array([[2.0, 0.0, 0.0]]), r"^motion\.velocity = \[\[2\.0, 0\.0, 0\.0\]\]: expected 3 finite numbers \[x, y, z\] \(an array of shape \(1, 3\), not a list\)$"),
        ("motion", "velocity", np.array([True, False, False]), r"^motion\.velocity = \[True, False, False\]: expected 3 finite numbers \[x, y, z\]$"),
        ("camera", "distortion", np.zeros((2, 4)), r"^camera\.distortion = \[\[0\.0, 0\.0, 0\.0, 0\.0\], \[0\.0, 0\.0, 0\.0, 0\.0\]\]: expected 4, 5 or 8 finite numbers, OpenCV's \[k1, k2, p1, p2, k3, k4, k5, k6\] \(an array of shape \(2, 4\), not a list\)$"),
        ("camera", "distortion", "-0.1 0.01 0 0", r"^camera\.distortion = '-0\.1 0\.01 0 0': expected 4, 5 or 8 finite numbers, .* \(a str, not a list\)$"),
        ("stereo", "positions", "0 1 2", r"^stereo\.positions = '0 1 2': expected a list of 2 or more finite numbers \(units of the baseline\) \(a str, not a list\)$"),
        ("video", "velocity", 1.0, r"^video\.velocity = 1\.0: expected 3 finite numbers \[x, y, z\] \(a float, not a list\)$"),
        ("video", "positions", np.zeros(9), r"^video\.positions = \[0, 0, 0, 0, 0, 0, 0, 0, 0\]: expected a list of 3 or more \[x, y, z\] camera positions, one per frame \(an array of shape \(9,\), not a list\)$"),
    ],
)
def test_rig_from_dict_names_what_is_no_list(section, key, value, message):
    d = copy.deepcopy(BASE)
    d[section][key] = value
    if section == "video" and key != "velocity":
        del d["video"]["velocity"]
    with pytest.raises(RigError, match=message):
        rig_from_dict(d)


@pytest.mark.parametrize(
    ("direction", "unit", "axis"),
    [
        ([1e-170, 0.0, 0.0], [1.0, 0.0, 0.0], "x"),  # was [inf, nan, nan] with RuntimeWarnings (its square underflows), then refused
        ([0.0, 5e-324, 0.0], [0.0, 1.0, 0.0], "y"),
        ([1e300, 0.0, 0.0], [1.0, 0.0, 0.0], "x"),
        ([1e200, 1e200, 0.0], [0.5**0.5, 0.5**0.5, 0.0], None),  # was [0, 0, 0] (its square overflows)
        ([1e308, -1e308, 1e308], [3**-0.5, -(3**-0.5), 3**-0.5], None),
    ],
)
def test_stereo_direction_of_any_magnitude_is_normalised(direction, unit, axis):
    d = copy.deepcopy(BASE)
    d["stereo"] = {"baseline": 1.0, "direction": direction}
    rig = rig_from_dict(d)
    np.testing.assert_allclose(rig.stereo.direction, unit, rtol=1e-15, atol=0)
    if axis is not None:
        assert stereo_options_from_rig(rig)["axis"] == axis
    else:
        with pytest.raises(RigError, match=r"^stereo\.direction = \[0\.57735|^stereo\.direction = \[0\.707107, 0\.707107, 0\]"):
            stereo_options_from_rig(rig)
    text = rig_to_toml(rig)  # was "direction = [inf, nan, nan]", which no TOML reader takes
    assert "nan" not in text and "inf" not in text
    assert rig_from_dict(tomllib.loads(text)) == rig
    # a StereoSpec built by hand with such a direction is read by its direction too (its norm overflowed: a RuntimeWarning)
    from nfdepth.rig import StereoSpec

    built = dataclasses.replace(rig, stereo=StereoSpec(baseline=1.0, direction=np.array(direction)))
    if axis is not None:
        assert stereo_options_from_rig(built)["axis"] == axis


@pytest.mark.parametrize(
    ("frame", "error", "message"),
    [
        (np.zeros(200), ValueError, r"^frames\[0\] must be a 2-D grey image \(rows, cols\), got shape \(200,\)$"),
        (None, TypeError, r"^frames\[0\] must be a numeric 2-D array, got dtype object$"),
        ("I1.png", TypeError, r"^frames\[0\] must be a numeric 2-D array, got dtype <U6$"),
        (np.zeros((200, 200, 3)), ValueError, r"^frames\[0\] must be a 2-D grey image \(rows, cols\), got shape \(200, 200, 3\); convert colour to grey first"),
    ],
)
def test_dynamic_stereo_from_rig_checks_the_frames_as_dynamic_stereo_does(frame, error, message):
    """A 1-D, None or text frame was an IndexError (tuple index out of range) from the size check: now dynamic_stereo's message."""
    rig = rig_from_dict(BASE)
    with pytest.raises(error, match=message):
        dynamic_stereo_from_rig([frame] + [np.zeros((200, 200))] * 4, rig)
    with pytest.raises(ValueError, match=r"^image I1 must be a 2-D grey image \(rows, cols\), got shape \(200,\)$"):
        rig.check_image_shape((200,), what="image I1")


def test_dynamic_cli_refuses_points_beyond_float32_before_writing(tmp_path, capsys, paper_pngs):
    """Depths up to 2e37 fit float32, but X = x Z of points 120 focal lengths off the axis does not: --ply cast them to inf
    (a raw "overflow encountered in cast" warning) and dropped them, 141 points against the 494 of --csv. Now one line, exit 2,
    nothing written."""
    rig = tmp_path / "far.toml"
    rig.write_text(
        "[camera]\nfocal_px = 1.0\nwidth_px = 200\nheight_px = 200\ncx_px = 80.0\ncy_px = 120.0\n"
        "[motion]\nvelocity = [1e30, 0, 0]\nframe_interval = 1e7\n"
    )
    outs = ["--out", tmp_path / "z.npy", "--csv", tmp_path / "z.csv", "--ply", tmp_path / "z.ply"]
    code, out, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", rig, *outs)
    assert (code, out) == (2, "")
    assert re.fullmatch(
        r"nfdepth: error: a point coordinate of [0-9.]+e\+39 does not fit a float32 output \(about 1e-45 to 3\.4e38\): a \.ply file"
        r" stores float32: give the rig's speeds \(motion\.velocity\) in a unit that keeps the points in that range\n",
        err,
    ), err
    assert not any((tmp_path / n).exists() for n in ("z.npy", "z.csv", "z.ply"))
    code, _, err = run_cli(capsys, "dynamic", *paper_pngs, "--rig", rig, *outs[:4])  # without --ply: the depths fit
    assert code == 0, err
