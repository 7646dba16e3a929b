"""The benchmark's documents rendered from its ``results.json``: ``tables.md`` and the charts
beside it and the benchmark blocks of the site's speed page (``docs/speed.md``), so that every
figure the page quotes from a run comes from that run, and a change to a chart's drawing needs no
new run.

A block in the page is the text between ``<!-- bench:NAME -->`` and ``<!-- /bench:NAME -->``
(each marker on a line of its own); NAME is one of :data:`BLOCKS`. Everything outside the blocks
is left as it is, and rendering twice changes nothing. ``make bench-docs`` runs the benchmark
into ``docs/bench`` and then this module::

    python -m mechviz.bench.docs docs/bench docs/speed.md      # tables.md, charts, the page
    python -m mechviz.bench.docs --check docs/speed.md         # only check the page's blocks

A page whose blocks are missing, repeated or unknown is refused before anything is written
(exit status 2). Each file is replaced whole (:func:`mechviz.dynamics.files.write_files_atomically`),
the charts and ``tables.md`` as one set first: rendering again from the same ``results.json``
repairs an interrupted render.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from mechviz.dynamics.files import WriteFailed, write_files_atomically

from . import charts, report


def run_line(result: dict) -> str:
    """The run's particulars: command, date, duration, machine, load and versions."""
    load = result.get("load_average") or {}
    before, after = ((load.get(k) or [None])[0] for k in ("before", "after"))
    versions = ", ".join(f"{k} {v}" for k, v in result["versions"].items())
    m = result["machine"]
    minutes, seconds = divmod(round(result["duration_s"]), 60)
    return (
        f"Figures below: `{result['command']}`, {result['date']}, {minutes} min {seconds:02d} s, "
        f"{m.get('cpu') or m.get('processor', '')} with {m['cpus']} cores, load average "
        f"{before} before and {after} after; {versions}."
    )


BLOCKS = {
    "run": run_line,
    "targets": report.targets_summary,
    "ratios": report.ratio_table,
    "peers": report.peers_block,
    "long-run": report.long_run_table,
    "steps": report.step_table,
}

_BLOCK = re.compile(
    r"^<!-- bench:(?P<name>[a-z-]+) -->\n(?P<body>.*?)^<!-- /bench:(?P=name) -->$",
    re.S | re.M,
)
_OPEN = re.compile(r"^<!-- bench:([a-z-]+) -->$", re.M)


def check(text: str) -> None:
    """Raise ``ValueError`` naming the block unless each of :data:`BLOCKS` appears exactly once,
    closed, and no other block does."""
    opened = _OPEN.findall(text)
    closed = [m.group("name") for m in _BLOCK.finditer(text)]
    for name in opened:
        if name not in BLOCKS:
            raise ValueError(f"unknown benchmark block {name!r} (known: {', '.join(BLOCKS)})")
    for name in BLOCKS:
        if opened.count(name) != 1 or closed.count(name) != 1:
            raise ValueError(
                f"benchmark block {name!r} must appear once, as '<!-- bench:{name} -->' "
                f"... '<!-- /bench:{name} -->' (found {opened.count(name)} opening, "
                f"{closed.count(name)} closed)"
            )


def splice(text: str, result: dict) -> str:
    """``text`` with every benchmark block's body rendered from ``result``."""
    check(text)
    return _BLOCK.sub(
        lambda m: (
            f"<!-- bench:{m['name']} -->\n{BLOCKS[m['name']](result).rstrip()}\n"
            f"<!-- /bench:{m['name']} -->"
        ),
        text,
    )


def render(out: Path, readme: Path) -> None:
    """Write ``out/tables.md``, the charts and the page's blocks from ``out/results.json``."""
    result = json.loads((out / "results.json").read_text())
    text = splice(readme.read_text(), result)
    files = {**charts.render_charts(result), "tables.md": report.markdown(result).encode()}
    write_files_atomically(out, files)
    write_files_atomically(readme.parent, {readme.name: text.encode()})


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m mechviz.bench.docs", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--check", action="store_true", help="only check the page's blocks")
    parser.add_argument("paths", nargs="+", metavar="PATH", help="[RESULTS_DIR] PAGE")
    args = parser.parse_args(argv)
    try:
        if args.check:
            if len(args.paths) != 1:
                parser.error("--check takes the page only")
            check(Path(args.paths[0]).read_text())
            return 0
        if len(args.paths) != 2:
            parser.error("give the results folder and the page")
        render(Path(args.paths[0]), Path(args.paths[1]))
    except WriteFailed as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except (OSError, ValueError, KeyError) as exc:  # a missing file, bad JSON, a bad page
        print(f"error: {Path(args.paths[-1]).name}: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
