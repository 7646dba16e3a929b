"""A set of plain files in a folder, described by a manifest written last, so that a reader can
always tell a whole set from a mixed one and name the file that does not belong.

The layout, for a set ``NAME`` of files ``NAME.viser``, ``NAME.csv``, ..., ``NAME.json`` in
``DIR``: the files themselves, regular files, nothing else (no links, no hidden folder; a zip of
``DIR`` holds each file once). The manifest (the last file given, ``NAME.json``) carries
``schema_version`` and, under ``files``, the size and SHA-256 of every other file of the set.

A writer (:func:`write_set`) takes an exclusive lock on ``DIR`` itself (``fcntl.flock`` on the
folder, so no lock file is left behind; a second writer waits for it, readers take a shared
lock and wait too), writes every file under a temporary name in ``DIR`` (``.FILE.ID.partial``)
and fsyncs it, then renames each over its name with ``os.replace``, the manifest last. A file is
therefore always whole, old or new, whatever moment a process is killed at (``kill -9``, the OOM
killer, a power cut); a set cut in the middle of its renames shows new files beside the old
manifest, which every reader (:func:`check_set`) refuses, naming the file, until the next write.
Temporaries a killed writer left are removed by the next writer. A second writer never mixes
its files with the first's: it waits for the lock and then writes a whole set of its own.

A folder written by the earlier layout (each ``DIR/NAME.*`` a symlink into
``DIR/.mechviz/NAME/current/``) still reads through its links; the next write replaces each link
by a regular file and then removes ``DIR/.mechviz/NAME``.

Signals (SIGINT, SIGTERM, SIGHUP) and I/O errors before the renames undo the write (the folder
is as it was); a signal that arrives later is held until the renames and the clean-up are over,
then handled: SIGINT raises :class:`~mechviz.dynamics.files.WriteInterrupted` saying the new set
is complete, SIGTERM and SIGHUP end the process as their default does.

Nothing here imports a POSIX-only module at module level: ``fcntl`` is imported where a lock is
taken, and where it does not exist sets are written and read without one.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import secrets
import shutil
import signal
import stat
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from .files import (
    WriteFailed,
    WriteInterrupted,
    _fsync_dir,
    _make_dirs,
    _SignalGuard,
    _Signalled,
)

#: The manifest's layout: 2 adds ``schema_version`` itself (a manifest without it is 1).
SCHEMA_VERSION = 2
OLD_HOME = ".mechviz"  # the earlier layout's hidden folder of sets, taken over by the next write
_PARTIAL = ".partial"
_LONGEST_ID = 40  # characters of the longest write ID, for the path-length check

WaitFn = Callable[[str], None]


class SetMismatch(ValueError):
    """The files beside a manifest are not the set it describes. ``file`` is the name that does
    not belong (or is missing); the message says so in one sentence."""

    def __init__(self, message: str, file: str) -> None:
        super().__init__(message)
        self.file = file


def check_room(out_dir: str | os.PathLike, name: str, file_names: list[str]) -> None:
    """``OSError`` (``ENAMETOOLONG`` and the like) if the longest path :func:`write_set` makes
    under ``out_dir`` cannot exist on this system; nothing is created. Call it before the work
    that produces the files."""
    longest = max(file_names, key=len)
    for p in (Path(out_dir), Path(out_dir) / _temp_name(longest, "x" * _LONGEST_ID)):
        try:
            os.lstat(p)
        except (FileNotFoundError, NotADirectoryError):
            pass


def _temp_name(file_name: str, write_id: str) -> str:
    return f".{file_name}.{write_id}{_PARTIAL}"


def _new_id() -> str:
    return f"{time.strftime('%Y%m%dT%H%M%S')}-{os.getpid()}-{secrets.token_hex(4)}"


def _fcntl():
    """The ``fcntl`` module, or None where it does not exist (then nothing is locked)."""
    try:
        import fcntl  # POSIX only: imported here so that the package imports anywhere
    except ImportError:
        return None
    return fcntl


# flock errors that mean "no locks on this file system" (some network mounts): go on unlocked.
_NO_LOCKS = (errno.ENOLCK, errno.EOPNOTSUPP, errno.EBADF, errno.EINVAL)


class _Lock:
    """An exclusive ``flock`` on the folder ``folder`` (made if missing; the folders made are
    added to ``created``). ``on_wait(message)`` is called once if another process holds it."""

    def __init__(self, folder: Path, created: list[Path], on_wait: WaitFn | None) -> None:
        self.folder, self.created, self.on_wait = folder, created, on_wait
        self.fd: int | None = None

    def __enter__(self) -> _Lock:
        fcntl = _fcntl()
        if fcntl is None:  # no flock here (Windows): the folder is written unlocked
            self.created += _make_dirs(self.folder)
            return self
        told = False
        while True:
            self.created += _make_dirs(self.folder)
            fd = os.open(self.folder, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
            try:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except BlockingIOError:
                    if self.on_wait is not None and not told:
                        self.on_wait(
                            f"another mechviz process is using {self.folder}; waiting for it"
                        )
                        told = True
                    fcntl.flock(fd, fcntl.LOCK_EX)
                except OSError as exc:
                    if exc.errno not in _NO_LOCKS:
                        raise
                # The holder may have removed the folder (a first write that failed): retry.
                here = os.fstat(fd)
                try:
                    now = os.stat(self.folder)
                except FileNotFoundError:
                    now = None
                if now is not None and (now.st_dev, now.st_ino) == (here.st_dev, here.st_ino):
                    self.fd = fd
                    return self
            except BaseException:
                os.close(fd)
                raise
            os.close(fd)

    def __exit__(self, *exc) -> None:
        if self.fd is not None:
            os.close(self.fd)  # closing releases the lock
            self.fd = None


@contextlib.contextmanager
def reading(folder: str | os.PathLike) -> Iterator[None]:
    """A shared lock on ``folder`` while a set in it is read: a writer's renames never fall
    in the middle of the reading (it waits, and so does a reader that comes during a write).
    Without ``fcntl``, or where the folder cannot be opened or locked, nothing is locked."""
    fcntl = _fcntl()
    fd = None
    if fcntl is not None:
        with contextlib.suppress(OSError):
            fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
    try:
        if fd is not None:
            try:
                fcntl.flock(fd, fcntl.LOCK_SH)
            except OSError as exc:
                if exc.errno not in _NO_LOCKS:
                    raise
        yield
    finally:
        if fd is not None:
            os.close(fd)


def _remove(path: Path) -> None:
    """Remove a file, link or folder tree; missing is fine."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return
    if stat.S_ISDIR(st.st_mode):
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()


def _tidy(out_dir: Path, file_names: list[str]) -> None:
    """Remove what killed writers left in ``out_dir``: temporaries of these names (this
    layout's and the earlier layouts')."""
    prefixes = tuple(f".{f}." for f in file_names)
    for p in out_dir.iterdir():
        n = p.name
        if n.startswith(prefixes) and (n.endswith((_PARTIAL, ".old")) or ".link-" in n):
            _remove(p)


def _old_home(out_dir: Path, name: str) -> Path | None:
    """``DIR/.mechviz/NAME`` of the earlier layout, if there is one. ``NotADirectoryError`` if
    it, or ``DIR/.mechviz``, is not a folder of its own (a link?): its removal must never be led
    elsewhere."""
    home = out_dir / OLD_HOME / name
    for folder in (out_dir / OLD_HOME, home):
        try:
            st = os.lstat(folder)
        except FileNotFoundError:
            return None
        if not stat.S_ISDIR(st.st_mode):
            raise NotADirectoryError(
                errno.ENOTDIR, "not a folder of its own (a link?); remove it", str(folder)
            )
    return home


def _forget_old_layout(out_dir: Path, name: str, home: Path | None, drop: list[str]) -> None:
    """After the renames: the names of ``drop`` (files an earlier set had and this one has not)
    and every link into the earlier layout's ``home`` go, then ``home`` itself, and
    ``DIR/.mechviz`` if nothing else is in it."""
    for f in drop:
        _remove(out_dir / f)
    if home is not None:
        prefix = f"{OLD_HOME}/{name}/"
        for p in out_dir.iterdir():
            with contextlib.suppress(OSError):
                if p.is_symlink() and os.readlink(p).startswith(prefix):
                    p.unlink()
        _remove(home)
    with contextlib.suppress(OSError):  # also when a killed writer removed only the set
        (out_dir / OLD_HOME).rmdir()  # only if empty: other sets of the earlier layout stay


def _left_over(out_dir: Path, file_names: list[str]) -> list[str]:
    """The files the manifest in place (``file_names[-1]``) lists that the new set has not."""
    try:
        old = manifest_of(out_dir, file_names[-1])
    except (SetMismatch, OSError):
        return []
    listed = old["files"] if old is not None else {}
    return [f for f in listed if isinstance(f, str) and _plain(f) and f not in file_names]


def _write_temporaries(out_dir: Path, files: dict[str, bytes], temps: dict[str, Path]) -> None:
    write_id = _new_id()
    for file_name, content in files.items():
        tmp = out_dir / _temp_name(file_name, write_id)
        temps[file_name] = tmp
        with open(tmp, "xb") as fh:
            fh.write(content)
            fh.flush()
            os.fsync(fh.fileno())


def write_set(
    out_dir: str | os.PathLike,
    name: str,
    files: dict[str, bytes],
    *,
    on_wait: WaitFn | None = None,
) -> None:
    """Write ``files`` (``file name -> bytes``; names without a folder) into ``out_dir``
    (created if missing) as regular files, each replaced atomically, in the order given: the
    last is the manifest (module docstring). Files the manifest being replaced lists and the new
    set has not (a chart format not asked for this time) are removed once the new set is in.

    ``on_wait(message)`` is called once if another process is writing to ``out_dir`` (this call
    then waits for it). Returns None when the new set is in place and nothing else is left.
    Raises :class:`~mechviz.dynamics.files.WriteFailed` (an ``OSError``) on an I/O error and
    :class:`~mechviz.dynamics.files.WriteInterrupted` (a ``KeyboardInterrupt``) on SIGINT; their
    ``unchanged`` says whether the folder shows the old set (True) and ``committed`` whether it
    shows the complete new one (a signal that came after the renames). SIGTERM and SIGHUP end
    the process after the clean-up, as their default does. Signals are caught only in the main
    thread and only while their handler is the default one, as
    :func:`mechviz.dynamics.files.write_files_atomically` does.
    """
    out_dir = Path(out_dir)
    if not name or name in (".", "..") or os.sep in name or "\0" in name:
        raise ValueError(f"not a plain set name: {name!r}")
    file_names = list(files)
    for f in file_names:
        if not f or os.sep in f or f.startswith(".") or "\0" in f:
            raise ValueError(f"not a plain file name: {f!r}")
    guard = _SignalGuard()
    created: list[Path] = []
    temps: dict[str, Path] = {}
    switched: list[str] = []
    committed = False
    lock = _Lock(out_dir, created, on_wait)
    with guard:
        try:
            lock.__enter__()
            home = _old_home(out_dir, name)
            drop = _left_over(out_dir, file_names)
            _tidy(out_dir, file_names)
            for f in file_names:
                if (out_dir / f).is_dir() and not (out_dir / f).is_symlink():
                    raise IsADirectoryError(
                        errno.EISDIR, os.strerror(errno.EISDIR), str(out_dir / f)
                    )
            _write_temporaries(out_dir, files, temps)
            guard.hold()  # from here on signals wait until the folder is settled
            if guard.pending is not None:
                raise _Signalled(guard.pending)
            for f in file_names:  # the manifest last: until it is in, readers refuse a mix
                os.replace(temps[f], out_dir / f)
                del temps[f]
                switched.append(f)
            _fsync_dir(out_dir)
            committed = True
            _forget_old_layout(out_dir, name, home, drop)
            _fsync_dir(out_dir)
        except BaseException as exc:
            guard.hold()
            _undo(temps, [] if switched else created)  # still under the lock
            lock.__exit__()
            signum = exc.signum if isinstance(exc, _Signalled) else guard.pending
            if signum is None and isinstance(exc, KeyboardInterrupt):
                signum = signal.SIGINT
            guard.restore()
            _settle(guard, out_dir, signum, committed, exc, switched)
            raise
        lock.__exit__()
        guard.restore()
        _settle(guard, out_dir, guard.pending, True, None, file_names)


def _undo(temps: dict[str, Path], created: list[Path]) -> None:
    """Remove the temporaries not renamed yet and the folders this call made (when nothing
    was renamed into them)."""
    for p in temps.values():
        with contextlib.suppress(OSError):
            p.unlink()
    for d in reversed(created):
        with contextlib.suppress(OSError):
            d.rmdir()


def _settle(guard, out_dir, signum, committed, exc, switched) -> None:
    """After the lock is released: act on a signal that came, or turn ``exc`` into the
    exception that says what is on disk. Returns only when there is nothing to raise."""
    if signum is not None and signum != signal.SIGINT:
        guard.redeliver(signum)  # SIGTERM/SIGHUP: the folder is settled; end as before the call
    if signum is not None:
        raise WriteInterrupted(out_dir, signum, switched, committed=committed) from None
    if exc is not None and isinstance(exc, OSError) and not isinstance(exc, WriteFailed):
        raise WriteFailed(
            out_dir,
            exc,
            switched,
            committed=committed,
            mixed="readers refuse it, naming the file; the next write replaces it",
        ) from exc


# --------------------------------------------------------------------------- reading
def manifest_of(folder: str | os.PathLike, manifest_name: str) -> dict[str, Any] | None:
    """The manifest ``folder/manifest_name`` if it describes a set (a JSON object with
    ``files``), None if there is no such file or it describes none (any other JSON file).
    :class:`SetMismatch` if it cannot be read as JSON or was written by a newer layout."""
    return _manifest(Path(folder), manifest_name)[0]


def _manifest(folder: Path, manifest_name: str) -> tuple[dict[str, Any] | None, bytes]:
    try:
        text = (folder / manifest_name).read_bytes()
    except FileNotFoundError:
        return None, b""
    try:
        data = json.loads(text)
    except (ValueError, RecursionError):
        raise SetMismatch(f"{manifest_name} is not a manifest (not JSON)", manifest_name) from None
    if not isinstance(data, dict) or not isinstance(data.get("files"), dict):
        return None, text
    version = data.get("schema_version", 1)
    if not isinstance(version, int) or version > SCHEMA_VERSION:
        raise SetMismatch(
            f"{manifest_name} was written by a newer mechviz (schema_version {version}); this one "
            f"reads up to {SCHEMA_VERSION}",
            manifest_name,
        )
    return data, text


def check_set(
    folder: str | os.PathLike,
    manifest_name: str,
    *,
    have: dict[str, bytes] | None = None,
    belongs: str | None = None,
) -> tuple[dict[str, Any] | None, dict[str, bytes]]:
    """Read the set ``folder/manifest_name`` describes and check every file against it: its
    size and SHA-256. Returns ``(manifest, contents)``, the bytes of every file checked (those
    in ``have`` are checked as given instead of read) and of the manifest itself. ``(None, {})``
    if there is no manifest describing a set (:func:`manifest_of`).

    :class:`SetMismatch` names the first file that does not belong: one that is missing, or
    whose content is not what the manifest lists ("helix.csv is from an older recording than
    helix.json"), or ``belongs`` (a file the caller is about to use) when the manifest does
    not list it. Hold :func:`reading` around this and the use of the contents to keep a
    writer's renames out of the way."""
    folder = Path(folder)
    man, text = _manifest(folder, manifest_name)
    if man is None:
        return None, {}
    listed: dict[str, Any] = man["files"]
    if belongs is not None and belongs not in listed and belongs != manifest_name:
        raise SetMismatch(
            f"{belongs} is not one of the files {manifest_name} lists: it is from another "
            "recording",
            belongs,
        )
    have = have or {}
    contents: dict[str, bytes] = {}
    for file_name, meta in listed.items():
        if not isinstance(file_name, str) or not _plain(file_name):
            raise SetMismatch(
                f"{manifest_name} lists {file_name!r}, not a file name", manifest_name
            )
        if file_name in have:
            data = have[file_name]
        else:
            try:
                data = (folder / file_name).read_bytes()
            except FileNotFoundError:
                raise SetMismatch(
                    f"{file_name} is missing ({manifest_name} lists it)", file_name
                ) from None
        size = meta.get("bytes") if isinstance(meta, dict) else None
        digest = meta.get("sha256") if isinstance(meta, dict) else None
        if len(data) != size or hashlib.sha256(data).hexdigest() != digest:
            raise SetMismatch(
                f"{file_name} is from {_which(folder, file_name, manifest_name)} recording than "
                f"{manifest_name}{_when(man)}: the set is mixed; record it again",
                file_name,
            )
        contents[file_name] = data
    contents[manifest_name] = text
    return man, contents


def _plain(file_name: str) -> bool:
    return (
        bool(file_name)
        and "/" not in file_name
        and os.sep not in file_name
        and (not file_name.startswith("."))
    )


def _which(folder: Path, file_name: str, manifest_name: str) -> str:
    """ "an older", "a newer" or "another", by the files' modification times: the manifest is
    always written last, so a file clearly older than it was left from an earlier set, and one
    newer than it from a write that did not finish."""
    try:
        age = os.stat(folder / file_name).st_mtime - os.stat(folder / manifest_name).st_mtime
    except OSError:
        return "another"
    if age < -1.0:
        return "an older"
    if age > 1.0:
        return "a newer (unfinished)"
    return "another"


def _when(man: dict[str, Any]) -> str:
    when = man.get("recorded_at")
    return f" (recorded {when})" if isinstance(when, str) else ""


def check_beside(path: str | os.PathLike, data: bytes | None = None) -> dict[str, Any] | None:
    """Check the set the file ``path`` belongs to, described by the manifest beside it (same
    name, ``.json``), if there is one; ``data``: the bytes of ``path`` already read (checked as
    given). Returns the manifest (None without one). :class:`SetMismatch` names the file that
    does not belong."""
    path = Path(path)
    have = {path.name: data} if data is not None else None
    man, _ = check_set(path.parent, path.with_suffix(".json").name, have=have, belongs=path.name)
    return man
