"""The right-hand side ``rhs(y, p, out)`` generated from :class:`.Equations`.

The expressions are reduced by common-subexpression elimination (``sympy.cse``: the hoop's
``sin(th1 - th2)``, ``cos(th1 - th2)`` and determinant are computed once) and printed as a
numba function in scalar locals, with the calling convention of the product's right-hand sides
(:data:`mechviz.dynamics.integrators.kernels.RHS`, which are these, generated for the product's
systems): ``y`` (d,) the state, ``p`` the parameters' array, ``out`` (d,) written in place.
"""

from __future__ import annotations

import functools

import sympy as sp
from sympy.printing.pycode import pycode

from .build import load
from .equations import Equations


def plain(eq: Equations) -> tuple[list[sp.Symbol], list[sp.Symbol], list[sp.Expr]]:
    """``eq``'s right-hand sides with the state renamed ``y0, y1, ...`` and the parameters
    ``p0, p1, ...`` (names the generated code can use whatever the equations call them)."""
    ys = [sp.Symbol(f"y{i}", real=True) for i in range(eq.dim)]
    ps = [sp.Symbol(f"p{j}", real=True) for j in range(len(eq.params))]
    rename = dict(zip(eq.state, ys, strict=True)) | dict(zip(eq.params, ps, strict=True))
    return ys, ps, [e.xreplace(rename) for e in eq.rhs]


def rhs_source(eq: Equations) -> str:
    """The generated module's body: ``rhs(y, p, out)``."""
    ys, ps, exprs = plain(eq)
    temps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("t"))
    used = set().union(*(e.free_symbols for e in reduced), *(e.free_symbols for _, e in temps))
    lines = ["@njit(cache=True)", "def rhs(y, p, out):", f'    """d = {eq.dim}."""']
    lines += [f"    {s} = y[{i}]" for i, s in enumerate(ys) if s in used]
    lines += [f"    {s} = p[{j}]" for j, s in enumerate(ps) if s in used]
    lines += [f"    {s} = {pycode(e)}" for s, e in temps]
    lines += [
        f"    out[{i}] = {repr(float(e)) if e.is_Number else pycode(e)}"
        for i, e in enumerate(reduced)
    ]
    return "\n".join(lines) + "\n"


@functools.cache
def generated_rhs(eq: Equations):
    """The compiled ``rhs(y, p, out)`` of ``eq`` (generated, written and compiled once)."""
    return load(eq, "rhs", rhs_source).rhs
