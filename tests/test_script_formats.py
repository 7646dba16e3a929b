"""What scripts read: ``--json`` with numbers as numbers (the step as ``dt``, ``rtol``, ``atol``
beside its words, counts), ``--json`` on the listing commands, and progress bars only on a
terminal, on stderr, and never with ``--no-progress``."""

from __future__ import annotations

import io
import json

import pytest

from mechviz.viz import progress
from mechviz.viz.cli import main


def run_json(capsys, *argv: str):
    assert main(list(argv)) == 0
    out = capsys.readouterr().out
    return json.loads(out)


def test_simulate_json_gives_the_step_as_numbers(capsys):
    fixed = run_json(
        capsys, "simulate", "hoop", "--t-end", "1", "--method", "rk4", "--dt", "0.01", "--json"
    )
    assert fixed["step"] == "dt=0.01 s"
    assert fixed["dt"] == pytest.approx(0.01) and isinstance(fixed["dt"], float)
    assert fixed["rtol"] is None and fixed["atol"] is None
    assert fixed["steps"] == 100 and fixed["samples"] == 201 and fixed["members"] == 1
    adaptive = run_json(
        capsys, "simulate", "hoop", "--t-end", "1", "--method", "dop853", "--rtol", "1e-8",
        "--atol", "1e-10", "--json",
    )  # fmt: skip
    assert (adaptive["dt"], adaptive["rtol"], adaptive["atol"]) == (None, 1e-8, 1e-10)
    assert isinstance(adaptive["steps"], int) and isinstance(adaptive["rhs_evaluations"], int)


def test_the_api_summary_has_the_same_numbers():
    from mechviz.dynamics import api

    s = api.simulate("hoop", method="rk4", dt=0.01, t_end=1.0).summary()
    assert s["dt"] == pytest.approx(0.01) and s["rtol"] is None and s["samples"] >= 2


def test_the_listings_print_json(capsys):
    from mechviz.viz import record as rec

    methods = run_json(capsys, "simulate", "--list-methods", "--json")["methods"]
    rk4 = next(m for m in methods if m["name"] == "rk4")
    assert rk4["order"] == 4 and rk4["adaptive"] is False and "hoop" in rk4["applies_to"]
    demos = run_json(capsys, "record", "--list", "--json")["demos"]
    assert [d["name"] for d in demos] == rec.demo_names()
    helix = next(d for d in demos if d["name"] == "helix")
    assert isinstance(helix["fps"], int) and isinstance(helix["duration"], float)


def test_record_json_without_list_is_refused_in_one_line(capsys):
    assert main(["record", "helix", "--json", "--out", "x"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--json: only with --list" in err


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_bar_shows_on_a_terminal_only_and_never_after_no_progress(monkeypatch):
    monkeypatch.setattr(progress, "_silenced", False)
    assert progress.progress_bar("x", 10, stream=io.StringIO()).disable  # a pipe: silent
    on_terminal = progress.progress_bar("x", 10, stream=_Terminal())
    assert not on_terminal.disable
    on_terminal.close()
    progress.silence()
    assert progress.progress_bar("x", 10, stream=_Terminal()).disable


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", "hoop", "--t-end", "1"],
        ["record", "helix", "--out", "x"],
        ["video", "x.viser"],
        ["bench"],
        ["atlas", "--out", "x"],
    ],
)
def test_every_command_that_shows_progress_takes_no_progress(argv):
    from mechviz.viz.cli import build_parser

    args = build_parser().parse_args([*argv, "--no-progress"])
    assert args.no_progress is True


def test_the_atlas_bar_stays_out_of_a_pipe(monkeypatch):
    pytest.importorskip("xarray")
    from mechviz.dynamics.atlas import driver

    monkeypatch.setattr("sys.stderr", io.StringIO())
    with driver._progress(True, 3, 0) as bar:
        assert bar.disable
