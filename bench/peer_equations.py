"""Our right-hand sides in heyoka's expression system, generated from the equations written once.

The expressions are those of :data:`mechviz.dynamics.codegen.equations.EQUATIONS`, in the form
the product's RK4 steps are printed from (:func:`mechviz.dynamics.codegen.steps.hoisted`): every
constant of the parameters (the hoop's ``2M + m``, ``-(g/a)``, ``-(M + m) g/a``; the free body's
``(I2 - I3)/I1``) is one of heyoka's runtime parameters ``hy.par[i]``, so one compiled integrator
serves every case of a system and heyoka's Taylor decomposition has no expression of parameters
to expand at every step. The same expressions can instead carry one parameter set's constants
as numbers (``heyoka_equations(sys_id, constants)``): an integrator compiled per parameter set,
its numbers built into the code. :func:`heyoka_pars` forms those constants from our kernel
parameters in double precision, with the very expressions our RK4 steps form them with, so that
a run in extended precision (the references) solves the equations our methods solve.

The translation walks sympy's tree: sums (terms with a minus sign subtracted), products (a
factor with a negative integer power becomes a division, which heyoka's decomposition takes as
one quotient rather than a power), integer powers (a square as a product), ``sin`` and ``cos``;
anything else raises (a system with another function would extend :func:`to_heyoka`). sympy's
common subexpressions enter as shared heyoka expressions.
"""

from __future__ import annotations

import functools
import math

import numpy as np


@functools.cache
def _form(sys_id: int):
    from mechviz.dynamics.codegen.equations import EQUATIONS
    from mechviz.dynamics.codegen.steps import hoisted

    return hoisted(EQUATIONS[sys_id]())


@functools.cache
def _constants(sys_id: int):
    """``f(p) -> [k0, k1, ...]``: the constants as our RK4 step computes them (the same printed
    expressions, in Python floats: the same IEEE double operations as the compiled step)."""
    from sympy.printing.pycode import pycode

    form = _form(sys_id)
    lines = ["def constants(p):"]
    lines += [f"    {s} = p[{j}]" for j, s in enumerate(form.ps)]
    lines += [f"    {s} = {pycode(e)}" for s, e in form.consts]
    lines.append(f"    return [{', '.join(map(str, form.ks))}]")
    scope: dict = {"math": math}
    exec("\n".join(lines), scope)  # text printed from our own equations
    return scope["constants"]


def heyoka_pars(sys_id: int, params: np.ndarray) -> np.ndarray:
    """The runtime parameters of :func:`heyoka_equations` from our kernel parameters
    ``params`` (the system's ``kernel_params()``): its constants, in double precision."""
    p = [float(v) for v in np.asarray(params, dtype=float)]
    return np.array(_constants(sys_id)(p), dtype=float)


def to_heyoka(e, names: dict):
    """The sympy expression ``e`` as a heyoka expression, ``names`` mapping its symbols to
    heyoka expressions (variables, parameters, shared subexpressions)."""
    import heyoka as hy
    import sympy as sp

    if e.is_Symbol:
        return names[e]
    if e.is_Number:
        return hy.expression(float(e))
    if e.is_Add:  # a term with a minus sign is subtracted, not negated and added
        plus = [a for a in e.args if not a.could_extract_minus_sign()]
        minus = [to_heyoka(-a, names) for a in e.args if a.could_extract_minus_sign()]
        out = (
            functools.reduce(lambda a, b: a + b, [to_heyoka(a, names) for a in plus])
            if plus
            else -minus.pop(0)
        )
        return functools.reduce(lambda a, b: a - b, minus, out)
    if e.is_Mul:
        num, den = [], []
        for a in e.args:
            if a.is_Pow and a.exp.is_Integer and a.exp < 0:
                den.append(to_heyoka(a.base**-a.exp, names))
            else:
                num.append(to_heyoka(a, names))
        top = functools.reduce(lambda a, b: a * b, num) if num else hy.expression(1.0)
        return top / functools.reduce(lambda a, b: a * b, den) if den else top
    if e.is_Pow and e.exp.is_Integer:
        if e.exp < 0:
            return 1.0 / to_heyoka(e.base**-e.exp, names)
        if e.exp == 2:  # one product: cheaper in heyoka's Taylor recurrences than a power
            base = to_heyoka(e.base, names)
            return base * base
        return to_heyoka(e.base, names) ** int(e.exp)
    if isinstance(e, sp.sin):
        return hy.sin(to_heyoka(e.args[0], names))
    if isinstance(e, sp.cos):
        return hy.cos(to_heyoka(e.args[0], names))
    raise NotImplementedError(f"no heyoka form of {type(e).__name__}: {e}")


def heyoka_equations(sys_id: int, constants: np.ndarray | None = None) -> list:
    """Our right-hand sides in heyoka's expressions, ``[(variable, rate), ...]`` in the state's
    order: the constants of :func:`heyoka_pars` as runtime parameters ``hy.par[i]``, or, given
    ``constants`` (:func:`heyoka_pars`' values for one parameter set), those numbers built into
    the expressions (an integrator per parameter set, compiled with its numbers)."""
    import heyoka as hy
    import sympy as sp

    form = _form(sys_id)
    ys = hy.make_vars(*map(str, form.ys))
    ys = ys if isinstance(ys, list) else [ys]
    names = dict(zip(form.ys, ys, strict=True))
    if constants is None:
        names |= {k: hy.par[i] for i, k in enumerate(form.ks)}
    else:
        values = [float(c) for c in np.asarray(constants, dtype=float)]
        if len(values) != len(form.ks):
            raise ValueError(f"{len(form.ks)} constants expected, got {len(values)}")
        names |= {k: hy.expression(c) for k, c in zip(form.ks, values, strict=True)}
    # the rates whole, common factors out of sums (the free body's 1/2 once per rate), then
    # their common subexpressions again (the hoop's reciprocal of the determinant once): of the
    # arrangements measured, the one heyoka solved fastest, as fast as the hand-written one
    rates = list(form.rates)
    for s, e in reversed(form.temps):
        rates = [r.xreplace({s: e}) for r in rates]
    temps, rates = sp.cse([sp.factor_terms(r) for r in rates], symbols=sp.numbered_symbols("t"))
    for s, e in temps:
        names[s] = to_heyoka(e, names)
    return [(y, to_heyoka(r, names)) for y, r in zip(ys, rates, strict=True)]
