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
(:func:`mechviz.dynamics.integrators.taylor.charge_expand`): ``A`` (rows, >= order + 1) with the
state's order-0 coefficients in ``A[:d, 0]``; it fills orders 1 ... ``order`` of the state's
rows and orders 0 ... ``order - 1`` of the auxiliary rows after them (:data:`ROWS` in the
generated module: the rows ``A`` must have).
"""

from __future__ import annotations

import functools
import re

import sympy as sp
from sympy.printing.pycode import pycode

from .build import load
from .equations import Equations
from .rhs import plain

#: An expression as ``(constants, [(c, row)], [(c, row, row)])``: constants, constants times
#: series, constants times products of two series (:meth:`_Graph.terms`).
Terms = tuple[list[sp.Expr], list[tuple[sp.Expr, int]], list[tuple[sp.Expr, int, int]]]


class _Graph:
    """The expression graph of a system's right-hand sides: series nodes (rows) and constants.

    Sums of constants, series times constants and products of two series times constants are
    one node, a linear combination (``"lin"``): ``c + sum c_i x_i + sum c_j (u_j v_j)``, its
    Cauchy products summed in one loop (the free body's quaternion rates are one node each, as
    the hand-written expansion sums them)."""

    def __init__(self, ys: list[sp.Symbol], ps: list[sp.Symbol]) -> None:
        self.rows: dict[sp.Expr, int] = {y: i for i, y in enumerate(ys)}
        self.params = set(ps)
        self.consts: dict[sp.Expr, str] = {}
        self.const_lines: list[str] = []
        self.ops: list[tuple] = []  # (kind, out row(s), operands...) in dependency order
        self.sincos: dict[sp.Expr, tuple[int, int]] = {}
        self.depth: dict[int, int] = dict.fromkeys(range(len(ys)), 0)
        self.needs: dict[int, tuple[int, ...]] = {}  # a node's operands (rows)

    # ---- nodes
    def const(self, e: sp.Expr) -> str:
        """The scalar holding the constant ``e`` (parameters and numbers only)."""
        if e not in self.consts:
            name = f"c{len(self.consts)}"
            self.consts[e] = name
            value = repr(float(e)) if e.is_Number else pycode(e)  # every digit of a number
            self.const_lines.append(f"    {name} = {value}")
        return self.consts[e]

    def _row(self, e: sp.Expr, op: tuple, operands: tuple[int, ...]) -> int:
        r = len(set(self.rows.values()))
        self.rows[e] = r
        self.ops.append((op[0], r, *op[1:]))
        self.depth[r] = 1 + max((self.depth[a] for a in operands), default=0)
        self.needs[r] = operands
        return r

    def is_const(self, e: sp.Expr) -> bool:
        return e.free_symbols <= self.params

    def output(self, e: sp.Expr) -> str:
        """The expression of ``f(y)^[k] / (k + 1)`` (``inv`` is ``1/(k + 1)``) for a right-hand
        side ``e``: a row, or (a linear
        combination without products, the charge's ``Omega vy``) the combination itself, which
        then needs no row of its own."""
        if e in self.rows:
            return f"A[{self.rows[e]}, k] * inv"
        if self.is_const(e):
            return f"({self.const(e)} * inv if k == 0 else 0.0)"
        consts, lin, prods = self.terms(e)
        if prods:
            return f"A[{self.series(e)}, k] * inv"
        # a coefficient times 1/(k + 1) first: one multiplication on the chain from order k
        parts = [_term(*self.coefficient(c), f"A[{a}, k]", scale="inv") for c, a in lin]
        if consts:
            parts.append(f"+ ({self.const(sp.Add(*consts))} * inv if k == 0 else 0.0)")
        return _sum(parts)

    def coefficient(self, c: sp.Expr) -> tuple[int, str | None]:
        """``(sign, name)`` of a constant factor; ``name`` None for a factor of 1."""
        sign = -1 if c.could_extract_minus_sign() else 1
        c = sign * c
        return sign, None if c == 1 else self.const(c)

    def series(self, e: sp.Expr) -> int:
        """The row of the series of ``e`` (time-dependent), building its node if new."""
        if e in self.rows:
            return self.rows[e]
        factors = [a for a in e.args if not self.is_const(a)] if e.is_Mul else []
        if e.is_Add or (
            e.is_Mul
            and not any(_is_denominator(a) for a in e.args)
            and (len(factors) <= 2 or len(factors) < len(e.args))
        ):
            consts, lin, prods = self.terms(e)
            if not consts and not prods and len(lin) == 1 and lin[0][0] == 1:
                return self._alias(e, lin[0][1])
            return self._lin(e, consts, lin, prods)
        if e.is_Mul:
            return self._mul(e)
        if e.is_Pow:
            return self._pow(e)
        if isinstance(e, (sp.sin, sp.cos)):
            s, c = self._sincos(e.args[0])
            return s if isinstance(e, sp.sin) else c
        if isinstance(e, sp.exp):
            a = self.series(e.args[0])
            return self._row(e, ("exp", a), (a,))
        raise NotImplementedError(f"no Taylor rule for {type(e).__name__}: {e}")

    def terms(self, e: sp.Expr, coeff: sp.Expr = sp.S.One) -> Terms:
        """``coeff e`` as constants, constants times series and constants times products of two
        series: ``(consts, [(c, row)], [(c, row, row)])``."""
        if self.is_const(e):
            return [coeff * e], [], []
        if e.is_Add:
            out: Terms = ([], [], [])
            for a in e.args:
                for whole, part in zip(out, self.terms(a, coeff), strict=True):
                    whole.extend(part)
            return out
        if e.is_Mul and not any(_is_denominator(a) for a in e.args):
            c = sp.Mul(*[a for a in e.args if self.is_const(a)])
            rest = [a for a in e.args if not self.is_const(a)]
            if len(rest) == 1:
                return self.terms(rest[0], coeff * c)
            if len(rest) == 2:
                return [], [], [(coeff * c, self.series(rest[0]), self.series(rest[1]))]
            return [], [(coeff * c, self.series(sp.Mul(*rest)))], []
        if e.is_Mul:  # a quotient: its own node, times its constant factor
            c = sp.Mul(*[a for a in e.args if self.is_const(a)])
            rest = sp.Mul(*[a for a in e.args if not self.is_const(a)])
            return [], [(coeff * c, self.series(rest))], []
        return [], [(coeff, self.series(e))], []

    def _lin(self, e: sp.Expr, consts, lin, prods) -> int:
        c = self.const(sp.Add(*consts)) if consts else None
        lin = tuple((*self.coefficient(k), a) for k, a in lin)
        prods = tuple((*self.coefficient(k), a, b) for k, a, b in prods)
        operands = tuple(x[-1] for x in lin) + tuple(y for x in prods for y in x[-2:])
        return self._row(e, ("lin", c, lin, prods), operands)

    def _mul(self, e: sp.Expr) -> int:
        """A product of three or more series, or a quotient (times constants)."""
        consts = [a for a in e.args if self.is_const(a)]
        if consts:
            rest = sp.Mul(*[a for a in e.args if not self.is_const(a)])
            return self._lin(e, [], [(sp.Mul(*consts), self.series(rest))], [])
        num = [a for a in e.args if not _is_denominator(a)]
        den = [a.base ** (-a.exp) for a in e.args if _is_denominator(a)]
        if not den:  # a chain of Cauchy products, each partial product a node
            head = sp.Mul(*num[:-1])
            a, b = self.series(head), self.series(num[-1])
            return self._row(e, ("lin", None, (), ((1, None, a, b),)), (a, b))
        d = self.series(sp.Mul(*den))
        if num:
            a = self.series(sp.Mul(*num))
            return self._row(e, ("div", ("s", a), d), (a, d))
        return self._row(e, ("div", ("c", self.const(sp.Integer(1))), d), (d,))

    def _alias(self, e: sp.Expr, row: int) -> int:
        self.rows[e] = row
        return row

    def _pow(self, e: sp.Expr) -> int:
        base, n = e.base, e.exp
        if not self.is_const(n):
            raise NotImplementedError(f"no Taylor rule for a variable exponent: {e}")
        if n == 2:
            a = self.series(base)
            return self._row(e, ("square", a), (a,))
        if n.is_Integer and n > 2:  # by squaring and multiplying
            half = base ** (n // 2)
            sq = self.series(half**2)
            if n % 2 == 0:
                return sq
            a = self.series(base)
            return self._row(e, ("lin", None, (), ((1, None, sq, a),)), (sq, a))
        if n.is_Integer and n < 0:
            d = self.series(base**-n)
            return self._row(e, ("div", ("c", self.const(sp.Integer(1))), d), (d,))
        a = self.series(base)
        if n == sp.Rational(1, 2):
            return self._row(e, ("sqrt", a), (a,))
        return self._row(e, ("pow", a, self.const(n)), (a,))

    def _sincos(self, u: sp.Expr) -> tuple[int, int]:
        if u not in self.sincos:
            a = self.series(u)
            s = len(set(self.rows.values()))
            self.rows[sp.sin(u)] = s
            self.rows[sp.cos(u)] = s + 1
            self.ops.append(("sincos", (s, s + 1), a))
            self.depth[s] = self.depth[s + 1] = self.depth[a] + 1
            self.needs[s] = (a,)
            self.sincos[u] = (s, s + 1)
        return self.sincos[u]


def _is_denominator(e: sp.Expr) -> bool:
    return e.is_Pow and e.exp.is_Integer and e.exp < 0


def _sum(terms: list[str]) -> str:
    """Signed terms (``+ x``, ``- y``) as one expression, its leading ``+`` dropped."""
    return " ".join(terms).lstrip("+ ")


def _product(sign: int, a: int, b: int, j: str = "j", i: str = "i") -> str:
    """``+ A[a, j] * A[b, i]`` (``-`` for a negative sign): one term of a Cauchy product."""
    return f"{'-' if sign < 0 else '+'} A[{a}, {j}] * A[{b}, {i}]"


def _accumulators(accs: dict, prefix: str, start: list[str], loop: list[str]) -> list[str]:
    """An accumulator ``{prefix}{n}`` per factor of ``accs`` (its name or ``None``: its terms),
    begun in ``start``, summed in ``loop``; returns the terms ``+ factor * accumulator``."""
    parts = []
    for n, (name, terms) in enumerate(accs.items()):
        start.append(f"{prefix}{n} = 0.0")
        loop.append(f"    {prefix}{n} += {_sum(terms)}")
        parts.append(_term(1, name, f"{prefix}{n}"))
    return parts


def _term(sign: int, name: str | None, value: str, scale: str | None = None) -> str:
    """``+ name * value`` (``- ...`` for a negative sign), the factor ``(name * scale)``."""
    factor = name if scale is None else (scale if name is None else f"({name} * {scale})")
    if factor is None:
        return f"{'-' if sign < 0 else '+'} {value}"
    return f"{'-' if sign < 0 else '+'} {factor} * {value}"


def _lin_group(ops: list[tuple]) -> list[str]:
    """Order ``k`` of independent linear combinations, their Cauchy products in one loop (one
    accumulator per node and coefficient: a sum is a chain of dependent additions, several of
    them interleaved keep the floating-point units busy)."""
    out, loop, finish = [], [], []
    for _, r, c, lin, prods in ops:
        accs: dict[str | None, list[str]] = {}
        for sign, name, a, b in prods:
            accs.setdefault(name, []).append(_product(sign, a, b))
        parts = _accumulators(accs, f"s{r}_", out, loop)
        parts += [_term(sign, name, f"A[{a}, k]") for sign, name, a in lin]
        finish.append(f"A[{r}, k] = {_sum(parts) or '0.0'}")
        if c is not None:
            finish += ["if k == 0:", f"    A[{r}, 0] += {c}"]
    if loop:
        out += ["for j in range(k + 1):", "    i = k - j", *loop]
    return out + finish


def _square_group(ops: list[tuple]) -> list[str]:
    """Order ``k`` of independent squares in one loop over half the terms (by symmetry)."""
    out = [f"q{r} = 0.0" for _, r, _ in ops]
    out += ["for j in range((k + 1) // 2):", "    i = k - j"]
    out += [f"    q{r} += A[{a}, j] * A[{a}, i]" for _, r, a in ops]
    out += ["if k % 2 == 0:", "    h = k // 2"]
    out += [f"    A[{r}, k] = 2.0 * q{r} + A[{a}, h] * A[{a}, h]" for _, r, a in ops]
    out += ["else:"] + [f"    A[{r}, k] = 2.0 * q{r}" for _, r, _ in ops]
    return out


def _sincos_group(ops: list[tuple], slopes: dict[int, str], angles: dict[int, tuple]) -> list[str]:
    """Order ``k`` of independent sine/cosine pairs in one loop. ``slopes[a]``: ``j u^[j]`` of
    an argument ``u`` (row ``a``) as its derivative's order ``j - 1`` where that is known (the
    hoop's ``th1' = w1``: no multiplication by ``j``, and no rounding of it); ``angles[a]``:
    ``(sign, pair, sign, pair)`` for an argument ``+-x +- y`` whose two pairs are computed first,
    its order 0 then by the addition formulas (no library call)."""
    first = [op for op in ops if op[2] not in angles] + [op for op in ops if op[2] in angles]
    out = ["if k == 0:"]
    for _, (s_, c_), a in first:
        if a in angles:
            # sin(sx x + sy y) = sx sin x cos y + sy cos x sin y, cos(...) = cos x cos y -
            # sx sy sin x sin y, with the signs sx, sy +-1
            sx, (sa, ca), sy, (sb, cb) = angles[a]
            sin_xy = _term(sx, None, f"A[{sa}, 0] * A[{cb}, 0]")
            sin_xy += " " + _term(sy, None, f"A[{ca}, 0] * A[{sb}, 0]")
            cos_xy = f"A[{ca}, 0] * A[{cb}, 0] " + _term(-sx * sy, None, f"A[{sa}, 0] * A[{sb}, 0]")
            out.append(f"    A[{s_}, 0] = {_sum([sin_xy])}")
            out.append(f"    A[{c_}, 0] = {cos_xy}")
        else:
            out.append(f"    A[{s_}, 0] = math.sin(A[{a}, 0])")
            out.append(f"    A[{c_}, 0] = math.cos(A[{a}, 0])")
    out.append("else:")
    for _, (s_, _), _ in ops:
        out.append(f"    s{s_} = c{s_} = 0.0")
    out += ["    for j in range(1, k + 1):", "        i = k - j"]
    for _, (s_, c_), a in ops:
        t = slopes.get(a, f"j * A[{a}, j]")
        out += [
            f"        t = {t}",
            f"        s{s_} += t * A[{c_}, i]",
            f"        c{s_} += t * A[{s_}, i]",
        ]
    out.append("    inv_k = 1.0 / k")
    for _, (s_, c_), _ in ops:
        out += [f"    A[{s_}, k] = s{s_} * inv_k", f"    A[{c_}, k] = -c{s_} * inv_k"]
    return out


def _slopes(g: _Graph, rates: dict[int, int]) -> dict[int, str]:
    """``j u^[j] = u'^[j-1]`` of the rows whose derivative is a known row: a state component
    whose rate is a row (``rates``), or a sum of such components with coefficients +-1."""
    out = {r: f"A[{q}, j - 1]" for r, q in rates.items()}
    for op in g.ops:
        if op[0] == "lin" and not op[4] and op[3]:
            _, r, _, lin, _ = op
            if all(name is None and a in rates for _, name, a in lin):
                parts = [_term(sign, None, f"A[{rates[a]}, j - 1]") for sign, _, a in lin]
                out[r] = _sum(parts)
    return out


def _angles(g: _Graph) -> dict[int, tuple]:
    """The sine/cosine arguments ``+-x +- y`` whose ``x`` and ``y`` have pairs of their own
    (the hoop's ``th1 - th2``): ``{row: (sign, pair of x, sign, pair of y)}``."""
    pairs = {op[2]: op[1] for op in g.ops if op[0] == "sincos"}
    out = {}
    for op in g.ops:
        if op[0] == "lin" and op[1] in pairs and op[2] is None and not op[4] and len(op[3]) == 2:
            (sx, nx, x), (sy, ny, y) = op[3]
            if nx is None and ny is None and x in pairs and y in pairs:
                out[op[1]] = (sx, pairs[x], sy, pairs[y])
    return out


def _read(g: _Graph, skip: set[int], text: list[str]) -> list[tuple]:
    """The nodes some statement reads (a sine/cosine pair whose order 0 and slopes come from
    elsewhere, ``skip``, does not read its argument: the hoop's ``th1 - th2`` is then no row),
    with ``text`` the statements outside the nodes (the solve, the outputs)."""
    ops = list(g.ops)
    outside = {int(r) for line in text for r in re.findall(r"A\[(\d+), ", line)}
    while True:
        reads = set(outside)
        for op in ops:
            if not (op[0] == "sincos" and op[2] in skip):
                reads.update(g.needs[_out(op)])
        unread = [op for op in ops if op[0] == "lin" and op[1] not in reads]
        if not unread:
            return ops
        ops = [op for op in ops if op not in unread]


def _schedule(g: _Graph, ops: list[tuple], computed: set[int]) -> list[list[tuple]]:
    """The nodes in groups of one kind whose members are independent, each group computable
    from the rows before it. In waves: the linear combinations without products that are
    ready first (each costs a few operations and may make others ready, as ``th1 - th2``
    makes its sine and cosine), else every ready node, one group per kind in the order met."""
    todo = list(ops)
    groups: list[list[tuple]] = []
    while todo:
        ready = [op for op in todo if set(g.needs[_out(op)]) <= computed]
        if not ready:  # a node needing a row no node computes: a bug here, not a hang
            raise AssertionError(f"{len(todo)} nodes cannot be computed: {todo[0]}")
        wave = [op for op in ready if op[0] == "lin" and not op[4]] or ready
        kinds: dict[str, list[tuple]] = {}
        for op in wave:
            key = op[0] if op[0] in ("lin", "square", "sincos") else f"{op[0]}{_out(op)}"
            kinds.setdefault(key, []).append(op)
        groups += kinds.values()
        for op in wave:
            todo.remove(op)
            computed.update(op[1] if op[0] == "sincos" else (op[1],))
    return groups


def _out(op: tuple) -> int:
    return op[1][0] if op[0] == "sincos" else op[1]


def _emit(op: tuple) -> list[str]:
    """The statements computing order ``k`` of one node of a kind that is not grouped (inside
    the loop over ``k``; linear combinations, squares and sine/cosine pairs are emitted in
    groups: :func:`_lin_group`, :func:`_square_group`, :func:`_sincos_group`)."""
    kind, r = op[0], op[1]
    if kind == "div":
        (tk, top), b = op[2], op[3]
        first = f"A[{top}, k]" if tk == "s" else f"{top} if k == 0 else 0.0"
        return [
            f"s = {first}",
            "for j in range(1, k + 1):",
            f"    s -= A[{b}, j] * A[{r}, k - j]",
            f"A[{r}, k] = s / A[{b}, 0]",
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


def _entry(g: _Graph, e: sp.Expr) -> tuple[sp.Expr | str | None, list[tuple[int, str | None, int]]]:
    """A mass matrix entry as ``(constant part, [(sign, name, row)])``: its order 0 is the
    constant plus the rows' order 0, its higher orders the rows' (an entry with products of
    series is one row of its own). A constant entry is ``(a number or the constant's symbol,
    [])``, which the closed-form inverse simplifies with (the hoop's 1)."""
    if g.is_const(e):
        return (e if e.is_Number else sp.Symbol(g.const(e))), []
    consts, lin, prods = g.terms(e)
    if prods:
        return None, [(1, None, g.series(e))]
    c = g.const(sp.Add(*consts)) if consts else None
    return c, [(*g.coefficient(k), a) for k, a in lin]


def _mass_solve(g: _Graph, mass: list[list[sp.Expr]], force: list[sp.Expr]) -> tuple[list, list]:
    """The statements solving ``M^[0] a^[k] = f^[k] - sum_{1<=j<=k} M^[j] a^[k-j]`` for order
    ``k`` of the accelerations ``a`` (rows of their own), ``M^[0]`` inverted once per step (at
    ``k = 0``, in closed form): ``(the statements before the loop, in it)``; the accelerations'
    rows are the last of ``g``.

    The force's products are not rows: their terms ``j >= 1`` are summed in the loop over ``j``
    that sums the matrix's, into one accumulator per equation and coefficient (the hoop's
    ``-m sin(u) w2^2`` and ``-m cos(u) a2`` share one), and their term ``j = 0`` after it."""
    n = len(mass)
    entries = [[_entry(g, e) for e in row] for row in mass]
    forces = [g.terms(f) for f in force]
    forces = [
        (
            g.const(sp.Add(*consts)) if consts else None,
            [(*g.coefficient(k), a) for k, a in lin],
            [(*g.coefficient(k), a, b) for k, a, b in prods],
        )
        for consts, lin, prods in forces
    ]
    first = len(set(g.rows.values()))
    acc = list(range(first, first + n))
    for i, r in enumerate(acc):
        g.rows[sp.Symbol(f"_acceleration{i}")] = r
    # the inverse of M^[0] from the entries' order 0 (numbers where an entry is one)
    sym = [[sp.Symbol(f"e{i}_{l}") for l in range(n)] for i in range(n)]
    values = []
    for i in range(n):
        for l in range(n):
            c, rows = entries[i][l]
            if not rows:
                sym[i][l] = c
                continue
            parts = [_term(sign, name, f"A[{r}, 0]") for sign, name, r in rows]
            values.append(f"e{i}_{l} = {_sum(parts)}" + (f" + {c}" if c else ""))
    matrix = sp.Matrix(sym)
    det_inv = sp.Symbol("det_inv")
    adj = matrix.adjugate()
    inverse = [f"det_inv = 1.0 / ({pycode(matrix.det(method='berkowitz'))})"]
    inverse += [f"i{i}_{l} = {pycode(adj[i, l] * det_inv)}" for i in range(n) for l in range(n)]
    before = [" = ".join([f"i{i}_{l}" for i in range(n) for l in range(n)] + ["0.0"])]
    body = ["if k == 0:", *(f"    {x}" for x in values + inverse)]
    # sums over j >= 1, one accumulator per (equation, coefficient)
    accs: list[dict[str | None, list[str]]] = [{} for _ in range(n)]
    zero: list[dict[str | None, list[str]]] = [{} for _ in range(n)]
    for i, (_, _, prods) in enumerate(forces):
        for sign, name, a, b in prods:
            accs[i].setdefault(name, []).append(_product(sign, a, b))
            zero[i].setdefault(name, []).append(_product(sign, a, b, "0", "k"))
    for i in range(n):
        for l in range(n):
            for sign, name, r in entries[i][l][1]:  # subtracted: the opposite sign
                accs[i].setdefault(name, []).append(_product(-sign, r, acc[l]))
    loop, finish = [], []
    for i in range(n):
        parts = _accumulators(accs[i], f"b{i}_", body, loop)
        # the order-0 products, which the loop over j >= 1 leaves out
        for m_, name in enumerate(accs[i]):
            if name in zero[i]:
                finish.append(f"b{i}_{m_} += {_sum(zero[i][name])}")
        c, lin, _ = forces[i]
        parts += [_term(sign, name, f"A[{a}, k]") for sign, name, a in lin]
        finish.append(f"b{i} = {_sum(parts) or '0.0'}")
        if c is not None:
            finish += ["if k == 0:", f"    b{i} += {c}"]
    if loop:
        body += ["for j in range(1, k + 1):", "    i = k - j", *loop]
    body += finish
    for i in range(n):
        solve = " + ".join(f"i{i}_{l} * b{l}" for l in range(n))
        body += [f"a{i} = {solve}", f"A[{acc[i]}, k] = a{i}"]
    return before, body


def series_source(eq: Equations) -> str:
    """The generated module's body: ``ROWS`` and ``expand(A, p, order)``."""
    ys, ps, exprs = plain(eq)
    g = _Graph(ys, ps)
    n = len(eq.mass)
    d = eq.dim
    outs = [g.output(e) for e in exprs[: d - n]]  # f(y)^[k], in the state's order
    before, solve = [], []
    if n:  # the last n rates solve the mass matrix's system (module docstring)
        rename = dict(zip(eq.state, ys, strict=True)) | dict(zip(eq.params, ps, strict=True))
        mass = [[e.xreplace(rename) for e in row] for row in eq.mass]
        before, solve = _mass_solve(g, mass, [f.xreplace(rename) for f in eq.force])
        outs += [f"a{i} * inv" for i in range(n)]
    body = []
    rates = {i: g.rows[e] for i, e in enumerate(exprs[: d - n]) if e in g.rows}
    rates |= {d - n + i: len(set(g.rows.values())) - n + i for i in range(n)}
    slopes, angles = _slopes(g, rates), _angles(g)
    skip = set(slopes) & set(angles)
    ops = _read(g, skip, solve + outs)
    for op in ops:  # such a pair needs what the pairs of its order 0 need, no more
        if op[0] == "sincos" and op[2] in skip:
            _, x, _, y = angles[op[2]]
            g.needs[op[1][0]] = g.needs[x[0]] + g.needs[y[0]]
    for group in _schedule(g, ops, set(range(d))):
        if group[0][0] == "lin":
            body += _lin_group(group)
        elif group[0][0] == "square":
            body += _square_group(group)
        elif group[0][0] == "sincos":
            body += _sincos_group(group, slopes, angles)
        else:
            body += _emit(group[0])
    body += solve
    body += [f"A[{i}, k + 1] = {x}" for i, x in enumerate(outs)]
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
    lines += [f"    {line}" for line in before]
    lines += ["    for k in range(order):", "        inv = 1.0 / (k + 1)"]
    lines += [f"        {line}" for line in body]
    return "\n".join(lines) + "\n"


@functools.cache
def generated_expand(eq: Equations):
    """``(expand, rows)``: the compiled expansion of ``eq`` and the rows its array needs."""
    module = load(eq, "series", series_source)
    return module.expand, module.ROWS
