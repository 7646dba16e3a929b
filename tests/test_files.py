"""Atomic writing (:mod:`mechviz.dynamics.files`): what the benchmark, the endurance run and the recorder
write is either the old file or the whole new one, never half of it."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest
from faults import disk_full_at_nth_fsync

from mechviz.dynamics import files


def test_json_is_written_whole_and_replaces_the_old_file(tmp_path):
    path = tmp_path / "out" / "results.json"
    files.write_json_atomically(path, {"ratio": 15.0}, indent=1)
    files.write_json_atomically(path, {"ratio": 19.0}, indent=1)
    assert json.loads(path.read_text()) == {"ratio": 19.0}
    assert sorted(p.name for p in path.parent.iterdir()) == ["results.json"]


def test_a_full_disk_midway_keeps_every_old_file_and_leaves_no_partial_one(tmp_path, monkeypatch):
    old = {"tables.md": b"old tables\n", "results.json": b'{"old": true}\n'}
    files.write_files_atomically(tmp_path, old)
    disk_full_at_nth_fsync(monkeypatch, 2)  # the second file: the first is written in full
    with pytest.raises(OSError, match="No space left"):
        files.write_files_atomically(
            tmp_path, {"tables.md": b"new tables\n", "results.json": b'{"new": true}\n'}
        )
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == old


OLD = {"a.viser": b"old viser\n", "a.csv": b"old csv\n", "a.json": b'{"old": true}\n'}
NEW = {"a.viser": b"new viser\n", "a.csv": b"new csv\n", "a.json": b'{"new": true}\n'}


def _contents(folder):
    return {p.name: p.read_bytes() for p in folder.iterdir()}


def test_an_io_error_between_two_renames_puts_the_old_set_back_and_says_so(tmp_path, monkeypatch):
    files.write_files_atomically(tmp_path, OLD)
    real_replace = os.replace
    calls = []

    def failing_replace(src, dst):
        calls.append(dst)
        if len(calls) == 2:  # the first new file is already in place
            raise OSError(5, "Input/output error")
        real_replace(src, dst)

    monkeypatch.setattr(files.os, "replace", failing_replace)
    with pytest.raises(files.WriteFailed) as info:
        files.write_files_atomically(tmp_path, NEW)
    monkeypatch.undo()
    assert _contents(tmp_path) == OLD
    assert info.value.unchanged and info.value.new_files == ()
    assert isinstance(info.value, OSError) and "unchanged" in str(info.value)


def test_ctrl_c_during_the_switch_is_held_until_it_is_over_and_then_undoes_it(
    tmp_path, monkeypatch
):
    files.write_files_atomically(tmp_path, OLD)
    real_replace = os.replace

    def interrupted_replace(src, dst):
        real_replace(src, dst)
        if str(dst).endswith("a.viser"):
            signal.raise_signal(signal.SIGINT)  # Ctrl-C after the first rename

    monkeypatch.setattr(files.os, "replace", interrupted_replace)
    with pytest.raises(KeyboardInterrupt) as info:
        files.write_files_atomically(tmp_path, NEW)
    monkeypatch.undo()
    assert _contents(tmp_path) == OLD
    assert isinstance(info.value, files.WriteInterrupted) and info.value.unchanged
    assert info.value.signum == signal.SIGINT
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_full_disk_in_a_new_folder_leaves_no_folder_behind(tmp_path, monkeypatch):
    def full(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.os, "fsync", full)
    with pytest.raises(files.WriteFailed, match="No space left") as info:
        files.write_files_atomically(tmp_path / "new" / "demo", NEW)
    assert info.value.unchanged
    assert list(tmp_path.iterdir()) == []


def test_a_new_set_replaces_the_old_one_whole_and_leaves_nothing_else(tmp_path):
    files.write_files_atomically(tmp_path, OLD)
    files.write_files_atomically(tmp_path, NEW)
    assert _contents(tmp_path) == NEW


_CHILD = """
import os, sys, time
from pathlib import Path
from mechviz.dynamics import files
out = Path(sys.argv[1])
real_fsync = os.fsync
def slow_fsync(fd):
    real_fsync(fd)
    print("writing", flush=True)
    time.sleep(60)
files.os.fsync = slow_fsync
files.write_files_atomically(out, {"a.viser": b"new viser", "a.csv": b"new csv"})
"""


@pytest.mark.parametrize("signame", ["SIGTERM", "SIGHUP", "SIGINT"])
@pytest.mark.slow
def test_a_signal_while_writing_leaves_the_folder_as_it_was(tmp_path, signame):
    files.write_files_atomically(tmp_path, OLD)
    child = subprocess.Popen(
        [sys.executable, "-c", _CHILD, str(tmp_path)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout.readline().strip() == "writing"
        child.send_signal(getattr(signal, signame))
        rc = child.wait(timeout=30)
    finally:
        child.kill()
        child.wait()
    assert _contents(tmp_path) == OLD
    # The signal still ends the process (SIGINT: through the KeyboardInterrupt it raises).
    assert rc in ((1, -signal.SIGINT) if signame == "SIGINT" else (-getattr(signal, signame),))


def test_json_safe_turns_non_finite_numbers_into_null_and_says_where():
    reasons = {}
    out = files.json_safe(
        {"period": float("inf"), "x": [1.0, float("nan")], "n": np.float64(2.5)}, reasons=reasons
    )
    assert json.loads(json.dumps(out, allow_nan=False)) == {
        "period": None,
        "x": [1.0, None],
        "n": 2.5,
    }
    assert reasons == {"period": "not finite (inf)", "x[1]": "not finite (nan)"}


def test_write_json_atomically_writes_valid_json_for_nan(tmp_path):
    files.write_json_atomically(tmp_path / "r.json", {"ratio": float("nan")})
    assert json.loads((tmp_path / "r.json").read_text()) == {"ratio": None}


def test_a_folder_where_a_file_should_go_fails_the_write_and_changes_nothing(tmp_path):
    files.write_files_atomically(tmp_path, {"a.csv": b"old csv\n"})
    (tmp_path / "a.json").mkdir()
    with pytest.raises(files.WriteFailed, match="Is a directory") as info:
        files.write_files_atomically(tmp_path, {"a.csv": b"new csv\n", "a.json": b"{}\n"})
    assert info.value.unchanged
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "a.json"]
    assert (tmp_path / "a.csv").read_bytes() == b"old csv\n"
