"""The exhibits' models run headless: a demo's samples, CSV and measured figures come out of
:mod:`mechviz.viz.model` with viser unimportable, and match what the drawn exhibit records.

Also the shape of the code the model split promises: no import cycle (imports inside functions
counted), no module over 600 lines, each system named (as a string) outside its own modules in
one file at most (:mod:`mechviz.dynamics.ids`, where the names are written once).
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from mechviz import dynamics

ROOT = Path(__file__).resolve().parents[1]

_HEADLESS = textwrap.dedent(
    """
    import json, sys
    sys.modules["viser"] = None  # importing viser now raises ImportError
    from mechviz.viz.record.demo import load_demo
    from mechviz.viz.record.figures import figures
    from mechviz.viz.record.outputs import traces_csv
    from mechviz.viz.record.run import trace_demo

    demo = load_demo("radial-kick").with_overrides(duration=8.0, fps=20)
    tr = trace_demo(demo)
    csv = traces_csv(demo, tr).decode()
    print(json.dumps({
        "rows": len(csv.splitlines()) - 1,
        "header": csv.splitlines()[0],
        "figures": figures(demo, tr),
        "state": tr.states[tr.main][-1, 0].tolist(),
        "viser": "viser" in sys.modules and sys.modules["viser"] is not None,
    }))
    """
)


@pytest.mark.slow
def test_a_demo_runs_headless_without_viser_and_its_figures_are_the_physics():
    out = subprocess.run(
        [sys.executable, "-c", _HEADLESS], capture_output=True, text=True, timeout=300, cwd=ROOT
    )
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout)
    assert not r["viser"]
    assert r["rows"] == 8 * 20 + 1 and r["header"].startswith("run,member,t,x,y,z")
    figs = {f["name"]: f for f in r["figures"]}
    # the gyrofrequency |qB|/m measured from the frames, unchanged by the kick; the circle's
    # shift |dv|/|Omega| = 0.5 m and the new radius sqrt(1 + 0.5^2) m (q = m = B = 1, v = 1 m/s)
    for name in ("gyrofrequency", "gyrofrequency after the kick"):
        assert figs[name]["measured"] == pytest.approx(figs[name]["predicted"], rel=1e-3)
    assert figs["circle shift after the kick"]["predicted"] == pytest.approx(0.5)
    assert figs["circle shift after the kick"]["measured"] == pytest.approx(0.5, rel=1e-9)
    assert figs["radius after the kick"]["measured"] == pytest.approx(np.hypot(1.0, 0.5), rel=1e-9)


@pytest.mark.slow
def test_the_headless_model_records_what_the_drawn_exhibit_records():
    from mechviz.viz.record.demo import load_demo
    from mechviz.viz.record.run import run_demo, trace_demo

    demo = load_demo("hoop-mode1").with_overrides(duration=1.0, fps=15)
    alone = trace_demo(demo)
    drawn = run_demo(demo).traces
    label = alone.main
    np.testing.assert_array_equal(alone.states[label], drawn.states[label])
    np.testing.assert_array_equal(alone.energy_error[label], drawn.energy_error[label])
    assert alone.steps == drawn.steps


def _modules() -> dict[str, Path]:
    out = {}
    for folder in ("dynamics", "viz", "bench"):  # mapped to mechviz.<folder> (pyproject.toml)
        for path in (ROOT / folder).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(("mechviz", *(parts[:-1] if parts[-1] == "__init__" else parts)))
            out[name] = path
    assert len(out) > 100, sorted(out)  # the scan found the package
    return out


def _imports(name: str, path: Path, known: set[str]) -> set[str]:
    """The project modules ``name`` imports anywhere in its text (inside functions too; not those
    under ``if TYPE_CHECKING:``, which never run)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    typing_only = {
        id(n)
        for node in ast.walk(tree)
        if isinstance(node, ast.If) and ast.unparse(node.test).endswith("TYPE_CHECKING")
        for n in ast.walk(node)
    }
    found = set()
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package
            for _ in range(node.level - 1):
                base = base.rpartition(".")[0]
            mod = node.module or ""
            root = (base + "." + mod).strip(".") if node.level else mod
            targets = [root] + [f"{root}.{a.name}" for a in node.names]
        else:
            continue
        for t in targets:
            while t and t not in known:
                t = t.rpartition(".")[0]
            if t and t != name:
                found.add(t)
    return found


def test_the_packages_have_no_import_cycle_counting_imports_inside_functions():
    mods = _modules()
    known = set(mods)
    graph = {
        n: {m for m in _imports(n, p, known) if not n.startswith(m + ".")} for n, p in mods.items()
    }
    # an import of a package runs its __init__, which a submodule of it may not import back
    cycles = []
    state: dict[str, int] = {}

    def visit(n: str, stack: list[str]) -> None:
        state[n] = 1
        for m in sorted(graph[n]):
            if state.get(m) == 1:
                cycles.append(stack[stack.index(m) :] + [m] if m in stack else [n, m])
            elif m not in state:
                visit(m, [*stack, m])
        state[n] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n, [n])
    assert not cycles, cycles[:5]


def test_no_module_is_over_six_hundred_lines():
    long = {
        str(p.relative_to(ROOT)): n
        for p in _modules().values()
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > 600
    }
    assert not long, long


def _string_constants(tree: ast.AST) -> set[str]:
    """The string literals of ``tree``, docstrings left out (they document, they do not
    dispatch)."""
    docs = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return {
        n.value
        for n in ast.walk(tree)
        if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs
    }


def test_each_system_is_named_in_its_own_modules_and_at_most_one_other_file():

    own = {"dynamics", "viz/model", "viz/scene"}
    by_system: dict[str, set[str]] = {}
    for spec_name in dynamics.SPECS:
        # the driver's names of the same system (the disk's two motions) count as its name
        names = {spec_name} | {n for n in dynamics.SYSTEMS if spec_name in n}
        if spec_name == "disk":
            names |= {dynamics.ReleasedDisk.name}
        for path in _modules().values():
            rel = path.relative_to(ROOT)
            if str(rel.parent) in own and rel.stem == spec_name:
                continue
            tree = ast.parse(path.read_text(encoding="utf-8"))
            if names & _string_constants(tree):
                by_system.setdefault(spec_name, set()).add(str(rel))
    assert by_system, "the scan found no system's name at all: it scans nothing"
    crowded = {n: sorted(f) for n, f in by_system.items() if len(f) > 1}
    assert not crowded, crowded
