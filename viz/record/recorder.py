"""Recording a demo into a folder: five files, written together or not at all.

``DEMO.viser`` (viser's scene recording, played by ``mechviz play`` with a time slider),
``DEMO.html`` (the same in viser's self-contained page; plays from file://), ``DEMO.csv``,
``DEMO.png`` and ``DEMO.json`` (:mod:`mechviz.viz.record.outputs`). All five are built in memory, then
written as one set by :func:`mechviz.dynamics.fileset.write_set`: regular files, each replaced
atomically, the manifest last with the size and SHA-256 of each other file. A recording that
fails or is interrupted leaves the old set; one killed while it renames leaves every file whole
and a set that every reader (:func:`read_recording`, ``play``, ``video``, ``still``) refuses,
naming the file from the other recording; a second recording into the same folder waits for
the first; :class:`RecordingFailed` says what the folder holds.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mechviz import dynamics
from mechviz.dynamics.files import WriteFailed, WriteInterrupted, json_safe
from mechviz.dynamics.fileset import SCHEMA_VERSION, WaitFn, check_room, write_set

from . import charts
from .demo import Demo, load_demo
from .figures import figures
from .outputs import chart_figure, manifest, traces_csv
from .run import ProgressFn, run_demo

SUFFIXES = (".viser", ".html", ".csv", ".png", ".json")


class RecordingFailed(RuntimeError):
    """A recording that did not complete; the message says what the output folder now holds.
    ``interrupted``: ended by Ctrl-C; ``bad_input``: the demo asks for what cannot be done (too
    much work, a start the system refuses), which the command line reports as a usage error."""

    interrupted = False
    bad_input = False


@dataclass
class RecordResult:
    demo: Demo
    paths: dict[str, Path]
    manifest: dict[str, Any]
    wall_seconds: float
    frames: int


def existing_recording(out_dir: Path, name: str) -> str:
    """What ``out_dir`` holds for demo ``name``, for failure messages."""
    present = [s for s in SUFFIXES if (out_dir / f"{name}{s}").exists()]
    if not present:
        return f"nothing was written to {out_dir}"
    when = ""
    with contextlib.suppress(Exception):
        when = json.loads((out_dir / f"{name}.json").read_text())["recorded_at"]
        when = f" (recorded {when})"
    return f"{out_dir} keeps the previous complete recording of {name}{when}, unchanged"


def record(
    demo: Demo | str,
    out_dir: str | os.PathLike,
    *,
    progress: ProgressFn | None = None,
    theme: str = "light",
    on_wait: WaitFn | None = None,
    interruptible: Callable[[], contextlib.AbstractContextManager] = contextlib.nullcontext,
    plots: tuple[str, ...] | str = (),
) -> RecordResult:
    """Record ``demo`` into ``out_dir`` (the five files of the module docstring, and the chart
    in each of ``plots`` as well: ``"svg"``, ``"pdf"``, :mod:`mechviz.viz.record.charts`).

    ``progress(frame, frames)`` is called after each frame. Raises :class:`RecordingFailed`
    (the cause chained) if a run blows up or anything fails before the files are in place;
    ``KeyboardInterrupt`` becomes ``RecordingFailed`` with ``interrupted`` set. Either way the
    folder holds nothing new. ``theme``: the page of the ``.html`` ("light" or "dark").
    ``on_wait(message)`` is called if another process is writing to ``out_dir`` (the recording
    then waits for it before switching its files in). ``interruptible``: a context manager
    around everything but the writing (the command line's ends the run within a second of
    Ctrl-C even where numba's compiler swallows it)."""
    d = load_demo(demo) if isinstance(demo, str) else demo
    out = Path(out_dir)
    vector = tuple(f".{f}" for f in charts.check_formats(plots))
    suffixes = (*SUFFIXES, *vector)
    t_start = time.perf_counter()
    try:
        check_room(out, d.name, [f"{d.name}{s}" for s in suffixes])
        with interruptible():
            rec = run_demo(d, progress, theme=theme)
            tr = rec.traces
            figs = figures(d, tr)
            drawn = charts.save(chart_figure(d, tr, figs), ("png", *(s[1:] for s in vector)))
            files = {
                f"{d.name}.viser": rec.viser,
                f"{d.name}.html": rec.html,
                f"{d.name}.csv": traces_csv(d, tr),
                **{f"{d.name}{s}": b for s, b in drawn.items()},
            }
            man = {"schema_version": SCHEMA_VERSION}
            man |= manifest(d, tr, figs, wall=time.perf_counter() - t_start)
            man["scene"] = rec.scene  # the exhibit's bounds and camera: videos frame it
        man["files"] = {
            n: {"bytes": len(b), "sha256": hashlib.sha256(b).hexdigest()} for n, b in files.items()
        }
        reasons: dict[str, str] = {}
        man = json_safe(man, reasons=reasons)  # NaN and infinities as null, with the reason
        if reasons:
            man["null_reasons"] = reasons
        files[f"{d.name}.json"] = (json.dumps(man, indent=2, allow_nan=False) + "\n").encode()
        write_set(out, d.name, files, on_wait=on_wait)
    except WriteInterrupted as exc:  # the write says itself what it left on disk
        where = f"{out} holds the complete new recording" if exc.committed else exc.on_disk
        err = RecordingFailed(f"recording of {d.name} interrupted; {where}")
        err.interrupted = True
        raise err from exc
    except WriteFailed as exc:
        raise RecordingFailed(f"recording of {d.name} failed: {exc}") from exc
    except KeyboardInterrupt as exc:
        err = RecordingFailed(
            f"recording of {d.name} interrupted; {existing_recording(out, d.name)}"
        )
        err.interrupted = True
        raise err from exc
    except (dynamics.IntegrationError, OSError, ValueError) as exc:
        err = RecordingFailed(
            f"recording of {d.name} failed: {exc}; {existing_recording(out, d.name)}"
        )
        err.bad_input = (
            isinstance(exc, ValueError) or getattr(exc, "errno", 0) == errno.ENAMETOOLONG
        )
        raise err from exc
    wall = time.perf_counter() - t_start
    return RecordResult(d, {s: out / f"{d.name}{s}" for s in suffixes}, man, wall, d.frames)


def measure_record_speed(demo: str = "helix", duration: float = 30.0, fps: int = 30) -> dict:
    """Record ``demo`` for ``duration`` s at ``fps`` into a temporary folder (after one short
    warm-up recording, so compilation is not counted): wall seconds to record, speed-up over
    real time, file sizes in MB, and whether the targets (30 s at 30 fps in under 3 s, a
    ``.viser`` under 2 MB) are met."""
    d = load_demo(demo)
    with tempfile.TemporaryDirectory() as tmp:
        record(d.with_overrides(duration=1.0, fps=fps), Path(tmp) / "warmup")
        res = record(d.with_overrides(duration=duration, fps=fps), tmp)
        sizes = {s: res.paths[s].stat().st_size / 1e6 for s in (".viser", ".html", ".csv", ".png")}
    return {
        "demo": demo,
        "duration_s": duration,
        "fps": fps,
        "frames": res.frames,
        "record_wall_s": round(res.wall_seconds, 3),
        "speedup_over_real_time": round(duration / res.wall_seconds, 2),
        "viser_mb": round(sizes[".viser"], 4),
        "html_mb": round(sizes[".html"], 4),
        "csv_mb": round(sizes[".csv"], 4),
        "png_mb": round(sizes[".png"], 4),
        "targets": {
            "record_wall_s_max": 3.0,  # 30 s of playback at 30 fps, 10x faster than real time
            "viser_mb_max": 2.0,
            "met": res.wall_seconds < 3.0 and sizes[".viser"] < 2.0,
        },
    }
