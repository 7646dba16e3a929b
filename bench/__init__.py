"""Speed against accuracy: work-precision sweeps, long runs, stability, step costs.

``run_bench(quick=..., out=...)`` runs everything on the fixed problems of :mod:`.problems`,
writes ``results.json`` and PNG charts to ``out`` and returns the result. ``mechviz bench``
(:mod:`mechviz.viz.cli.bench`) is the command-line entry. Nothing here imports viser; matplotlib is
imported only by :mod:`.charts`.
"""

from .problems import PROBLEMS, load_references, reference_state
from .run import run_bench, summary

__all__ = ["PROBLEMS", "load_references", "reference_state", "run_bench", "summary"]
