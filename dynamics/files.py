"""Writing a set of files so that a reader sees either the whole old set or the whole new one,
and JSON that is valid whatever numbers it carries.

Used by the benchmark's results and charts and the viewer's endurance results. The switch
renames each file in turn and rolls back on failure, which a process killed with SIGKILL cannot
do; the recorder's demo files use :mod:`mechviz.dynamics.fileset` instead, whose manifest, written
last, lets every reader tell a whole set from one a killed writer left mixed.

:func:`write_files_atomically` writes every file to a temporary name in the target folder and
fsyncs it, then switches the set in one step: each old file is kept under a hard link, the new
files are renamed into place, and if anything fails (an I/O error, ``KeyboardInterrupt``, SIGTERM
or SIGHUP) the renamed ones are put back and the temporaries removed. Its exceptions say what is
on disk (:class:`WriteFailed`, :class:`WriteInterrupted`).

:func:`json_safe` turns NaN and infinities (which ``json.dumps`` writes as the invalid tokens
``NaN`` and ``Infinity``) into ``null``, and :func:`write_json_atomically` uses it.
"""

from __future__ import annotations

import contextlib
import errno
import json
import math
import os
import signal
import threading
from pathlib import Path
from typing import Any

# Signals that end a write: the files are cleaned up, then the signal is handled as before
# (KeyboardInterrupt for SIGINT; SIGTERM and SIGHUP end the process, as their default does).
_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


class _Outcome:
    """What a failed write left on disk (shared by :class:`WriteFailed` and
    :class:`WriteInterrupted`).

    Attributes
    ----------
    out_dir : the target folder.
    unchanged : True when ``out_dir`` is exactly as it was before the call: the same old files
        (or no folder at all, if the call created it), no new and no temporary files. This is
        always the case unless putting the old files back failed too.
    new_files : names now holding the new content (empty when ``unchanged``).
    committed : True when every new file is in place (the write was switched whole before the
        signal or error came, as :func:`mechviz.dynamics.fileset.write_set` does).
    signum : the signal that ended the write, or None.
    on_disk : one sentence stating the above, also the end of the exception's message.
    """

    out_dir: Path
    unchanged: bool
    new_files: tuple[str, ...]
    signum: int | None
    on_disk: str

    def _describe(
        self,
        out_dir: Path,
        new_files: list[str],
        signum: int | None,
        committed: bool = False,
        mixed: str = "restoring them failed",
    ) -> str:
        self.out_dir = out_dir
        self.new_files = tuple(new_files)
        self.unchanged = not new_files
        self.committed = committed
        self.signum = signum
        if committed:
            self.on_disk = f"{out_dir} holds the complete new set"
        elif self.unchanged:
            self.on_disk = f"{out_dir} is unchanged"
        else:
            self.on_disk = (
                f"{out_dir} is MIXED: {', '.join(new_files)} hold the new content, "
                f"the other files the old ({mixed})"
            )
        return self.on_disk


class WriteFailed(_Outcome, OSError):
    """An I/O error (full disk, permissions, ...) ended :func:`write_files_atomically`; the
    cause is chained. An ``OSError``, so ``except OSError`` still catches it."""

    def __init__(
        self,
        out_dir: Path,
        cause: BaseException,
        new_files: list[str],
        *,
        committed: bool = False,
        mixed: str = "restoring them failed",
    ) -> None:
        where = self._describe(out_dir, new_files, None, committed, mixed)
        self.message = f"writing to {out_dir} failed: {_reason(cause)}; {where}"
        super().__init__(getattr(cause, "errno", None), self.message)

    def __str__(self) -> str:
        return self.message


class WriteInterrupted(_Outcome, KeyboardInterrupt):
    """Ctrl-C (SIGINT) ended :func:`write_files_atomically`. A ``KeyboardInterrupt``, so code
    that handles Ctrl-C keeps doing so."""

    def __init__(
        self, out_dir: Path, signum: int, new_files: list[str], *, committed: bool = False
    ) -> None:
        where = self._describe(out_dir, new_files, signum, committed)
        super().__init__(f"writing to {out_dir} interrupted; {where}")

    def __str__(self) -> str:
        return str(self.args[0])


def _reason(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        name = exc.filename and Path(exc.filename).name
        return f"{exc.strerror}" + (f" ({name})" if name else "")
    return str(exc) or exc.__class__.__name__


class _Signalled(BaseException):
    """Raised inside the write by a signal handler (never escapes this module)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


def write_files_atomically(out_dir: str | os.PathLike, files: dict[str, bytes]) -> None:
    """Write every ``name -> bytes`` into ``out_dir`` (created if missing) as one set.

    Each file goes to ``.NAME.PID.partial`` in ``out_dir`` and is fsynced. Then the set is
    switched: every existing ``NAME`` is kept under a hard link ``.NAME.PID.old``, the new files
    are renamed over the old in the order given (put a manifest last), and the links are
    removed. Readers of a single file always see it whole (``os.replace`` is atomic on POSIX).

    Failure semantics, for callers that report what is on disk:

    - Returns None: every new file is in place, no temporary file is left.
    - Raises :class:`WriteFailed` (an ``OSError``; the cause chained) on an I/O error at any
      point, including during the switch: the files already switched are put back, temporaries
      are removed, and a folder this call created is removed again.
    - Raises :class:`WriteInterrupted` (a ``KeyboardInterrupt``) on SIGINT, with the same
      clean-up. A signal that arrives during the switch is held until the switch is over and
      then undoes it, so the renames are never cut in half. One that arrives after the switch
      (while the folder is synced) keeps the new set: SIGINT raises :class:`WriteInterrupted`
      with ``committed`` set.
    - On SIGTERM or SIGHUP, cleans up the same way and then lets the signal do what it did
      before the call (by default: end the process).

    Either exception has ``unchanged`` (True unless restoring an old file failed too),
    ``new_files``, ``signum`` and ``on_disk``, a sentence saying what the folder holds, which
    also ends the message. Signals are caught only when called from the main thread (Python
    delivers them there) and only while their handler is the default one; a program that
    handles a signal itself keeps doing so.
    """
    out_dir = Path(out_dir)
    guard = _SignalGuard()
    created: list[Path] = []
    temps: dict[str, Path] = {}
    backups: dict[str, Path] = {}  # name -> hard link to the old file (or None if none)
    switched: list[str] = []
    pid = os.getpid()
    with guard:
        try:
            created = _make_dirs(out_dir)
            for name, content in files.items():
                tmp = out_dir / f".{name}.{pid}.partial"
                temps[name] = tmp
                with open(tmp, "wb") as fh:
                    fh.write(content)
                    fh.flush()
                    os.fsync(fh.fileno())
            # The switch: signals are held (recorded, not raised) until it is over.
            guard.hold()
            for name in files:
                final = out_dir / name
                if final.exists() or final.is_symlink():
                    backup = out_dir / f".{name}.{pid}.old"
                    _keep_old(final, backup)
                    backups[name] = backup
                os.replace(temps[name], final)
                del temps[name]
                switched.append(name)
            guard.release()  # a signal held during the switch raises here: undone below
            guard.hold()  # the new set is in place: later signals wait for the clean-up
        except BaseException as exc:
            guard.hold()  # the clean-up is not interrupted either
            left = _roll_back(out_dir, switched, backups, temps, created)
            signum = exc.signum if isinstance(exc, _Signalled) else guard.pending
            if signum is None and isinstance(exc, KeyboardInterrupt):
                signum = signal.SIGINT
            guard.restore()
            if signum is not None and signum != signal.SIGINT:
                # SIGTERM/SIGHUP: now that the folder is clean, handle it as before the call.
                guard.redeliver(signum)
            if signum is not None:
                raise WriteInterrupted(out_dir, signum, left) from None
            if isinstance(exc, OSError):
                raise WriteFailed(out_dir, exc, left) from exc
            raise
        for backup in backups.values():
            with contextlib.suppress(OSError):
                backup.unlink()
        _fsync_dir(out_dir)
        guard.restore()
        if guard.pending is not None:  # came after the switch: the new set stays
            if guard.pending != signal.SIGINT:
                guard.redeliver(guard.pending)
            raise WriteInterrupted(out_dir, guard.pending, list(files), committed=True)


def _make_dirs(path: Path) -> list[Path]:
    """``mkdir -p``; returns the folders it created, outermost first."""
    missing = []
    p = path
    while not p.exists():
        missing.append(p)
        if p.parent == p:
            break
        p = p.parent
    missing.reverse()
    made = []
    try:
        for d in missing:
            d.mkdir()
            made.append(d)
    except BaseException:
        for d in reversed(made):
            with contextlib.suppress(OSError):
                d.rmdir()
        raise
    return made


def _keep_old(final: Path, backup: Path) -> None:
    if final.is_dir() and not final.is_symlink():
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(final))
    with contextlib.suppress(FileNotFoundError):
        backup.unlink()
    try:
        os.link(final, backup, follow_symlinks=False)
    except OSError:  # no hard links here (some network or FAT file systems): copy the name
        os.replace(final, backup)


def _roll_back(out_dir, switched, backups, temps, created) -> list[str]:
    """Put back what the switch replaced; returns the names still holding new content."""
    left = []
    for name in reversed(switched):
        final = out_dir / name
        try:
            if name in backups:
                os.replace(backups.pop(name), final)
            else:
                final.unlink()
        except OSError:
            left.append(name)
    for p in [*temps.values(), *backups.values()]:
        with contextlib.suppress(OSError):
            p.unlink()
    if not left:
        for d in reversed(created):
            with contextlib.suppress(OSError):
                d.rmdir()
    return sorted(left)


def _fsync_dir(out_dir: Path) -> None:
    with contextlib.suppress(OSError):  # make the renames durable (POSIX)
        fd = os.open(out_dir, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


class _SignalGuard:
    """Turns SIGINT, SIGTERM and SIGHUP into :class:`_Signalled` while files are written, and
    records them without raising while they are held (the switch and its clean-up)."""

    def __init__(self) -> None:
        self.active = threading.current_thread() is threading.main_thread()
        self.previous: dict[int, Any] = {}
        self.holding = False
        self.pending: int | None = None

    def __enter__(self) -> _SignalGuard:
        # Only signals whose handler is the default one: a program that handles a signal itself
        # (the viewer turns Ctrl-C into a flag) keeps its own handling.
        if self.active:
            for s in _SIGNALS:
                default = signal.default_int_handler if s == signal.SIGINT else signal.SIG_DFL
                if signal.getsignal(s) is default:
                    self.previous[s] = signal.signal(s, self._handler)
        return self

    def __exit__(self, *exc) -> None:
        self.restore()

    def _handler(self, signum, _frame) -> None:
        if self.pending is None:
            self.pending = signum
        if not self.holding:
            raise _Signalled(signum)

    def hold(self) -> None:
        self.holding = True

    def release(self) -> None:
        self.holding = False
        if self.pending is not None:
            raise _Signalled(self.pending)

    def restore(self) -> None:
        if self.active:
            for s, h in self.previous.items():
                signal.signal(s, h)
            self.previous.clear()

    def redeliver(self, signum: int) -> None:
        if self.active:
            signal.raise_signal(signum)


# --------------------------------------------------------------------------- JSON
def json_safe(data: Any, *, reasons: dict[str, str] | None = None, _path: str = "") -> Any:
    """``data`` with every float that is NaN or infinite replaced by ``None`` (JSON ``null``),
    through dicts, lists, tuples and NumPy scalars and arrays.

    If ``reasons`` is a dict, each replacement adds ``"path": "why"`` to it (path like
    ``period`` or ``final_state.x``; why: ``"not finite (nan)"`` or ``"not finite (inf)"``), so
    a caller can say in its output why a value is null. ``json.dumps(json_safe(x),
    allow_nan=False)`` always succeeds for numeric data.
    """
    if isinstance(data, dict):
        return {
            k: json_safe(v, reasons=reasons, _path=f"{_path}.{k}" if _path else str(k))
            for k, v in data.items()
        }
    if isinstance(data, list | tuple):
        return [json_safe(v, reasons=reasons, _path=f"{_path}[{i}]") for i, v in enumerate(data)]
    if hasattr(data, "tolist") and not isinstance(data, str | bytes):  # NumPy arrays and scalars
        return json_safe(data.tolist(), reasons=reasons, _path=_path)
    if isinstance(data, float) and not math.isfinite(data):
        if reasons is not None:
            reasons[_path] = f"not finite ({data})"
        return None
    return data


def write_json_atomically(path: str | os.PathLike, data: Any, **dumps_kwargs) -> None:
    """``json.dumps(json_safe(data), **dumps_kwargs)`` plus a newline to ``path``, atomically
    (:func:`write_files_atomically`); non-finite numbers are written as ``null``."""
    path = Path(path)
    text = json.dumps(json_safe(data), allow_nan=False, **dumps_kwargs) + "\n"
    write_files_atomically(path.parent, {path.name: text.encode()})
