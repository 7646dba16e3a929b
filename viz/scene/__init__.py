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



def bench_cases() -> dict[str, dict]:
    """The viewer's default exhibits as the bench's exhibit-defaults sweep takes them
    (``dynamics.bench.exhibits.choose_defaults``): system, initial state and a note."""
    import dynamics

    cyc, hoop, disk = CyclotronConfig(), HoopConfig(), DiskConfig()
    released = dynamics.ReleasedDisk(disk.physics(), tuple(disk.extra_spin))
    return {
        "cyclotron": {
            "system": dynamics.Cyclotron(cyc.physics()),
            "state": cyc.initial_state(),
            "state_note": f"speed {cyc.speed:g} m/s, vz {cyc.vz:g} m/s (the viewer's default)",
        },
        "hoop": {
            "system": dynamics.Hoop(hoop.physics()),
            "state": hoop.initial_state(),
            "state_note": f"mode {hoop.mode!r}, amplitude {hoop.amplitude:g} rad (the viewer's default)",
        },
        "disk-released": {
            "system": released,
            "state": released.default_state(),
            "state_note": f"omega {disk.physics().omega:g} rad/s, extra spin {disk.extra_spin} "
            "rad/s (the viewer's default)",
        },
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
    "bench_cases",
]
