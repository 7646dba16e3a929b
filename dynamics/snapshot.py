"""A run's whole state in one flat row of floats, and back: what going back in a run needs.

:func:`snapshot` writes what :class:`mechviz.dynamics.simulation.Simulation` carries from one call to the
next (time and the clock asked for, the state and the start it is measured from, the counters,
the step the adaptive methods go on with, and the tight reference run's own row); :func:`restore`
puts a run back where a row says it was, so it goes on from there as it went on then: a fixed-step
method takes the very same steps again, an adaptive one starts a fresh step from that state (its
kept step, a dense-output interpolant, is not stored: it is dropped, as on a jump). The row has a
fixed length for a run (:func:`width`), so a viewer keeps its snapshots in one preallocated
buffer; the row of the reference run is reserved whether or not the run has one now (a jump may
start or end one).

Layout of a row, for a run of ``n`` members of dimension ``d``: ``t, clock, t0, steps, nfev,
rejected, h`` (the Taylor step, NaN for none), a flag (1: a reference row follows), then
``state`` and ``state0`` (``n d`` each), the DOP853 step sizes (``n``) and its counters (``3 n``),
then the reference run's row in the same layout, then that of the reference's check run (the
looser DOP853 run that measures the reference's own error).
"""

from __future__ import annotations

import math

import numpy as np

from .simulation import Simulation, reference_run

_HEAD = 8  # t, clock, t0, steps, nfev, rejected, taylor h, has-reference flag


def _own_width(sim: Simulation) -> int:
    n, d = sim.state.shape
    return _HEAD + 2 * n * d + 4 * n


def width(sim: Simulation) -> int:
    """The length of ``sim``'s rows (its own and room for a reference run's and its check's)."""
    own = _own_width(sim)
    return own + (2 * own if sim._reference_mode == "auto" else 0)


def snapshot(sim: Simulation, out: np.ndarray | None = None) -> np.ndarray:
    """``sim``'s state as a row of :func:`width` floats (written into ``out`` if given)."""
    row = np.full(width(sim), math.nan) if out is None else out
    _write(sim, row)
    ref, own = sim._reference, _own_width(sim)
    if ref is not None and len(row) > own:
        row[_HEAD - 1] = 1.0
        _write(ref, row[own : 2 * own])
        _write(ref._reference, row[2 * own :])
    else:
        row[own:] = math.nan  # room for a reference run it has not (now)
    return row


def _write(sim: Simulation, row: np.ndarray) -> None:
    h = math.nan if sim._taylor_h is None else sim._taylor_h
    row[:_HEAD] = (sim.t, sim.clock, sim.t0, sim.steps, sim.nfev, sim.rejected, h, 0.0)
    k = _HEAD
    for block in (sim.state, sim.state0, sim._H, sim._stats):
        size = block.size
        row[k : k + size] = block.ravel()
        k += size


def restore(sim: Simulation, row: np.ndarray) -> None:
    """Put ``sim`` back where ``row`` (from :func:`snapshot` of this run) says it was."""
    _read(sim, row)
    own = _own_width(sim)
    if sim._reference_mode == "auto" and len(row) > own and row[_HEAD - 1] == 1.0:
        if sim._reference is None:  # the run had one then (a jump has ended it since)
            sim._reference = reference_run(sim.system, sim.state0)
        _read(sim._reference, row[own : 2 * own])
        _read(sim._reference._reference, row[2 * own :])
    else:
        sim._reference = None
    sim._track_error = sim._reference_mode is not None and (
        sim._has_exact or sim._reference_mode == "auto"
    )


def _read(sim: Simulation, row: np.ndarray) -> None:
    n, d = sim.state.shape
    sim.t, sim.clock, sim.t0 = float(row[0]), float(row[1]), float(row[2])
    sim.steps, sim.nfev, sim.rejected = (int(x) for x in row[3:6])
    sim._taylor_h = None if math.isnan(row[6]) else float(row[6])
    k = _HEAD
    new0 = row[k + n * d : k + 2 * n * d].reshape(n, d)
    if not np.array_equal(new0, sim.state0):  # measured from another start (before a jump)
        sim.state0 = new0.copy()
        sim._start_energy = None
        sim._exact_known = None
    sim.state[:] = row[k : k + n * d].reshape(n, d)
    k += 2 * n * d
    sim._H[:] = row[k : k + n]
    sim._stats[:] = row[k + n : k + 4 * n].reshape(n, 3)
    if sim._carry is not None:
        sim._carry.forget()  # a kept step belongs to the state it was taken from
