"""Many short problems: our batch mode against our one-problem solves and heyoka's batch mode.

:data:`N` problems of one system, each from its own random start with its own random
parameters (a fixed seed), solved from 0 to :data:`T_END` seconds at ``rtol = atol =``
:data:`TOL`, construction counted; reported in microseconds per problem:

- ``ours batch``: one :class:`~mechviz.dynamics.solver.Solver` built and
  :meth:`~mechviz.dynamics.solver.Solver.solve_many` (the batch mode,
  :mod:`mechviz.dynamics.integrators.taylor_batch`);
- ``ours Solver loop``: a ``Solver`` built and :meth:`~mechviz.dynamics.solver.Solver.solve`
  called per problem in a Python loop;
- ``ours solve_taylor njit loop``: :func:`~mechviz.dynamics.solver.solve_taylor` per problem
  in one compiled loop (the order chosen in the call);
- ``heyoka batch B`` (``fast_math`` on and off, B = 4 and 8): heyoka's
  ``taylor_adaptive_batch`` in its fastest form, compiled once (untimed: heyoka keeps compiled
  integrators) and reset per batch of B problems (time, state, runtime parameters; the last
  batch padded with copies of its last problem). Skipped, with the reason, if heyoka is not
  installed.

Every contender runs once untimed (compilation), then all are timed in interleaved rounds in
this process (the order rotated each round, the garbage collector off), each call timed in CPU
time of this thread, so that load on a shared machine falls on all alike; the median round per
contender is reported, with the ratio
of each to ours. Each contender's final states are compared with ours (largest difference,
relative to ``1 + |y|``). The target: ours at most as slow per problem as heyoka's fastest
variant; :func:`missed` lists each system where it is not (``mechviz bench --batch`` exits
with status 1 then).
"""

from __future__ import annotations

import gc
import statistics
import time
from collections.abc import Callable

import numpy as np

from mechviz.dynamics import Hoop, ReleasedDisk
from mechviz.dynamics._jit import njit
from mechviz.dynamics.ids import FREE_BODY, HOOP, NAMES
from mechviz.dynamics.integrators.taylor_batch import LANES
from mechviz.dynamics.solver import Solver, solve_taylor
from mechviz.dynamics.taylor_order import order_for

from .peer_equations import heyoka_equations, heyoka_pars

N = 1000  # problems per call
T_END = 2.0  # [s]
TOL = 1e-9  # rtol = atol
SEED = 20_261_129
HEYOKA_LANES = (4, 8)
OURS = "ours batch"


def hoop_cases(n: int, seed: int = SEED) -> tuple[np.ndarray, np.ndarray]:
    """``n`` hoop starts (angles within 1.2 rad, rates within 2 rad/s) and parameter rows
    ``[M, m, a, g]`` (M 0.5-2 kg, m 0.2-1 kg, a 0.5-1.5 m, g 5-15 m/s^2)."""
    rng = np.random.default_rng(seed)
    y0 = np.column_stack([rng.uniform(-1.2, 1.2, (n, 2)), rng.uniform(-2.0, 2.0, (n, 2))])
    low, high = np.array([0.5, 0.2, 0.5, 5.0]), np.array([2.0, 1.0, 1.5, 15.0])
    return y0, rng.uniform(low, high, (n, 4))


def free_body_cases(n: int, seed: int = SEED) -> tuple[np.ndarray, np.ndarray]:
    """``n`` free-body starts (body rates within 2 rad/s, a random unit quaternion) and
    principal moments 0.5-2 kg m^2."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return np.column_stack([rng.uniform(-2.0, 2.0, (n, 3)), q]), rng.uniform(0.5, 2.0, (n, 3))


#: By the compiled system's name: its adapter, id and cases.
SYSTEMS = {
    NAMES[HOOP]: (Hoop, HOOP, hoop_cases),
    NAMES[FREE_BODY]: (ReleasedDisk, FREE_BODY, free_body_cases),
}


@njit  # not disk-cached: the benchmark lives outside the package's hashed sources
def _solve_all(sys_id, y0, p, t_end, rtol, atol, order, a, out):
    for m in range(y0.shape[0]):
        solve_taylor(sys_id, y0[m], p[m], t_end, rtol, atol, order, a, out[m])


def _ours(system, y0: np.ndarray, p: np.ndarray) -> dict[str, Callable[[], np.ndarray]]:
    sys_id = system.sys_id

    def batch() -> np.ndarray:
        return Solver(system, rtol=TOL, atol=TOL).solve_many(T_END, y0, p)

    def loop() -> np.ndarray:
        out = np.empty_like(y0)
        for m in range(len(y0)):
            out[m] = Solver(system, rtol=TOL, atol=TOL).solve(T_END, y0[m], p[m])
        return out

    def compiled() -> np.ndarray:
        order, a = order_for(TOL, TOL, sys_id)
        out = np.empty_like(y0)
        _solve_all(sys_id, y0, p, T_END, TOL, TOL, order, a, out)
        return out

    return {OURS: batch, "ours Solver loop": loop, "ours solve_taylor njit loop": compiled}


def _heyoka(sys_id: int, y0: np.ndarray, p: np.ndarray) -> dict[str, Callable[[], np.ndarray]]:
    """heyoka's batch integrators (module docstring), one per batch size and ``fast_math``."""
    import heyoka as hy

    n, d = y0.shape
    pars = np.array([heyoka_pars(sys_id, row) for row in p])  # its constants: an input
    calls = {}
    for lanes in HEYOKA_LANES:
        rows = -(-n // lanes) * lanes
        pad = np.concatenate([np.arange(n), np.full(rows - n, n - 1)])
        ys, ps = y0[pad], pars[pad]
        for fast in (True, False):
            ta = hy.taylor_adaptive_batch(
                heyoka_equations(sys_id),
                np.zeros((d, lanes)),
                tol=TOL,
                pars=np.zeros((pars.shape[1], lanes)),
                fast_math=fast,
            )

            def call(ta=ta, lanes=lanes, rows=rows, ys=ys, ps=ps) -> np.ndarray:
                out = np.empty((rows, d))
                for s in range(0, rows, lanes):
                    ta.set_time(0.0)
                    ta.state[:] = ys[s : s + lanes].T
                    ta.pars[:] = ps[s : s + lanes].T
                    ta.propagate_until(T_END)
                    out[s : s + lanes] = ta.state.T
                return out[:n]

            calls[f"heyoka batch {lanes}{' fast_math' if fast else ''}"] = call
    return calls


def _rounds(calls: dict[str, Callable], rounds: int) -> dict[str, list[float]]:
    """CPU seconds of this thread in each call per round (``time.thread_time``: time spent
    waiting for a core on a busy machine does not count; every contender computes in the
    calling thread), interleaved, the order rotated each round."""
    names = list(calls)
    times: dict[str, list[float]] = {k: [] for k in names}
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        for r in range(rounds):
            for k in names[r % len(names) :] + names[: r % len(names)]:
                t0 = time.thread_time()
                calls[k]()
                times[k].append(time.thread_time() - t0)
    finally:
        if was_enabled:
            gc.enable()
    return times


def measure_system(name: str, n: int = N, rounds: int = 25, heyoka: bool = True) -> dict:
    """One system's figures (module docstring); ``heyoka=False`` leaves heyoka out."""
    kind, sys_id, cases = SYSTEMS[name]
    system = kind()
    y0, p = cases(n)
    calls = _ours(system, y0, p)
    skipped = None if heyoka else "left out"
    try:
        if heyoka:
            calls |= _heyoka(sys_id, y0, p)
    except ImportError as exc:
        skipped = f"heyoka not installed ({exc})"
    ref = calls[OURS]()
    solver = Solver(system, rtol=TOL, atol=TOL)
    solver.solve_many(T_END, y0, p)
    steps = solver.member_steps
    difference = {}
    for k, call in calls.items():  # the untimed first call of each: compiled, and compared
        out = call()
        difference[k] = float(np.max(np.abs(out - ref) / (1.0 + np.abs(ref))))
    times = _rounds(calls, rounds)
    us = {k: 1e6 * statistics.median(v) / n for k, v in times.items()}
    best = {k: 1e6 * min(v) / n for k, v in times.items()}
    heyoka = {k: v for k, v in us.items() if k.startswith("heyoka")}
    fastest = min(heyoka, key=heyoka.get) if heyoka else None
    return {
        "problems": n,
        "rounds": rounds,
        "steps_per_problem": float(np.mean(steps)),
        "failed": int(np.sum(steps < 0)),
        "us_per_problem": us,
        "best_us_per_problem": best,
        "over_ours": {k: v / us[OURS] for k, v in us.items()},
        "heyoka_fastest": fastest,
        "ours_at_most_heyoka": None if fastest is None else us[OURS] <= heyoka[fastest],
        "max_difference_from_ours": difference,
        "heyoka_skipped": skipped,
    }


def run(quick: bool = False, systems: tuple[str, ...] = tuple(SYSTEMS)) -> dict:
    """Every system's figures, with the settings."""
    rounds = 9 if quick else 25
    return {
        "settings": {"problems": N, "t_end_s": T_END, "rtol": TOL, "atol": TOL, "seed": SEED},
        "lanes": LANES,
        "systems": {name: measure_system(name, rounds=rounds) for name in systems},
    }


def missed(result: dict) -> list[str]:
    """Each system where ours is slower per problem than heyoka's fastest batch variant."""
    out = []
    for name, row in result["systems"].items():
        if row["ours_at_most_heyoka"] is False:
            k = row["heyoka_fastest"]
            us = row["us_per_problem"]
            out.append(
                f"batch {name}: ours {us[OURS]:.2f} us > {k} {us[k]:.2f} us a problem "
                f"(ratio {us[OURS] / us[k]:.2f})"
            )
    return out


def markdown(result: dict) -> str:
    """The figures as a table per system."""
    s = result["settings"]
    parts = [
        f"{s['problems']} problems of {s['t_end_s']:g} s at rtol = atol = {s['rtol']:g}, random "
        f"starts and parameters (seed {s['seed']}), construction counted; our batch runs "
        f"{result['lanes']} members at a time. Median of interleaved rounds; *over ours*: the "
        "contender's time over our batch mode's (above 1: ours faster)."
    ]
    for name, row in result["systems"].items():
        lines = [
            f"**{name}** ({row['steps_per_problem']:.1f} steps a problem"
            + (f"; {row['heyoka_skipped']}" if row["heyoka_skipped"] else "")
            + ")",
            "",
            "| contender | us / problem | over ours | largest difference from ours |",
            "|---|---:|---:|---:|",
        ]
        for k, us in sorted(row["us_per_problem"].items(), key=lambda kv: kv[1]):
            diff = row["max_difference_from_ours"][k]
            lines.append(f"| {k} | {us:.2f} | {row['over_ours'][k]:.2f} | {diff:.1e} |")
        parts.append("\n".join(lines))
    return "\n\n".join(parts)


def report(result: dict) -> str:
    """The figures and the verdict, for the terminal."""
    lost = missed(result)
    verdict = "\n".join(lost) if lost else "target met: ours at most as slow as heyoka's batch"
    return markdown(result) + "\n\n" + verdict
