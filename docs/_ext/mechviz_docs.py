"""The parts of mechviz's site generated from the code, so that they cannot drift from it.

- ``{mechviz-cli}``: the command-line reference, every subcommand's ``--help`` from the argument
  parsers themselves (:func:`mechviz.viz.cli.build_parser`).
- ``{mechviz-demo-schema}``: the demo-file reference, every table and field of a demo file with
  its type and default, from the msgspec structs that read demo files
  (:mod:`mechviz.viz.record.demo`).
- The tutorials: the example notebooks (``examples/``), copied under ``_generated/`` and executed
  by myst-nb when the site is built.
- The gallery (``gallery.md`` and a page per built-in demo under ``_generated/``, an ignored
  folder): each demo's still from ``docs/img/demos`` and its recording, made by ``mechviz record``
  when the site is built, playing in the page. ``MECHVIZ_DOCS_DEMOS`` (comma-separated names)
  limits the gallery to some demos, for a quicker build.
- MathJax, fetched once from the npm registry into ``build/docs-tools`` and served with the site,
  so that its equations are typeset offline.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import msgspec
from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.application import Sphinx
from sphinx.errors import ExtensionError

DOCS = Path(__file__).resolve().parents[1]
GENERATED = DOCS / "_generated"
TOOLS = DOCS.parent / "build" / "docs-tools"  # ignored by git, kept between builds
MATHJAX = "mathjax@3"


class CliReference(Directive):
    """Every subcommand's help, as the ``mechviz`` command prints it."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        from mechviz.viz.cli import build_parser

        parser = build_parser()
        out: list[nodes.Node] = []
        out.append(self._section("mechviz", parser.format_help()))
        subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        for name, sub in subparsers.choices.items():
            out.append(self._section(f"mechviz {name}", sub.format_help()))
        return out

    def _section(self, title: str, text: str) -> nodes.section:
        section = nodes.section(ids=[nodes.make_id(title)])
        section += nodes.title(text=title)
        section += nodes.literal_block(text, text)
        return section


class DemoSchema(Directive):
    """The tables and fields of a demo file, from the structs that read it."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        from mechviz.viz.record import demo as schema

        out: list[nodes.Node] = []
        for struct, table in (
            (schema.Demo, "top level"),
            (schema.Initial, "[initial]"),
            (schema.Compare, "[compare]"),
            (schema.Camera, "[camera]"),
            (schema.Event, "[[events]]"),
        ):
            section = nodes.section(ids=[nodes.make_id(f"demo-{table}")])
            section += nodes.title(text=table)
            doc = textwrap.dedent(struct.__doc__ or "").strip()
            if doc:
                section += nodes.paragraph(text=" ".join(doc.split()))
            rows = []
            for f in msgspec.structs.fields(struct):
                if f.name in ("name", "source"):  # set by the loader, not written in a file
                    continue
                default = "required" if f.required else repr(f.default)
                if f.default_factory is not msgspec.NODEFAULT:
                    default = repr(f.default_factory())
                rows.append((f.name, _type_name(f.type), default))
            section += _table(("key", "type", "default"), rows)
            out.append(section)
        return out


def _type_name(tp) -> str:
    text = getattr(tp, "__name__", None) if isinstance(tp, type) else None
    return text or str(tp).replace("typing.", "").replace("mechviz.viz.record.demo.", "")


def _table(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> nodes.table:
    table = nodes.table()
    group = nodes.tgroup(cols=len(header))
    table += group
    for _ in header:
        group += nodes.colspec(colwidth=1)
    head = nodes.thead()
    group += head
    head += _row(header)
    body = nodes.tbody()
    group += body
    for r in rows:
        body += _row(r)
    return table


def _row(cells: tuple[str, ...]) -> nodes.row:
    row = nodes.row()
    for c in cells:
        entry = nodes.entry()
        entry += nodes.paragraph(text="")
        entry[0] += nodes.literal(text=c)
        row += entry
    return row


def _gallery(app: Sphinx) -> None:
    """Record every built-in demo and write its gallery page (before the pages are read)."""
    from mechviz.viz.record.demo import DEMO_DIR, load_demo

    names = sorted(p.stem for p in DEMO_DIR.glob("*.toml"))
    wanted = os.environ.get("MECHVIZ_DOCS_DEMOS")
    if wanted:
        unknown = set(wanted.split(",")) - set(names)
        if unknown:
            raise ExtensionError(f"MECHVIZ_DOCS_DEMOS: no built-in demo {sorted(unknown)}")
        names = [n for n in names if n in wanted.split(",")]
    if GENERATED.exists():
        shutil.rmtree(GENERATED)
    pages = GENERATED / "gallery"
    static = GENERATED / "static" / "recordings"
    pages.mkdir(parents=True)
    static.mkdir(parents=True)
    for name in names:
        demo = load_demo(name)
        out = GENERATED / "work" / name
        run = subprocess.run(
            [sys.executable, "-m", "mechviz.viz.cli", "record", name, "--out", str(out)],
            capture_output=True,
            text=True,
        )
        if run.returncode != 0:
            raise ExtensionError(f"mechviz record {name} failed: {run.stderr.strip()[-500:]}")
        shutil.copyfile(out / f"{name}.html", static / f"{name}.html")
        still = DOCS / "img" / "demos" / f"{name}.png"
        title = demo.title or name
        lines = [
            f"# {name}",
            "",
            f"*{title}*",
            "",
            demo.description.strip(),
            "",
            f'```{{raw}} html\n<iframe class="mechviz-recording" src="../../_static/recordings/{name}.html" '
            f'title="{name}: the recording" width="100%" height="520" loading="lazy"></iframe>\n```',
            "",
            "The recording above plays in the page: drag to turn the view, the bar below it plays,",
            f"pauses and scrubs. `mechviz record {name}` makes it; `mechviz play` serves it.",
            "",
        ]
        if still.is_file():
            lines += [f"![{name}: the still](../../img/demos/{name}.png)", ""]
        (pages / f"{name}.md").write_text("\n".join(lines))
    shutil.rmtree(GENERATED / "work")
    # the example notebooks, executed by myst-nb when the pages are read
    tutorials = GENERATED / "tutorials"
    tutorials.mkdir()
    for nb in sorted((DOCS.parent / "examples").glob("*.ipynb")):
        shutil.copyfile(nb, tutorials / nb.name)


def _static_files(app: Sphinx, config) -> None:
    """The gallery's recordings and MathJax, served from the site's ``_static``."""
    (GENERATED / "static").mkdir(parents=True, exist_ok=True)
    config.html_static_path.append(str(GENERATED / "static"))
    modules = TOOLS / "node_modules"
    if not (modules / config.mathjax_path).is_file():
        npm = shutil.which("npm")
        if npm is None:
            raise ExtensionError(
                "the site serves MathJax itself: install npm (Node.js) to fetch it"
            )
        TOOLS.mkdir(parents=True, exist_ok=True)
        got = subprocess.run(
            [
                npm,
                "install",
                "--prefix",
                str(TOOLS),
                "--no-audit",
                "--no-fund",
                "--silent",
                MATHJAX,
            ],
            capture_output=True,
            text=True,
        )
        if got.returncode != 0:
            raise ExtensionError(f"npm install {MATHJAX} failed: {got.stderr.strip()[-500:]}")
    config.html_static_path.append(str(modules))


def setup(app: Sphinx) -> dict:
    app.add_directive("mechviz-cli", CliReference)
    app.add_directive("mechviz-demo-schema", DemoSchema)
    app.connect("config-inited", _static_files)
    app.connect("builder-inited", _gallery)
    return {"parallel_read_safe": True, "version": "1"}
