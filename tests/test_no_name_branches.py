"""No product module branches on a system's or a method's name outside the registries and the
systems' own modules: a fourth system or a new method is added in one place, and a part of the
product that meets one it does not know asks the registry (which raises naming it) instead of
falling through to another's behaviour.

The scan parses every module of ``dynamics``, ``viz`` and ``bench`` and reports, as
``file:line``, each comparison, ``match`` case, dict-literal key, subscript and ``.get``/``.pop``
lookup whose operand is a system's or a method's name as a string literal (``name == "hoop"``,
``{"hoop": ...}``, ``system in ("disk",)``, ``PROBLEMS["charge"]``) or a system object's
``.name``/``.key`` (``d.exhibit == HOOP.name``). The names are the registries' own
(:data:`mechviz.dynamics.SPECS`, :data:`mechviz.dynamics.SYSTEMS`, the benchmark problems'
keys, :data:`mechviz.dynamics.integrators.METHODS`), so the scan follows them.
"""

from __future__ import annotations

import ast
import textwrap
from pathlib import Path

import pytest

from mechviz import dynamics
from mechviz.dynamics.integrators import METHODS
from mechviz.viz.model import MODELS
from mechviz.viz.scene import EXHIBITS

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ("dynamics", "viz", "bench")

#: The registries and the systems' and methods' own modules: where a name is the entry itself.
#: Each system's own modules are found by its name (``dynamics/<name>.py``, ``viz/model/<name>.py``,
#: ``viz/scene/<name>.py``), so a new system's are exempt without a line here.
REGISTRIES = {
    "dynamics/registry.py": "the one registry of systems",
    "dynamics/systems.py": "the systems' adapters (each system as the driver sees it)",
    "dynamics/ids.py": "the compiled ids of the systems, by name (the kernels' tables' index)",
    "dynamics/integrators": "the methods' registry (base.py) and the methods' own modules",
}
#: Where a name is data, not a branch: (file, name) -> why. Keep it short.
ALLOWED: dict[tuple[str, str], str] = {}

#: What the scan looks for, through the registries (so it follows them).
SYSTEM_NAMES = (
    set(dynamics.SPECS)
    | set(dynamics.SYSTEMS)
    | {case.key for spec in dynamics.SPECS.values() for case in spec.bench[:1]}
)
NAMES = SYSTEM_NAMES | set(METHODS)
#: The identifiers a module may hold a system by: its adapter, description, model and exhibit.
SYSTEM_OBJECTS = (
    {cls.__name__ for cls in dynamics.SYSTEMS.values()}
    | {name.upper() for name in dynamics.SPECS}
    | {cls.__name__ for cls in (*MODELS.values(), *EXHIBITS.values())}
    | {cls.Config.__name__ for cls in MODELS.values()}
)


def _literals(node: ast.AST) -> list[str]:
    """The names ``node`` spells: a string literal, a system object's ``.name``/``.key``, or a
    tuple, list or set of these."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value] if node.value in NAMES else []
    if (
        isinstance(node, ast.Attribute)
        and node.attr in ("name", "key")
        and isinstance(node.value, ast.Name)
        and node.value.id in SYSTEM_OBJECTS
    ):
        return [f"{node.value.id}.{node.attr}"]
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return [n for e in node.elts for n in _literals(e)]
    return []


def name_branches(source: str) -> list[tuple[int, str]]:
    """``(line, name)`` for each branch or lookup on a name in ``source`` (module docstring)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        operands: list[ast.AST] = []
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
        elif isinstance(node, ast.Dict):
            operands = [k for k in node.keys if k is not None]
        elif isinstance(node, ast.MatchValue):
            operands = [node.value]
        elif isinstance(node, ast.Subscript):
            # a type (Literal["exact", ...]) names values a parameter takes; it does not branch
            is_type = isinstance(node.value, ast.Name) and node.value.id == "Literal"
            operands = [] if is_type else [node.slice]
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr in ("get", "pop")
            and node.args
        ):
            operands = [node.args[0]]
        found += [(node.lineno, n) for op in operands for n in _literals(op)]
    return sorted(set(found))


def _own(rel: Path) -> bool:
    """Whether ``rel`` is a registry or a system's own module."""
    if any(str(rel) == p or str(rel).startswith(p + "/") for p in REGISTRIES):
        return True
    own_folders = {"dynamics", "viz/model", "viz/scene"}
    return str(rel.parent) in own_folders and rel.stem in dynamics.SPECS


def test_no_product_module_branches_on_a_system_or_method_name():
    scanned, found = 0, []
    for folder in FOLDERS:
        for path in sorted((ROOT / folder).rglob("*.py")):
            rel = path.relative_to(ROOT)
            if _own(rel):
                continue
            scanned += 1
            for line, name in name_branches(path.read_text(encoding="utf-8")):
                if (str(rel), name) not in ALLOWED:
                    found.append(f"{rel}:{line}: {name}")
    assert scanned > 100, scanned  # the scan found the package
    assert not found, "\n".join(found)


def test_the_allowed_names_are_still_there_and_say_why():
    for (file, name), why in ALLOWED.items():
        assert why.strip(), (file, name)
        assert name in {n for _, n in name_branches((ROOT / file).read_text(encoding="utf-8"))}


@pytest.mark.parametrize(
    "planted",
    [
        'if name == "hoop":\n    pass',
        'x = {"hoop": 1, "other": 2}',
        'ok = system in ("disk",)',
        'match method:\n    case "rk4":\n        pass',
        'p = PROBLEMS["charge"]',
        'f = TABLE.get("free-body")',
        "same = d.exhibit == HOOP.name",
        "first = {CyclotronModel.key: 1}",
    ],
)
def test_the_scan_finds_a_planted_branch(planted):
    source = textwrap.dedent(
        f"def f(name, method, system, d):\n{textwrap.indent(planted, '    ')}\n"
    )
    assert name_branches(source), planted


def test_the_scan_leaves_lookups_through_the_registry_and_words_that_are_not_names():
    source = textwrap.dedent(
        '''
        def f(d, m, reference: Literal["exact", "reference"] = "auto"):
            """Docstrings may name the hoop: they document, they do not branch."""
            spec = dynamics.spec(d.exhibit)
            label = {"energy": 1, "error": 2}
            return m.closed_form or d.motion == "driven" or spec.name
        '''
    )
    assert name_branches(source) == []


def test_a_system_the_registry_does_not_know_raises_naming_it():
    from mechviz.dynamics.registry import spec_named, system_named

    for ask, known in ((spec_named, dynamics.SPECS), (system_named, dynamics.SYSTEMS)):
        with pytest.raises(KeyError, match="pendulum") as err:
            ask("pendulum")
        assert all(name in str(err.value) for name in known)  # and says what there is


def test_the_exhibits_are_keyed_by_the_registry_and_refuse_a_system_without_one():
    from mechviz.viz.model import by_system

    assert list(MODELS) == list(dynamics.SPECS) == list(EXHIBITS)
    first, *rest = MODELS.values()
    with pytest.raises(KeyError, match=first.key):
        by_system(tuple(rest), "model")

    class Stray:
        key = "pendulum"

    with pytest.raises(KeyError, match="pendulum"):
        by_system((*MODELS.values(), Stray), "model")


def test_a_model_that_leaves_a_hook_out_says_so_instead_of_answering_for_another():
    from mechviz.viz.model import SystemHooks

    class Bare(SystemHooks):
        pass

    with pytest.raises(NotImplementedError, match="Bare"):
        Bare.shortest_period(None, {})
    with pytest.raises(NotImplementedError, match="Bare"):
        Bare.draw_motion_chart(None, None, None, None)
