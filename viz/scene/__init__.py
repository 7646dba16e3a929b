"""The three scenes, one module each: its exhibit drawn with viser over the headless model of
:mod:`mechviz.viz.model` (whose ``Config`` holds the settings), and its GUI panel. :data:`EXHIBITS` is
the registry of exhibits, keyed by the one registry of systems (:data:`mechviz.dynamics.SPECS`:
its order is the order the viewer lays them out and shows their tabs; a system without an exhibit
raises here)."""

from ..model.hooks import by_system
from .base import Exhibit
from .cyclotron import CyclotronExhibit
from .disk import DiskExhibit
from .hoop import HoopExhibit

EXHIBITS: dict[str, type[Exhibit]] = by_system(
    (CyclotronExhibit, DiskExhibit, HoopExhibit), "exhibit"
)

__all__ = ["EXHIBITS", "CyclotronExhibit", "DiskExhibit", "Exhibit", "HoopExhibit"]
