"""``mechviz record`` killed, run twice at once, or interrupted while it starts: the output folder
always shows one whole recording (the old or the new), every file matching its manifest, and
the next recording leaves nothing else behind."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from faults import killed_after_nth_call

from mechviz.dynamics import fileset
from mechviz.viz import record as rec

SUFFIXES = rec.SUFFIXES


def shown(folder: Path) -> dict[str, bytes]:
    """What a reader sees under the recording's names (a dangling link shows nothing)."""
    names = [f"helix{s}" for s in SUFFIXES]
    return {n: (folder / n).read_bytes() for n in names if (folder / n).exists()}


def assert_whole_recording(folder: Path, old: dict[str, bytes]) -> str:
    """The names show the old recording, or a complete new one whose every file matches its
    manifest; returns "old" or "new"."""
    seen = shown(folder)
    if seen == old:
        return "old"
    assert len(seen) == len(SUFFIXES), sorted(seen)
    man = json.loads(seen["helix.json"])
    for name, meta in man["files"].items():
        assert hashlib.sha256(seen[name]).hexdigest() == meta["sha256"], name
        assert seen[name] != old.get(name), name  # old and new recordings differ in every file
    return "new"


def assert_nothing_stray(folder: Path) -> None:
    current = fileset.current_set(folder, "helix")
    assert current is not None
    names = {f"helix{s}" for s in SUFFIXES}
    expected = names | {".mechviz", ".mechviz/helix", ".mechviz/helix/current"}
    expected |= {f".mechviz/helix/{current.name}"} | {
        f".mechviz/helix/{current.name}/{n}" for n in names
    }
    assert {str(p.relative_to(folder)) for p in folder.rglob("*")} == expected


def record_short(out: Path, duration: float = 0.5) -> None:
    rec.record(rec.load_demo("helix").with_overrides(duration=duration, fps=5), out)


def earlier_layout(out: Path) -> dict[str, bytes]:
    """A recording as the earlier writer left it: the five files themselves in the folder."""
    record_short(out)
    files = shown(out)
    shutil.rmtree(out / fileset.HOME)
    for name, data in files.items():
        (out / name).unlink()
        (out / name).write_bytes(data)
    return files


_RECORD = [
    sys.executable,
    "-m",
    "mechviz.viz.cli",
    "record",
    "helix",
    "--duration",
    "0.6",
    "--fps",
    "5",
]

_KILL_AFTER_RENAME = killed_after_nth_call(
    ("rename", "replace"),
    """
from mechviz.viz.cli import main
sys.exit(main(sys.argv[2:]))
""",
)


@pytest.mark.parametrize(
    ("start", "n"), [*(("earlier layout", n) for n in (1, 2, 3, 4)), ("links", 1)]
)
@pytest.mark.slow
def test_record_killed_after_its_nth_rename_leaves_a_whole_recording(tmp_path, start, n):
    out = tmp_path / "out"
    if start == "links":
        record_short(out)
        old = shown(out)
    else:
        old = earlier_layout(out)
    res = subprocess.run(
        [sys.executable, "-c", _KILL_AFTER_RENAME, str(n), *_RECORD[3:], "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == -signal.SIGKILL, res.stderr
    assert_whole_recording(out, old)
    record_short(out, duration=0.4)
    assert_nothing_stray(out)


@pytest.mark.slow
def test_two_records_at_once_end_with_one_complete_recording(tmp_path):
    out = tmp_path / "out"
    old = earlier_layout(out)
    procs = [
        subprocess.Popen(
            [*_RECORD, "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        for _ in range(2)
    ]
    results = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    for p in procs:
        p.stdout.close()
        p.stderr.close()
    assert [rc for rc, _ in results] == [0, 0], results
    assert assert_whole_recording(out, old) == "new"
    assert_nothing_stray(out)


def _snapshot(folder: Path) -> dict[str, bytes | str]:
    out: dict[str, bytes | str] = {}
    for p in sorted(folder.rglob("*")):
        key = str(p.relative_to(folder))
        out[key] = (
            f"-> {os.readlink(p)}" if p.is_symlink() else p.read_bytes() if p.is_file() else "dir"
        )
    return out


@pytest.mark.slow
def test_ctrl_c_0_3_s_after_start_exits_130_and_leaves_the_folder_unchanged(tmp_path):
    record_short(tmp_path)
    before = _snapshot(tmp_path)
    child = subprocess.Popen([*_RECORD, "--out", str(tmp_path)], stderr=subprocess.PIPE, text=True)
    time.sleep(0.3)  # the moment the issue names: the child is still importing
    child.send_signal(signal.SIGINT)
    assert child.wait(timeout=120) == 130
    err = child.stderr.read().strip()
    child.stderr.close()
    assert len(err.splitlines()) == 1 and "interrupted" in err, err
    assert _snapshot(tmp_path) == before


_STOP_IN_TRIMESH = """
import sys
class Stop:
    stopped = False
    def find_spec(self, name, path=None, target=None):
        if name == "trimesh.path" and not self.stopped:  # trimesh imports it in a try/except
            Stop.stopped = True                          # BaseException
            print("in trimesh", flush=True)
            sys.stdin.readline()
        return None
sys.meta_path.insert(0, Stop())
from mechviz.viz.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.slow
def test_ctrl_c_while_trimesh_imports_is_not_swallowed(tmp_path):
    record_short(tmp_path)
    before = _snapshot(tmp_path)
    child = subprocess.Popen(
        [sys.executable, "-c", _STOP_IN_TRIMESH, *_RECORD[3:], "--out", str(tmp_path)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "in trimesh"
        child.send_signal(signal.SIGINT)
        child.stdin.write("go\n")
        child.stdin.flush()
        rc = child.wait(timeout=120)
        err = child.stderr.read()
    finally:
        child.kill()
        child.wait()
        for f in (child.stdin, child.stdout, child.stderr):
            f.close()
    assert rc == 130, err
    assert _snapshot(tmp_path) == before
