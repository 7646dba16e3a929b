"""The work of one chunk: every cell a full run of a compiled method through :class:`Simulation`.

The cells of a chunk run as one ensemble (``Simulation`` on an (N, d) state), which costs far less
per cell than N separate runs. The compiled loops advance each member on its own (member outer),
so a member's numbers do not depend on which others share its ensemble or on how the run is cut
into calls: a chunk gives, bit for bit, what its cells would give one at a time.

A member that blows up (its state turns non-finite, an implicit solve fails) makes the whole
call raise; :class:`Ensemble` then runs that call's members one by one, records the step at which
each failing one stopped, and goes on with the rest.

Chaos: the largest Lyapunov exponent by renormalised twin runs (Benettin et al. 1980): each start
has a twin ``separation`` away along ``theta1``; every ``renormalise`` seconds the twin's distance
``d`` (Euclidean in state space) is logged and the twin put back at ``separation`` along the
current difference; the exponent [1/s] is ``sum(log(d / separation)) / duration``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..integrators import IntegrationError, get_method
from ..simulation import REFERENCE_ATOL, REFERENCE_TOL, Simulation
from .grid import HOOP_COORDINATES, AtlasSpec
from .theory import fastest_period, start_states

#: What each kind of map stores per cell: name -> (dtype, fill for a cell not computed).
VARIABLES = {
    "stability": {
        "energy_error": ("f8", np.nan),
        "escape_time": ("f8", np.nan),
        "bounded": ("i1", -1),
    },
    "chaos": {"lyapunov": ("f8", np.nan), "energy_error": ("f8", np.nan)},
    "accuracy": {"error": ("f8", np.nan)},
}


class Ensemble:
    """Members ``states`` (N, d) advanced together by fixed steps of ``dt`` [s] with ``method``.

    A member that blows up is taken out: :attr:`failed_step` holds the step it failed at (-1
    while it runs), :attr:`alive` is False and its last state stays in :attr:`states`.
    """

    def __init__(self, system, method: str, dt: float, states: np.ndarray) -> None:
        self.system, self.method, self.dt = system, method, dt
        self.states = np.array(states, dtype=np.float64)
        self.alive = np.ones(len(self.states), dtype=bool)
        self.failed_step = np.full(len(self.states), -1, dtype=np.int64)
        self.steps = 0
        self._sim: Simulation | None = None
        self._base = 0  # self.steps when _sim was made (its own t is 0 there)

    def _simulation(self, states: np.ndarray) -> Simulation:
        return Simulation(self.system, self.method, dt=self.dt, state=states, reference=None)

    def advance(self, n: int) -> None:
        """``n`` more steps for every live member."""
        live = np.flatnonzero(self.alive)
        if n <= 0 or live.size == 0:
            self.steps += max(n, 0)
            return
        if self._sim is None:
            self._sim, self._base = self._simulation(self.states[live]), self.steps
        sim = self._sim
        try:
            sim.advance_to((self.steps + n - self._base) * self.dt)
        except IntegrationError:
            self._one_by_one(live, n)
            self._sim = None
        else:
            if sim.steps != self.steps + n - self._base:
                raise RuntimeError("the driver took a different number of steps than asked")
            self.states[live] = sim.state
        self.steps += n

    def _one_by_one(self, live: np.ndarray, n: int) -> None:
        for i in live:
            sim = self._simulation(self.states[i])
            try:
                sim.advance_to(n * self.dt)
            except IntegrationError as exc:
                self.alive[i] = False
                self.failed_step[i] = self.steps + round(exc.t / self.dt)
                self.states[i] = sim.state[0]
            else:
                self.states[i] = sim.state[0]

    def retire(self, members: np.ndarray) -> None:
        """Stop advancing ``members`` (a boolean mask): the others go on without them."""
        if np.any(members & self.alive):
            self.alive &= ~members
            self._sim = None

    def replace(self, states: np.ndarray) -> None:
        """New states for the live members (the twins' renormalisation); time goes on."""
        self.states[self.alive] = states
        if self._sim is not None:
            self._sim.jump(states)


def relative_energy_error(system, states: np.ndarray, e0: np.ndarray) -> np.ndarray:
    """``(E - E0) / (E0 - E_floor)`` per member (as :meth:`Simulation.sample` reports it)."""
    moving = e0 - system.energy_floor()
    scale = np.where(moving > 0.0, moving, 1.0)
    with np.errstate(over="ignore", invalid="ignore"):
        return (np.asarray(system.energy(states), dtype=float) - e0) / scale


# --------------------------------------------------------------------------- the three kinds
def stability_cells(spec: AtlasSpec, method: str, dts: np.ndarray, amps: np.ndarray) -> dict:
    """Per (dt, amplitude): the relative energy error after ``spec.periods`` periods of the
    fastest linear mode (or when it first exceeded ``spec.threshold``, checked once a period),
    the time [s] it did (NaN if never), and whether the run stayed bounded (1) or not (0).
    A run that blew up has an infinite error."""
    system = spec.make_system()
    s0 = start_states(system, amps)
    e0 = np.asarray(system.energy(s0), dtype=float)
    period = fastest_period(spec)
    shape = (len(dts), len(amps))
    err, escape = np.full(shape, np.nan), np.full(shape, np.nan)
    for r, dt in enumerate(dts):
        dt = float(dt)
        total = max(1, math.ceil(spec.periods * period / dt - 1e-9))
        per_check = max(1, math.ceil(period / dt - 1e-9))
        ens = Ensemble(system, method, dt, s0)
        while ens.steps < total and ens.alive.any():
            ens.advance(min(per_check, total - ens.steps))
            e = relative_energy_error(system, ens.states, e0)
            out = ens.alive & ~(e < spec.threshold)  # over the threshold, or not a number
            err[r, out] = e[out]
            escape[r, out] = ens.steps * dt
            ens.retire(out)
        blown = ens.failed_step >= 0
        err[r, blown] = np.inf
        escape[r, blown] = ens.failed_step[blown] * dt
        done = ens.alive
        err[r, done] = relative_energy_error(system, ens.states[done], e0[done])
    bounded = np.isnan(escape).astype(np.int8)
    return {"energy_error": err, "escape_time": escape, "bounded": bounded}


def chaos_cells(spec: AtlasSpec, method: str, ys: np.ndarray, xs: np.ndarray) -> dict:
    """Per start of the section (:data:`.grid.CHAOS_SECTIONS`: the two coordinates the axes
    name, the others zero): the largest Lyapunov exponent [1/s] (module docstring) and the
    relative energy error of the start's own run at the end."""
    system = spec.make_system()
    gx, gy = np.meshgrid(xs, ys)
    base = np.zeros((gx.size, 4))
    base[:, HOOP_COORDINATES[spec.x.name]] = gx.ravel()
    base[:, HOOP_COORDINATES[spec.y.name]] = gy.ravel()
    twin = base.copy()
    twin[:, 0] += spec.separation
    n = len(base)
    ens = Ensemble(system, method, spec.step, np.concatenate([base, twin]))
    e0 = np.asarray(system.energy(base), dtype=float)
    total = max(1, math.ceil(spec.duration / spec.step - 1e-9))
    per = max(1, math.ceil(spec.renormalise / spec.step - 1e-9))
    logs = np.zeros(n)
    while ens.steps < total:
        ens.advance(min(per, total - ens.steps))
        if not ens.alive.all():
            break
        diff = ens.states[n:] - ens.states[:n]
        d = np.linalg.norm(diff, axis=1)
        logs += np.log(d / spec.separation)
        twin = ens.states[:n] + diff * (spec.separation / d)[:, None]
        ens.replace(np.concatenate([ens.states[:n], twin]))
    lyap = logs / (ens.steps * spec.step)
    lost = ~(ens.alive[:n] & ens.alive[n:])
    lyap[lost] = np.nan
    energy = relative_energy_error(system, ens.states[:n], e0)
    energy[lost] = np.inf
    shape = (len(ys), len(xs))
    return {"lyapunov": lyap.reshape(shape), "energy_error": energy.reshape(shape)}


def accuracy_cells(spec: AtlasSpec, method: str, steps: np.ndarray, amps: np.ndarray) -> dict:
    """Per (step or tolerance, amplitude): the error after ``spec.duration`` seconds against the
    exact solution where the system has one, else a tight DOP853 run (as :class:`Simulation`
    measures it); infinite where the run blew up. A fixed step ``dt`` is shortened to
    ``T / ceil(T / dt)`` so the run ends at ``T`` itself: a run that stopped short of it would
    add the motion over the remainder to the error, an error of order ``dt`` whatever the
    method's order."""
    system = spec.make_system()
    s0 = start_states(system, amps)
    if system.has_exact(s0):
        ref = np.atleast_2d(system.exact(s0, spec.duration))
    else:
        r = Simulation(
            system, "dop853", rtol=REFERENCE_TOL, atol=REFERENCE_ATOL, state=s0, reference=None
        )
        r.advance_to(spec.duration)
        ref = r.state
    m = get_method(method)
    out = np.full((len(steps), len(amps)), np.inf)
    for row, value in enumerate(steps):
        if m.adaptive:
            end, ok = _adaptive_run(system, method, float(value), s0, spec.duration)
        else:
            n = max(1, math.ceil(spec.duration / float(value) - 1e-9))
            ens = Ensemble(system, method, spec.duration / n, s0)
            ens.advance(n)
            end, ok = ens.states, ens.alive
        with np.errstate(over="ignore", invalid="ignore"):
            e = system.error(end, ref)
        out[row, ok] = e[ok]
    return {"error": out}


def _adaptive_run(system, method: str, rtol: float, s0: np.ndarray, t: float):
    """End states and which members reached ``t`` (an ensemble that fails runs one by one).
    Taylor's method on a system with a batch expansion solves the members together
    (:meth:`~mechviz.dynamics.solver.Solver.solve_many`: each member's end the ensemble's to
    round-off, a failing member marked on its own)."""
    if get_method(method).series:
        from ..integrators.taylor_batch import batched
        from ..solver import Solver

        if batched(system.sys_id):
            solver = Solver(system, rtol=rtol)
            end = solver.solve_many(t, s0)
            ok = solver.member_steps >= 0
            return np.where(ok[:, None], end, s0), ok
    try:
        sim = Simulation(system, method, rtol=rtol, state=s0, reference=None)
        sim.advance_to(t)
        return sim.state, np.ones(len(s0), dtype=bool)
    except IntegrationError:
        end, ok = s0.copy(), np.zeros(len(s0), dtype=bool)
        for i, s in enumerate(s0):
            sim = Simulation(system, method, rtol=rtol, state=s, reference=None)
            try:
                sim.advance_to(t)
                end[i], ok[i] = sim.state[0], True
            except IntegrationError:
                pass
        return end, ok


CELLS = {"stability": stability_cells, "chaos": chaos_cells, "accuracy": accuracy_cells}


def compute_chunk(spec: AtlasSpec, index: tuple[int, int, int]) -> dict:
    """The arrays of chunk ``index`` (each (rows, columns)), the seconds it took (``"seconds"``)
    and the CPU seconds its thread got meanwhile (``"cpu_seconds"``: below ``seconds`` when
    other processes share the core). What a Dask task runs; pure, so a lost task is simply run
    again."""
    t0, c0 = time.perf_counter(), time.thread_time()
    k, rows, cols = spec.cells(index)
    ys, xs = spec.y.values()[rows], spec.x.values()[cols]
    out = CELLS[spec.kind](spec, spec.methods[k], ys, xs)
    out["seconds"] = time.perf_counter() - t0
    out["cpu_seconds"] = time.thread_time() - c0
    return out
