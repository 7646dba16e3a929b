"""DOP853: Dormand and Prince's explicit Runge-Kutta pair of order 8 with a dense output of order 7.

The tableau is scipy's (``scipy/integrate/_ivp/dop853_coefficients.py``, read from its file, not
retyped), after Hairer, Norsett & Wanner, *Solving Ordinary Differential Equations I*, 2nd ed.,
Sec. II.10 and the Fortran ``dop853``. The error estimate blends the 5th- and 3rd-order
estimators (``E5``, ``E3``); the continuous extension needs three extra stages and is Hairer's
nested form (scipy's ``Dop853DenseOutput``). Run by :mod:`.rk` with scipy's step control, it takes
the same steps with the same number of evaluations as ``solve_ivp(method="DOP853")``.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import scipy

from .rk import Pair


def _scipy_tableau():
    """scipy's ``dop853_coefficients`` module, loaded from its file: importing it the usual way
    imports all of ``scipy.integrate`` first (about 0.1 s before a first answer)."""
    path = Path(scipy.__file__).parent / "integrate" / "_ivp" / "dop853_coefficients.py"
    spec = importlib.util.spec_from_file_location("_mechviz_dop853_coefficients", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_coef = _scipy_tableau()
_SHAPE = (12, 16, 7)  # stages of a step; with the end's derivative and the dense output's 3; rows
if (_coef.N_STAGES, _coef.N_STAGES_EXTENDED, _coef.INTERPOLATOR_POWER) != _SHAPE:
    raise ImportError(f"scipy's DOP853 tableau changed shape; this pair expects {_SHAPE}")

_A = np.array(_coef.A[:16, :16], dtype=float)
_A[12, :12] = _coef.B  # the step's end (scipy keeps B apart)

PAIR = Pair(
    name="dop853",
    order=8,
    error_order=7,
    dense_order=7,
    n_stages=12,
    A=_A,
    b=np.array(_coef.B, dtype=float),
    c=np.concatenate([_coef.C[:12], [1.0], _coef.C[13:16]]).astype(float),
    E=np.array([_coef.E5, _coef.E3], dtype=float),
    P=np.array(_coef.D, dtype=float),
    interpolant="hairer",
    source="scipy.integrate._ivp.dop853_coefficients (Hairer, Norsett & Wanner)",
)
