"""What every command of the ``mechviz`` command line shares: its error and its number rule."""

from __future__ import annotations

import argparse
import re

from mechviz.dynamics.params import SettingError, parse_number


def command(sub, name: str, about: str, **kwargs) -> argparse.ArgumentParser:
    """Register the sub-command ``name`` on ``sub``: the first paragraph of ``about`` is its
    one-line help in ``mechviz --help``, the rest its description (``mechviz NAME --help``)."""
    head, _, rest = about.strip().partition("\n\n")
    head = " ".join(head.split())
    return sub.add_parser(name, help=head, description=" ".join(rest.split()) or head, **kwargs)


class CliError(Exception):
    """A bad flag or value: reported as one line, exit status 2."""


def number(text: str) -> float:
    """argparse type: a number by the one rule for typed numbers
    (:func:`mechviz.dynamics.params.parse_number`)."""
    try:
        return parse_number("value", text)
    except SettingError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("value ")) from None


def whole(text: str) -> int:
    """argparse type: a whole number by the same rule (ASCII digits, an optional sign, no
    underscores: ``int()`` alone takes ``1_0`` and full-width digits)."""
    t = str(text).strip()
    if not re.fullmatch(r"[+-]?[0-9]+", t, flags=re.ASCII):
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}")
    return int(t)
