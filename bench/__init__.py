"""Speed against accuracy: work-precision sweeps, long runs, stability, step costs.

``run_bench(quick=..., out=...)`` runs everything on the fixed problems of :mod:`.problems`,
writes ``results.json`` and PNG charts to ``out`` and returns the result. ``mechviz bench``
(:mod:`mechviz.viz.cli.bench`) is the command-line entry. Nothing here imports viser; matplotlib is
imported only by :mod:`.charts`.
"""

import os

# The benchmark times numba's compiled code, as it always has, and builds nothing in the
# background while it times: Taylor's method compiled ahead of time (mechviz.dynamics.aot) is
# timed on its own, in the fresh processes of .first_answer, which run with a user's default.
os.environ.setdefault("MECHVIZ_AOT", "0")

from .problems import PROBLEMS, load_references, reference_state


def __getattr__(name: str):
    # Loaded when first used (PEP 562), so that ``python -m mechviz.bench.first_answer`` does not
    # find its own module imported (through .run) before it runs.
    if name in ("run_bench", "summary"):
        from . import run

        return getattr(run, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["PROBLEMS", "load_references", "reference_state", "run_bench", "summary"]
