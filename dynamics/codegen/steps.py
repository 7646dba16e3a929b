"""Fixed-step methods' steps generated from :class:`.Equations`: classical RK4 in scalar locals.

The product's RK4 steps (:data:`mechviz.dynamics.integrators.kernels.RK4`) are these, generated
for its systems. They are written out in scalar locals, as the hand-written steps they replaced
were, because stage arrays cost 3-4x as much: the right-hand side as a function of scalars
returning a tuple (compiled into the step), called four times, with every constant of the
parameters (the hoop's ``g/a``, the free body's ``(I2 - I3)/I1``) computed once per step rather
than once per evaluation. Calling convention
of a direct step (:mod:`mechviz.dynamics.integrators.kernels`): ``rk4_step(y, p, h)`` advances
``y`` in place and returns the evaluations used (4).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import sympy as sp
from sympy.printing.pycode import pycode

from .build import load
from .equations import Equations
from .rhs import plain


def hoist_constants(
    exprs: list[sp.Expr], params: set[sp.Symbol]
) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    """Every largest subexpression of the parameters alone (and of numbers) replaced by a symbol
    ``k0, k1, ...``: ``(definitions, expressions)``. In a sum or product the constant terms or
    factors are gathered into one (``-m (M + m) g/a`` is one constant of a product)."""
    defs: dict[sp.Expr, sp.Symbol] = {}

    def name(e: sp.Expr) -> sp.Expr:
        if e.is_Number:
            return e
        if e not in defs:
            defs[e] = sp.Symbol(f"k{len(defs)}", real=True)
        return defs[e]

    def walk(e: sp.Expr) -> sp.Expr:
        if e.free_symbols <= params:
            return name(e)
        if e.is_Atom:
            return e
        if e.is_Add or e.is_Mul:
            const = [a for a in e.args if a.free_symbols <= params]
            rest = [walk(a) for a in e.args if not a.free_symbols <= params]
            if const:
                rest.insert(0, name(e.func(*const)))
            return e.func(*rest, evaluate=False)
        return e.func(*(walk(a) for a in e.args))

    out = [walk(e) for e in exprs]
    return [(s, e) for e, s in defs.items()], out


def _number(e: sp.Expr) -> str:
    return repr(float(e)) if e.is_Number else pycode(e)


@dataclass(frozen=True)
class Hoisted:
    """``eq``'s right-hand sides with every constant of the parameters named: the state ``ys``
    (``y0, y1, ...``), the parameters ``ps`` (``p0, p1, ...``, the kernel-parameter order), the
    constants ``consts`` (``k_i = expression of ps``, in the order they are used), and the rates
    as common subexpressions ``temps`` (``t_j = expression``, each using the ``ys``, ``ks`` and
    earlier ``t``) and ``rates`` (one expression per state component). The RK4 steps here and
    the benchmark's peer forms (heyoka's expressions with the constants as its runtime
    parameters, the C steps) are all printed from this one form, so each computes the
    constants once, outside its inner loop, from the same expressions."""

    ys: list[sp.Symbol]
    ps: list[sp.Symbol]
    consts: list[tuple[sp.Symbol, sp.Expr]]
    temps: list[tuple[sp.Symbol, sp.Expr]]
    rates: list[sp.Expr]

    @property
    def ks(self) -> list[sp.Symbol]:
        """The constants' symbols ``k0, k1, ...``."""
        return [s for s, _ in self.consts]


def hoisted(eq: Equations) -> Hoisted:
    """:class:`Hoisted` of ``eq``."""
    ys, ps, exprs = plain(eq)
    consts, exprs = hoist_constants(exprs, set(ps))
    temps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("t"))
    return Hoisted(ys, ps, consts, temps, reduced)


def rk4_source(eq: Equations) -> str:
    """The generated module's body: ``rates(y0, ..., k0, ...)`` and ``rk4_step(y, p, h)``."""
    form = hoisted(eq)
    ys, ps, consts, temps, reduced = form.ys, form.ps, form.consts, form.temps, form.rates
    ks = form.ks
    d = eq.dim
    args = ", ".join(map(str, ys + ks))
    lines = ["@njit(cache=True)", f"def rates({args}):", '    """y\' as a tuple."""']
    lines += [f"    {s} = {pycode(e)}" for s, e in temps]
    lines += [f"    return ({', '.join(_number(e) for e in reduced)},)", "", ""]
    lines += ["@njit(cache=True)", "def rk4_step(y, p, h):", '    """Classical RK4."""']
    lines += [f"    {s} = p[{j}]" for j, s in enumerate(ps)]
    lines += [f"    {s} = {pycode(e)}" for s, e in consts]
    lines += [f"    a{i} = y[{i}]" for i in range(d)]
    lines.append("    hh = 0.5 * h")
    k_args = ", ".join(map(str, ks))
    base = [f"a{i}" for i in range(d)]
    for stage, (prev, step) in enumerate([(None, ""), ("b", "hh"), ("c", "hh"), ("e", "h")]):
        out = "bcef"[stage]
        ins = base if prev is None else [f"a{i} + {step} * {prev}{i}" for i in range(d)]
        call = ", ".join(ins + ([k_args] if k_args else []))
        lines.append(f"    {', '.join(f'{out}{i}' for i in range(d))}, = rates({call})")
    lines.append("    c = h / 6.0")
    lines += [f"    y[{i}] = a{i} + c * (b{i} + 2.0 * (c{i} + e{i}) + f{i})" for i in range(d)]
    lines.append("    return 4")
    return "\n".join(lines) + "\n"


@functools.cache
def generated_rk4(eq: Equations):
    """The compiled ``rk4_step(y, p, h)`` of ``eq``."""
    return load(eq, "rk4", rk4_source).rk4_step
