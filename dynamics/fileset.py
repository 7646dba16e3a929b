"""A set of files in a folder, switched from the old set to the new one by a single rename, so
that a process killed at any instant (``kill -9``, the OOM killer, a power cut) leaves the whole
old set or the whole new one, and a second writer waits for the first.

The layout, for a set ``NAME`` of files ``NAME.viser``, ``NAME.json``, ... in ``DIR``::

    DIR/NAME.viser -> .mechviz/NAME/current/NAME.viser     (one symlink per file, never changes)
    DIR/.mechviz/NAME/current -> set-ID                    (the commit point)
    DIR/.mechviz/NAME/set-ID/NAME.viser, NAME.json, ...    (the files themselves)

A writer (:func:`write_set`) takes an exclusive lock on ``DIR/.mechviz`` (``fcntl.flock``; a
second writer waits for it), writes the new files into a fresh ``set-ID`` folder and fsyncs
them, makes sure the symlinks exist, and then renames a new ``current`` link over the old one:
that rename is the only step that changes what the names show. Afterwards it removes the old set
folder. Whatever a killed writer leaves (a set folder never made current, a temporary link, an
old set not yet removed) is never reachable from the names in ``DIR``, and the next writer
removes it before writing. A folder written by the earlier layout (the files themselves in
``DIR``, switched by renaming each) is taken over without a mixed moment: the old files are
first copied into a set of their own and made current, then each is replaced by its link.

Signals (SIGINT, SIGTERM, SIGHUP) and I/O errors before the commit undo the write (the folder is
as it was); a signal that arrives later is held until the commit and the clean-up are over, then
handled: SIGINT raises :class:`~mechviz.dynamics.files.WriteInterrupted` saying the new set is complete,
SIGTERM and SIGHUP end the process as their default does.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import shutil
import signal
import stat
import time
from collections.abc import Callable
from pathlib import Path

from .files import (
    WriteFailed,
    WriteInterrupted,
    _fsync_dir,
    _make_dirs,
    _SignalGuard,
    _Signalled,
)

HOME = ".mechviz"  # the hidden folder inside DIR that holds the sets and the lock
CURRENT = "current"
_SET_PREFIX = "set-"
_LONGEST_ID = 40  # characters of the longest set-ID, for the path-length check

WaitFn = Callable[[str], None]


def set_home(out_dir: str | os.PathLike, name: str) -> Path:
    """``DIR/.mechviz/NAME``: where the sets of ``name`` live."""
    return Path(out_dir) / HOME / name


def current_set(out_dir: str | os.PathLike, name: str) -> Path | None:
    """The committed set folder of ``name`` in ``out_dir``, or None if there is none."""
    link = set_home(out_dir, name) / CURRENT
    try:
        target = os.readlink(link)
    except OSError:
        return None
    folder = link.parent / target
    if os.sep in target or not target.startswith(_SET_PREFIX) or not folder.is_dir():
        return None
    return folder


def check_room(out_dir: str | os.PathLike, name: str, file_names: list[str]) -> None:
    """``OSError`` (``ENAMETOOLONG`` and the like) if the longest path :func:`write_set` makes
    under ``out_dir`` cannot exist on this system; nothing is created. Call it before the work
    that produces the files."""
    longest = max(file_names, key=len)
    deepest = set_home(out_dir, name) / (_SET_PREFIX + "x" * _LONGEST_ID) / longest
    for p in (Path(out_dir), deepest, Path(out_dir) / f".{longest}.link-{'x' * _LONGEST_ID}"):
        try:
            os.lstat(p)
        except (FileNotFoundError, NotADirectoryError):
            pass


def _link_target(name: str, file_name: str) -> str:
    return f"{HOME}/{name}/{CURRENT}/{file_name}"


def _new_id() -> str:
    return f"{time.strftime('%Y%m%dT%H%M%S')}-{os.getpid()}-{secrets.token_hex(4)}"


class _Lock:
    """An exclusive ``flock`` on the folder ``home`` (made if missing; the folders made are
    added to ``created``). ``on_wait(message)`` is called once if another process holds it."""

    def __init__(self, home: Path, created: list[Path], on_wait: WaitFn | None) -> None:
        self.home, self.created, self.on_wait = home, created, on_wait
        self.fd: int | None = None

    def __enter__(self) -> _Lock:
        import fcntl  # POSIX only: imported where a set is written, so reading works anywhere

        told = False
        while True:
            self.created += _make_dirs(self.home)
            fd = os.open(self.home, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
            try:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except BlockingIOError:
                    if self.on_wait is not None and not told:
                        where = self.home.parent
                        self.on_wait(
                            f"another mechviz process is writing to {where}; waiting for it"
                        )
                        told = True
                    fcntl.flock(fd, fcntl.LOCK_EX)
                except OSError as exc:
                    # A file system without flock (some network mounts): write unlocked.
                    if exc.errno not in (errno.ENOLCK, errno.EOPNOTSUPP, errno.EBADF, errno.EINVAL):
                        raise
                # The holder may have removed the folder (a first write that failed): retry.
                here = os.fstat(fd)
                try:
                    now = os.stat(self.home)
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


def _tidy(out_dir: Path, name: str, file_names: list[str]) -> None:
    """Remove what killed writers left: every entry of the set's home other than ``current``
    and its set, temporary links in ``out_dir``, and the earlier layout's temporaries."""
    home = set_home(out_dir, name)
    keep = current_set(out_dir, name)
    for p in home.iterdir():
        if p.name != CURRENT and (keep is None or p.name != keep.name):
            _remove(p)
    prefixes = tuple(f".{f}." for f in file_names)
    for p in out_dir.iterdir():
        n = p.name
        if n.startswith(prefixes) and (n.endswith((".partial", ".old")) or ".link-" in n):
            _remove(p)


def _require_real_folders(*folders: Path) -> None:
    """``NotADirectoryError`` unless each is a folder itself, not a link to one: the clean-up
    removes what it finds inside, so it must never be led elsewhere."""
    for folder in folders:
        if not stat.S_ISDIR(os.lstat(folder).st_mode):
            raise NotADirectoryError(
                errno.ENOTDIR, "not a folder of its own (a link?); remove it", str(folder)
            )


def _write_folder(folder: Path, files: dict[str, bytes]) -> None:
    folder.mkdir()
    for file_name, content in files.items():
        with open(folder / file_name, "xb") as fh:
            fh.write(content)
            fh.flush()
            os.fsync(fh.fileno())
    _fsync_dir(folder)


def _point(home: Path, target: str) -> None:
    """Make ``home/current`` lead to ``target`` in one rename (the commit)."""
    _put_link(home, CURRENT, target)
    _fsync_dir(home)


def _put_link(out_dir: Path, file_name: str, target: str) -> None:
    """``out_dir/file_name`` as a symlink to ``target``, replacing what is there in one rename."""
    tmp = out_dir / f".{file_name}.link-{_new_id()}"
    os.symlink(target, tmp)
    try:
        os.replace(tmp, out_dir / file_name)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def _take_over_earlier_layout(out_dir: Path, name: str, file_names: list[str]) -> None:
    """Regular files ``out_dir/NAME.*`` (the earlier layout) become a committed set of their
    own, then each is replaced by its link: every step shows the same old content."""
    home = set_home(out_dir, name)
    plain = [f for f in file_names if (out_dir / f).is_file() and not (out_dir / f).is_symlink()]
    if not plain:
        return
    if current_set(out_dir, name) is None:
        folder = home / f"{_SET_PREFIX}{_new_id()}"
        folder.mkdir()
        for f in plain:
            with open(out_dir / f, "rb") as src, open(folder / f, "xb") as dst:
                shutil.copyfileobj(src, dst)
                dst.flush()
                os.fsync(dst.fileno())
        _fsync_dir(folder)
        _point(home, folder.name)
    for f in plain:
        _put_link(out_dir, f, _link_target(name, f))
    _fsync_dir(out_dir)


def _make_links(out_dir: Path, name: str, file_names: list[str]) -> list[str]:
    """Every ``out_dir/FILE`` a link through ``current``; returns the names that were missing
    (they are new, and dangle until the first commit)."""
    made = []
    for f in file_names:
        target = _link_target(name, f)
        path = out_dir / f
        try:
            st = os.lstat(path)
        except FileNotFoundError:
            os.symlink(target, path)
            made.append(f)
            continue
        if stat.S_ISDIR(st.st_mode):
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        if not (stat.S_ISLNK(st.st_mode) and os.readlink(path) == target):
            _put_link(out_dir, f, target)
    return made


def write_set(
    out_dir: str | os.PathLike,
    name: str,
    files: dict[str, bytes],
    *,
    on_wait: WaitFn | None = None,
) -> None:
    """Write ``files`` (``file name -> bytes``; names without a folder) into ``out_dir``
    (created if missing) as the set ``name``, switched in one rename (module docstring).

    ``on_wait(message)`` is called once if another process is writing to ``out_dir`` (this call
    then waits for it). Returns None when the new set is in place and nothing else is left.
    Raises :class:`~mechviz.dynamics.files.WriteFailed` (an ``OSError``) on an I/O error and
    :class:`~mechviz.dynamics.files.WriteInterrupted` (a ``KeyboardInterrupt``) on SIGINT; their
    ``unchanged`` says whether the folder shows the old set (True) or the complete new one
    (a signal that came after the commit). SIGTERM and SIGHUP end the process after the
    clean-up, as their default does. Signals are caught only in the main thread and only while
    their handler is the default one, as :func:`mechviz.dynamics.files.write_files_atomically` does.
    """
    out_dir = Path(out_dir)
    if not name or name in (".", "..") or os.sep in name or "\0" in name:
        raise ValueError(f"not a plain set name: {name!r}")
    file_names = list(files)
    for f in file_names:
        if not f or os.sep in f or f.startswith(".") or f in (HOME, CURRENT):
            raise ValueError(f"not a plain file name: {f!r}")
    home = set_home(out_dir, name)
    guard = _SignalGuard()
    created: list[Path] = []
    made_links: list[str] = []
    new_folder: Path | None = None
    committed = False
    lock = _Lock(out_dir / HOME, created, on_wait)
    with guard:
        try:
            lock.__enter__()
            created += _make_dirs(home)
            _require_real_folders(out_dir / HOME, home)
            _tidy(out_dir, name, file_names)
            _take_over_earlier_layout(out_dir, name, file_names)
            old = current_set(out_dir, name)
            new_folder = home / f"{_SET_PREFIX}{_new_id()}"
            _write_folder(new_folder, files)
            made_links = _make_links(out_dir, name, file_names)
            _fsync_dir(out_dir)
            guard.hold()  # from here on signals wait until the folder is settled
            if guard.pending is not None:
                raise _Signalled(guard.pending)
            _point(home, new_folder.name)
            committed = True
            if old is not None:
                _remove(old)
                _fsync_dir(home)
        except BaseException as exc:
            guard.hold()
            if not committed:
                _undo(out_dir, new_folder, made_links, created)  # still under the lock
            lock.__exit__()
            signum = exc.signum if isinstance(exc, _Signalled) else guard.pending
            if signum is None and isinstance(exc, KeyboardInterrupt):
                signum = signal.SIGINT
            guard.restore()
            _settle(guard, out_dir, signum, committed, exc, file_names)
            raise
        lock.__exit__()
        guard.restore()
        _settle(guard, out_dir, guard.pending, True, None, file_names)


def _undo(out_dir, new_folder, made_links, created) -> None:
    """Before the commit: remove the new set, the links this call made and the folders it made."""
    if new_folder is not None:
        _remove(new_folder)
    for f in made_links:
        with contextlib.suppress(OSError):
            (out_dir / f).unlink()
    for d in reversed(created):
        with contextlib.suppress(OSError):
            d.rmdir()


def _settle(guard, out_dir, signum, committed, exc, file_names) -> None:
    """After the lock is released: act on a signal that came, or turn ``exc`` into the
    exception that says what is on disk. Returns only when there is nothing to raise."""
    new = file_names if committed else []
    if signum is not None and signum != signal.SIGINT:
        guard.redeliver(signum)  # SIGTERM/SIGHUP: the folder is settled; end as before the call
    if signum is not None:
        raise WriteInterrupted(out_dir, signum, new, committed=committed) from None
    if exc is not None and isinstance(exc, OSError) and not isinstance(exc, WriteFailed):
        raise WriteFailed(out_dir, exc, new, committed=committed) from exc
