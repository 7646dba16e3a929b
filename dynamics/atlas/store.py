"""An atlas on disk: an xarray Dataset in a Zarr store, written chunk by chunk as chunks finish.

Layout: each map variable has dims ``(method, y, x)`` (names from :mod:`.grid`) and Zarr chunks
equal to the atlas's chunks, so writing one chunk touches only its own files. Beside them, per
chunk (dims ``(method, chunk_row, chunk_col)``): ``chunk_done`` (1 once its cells are written),
``chunk_seconds`` (the time its task took), ``chunk_session`` (a random id of the run that
computed it) and ``chunk_checksum`` (a hash of its cells as written, :func:`checksum`). A chunk's
cells are written before its flags, so a run killed between the two leaves the chunk not done.

A resumed run trusts no flag alone (:func:`open_for_resume`): a chunk is kept only if it is
marked done, its cells read back and their hash is the one recorded when they were written. Any
other chunk with a trace on disk (a file deleted, cut short or overwritten, of its cells or of its
flags) is named, its files removed and computed again; damaged metadata (a variable's
``zarr.json``, the coordinates, the run key) is refused as a whole (:class:`DamagedStore`).
Only one run works on a folder at a time (:func:`locked`).

Every variable and axis has ``units`` and ``long_name`` attributes; a finished store's metadata
is consolidated (:func:`finish`). The attributes hold the run key (:meth:`AtlasSpec.run_key`),
the spec as JSON, the versions of Python, the project and the libraries, the creation time and,
for the lines drawn over the map,
what theory says (the linear stability limit per method and amplitude is a variable,
``linear_limit_dt``; the hoop's unstable mode-1 amplitudes an attribute).
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime as _dt
import errno
import hashlib
import json
import os
import platform
import shutil
import warnings
from importlib import metadata
from pathlib import Path

import numpy as np
import xarray as xr

from .grid import AtlasSpec
from .kernels import VARIABLES
from .theory import linear_limit_dt, mode1_unstable_intervals

BOOKKEEPING = ("chunk_done", "chunk_seconds", "chunk_session", "chunk_checksum")
UNITS = {"dt": "s", "rtol": "1", "amplitude": None, "theta1": "rad", "theta2": "rad"}
UNITS |= {"omega1": "rad/s", "omega2": "rad/s"}
DESCRIPTIONS = {
    "energy_error": "relative energy error (E - E0) / (E0 - E_floor) at the end or at escape",
    "escape_time": "time [s] the energy error first exceeded the threshold (NaN: never)",
    "bounded": "1 if the energy error stayed below the threshold, 0 if not, -1 not computed",
    "lyapunov": "largest Lyapunov exponent [1/s], renormalised twin runs",
    "error": "relative state error at the end against the exact solution or a tight DOP853 run",
}


#: Each variable's ``units`` (UDUNITS: "1" for a ratio, a flag or a count) and ``long_name``, as
#: the CF conventions name them: what a reader of the store (xarray, Panoply) labels axes with.
VARIABLE_UNITS = {
    "energy_error": ("1", "relative energy error"),
    "escape_time": ("s", "time the energy error first exceeded the threshold"),
    "bounded": ("1", "energy error stayed below the threshold (1), did not (0), not computed (-1)"),
    "lyapunov": ("1/s", "largest Lyapunov exponent"),
    "error": ("1", "relative state error at the end"),
    "chunk_done": ("1", "chunk written (1) or not (0)"),
    "chunk_seconds": ("s", "time the chunk's task took"),
    "chunk_session": ("1", "id of the run that computed the chunk"),
    "chunk_checksum": ("1", "hash of the chunk's cells as written (0: none recorded)"),
    "linear_limit_dt": ("s", "largest linearly stable step"),
}
AXIS_NAMES = {
    "dt": "step size",
    "rtol": "relative tolerance",
    "amplitude": "amplitude of the start",
    "theta1": "hoop angle at the start",
    "theta2": "bead angle at the start",
    "omega1": "hoop rate at the start",
    "omega2": "bead rate at the start",
}


class StoreError(ValueError):
    """The store cannot be used for this run (exists, belongs to another run, unreadable)."""


class DamagedStore(StoreError):
    """The store's metadata is damaged: no chunk of it can be trusted."""


class StoreBusy(StoreError):
    """Another run holds the folder's lock."""


def versions() -> dict[str, str]:
    out = {"python": platform.python_version()}
    for name in ("mechviz", "numpy", "numba", "scipy", "dask", "distributed", "xarray", "zarr"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def template(spec: AtlasSpec) -> xr.Dataset:
    """The empty dataset of ``spec``: every cell at its fill value, no chunk done."""
    from .theory import amplitude_unit

    y, x = spec.y.name, spec.x.name
    coords = {
        "method": np.array(spec.methods, dtype=object),
        y: spec.y.values(),
        x: spec.x.values(),
    }
    data = {}
    for name, (dtype, fill) in VARIABLES[spec.kind].items():
        cells = np.full(spec.shape, fill, dtype=dtype)
        data[name] = (("method", y, x), cells, {"description": DESCRIPTIONS[name]})
    grid = spec.chunk_grid
    dims = ("method", "chunk_row", "chunk_col")
    data["chunk_done"] = (dims, np.zeros(grid, dtype="i1"))
    data["chunk_seconds"] = (dims, np.full(grid, np.nan))
    data["chunk_session"] = (dims, np.zeros(grid, dtype="i8"))
    data["chunk_checksum"] = (dims, np.zeros(grid, dtype="i8"))
    system = spec.make_system()
    attrs = {
        "title": f"mechviz atlas: {spec.kind} of the {spec.system}",
        "run_key": spec.run_key(),
        "spec": json.dumps(spec.as_dict()),
        "versions": json.dumps(versions()),
        "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
    }
    if spec.kind == "stability":
        lim = np.stack([linear_limit_dt(system, m, spec.x.values()) for m in spec.methods])
        about = {"description": "largest linearly stable step [s]"}
        data["linear_limit_dt"] = (("method", x), lim, about)
    if spec.kind == "chaos":
        attrs["mode1_unstable"] = json.dumps(mode1_unstable_intervals(system.params))
    ds = xr.Dataset(data, coords=coords, attrs=attrs)
    for name in (y, x):
        unit = UNITS.get(name) or amplitude_unit(spec.system)
        ds[name].attrs["units"] = unit
        ds[name].attrs["long_name"] = AXIS_NAMES.get(name, name)
    ds["method"].attrs["long_name"] = "integration method"
    for name, (unit, long_name) in VARIABLE_UNITS.items():
        if name in ds:
            ds[name].attrs.update(units=unit, long_name=long_name)
    return ds


def finish(path: str | Path) -> None:
    """Consolidate the metadata of the finished store at ``path`` (every chunk done), so that a
    reader opens it with one read (``xr.open_zarr(path)``). Zarr writes the consolidated
    metadata to a temporary name and renames it into place: the store is whole throughout."""
    import zarr

    with warnings.catch_warnings():  # consolidated metadata is not yet in the Zarr v3 spec
        warnings.simplefilter("ignore", UserWarning)
        zarr.consolidate_metadata(str(path))


def _encoding(spec: AtlasSpec, ds: xr.Dataset) -> dict:
    enc = {}
    for name in VARIABLES[spec.kind]:
        enc[name] = {"chunks": (1, *spec.chunk)}
    for name in BOOKKEEPING:
        enc[name] = {"chunks": (1, 1, 1)}
    return enc


def _partial(path: Path) -> Path:
    return path.with_name(path.name + ".partial")


def create(path: str | Path, spec: AtlasSpec) -> None:
    """Write the empty dataset of ``spec`` to a new store at ``path``: written beside it and
    renamed into place, so a store at ``path`` is always whole."""
    path = Path(path)
    if path.exists():
        raise StoreError(
            f"--out: {path} exists; pass --resume to continue it, --fresh to start it again, "
            "or another --out"
        )
    ds = template(spec)
    partial = _partial(path)
    shutil.rmtree(partial, ignore_errors=True)
    try:
        with warnings.catch_warnings():  # strings are not yet in the Zarr v3 specification
            warnings.simplefilter("ignore", UserWarning)
            ds.to_zarr(partial, mode="w-", encoding=_encoding(spec, ds), consolidated=False)
        partial.rename(path)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise


def has_partial(path: str | Path) -> bool:
    """A store at ``path`` was being created when its run ended (only the copy beside it)."""
    return _partial(Path(path)).exists()


def remove(path: str | Path) -> None:
    """Remove the store at ``path`` (and a copy left half-made beside it)."""
    path = Path(path)
    for p in (path, _partial(path)):
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p)
        elif p.exists() or p.is_symlink():
            p.unlink()


@contextlib.contextmanager
def locked(folder: str | Path):
    """Hold the lock of ``folder`` (the one an atlas store lives in) while inside; raises
    :class:`StoreBusy` at once if another run holds it (waiting could be for hours). The lock is
    ``flock`` on the folder itself: it leaves no file behind and goes with the process, however
    that ends."""
    import fcntl

    folder = Path(folder)
    fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise
            raise StoreBusy(
                f"--out: another mechviz atlas is working in {folder}; wait for it to end, "
                "or use another --out"
            ) from None
        yield
    finally:
        os.close(fd)  # releases the lock


def checksum(spec: AtlasSpec, cells: dict) -> int:
    """A 63-bit hash of a chunk's cells as they are stored (dtype, shape and bytes of each
    variable): what the chunk's data must read back as for a resumed run to keep it."""
    h = hashlib.blake2b(digest_size=8)
    for name, (dtype, _fill) in VARIABLES[spec.kind].items():
        a = np.ascontiguousarray(np.asarray(cells[name], dtype=dtype))
        h.update(f"{name}:{a.dtype.str}:{a.shape}:".encode())
        h.update(a.tobytes())
    return int.from_bytes(h.digest(), "little") >> 1 or 1  # 0 means "none recorded"


@dataclasses.dataclass
class Resumed:
    """What :func:`open_for_resume` found: the chunks kept (verified) and those that were
    damaged, each with what was wrong."""

    done: np.ndarray
    damaged: dict[tuple[int, int, int], str]
    restarted: bool = False  # the store was never completed: started afresh

    def describe_damage(self, limit: int = 8) -> str:
        items = [f"{'/'.join(map(str, c))} ({why})" for c, why in sorted(self.damaged.items())]
        more = f" and {len(items) - limit} more" if len(items) > limit else ""
        return ", ".join(items[:limit]) + more


def _damaged(path: Path, what: str) -> DamagedStore:
    return DamagedStore(
        f"--resume: {path} is damaged ({what}); start it again with --fresh, or use another --out"
    )


def _open_checked(path: Path, spec: AtlasSpec):
    """The store's Zarr group, its metadata checked against ``spec``'s (:class:`DamagedStore`
    or :class:`StoreError` naming what is wrong)."""
    import zarr

    try:
        # each array's own metadata, not the consolidated copy a finished store also holds: a
        # deleted or damaged array file must be found here, not when xarray opens the store
        group = zarr.open_group(path, mode="r", use_consolidated=False)
        attrs = dict(group.attrs)
    except Exception as exc:
        raise _damaged(path, f"its zarr.json cannot be read: {exc.__class__.__name__}") from None
    key = attrs.get("run_key")
    if key != spec.run_key():
        raise StoreError(
            f"--resume: {path} holds another run (key {key}, this one {spec.run_key()}); "
            "same flags and code, or another --out"
        )
    ds = template(spec)
    enc = _encoding(spec, ds)
    for name, var in ds.variables.items():
        try:
            arr = group[name]
            meta = (arr.shape, arr.dtype == var.dtype or var.dtype == object)
        except Exception as exc:
            raise _damaged(path, f"{name}/zarr.json: {exc.__class__.__name__}") from None
        if meta != (var.shape, True):
            raise _damaged(path, f"{name}: shape or type is not this run's")
        want = enc.get(name, {}).get("chunks")
        if want is not None and tuple(arr.chunks) != tuple(want):
            raise _damaged(path, f"{name}: chunks are not this run's")
        if name in ds.coords or name == "linear_limit_dt":
            try:
                values = arr[...]
            except Exception as exc:
                raise _damaged(path, f"{name}: {exc.__class__.__name__}") from None
            same = (
                list(map(str, values)) == list(map(str, var.values))
                if var.dtype == object
                else np.array_equal(values, var.values, equal_nan=True)
            )
            if not same:
                raise _damaged(path, f"{name}: values are not this run's")
    return group


def open_for_resume(path: str | Path, spec: AtlasSpec, *, repair: bool = True) -> Resumed:
    """Check that the store at ``path`` is the same run as ``spec`` and verify every chunk it
    marks done (module docstring); with ``repair``, remove the files of the damaged chunks so
    they are computed again from scratch. A store that was never completed (a run killed while
    it created the store left only the copy beside it) is created afresh."""
    path = Path(path)
    if not path.exists():
        if repair and _partial(path).exists():
            create(path, spec)
            return Resumed(np.zeros(spec.chunk_grid, dtype=bool), {}, restarted=True)
        raise StoreError(f"--resume: no atlas at {path}")
    group = _open_checked(path, spec)
    done = np.zeros(spec.chunk_grid, dtype=bool)
    damaged: dict[tuple[int, int, int], str] = {}
    names = list(VARIABLES[spec.kind])
    # each array read whole when it can be (a store of many chunks is checked in seconds, not
    # one read per chunk); one with a damaged chunk is read chunk by chunk
    arrays = {n: group[n] for n in (*names, *BOOKKEEPING)}  # each opened once
    whole = {n: _read_whole(arrays[n]) for n in (*names, "chunk_done", "chunk_checksum")}
    for c in spec.chunks():
        why = _check_chunk(path, arrays, spec, c, names, whole)
        if why is None:
            done[c] = True
        elif why:
            damaged[c] = why
    if repair:
        for c in damaged:
            _remove_chunk(path, arrays, c, names)
    return Resumed(done, damaged)


def _chunk_file(path: Path, arr, name: str, index) -> Path:
    return path / name / arr.metadata.encode_chunk_key(tuple(index))


def _read_whole(arr) -> np.ndarray | None:
    try:
        return arr[...]
    except Exception:  # a chunk that does not decode: read chunk by chunk instead
        return None


def _block(group, name: str, c, spec: AtlasSpec, whole: dict) -> np.ndarray:
    """Chunk ``c`` of variable ``name``: from the array read whole, or read alone."""
    a = whole.get(name)
    if a is None:
        return group[name].get_block_selection(c)
    if name in BOOKKEEPING:
        return a[c[0] : c[0] + 1, c[1] : c[1] + 1, c[2] : c[2] + 1]
    k, rows, cols = spec.cells(c)
    return a[k : k + 1, rows, cols]


def _check_chunk(path: Path, group: dict, spec: AtlasSpec, c, names, whole: dict) -> str | None:
    """None if chunk ``c`` is done and verified; "" if it was never written; else what is
    wrong with it."""
    try:
        flag = int(_block(group, "chunk_done", c, spec, whole).ravel()[0])
    except Exception:
        return "done flag unreadable"
    try:
        recorded = int(_block(group, "chunk_checksum", c, spec, whole).ravel()[0])
    except Exception:
        return "checksum unreadable"
    if flag != 1:
        traces = [n for n in names if _chunk_file(path, group[n], n, c).exists()]
        if flag != 0:
            return "done flag damaged"
        if recorded != 0:
            return "done flag missing"
        return f"{traces[0]} written but not marked done" if traces else ""
    if recorded == 0:
        return "no checksum recorded"
    cells = {}
    for n in names:
        if not _chunk_file(path, group[n], n, c).exists():
            return f"{n} missing"
        try:
            cells[n] = _block(group, n, c, spec, whole)[0]
        except Exception:
            return f"{n} unreadable"
    if checksum(spec, cells) != recorded:
        return "checksum differs"
    return None


def _remove_chunk(path: Path, group, c, names) -> None:
    for n in (*names, *BOOKKEEPING):
        f = _chunk_file(path, group[n], n, c)
        if f.is_file() or f.is_symlink():
            f.unlink()


def done_chunks(path: str | Path) -> np.ndarray:
    """The store's ``chunk_done`` flags (method, chunk_row, chunk_col) as booleans."""
    with xr.open_zarr(path, consolidated=False) as ds:
        return ds["chunk_done"].values.astype(bool)


def write_chunk(path: str | Path, spec: AtlasSpec, index, cells: dict, session: int) -> None:
    """Write chunk ``index``'s cells, then its flags and checksum (module docstring)."""
    k, rows, cols = spec.cells(index)
    y, x = spec.y.name, spec.x.name
    region = {"method": slice(k, k + 1), y: rows, x: cols}
    data = {
        name: (("method", y, x), np.asarray(cells[name], dtype=dtype)[None])
        for name, (dtype, _fill) in VARIABLES[spec.kind].items()
    }
    xr.Dataset(data).to_zarr(path, region=region, consolidated=False)
    m, by, bx = index
    flags = {
        "chunk_done": np.ones((1, 1, 1), dtype="i1"),
        "chunk_seconds": np.full((1, 1, 1), float(cells["seconds"])),
        "chunk_session": np.full((1, 1, 1), session, dtype="i8"),
        "chunk_checksum": np.full((1, 1, 1), checksum(spec, cells), dtype="i8"),
    }
    dims = ("method", "chunk_row", "chunk_col")
    region = {
        "method": slice(m, m + 1),
        "chunk_row": slice(by, by + 1),
        "chunk_col": slice(bx, bx + 1),
    }
    flags_ds = xr.Dataset({n: (dims, v) for n, v in flags.items()})
    flags_ds.to_zarr(path, region=region, consolidated=False)


def load(path: str | Path) -> xr.Dataset:
    """The atlas at ``path``, read into memory."""
    with xr.open_zarr(path, consolidated=False) as ds:
        return ds.load()


def spec_of(ds: xr.Dataset) -> AtlasSpec:
    return AtlasSpec.from_dict(json.loads(ds.attrs["spec"]))
