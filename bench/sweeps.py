"""Work-precision sweeps: every method on every problem, each through the same driver.

Fixed-step methods sweep the number of steps ``n = n0 * 2^(k/2)`` (``2^k`` in quick mode),
``dt = T / n``; adaptive methods sweep ``rtol = atol`` from ``1e-3`` down in half-decades
(decades in quick mode). A sweep stops when the error falls below the problem's floor, when
one call takes longer than the cap, or when the error stops falling (round-off).

Each point records the final error, the median wall time of ``Simulation.advance_to(T)``
(:mod:`.timing`), evaluations and steps, and the largest relative energy error seen at
``energy_samples`` equally spaced times. For fixed-step methods those samples come from the
untimed first run itself (advancing in pieces takes exactly the same steps); an adaptive run
restarted at every sample would change its steps, so there the samples come from a second,
segmented run, and the final state from the unsegmented one.
"""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from mechviz.dynamics.integrators.base import IntegrationError, get_method
from mechviz.dynamics.simulation import Simulation

from .peers import PEERS
from .peers import prepare as prepare_peer
from .problems import ADAPTIVE_SCIPY, Problem, reference_state
from .timing import time_calls


@dataclass
class Point:
    problem: str
    method: str
    adaptive: bool
    dt: float | None
    tol: float | None
    steps: int
    nfev: int
    error: float | None  # None: the run failed
    energy_error_max: float | None
    seconds: float | None  # median wall time of one run to T
    seconds_best: float | None  # fastest sample
    first_call: float | None
    samples: int
    calls_per_sample: int
    status: str

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def failed(
        cls,
        problem: str,
        method: str,
        adaptive: bool,
        dt: float | None,
        tol: float | None,
        status: str,
        *,
        steps: int = 0,
        nfev: int = 0,
        first_call: float | None = None,
    ) -> Point:
        """A point whose run failed (``status`` says how): no error and no timing."""
        return cls(
            problem,
            method,
            adaptive,
            dt,
            tol,
            steps,
            nfev,
            error=None,
            energy_error_max=None,
            seconds=None,
            seconds_best=None,
            first_call=first_call,
            samples=0,
            calls_per_sample=0,
            status=status,
        )


@dataclass(frozen=True)
class Settings:
    quick: bool = False
    repeats: int = 5
    min_sample: float = 2e-3
    cap: float = 2.0  # stop a sweep after a single call longer than this [s]
    energy_samples: int = 50
    half_steps: bool = True  # fixed-step sweep in factors sqrt(2) (else 2)
    # Quarter-decades: the error an adaptive method reaches is not smooth in its tolerance (a
    # decade tighter can move it by more than a decade), so a coarse grid charges every method,
    # ours and scipy's alike, for accuracy it was not asked for.
    tolerances: tuple[float, ...] = tuple(10.0 ** (-k / 4) for k in range(12, 61))
    head_to_head_rounds: int = 9
    scipy_methods: tuple[str, ...] = ADAPTIVE_SCIPY
    skip_fixed: tuple[str, ...] = ()
    one_sample_from: float = math.inf  # a call at least this long [s] is timed once

    @classmethod
    def for_mode(cls, quick: bool) -> Settings:
        if not quick:
            return cls()
        return cls(
            quick=True,
            repeats=3,
            cap=0.25,
            energy_samples=10,
            half_steps=False,
            tolerances=tuple(10.0 ** (-k / 2) for k in range(6, 31)),
            head_to_head_rounds=5,
            # The scipy options that can be fastest (full runs: RK45 and Radau never are).
            scipy_methods=("scipy-dop853", "scipy-lsoda", "odeint"),
            # Never fastest at any target, and each costs ~1 s of compilation per system.
            skip_fixed=("euler", "midpoint"),
            one_sample_from=0.02,
        )


def _restart_and_run(sim: Simulation, t_end: float) -> None:
    """One timed run: back to t = 0 (what a run costs beyond the solve) and on to ``t_end``."""
    sim.restart()
    sim.advance_to(t_end)


def _simulation(problem: Problem, method: str, dt: float | None, tol: float | None) -> Simulation:
    return Simulation(
        problem.system, method, dt=dt, rtol=tol, atol=tol, state=problem.y0, reference=None
    )


def _energy(problem: Problem, y: np.ndarray) -> float:
    with np.errstate(over="ignore", invalid="ignore"):  # a run that blew up is huge, not wrong
        return float(np.asarray(problem.system.energy(np.atleast_2d(y)))[0])


class PointFailed(Exception):
    """A run that failed at one point of a sweep: a result (its ``status``), not a crash."""

    def __init__(self, status: str):
        super().__init__(status)
        self.status = status


@dataclass(frozen=True)
class Solved:
    """The untimed run of one point: what it reached and how to time it."""

    final_state: np.ndarray
    steps: int
    nfev: int
    first: float  # wall time of the untimed run [s]
    first_is_one_call: bool  # the untimed run was one call to T (else the timing makes its own)
    energy_error_max: float | None
    make: Callable[[], Callable[[], object]]  # a fresh timed call (:func:`.timing.time_calls`)


def measure_point(
    problem: Problem,
    method: str,
    adaptive: bool,
    dt: float | None,
    tol: float | None,
    settings: Settings,
    solve: Callable[[], Solved],
) -> Point:
    """One sweep point: ``solve()`` runs it once untimed (raising :class:`PointFailed` when it
    fails), its final state is measured against the problem's reference, and the run is timed
    (:func:`mechviz.bench.timing.time_calls`). A non-finite final state is a failed point."""
    ref = reference_state(problem)
    try:
        run = solve()
    except PointFailed as failure:
        return Point.failed(problem.key, method, adaptive, dt, tol, failure.status)
    err = problem.error(run.final_state, ref)
    if not math.isfinite(err):
        return Point.failed(
            problem.key,
            method,
            adaptive,
            dt,
            tol,
            "failed: non-finite final state",
            steps=run.steps,
            nfev=run.nfev,
            first_call=run.first,
        )
    timing = time_calls(
        run.make,
        repeats=settings.repeats,
        min_sample=settings.min_sample,
        first_call=run.first if run.first_is_one_call else None,
        one_sample_from=settings.one_sample_from,
    )
    return Point(
        problem.key,
        method,
        adaptive,
        dt,
        tol,
        run.steps,
        run.nfev,
        err,
        run.energy_error_max,
        timing.median,
        timing.best,
        timing.first_call,
        timing.samples,
        timing.calls_per_sample,
        "ok",
    )


def _energy_error_in_pieces(problem: Problem, sim: Simulation, pieces: int) -> float:
    """Advance ``sim`` to T in ``pieces`` equal spans; the largest relative energy error at
    their ends."""
    T = problem.t_end
    E0 = float(problem.system.energy(problem.y0))
    worst = 0.0
    for k in range(1, pieces + 1):
        sim.advance_to(T * k / pieces)
        worst = max(worst, abs(_energy(problem, sim.state) - E0) / abs(E0))
    return worst


def run_point(
    problem: Problem,
    method: str,
    settings: Settings,
    *,
    dt: float | None = None,
    tol: float | None = None,
) -> Point:
    adaptive = get_method(method).adaptive
    T = problem.t_end
    S = settings.energy_samples

    def solve() -> Solved:
        try:
            sim = _simulation(problem, method, dt, tol)
            t0 = time.perf_counter()
            if adaptive:
                sim.advance_to(T)
            else:
                energy_max = _energy_error_in_pieces(problem, sim, S)
            first = time.perf_counter() - t0
            y, steps, nfev = sim.state[0].copy(), sim.steps, sim.nfev
            if adaptive and first < settings.cap:
                energy_max = _energy_error_in_pieces(
                    problem, _simulation(problem, method, dt, tol), S
                )
            elif adaptive:
                E0 = float(problem.system.energy(problem.y0))
                energy_max = abs(_energy(problem, y) - E0) / abs(E0)
        except IntegrationError as exc:
            raise PointFailed(f"failed: {exc.reason}") from exc
        timed = _simulation(problem, method, dt, tol)
        return Solved(
            y,
            int(steps),
            int(nfev),
            first,
            adaptive,
            energy_max,
            lambda: lambda: _restart_and_run(timed, T),
        )

    return measure_point(problem, method, adaptive, dt, tol, settings, solve)


def sweep_fixed(problem: Problem, method: str, settings: Settings, progress=None) -> list[Point]:
    points: list[Point] = []
    factor = math.sqrt(2.0) if settings.half_steps else 2.0
    best = math.inf
    rises = 0
    for k in range(60):
        n = int(round(problem.n0 * factor**k))
        pt = run_point(problem, method, settings, dt=problem.t_end / n)
        points.append(pt)
        if progress:
            progress()
        if pt.error is None:
            continue  # unstable or no convergence at this step: try a smaller one
        if pt.error < problem.floor:
            break
        if (pt.first_call or 0.0) > settings.cap or n > 2**26:
            break
        if pt.error >= best and best < 1e-5:
            rises += 1
            if rises >= 2:
                break  # round-off floor reached
        best = min(best, pt.error)
    return points


STALL_DECADES = 2.0  # stop once the tolerance is this many decades below the best point's


def _stalled(points: list[Point]) -> bool:
    """True once the tolerance has gone ``STALL_DECADES`` decades below the tolerance of the
    point with the smallest error without beating it: round-off, or a solver that clips the
    tolerance (scipy's below 2.2e-14). The error of an adaptive method is not monotone in its
    tolerance over a decade (a Taylor method changes order in whole steps), so a shorter window
    cut sweeps short."""
    ok = [p for p in points if p.error is not None and p.tol]
    if not ok:
        return False
    best = min(ok, key=lambda p: p.error)
    return points[-1].tol is not None and points[-1].tol < best.tol * 10.0**-STALL_DECADES


def sweep_tolerances(
    problem: Problem,
    settings: Settings,
    solve: Callable[[float], Point],
    progress=None,
) -> list[Point]:
    """``solve(tol)`` along ``settings.tolerances``, from the loosest, until the error falls below
    the problem's floor, a call takes longer than the cap, or the sweep stalls."""
    points: list[Point] = []
    for tol in settings.tolerances:
        pt = solve(tol)
        points.append(pt)
        if progress:
            progress()
        if pt.error is not None and pt.error < problem.floor:
            break
        if (pt.first_call or 0.0) > settings.cap or _stalled(points):
            break
    return points


def sweep_adaptive(problem: Problem, method: str, settings: Settings, progress=None) -> list[Point]:
    return sweep_tolerances(
        problem, settings, lambda tol: run_point(problem, method, settings, tol=tol), progress
    )


TARGETS = (1e-3, 1e-6, 1e-9, 1e-12)


def time_to_reach(points: list[Point], target: float) -> Point | None:
    """The fastest point whose error is at or below ``target``."""
    ok = [
        p
        for p in points
        if p.error is not None and p.error <= target and p.seconds and p.status == "ok"
    ]
    return min(ok, key=lambda p: p.seconds) if ok else None


def swept_point(points: list[Point], key: str, method: str, best: dict) -> Point:
    """The sweep point of ``method`` on problem ``key`` that a table entry ``best`` (with its
    ``dt`` and ``tol``) was taken from."""
    return next(
        p
        for p in points
        if p.problem == key and p.method == method and p.dt == best["dt"] and p.tol == best["tol"]
    )


def ratio_table(points: list[Point], ours: set[str], theirs: set[str]) -> dict:
    """Per problem and target: the fastest of ours, the fastest scipy option, and their ratio.

    When no scipy option reaches the target within the cap, the ratio is a lower bound: the
    slowest scipy call made (which still missed) over our time.
    """
    table: dict = {}
    for key in sorted({p.problem for p in points}):
        pts = [p for p in points if p.problem == key]
        row = {}
        for target in TARGETS:
            per_method = {}
            for m in sorted({p.method for p in pts}):
                best = time_to_reach([p for p in pts if p.method == m], target)
                per_method[m] = (
                    None
                    if best is None
                    else {
                        "seconds": best.seconds,
                        "nfev": best.nfev,
                        "dt": best.dt,
                        "tol": best.tol,
                        "error": best.error,
                    }
                )
            our = [(v["seconds"], m) for m, v in per_method.items() if m in ours and v]
            sci = [(v["seconds"], m) for m, v in per_method.items() if m in theirs and v]
            entry = {
                "per_method": per_method,
                "ours_methods": sorted(m for m in per_method if m in ours),
                "scipy_methods": sorted(m for m in per_method if m in theirs),
            }
            if our:
                entry["ours"] = {"method": min(our)[1], "seconds": min(our)[0]}
            if our and sci:
                entry["scipy"] = {"method": min(sci)[1], "seconds": min(sci)[0]}
                entry["ratio"] = min(sci)[0] / min(our)[0]
                entry["ratio_is_lower_bound"] = False
            elif our:
                tried = [p.seconds for p in pts if p.method in theirs and p.seconds]
                entry["ratio"] = (max(tried) / min(our)[0]) if tried else None
                entry["ratio_is_lower_bound"] = True
            row[f"{target:.0e}"] = entry
        table[key] = row
    return table


_PREPARED: dict = {}


def _prepared(problem: Problem, pt: Point):
    """A callable that runs ``pt`` once to ``T``: ours restart a kept Simulation, a peer's
    integrator is built once (untimed) and restarted."""
    key = (problem.key, pt.method, pt.dt, pt.tol)
    if key not in _PREPARED:
        if pt.method in PEERS:
            _PREPARED[key] = prepare_peer(pt.method, problem, pt.tol).run
        else:
            sim = _simulation(problem, pt.method, pt.dt, pt.tol)
            _PREPARED[key] = lambda: _restart_and_run(sim, problem.t_end)
    return _PREPARED[key]


def _run_seconds(problem: Problem, pt: Point, calls: int) -> float:
    """Seconds per call of ``calls`` fresh runs of ``pt`` to ``T`` (gc off, set-up untimed)."""
    run = _prepared(problem, pt)
    gc.disable()
    try:
        t0 = time.perf_counter()
        for _ in range(calls):
            run()
        return (time.perf_counter() - t0) / calls
    finally:
        gc.enable()


def head_to_head(problem: Problem, pts: list[Point], rounds: int, min_sample: float) -> list[float]:
    """Seconds per run of each point: its fastest of ``rounds`` interleaved rounds.

    A sweep times one method after another, minutes apart; on a shared machine the load can
    change in between and tilt a ratio either way. Here every round times every contender once,
    in rotating order, so both sides of a ratio see the same conditions, and each side's fastest
    round (the one least disturbed by other jobs) is kept: with bursts of load the median of a
    few rounds moved a ratio by up to 2.8x between two head-to-head timings of the same points.
    """
    calls = [max(1, math.ceil(min_sample / max(p.seconds or min_sample, 1e-7))) for p in pts]
    samples: list[list[float]] = [[] for _ in pts]
    for r in range(rounds):
        for k in range(len(pts)):
            i = (k + r) % len(pts)
            samples[i].append(_run_seconds(problem, pts[i], calls[i]))
    return [min(x) for x in samples]


def retime_ratios(
    table: dict,
    points: list[Point],
    problems: dict[str, Problem],
    settings: Settings,
    close: float = 1.5,
) -> None:
    """Replace each sweep ratio by a head-to-head one, in place.

    Contenders on each side are the points that reached the target within ``close`` times the
    side's fastest sweep time (so a near tie is settled by the interleaved timing, not by
    the order of the sweeps); the sweep's figures stay as ``sweep_ratio`` and ``sweep``.
    """
    for key, row in table.items():
        problem = problems[key]
        for entry in row.values():
            if "scipy" not in entry or "ours" not in entry:
                continue
            sides = {}
            for side in ("ours", "scipy"):
                fastest = entry[side]["seconds"]
                names = entry["ours_methods" if side == "ours" else "scipy_methods"]
                sides[side] = [
                    m
                    for m in names
                    if entry["per_method"][m]
                    and entry["per_method"][m]["seconds"] <= close * fastest
                ]
            contenders = [(side, m) for side in ("ours", "scipy") for m in sides[side]]
            pts = [swept_point(points, key, m, entry["per_method"][m]) for _, m in contenders]
            secs = head_to_head(problem, pts, settings.head_to_head_rounds, settings.min_sample)
            best = {}
            for (side, m), t in zip(contenders, secs, strict=True):
                if side not in best or t < best[side][1]:
                    best[side] = (m, t)
            entry["sweep"] = {"ours": entry["ours"], "scipy": entry["scipy"]}
            entry["sweep_ratio"] = entry["ratio"]
            entry["head_to_head"] = {
                "rounds": settings.head_to_head_rounds,
                "seconds": {
                    f"{side}:{m}": t for (side, m), t in zip(contenders, secs, strict=True)
                },
            }
            entry["ours"] = {"method": best["ours"][0], "seconds": best["ours"][1]}
            entry["scipy"] = {"method": best["scipy"][0], "seconds": best["scipy"][1]}
            entry["ratio"] = best["scipy"][1] / best["ours"][1]


def finite_or_none(x: float | None) -> float | None:
    return None if x is None or not np.isfinite(x) else float(x)
