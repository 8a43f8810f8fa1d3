"""Every command in the README's walkthrough runs (on the demo's generated data)."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"


def readme_commands():
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"<!-- readme-test -->\s*```bash\n(.*?)```", text, flags=re.S)
    return [line.strip() for block in blocks for line in block.splitlines() if line.strip() and not line.startswith("#")]


def test_readme_has_tested_commands():
    cmds = readme_commands()
    assert len(cmds) >= 5
    assert all(c.startswith("nfdepth ") for c in cmds)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    work = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "examples", work / "examples")
    exe = [sys.executable, "-m", "nfdepth"]
    res = subprocess.run([*exe, "demo", "--out", "nfdepth-demo"], cwd=work, capture_output=True, text=True, check=False)
    assert res.returncode == 0, res.stderr
    return work


def _data_folder() -> Path | None:
    """Where the library finds the data (nfdepth.datasets.data_root), or None."""
    from nfdepth.datasets import DataNotFoundError, data_root

    try:
        return data_root()
    except DataNotFoundError:
        return None


@pytest.mark.parametrize("command", readme_commands())
def test_readme_command_runs(workdir, command):
    data = _data_folder()
    if " evaluate " in f" {command} " and data is None:
        pytest.skip("real data not found: set NFDEPTH_DATA or put it at ../shared/data")
    argv = shlex.split(command)
    env = dict(os.environ)
    if data is not None:  # the commands run elsewhere (a temporary folder): name the data the tests found
        env["NFDEPTH_DATA"] = str(data)
    res = subprocess.run([sys.executable, "-m", "nfdepth", *argv[1:]], cwd=workdir, capture_output=True, text=True, env=env, check=False)
    assert res.returncode == 0, f"{command}\n{res.stderr}"
    assert "Traceback" not in res.stderr
