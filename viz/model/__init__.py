"""The exhibits' headless models: settings, runs, events, samples and measured figures.

Nothing here imports viser: the recorder's data, the notebook's runs and the tests use these
alone; :mod:`mechviz.viz.scene` draws them.
"""

from .base import ExhibitConfig, ExhibitModel
from .cyclotron import CyclotronConfig, CyclotronModel
from .disk import DiskConfig, DiskModel
from .hoop import HoopConfig, HoopModel

#: Every exhibit's model by its key, in the order the viewer lays the exhibits out.
MODELS: dict[str, type[ExhibitModel]] = {
    cls.key: cls for cls in (CyclotronModel, DiskModel, HoopModel)
}

__all__ = [
    "MODELS",
    "CyclotronConfig",
    "CyclotronModel",
    "DiskConfig",
    "DiskModel",
    "ExhibitConfig",
    "ExhibitModel",
    "HoopConfig",
    "HoopModel",
]
