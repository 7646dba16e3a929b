"""The hoop's two atlas maps in the viewer, headless: where its starts turn chaotic, and where the
chosen method's step stays stable.

- The **chaos map** of the hoop's start plane at rest, ``(theta1, theta2)`` [rad] over
  [-3, 3] rad each (:func:`chaos_spec`): the largest Lyapunov exponent [1/s] of each start from
  renormalised twin runs (:mod:`mechviz.dynamics.atlas.kernels`), RK4 at 0.01 s over 30 s, for the
  hoop's current parameters. A point of the map is a start: :meth:`ChaosMap.angles_at` turns a
  place on the picture into the angles, :meth:`ChaosMap.place_of` the angles into a place.
- The **stability map** of one fixed-step method (:func:`stability_spec`): bounded or not after
  50 periods of the fastest mode over step ``dt`` [s] (log axis) and amplitude ``A`` [rad] of
  each normal mode; the current step sits on it at ``(A_start, dt)`` with ``A_start`` the larger
  of the start's two normal-mode amplitudes (:meth:`StabilityMap.place_of`).

Places on a map are fractions ``(u, v)`` of its width and height, ``u`` from the left and ``v``
from the top, so a picture of any size (the panel's figure, the scene's texture) maps alike.

Both are computed by the atlas's own kernel (:func:`mechviz.dynamics.atlas.kernels.compute_chunk`, the
whole grid one chunk) in a background process (:class:`MapWorker`): the compiled loops hold
the interpreter's lock for their whole call, which in a thread would stall the viewer's frames.
The default hoop's maps are shipped (``assets/atlas/hoop-maps.npz``: the chaos map and each
fixed-step method's stability map, written by ``python -m mechviz.viz.model.atlas_map``) and loaded at
once, so the viewer starts with them; other parameters compute theirs in the background (a few
seconds each). Needs neither Dask nor xarray.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mechviz.dynamics import Hoop, assets, hoop, methods_for
from mechviz.dynamics.atlas.grid import AtlasSpec, Axis

#: The chaos map's angles [rad]: both axes, inside the viewer's start range (-pi, pi).
CHAOS_RANGE = (-3.0, 3.0)
CHAOS_CELLS = 64  # per axis
CHAOS_DURATION = 30.0  # s
CHAOS_METHOD, CHAOS_STEP = "rk4", 0.01
#: The stability map: steps omega_2 dt over these (log axis), amplitudes over the viewer's range.
STABILITY_OMEGA_DT = (0.02, 4.0)
STABILITY_ROWS, STABILITY_AMPLITUDES = 40, (0.05, 2.5, 20)
STABILITY_PERIODS = 50.0
SHIPPED = ("atlas", "hoop-maps.npz")
#: The chaos map's colours, from dark blue (regular) to yellow (chaotic): no colour of it is one
#: the scene gives a body or a trail, so the map never passes for one.
COLOURMAP = "cividis"


def _params(p: hoop.HoopParams) -> tuple[tuple[str, float], ...]:
    return tuple((k, float(v)) for k, v in vars(p).items())


def chaos_spec(p: hoop.HoopParams) -> AtlasSpec:
    """The viewer's chaos map of the hoop with parameters ``p`` (module docstring)."""
    lo, hi = CHAOS_RANGE
    return AtlasSpec(
        "chaos",
        Hoop.name,
        (CHAOS_METHOD,),
        Axis("theta2", lo, hi, CHAOS_CELLS),
        Axis("theta1", lo, hi, CHAOS_CELLS),
        params=_params(p),
        duration=CHAOS_DURATION,
        step=CHAOS_STEP,
        chunk=(CHAOS_CELLS, CHAOS_CELLS),
    )


def stability_spec(p: hoop.HoopParams, method: str) -> AtlasSpec | None:
    """The viewer's stability map of ``method`` on the hoop ``p``, or None for a method with no
    fixed step (adaptive) or no compiled kernel."""
    try:
        return AtlasSpec(
            "stability",
            Hoop.name,
            (method,),
            _dt_axis(p),
            Axis("amplitude", *STABILITY_AMPLITUDES),
            params=_params(p),
            periods=STABILITY_PERIODS,
            chunk=(STABILITY_ROWS, STABILITY_AMPLITUDES[2]),
        )
    except ValueError:
        return None


def _dt_axis(p: hoop.HoopParams) -> Axis:
    omega2 = float(hoop.normal_modes(p)[0][1])
    lo, hi = STABILITY_OMEGA_DT
    return Axis("dt", lo / omega2, hi / omega2, STABILITY_ROWS, "log")


def compute(spec_json: str) -> dict[str, np.ndarray]:
    """The map of the spec (JSON of :meth:`AtlasSpec.as_dict`): its arrays, the whole grid one
    chunk. What the background process runs."""
    from mechviz.dynamics.atlas.kernels import compute_chunk

    spec = AtlasSpec.from_dict(json.loads(spec_json))
    out = compute_chunk(spec, (0, 0, 0))
    return {k: np.asarray(v) for k, v in out.items() if isinstance(v, np.ndarray)}


# --------------------------------------------------------------------------- the maps
def _fraction(value: float, axis: Axis) -> float:
    """Where ``value`` sits along ``axis`` as a fraction of the picture: cell centres at
    ``(i + 1/2) / n`` (each cell a square of the picture), linear or logarithmic as the axis."""
    a, b = (
        (math.log(axis.start), math.log(axis.stop))
        if axis.scale == "log"
        else (axis.start, axis.stop)
    )
    x = math.log(value) if axis.scale == "log" else value
    if axis.n == 1:
        return 0.5
    step = (b - a) / (axis.n - 1)
    return (x - a + 0.5 * step) / (step * axis.n)


def _value(fraction: float, axis: Axis) -> float:
    a, b = (
        (math.log(axis.start), math.log(axis.stop))
        if axis.scale == "log"
        else (axis.start, axis.stop)
    )
    step = (b - a) / max(axis.n - 1, 1)
    x = a - 0.5 * step + fraction * step * axis.n
    return math.exp(x) if axis.scale == "log" else x


@dataclass(frozen=True)
class ChaosMap:
    """The largest Lyapunov exponent [1/s] ``lyapunov`` (theta2 rows, theta1 columns; row 0 is
    the lowest theta2) of the starts at rest of :attr:`spec`."""

    spec: AtlasSpec
    lyapunov: np.ndarray

    def __post_init__(self) -> None:
        if self.spec.kind != "chaos" or self.lyapunov.shape != self.spec.shape[1:]:
            raise ValueError("lyapunov: not the chaos map of the spec")

    def angles_at(self, u: float, v: float) -> tuple[float, float] | None:
        """The start ``(theta1, theta2)`` [rad] at the place ``(u, v)`` of the picture (``v``
        from the top, where theta2 is largest), or None outside it."""
        if not (0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
            return None
        return _value(u, self.spec.x), _value(1.0 - v, self.spec.y)

    def place_of(self, theta1: float, theta2: float) -> tuple[float, float]:
        """The place ``(u, v)`` of the start ``(theta1, theta2)``."""
        return _fraction(theta1, self.spec.x), 1.0 - _fraction(theta2, self.spec.y)

    def exponent_at(self, theta1: float, theta2: float) -> float:
        """The exponent of the cell holding ``(theta1, theta2)`` (NaN outside the map)."""
        u, v = self.place_of(theta1, theta2)
        ny, nx = self.lyapunov.shape
        i, j = int((1.0 - v) * ny), int(u * nx)
        return float(self.lyapunov[i, j]) if 0 <= i < ny and 0 <= j < nx else math.nan

    def colour_scale(self) -> float:
        """The exponent [1/s] the colours saturate at: the 99th percentile, at least 0.5."""
        finite = self.lyapunov[np.isfinite(self.lyapunov)]
        return max(0.5, float(np.percentile(finite, 99))) if finite.size else 1.0

    def rgb(self) -> np.ndarray:
        """The map as an (rows, columns, 3) uint8 picture, top row the largest theta2
        (:data:`COLOURMAP` from 0 to :meth:`colour_scale`; grey where a run was lost)."""
        import matplotlib

        top = self.colour_scale()
        lyap = self.lyapunov[::-1]
        rgba = matplotlib.colormaps[COLOURMAP](np.clip(np.nan_to_num(lyap) / top, 0.0, 1.0))
        out = (255 * rgba[..., :3]).round().astype(np.uint8)
        out[~np.isfinite(lyap)] = 128
        return out


@dataclass(frozen=True)
class StabilityMap:
    """Whether each cell of :attr:`spec` stayed bounded (``bounded``, dt rows from the smallest,
    amplitude columns) and its relative energy error at the end or at escape."""

    spec: AtlasSpec
    bounded: np.ndarray
    energy_error: np.ndarray

    def place_of(self, amplitude: float, dt: float) -> tuple[float, float]:
        """The place ``(u, v)`` of step ``dt`` [s] at ``amplitude`` [rad] (``v`` from the top,
        where dt is largest); outside [0, 1] when off the map."""
        return _fraction(amplitude, self.spec.x), 1.0 - _fraction(dt, self.spec.y)

    def dt_at(self, v: float) -> float:
        """The step [s] at height ``v`` of the picture."""
        return _value(1.0 - v, self.spec.y)

    def linear_limit(self) -> np.ndarray:
        """The largest linearly stable step [s] per amplitude of the map."""
        from mechviz.dynamics.atlas.theory import linear_limit_dt

        return linear_limit_dt(self.spec.make_system(), self.spec.methods[0], self.spec.x.values())


def start_amplitude(p: hoop.HoopParams, angles) -> float:
    """The larger of the two normal-mode amplitudes [rad] of a start at rest (the stability
    map's abscissa: each mode displaced by it)."""
    _, shapes = hoop.normal_modes(p)
    from mechviz.dynamics.measure import modal_coordinates

    return float(np.abs(modal_coordinates(np.asarray(angles, float)[None, :2], shapes)).max())


def load_shipped(p: hoop.HoopParams) -> ChaosMap | None:
    """The shipped chaos map if it is the one :func:`chaos_spec` asks for ``p``, else None."""
    arrays = _shipped(chaos_spec(p), "chaos")
    if arrays is None:
        return None
    return ChaosMap(chaos_spec(p), arrays["lyapunov"].astype(np.float64))


def load_shipped_stability(p: hoop.HoopParams, method: str) -> StabilityMap | None:
    """The shipped stability map of ``method`` if it is the one :func:`stability_spec` asks
    for, else None."""
    spec = stability_spec(p, method)
    arrays = None if spec is None else _shipped(spec, method)
    if arrays is None:
        return None
    return StabilityMap(spec, arrays["bounded"], arrays["energy_error"])


def _shipped(spec: AtlasSpec, name: str) -> dict[str, np.ndarray] | None:
    """The arrays stored under ``name`` in the shipped file if they are of ``spec``."""
    path = assets.asset(*SHIPPED)
    if not path.is_file():
        return None
    with np.load(path) as data:
        if f"{name}.spec" not in data.files:
            return None
        if json.loads(str(data[f"{name}.spec"])) != spec.as_dict():
            return None
        prefix = f"{name}."
        return {k[len(prefix) :]: np.array(data[k]) for k in data.files if k.startswith(prefix)}


def shipped_specs() -> dict[str, AtlasSpec]:
    """What the shipped file holds, by name: the default hoop's chaos map and the stability
    map of each of its fixed-step compiled methods."""
    p = hoop.HoopParams()
    out = {"chaos": chaos_spec(p)}
    for m in methods_for(Hoop):
        spec = stability_spec(p, m.name)
        if spec is not None:
            out[m.name] = spec
    return out


def write_shipped(path: Path | None = None) -> Path:
    """Compute the maps of :func:`shipped_specs` here and write them where :func:`load_shipped`
    looks (the exponents as float32)."""
    arrays = {}
    for name, spec in shipped_specs().items():
        arrays[f"{name}.spec"] = np.array(json.dumps(spec.as_dict()))
        for key, value in compute(json.dumps(spec.as_dict())).items():
            if key == "lyapunov":
                value = value.astype(np.float32)
            arrays[f"{name}.{key}"] = value
    path = Path(path) if path is not None else assets.asset(*SHIPPED)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".partial.npz")
    np.savez_compressed(partial, **arrays)
    partial.replace(path)
    return path


# --------------------------------------------------------------------------- in the background
class MapWorker:
    """Maps computed in background processes, one per request (``python -m
    mechviz.viz.model.atlas_map --compute SPEC OUT``: a process of its own imports nothing of the
    caller's, and is simply killed when its map is no longer wanted). :meth:`request` asks for
    the map of a spec in a slot (a request still running in that slot is killed); :meth:`poll`
    returns ``(spec, arrays)`` once it is done, or None."""

    def __init__(self) -> None:
        self._pending: dict[str, tuple[AtlasSpec, subprocess.Popen, Path]] = {}

    def request(self, slot: str, spec: AtlasSpec) -> None:
        self.cancel(slot)
        folder = Path(tempfile.mkdtemp(prefix="mechviz-map-"))
        (folder / "spec.json").write_text(json.dumps(spec.as_dict()))
        cmd = [sys.executable, "-m", __name__, "--compute", str(folder / "spec.json")]
        with open(folder / "err.txt", "wb") as err:
            proc = subprocess.Popen(
                [*cmd, str(folder / "map.npz")],
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=err,
                start_new_session=True,  # a terminal's Ctrl-C is the viewer's to handle
            )
        self._pending[slot] = (spec, proc, folder)

    def busy(self, slot: str) -> bool:
        return slot in self._pending

    def poll(self, slot: str) -> tuple[AtlasSpec, dict] | None:
        """The finished request of ``slot``; a failed one raises ``RuntimeError`` with the
        last line it wrote."""
        entry = self._pending.get(slot)
        if entry is None or entry[1].poll() is None:
            return None
        del self._pending[slot]
        spec, proc, folder = entry
        try:
            if proc.returncode != 0:
                lines = (folder / "err.txt").read_text(errors="replace").strip().splitlines()
                raise RuntimeError(lines[-1] if lines else f"exit status {proc.returncode}")
            with np.load(folder / "map.npz") as data:
                return spec, {k: np.array(data[k]) for k in data.files}
        finally:
            shutil.rmtree(folder, ignore_errors=True)

    def cancel(self, slot: str) -> None:
        entry = self._pending.pop(slot, None)
        if entry is not None:
            _, proc, folder = entry
            proc.kill()
            proc.wait()
            shutil.rmtree(folder, ignore_errors=True)

    def close(self) -> None:
        for slot in list(self._pending):
            self.cancel(slot)


def _compute_to(spec_path: str, out_path: str) -> None:
    arrays = compute(Path(spec_path).read_text())
    partial = out_path + ".partial.npz"
    np.savez(partial, **arrays)
    os.replace(partial, out_path)


class HoopMaps:
    """The maps for the hoop's current parameters and method. :meth:`update` (in the loop
    thread) asks for what is missing and takes what is done; True when a map changed.
    ``chaos`` and ``stability`` are the maps shown (None while computing, or for a method with
    no fixed step); ``status`` says which is being computed."""

    def __init__(self, worker: MapWorker | None = None) -> None:
        self.worker = worker or MapWorker()
        self.chaos: ChaosMap | None = None
        self.stability: StabilityMap | None = None
        self._wanted: dict[str, AtlasSpec | None] = {"chaos": None, "stability": None}
        self.failed: str | None = None

    def update(self, p: hoop.HoopParams, method: str) -> bool:
        changed = False
        want = chaos_spec(p)
        if self._wanted["chaos"] != want:
            self._wanted["chaos"] = want
            shipped = load_shipped(p)
            self.chaos, changed = shipped, True
            if shipped is None:
                self.worker.request("chaos", want)
        want_s = stability_spec(p, method)
        if self._wanted["stability"] != want_s:
            self._wanted["stability"], changed = want_s, True
            self.stability = load_shipped_stability(p, method)
            if want_s is not None and self.stability is None:
                self.worker.request("stability", want_s)
        for slot in ("chaos", "stability"):
            try:
                done = self.worker.poll(slot)
            except Exception as exc:  # a map that cannot be computed is shown as such
                self.failed = f"{slot} map: {exc.__class__.__name__}: {exc}"
                changed = True
                continue
            if done is None or done[0] != self._wanted[slot]:
                continue
            spec, arrays = done
            if slot == "chaos":
                self.chaos = ChaosMap(spec, arrays["lyapunov"])
            else:
                self.stability = StabilityMap(spec, arrays["bounded"], arrays["energy_error"])
            changed = True
        return changed

    @property
    def status(self) -> str:
        busy = [s for s in ("chaos", "stability") if self.worker.busy(s)]
        if self.failed:
            return self.failed
        return f"computing the {' and '.join(busy)} map…" if busy else ""

    def close(self) -> None:
        self.worker.close()


if __name__ == "__main__":
    if sys.argv[1:2] == ["--compute"]:  # a background request (MapWorker)
        _compute_to(sys.argv[2], sys.argv[3])
    else:  # python -m mechviz.viz.model.atlas_map [PATH]: the shipped maps
        print(write_shipped(Path(sys.argv[1]) if len(sys.argv) > 1 else None))
