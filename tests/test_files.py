"""Atomic writing (:mod:`dynamics.files`): what the benchmark, the endurance run and the recorder
write is either the old file or the whole new one, never half of it."""

from __future__ import annotations

import json
import os

import pytest

from dynamics import files


def test_json_is_written_whole_and_replaces_the_old_file(tmp_path):
    path = tmp_path / "out" / "results.json"
    files.write_json_atomically(path, {"ratio": 15.0}, indent=1)
    files.write_json_atomically(path, {"ratio": 19.0}, indent=1)
    assert json.loads(path.read_text()) == {"ratio": 19.0}
    assert sorted(p.name for p in path.parent.iterdir()) == ["results.json"]


def test_a_full_disk_midway_keeps_every_old_file_and_leaves_no_partial_one(tmp_path, monkeypatch):
    old = {"tables.md": b"old tables\n", "results.json": b'{"old": true}\n'}
    files.write_files_atomically(tmp_path, old)
    calls = []
    real_fsync = os.fsync

    def failing_fsync(fd):
        calls.append(fd)
        if len(calls) == 2:  # the second file: the first is already written in full
            raise OSError(28, "No space left on device")
        real_fsync(fd)

    monkeypatch.setattr(files.os, "fsync", failing_fsync)
    with pytest.raises(OSError, match="No space left"):
        files.write_files_atomically(
            tmp_path, {"tables.md": b"new tables\n", "results.json": b'{"new": true}\n'}
        )
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == old
