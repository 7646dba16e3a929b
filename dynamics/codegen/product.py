"""The product's systems' generated forms, loaded without sympy once they are generated.

The generated modules of the systems of :data:`.equations.EQUATIONS` are named by system id
and kind alone: their folder is keyed on a hash of every source file of the package
(:func:`mechviz.dynamics._cachedir.cache_dir`), the equations' and the generator's included,
so an edit to either starts a fresh folder. A process that finds the file imports it and
neither imports sympy (about half a second) nor generates anything; only the first process of
a version of the sources does (:mod:`.equations` is imported here inside the function, for
that case alone).
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType

from .build import HEADER, load_named


def product_module(sys_id: int, kind: str) -> ModuleType:
    """The generated module ``kind`` (``"series"``: :mod:`.series`; ``"step"``: :mod:`.steps`' RK4 step;
    ``"rhs"``: :mod:`.rhs`) of the product's system ``sys_id``."""

    def text() -> str:
        from . import equations, rhs, series, steps

        eq = equations.EQUATIONS[sys_id]()
        make: dict[str, Callable] = {
            "series": series.series_source,
            "step": steps.rk4_source,
            "rhs": rhs.rhs_source,
        }
        return HEADER.format(name=eq.name, key="the package's sources") + make[kind](eq)

    return load_named(f"mechviz_generated_{kind}_system{int(sys_id)}", text)
