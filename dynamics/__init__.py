"""mechviz dynamics: the physics of the three systems and the integrators that advance them.

Modules: :mod:`.cyclotron`, :mod:`.disk`, :mod:`.hoop` (one system each: parameters, equations of
motion, invariants, exact and analytic results); :mod:`.integrators` (methods as data, compiled
kernels, scipy behind the same interface); :mod:`.systems` and :mod:`.simulation` (the driver).
This package never imports viser.
"""

from . import (
    _jit,  # noqa: F401  (sets up numba's cache before any kernel is defined)
    cyclotron,
    disk,
    hoop,
)
from .integrators import METHODS, IntegrationError, Method, get_method, methods_for
from .simulation import Sample, Simulation, Trajectory
from .systems import Cyclotron, DrivenDisk, Hoop, ReleasedDisk

__all__ = [
    "METHODS",
    "Cyclotron",
    "DrivenDisk",
    "Hoop",
    "IntegrationError",
    "Method",
    "ReleasedDisk",
    "Sample",
    "Simulation",
    "Trajectory",
    "cyclotron",
    "disk",
    "get_method",
    "hoop",
    "methods_for",
]
