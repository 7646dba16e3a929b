"""The Taylor coefficients' recurrences generated from :class:`.Equations` (automatic
differentiation of the expression graph, as Jorba and Zou's ``taylor`` program and heyoka do).

The right-hand sides are decomposed into elementary operations, each a series (a row of the
coefficient array) or a constant (a scalar of the parameters, computed once per expansion). A
subexpression met twice is one node (sympy's expressions are compared by structure). With
``u^[k]`` the order-k coefficient of ``u`` (``u^(k)(t) / k!``), the rules are (Jorba & Zou,
*Exp. Math.* 14 (2005) 99-117, section 3; heyoka's ``taylor_decompose`` / ``taylor_diff``):

- sum ``u + v``: ``u^[k] + v^[k]``; constant times series ``c u``: ``c u^[k]``;
- product (Cauchy) ``(uv)^[k] = sum_{j<=k} u^[j] v^[k-j]``, the square over half the terms;
- quotient ``q = u / v``: ``q^[k] = (u^[k] - sum_{1<=j<=k} v^[j] q^[k-j]) / v^[0]``;
- ``s, c = sin u, cos u`` (a pair, whichever of them the equations use):
  ``s^[k] = (1/k) sum_{1<=j<=k} j u^[j] c^[k-j]``, ``c^[k] = -(1/k) sum j u^[j] s^[k-j]``;
- ``e = exp u``: ``e^[k] = (1/k) sum_{1<=j<=k} j u^[j] e^[k-j]``;
- ``w = sqrt u``: ``w^[k] = (u^[k] - sum_{1<=j<k} w^[j] w^[k-j]) / (2 w^[0])``;
- ``w = u^a`` (constant ``a``): ``w^[k] = sum_{0<=j<k} (a (k-j) - j) u^[k-j] w^[j] / (k u^[0])``.

The state's coefficients follow from ``y^[k+1] = f(y)^[k] / (k + 1)``. The generated
``expand(A, p, order)`` has the calling convention of the hand-written expansions
(:func:`mechviz.dynamics.integrators.taylor.hoop_expand`): ``A`` (rows, >= order + 1) with the
state's order-0 coefficients in ``A[:d, 0]``; it fills orders 1 ... ``order`` of the state's
rows and orders 0 ... ``order - 1`` of the auxiliary rows after them (:data:`ROWS` in the
generated module: the rows ``A`` must have).
"""

from __future__ import annotations

import functools

import sympy as sp
from sympy.printing.pycode import pycode

from .build import load
from .equations import Equations
from .rhs import plain


class _Graph:
    """The expression graph of a system's right-hand sides: series nodes (rows) and constants."""

    def __init__(self, ys: list[sp.Symbol], ps: list[sp.Symbol]) -> None:
        self.rows: dict[sp.Expr, int] = {y: i for i, y in enumerate(ys)}
        self.params = set(ps)
        self.consts: dict[sp.Expr, str] = {}
        self.const_lines: list[str] = []
        self.ops: list[tuple] = []  # (kind, out row(s), operands...) in dependency order
        self.sincos: dict[sp.Expr, tuple[int, int]] = {}

    # ---- nodes
    def const(self, e: sp.Expr) -> str:
        """The scalar holding the constant ``e`` (parameters and numbers only)."""
        if e not in self.consts:
            name = f"c{len(self.consts)}"
            self.consts[e] = name
            value = repr(float(e)) if e.is_Number else pycode(e)  # every digit of a number
            self.const_lines.append(f"    {name} = {value}")
        return self.consts[e]

    def _row(self, e: sp.Expr, op: tuple) -> int:
        r = len(self.rows)
        self.rows[e] = r
        self.ops.append((op[0], r, *op[1:]))
        return r

    def is_const(self, e: sp.Expr) -> bool:
        return e.free_symbols <= self.params

    def node(self, e: sp.Expr) -> tuple[str, object]:
        """``("c", name)`` for a constant, ``("s", row)`` for a series."""
        if self.is_const(e):
            return "c", self.const(e)
        return "s", self.series(e)

    def series(self, e: sp.Expr) -> int:
        """The row of the series of ``e`` (time-dependent), building its node if new."""
        if e in self.rows:
            return self.rows[e]
        if e.is_Add:
            return self._add(e)
        if e.is_Mul:
            return self._mul(e)
        if e.is_Pow:
            return self._pow(e)
        if isinstance(e, (sp.sin, sp.cos)):
            s, c = self._sincos(e.args[0])
            return s if isinstance(e, sp.sin) else c
        if isinstance(e, sp.exp):
            return self._row(e, ("exp", self.series(e.args[0])))
        raise NotImplementedError(f"no Taylor rule for {type(e).__name__}: {e}")

    def _add(self, e: sp.Expr) -> int:
        consts, terms = [], []
        for arg in e.args:
            if self.is_const(arg):
                consts.append(arg)
                continue
            coeff, rest = arg.as_coeff_Mul()
            if coeff == -1:  # a difference, not a product by -1
                terms.append((-1, self.series(rest)))
            else:
                terms.append((1, self.series(arg)))
        c = self.const(sp.Add(*consts)) if consts else None
        return self._row(e, ("add", tuple(terms), c))

    def _mul(self, e: sp.Expr) -> int:
        consts, num, den = [], [], []
        for arg in e.args:
            if self.is_const(arg):
                consts.append(arg)
            elif arg.is_Pow and arg.exp.is_Integer and arg.exp < 0:
                den.append(arg.base ** (-arg.exp))
            else:
                num.append(arg)
        row = None
        if len(num) == 1 and not consts and not den:
            return self.series(num[0])
        for part in num:  # a chain of Cauchy products, each partial product a node
            r = self.series(part)
            if row is None:
                row, acc = r, part
            else:
                acc = acc * part
                row = self.rows.get(acc) or self._row(acc, ("mul", row, r))
        if den:
            d = sp.Mul(*den)
            top = ("c", self.const(sp.Mul(*consts))) if row is None else ("s", row)
            quotient = (acc if row is not None else sp.Mul(*consts)) / d
            row = self.rows.get(quotient) or self._row(quotient, ("div", top, self.series(d)))
            if row is not None and top[0] == "c":
                return self._alias(e, row)
        if consts:
            return self._row(e, ("scale", self.const(sp.Mul(*consts)), row))
        return self._alias(e, row)

    def _alias(self, e: sp.Expr, row: int) -> int:
        self.rows[e] = row
        return row

    def _pow(self, e: sp.Expr) -> int:
        base, n = e.base, e.exp
        if not self.is_const(n):
            raise NotImplementedError(f"no Taylor rule for a variable exponent: {e}")
        if n == 2:
            return self._row(e, ("square", self.series(base)))
        if n.is_Integer and n > 2:  # by squaring and multiplying
            half = self.series(base ** (n // 2))
            sq = self.rows.get(base ** (2 * (n // 2))) or self._row(
                base ** (2 * (n // 2)), ("square", half)
            )
            return sq if n % 2 == 0 else self._row(e, ("mul", sq, self.series(base)))
        if n.is_Integer and n < 0:
            return self._row(e, ("div", ("c", self.const(sp.Integer(1))), self.series(base**-n)))
        if n == sp.Rational(1, 2):
            return self._row(e, ("sqrt", self.series(base)))
        return self._row(e, ("pow", self.series(base), self.const(n)))

    def _sincos(self, u: sp.Expr) -> tuple[int, int]:
        if u not in self.sincos:
            a = self.series(u)
            s = len(self.rows)
            self.rows[sp.sin(u)] = s
            self.rows[sp.cos(u)] = s + 1
            self.ops.append(("sincos", (s, s + 1), a))
            self.sincos[u] = (s, s + 1)
        return self.sincos[u]


def _emit(op: tuple) -> list[str]:
    """The statements computing order ``k`` of one node (inside the loop over ``k``)."""
    kind, r = op[0], op[1]
    if kind == "add":
        terms, c = op[2], op[3]
        text = " ".join(f"{'-' if s < 0 else '+'} A[{a}, k]" for s, a in terms).lstrip("+ ")
        out = [f"A[{r}, k] = {text}"]
        if c is not None:
            out += ["if k == 0:", f"    A[{r}, 0] += {c}"]
        return out
    if kind == "scale":
        return [f"A[{r}, k] = {op[2]} * A[{op[3]}, k]"]
    if kind == "mul":
        a, b = op[2], op[3]
        return [
            "s = 0.0",
            "for j in range(k + 1):",
            f"    s += A[{a}, j] * A[{b}, k - j]",
            f"A[{r}, k] = s",
        ]
    if kind == "square":
        a = op[2]
        return [
            "s = 0.0",
            "for j in range((k + 1) // 2):",
            f"    s += A[{a}, j] * A[{a}, k - j]",
            "s *= 2.0",
            "if k % 2 == 0:",
            f"    s += A[{a}, k // 2] * A[{a}, k // 2]",
            f"A[{r}, k] = s",
        ]
    if kind == "div":
        (tk, top), b = op[2], op[3]
        first = f"A[{top}, k]" if tk == "s" else f"{top} if k == 0 else 0.0"
        return [
            f"s = {first}",
            "for j in range(1, k + 1):",
            f"    s -= A[{b}, j] * A[{r}, k - j]",
            f"A[{r}, k] = s / A[{b}, 0]",
        ]
    if kind == "sincos":
        (s_, c_), a = r, op[2]
        return [
            "if k == 0:",
            f"    A[{s_}, 0] = math.sin(A[{a}, 0])",
            f"    A[{c_}, 0] = math.cos(A[{a}, 0])",
            "else:",
            "    s = 0.0",
            "    c = 0.0",
            "    for j in range(1, k + 1):",
            f"        t = j * A[{a}, j]",
            f"        s += t * A[{c_}, k - j]",
            f"        c += t * A[{s_}, k - j]",
            f"    A[{s_}, k] = s / k",
            f"    A[{c_}, k] = -c / k",
        ]
    if kind == "exp":
        a = op[2]
        return [
            "if k == 0:",
            f"    A[{r}, 0] = math.exp(A[{a}, 0])",
            "else:",
            "    s = 0.0",
            "    for j in range(1, k + 1):",
            f"        s += j * A[{a}, j] * A[{r}, k - j]",
            f"    A[{r}, k] = s / k",
        ]
    if kind == "sqrt":
        a = op[2]
        return [
            "if k == 0:",
            f"    A[{r}, 0] = math.sqrt(A[{a}, 0])",
            "else:",
            f"    s = A[{a}, k]",
            "    for j in range(1, k):",
            f"        s -= A[{r}, j] * A[{r}, k - j]",
            f"    A[{r}, k] = s / (2.0 * A[{r}, 0])",
        ]
    if kind == "pow":
        a, n = op[2], op[3]
        return [
            "if k == 0:",
            f"    A[{r}, 0] = A[{a}, 0] ** {n}",
            "else:",
            "    s = 0.0",
            "    for j in range(k):",
            f"        s += ({n} * (k - j) - j) * A[{a}, k - j] * A[{r}, j]",
            f"    A[{r}, k] = s / (k * A[{a}, 0])",
        ]
    raise AssertionError(kind)


def series_source(eq: Equations) -> str:
    """The generated module's body: ``ROWS`` and ``expand(A, p, order)``."""
    ys, ps, exprs = plain(eq)
    g = _Graph(ys, ps)
    outs = [g.node(e) for e in exprs]  # the right-hand sides' nodes, in the state's order
    body = [line for op in g.ops for line in _emit(op)]
    for i, (kind, x) in enumerate(outs):
        if kind == "s":
            body.append(f"A[{i}, k + 1] = A[{x}, k] * inv")
        else:
            body.append(f"A[{i}, k + 1] = ({x} if k == 0 else 0.0) * inv")
    lines = [
        f"ROWS = {len(set(g.rows.values()))}",
        "",
        "",
        '@njit(cache=True, fastmath={"contract", "reassoc"})',
        "def expand(A, p, order):",
        f'    """Orders 1 ... order of the {eq.dim} state rows of A (module docstring)."""',
    ]
    lines += [f"    {s} = p[{j}]" for j, s in enumerate(ps)]
    lines += g.const_lines
    lines += ["    for k in range(order):", "        inv = 1.0 / (k + 1)"]
    lines += [f"        {line}" for line in body]
    return "\n".join(lines) + "\n"


@functools.cache
def generated_expand(eq: Equations):
    """``(expand, rows)``: the compiled expansion of ``eq`` and the rows its array needs."""
    module = load(eq, "series", series_source)
    return module.expand, module.ROWS
