"""The three scenes, one module each: its exhibit drawn with viser over the headless model of
:mod:`mechviz.viz.model` (whose ``Config`` holds the settings), and its GUI panel. :data:`EXHIBITS` is
the one registry of exhibits, in the order the viewer lays them out and shows their tabs."""

from .base import Exhibit
from .cyclotron import CyclotronExhibit
from .disk import DiskExhibit
from .hoop import HoopExhibit

EXHIBITS: dict[str, type[Exhibit]] = {
    cls.key: cls for cls in (CyclotronExhibit, DiskExhibit, HoopExhibit)
}

__all__ = ["EXHIBITS", "CyclotronExhibit", "DiskExhibit", "Exhibit", "HoopExhibit"]
