"""The compiled loops' status codes and the fixed-step methods' constants, importable without
numba: the driver and the methods' descriptions read them in a process that may never compile
anything (a Taylor run answered by the module compiled ahead of time, :mod:`mechviz.dynamics.aot`).
:mod:`.kernels` re-exports them."""

from __future__ import annotations

# Status codes written to ``status[0]`` (``status = [code, step index, member index]``);
# :func:`mechviz.dynamics.integrators.base.integration_error` words them.
OK, NONFINITE, NO_CONVERGENCE, TOO_SMALL_STEP = 0, 1, 2, 3

MIDPOINT_TOL = 1e-14
MIDPOINT_MAX_ITER = 100

# Yoshida's triple jump: w1 + w0 + w1 = 1 and 2 w1^3 + w0^3 = 0 cancel the third-order error.
_CBRT2 = 2.0 ** (1.0 / 3.0)
YOSHIDA_W1 = 1.0 / (2.0 - _CBRT2)
YOSHIDA_W0 = -_CBRT2 / (2.0 - _CBRT2)
