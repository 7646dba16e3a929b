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
