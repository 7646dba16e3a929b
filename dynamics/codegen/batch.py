"""The Taylor recurrences of a batch of problems, generated from the one-problem expansion.

A batch advances ``B`` problems of one system together (different starts and parameters, one
order): the coefficient array is ``A[row, k, b]`` (rows, >= order + 1, ``B``) and the
parameters ``p[j, b]`` (parameters, ``B``), the member index ``b`` innermost and contiguous,
so that the same operation on the ``B`` members reads and writes one vector.

The source is not written anew: it is :func:`.series.series_source`'s expansion of the same
equations (one walk of the expression graph, one set of recurrences), rewritten statement by
statement on Python's syntax tree. Names are of two kinds:

- *index* names, the same for every member: the loops' counters (``k``, ``j``, ``i``), the
  order, and names computed from those alone (``inv = 1/(k + 1)``, ``h = k // 2``); statements
  assigning them, loops and tests (``if k == 0``) stay as they are;
- *lane* names, one value per member: every name computed from the coefficients, the
  parameters or another lane name (accumulators, the mass matrix's inverse, constants of the
  parameters). A statement assigning one is written ``B`` times, once per member in turn, with
  ``name`` renamed ``name_l{b}`` and ``A[r, k]`` / ``p[j]`` indexed ``[r, k, b]`` / ``[j, b]``.

Each member's arithmetic is then the one-problem expansion's, statement for statement, in
scalar variables (registers: no array of accumulators whose aliasing the compiler must
doubt); the ``B`` copies of a statement sit side by side, isomorphic and reading contiguous
memory, which LLVM's superword-level vectoriser packs into vector instructions, and which
otherwise are ``B`` independent chains of additions (a one-problem sum is one dependent chain).
Only contraction to fused multiply-adds is licensed (no reassociation: a member's sums keep
their order), so a member's coefficients equal the one-problem expansion's to round-off
(bit for bit where both compilers contract the same products).
"""

from __future__ import annotations

import ast
import copy

from .build import HEADER, load, load_named

#: The arrays of the expansion's signature ``expand(A, p, order)``.
_COEFFS, _PARAMS, _ORDER = "A", "p", "order"


def _names(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def _reads_arrays(node: ast.AST) -> bool:
    return any(
        isinstance(n, ast.Subscript) and isinstance(n.value, ast.Name) for n in ast.walk(node)
    )


def _targets(stmt: ast.stmt) -> list[ast.expr]:
    return list(stmt.targets) if isinstance(stmt, ast.Assign) else [stmt.target]


def lane_names(fn: ast.FunctionDef) -> set[str]:
    """The names of ``fn`` with one value per member (module docstring): assigned from an
    array element or from another such name, to a fixed point."""
    values: dict[str, list[ast.expr]] = {}
    for stmt in ast.walk(fn):
        if isinstance(stmt, (ast.Assign, ast.AugAssign)):
            for t in _targets(stmt):
                if isinstance(t, ast.Name):
                    values.setdefault(t.id, []).append(stmt.value)
    lane: set[str] = set()
    changed = True
    while changed:
        changed = False
        for name, exprs in values.items():
            if name not in lane and any(_reads_arrays(e) or _names(e) & lane for e in exprs):
                lane.add(name)
                changed = True
    return lane


class _Lane(ast.NodeTransformer):
    """One member's copy of a statement: lane names renamed, array elements given the lane."""

    def __init__(self, lane: set[str], b: int) -> None:
        self.lane, self.b = lane, b

    def visit_Name(self, node: ast.Name) -> ast.Name:
        if node.id in self.lane:
            return ast.copy_location(ast.Name(f"{node.id}_l{self.b}", node.ctx), node)
        return node

    def visit_Subscript(self, node: ast.Subscript) -> ast.Subscript:
        self.generic_visit(node)
        name = node.value.id if isinstance(node.value, ast.Name) else None
        b = ast.Constant(self.b)
        if name == _COEFFS and isinstance(node.slice, ast.Tuple) and len(node.slice.elts) == 2:
            node.slice = ast.Tuple([*node.slice.elts, b], ast.Load())
        elif name == _PARAMS and not isinstance(node.slice, ast.Tuple):
            node.slice = ast.Tuple([node.slice, b], ast.Load())
        else:
            raise NotImplementedError(f"no batch form of {ast.unparse(node)}")
        return node


def _is_lane_stmt(stmt: ast.stmt, lane: set[str]) -> bool:
    return _reads_arrays(stmt) or bool(_names(stmt) & lane)


def _check_shared(node: ast.expr, lane: set[str], what: str) -> None:
    """A loop's range or a test must be the same for every member (they share the order)."""
    if _reads_arrays(node) or _names(node) & lane:
        raise NotImplementedError(f"a {what} that differs between members: {ast.unparse(node)}")


def _batch_body(body: list[ast.stmt], lane: set[str], lanes: int) -> list[ast.stmt]:
    out: list[ast.stmt] = []
    for stmt in body:
        if isinstance(stmt, ast.For):
            _check_shared(stmt.iter, lane, "loop")
            stmt.body = _batch_body(stmt.body, lane, lanes)
            out.append(stmt)
        elif isinstance(stmt, ast.If):
            _check_shared(stmt.test, lane, "test")
            stmt.body = _batch_body(stmt.body, lane, lanes)
            stmt.orelse = _batch_body(stmt.orelse, lane, lanes)
            out.append(stmt)
        elif isinstance(stmt, (ast.Assign, ast.AugAssign)) and _is_lane_stmt(stmt, lane):
            out += [_Lane(lane, b).visit(copy.deepcopy(stmt)) for b in range(lanes)]
        elif isinstance(stmt, (ast.Assign, ast.AugAssign, ast.Expr)):
            out.append(stmt)  # an index name's statement, or the docstring
        else:
            raise NotImplementedError(f"no batch form of {type(stmt).__name__}")
    return out


def batch_from_series(serial: str, lanes: int, fastmath: str = '{"contract"}') -> str:
    """The batch module's body from a one-problem module's (:func:`.series.series_source`):
    ``ROWS``, ``LANES`` and ``expand(A, p, order)`` over ``A`` (rows, >= order + 1, ``lanes``)
    and ``p`` (parameters, ``lanes``). ``fastmath``: the licence of the generated function
    (contraction only by default, module docstring)."""
    if not 1 <= lanes <= 64:
        raise ValueError(f"lanes must be between 1 and 64; got {lanes}")
    tree = ast.parse(serial)
    fn = next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "expand")
    lane = lane_names(fn)
    taken = _names(fn)
    clash = {f"{n}_l{b}" for n in lane for b in range(lanes)} & taken
    if clash:
        raise NotImplementedError(f"the names {sorted(clash)} are taken")
    body = fn.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        body = body[1:]  # the one-problem docstring, replaced
    fn.body = _batch_body(body, lane, lanes)
    fn.body.insert(
        0,
        ast.Expr(
            ast.Constant(
                f"Orders 1 ... order of the state rows of the {lanes} members of A[row, k, b], "
                "parameters p[j, b] (module docstring)."
            )
        ),
    )
    fn.decorator_list = [ast.parse(f"njit(cache=True, fastmath={fastmath})", mode="eval").body]
    tree.body.insert(1, ast.parse(f"LANES = {lanes}").body[0])
    return ast.unparse(ast.fix_missing_locations(tree)) + "\n"


def batch_source(eq, lanes: int) -> str:
    """The batch expansion of the equations ``eq`` (:class:`.equations.Equations`), ``lanes``
    members at a time."""
    from .series import series_source  # sympy: only where something is generated

    return batch_from_series(series_source(eq), lanes)


def batch_module(sys_id: int, lanes: int):
    """The generated batch expansion of the product's system ``sys_id``, ``lanes`` members at a
    time (a module with ``ROWS``, ``LANES`` and ``expand``), loaded as
    :func:`.product.product_module` loads the one-problem forms."""

    def text() -> str:
        from . import equations

        eq = equations.EQUATIONS[sys_id]()
        head = HEADER.format(name=eq.name, key="the package's sources")
        return head + batch_source(eq, lanes)

    return load_named(f"mechviz_generated_batch{int(lanes)}_system{int(sys_id)}", text)


def generated_batch_expand(eq, lanes: int):
    """``(expand, rows)``: the compiled batch expansion of any :class:`.equations.Equations`
    (a test's system, say), ``lanes`` members at a time, and the rows its array needs."""
    module = load(eq, f"batch{int(lanes)}", lambda e: batch_source(e, lanes))
    return module.expand, module.ROWS
