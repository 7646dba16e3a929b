"""The three scenes, one module each: its settings (``Config``), its exhibit (drawing, readouts,
measurements) and its GUI panel. :data:`EXHIBITS` is the one registry of exhibits, in the order
the viewer lays them out and shows their tabs."""

from .base import Exhibit, ExhibitConfig
from .cyclotron import CyclotronConfig, CyclotronExhibit
from .disk import DiskConfig, DiskExhibit
from .hoop import HoopConfig, HoopExhibit

EXHIBITS: dict[str, type[Exhibit]] = {
    cls.key: cls for cls in (CyclotronExhibit, DiskExhibit, HoopExhibit)
}


__all__ = [
    "EXHIBITS",
    "CyclotronConfig",
    "CyclotronExhibit",
    "DiskConfig",
    "DiskExhibit",
    "Exhibit",
    "ExhibitConfig",
    "HoopConfig",
    "HoopExhibit",
]
