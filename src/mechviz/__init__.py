"""mechviz: see classical mechanics, exactly where physics allows and honest about numerical error.

Three systems (a charge in a magnetic field, a spinning disk with a bead, a bead on a hanging hoop),
their physics and integrators in :mod:`mechviz.dynamics` (no viser there), the viewer, recordings,
videos and notebooks in :mod:`mechviz.viz`. A notebook starts with::

    from mechviz.dynamics import api
    run = api.simulate("hoop", t_end=10.0)

The ``mechviz`` command is :func:`mechviz.viz.cli.main`.
"""

from __future__ import annotations

from importlib import metadata as _metadata

try:
    __version__: str = _metadata.version("mechviz-lab")
except _metadata.PackageNotFoundError:  # imported from a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["__version__"]
