"""An installed wheel is the whole product: `pip install .` (not editable) into a fresh virtual
environment, then a built-in demo records from outside the checkout."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_a_wheel_installed_in_a_fresh_venv_records_a_built_in_demo(tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    py = venv / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    # the working tree's files as git sees them, copied: the build leaves nothing in the checkout
    files = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    src = tmp_path / "src"
    for name in files:
        if (ROOT / name).is_file():
            (src / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, src / name)
    pip = subprocess.run(
        [str(py), "-m", "pip", "install", "-q", str(src)],
        capture_output=True,
        text=True,
        timeout=1800,
        env=env,
        cwd=tmp_path,
    )
    assert pip.returncode == 0, pip.stderr[-2000:]
    out = tmp_path / "out"
    run = subprocess.run(
        [
            str(venv / "bin" / "mechviz"),
            "record",
            "helix",
            "--out",
            str(out),
            "--duration",
            "1",
            "--fps",
            "5",
        ],
        capture_output=True,
        text=True,
        timeout=900,
        env=env,
        cwd=tmp_path,
    )
    assert run.returncode == 0, run.stderr
    manifest = json.loads((out / "helix.json").read_text())
    assert manifest["demo"] == "helix" and manifest["exhibit"] == "cyclotron"
    assert (out / "helix.csv").stat().st_size > 0 and (out / "helix.viser").stat().st_size > 0
    # the code that ran is the installed copy, not the checkout
    where = subprocess.run(
        [str(py), "-c", "import viz, dynamics.assets as a; print(viz.__file__, a.asset('demos'))"],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
        cwd=tmp_path,
    )
    assert str(ROOT) not in where.stdout and "share/mechviz/demos" in where.stdout, where.stdout
