"""mechviz: see classical mechanics, exactly where physics allows and honest about numerical error.

Three systems (a charge in a magnetic field, a spinning disk with a bead, a bead on a hanging hoop),
their physics and integrators in :mod:`mechviz.dynamics` (no viser there), the viewer, recordings,
videos and notebooks in :mod:`mechviz.viz`. A notebook starts with::

    from mechviz.dynamics import api
    run = api.simulate("hoop", t_end=10.0)

The ``mechviz`` command is :func:`mechviz.viz.cli.main`.
"""

from __future__ import annotations

__version__: str  # from the package metadata, read when first asked for (below)

__all__ = ["__version__"]


def __getattr__(name: str) -> str:
    # importlib.metadata costs tens of milliseconds (it imports the email package): read at
    # the first use, not by every command before it holds Ctrl-C (mechviz.viz.interrupts).
    if name != "__version__":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib import metadata

    try:
        version = metadata.version("mechviz-lab")
    except metadata.PackageNotFoundError:  # imported from a source tree never installed
        version = "0+unknown"
    globals()["__version__"] = version
    return version
