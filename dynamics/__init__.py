"""mechviz dynamics: the physics of the three systems and the integrators that advance them.

Modules: :mod:`.cyclotron`, :mod:`.disk`, :mod:`.hoop` (one system each: parameters, equations of
motion, invariants, exact and analytic results); :mod:`.integrators` (methods as data, compiled
kernels, scipy behind the same interface); :mod:`.spec` and :mod:`.systems` (each system
described once, :data:`SPECS`, and as the driver sees it, :data:`SYSTEMS`); :mod:`.steps` (step
control as one value); :mod:`.params` (one error type and one rule for typed numbers);
:mod:`.simulation` (the driver); :mod:`.measure` (estimators of sampled motion, shared by the
viewer and the recorder).
This package never imports viser.
"""

from . import (
    _jit,  # noqa: F401  (sets up numba's cache before any kernel is defined)
    measure,
)
from . import cyclotron as cyclotron  # the physics modules, by the explicit re-export idiom
from . import disk as disk
from . import hoop as hoop
from .integrators import METHODS, IntegrationError, Method, get_method, methods_for
from .params import SettingError, parse_number
from .simulation import Sample, Simulation, Trajectory
from .spec import Setting, Setup, SystemSpec
from .steps import Exact, Fixed, Step, Tolerance, step_control
from .systems import SPECS, SYSTEMS, Cyclotron, DrivenDisk, Hoop, ReleasedDisk

__all__ = [
    "METHODS",
    "SPECS",
    "SYSTEMS",
    "Cyclotron",
    "DrivenDisk",
    "Exact",
    "Fixed",
    "Hoop",
    "IntegrationError",
    "Method",
    "ReleasedDisk",
    "Sample",
    "Setting",
    "SettingError",
    "Setup",
    "Simulation",
    "Step",
    "SystemSpec",
    "Tolerance",
    "Trajectory",
    "get_method",
    "measure",
    "methods_for",
    "parse_number",
    "step_control",
]
