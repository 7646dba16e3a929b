"""Taylor's method compiled ahead of time: a first answer in a fresh process without numba.

numba compiles on first use, or loads its on-disk cache; either way a fresh process pays for
importing numba and starting its compiler before the first kernel runs, several tenths of a
second, more than the whole solve. :func:`build` compiles :func:`mechviz.dynamics.solver.solve_taylor`
once into an extension module (numba's ``pycc``) kept beside numba's cache, in the folder of
this version of the sources (:mod:`._cachedir`); :func:`solve` loads it with nothing but numpy,
and falls back to the just-in-time :func:`~mechviz.dynamics.solver.solve_taylor` while it is not built.
``python -m mechviz.dynamics.aot`` builds it (tens of seconds); ``mechviz bench`` builds it before it
times the first answer.

``solve("hoop", state, t_end, params=[M, m, a, g], rtol=1e-9)`` returns the state at ``t_end``
from ``state`` at 0: the steps of :class:`mechviz.dynamics.solver.Solver` at that tolerance. The
parameters are the system's kernel parameters (``System.kernel_params()``: charge ``[Omega]``,
hoop ``[M, m, a, g]``, free body ``[I1, I2, I3]``).
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import sys
from pathlib import Path

import numpy as np

from ._cachedir import cache_dir
from .ids import SYSTEM_IDS
from .taylor_order import order_for

NAME = "mechviz_taylor_aot"
_LOADED: list = []


def folder() -> Path:
    return Path(cache_dir()) / "aot"


def path() -> Path | None:
    """The built module for these sources, or ``None``."""
    found = sorted(folder().glob(f"{NAME}*.so")) + sorted(folder().glob(f"{NAME}*.pyd"))
    return found[0] if found else None


def load():
    """The built module (imported once), or ``None`` if it is not built for these sources."""
    if _LOADED:
        return _LOADED[0]
    where = path()
    if where is None:
        return None
    loader = importlib.machinery.ExtensionFileLoader(NAME, str(where))
    spec = importlib.util.spec_from_file_location(NAME, where, loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    _LOADED.append(module)
    return module


def build() -> Path:
    """Compile the module for these sources (replacing any) and return its path."""
    import warnings

    from numba.pycc import CC

    from .solver import solve_taylor

    out = folder()
    out.mkdir(parents=True, exist_ok=True)
    cc = CC(NAME)
    cc.output_dir = str(out)
    cc.verbose = False

    @cc.export("solve", "i8(i8, f8[::1], f8[::1], f8, f8, f8, i8, f8, f8[::1])")
    def _solve(sys_id, y0, p, t_end, rtol, atol, order, a, result):
        return solve_taylor(sys_id, y0, p, t_end, rtol, atol, order, a, result)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pycc's deprecation notice
        cc.compile()
    _LOADED.clear()
    built = path()
    if built is None:
        raise RuntimeError(f"pycc wrote no {NAME} module to {out}")
    return built


def solve(system: str, state, t_end: float, params, rtol: float = 1e-9, atol=None) -> np.ndarray:
    """The state at ``t_end`` of ``system`` (``"cyclotron"``, ``"hoop"`` or ``"free-body"``)
    from ``state`` at 0 (module docstring)."""
    if system not in SYSTEM_IDS:
        raise ValueError(f"system must be one of {', '.join(SYSTEM_IDS)}; got {system!r}")
    sys_id = SYSTEM_IDS[system]
    atol = rtol if atol is None else atol
    y0 = np.ascontiguousarray(state, dtype=np.float64)
    p = np.ascontiguousarray(params, dtype=np.float64)
    order, a = order_for(float(rtol), float(atol), sys_id)
    out = np.empty_like(y0)
    module = load()
    if module is None:
        from .solver import solve_taylor as run
    else:
        run = module.solve
    steps = run(sys_id, y0, p, float(t_end), float(rtol), float(atol), order, a, out)
    if steps == -2:
        raise ValueError("state, params and t_end must be finite")
    if steps < 0:
        raise FloatingPointError(f"{system}: the state stopped being finite")
    return out


if __name__ == "__main__":
    print(build())
    sys.exit(0)
