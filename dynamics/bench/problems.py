"""The fixed benchmark problems of issue 6, their error metric and their reference final states.

========  ==========================================  ===================  ====================
problem   system and initial value                    span                 reference
========  ==========================================  ===================  ====================
charge    q = m = 1, B = 1 along +z; (1, 0, 0),       100 gyro-periods     exact helix
          velocity (0, 1, 0.1)                        (``200 pi``)
hoop      M = 1, m = 0.5, a = 1, g = 9.81;            20 s                 compiled DOP853 at
          theta = (0.5, -0.3) at rest                                      ``rtol = atol = 1e-13``
disk      the seed's disk and bead (M = R = 1, bead   50 s                 as for the hoop
          5M/4) released spinning at 1 rad/s about
          the axle plus 0.01 rad/s about x and z
========  ==========================================  ===================  ====================

Error: relative 2-norm of the final state against the reference; for the charge the norm of the
reference is that of its transverse part ``(x, y, vx, vy)``, so that the drift along B does not
hide the gyration error (:meth:`dynamics.systems.Cyclotron.error`). The references for the hoop
and the disk are computed once by :func:`compute_references`, cross-checked against scipy's
Radau at ``1e-12``, and stored with the library versions in ``assets/bench/references.json``.
"""

from __future__ import annotations

import json
import math
import platform
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..disk import DiskParams
from ..files import write_json_atomically
from ..simulation import Simulation
from ..systems import Cyclotron, Hoop, ReleasedDisk

REFERENCE_PATH = Path(__file__).resolve().parents[2] / "assets" / "bench" / "references.json"
REFERENCE_TOL = 1e-13
CROSS_CHECK_TOL = 1e-12


@dataclass(frozen=True)
class Problem:
    """One benchmark problem: a system, its initial state, the span and the methods to compare."""

    key: str
    title: str
    system: object
    state0: tuple[float, ...]
    t_end: float
    fixed: tuple[str, ...]  # our fixed-step methods
    n0: int  # fewest steps in the fixed-step sweep
    floor: float  # errors below this cannot be resolved against the reference
    period: float  # the period used for "10^4 periods" in the long run
    exact_reference: bool

    @property
    def y0(self) -> np.ndarray:
        return np.array(self.state0, dtype=float)

    def error(self, y: np.ndarray, ref: np.ndarray) -> float:
        return float(np.asarray(self.system.error(np.atleast_2d(y), np.atleast_2d(ref)))[0])


ADAPTIVE_OURS = ("dop853",)
ADAPTIVE_SCIPY = ("scipy-rk45", "scipy-dop853", "scipy-radau", "scipy-lsoda", "odeint")

PROBLEMS: dict[str, Problem] = {
    "charge": Problem(
        "charge",
        "Charge in a uniform field (100 gyro-periods)",
        Cyclotron(),
        (1.0, 0.0, 0.0, 0.0, 1.0, 0.1),
        200.0 * math.pi,
        ("rk4", "boris", "yoshida4", "midpoint", "euler"),
        256,
        1e-12,
        2.0 * math.pi,
        True,
    ),
    "hoop": Problem(
        "hoop",
        "Bead on a hoop (20 s)",
        Hoop(),
        (0.5, -0.3, 0.0, 0.0),
        20.0,
        ("rk4", "verlet", "yoshida4", "midpoint", "euler"),
        64,
        1e-10,
        2.0 * math.pi / math.sqrt(9.81 / 2.0),  # the slower normal mode
        False,
    ),
    "disk": Problem(
        "disk",
        "Released disk with bead (50 s)",
        ReleasedDisk(DiskParams(), extra_spin=(0.01, 0.0, 0.01)),
        tuple(ReleasedDisk(DiskParams(), extra_spin=(0.01, 0.0, 0.01)).default_state()),
        50.0,
        ("rk4", "splitting", "yoshida4", "midpoint", "euler"),
        32,
        1e-10,
        2.0 * math.pi,  # one turn at the spin rate of 1 rad/s
        False,
    ),
}


def versions() -> dict[str, str]:
    """Library versions that the stored references and timings depend on."""
    import llvmlite
    import numba
    import scipy

    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "llvmlite": llvmlite.__version__,
    }


def _final_state(problem: Problem, method: str, tol: float) -> tuple[np.ndarray, int, float]:
    sim = Simulation(problem.system, method, rtol=tol, atol=tol, state=problem.y0, reference=None)
    t0 = time.perf_counter()
    sim.advance_to(problem.t_end)
    return sim.state[0].copy(), sim.nfev, time.perf_counter() - t0


def compute_references(path: Path = REFERENCE_PATH, cross_check: bool = True) -> dict:
    """Compute every reference final state, cross-check it and write ``path`` (JSON)."""
    out = {
        "about": (
            "Reference final states of the benchmark problems: compiled DOP853 at rtol = atol = "
            "1e-13 (exact helix for the charge), cross-checked against scipy Radau at 1e-12. "
            "Written by `python -m dynamics.bench.problems`."
        ),
        "versions": versions(),
        "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "problems": {},
    }
    for key, pb in PROBLEMS.items():
        entry: dict = {"t_end": pb.t_end, "state0": list(pb.state0)}
        exact = pb.system.exact(pb.y0, pb.t_end)
        y, nfev, secs = _final_state(pb, "dop853", REFERENCE_TOL)
        if exact is not None:
            entry.update(
                kind="exact",
                final_state=[float(v) for v in exact],
                dop853_error=pb.error(y, exact),
            )
        else:
            entry.update(
                kind=f"dop853 rtol=atol={REFERENCE_TOL:g}",
                final_state=[float(v) for v in y],
                nfev=nfev,
                seconds=round(secs, 4),
            )
        if cross_check and exact is None:
            yr, nfev_r, secs_r = _final_state(pb, "scipy-radau", CROSS_CHECK_TOL)
            ref = np.array(entry["final_state"])
            entry["radau_1e-12"] = {
                "error": pb.error(yr, ref),
                "nfev": nfev_r,
                "seconds": round(secs_r, 2),
            }
        out["problems"][key] = entry
    write_json_atomically(path, out, indent=2)
    return out


_CACHE: dict | None = None


def load_references(path: Path = REFERENCE_PATH) -> dict:
    """The stored references (computing them first if the file is missing)."""
    global _CACHE
    if _CACHE is None:
        _CACHE = json.loads(path.read_text()) if path.exists() else compute_references(path)
    return _CACHE


def reference_state(problem: Problem) -> np.ndarray:
    """The final state the error of ``problem`` is measured against."""
    if problem.exact_reference:
        return np.asarray(problem.system.exact(problem.y0, problem.t_end), dtype=float)
    return np.array(load_references()["problems"][problem.key]["final_state"])


if __name__ == "__main__":
    print(json.dumps(compute_references(), indent=2))
