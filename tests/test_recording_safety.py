"""``mechviz record`` killed, run twice at once, or interrupted while it starts: every file in the
output folder is always whole, and the folder shows one whole recording (the old or the new) or
one that every reader refuses, naming the file from the other recording; the next recording
leaves nothing else behind. A recording folder holds regular files only."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest
from faults import killed_after_nth_call

from mechviz.dynamics import api, fileset
from mechviz.viz import play
from mechviz.viz import record as rec
from mechviz.viz.cli.errors import CliError

SUFFIXES = rec.SUFFIXES


def shown(folder: Path) -> dict[str, bytes]:
    """What a reader sees under the recording's names."""
    names = [f"helix{s}" for s in SUFFIXES]
    return {n: (folder / n).read_bytes() for n in names if (folder / n).exists()}


def assert_whole_recording(folder: Path, old: dict[str, bytes]) -> str:
    """Every file is whole, from the old recording or the new one; the names show the old
    recording ("old"), a complete new one whose every file matches its manifest ("new"), or a
    mix that :func:`mechviz.dynamics.api.read_recording` refuses, naming a file ("mixed")."""
    seen = shown(folder)
    if seen == old:
        return "old"
    try:
        got = api.read_recording(folder / "helix")
    except fileset.SetMismatch as exc:
        # The manifest is renamed last: a mix shows the old one beside a new file, named.
        assert seen["helix.json"] == old["helix.json"]
        assert exc.file in seen and seen[exc.file] != old[exc.file], exc
        assert "newer (unfinished) recording than helix.json" in str(exc)
        return "mixed"
    assert set(got.files) == set(seen) and len(seen) == len(SUFFIXES), sorted(seen)
    for name, meta in got.manifest["files"].items():
        assert hashlib.sha256(seen[name]).hexdigest() == meta["sha256"], name
        assert seen[name] != old.get(name), name  # old and new recordings differ in every file
    return "new"


def assert_nothing_stray(folder: Path) -> None:
    """The recording's names, regular files, and nothing else."""
    names = {f"helix{s}" for s in SUFFIXES}
    assert {str(p.relative_to(folder)) for p in folder.rglob("*")} == names
    assert all((folder / n).is_file() and not (folder / n).is_symlink() for n in names)


def record_short(out: Path, duration: float = 0.5) -> None:
    rec.record(rec.load_demo("helix").with_overrides(duration=duration, fps=5), out)


def links_layout(out: Path) -> dict[str, bytes]:
    """A recording as the earlier writer left it: each name a link into
    ``.mechviz/helix/current/``."""
    record_short(out)
    files = shown(out)
    home = out / fileset.OLD_HOME / "helix"
    (home / "set-1").mkdir(parents=True)
    (home / "current").symlink_to("set-1")
    for name in files:
        os.replace(out / name, home / "set-1" / name)
        (out / name).symlink_to(f"{fileset.OLD_HOME}/helix/current/{name}")
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
    ("start", "n"), [*(("links", n) for n in (1, 3, 5, 6)), ("plain", 2), ("plain", 5)]
)
@pytest.mark.slow
def test_record_killed_after_its_nth_rename_leaves_whole_files(tmp_path, start, n):
    out = tmp_path / "out"
    if start == "plain":
        record_short(out)
        old = shown(out)
    else:
        old = links_layout(out)
    res = subprocess.run(
        [sys.executable, "-c", _KILL_AFTER_RENAME, str(n), *_RECORD[3:], "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    if n <= len(SUFFIXES):
        assert res.returncode == -signal.SIGKILL, res.stderr
    state = assert_whole_recording(out, old)
    assert state == ("new" if n >= len(SUFFIXES) else "mixed"), state
    record_short(out, duration=0.4)
    assert_nothing_stray(out)


def test_a_recording_folder_holds_regular_files_that_a_zip_holds_once(tmp_path):
    out = tmp_path / "out"
    links_layout(out)  # a folder of the earlier layout, recorded over
    record_short(out, duration=0.4)
    assert_nothing_stray(out)
    with zipfile.ZipFile(tmp_path / "out.zip", "w") as z:
        for p in sorted(out.rglob("*")):
            z.write(p, p.relative_to(out))
    with zipfile.ZipFile(tmp_path / "out.zip") as z:
        listed = z.namelist()
        assert sorted(listed) == sorted(f"helix{s}" for s in SUFFIXES)
        assert all(z.read(n) == (out / n).read_bytes() for n in listed)
    man = json.loads((out / "helix.json").read_text())
    assert man["schema_version"] == fileset.SCHEMA_VERSION
    assert sorted(man["files"]) == sorted(f"helix{s}" for s in SUFFIXES if s != ".json")
    # The CSV's units are in the manifest; its numbers are floats, whatever a reader guesses.
    header, *rows = [line.split(",") for line in (out / "helix.csv").read_text().splitlines()]
    assert list(man["csv_columns"]) == header
    assert man["csv_columns"]["r"] == {"units": "m", "long_name": "distance from the axis r"}
    assert man["csv_columns"]["t"]["units"] == "s" and man["csv_columns"]["vx"]["units"] == "m/s"
    r = header.index("r")
    assert all(any(c in row[r] for c in ".en") for row in rows), [row[r] for row in rows]
    table = api.read_recording(out / "helix").columns()
    assert table["r"].dtype.kind == "f" and table["member"].dtype.kind == "i"


def test_a_recording_with_a_file_from_an_older_one_is_named_by_every_reader(tmp_path, capsys):
    from mechviz.viz import notebook
    from mechviz.viz.cli import main

    older, out = tmp_path / "older", tmp_path / "out"
    record_short(older, duration=0.4)
    hour_ago = time.time() - 3600
    os.utime(older / "helix.viser", (hour_ago, hour_ago))  # recorded an hour before the other
    record_short(out, duration=0.6)
    assert api.read_recording(out / "helix").manifest["duration"] == 0.6  # whole, it reads
    shutil.copy2(older / "helix.viser", out / "helix.viser")  # as a file manager copies one
    sentence = "helix.viser is from an older recording than helix.json"
    with pytest.raises(fileset.SetMismatch, match=sentence):
        api.read_recording(out / "helix")
    with pytest.raises(ValueError, match=sentence):
        notebook.recorded(out / "helix")
    for where in (out, out / "helix.viser"):  # play refuses it before it serves anything
        with pytest.raises(CliError, match=sentence):
            play.make_play_server(where, "127.0.0.1", 0)
    for command in (
        ["video", str(out / "helix.viser"), "--out", str(tmp_path / "v.mp4")],
        ["still", str(out / "helix.html"), "--at", "0", "--out", str(tmp_path / "s.png")],
    ):
        assert main(command) == 2, command
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and sentence in err, (command, err)
    assert not (tmp_path / "v.mp4").exists() and not (tmp_path / "s.png").exists()


def test_play_answers_409_naming_the_file_once_the_set_it_serves_is_mixed(tmp_path):
    import threading
    import urllib.error
    import urllib.request

    older, out = tmp_path / "older", tmp_path / "out"
    record_short(older, duration=0.4)
    record_short(out, duration=0.6)
    server, _ = play.make_play_server(out, "127.0.0.1", 0)
    threading.Thread(
        target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True
    ).start()
    url = f"http://127.0.0.1:{server.server_address[1]}/recordings/helix.viser"
    try:
        with urllib.request.urlopen(url, timeout=30) as r:
            assert r.read() == (out / "helix.viser").read_bytes()
        shutil.copy(older / "helix.csv", out / "helix.csv")
        with pytest.raises(urllib.error.HTTPError) as info:
            urllib.request.urlopen(url, timeout=30)
        assert info.value.code == 409
        assert info.value.read().decode().startswith("helix.csv is from ")
    finally:
        server.shutdown()
        server.server_close()


@pytest.mark.slow
def test_two_records_at_once_end_with_one_complete_recording(tmp_path):
    out = tmp_path / "out"
    old = links_layout(out)
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
