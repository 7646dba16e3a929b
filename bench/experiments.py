"""The benchmark's other measurements: long-run energy, stability, and cost per compiled step.

- :func:`long_run_energy`: relative energy error over ``10^4`` periods at one loose step, RK4
  against the symplectic / symmetric methods (the regime of a viewer whose step is fixed).
- :func:`stability_points`: the measured amplification factor per step against ``omega dt``,
  beside the closed forms of :mod:`mechviz.dynamics.stability`.
- :func:`per_step_costs`: ns per compiled step of the direct kernels through
  :func:`mechviz.dynamics.integrators.kernels.run_direct`, and the same steps written in C
  (``c_steps.c``, its RK4 loops generated from the equations by :mod:`.c_form`, built with gcc
  ``-O2`` when a compiler is found), measured in the same run.
"""

from __future__ import annotations

import gc
import math
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from mechviz.dynamics import hoop, stability
from mechviz.dynamics.integrators import METHODS, kernels
from mechviz.dynamics.integrators.base import IntegrationError
from mechviz.dynamics.simulation import Simulation
from mechviz.dynamics.systems import Cyclotron, Hoop

from .c_form import c_rk4_header
from .problems import PROBLEMS

# ----------------------------------------------------------------------------- long runs
#: Each problem's long run (step, methods), as its system's description gives it
#: (:attr:`mechviz.dynamics.BenchCase.long_run`); the step is loose on purpose: a frame-budget step.
LONG_RUNS = {key: pb.long_run for key, pb in PROBLEMS.items() if pb.long_run is not None}


def long_run_energy(periods: float = 1e4, samples: int = 400, progress=None) -> dict:
    """Relative energy error at ``samples`` times over ``periods`` periods: ``(E - E0)`` over
    the energy that moves, ``E0 - E_floor`` (:meth:`mechviz.dynamics.Simulation.energy_scale`), both
    from ``energy_above_floor`` (no cancellation), as everywhere else."""
    out = {}
    for key, (dt, methods) in LONG_RUNS.items():
        pb = PROBLEMS[key]
        T = periods * pb.period
        n = int(round(T / dt))
        T = n * dt
        res = {"dt": dt, "t_end": T, "periods": periods, "methods": {}}
        for m in methods:
            sim = Simulation(pb.system, m, dt=dt, state=pb.y0, reference=None)
            E0 = float(pb.system.energy_above_floor(pb.y0))
            scale = float(sim.energy_scale()[0])
            ts, errs = [0.0], [0.0]
            t0 = time.perf_counter()
            for k in range(1, samples + 1):
                sim.advance_to(T * k / samples)
                ts.append(sim.t)
                errs.append((float(pb.system.energy_above_floor(sim.state)[0]) - E0) / scale)
            secs = time.perf_counter() - t0
            e = np.array(errs[1:])
            tenth = max(1, len(e) // 10)
            res["methods"][m] = {
                "t": ts,
                "energy_error": errs,
                "max_abs": float(np.max(np.abs(e))),
                "mean_first_10pc": float(np.mean(e[:tenth])),
                "mean_last_10pc": float(np.mean(e[-tenth:])),
                # bounded: the error at the end is no larger (within 2x) than at the start
                "bounded": bool(
                    np.max(np.abs(e[-tenth:])) <= 2.0 * max(np.max(np.abs(e[:tenth])), 1e-15)
                ),
                "seconds": secs,
                "steps": sim.steps,
            }
            if progress:
                progress()
        out[key] = res
    return out


# ----------------------------------------------------------------------------- stability
X_POINTS = (0.25, 0.5, 1.0, 1.5, 1.9, 2.1, 2.5, 2.75, 2.9, 3.25, 3.75)


def _charge_factor(method: str, x: float, n: int = 64) -> tuple[float | None, str]:
    """Measured ``(|v_perp(n)| / |v_perp(0)|)^(1/n)`` on the charge at ``omega dt = x``."""
    sim = Simulation(
        Cyclotron(), method, dt=x, state=np.array([1.0, 0, 0, 0, 1.0, 0]), reference=None
    )
    try:
        sim.advance_to(n * x)
    except IntegrationError as exc:
        return None, exc.reason
    v = math.hypot(sim.state[0, 3], sim.state[0, 4])
    return v ** (1.0 / sim.steps), "ok"


def _mode2_amplitude(p, omega2: float, state: np.ndarray) -> float:
    """Amplitude of the linearised hoop's mode 2, ``sqrt(c^2 + (c'/omega2)^2)``."""
    _, shapes = hoop.normal_modes(p)
    basis = shapes.T
    c = np.linalg.solve(basis, state[:2])[1]
    cd = np.linalg.solve(basis, state[2:])[1]
    return math.hypot(c, cd / omega2)


def hoop_mode2_factor(method: str, x: float, n_max: int = 400, a0: float = 1e-6):
    """Measured growth per step of the hoop's mode 2 (amplitude ``a0``, linear regime) at
    ``omega_max dt = x``: the largest amplitude over the last quarter of the steps over the
    largest over the first quarter, to the power ``1 / (steps between)``. Stepping stops early
    once the amplitude has grown ``1e4``-fold (still linear)."""
    sysm = Hoop()
    p = sysm.params
    w2 = float(hoop.normal_modes(p)[0][1])
    dt = x / w2
    sim = Simulation(sysm, method, dt=dt, state=hoop.mode_state(p, (0.0, a0)), reference=None)
    amps = []
    try:
        for _ in range(n_max):
            sim.advance_to(sim.t + dt * (1 + 1e-12))
            amps.append(_mode2_amplitude(p, w2, sim.state[0]))
            if amps[-1] > 1e4 * a0:
                break
    except IntegrationError as exc:
        return None, exc.reason
    q = max(1, len(amps) // 4)
    first, last = max(amps[:q]), max(amps[-q:])
    span = len(amps) - q
    return (last / first) ** (1.0 / span), "ok"


#: The oscillations a method's amplification is measured on, by the name its entry gives
#: (:attr:`mechviz.dynamics.integrators.Method.stability_probe`): where it is measured, on which
#: system, and how.
PROBES = {
    "gyration": ("charge", Cyclotron, _charge_factor),
    "mode 2": ("hoop mode 2", Hoop, hoop_mode2_factor),
}


def stability_points(progress=None) -> dict:
    """Theory curves and measured points of the amplification factor against ``omega dt``."""
    xs = np.linspace(0.0, 4.0, 401)
    # each method measured on the oscillation its entry names (Method.stability_probe)
    methods = {m.name: PROBES[m.stability_probe] for m in METHODS.values() if m.stability_probe}
    out = {"x": xs.tolist(), "methods": {}}
    for m, (where, system, fn) in methods.items():
        theory = [stability.amplification(m, x) for x in xs]
        limit = stability.limit_omega_dt(m, system)
        pts = []
        for x in X_POINTS:
            g, status = fn(m, x)
            pts.append(
                {"x": x, "measured": g, "theory": stability.amplification(m, x), "status": status}
            )
        out["methods"][m] = {
            "on": where,
            "theory": theory,
            "limit": limit,
            "points": pts,
            "reason": stability.reason(m),
        }
        if progress:
            progress()
    return out


# ----------------------------------------------------------------------------- per-step cost
C_SOURCE = Path(__file__).with_name("c_steps.c")
C_HEADER = "c_rk4_generated.h"  # what C_SOURCE includes: its RK4 loops, generated (.c_form)
STEP_CASES = (
    # name, table, system id (the problem of that system runs), h, steps
    ("rk4-charge", kernels.RK4, kernels.CYCLOTRON, 0.01, 1_000_000),
    ("boris-charge", kernels.SYMMETRIC2, kernels.CYCLOTRON, 0.01, 1_000_000),
    ("rk4-hoop", kernels.RK4, kernels.HOOP, 0.001, 125_000),
    ("verlet-hoop", kernels.SYMMETRIC2, kernels.HOOP, 0.001, 125_000),
    ("rk4-free-body", kernels.RK4, kernels.FREE_BODY, 0.001, 250_000),
    ("splitting-free-body", kernels.SYMMETRIC2, kernels.FREE_BODY, 0.001, 125_000),
)
# C -O2 per-step costs measured earlier on this machine (other load): reference figures.
NOTES_C_NS = {
    "rk4-charge": 10.7,
    "boris-charge": 4.0,
    "rk4-hoop": 168.0,
    "rk4-free-body": 16.0,
    "splitting-free-body": 77.0,
}


def problem_of(sys_id: int):
    """The benchmark problem whose system has the compiled id ``sys_id``; ``KeyError`` naming it
    if none has."""
    for pb in PROBLEMS.values():
        if pb.system.sys_id == sys_id:
            return pb
    raise KeyError(f"no benchmark problem of the compiled system {sys_id}")


def c_cases() -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Each system's ``(kernel parameters, start)`` of its benchmark problem, which the
    generated C RK4 loops start from (as the numba steps measured beside them do)."""
    out = {}
    for sys_id in sorted({case[2] for case in STEP_CASES}):
        pb = problem_of(sys_id)
        out[sys_id] = (pb.system.kernel_params(), pb.y0)
    return out


def _numba_cost(table, sys_id, h, n, repeats) -> tuple[float, float]:
    pb = problem_of(sys_id)
    step = table[sys_id]
    p = pb.system.kernel_params()
    status = np.zeros(3, dtype=np.int64)
    Y = np.atleast_2d(pb.y0).copy()
    t0 = time.perf_counter()
    kernels.run_direct(step, Y.copy(), p, h, 10, status)  # compiles (or loads) the loop
    compile_s = time.perf_counter() - t0
    ts = []
    gc.disable()
    try:
        for _ in range(repeats):
            Yc = Y.copy()
            t0 = time.perf_counter()
            kernels.run_direct(step, Yc, p, h, n, status)
            ts.append(time.perf_counter() - t0)
    finally:
        gc.enable()
    return statistics.median(ts) / n * 1e9, compile_s


def _c_costs(n: int, repeats: int) -> dict[str, float] | str:
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        return "no C compiler found"
    with tempfile.TemporaryDirectory() as tmp:
        exe = Path(tmp) / "c_steps"
        (Path(tmp) / C_HEADER).write_text(c_rk4_header(c_cases()), encoding="utf-8")
        try:
            subprocess.run(
                [cc, "-O2", f"-I{tmp}", str(C_SOURCE), "-lm", "-o", str(exe)],
                check=True,
                capture_output=True,
                timeout=60,
            )
            out = subprocess.run(
                [str(exe), str(n), str(repeats)],
                check=True,
                capture_output=True,
                text=True,
                timeout=120,
            ).stdout
        except (subprocess.SubprocessError, OSError) as exc:
            return f"C build or run failed: {exc}"
    return {line.split()[0]: float(line.split()[1]) for line in out.splitlines() if line.strip()}


def per_step_costs(quick: bool = False, progress=None) -> dict:
    """ns per step, numba (through ``run_direct``) and C, measured in the same run."""
    repeats = 3 if quick else 7
    scale = 4 if quick else 1
    rows = {}
    for name, table, sys_id, h, n in STEP_CASES:
        ns, comp = _numba_cost(table, sys_id, h, n // scale, repeats)
        rows[name] = {"numba_ns": ns, "first_call_s": comp, "steps": n // scale}
        if progress:
            progress()
    c = _c_costs(1_000_000 // scale, repeats)
    for name, row in rows.items():
        row["c_notes_ns"] = NOTES_C_NS.get(name)
        if isinstance(c, dict) and name in c:
            row["c_ns"] = c[name]
            row["ratio_to_c"] = row["numba_ns"] / c[name]
            row["within_2x_of_c"] = row["ratio_to_c"] <= 2.0
    return {
        "rows": rows,
        "c": "gcc -O2, same arithmetic, state in locals (bench/c_steps.c, RK4 generated)"
        if isinstance(c, dict)
        else c,
        "note": "numba steps run through kernels.run_direct on one trajectory (state stored to its "
        "array every step, non-finite check every step); median of repeats.",
    }


# ----------------------------------------------------------------------------- ensembles
ENSEMBLE_SIZES = (1, 10, 100, 1000, 10_000, 100_000)
ENSEMBLE_TOL = 1e-9
ENSEMBLE_MEMBER_STEPS = 200_000  # about this many member-steps per timed run (hoop: ~0.1 s)


def ensemble_costs(quick: bool = False, progress=None) -> dict:
    """ns per member-step of Taylor's method on an ensemble of N hoops (N from 1 to 10^5), the
    members run one after another (serial) and spread over numba's threads (parallel), timed in
    interleaved rounds; the best round of each. The members start 1e-3 rad apart; the span
    shrinks with N so that a run is about :data:`ENSEMBLE_MEMBER_STEPS` member-steps (half as
    many in a quick run)."""
    import os

    import numba

    from mechviz.dynamics.integrators import taylor

    rounds = 2 if quick else 5
    member_steps = ENSEMBLE_MEMBER_STEPS // (2 if quick else 1)
    pb = problem_of(kernels.HOOP)
    rng = np.random.default_rng(0)
    rows = {}
    saved = taylor.PARALLEL_MIN
    try:
        for n in ENSEMBLE_SIZES:
            states = pb.y0 + 1e-3 * rng.standard_normal((n, pb.y0.size))
            per_member = member_steps / n
            t_end = min(pb.t_end, max(0.2, per_member / 9.0))  # the hoop: ~9 steps/s at 1e-9
            sim = Simulation(
                pb.system,
                "taylor",
                rtol=ENSEMBLE_TOL,
                atol=ENSEMBLE_TOL,
                state=states,
                reference=None,
            )
            best = {"serial": math.inf, "parallel": math.inf}
            finals = {}
            for r in range(rounds + 1):  # round 0 compiles (or loads) both loops, untimed
                for mode, threshold in (("serial", 1 << 62), ("parallel", 1)):
                    taylor.PARALLEL_MIN = threshold
                    sim.restart()
                    gc.disable()
                    t0 = time.perf_counter()
                    sim.advance_to(t_end)
                    dt = time.perf_counter() - t0
                    gc.enable()
                    if r:
                        best[mode] = min(best[mode], dt / sim.steps)
                    finals[mode] = sim.state.copy()
            rows[str(n)] = {
                "members": n,
                "t_end": t_end,
                "member_steps": sim.steps,
                "serial_ns": 1e9 * best["serial"],
                "parallel_ns": 1e9 * best["parallel"],
                "speedup": best["serial"] / best["parallel"],
                "bitwise_equal": bool(np.array_equal(finals["serial"], finals["parallel"])),
            }
            if progress:
                progress()
    finally:
        taylor.PARALLEL_MIN = saved
    return {
        "rows": rows,
        "cores": os.cpu_count(),
        "threads": numba.config.NUMBA_NUM_THREADS,
        "threading_layer": _threading_layer(),
        "parallel_min": saved if saved < 1 << 62 else None,
        "note": f"hoop, taylor at rtol = atol = {ENSEMBLE_TOL:g}, restart() + advance_to(T); "
        + (
            f"the driver runs ensembles of {saved} or more members in parallel"
            if saved < 1 << 62
            else "the driver never runs ensembles in parallel (turned off)"
        ),
    }


def _threading_layer() -> str | None:
    import numba

    try:
        return numba.threading_layer()
    except ValueError:  # no parallel function has run in this process
        return None
