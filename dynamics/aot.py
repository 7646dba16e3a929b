"""Taylor's method compiled ahead of time: a first answer in a fresh process without numba.

numba compiles on first use, or loads its on-disk cache; either way a fresh process pays for
importing numba and starting its compiler before the first kernel runs, several tenths of a
second, more than the whole solve. :func:`build` compiles Taylor's loops once into an extension
module (numba's ``pycc``) kept beside numba's cache, in the folder of this version of the
sources (:mod:`._cachedir`) and of this machine's processor: it is compiled for this processor
and its features, as numba's just-in-time code is, so that it takes the same steps with the same
arithmetic (the tests compare the two) and runs as fast. It exports

- ``solve``: :func:`mechviz.dynamics.solver.solve_taylor` (the :class:`~mechviz.dynamics.solver.Solver`'s
  steps), which :func:`solve` calls;
- ``run``: :func:`mechviz.dynamics.integrators.taylor.run_taylor_compiled` with its kept step
  (the carry) as five arrays: what a :class:`~mechviz.dynamics.simulation.Simulation` of a
  shipped system with ``"taylor"`` runs by default once the module is built
  (:func:`taylor_runner`), so that such a run in a fresh process imports neither
  numba nor scipy.

How it gets built: ``python -m mechviz.dynamics.aot`` builds it (tens of seconds of one core);
``mechviz bench`` builds it before it times the first answer; and the first Taylor run of a
shipped system that has to go through numba (the module not built for these sources) starts
the build in the background, in a separate process at low priority, once per version of the
sources (:func:`build_in_background`). The background build was chosen over building on first
use in the foreground (tens of seconds on a call that takes milliseconds) and over a build step
of the install (an editable install has none, and every edit of the sources starts a fresh
folder): the process that pays numba's start anyway starts it, and the next process answers
without numba. ``MECHVIZ_AOT=0`` turns both off (runs go through numba; nothing is built in the
background): the test suite and the benchmark's timings of the compiled methods set it.

``solve("hoop", state, t_end, params=[M, m, a, g], rtol=1e-9)`` returns the state at ``t_end``
from ``state`` at 0: the steps of :class:`mechviz.dynamics.solver.Solver` at that tolerance. The
parameters are the system's kernel parameters (``System.kernel_params()``: charge ``[Omega]``,
hoop ``[M, m, a, g]``, free body ``[I1, I2, I3]``).
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ._cachedir import cache_dir
from .ids import SYSTEM_IDS
from .integrators.taylor_carry import PARALLEL_MIN
from .taylor_order import order_for

NAME = "mechviz_taylor_aot"
_LOADED: list = []
#: A background build that left no module after this long [s] is taken to have died: the next
#: run may start another.
STALE_BUILD_S = 900.0
_MARKER = "building"
_TAYLOR = __name__.rsplit(".", 1)[0] + ".integrators.taylor"


def enabled() -> bool:
    """Whether runs use the module by default and may build it in the background
    (``MECHVIZ_AOT``, default on; ``0`` off)."""
    return os.environ.get("MECHVIZ_AOT", "1").strip() != "0"


def machine_key() -> str:
    """What the module's machine code depends on beyond the sources: the processor's model and
    features (Linux: /proc/cpuinfo's first model name and flags), the architecture and the
    interpreter's ABI. Read without numba or LLVM."""
    cpu = platform.processor()
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            lines = [ln for ln in f.read(1 << 16).splitlines() if ":" in ln]
        wanted = ("model name", "flags", "features", "cpu model", "isa")
        cpu += "".join(sorted({ln for ln in lines if ln.split(":")[0].strip() in wanted}))
    except OSError:
        pass
    about = f"{platform.machine()}|{sys.implementation.cache_tag}|{cpu}"
    return hashlib.sha256(about.encode()).hexdigest()[:12]


def folder() -> Path:
    return Path(cache_dir()) / "aot" / machine_key()


def path() -> Path | None:
    """The built module for these sources and this machine, or ``None``."""
    where = folder()
    if not where.is_dir():
        return None
    found = sorted(where.glob(f"{NAME}*.so")) + sorted(where.glob(f"{NAME}*.pyd"))
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
    """Compile the module for these sources and this machine (replacing any) and return its
    path. It is compiled into a folder of its own and moved into place whole, so a process
    that loads it meanwhile finds the old module or the new one, never half of one."""
    import shutil
    import tempfile
    import warnings

    from numba.core import codegen
    from numba.pycc import CC

    from .integrators.taylor import run_taylor_compiled
    from .solver import solve_taylor

    out = folder()
    out.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="build-", dir=out))
    cc = CC(NAME)
    cc.output_dir = str(work)
    cc.verbose = False
    cc.target_cpu = "host"

    @cc.export("solve", "i8(i8, f8[::1], f8[::1], f8, f8, f8, i8, f8, f8[::1])")
    def _solve(sys_id, y0, p, t_end, rtol, atol, order, a, result):
        return solve_taylor(sys_id, y0, p, t_end, rtol, atol, order, a, result)

    @cc.export(
        "run",
        "i8(i8, f8[:, ::1], f8[::1], f8, f8, f8, f8, i8, f8, i8[:, ::1], i8[::1],"
        " f8[:, :, ::1], f8[::1], f8[::1], f8[::1], f8[:, ::1])",
    )
    def _run(sys_id, Y, p, t0, t1, rtol, atol, order, a, stats, status, kept, b, c, s, last):
        carry = (kept, b, c, s, last)
        return run_taylor_compiled(sys_id, Y, p, t0, t1, rtol, atol, order, a, stats, status, carry)

    # The processor's own features, as numba's just-in-time code has them (pycc's default is
    # the architecture's generic processor, whose arithmetic differs: no fused multiply-add).
    generic = codegen.AOTCPUCodegen._customize_tm_features
    codegen.AOTCPUCodegen._customize_tm_features = lambda self: codegen.get_host_cpu_features()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pycc's deprecation notice
            cc.compile()
        built = sorted(work.glob(f"{NAME}*"))
        if not built:
            raise RuntimeError(f"pycc wrote no {NAME} module to {work}")
        final = out / built[0].name
        os.replace(built[0], final)
        (out / _MARKER).unlink(missing_ok=True)
    finally:
        codegen.AOTCPUCodegen._customize_tm_features = generic
        shutil.rmtree(work, ignore_errors=True)
    _LOADED.clear()
    return final


def build_in_background() -> bool:
    """Start :func:`build` in a process of its own at low priority, detached from this one,
    unless the module is built, a build is under way (or failed within :data:`STALE_BUILD_S`),
    or :func:`enabled` says no. Returns whether one was started."""
    import subprocess

    if not enabled() or path() is not None:
        return False
    out = folder()
    marker = out / _MARKER
    try:
        out.mkdir(parents=True, exist_ok=True)
        if marker.exists() and time.time() - marker.stat().st_mtime < STALE_BUILD_S:
            return False
        marker.unlink(missing_ok=True)
        os.close(os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY))  # one process wins
        with open(out / "build.log", "wb") as log:  # what went wrong, if anything did
            subprocess.Popen(
                [sys.executable, "-m", __name__, "--background"],
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,  # Ctrl-C in the terminal is not for it
            )
    except OSError:  # a read-only cache, a lost race: run without it
        return False
    return True


def _ahead_of_time(module):
    """:func:`.integrators.taylor.run_taylor`'s serial road through the module compiled ahead of
    time."""
    run = module.run

    def advance(sys_id, Y, p, t0, t1, rtol, atol, stats, status, carry) -> int:
        order, a = order_for(rtol, atol, sys_id)
        return run(sys_id, Y, p, t0, t1, rtol, atol, order, a, stats, status, *carry.arrays)

    return advance


#: The runner chosen, by whether the module compiled ahead of time may serve (a shipped system,
#: a serial run): chosen once per process, so that a run built per solve does not ask again.
_CHOSEN: dict[bool, Callable] = {}


def taylor_runner(sys_id, members: int) -> Callable:
    """The function ``f(sys_id, Y, p, t0, t1, rtol, atol, stats, status, carry) -> steps`` that
    advances a run of ``members`` members of system ``sys_id``: through this module where it
    serves (a shipped system, fewer members than numba's threads take; built, and
    :func:`enabled`), else through numba (and then the build is started in the background):
    :func:`.integrators.taylor.run_taylor`'s arguments and result, whichever code runs it."""
    taylor = sys.modules.get(_TAYLOR)  # its threshold, which the warm-up and the bench move
    threshold = PARALLEL_MIN if taylor is None else taylor.PARALLEL_MIN
    serial_shipped = type(sys_id) is int and members < threshold
    run = _CHOSEN.get(serial_shipped)
    if run is None:
        run = _CHOSEN[serial_shipped] = _choose(serial_shipped)
    return run


def _choose(serial_shipped: bool) -> Callable:
    if serial_shipped and enabled():
        module = load()
        if module is not None and hasattr(module, "run"):
            return _ahead_of_time(module)
    from .integrators.taylor import run_taylor  # numba, and the generated expansions written if new

    if serial_shipped and enabled():
        build_in_background()  # numba's start is paid now; the next process need not
    return run_taylor


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
    if "--background" in sys.argv[1:] and hasattr(os, "nice"):
        os.nice(10)  # the user's foreground work first
    print(build())
    sys.exit(0)
