"""The systems' names, written once, and the compiled systems' facts, importable without numba:
each one's id (the index of the kernels' tables) and the cost model of Taylor's method on it
(:mod:`mechviz.dynamics.taylor_order`).

One entry per compiled system, by the driver's name; :mod:`mechviz.dynamics.systems`' adapters and
:mod:`mechviz.dynamics.registry`'s descriptions take their names from here.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Compiled:
    """One compiled system. ``taylor_cost``: the cost of one Taylor step [ns] as
    ``c0 + c1 p + c2 p^2`` at order ``p`` (the step size and loop, Horner's evaluation and the
    linear recurrences, the Cauchy products; measured with the compiled pieces on a 2-core x86-64
    VM, only their ratios matter). ``entire``: its solutions are entire functions with
    coefficients falling as ``1/k!`` (the radius of convergence estimated from the last two grows
    with the order)."""

    sys_id: int
    taylor_cost: tuple[float, float, float]
    entire: bool = False

    def __post_init__(self) -> None:
        if self.sys_id < 0 or len(self.taylor_cost) != 3 or min(self.taylor_cost) < 0:
            raise ValueError(f"compiled system {self.sys_id}: a non-negative id and three costs")


CYCLOTRON, HOOP, FREE_BODY = 0, 1, 2
#: Every compiled system by the driver's name. The hoop's Taylor cost: a least-squares fit of whole
#: steps (180-1391 ns) at orders 6-32 on the benchmark hoop; the charge's sines and cosines are
#: entire.
COMPILED = {
    "cyclotron": Compiled(CYCLOTRON, (60.0, 1.0, 0.0), entire=True),
    "hoop": Compiled(HOOP, (72.0, 11.8, 0.92)),
    "free-body": Compiled(FREE_BODY, (55.0, 5.8, 1.0)),
}
if sorted(c.sys_id for c in COMPILED.values()) != list(range(len(COMPILED))):
    raise ValueError("the compiled ids must number the systems 0, 1, ... (the kernels' tables)")
SYSTEM_IDS = {name: c.sys_id for name, c in COMPILED.items()}
#: The disk as a person names it, and its driven motion (exact, no compiled kernel) as the driver
#: does; released, it is the free body above.
DISK_NAME, DRIVEN_DISK = "disk", "driven-disk"
NAMES = {i: name for name, i in SYSTEM_IDS.items()}
