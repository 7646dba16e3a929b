"""What cannot be used is refused up front with one line and exit status 2, and nothing is
written: demos asking for unbounded work, paths the system cannot hold, TOML nested too deeply,
crafted recordings given to ``mechviz video``; and a signal after a folder is switched ends the
process without a traceback, the new files complete."""

from __future__ import annotations

import json
import signal
import subprocess
import sys

import msgspec
import pytest
import zstandard

from mechviz.viz import record as rec
from mechviz.viz.cli import main
from mechviz.viz.record import demo as demo_module
from mechviz.viz.record import outputs

HEAD = 'title = "t"\ndescription = "d"\nexhibit = "cyclotron"\n'


def _one_line_status_2(capsys, argv) -> str:
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    return err


def test_more_scripted_events_than_the_limit_are_refused_naming_events(tmp_path, capsys):
    n = demo_module.MAX_EVENTS + 1
    events = "".join(f'[[events]]\nt = {i * 0.01}\naction = "kick"\n' for i in range(n))
    f = tmp_path / "many.toml"
    f.write_text(HEAD + 'method = "boris"\ndt = 0.01\nduration = 2.0\n' + events)
    err = _one_line_status_2(capsys, ["record", str(f), "--out", str(tmp_path / "out")])
    assert "events" in err and str(demo_module.MAX_EVENTS) in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("where", ["", "compare."])
def test_a_tolerance_below_the_floor_is_refused_naming_rtol(tmp_path, capsys, where):
    f = tmp_path / "tight.toml"
    if where:
        body = 'method = "boris"\ndt = 0.01\nduration = 1.0\n[compare]\nmethod = "dop853"\nrtol = 1e-300\n'
    else:
        body = 'method = "taylor"\nrtol = 1e-300\nduration = 1.0\n'
    f.write_text(HEAD + body)
    err = _one_line_status_2(capsys, ["record", str(f), "--out", str(tmp_path / "out")])
    assert f"{where}rtol = 1e-300" in err
    assert not (tmp_path / "out").exists()


def test_the_chart_marks_a_bounded_number_of_periods_however_many_the_recording_spans():
    from matplotlib.figure import Figure

    ax = Figure().subplots()
    outputs._mark_periods(ax, 2 * 3.141592653589793, 2e7, "predicted period")
    marks = sum(len(c.get_segments()) for c in ax.collections)
    assert 0 < marks <= outputs.MAX_PERIOD_MARKS
    ax = Figure().subplots()
    outputs._mark_periods(ax, 1.0, 10.0, "predicted period")
    assert sum(len(c.get_segments()) for c in ax.collections) == 10  # one per period when few


def test_a_toml_nested_1000_deep_is_one_line(tmp_path, capsys):
    f = tmp_path / "deep.toml"
    f.write_text(
        HEAD
        + 'method = "boris"\ndt = 0.01\nduration = 1.0\nparameters = '
        + "[" * 1000
        + "]" * 1000
        + "\n"
    )
    err = _one_line_status_2(capsys, ["record", str(f), "--out", str(tmp_path / "out")])
    assert "deep.toml" in err and "nested too deeply" in err


@pytest.mark.parametrize("command", ["record-demo", "record-out", "play", "video", "video-out"])
def test_a_5000_character_path_is_one_line(tmp_path, capsys, command):
    long = str(tmp_path / ("p" * 5000))
    viser = tmp_path / "a.viser"
    viser.write_bytes(_viser({"durationSeconds": 1.0, "messages": []}))
    argv = {
        "record-demo": ["record", long + ".toml", "--out", str(tmp_path / "out")],
        "record-out": ["record", "helix", "--out", long],
        "play": ["play", long],
        "video": ["video", long + ".viser"],
        "video-out": ["video", str(viser), "--out", long + ".mp4"],
    }[command]
    err = _one_line_status_2(capsys, argv)
    assert "File name too long" in err, err
    assert len(err) < 400  # the path is shortened in the message


def _viser(head: dict) -> bytes:
    """A ``.viser`` file around ``head`` (viser's format: size, then zstd of msgpack)."""
    packed = msgspec.msgpack.encode(head)
    inner = len(packed).to_bytes(8, "little") + packed
    return len(inner).to_bytes(8, "little") + zstandard.ZstdCompressor().compress(inner)


CRAFTED = [
    ({"durationSeconds": 1e308, "messages": []}, None, "too long to film"),
    ({"durationSeconds": 1e6, "messages": []}, None, "the limit is 100000"),
    ({"durationSeconds": -5.0, "messages": []}, None, "durationSeconds = -5"),
    ({"durationSeconds": "x", "messages": []}, None, "not a viser recording"),
    (
        {"durationSeconds": 1.0, "messages": []},
        {"fps": 0, "duration": 1.0, "title": "x"},
        "frame rate",
    ),
    (
        {"durationSeconds": 1.0, "messages": []},
        {"fps": [1], "duration": 1, "title": "x"},
        "fps must be a whole number",
    ),
    (
        {"durationSeconds": 1.0, "messages": []},
        {"fps": 30, "duration": 1e308, "title": "x"},
        "too long",
    ),
]


@pytest.mark.parametrize(("head", "manifest", "message"), CRAFTED)
def test_a_crafted_recording_given_to_video_is_one_line(tmp_path, capsys, head, manifest, message):
    f = tmp_path / "crafted.viser"
    f.write_bytes(_viser(head))
    if manifest is not None:
        (tmp_path / "crafted.json").write_text(json.dumps(manifest))
    err = _one_line_status_2(capsys, ["video", str(f)])
    assert message in err and "crafted.viser" in err, err
    assert not (tmp_path / "crafted.mp4").exists()


_HUP_AFTER_SWITCH = """
import os, signal, sys
from pathlib import Path
from mechviz.dynamics import files, fileset
real_replace, real_sync = os.replace, files._fsync_dir
def replace(src, dst):
    real_replace(src, dst)
    if sys.argv[2] == "set" and Path(dst).name == "a.json":  # the set's manifest, renamed last
        signal.raise_signal(signal.SIGHUP)
def sync(folder):  # write_files_atomically syncs the folder once every file is switched
    signal.raise_signal(signal.SIGHUP)
    real_sync(folder)
os.replace, files._fsync_dir = replace, sync
out = Path(sys.argv[1])
new = {"a.viser": b"new viser", "a.json": b"new json"}
if sys.argv[2] == "set":
    fileset.write_set(out, "a", new)
else:
    files.write_files_atomically(out, new)
"""


@pytest.mark.parametrize("writer", ["set", "files"])
@pytest.mark.slow
def test_sighup_while_syncing_after_the_switch_ends_quietly_with_the_new_files(tmp_path, writer):
    res = subprocess.run(
        [sys.executable, "-c", _HUP_AFTER_SWITCH, str(tmp_path), writer],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == -signal.SIGHUP and res.stderr == "", res.stderr
    assert (tmp_path / "a.viser").read_bytes() == b"new viser"
    assert (tmp_path / "a.json").read_bytes() == b"new json"
    assert not [p for p in tmp_path.iterdir() if p.name.endswith((".partial", ".old"))]


def test_the_builtin_demos_stay_within_the_limits():
    for d in rec.list_demos():
        demo_module.check_scale(d)


def test_an_output_folder_below_a_file_is_one_line(tmp_path, capsys):
    (tmp_path / "file").write_text("not a folder")
    err = _one_line_status_2(capsys, ["record", "helix", "--out", str(tmp_path / "file" / "out")])
    assert "is not a folder" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
