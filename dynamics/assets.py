"""Where the project's data files are: ``assets/`` beside the source in a checkout (and an
editable install), ``share/mechviz`` in the installed prefix otherwise (a wheel carries them
there: ``pip install .``, ``pipx install``)."""

from __future__ import annotations

import sys
from pathlib import Path

_CHECKOUT = Path(__file__).resolve().parents[1] / "assets"


def asset(*parts: str) -> Path:
    """The path of a data file or folder, e.g. ``asset("demos")``."""
    base = _CHECKOUT if _CHECKOUT.is_dir() else Path(sys.prefix) / "share" / "mechviz"
    return base.joinpath(*parts)
