"""An atlas on disk: an xarray Dataset in a Zarr store, written chunk by chunk as chunks finish.

Layout: each map variable has dims ``(method, y, x)`` (names from :mod:`.grid`) and Zarr chunks
equal to the atlas's chunks, so writing one chunk touches only its own files. Beside them, per
chunk (dims ``(method, chunk_row, chunk_col)``): ``chunk_done`` (1 once its cells are written),
``chunk_seconds`` (the time its task took) and ``chunk_session`` (a random id of the run that
computed it). A chunk's cells are written before its ``chunk_done``, so a run killed between the
two leaves the chunk not done and a resumed run computes it again: a chunk is never taken as done
with half its cells.

Every variable and axis has ``units`` and ``long_name`` attributes; a finished store's metadata
is consolidated (:func:`finish`). The attributes hold the run key (:meth:`AtlasSpec.run_key`),
the spec as JSON, the versions of Python, the project and the libraries, the creation time and,
for the lines drawn over the map,
what theory says (the linear stability limit per method and amplitude is a variable,
``linear_limit_dt``; the hoop's unstable mode-1 amplitudes an attribute).
"""

from __future__ import annotations

import datetime as _dt
import json
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

BOOKKEEPING = ("chunk_done", "chunk_seconds", "chunk_session")
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


def create(path: str | Path, spec: AtlasSpec) -> None:
    """Write the empty dataset of ``spec`` to a new store at ``path``: written beside it and
    renamed into place, so a store at ``path`` is always whole."""
    path = Path(path)
    if path.exists():
        raise StoreError(f"--out: {path} exists; pass --resume to continue it, or another --out")
    ds = template(spec)
    partial = path.with_name(path.name + ".partial")
    shutil.rmtree(partial, ignore_errors=True)
    try:
        with warnings.catch_warnings():  # strings are not yet in the Zarr v3 specification
            warnings.simplefilter("ignore", UserWarning)
            ds.to_zarr(partial, mode="w-", encoding=_encoding(spec, ds), consolidated=False)
        partial.rename(path)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise


def open_for_resume(path: str | Path, spec: AtlasSpec) -> np.ndarray:
    """Check that the store at ``path`` is the same run as ``spec``; returns its ``chunk_done``."""
    path = Path(path)
    if not path.exists():
        raise StoreError(f"--resume: no atlas at {path}")
    try:
        ds = xr.open_zarr(path, consolidated=False)
    except Exception as exc:
        raise StoreError(
            f"--resume: {path} is not an atlas store ({exc.__class__.__name__})"
        ) from None
    key = ds.attrs.get("run_key")
    if key != spec.run_key():
        raise StoreError(
            f"--resume: {path} holds another run (key {key}, this one {spec.run_key()}); "
            "same flags and code, or another --out"
        )
    return ds["chunk_done"].values.astype(bool)


def done_chunks(path: str | Path) -> np.ndarray:
    """The store's ``chunk_done`` flags (method, chunk_row, chunk_col) as booleans."""
    with xr.open_zarr(path, consolidated=False) as ds:
        return ds["chunk_done"].values.astype(bool)


def write_chunk(path: str | Path, spec: AtlasSpec, index, cells: dict, session: int) -> None:
    """Write chunk ``index``'s cells, then mark it done (module docstring)."""
    k, rows, cols = spec.cells(index)
    y, x = spec.y.name, spec.x.name
    region = {"method": slice(k, k + 1), y: rows, x: cols}
    data = {
        name: (("method", y, x), np.asarray(cells[name])[None]) for name in VARIABLES[spec.kind]
    }
    xr.Dataset(data).to_zarr(path, region=region, consolidated=False)
    m, by, bx = index
    flags = {
        "chunk_done": np.ones((1, 1, 1), dtype="i1"),
        "chunk_seconds": np.full((1, 1, 1), float(cells["seconds"])),
        "chunk_session": np.full((1, 1, 1), session, dtype="i8"),
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
