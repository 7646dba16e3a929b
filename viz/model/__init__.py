"""The exhibits' headless models: settings, runs, events, samples and measured figures.

Nothing here imports viser: the recorder's data, the notebook's runs and the tests use these
alone; :mod:`mechviz.viz.scene` draws them.
"""

from .base import ExhibitConfig, ExhibitModel
from .commands import Command, Kick, Reset, Set
from .cyclotron import CyclotronConfig, CyclotronModel
from .disk import DiskConfig, DiskModel
from .hooks import SystemHooks, by_system
from .hoop import HoopConfig, HoopModel

#: Every exhibit's model by its system's key, in the registry's order (the order the viewer lays
#: the exhibits out); each system of :data:`mechviz.dynamics.SPECS` has one, or this raises.
MODELS: dict[str, type[ExhibitModel]] = by_system((CyclotronModel, DiskModel, HoopModel), "model")

__all__ = [
    "MODELS",
    "Command",
    "CyclotronConfig",
    "CyclotronModel",
    "DiskConfig",
    "DiskModel",
    "ExhibitConfig",
    "ExhibitModel",
    "HoopConfig",
    "HoopModel",
    "Kick",
    "Reset",
    "Set",
    "SystemHooks",
]
