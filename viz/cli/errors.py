"""What every command of the ``mechviz`` command line shares: its error and its number rule."""

from __future__ import annotations

import argparse

from dynamics.params import SettingError, parse_number


class CliError(Exception):
    """A bad flag or value: reported as one line, exit status 2."""


def number(text: str) -> float:
    """argparse type: a number by the one rule for typed numbers
    (:func:`dynamics.params.parse_number`)."""
    try:
        return parse_number("value", text)
    except SettingError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("value ")) from None
