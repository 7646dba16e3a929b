"""Writing files so that a reader never sees one half-written: used by the benchmark's results
and charts, the viewer's endurance results and the recorder's demo files.

Each file goes to a temporary name in the same folder and is fsynced, then renamed into place
(``os.replace`` is atomic on POSIX); an interruption, a full disk or an exception before the
renames leaves the folder as it was.
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path
from typing import Any


def write_files_atomically(out_dir: Path, files: dict[str, bytes]) -> None:
    """Write every ``name -> bytes`` into ``out_dir`` so that readers see either the old files or
    the new ones: each goes to a temporary name in the same folder and is fsynced, then all are
    renamed into place in order (put the manifest last). On any error before the renames, the
    temporary files are removed and the folder is as it was."""
    out_dir.mkdir(parents=True, exist_ok=True)
    temps: list[tuple[Path, Path]] = []
    try:
        for name, content in files.items():
            final = out_dir / name
            tmp = out_dir / f".{name}.{os.getpid()}.partial"
            temps.append((tmp, final))
            with open(tmp, "wb") as fh:
                fh.write(content)
                fh.flush()
                os.fsync(fh.fileno())
    except BaseException:
        for tmp, _ in temps:
            with contextlib.suppress(OSError):
                tmp.unlink()
        raise
    for tmp, final in temps:
        os.replace(tmp, final)
    with contextlib.suppress(OSError):  # make the renames durable (POSIX)
        fd = os.open(out_dir, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def write_json_atomically(path: str | os.PathLike, data: Any, **dumps_kwargs) -> None:
    """``json.dumps(data, **dumps_kwargs)`` plus a newline to ``path``, atomically."""
    path = Path(path)
    text = json.dumps(data, **dumps_kwargs) + "\n"
    write_files_atomically(path.parent, {path.name: text.encode()})
