"""Recording demo sessions that play back anywhere, without Python.

A demo file (:mod:`.demo`) names an exhibit and its settings; :func:`record` runs the viewer's
own exhibit for it headless (:mod:`.run`), faster than real time, and writes the scene
recording, a self-contained page, the traces, a chart and a manifest (:mod:`.recorder`,
:mod:`.outputs`), with measured against predicted figures (:mod:`.figures`).
:func:`read_recording` reads one back, every file checked against its manifest.
"""

from mechviz.dynamics.api import Recording, read_recording

from .demo import DEMO_DIR, Demo, demo_names, list_demos, load_demo, parse_demo
from .figures import figures
from .recorder import (
    SUFFIXES,
    RecordingFailed,
    RecordResult,
    existing_recording,
    measure_record_speed,
    record,
)
from .run import Traces, run_demo

__all__ = [
    "DEMO_DIR",
    "SUFFIXES",
    "Demo",
    "RecordResult",
    "Recording",
    "RecordingFailed",
    "Traces",
    "demo_names",
    "existing_recording",
    "figures",
    "list_demos",
    "load_demo",
    "measure_record_speed",
    "parse_demo",
    "read_recording",
    "record",
    "run_demo",
]
