"""One description per system: the command line, the Python API, the viewer and a demo file start
every system from the same default, and refuse the same bad value naming the same setting.

Each front end names a setting in its own words (a flag ``--bead-mass``, an argument
``bead_mass``, a panel label "Bead mass m [kg]", a demo key ``parameters.bead_mass``); all of
them come from the one :class:`mechviz.dynamics.Setting` of :data:`mechviz.dynamics.SPECS`.
"""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys

import numpy as np
import pytest

from mechviz import dynamics
from mechviz.dynamics import api
from mechviz.viz.model.commands import Set

T_END = 0.25


def cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mechviz.viz.cli", *args],
        capture_output=True,
        text=True,
        timeout=300,
    )


@pytest.fixture(scope="module")
def app():
    viz_app = pytest.importorskip("mechviz.viz.app")
    a = viz_app.MechvizApp(port=0, start_loop=False, environment_map=False)
    yield a
    with contextlib.redirect_stdout(io.StringIO()):
        a.stop()


@pytest.fixture
def server():
    viser = pytest.importorskip("viser")
    with contextlib.redirect_stdout(io.StringIO()):
        srv = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield srv
    with contextlib.redirect_stdout(io.StringIO()):
        srv.stop()


def _start(ex) -> tuple[np.ndarray, dict, str]:
    sim = ex.model.runs()["main"]
    return sim.state0[0], dict(ex.model.config.physics().__dict__), sim.method.name


@pytest.mark.parametrize("system", list(dynamics.SPECS))
@pytest.mark.slow
def test_every_front_end_starts_a_system_from_the_same_default(system, app, server):
    from mechviz.viz.record.demo import parse_demo
    from mechviz.viz.scene import EXHIBITS

    spec = dynamics.SPECS[system]
    want = spec.setup()

    out = cli("simulate", system, "--t-end", str(T_END), "--samples", "2", "--json")
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout)
    from_cli = (np.array(list(r["initial_state"].values())), r["parameters"], r["method"])

    run = api.simulate(system, t_end=T_END, samples=2)
    from_api = (run.states[0], run.parameters, run.method)

    from_viewer = _start(app.exhibits[system])

    demo = parse_demo({"exhibit": system, "duration": 1.0}, name="minimal")
    from_demo = _start(EXHIBITS[system](server, demo.config()))

    for name, (state, params, method) in {
        "cli": from_cli,
        "api": from_api,
        "viewer": from_viewer,
        "demo": from_demo,
    }.items():
        np.testing.assert_allclose(state, want.state, rtol=0, atol=1e-15, err_msg=name)
        assert params == pytest.approx(want.params.__dict__), name
        assert method == want.method.name, name
    # and the default is one that moves: a start at rest in equilibrium would show nothing
    assert np.any(want.state != 0.0) and want.system.energy(want.state) != pytest.approx(
        want.system.energy_floor(), abs=1e-12
    )


# What each front end is given for one bad value: (setting, its method, the value as typed).
BAD = [
    ("dt", "rk4", "0"),
    ("rtol", "dop853", "2"),
    ("bead_mass", None, "-1"),
    ("bead_mass", None, "abc"),
]


def _named(spec, field: str) -> dict[str, str]:
    """How each front end names the setting ``field``."""
    if field in ("dt", "rtol"):
        return {"cli": f"--{field}", "api": field, "viewer": field, "demo": field}
    s = spec.setting(field)
    return {"cli": s.flag, "api": s.name, "viewer": s.panel_label, "demo": f"parameters.{s.name}"}


@pytest.mark.parametrize(("field", "method", "typed"), BAD)
@pytest.mark.slow
def test_every_front_end_refuses_a_bad_value_naming_the_same_setting(field, method, typed, app):
    from mechviz.viz.record.demo import parse_demo

    system = "hoop"
    spec = dynamics.SPECS[system]
    named = _named(spec, field)
    number = typed if typed == "abc" else float(typed)

    args = ["simulate", system, "--t-end", "1", *(["--method", method] if method else [])]
    out = cli(*args, named["cli"], typed)
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and named["cli"] in out.stderr, out.stderr

    kwargs = {"method": method} if method else {}
    with pytest.raises(dynamics.SettingError) as err:
        api.simulate(system, t_end=1.0, **kwargs, **{field: number})
    assert err.value.field == named["api"]

    ex = app.exhibits[system]
    before = ex.model.config
    if field == "rtol":  # a dropdown in the panel: only the model can be given a bad one
        with pytest.raises(dynamics.SettingError) as err:
            ex.model.apply(Set(fields={"method": method, "rtol": number}))
        assert err.value.field == named["viewer"]
    else:
        key = f"{system}.params.{field}" if field in spec.default_params() else f"{system}.{field}"
        count = len(app.messages)
        app.w[key].value = typed  # typed, then Enter
        app.number_fields[key].submit()
        app.step_frame()
        assert len(app.messages) > count
        label = named["viewer"] if field != "dt" else "Step dt [s]"
        assert app.messages[-1][1].startswith(label), app.messages[-1]
    assert ex.model.config == before

    table = {"exhibit": system, "duration": 1.0, **({"method": method} if method else {})}
    if field in spec.default_params():
        table["parameters"] = {field: number}
    else:
        table[field] = number
    with pytest.raises(dynamics.SettingError) as err:
        parse_demo(table, name="bad")
    assert err.value.field == named["demo"]
    assert named["demo"] in str(err.value)


def test_a_typed_number_is_read_by_one_rule_everywhere():
    """The command line, the panel and the demo's parameters accept what Python reads as a float
    and refuse the rest with the field named; a subnormal has lost its digits and is refused."""
    from mechviz.viz.scene.panel import parse_number as panel_number

    for text, value in [("2.5e-2", 0.025), ("1E-2", 0.01), ("\u22121", -1.0), (" 3 ", 3.0)]:
        assert dynamics.parse_number("x", text) == value
        assert panel_number("x", text) == value
    for text in ["abc", "nan", "inf", "1e-320", "2.5e", "", "1_0", "\uff11", "0x10"]:
        with pytest.raises(dynamics.SettingError) as err:
            dynamics.parse_number("Step dt [s]", text)
        assert err.value.field == "Step dt [s]" and str(err.value).startswith("Step dt [s]")


def test_the_step_control_is_one_value_checked_once():
    rk4, dop, exact = (dynamics.get_method(n) for n in ("rk4", "dop853", "exact"))
    assert dynamics.step_control(rk4, dt=0.1) == dynamics.Fixed(0.1)
    assert dynamics.step_control(dop, rtol=1e-6) == dynamics.Tolerance(1e-6, 1e-6)
    assert dynamics.step_control(exact) == dynamics.Exact()
    for method, kw, field in [
        (rk4, {}, "dt"),
        (rk4, {"dt": -1}, "dt"),
        (dop, {"rtol": 1}, "rtol"),
        (dop, {"rtol": 1e-6, "atol": 0}, "atol"),
    ]:
        with pytest.raises(dynamics.SettingError) as err:
            dynamics.step_control(method, **kw)
        assert err.value.field == field


@pytest.mark.parametrize(
    "flag, text", [("--mass", "1_0"), ("--mass", "\uff11"), ("--samples", "1_0")]
)
def test_the_command_line_refuses_underscores_and_digits_beyond_ascii(capsys, flag, text):
    from mechviz.viz.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["simulate", "cyclotron", flag, text])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and flag in err[0], err
