"""mechviz dynamics: the physics of the three systems and the integrators that advance them.

Modules: :mod:`.cyclotron`, :mod:`.disk`, :mod:`.hoop` (one system each: parameters, equations of
motion, invariants, exact and analytic results); :mod:`.integrators` (methods as data, compiled
kernels, scipy behind the same interface); :mod:`.systems` (the registry :data:`SYSTEMS`);
:mod:`.simulation` (the driver); :mod:`.measure` (estimators of sampled motion, shared by the
viewer and the recorder).
This package never imports viser.
"""

from . import (
    _jit,  # noqa: F401  (sets up numba's cache before any kernel is defined)
    cyclotron,
    disk,
    hoop,
    measure,
)
from .integrators import METHODS, IntegrationError, Method, get_method, methods_for
from .simulation import Sample, Simulation, Trajectory
from .systems import SYSTEMS, Cyclotron, DrivenDisk, Hoop, ReleasedDisk

__all__ = [
    "METHODS",
    "SYSTEMS",
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
    "measure",
    "methods_for",
]
