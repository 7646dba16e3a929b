"""The ``mechviz`` command: one entry point, a subcommand per use.

``analyze`` and ``simulate`` come from :mod:`mechviz.viz.cli.analysis` and need no viewer; ``view``,
``record``, ``play``, ``bench``, ``video``, ``still`` and ``atlas`` import what they need only
when run.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from ..interrupts import hold_sigint, release_sigint

# One module per command (analyze and simulate in mechviz.viz.cli.analysis): view, record and play,
# bench, video, still, atlas.
_COMMAND_MODULES = (
    "mechviz.viz.cli.view",
    "mechviz.viz.cli.record",
    "mechviz.viz.cli.bench",
    "mechviz.viz.cli.video",
    "mechviz.viz.cli.still",
    "mechviz.viz.cli.atlas",
)
_LIGHT_COMMANDS = ("analyze", "simulate")  # no viewer, no meshes


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (``mechviz: error: ...``) and exit status 2."""

    def error(self, message: str):  # type: ignore[override]
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        sys.exit(2)


def build_parser() -> argparse.ArgumentParser:
    from mechviz import __version__

    parser = _Parser(prog="mechviz", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"mechviz {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    from .analysis import add_commands  # numpy and numba: inside main's Ctrl-C handling

    add_commands(sub)
    # Each of these modules registers its own subcommands and imports viser (or matplotlib)
    # only inside the command it runs, so `analyze` and `simulate` stay light.
    for module in _COMMAND_MODULES:
        importlib.import_module(module).add_commands(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    # Ctrl-C is held from the first instruction until the libraries are imported, so that none
    # of them can swallow it (mechviz.viz.interrupts), and then delivered: status 130, nothing written.
    held = hold_sigint()
    from ..interrupts import exit_status, signals_end_like_ctrl_c

    # SIGTERM and SIGHUP end a command as Ctrl-C does: its children and temporary folders go too
    with signals_end_like_ctrl_c():
        try:
            try:
                from .errors import CliError

                parser = build_parser()
                args = parser.parse_args(argv)
                # a command line of its own (not a caller's list): a command may end the
                # process itself once its work is cleaned up
                args.whole_process = argv is None
                if args.command not in _LIGHT_COMMANDS:
                    importlib.import_module("trimesh")  # viser's and the exhibits' meshes
            finally:
                release_sigint(held)
            if getattr(args, "no_progress", False):
                from ..progress import silence

                silence()
            try:
                return int(args.func(args) or 0)
            except CliError as exc:
                print(f"mechviz: error: {exc}", file=sys.stderr)
                return 2
        except KeyboardInterrupt as exc:  # at any moment, start-up included: one line
            print("mechviz: interrupted", file=sys.stderr)
            return exit_status(exc)


if __name__ == "__main__":
    sys.exit(main())
