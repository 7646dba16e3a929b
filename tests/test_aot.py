"""Taylor's method compiled ahead of time: loaded without numba, the same steps as the Solver."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from mechviz.dynamics import Hoop
from mechviz.dynamics.solver import Solver

HOOP = {"state": [0.5, -0.3, 0.0, 0.0], "params": [1.0, 0.5, 1.0, 9.81]}
SCRIPT = """
import json, sys
from mechviz.dynamics.aot import load, solve
y = solve("hoop", {state}, 5.0, params={params}, rtol=1e-10)
print(json.dumps({{"y": list(y), "numba": "numba" in sys.modules, "aot": load() is not None}}))
"""


def _fresh(tmp_path) -> dict:
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    run = subprocess.run(
        [sys.executable, "-c", SCRIPT.format(**HOOP)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(run.stdout)


def _solver() -> np.ndarray:
    solver = Solver(Hoop(), rtol=1e-10)
    return solver.solve(5.0, HOOP["state"], HOOP["params"]).copy()


@pytest.mark.slow
def test_unbuilt_it_falls_back_to_the_compiled_solver(tmp_path):
    out = _fresh(tmp_path)
    assert out["aot"] is False and out["numba"] is True
    np.testing.assert_array_equal(out["y"], _solver())


def test_a_bad_system_or_state_is_refused():
    from mechviz.dynamics import aot

    with pytest.raises(ValueError, match="system"):
        aot.solve("pendulum", [0.0], 1.0, [1.0])
    with pytest.raises(ValueError, match="finite"):
        aot.solve("hoop", [0.0, np.nan, 0.0, 0.0], 1.0, HOOP["params"])


@pytest.mark.slow
def test_built_it_answers_in_a_process_that_never_imports_numba(tmp_path):
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    subprocess.run(
        [sys.executable, "-m", "mechviz.dynamics.aot"], env=env, check=True, capture_output=True
    )
    out = _fresh(tmp_path)
    assert out["aot"] is True and out["numba"] is False
    # the same steps compiled for a generic CPU: equal to round-off
    np.testing.assert_allclose(out["y"], _solver(), rtol=1e-12, atol=1e-12)


RUN = """
import json, sys
from mechviz.dynamics import Cyclotron, Hoop, ReleasedDisk, Simulation
from mechviz.dynamics import aot
out = {}
for name, system in (("cyclotron", Cyclotron()), ("hoop", Hoop()),
                     ("free-body", ReleasedDisk(extra_spin=(0.01, 0.0, 0.01)))):
    sim = Simulation(system, "taylor", rtol=1e-10, atol=1e-10, reference=None)
    states = []
    for t in (0.7, 3.0, 3.5, 20.0):  # sampled: the kept step carries from call to call
        sim.advance_to(t)
        states.append(sim.state[0].tolist())
    out[name] = {"states": states, "steps": sim.steps}
out["modules"] = {n: n in sys.modules for n in ("numba", "scipy", "sympy", "llvmlite")}
out["aot"] = aot.load() is not None
print(json.dumps(out))
"""


def _process(tmp_path, aot: str) -> dict:
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path), "MECHVIZ_AOT": aot}
    env.pop("NUMBA_CACHE_DIR", None)
    run = subprocess.run(
        [sys.executable, "-c", RUN], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(run.stdout)


def _jit_here() -> dict:
    from mechviz.dynamics import Cyclotron, ReleasedDisk, Simulation

    out = {}
    systems = (("cyclotron", Cyclotron()), ("hoop", Hoop()))
    for name, system in (*systems, ("free-body", ReleasedDisk(extra_spin=(0.01, 0.0, 0.01)))):
        sim = Simulation(system, "taylor", rtol=1e-10, atol=1e-10, reference=None)
        states = []
        for t in (0.7, 3.0, 3.5, 20.0):
            sim.advance_to(t)
            states.append(sim.state[0].tolist())
        out[name] = {"states": states, "steps": sim.steps}
    return out


@pytest.mark.slow
def test_a_taylor_run_builds_it_in_the_background_and_the_next_runs_without_numba(tmp_path):
    import time

    from mechviz.dynamics import aot as module

    assert os.environ.get("MECHVIZ_AOT") == "0"  # this process: through numba (conftest)
    first = _process(tmp_path, "1")  # through numba, and starts the build behind it
    assert first["aot"] is False and first["modules"]["numba"] is True
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}
    probe = "from mechviz.dynamics import aot; print(aot.path() or '')"
    deadline = time.monotonic() + 600
    while True:
        found = subprocess.run(
            [sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True
        ).stdout.strip()
        if found:
            break
        assert time.monotonic() < deadline, "the background build wrote no module in 600 s"
        time.sleep(5)
    assert module.STALE_BUILD_S > 0
    second = _process(tmp_path, "1")
    assert second["aot"] is True
    # a fresh process answered without numba, scipy or sympy
    assert not any(second["modules"].values()), second["modules"]
    # the same loop compiled for this processor: the same steps, the same numbers
    jit = _jit_here()
    for name in ("cyclotron", "hoop", "free-body"):
        assert second[name]["steps"] == first[name]["steps"] == jit[name]["steps"]
        np.testing.assert_array_equal(second[name]["states"], jit[name]["states"])
        np.testing.assert_array_equal(first[name]["states"], jit[name]["states"])
    # turned off, a process goes through numba even with the module built
    off = _process(tmp_path, "0")
    assert off["modules"]["numba"] is True
    np.testing.assert_array_equal(off["hoop"]["states"], jit["hoop"]["states"])
