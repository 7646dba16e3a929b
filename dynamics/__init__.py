"""mechviz dynamics: the physics of the three systems and the integrators that advance them.

Modules: :mod:`.cyclotron`, :mod:`.disk`, :mod:`.hoop` (one system each: parameters, equations of
motion, invariants, exact and analytic results); :mod:`.integrators` (methods as data, compiled
kernels, scipy behind the same interface); :mod:`.registry` (the one registry of systems: each
described once, :data:`SPECS`; :func:`register` adds one at run time, its compiled forms
:class:`SystemForms` generated from its equations), :mod:`.spec` (what a description
holds) and :mod:`.systems` (each system as the driver sees it, :data:`SYSTEMS`); :mod:`.steps`
(step control as one value); :mod:`.params` (one error type and one rule for typed numbers);
:mod:`.simulation` (the driver); :mod:`.measure` (estimators of sampled motion, shared by the
viewer and the recorder).
This package never imports viser.
"""

import importlib

# Loaded when first used (PEP 562), so that ``import mechviz.dynamics.aot`` and ``.ids`` cost no
# numba: every compiled module imports :mod:`._jit` (numba's cache set-up) itself.
_WHERE = {
    **dict.fromkeys(
        ("METHODS", "IntegrationError", "Method", "get_method", "methods_for"), ".integrators"
    ),
    **dict.fromkeys(("SettingError", "parse_number"), ".params"),
    **dict.fromkeys(("Sample", "Simulation", "Trajectory"), ".simulation"),
    **dict.fromkeys(("Setting", "Setup", "SystemSpec"), ".spec"),
    **dict.fromkeys(("Exact", "Fixed", "Step", "Tolerance", "step_control"), ".steps"),
    **dict.fromkeys(
        ("SYSTEMS", "Adapter", "Cyclotron", "DrivenDisk", "Hoop", "ReleasedDisk"), ".systems"
    ),
    **dict.fromkeys(
        (
            "SPECS",
            "BenchCase",
            "Registration",
            "lookup",
            "register",
            "spec_named",
            "system_named",
        ),
        ".registry",
    ),
    "SystemForms": ".forms",
}


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(importlib.import_module(_WHERE[name], __name__), name)
        globals()[name] = value
        return value
    try:  # a module of the package (mechviz.dynamics.hoop, mechviz.dynamics.measure, ...)
        return importlib.import_module(f".{name}", __name__)
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":  # the module exists; something it imports does not
            raise
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)


__all__ = [
    "METHODS",
    "SPECS",
    "SYSTEMS",
    "Adapter",
    "BenchCase",
    "Cyclotron",
    "DrivenDisk",
    "Exact",
    "Fixed",
    "Hoop",
    "IntegrationError",
    "Method",
    "Registration",
    "ReleasedDisk",
    "Sample",
    "Setting",
    "SettingError",
    "Setup",
    "Simulation",
    "Step",
    "SystemForms",
    "SystemSpec",
    "Tolerance",
    "Trajectory",
    "get_method",
    "lookup",
    "measure",
    "methods_for",
    "parse_number",
    "register",
    "spec_named",
    "step_control",
    "system_named",
]
