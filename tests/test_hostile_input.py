"""Hostile input, generated: every number a user can give, at the edges of the number line.

Command lines are generated from the parser itself (each option whose type is a number or a
count), demo files by mutating each numeric key of every built-in demo; each gets the values
0, +-5e-324, +-1e-308, +-1e308, inf, nan and out of range. Each must end in one of two ways:
refused with exit status 2 and one line naming that very flag or key, or a successful run. No
traceback, no refusal naming another field. The cheap checks run in-process (``main(argv)``);
recording the mutated demos that are accepted, and serving, run as subprocesses under a
time limit (marked slow).
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import io
import json
import math
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from mechviz.viz.cli import build_parser, main

# every test here runs the command line or records over hundreds of hostile inputs
pytestmark = pytest.mark.slow

TIMEOUT = 120 * float(os.environ.get("MECHVIZ_TIMEOUT_FACTOR", "1"))
EDGES = ["0", "5e-324", "-5e-324", "1e-308", "-1e-308", "1e308", "-1e308", "inf", "-inf", "nan"]
OUT_OF_RANGE = ["-1", "1e400", "1.7e308", str(10**100)]


def run_main(argv: list[str]) -> tuple[int, list[str]]:
    """``mechviz ARGV`` in this process: (exit status, stderr lines)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's refusals
            code = exc.code
    return code, [x for x in err.getvalue().splitlines() if x.strip()]


def numeric_options(*command: str) -> list[str]:
    """The options of ``mechviz COMMAND`` that take a number or a count."""
    parser = build_parser()
    for word in command:
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[word]
    return [
        a.option_strings[0]
        for a in parser._actions
        if a.option_strings and a.type is not None and a.type is not str and not a.choices
    ]


def assert_refused_naming(code, lines, name: str, argv, *, or_ok: bool = True) -> None:
    if or_ok and code == 0:
        return
    assert code == 2, (argv, code, lines)
    assert len(lines) == 1, (argv, lines)
    assert name in lines[0] and "Traceback" not in lines[0], (argv, lines)


# --------------------------------------------------------------------------- command lines
COMMANDS = {
    ("analyze", "cyclotron"): [],
    ("analyze", "disk"): [],
    ("analyze", "hoop"): [],
    ("simulate", "cyclotron"): ["--t-end", "1", "--method", "boris", "--dt", "0.01"],
    ("simulate", "disk"): [
        "--motion",
        "released",
        "--t-end",
        "1",
        "--method",
        "rk4",
        "--dt",
        "0.01",
    ],
    ("simulate", "hoop"): ["--t-end", "1", "--method", "rk4", "--dt", "0.01"],
}


def _argv(command: tuple[str, ...], base: list[str], flag: str, value: str) -> list[str]:
    base = list(base)
    if flag in base:  # the flag under test replaces the base's value
        i = base.index(flag)
        del base[i : i + 2]
    if flag == "--rtol":
        i = base.index("--dt") if "--dt" in base else None
        if i is not None:
            del base[i : i + 2]
        base += ["--method", "dop853"] if "--method" not in base else []
        base[base.index("--method") + 1] = "dop853"
    return [*command, *base, flag, value]


@pytest.mark.parametrize("command", list(COMMANDS), ids=" ".join)
def test_every_number_flag_of_analyze_and_simulate_is_refused_by_name_or_runs(command):
    base = COMMANDS[command]
    flags = numeric_options(*command)
    assert flags, command
    for flag in flags:
        for value in EDGES + OUT_OF_RANGE:
            argv = _argv(command, base, flag, value)
            code, lines = run_main(argv)
            assert_refused_naming(code, lines, flag, argv)


def test_the_disk_mass_whose_default_bead_overflows_is_blamed_not_the_bead():
    code, lines = run_main(["analyze", "disk", "--disk-mass", "1.5e308"])
    assert code == 2 and len(lines) == 1 and "--disk-mass" in lines[0]
    assert "--bead-mass" not in lines[0]


# (command, base argv, a sentinel failure after the checks: a value accepted reads as it)
GATED = {
    ("record",): (["helix", "--out", "{file}"], "--out"),
    ("video",): (["{missing}.viser"], "missing"),
    ("bench",): (["--endurance", "5"], None),
    ("view",): (["--host", "999.999.999.999"], "--host"),
    # a file as --out: refused once every other flag has been checked, before any work
    ("atlas",): (
        ["chaos", "--out", "{file}", "--theta1=-1:1:2", "--theta2=-1:1:2", "--duration", "1"],
        "is not a folder",
    ),
}


@pytest.mark.parametrize("command", list(GATED), ids=" ".join)
def test_every_count_and_number_of_the_other_commands_is_refused_by_name(command, tmp_path):
    base, sentinel = GATED[command]
    a_file = tmp_path / "a-file"
    a_file.write_text("")
    base = [
        b.replace("{file}", str(a_file)).replace("{missing}", str(tmp_path / "missing"))
        for b in base
    ]
    flags = [f for f in numeric_options(*command) if f not in ("--host",)]
    assert flags, command
    for flag in flags:
        for value in EDGES + OUT_OF_RANGE:
            if command == ("bench",) and flag == "--clients":
                argv = ["bench", "--endurance", "0", flag, value]  # refused either way
                code, lines = run_main(argv)
                assert code == 2 and len(lines) == 1, (argv, lines)
                assert flag in lines[0] or "--endurance" in lines[0], (argv, lines)
                continue
            argv = [*command, *[b for b in base if b != flag], flag, value]
            if flag in base:
                i = base.index(flag)
                argv = [*command, *base[:i], *base[i + 2 :], flag, value]
            code, lines = run_main(argv)
            if sentinel and code == 2 and len(lines) == 1 and sentinel in lines[0]:
                continue  # accepted: the run stopped at the sentinel that follows the checks
            assert_refused_naming(code, lines, flag, argv, or_ok=False)


@pytest.mark.parametrize(
    "host", ["999.999.999.999", "example.invalid", "a" * 300, "8.8.8.8", "-1", "a b", "::g"]
)
def test_a_host_that_cannot_be_served_on_is_one_line_naming_host(host):
    code, lines = run_main(["view", "--host", host, "--port", "0"])
    assert code == 2 and len(lines) == 1 and "--host" in lines[0], lines


def test_a_command_line_that_is_not_a_demo_or_a_path_is_refused_with_status_2(tmp_path):
    code, lines = run_main(["record", "no-such-demo", "--out", str(tmp_path / "o")])
    assert code == 2 and len(lines) == 1 and "no-such-demo" in lines[0]


# --------------------------------------------------------------------------- demo files
def _demo_dir() -> Path:
    from mechviz.viz.record.demo import DEMO_DIR

    return DEMO_DIR


def _toml(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    return "[" + ", ".join(_toml(v) for v in value) + "]"


def _dump(raw: dict) -> str:
    lines, tables = [], []
    for k, v in raw.items():
        if isinstance(v, dict) or (isinstance(v, list) and v and isinstance(v[0], dict)):
            tables.append((k, v))
        else:
            lines.append(f"{k} = {_toml(v)}")
    for k, v in tables:
        for item in [v] if isinstance(v, dict) else v:
            lines.append(f"[{k}]" if isinstance(v, dict) else f"[[{k}]]")
            lines += [f"{kk} = {_toml(vv)}" for kk, vv in item.items()]
    return "\n".join(lines) + "\n"


def _numeric_keys(raw: dict) -> list[tuple]:
    """Every numeric key path of ``raw`` (elements of arrays included), and the exhibit's
    parameters and step settings even where the file leaves them out."""
    from mechviz.viz.scene import EXHIBITS

    out: list[tuple] = []
    for k, v in raw.items():
        if isinstance(v, int | float) and not isinstance(v, bool):
            out.append((k,))
        elif isinstance(v, dict):
            for kk, vv in v.items():
                if isinstance(vv, int | float) and not isinstance(vv, bool):
                    out.append((k, kk))
                elif isinstance(vv, list):
                    out += [(k, kk, i) for i in range(len(vv))]
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for i, item in enumerate(v):
                out += [(k, i, kk) for kk, vv in item.items() if isinstance(vv, int | float)]
    out += [("parameters", p) for p in EXHIBITS[raw["exhibit"]].model_type.Config().params]
    out += [(k,) for k in ("speed", "dt", "rtol")]
    return list(dict.fromkeys(out))


def _set(raw: dict, path: tuple, value) -> dict:
    raw = copy.deepcopy(raw)
    cur = raw
    for p in path[:-1]:
        cur = cur.setdefault(p, {}) if isinstance(cur, dict) else cur[p]
    cur[path[-1]] = value
    return raw


def _key(path: tuple) -> str:
    """The key as a refusal names it: ``initial.speeds`` for ``initial.speeds[1]``."""
    text = ""
    for p in path:
        text += f"[{p}]" if isinstance(p, int) else (f".{p}" if text else p)
    return re.sub(r"\[\d+\]$", "", text)


DEMO_VALUES = [float(v) for v in EDGES] + [-1.0, 1e-300, 1e300, 1.7e308]


def _mutations():
    for path in sorted(_demo_dir().glob("*.toml")):
        raw = tomllib.loads(path.read_text())
        for keys in _numeric_keys(raw):
            for value in DEMO_VALUES:
                yield path.stem, keys, value, _set(raw, keys, value)


def test_every_mutated_demo_is_refused_naming_its_key_or_loads(tmp_path):
    from mechviz.viz.record import load_demo

    accepted = 0
    for name, keys, value, raw in _mutations():
        f = tmp_path / f"{name}.toml"
        f.write_text(_dump(raw))
        try:
            load_demo(str(f))
        except ValueError as exc:
            msg = str(exc)
            assert "\n" not in msg and _key(keys) in msg, (name, keys, value, msg)
            continue
        accepted += 1
    assert accepted > 0  # the values in range still load


def test_the_demo_cases_the_first_round_found_are_refused_by_key(tmp_path):
    cases = [
        ("tumbling-disk", ("parameters", "disk_mass"), 1e-300),
        ("tumbling-disk", ("parameters", "radius"), 1e-308),
        ("tumbling-disk", ("parameters", "radius"), 1e308),
        ("tumbling-disk", ("parameters", "omega"), 1e308),
        ("tumbling-disk", ("parameters", "omega"), 1e-308),
        ("helix", ("parameters", "charge"), 1e-300),
        ("helix", ("parameters", "field"), 1e-300),
        ("helix", ("duration",), 5e-324),
        ("helix", ("speed",), 1e-308),
        ("hoop-mode1", ("parameters", "gravity"), 1e-308),
        ("hoop-mode1", ("parameters", "bead_mass"), 1e308),
        ("hoop-mode1", ("parameters", "radius"), 1e-308),
    ]
    for name, keys, value in cases:
        raw = tomllib.loads((_demo_dir() / f"{name}.toml").read_text())
        f = tmp_path / f"{name}.toml"
        f.write_text(_dump(_set(raw, keys, value)))
        code, lines = run_main(["record", str(f), "--out", str(tmp_path / "out")])
        assert code == 2 and len(lines) == 1 and _key(keys) in lines[0], (name, keys, lines)
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_every_accepted_extreme_demo_records_or_is_refused_by_key(tmp_path):
    """The mutated demos that load, at the extreme values, recorded for real (5 fps)."""
    from mechviz.viz.record import load_demo

    checked = 0
    for name, keys, value, raw in _mutations():
        if value == 0.0 or 1e-6 < abs(value) < 1e6 or not math.isfinite(value):
            continue
        f = tmp_path / f"{name}.toml"
        f.write_text(_dump(raw))
        try:
            load_demo(str(f))
        except ValueError:
            continue
        out = subprocess.run(
            [
                sys.executable,
                "-m",
                "mechviz.viz.cli",
                "record",
                str(f),
                "--out",
                str(tmp_path / "o"),
                "--fps",
                "5",
            ],
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
        )
        checked += 1
        lines = [x for x in out.stderr.replace("\r", "\n").splitlines() if "error" in x]
        assert "Traceback" not in out.stderr, (name, keys, value, out.stderr[-2000:])
        assert out.returncode in (0, 2), (name, keys, value, out.stderr[-2000:])
        if out.returncode == 2:
            assert len(lines) == 1 and _key(keys) in lines[0], (name, keys, value, lines)
    assert checked > 0


@pytest.mark.slow
@pytest.mark.parametrize("host", ["999.999.999.999", "example.invalid", "a" * 300])
def test_view_answers_a_bad_host_at_once_as_a_process(host):
    out = subprocess.run(
        [sys.executable, "-m", "mechviz.viz.cli", "view", "--host", host, "--port", "0"],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
    )
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "--host" in out.stderr
    assert "compiling" not in out.stdout  # refused before anything compiles


def _viser(seconds: float) -> bytes:
    """A minimal recording in viser's format (as :mod:`recordings` reads it)."""
    import msgspec
    import zstandard

    payload = msgspec.msgpack.encode({"durationSeconds": seconds, "messages": []})
    inner = len(payload).to_bytes(8, "little") + payload
    return len(inner).to_bytes(8, "little") + zstandard.ZstdCompressor().compress(inner)


@pytest.mark.parametrize(
    "manifest, named",
    [
        ("{not json", "not JSON"),
        ('{"fps": 30, "duration": NaN, "title": "t"}', "NaN"),
        ('{"fps": 1000000000, "duration": 1, "title": "t"}', "frame rate"),
        ('{"fps": 30, "duration": 1}', "lacks title"),
        ('{"fps": 30, "duration": 1, "title": "a\\u0000b\\u001b[31m"}', "control character"),
        ("[1]", "not a JSON object"),
    ],
)
def test_video_refuses_a_broken_manifest_beside_the_recording_in_one_line(
    tmp_path, manifest, named
):
    (tmp_path / "r.viser").write_bytes(_viser(2.0))
    (tmp_path / "r.json").write_text(manifest)
    code, lines = run_main(["video", str(tmp_path / "r.viser"), "--out", str(tmp_path / "r.mp4")])
    assert code == 2 and len(lines) == 1, lines
    assert named in lines[0] and "\x1b" not in lines[0], lines
    assert not (tmp_path / "r.mp4").exists()


@pytest.mark.parametrize(
    "table",
    [
        {"title": "a\u0000b\u001b[31m"},
        {"description": "bell\u0007"},
        {"method": "rk4\u001b[2J"},
    ],
)
def test_every_text_of_a_demo_with_a_control_character_is_refused_naming_its_key(table):
    from mechviz.viz.record.demo import parse_demo

    with pytest.raises(ValueError) as err:
        parse_demo({"exhibit": "cyclotron", "duration": 1.0, **table}, name="bad")
    (key,) = table
    assert f"{key} holds a control character" in str(err.value)
    assert "\x1b" not in str(err.value) and "\x00" not in str(err.value)
