"""Recording demo sessions (mechviz.viz.record), headless: every built-in demo records, its manifest
agrees with theory, the .viser decodes frame by frame, failures leave no partial files."""

from __future__ import annotations

import csv
import io
import json
import os
from pathlib import Path

import numpy as np
import pytest
from faults import disk_full_at_nth_fsync
from recordings import decode_recording, frame_times

from mechviz import dynamics
from mechviz.viz import record as rec
from mechviz.viz.cli import main
from mechviz.viz.model.commands import Kick, Set
from mechviz.viz.scene import EXHIBITS, CyclotronExhibit

# Short runs that still hold enough motion to measure each demo's figures.
SHORT = {
    "beam": 6.3,  # one gyro-period (2 pi s)
    "driven-disk": 5.0,  # three zero crossings of the force (a full period) at omega = 2
    "euler-vs-boris": 3.0,
    "helix": 3.0,
    "hoop-large-amplitude": 5.0,  # three zero crossings (a full period) of the 3.8 s swing
    "hoop-mode1": 4.0,  # three zero crossings (a full period) at 2.8 s
    "hoop-mode2": 3.0,
    "radial-kick": 8.0,  # the kick is at t = 5 s
    "rk4-vs-verlet": 2.0,
    "tumbling-disk": 5.0,
}
FPS = 15


def test_every_builtin_demo_is_listed_with_a_short_run_here():
    assert sorted(SHORT) == rec.demo_names()
    assert len(rec.demo_names()) >= 10


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("demos")
    results = {}
    for name, duration in SHORT.items():
        demo = rec.load_demo(name).with_overrides(duration=duration, fps=FPS)
        results[name] = rec.record(demo, out)
    return out, results


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SHORT))
def test_builtin_demo_records_five_complete_files(recorded, name):
    out, results = recorded
    res = results[name]
    for suffix in rec.SUFFIXES:
        assert (out / f"{name}{suffix}").stat().st_size > 0
    assert not list(out.glob(".*partial"))
    man = json.loads((out / f"{name}.json").read_text())
    assert man["demo"] == name and man["frames"] == res.frames == round(SHORT[name] * FPS) + 1
    for key in ("parameters", "method", "step", "duration", "versions", "figures", "final_errors"):
        assert key in man, key
    assert man["versions"]["viser"] and man["versions"]["numpy"]
    for fname, meta in man["files"].items():
        assert (out / fname).stat().st_size == meta["bytes"]
    html = (out / f"{name}.html").read_text()
    assert "window.__VISER_EMBED_DATA__=" in html and "</html>" in html.lower()
    png = (out / f"{name}.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SHORT))
def test_viser_file_decodes_and_holds_one_frame_per_fps_tick(recorded, name):
    out, results = recorded
    data = (out / f"{name}.viser").read_bytes()
    decoded = decode_recording(data)
    frames = results[name].frames
    assert decoded["durationSeconds"] == pytest.approx(frames / FPS)
    times = frame_times(data)
    assert len(times) == frames
    assert times == pytest.approx([k / FPS for k in range(frames)])


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SHORT))
def test_csv_holds_every_run_member_and_frame(recorded, name):
    out, results = recorded
    rows = list(csv.DictReader(io.StringIO((out / f"{name}.csv").read_text())))
    res = results[name]
    demo = res.demo
    runs = 1 + (demo.compare is not None)
    members = demo.initial.beam or 1
    ghost = res.frames if demo.ghost else 0
    assert len(rows) == runs * members * res.frames + ghost
    first = rows[0]
    system = (
        "driven-disk"
        if demo.motion == "driven"
        else EXHIBITS[demo.exhibit].model_type.Config.system_name
    )
    names = dynamics.SYSTEMS[system].state_names
    assert list(first)[:3] == ["run", "member", "t"] and all(n in first for n in names)
    assert float(first["t"]) == 0.0 and float(first["energy_error"]) == 0.0


def _figures(recorded, name):
    return {f["name"]: f for f in recorded[1][name].manifest["figures"]}


# (demo, figure, relative tolerance against the analytic prediction)
AGREES = [
    ("helix", "gyrofrequency", 1e-4),  # Boris lags by (Omega dt)^2 / 12 = 8e-6
    ("helix", "Larmor radius", 1e-9),
    ("helix", "helix pitch", 1e-4),
    ("radial-kick", "circle shift after the kick", 1e-6),
    ("radial-kick", "radius after the kick", 1e-6),
    ("radial-kick", "gyrofrequency after the kick", 1e-4),
    ("beam", "shortest period in the beam", 1e-4),
    ("beam", "longest period in the beam", 1e-4),
    ("driven-disk", "spin rate", 1e-9),
    ("driven-disk", "bearing force amplitude at B", 1e-12),  # differences' bias divided out
    ("driven-disk", "bearing force frequency", 1e-3),
    ("tumbling-disk", "wobble growth rate", 1e-3),
    ("hoop-mode1", "mode 1 frequency", 5e-3),
    ("hoop-mode2", "mode 2 frequency", 1e-2),  # 0.1 rad: weakly nonlinear
    ("hoop-large-amplitude", "mode 1 frequency at this amplitude", 1e-3),
    ("euler-vs-boris", "final energy error, euler", 1e-9),  # (1 + (Omega dt)^2)^n - 1
]


@pytest.mark.slow
@pytest.mark.parametrize(("name", "figure", "tol"), AGREES)
def test_manifest_figure_agrees_with_analytic_prediction(recorded, name, figure, tol):
    f = _figures(recorded, name)[figure]
    assert f["relative_difference"] is not None
    assert f["relative_difference"] < tol, f


@pytest.mark.slow
def test_large_amplitude_hoop_departs_from_linear_theory(recorded):
    f = _figures(recorded, "hoop-large-amplitude")["mode 1 frequency"]
    assert f["relative_difference"] > 0.2  # 2 rad: the period is 33 % longer than linear theory


@pytest.mark.slow
def test_symplectic_runs_conserve_what_theory_says(recorded):
    boris = _figures(recorded, "euler-vs-boris")["final energy error, boris"]
    assert abs(boris["measured"]) < 1e-12
    assert _figures(recorded, "tumbling-disk")["final |L| change"]["measured"] < 1e-10
    errs = recorded[1]["rk4-vs-verlet"].manifest["final_errors"]
    assert set(errs) == {"verlet", "rk4"}
    for e in errs.values():  # against the DOP853 reference: its own error measured beside it
        assert e["error_against"] == "reference" and e["reference_error_final"] > 0.0
        assert e["error_resolved"] == (e["error_final"] >= 10 * e["reference_error_final"])


@pytest.mark.slow
def test_beam_periods_are_equal_although_speeds_differ(recorded):
    figs = _figures(recorded, "beam")
    assert figs["speed ratio in the beam"]["measured"] == pytest.approx(6.0)
    lo = figs["shortest period in the beam"]["measured"]
    hi = figs["longest period in the beam"]["measured"]
    assert (hi - lo) / lo < 1e-9


# --------------------------------------------------------------------------- failures
def _files(folder: Path) -> dict[str, bytes | str]:
    """Everything under ``folder``: files by content, links by target, folders as "dir"."""
    out: dict[str, bytes | str] = {}
    for p in sorted(folder.rglob("*")) if folder.exists() else []:
        key = str(p.relative_to(folder))
        out[key] = (
            f"-> {os.readlink(p)}" if p.is_symlink() else p.read_bytes() if p.is_file() else "dir"
        )
    return out


def _short(name="helix"):
    return rec.load_demo(name).with_overrides(duration=1.0, fps=10)


def _interrupt_at(frame):
    def progress(done, total):
        if done == frame:
            raise KeyboardInterrupt

    return progress


@pytest.mark.slow
def test_a_dark_recording_opens_on_the_dark_page(tmp_path):
    res = rec.record(_short(), tmp_path, theme="dark")
    assert "darkMode:true" in res.paths[".html"].read_text()
    assert "darkMode:false" in rec.record(_short(), tmp_path / "light").paths[".html"].read_text()


@pytest.mark.slow
def test_interrupted_first_recording_leaves_nothing(tmp_path):
    out = tmp_path / "new"
    with pytest.raises(rec.RecordingFailed, match="interrupted; nothing was written") as info:
        rec.record(_short(), out, progress=_interrupt_at(5))
    assert info.value.interrupted
    assert _files(out) == {}


@pytest.mark.slow
def test_interrupted_recording_keeps_the_previous_files_unchanged(tmp_path):
    rec.record(_short(), tmp_path)
    before = _files(tmp_path)
    assert sum("/" not in k and not k.startswith(".") for k in before) == 5
    with pytest.raises(rec.RecordingFailed, match="keeps the previous complete recording of helix"):
        rec.record(_short(), tmp_path, progress=_interrupt_at(3))
    assert _files(tmp_path) == before


@pytest.mark.slow
def test_full_disk_while_writing_leaves_no_partial_file(tmp_path, monkeypatch):
    rec.record(_short(), tmp_path)
    before = _files(tmp_path)
    disk_full_at_nth_fsync(monkeypatch, 3)
    with pytest.raises(rec.RecordingFailed, match=r"No space left on device; .* is unchanged"):
        rec.record(_short(), tmp_path)
    assert _files(tmp_path) == before  # no .partial file left behind, old files intact


def _blowing_up_demo(name="blowup"):
    raw = {
        "title": "Euler blows up",
        "description": "explicit Euler with a huge step",
        "exhibit": "cyclotron",
        "method": "euler",
        "dt": 100.0,
        "duration": 10.0,
        "fps": 10,
        "speed": 1000.0,
        "initial": {"speed": 1.0},
    }
    return rec.parse_demo(raw, name=name)


@pytest.mark.slow
def test_method_that_blows_up_fails_the_recording_and_writes_nothing(tmp_path):
    with pytest.raises(rec.RecordingFailed, match=r"euler.*nothing was written") as info:
        rec.record(_blowing_up_demo(), tmp_path / "out")
    assert isinstance(info.value.__cause__, dynamics.IntegrationError)
    assert "press Reset" not in str(info.value)  # the viewer's advice is not the recorder's
    assert _files(tmp_path / "out") == {}


# --------------------------------------------------------------------------- one path
@pytest.mark.slow
def test_recorded_beam_starts_where_the_live_beam_exhibit_starts(recorded, server):
    """The recorder draws with the viewer's exhibit: the beam demo's first frame holds the
    states the live cyclotron exhibit's beam starts from with the same settings."""
    out, results = recorded
    demo = results["beam"].demo
    live = CyclotronExhibit(server)
    live.model.apply(
        Set(
            fields={
                "method": demo.method,
                "dt": demo.dt,
                "vz": demo.initial.vz,
                "beam": True,
                "beam_size": demo.initial.beam,
                "beam_speeds": demo.initial.speeds,
            }
        )
    )
    rows = list(csv.DictReader(io.StringIO((out / "beam.csv").read_text())))
    names = dynamics.SYSTEMS["cyclotron"].state_names
    first = np.array([[float(r[n]) for n in names] for r in rows if float(r["t"]) == 0.0])
    assert first.shape == live.model.beam.state.shape == (12, 6)
    np.testing.assert_allclose(first, live.model.beam.state, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(
    ("name", "figure", "readout"),
    [
        ("helix", "gyrofrequency", lambda m: m["gyrofrequency"].value),
        (
            "hoop-mode2",
            "mode 2 frequency",
            lambda m: m["mode_frequencies"][1].value,
        ),
        ("driven-disk", "bearing force amplitude at B", lambda m: m["bearing_force"].value),
        ("tumbling-disk", "wobble growth rate", lambda m: m["growth_rate"].value),
    ],
)
@pytest.mark.slow
def test_a_readout_and_the_manifest_report_the_same_number_for_one_motion(name, figure, readout):
    """The exhibit's readout (what the viewer shows) and the manifest measure with the same
    estimator on the same samples, so they are the same number."""
    d = rec.load_demo(name).with_overrides(duration=SHORT[name], fps=FPS)
    run = rec.run_demo(d)
    figs = {f["name"]: f for f in rec.figures(d, run.traces)}
    shown = readout(run.traces.measured)
    assert shown is not None
    assert figs[figure]["measured"] == shown


# --------------------------------------------------------------------------- command line
def test_record_list_names_every_demo_with_a_description(capsys):
    assert main(["record", "--list"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in out] == rec.demo_names()
    assert all(len(line.split(None, 1)[1]) > 20 for line in out)


@pytest.mark.slow
def test_record_command_writes_the_files_and_reports(tmp_path, capsys):
    assert (
        main(["record", "hoop-mode1", "--out", str(tmp_path), "--duration", "1", "--fps", "10"])
        == 0
    )
    out = capsys.readouterr().out
    assert "hoop-mode1: 11 frames" in out
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".")) == [
        f"hoop-mode1{s}" for s in sorted(rec.SUFFIXES)
    ]


BAD_ARGS = [
    (["record", "nosuchdemo", "--out", "X"], "unknown demo 'nosuchdemo'"),
    (["record", "helix"], "--out DIR is required"),
    (["record", "--out", "X"], "give one DEMO or --all"),
    (["record", "helix", "--out", "X", "--dt", "-1"], "--dt: dt must be positive"),
    (
        ["record", "helix", "--out", "X", "--duration", "0"],
        "--duration: duration must be a positive",
    ),
    (["record", "helix", "--out", "X", "--fps", "0"], "--fps: fps must be a whole number"),
    (
        ["record", "helix", "--out", "X", "--method", "verlet"],
        "--method: method 'verlet' does not apply",
    ),
    (["record", "helix", "--out", "X", "--method", "nope"], "--method: method must be one of"),
    (["record", "helix", "--out", "X", "--fps", "ten"], "--fps: must be a whole number, got 'ten'"),
    (["record", "helix", "--out", "X", "--duration", "nan"], "must be finite"),
    (["play", "/nonexistent/demo.viser"], "no such file or folder"),
    (["record", "helix", "--out", "X", "--duration", "1e308"], "--duration: duration x fps gives"),
    (["record", "helix", "--out", "/tmp/" + "a" * 300], "--out: File name too long"),
]


@pytest.mark.parametrize(("argv", "message"), BAD_ARGS)
def test_bad_arguments_give_a_one_line_error_and_exit_status_2(argv, message, capsys, tmp_path):
    argv = [str(tmp_path / "X") if a == "X" else a for a in argv]
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert message in err, err
    assert not (tmp_path / "X").exists()


@pytest.mark.parametrize(
    ("extra", "named"),
    [("dt = 1e-9\n", "dt = 1e-09"), ("dt = 0.01\nspeed = 1e9\n", "speed x duration")],
)
def test_a_demo_beyond_the_step_limit_is_refused_before_it_runs(tmp_path, capsys, extra, named):
    demo_file = tmp_path / "huge.toml"
    demo_file.write_text(
        'title = "t"\ndescription = "d"\nexhibit = "cyclotron"\nmethod = "rk4"\n'
        "duration = 10.0\n" + extra
    )
    assert main(["record", str(demo_file), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "the limit is 1e+08" in err and named in err, err
    assert not (tmp_path / "out").exists()


def test_record_command_reports_a_blow_up_in_one_line_with_status_1(tmp_path, capsys):
    demo_file = tmp_path / "blowup.toml"
    demo_file.write_text(
        'title = "t"\ndescription = "d"\nexhibit = "cyclotron"\nmethod = "euler"\ndt = 100.0\n'
        "duration = 10.0\nfps = 10\nspeed = 1000.0\n"
    )
    assert main(["record", str(demo_file), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "nothing was written" in err
    assert not (tmp_path / "out").exists()


def test_demo_files_reject_unknown_keys():
    with pytest.raises(ValueError, match=r"x\.toml: contains unknown field `colour`"):
        rec.parse_demo({"colour": 1}, name="x")
    with pytest.raises(ValueError, match=r"x.toml: charg is not a parameter of the cyclotron"):
        rec.parse_demo(
            {
                "title": "t",
                "description": "d",
                "exhibit": "cyclotron",
                "method": "boris",
                "dt": 0.1,
                "duration": 1.0,
                "parameters": {"charg": 1.0},
            },
            name="x",
        )


# --------------------------------------------------------------------------- live Record toggle
@pytest.mark.slow
def test_viewer_record_toggle_records_the_session_and_offers_the_html(monkeypatch):
    import base64
    import re

    from mechviz.viz.app import MechvizApp

    app = MechvizApp(port=0, start_loop=False, environment_map=False)
    sent = []
    monkeypatch.setattr(
        app.server, "send_file_download", lambda name, content, **kw: sent.append((name, content))
    )
    try:
        recorder = app.recorder
        assert recorder is not None and recorder.checkbox.label == "Record"
        app.step_frame()
        recorder.checkbox.value = True  # as if ticked in the browser
        for k in range(40):
            if k == 10:
                app.enqueue("cyclotron", Kick(dv=0.5))
            if k == 20:
                app.enqueue("hoop", Set(fields={"method": "rk4"}))
            app.step_frame()
        assert recorder.recording
        recorder.checkbox.value = False
        app.step_frame()  # the loop applies the stop
        assert recorder.finished.wait(30)
    finally:
        app.stop()
    assert not recorder.recording
    assert [name for name, _ in sent] == [recorder.last_result[0]]
    name, html = sent[0]
    assert name.startswith("mechviz-session-") and name.endswith(".html")
    data = base64.b64decode(re.search(rb'__VISER_EMBED_DATA__="([^"]+)"', html).group(1))
    assert len(frame_times(data)) >= 40  # one frame per loop frame while recording
    assert any(title == "Recording saved" for title, _ in app.messages)


@pytest.mark.slow
def test_the_csv_holds_the_quantities_of_the_pictures_and_they_obey_their_physics(recorded):
    """The radial kick's rows: E_perp = p_r^2/2m + V_eff(r) for every sample (the well of the
    seed's argument, exact to round-off on Boris's rotation as on any state). The hoop's rows:
    the modal coordinates put the angles back together, theta = q1 s1 + q2 s2."""
    out, _ = recorded
    rows = list(csv.DictReader(io.StringIO((out / "radial-kick.csv").read_text())))
    p = rec.load_demo("radial-kick").config().physics()
    for r in rows:
        e_perp = 0.5 * p.mass * (float(r["vx"]) ** 2 + float(r["vy"]) ** 2)
        rebuilt = float(r["p_r"]) ** 2 / (2 * p.mass) + float(r["V_eff"])
        assert rebuilt == pytest.approx(e_perp, rel=1e-8, abs=1e-12)
    hoop = rec.load_demo("hoop-large-amplitude")
    _, shapes = dynamics.hoop.normal_modes(hoop.config().physics())
    rows = list(csv.DictReader(io.StringIO((out / "hoop-large-amplitude.csv").read_text())))
    assert {r["run"] for r in rows} >= {"linear-theory"}  # linear theory's coordinates too
    for r in rows:
        q = np.array([float(r["q1"]), float(r["q2"])])
        theta = q @ shapes
        assert theta == pytest.approx([float(r["theta1"]), float(r["theta2"])], abs=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "nodes"),
    [
        (
            "tumbling-disk",
            (
                "/disk/poinsot/ellipsoid",
                "/disk/invariable_plane/plane",
                "/disk/poinsot/polhode/c000001",
                "/disk/invariable_plane/herpolhode/c000001",
            ),
        ),
        (
            "hoop-mode1",
            ("/hoop/configuration_space/modes", "/hoop/configuration_space/path/c000001"),
        ),
    ],
)
def test_the_3d_pictures_are_in_the_scene_recording(recorded, name, nodes):
    """Poinsot's construction with its polhode and herpolhode traced, and configuration space
    with the path drawn: their scene nodes are in the .viser."""
    out, _ = recorded
    messages = decode_recording((out / f"{name}.viser").read_bytes())["messages"]
    names = {m.get("name") for _, m in messages if isinstance(m, dict)}
    assert set(nodes) <= names, set(nodes) - names
