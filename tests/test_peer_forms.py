"""The benchmark's peer forms, generated from the equations written once, are our equations.

Each peer's right-hand side (heyoka's expressions, with runtime parameters or with one
parameter set's constants built in, CyRK's C callback, odeint's callback, the compiled
functions scipy's solvers call, the C steps) is generated from
:data:`mechviz.dynamics.codegen.equations.EQUATIONS`; here each one, on random states and
parameters of every system, agrees with the product's generated right-hand side
(:data:`mechviz.dynamics.integrators.kernels.RHS`) to round-off. A peer writing a different
equation (a sign, a parameter in the wrong slot) would be off by O(1). The C and odeint forms
need no optional package (a C compiler for the C one); heyoka's are skipped without heyoka.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import numpy as np
import pytest

from mechviz.bench import c_form, experiments, fast_peers, peer_equations, peers
from mechviz.dynamics.codegen.equations import EQUATIONS
from mechviz.dynamics.ids import CYCLOTRON, FREE_BODY, HOOP
from mechviz.dynamics.integrators.kernels import RHS, RK4
from mechviz.dynamics.integrators.scipy_ivp import _make_fun

SYSTEMS = [CYCLOTRON, HOOP, FREE_BODY]
ROUND_OFF = 1e-13  # relative to the rates' size; a wrong equation is off by O(1)


def _cases(sys_id: int, n: int = 20, seed: int = 0):
    """``n`` random ``(state, kernel parameters)`` of the system: states of order 1, the
    parameters (masses, lengths, g, moments of inertia, the gyrofrequency) in [0.3, 3]."""
    eq = EQUATIONS[sys_id]()
    rng = np.random.default_rng(seed + sys_id)
    for _ in range(n):
        yield rng.uniform(-2.0, 2.0, eq.dim), rng.uniform(0.3, 3.0, len(eq.params))


def _ours(sys_id: int, y: np.ndarray, p: np.ndarray) -> np.ndarray:
    out = np.empty_like(y)
    RHS[sys_id](y, p, out)
    return out


def _close(got: np.ndarray, want: np.ndarray) -> bool:
    return float(np.max(np.abs(got - want))) <= ROUND_OFF * max(1.0, float(np.max(np.abs(want))))


@pytest.mark.parametrize("sys_id", SYSTEMS)
def test_odeint_callback_is_our_right_hand_side(sys_id):
    f = fast_peers.odeint_rhs(sys_id)
    for y, p in _cases(sys_id):
        got = f(y, 0.0, p)
        assert got.shape == y.shape
        assert _close(got, _ours(sys_id, y, p))


@pytest.mark.parametrize("sys_id", SYSTEMS)
def test_scipy_solvers_call_our_compiled_right_hand_side(sys_id):
    """The functions scipy's methods call: the one every method the bench sweeps calls through
    ``Simulation`` (``solve_ivp``'s methods and ``odeint``) and odeint's other form in the
    fastest-form comparison each call the compiled right-hand side and give ours."""
    d = EQUATIONS[sys_id]().dim
    for y, p in _cases(sys_id):
        want = _ours(sys_id, y, p)
        assert _close(_make_fun(sys_id, p, d)(0.0, y), want)
        assert _close(fast_peers.odeint_closure(sys_id, p)(y, 0.0), want)


@pytest.mark.parametrize("sys_id", SYSTEMS)
def test_cyrk_callback_is_our_right_hand_side(sys_id):
    """CyRK's C callback ``f(dy, t, y, args)``, called through its C address (no CyRK needed)."""
    cf = peers._cyrk_rhs(sys_id)
    ptr = ctypes.POINTER(ctypes.c_double)
    call = ctypes.CFUNCTYPE(None, ptr, ctypes.c_double, ptr, ptr)(cf.address)
    for y, p in _cases(sys_id):
        dy = np.full_like(y, np.nan)
        y, p = np.ascontiguousarray(y), np.ascontiguousarray(p)
        call(dy.ctypes.data_as(ptr), 0.0, y.ctypes.data_as(ptr), p.ctypes.data_as(ptr))
        assert _close(dy, _ours(sys_id, y, p))


@pytest.fixture(scope="module")
def c_library(tmp_path_factory):
    """The generated C header built into a shared library with exported wrappers of each
    system's ``rhs_<name>`` and ``rk4_<name>``."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    tmp = tmp_path_factory.mktemp("c_form")
    cases = experiments.c_cases()
    (tmp / experiments.C_HEADER).write_text(c_form.c_rk4_header(cases))
    wrappers = [f'#include "{experiments.C_HEADER}"']
    for name in (c_form.C_NAMES[sys_id] for sys_id in cases):
        wrappers.append(
            f"void call_rhs_{name}(const double *y, const double *p, double *o)"
            f" {{ rhs_{name}(y, p, o); }}\n"
            f"double call_rk4_{name}(long n, double h) {{ return rk4_{name}(n, h); }}"
        )
    (tmp / "wrap.c").write_text("\n".join(wrappers) + "\n")
    lib = tmp / "libpeer.so"
    subprocess.run(
        [cc, "-O2", "-shared", "-fPIC", f"-I{tmp}", str(tmp / "wrap.c"), "-lm", "-o", str(lib)],
        check=True,
        capture_output=True,
        timeout=120,
    )
    return ctypes.CDLL(str(lib))


@pytest.mark.parametrize("sys_id", SYSTEMS)
def test_c_right_hand_side_is_ours(c_library, sys_id):
    ptr = ctypes.POINTER(ctypes.c_double)
    f = getattr(c_library, f"call_rhs_{c_form.C_NAMES[sys_id]}")
    f.argtypes, f.restype = [ptr, ptr, ptr], None
    for y, p in _cases(sys_id):
        out = np.full_like(y, np.nan)
        f(y.ctypes.data_as(ptr), p.ctypes.data_as(ptr), out.ctypes.data_as(ptr))
        assert _close(out, _ours(sys_id, y, p))


@pytest.mark.parametrize("sys_id", SYSTEMS)
def test_c_rk4_loop_takes_our_rk4_steps(c_library, sys_id):
    """The C loop from the benchmark problem's start, n steps of h: the sum of its final state
    is that of the product's RK4 step taken n times, to round-off (a wrong stage would not be)."""
    f = getattr(c_library, f"call_rk4_{c_form.C_NAMES[sys_id]}")
    f.argtypes, f.restype = [ctypes.c_long, ctypes.c_double], ctypes.c_double
    p, y0 = experiments.c_cases()[sys_id]
    n, h = 500, 0.01
    y = np.array(y0, dtype=float)
    for _ in range(n):
        RK4[sys_id](y, p, h)
    assert abs(f(n, h) - y.sum()) <= 1e-11 * max(1.0, float(np.abs(y).sum()))
    assert abs(f(n, 2 * h) - y.sum()) > 1e-9  # another step lands elsewhere


@pytest.mark.parametrize("sys_id", SYSTEMS)
def test_heyoka_equations_are_ours(sys_id):
    """heyoka's generated expressions, compiled by heyoka (``cfunc``) with the parameters'
    constants of :func:`heyoka_pars`, evaluate to our right-hand side."""
    hy = pytest.importorskip("heyoka")
    eqs = peer_equations.heyoka_equations(sys_id)
    assert len(eqs) == EQUATIONS[sys_id]().dim
    cf = hy.cfunc([rate for _, rate in eqs], vars=[v for v, _ in eqs])
    for y, p in _cases(sys_id):
        got = np.asarray(cf(y, pars=peer_equations.heyoka_pars(sys_id, p)))
        assert _close(got, _ours(sys_id, y, p))


@pytest.mark.parametrize("sys_id", SYSTEMS)
def test_heyoka_equations_with_built_in_constants_are_ours(sys_id):
    """The same expressions with one parameter set's constants as numbers (no runtime
    parameters left) evaluate to our right-hand side for that parameter set."""
    hy = pytest.importorskip("heyoka")
    for y, p in _cases(sys_id, n=5):
        eqs = peer_equations.heyoka_equations(sys_id, peer_equations.heyoka_pars(sys_id, p))
        cf = hy.cfunc([rate for _, rate in eqs], vars=[v for v, _ in eqs])
        assert not any("par[" in str(rate) for _, rate in eqs)
        assert _close(np.asarray(cf(y)), _ours(sys_id, y, p))


def test_heyoka_parameters_are_the_rk4_steps_constants():
    """The hoop's runtime parameters are the constants of the parameters our steps form once
    (the mass matrix's ``-m`` and ``2M + m``, the forces' ``-g/a`` and ``-(M + m) g/a``), in
    double, bit for bit as the printed expressions give them."""
    M, m, a, g = 1.3, 0.7, 0.9, 9.81
    got = peer_equations.heyoka_pars(HOOP, np.array([M, m, a, g]))
    assert list(got) == [-m, 2 * M + m, -g / a, -g * (M + m) / a]


@pytest.mark.parametrize("sys_id", SYSTEMS)
def test_mpmath_reference_equations_are_ours(sys_id):
    """The right-hand side mpmath's 25-digit references integrate, at 25 digits, rounds to
    ours (which forms its constants in double: round-off apart)."""
    mpmath = pytest.importorskip("mpmath")
    from mechviz.bench.problems import mpmath_rhs

    with mpmath.workdps(25):
        for y, p in _cases(sys_id):
            f = mpmath_rhs(sys_id, p)
            got = np.array([float(v) for v in f(0, [mpmath.mpf(float(v)) for v in y])])
            assert _close(got, _ours(sys_id, y, p))
