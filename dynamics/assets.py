"""Where the project's data files are: the package ``mechviz.assets`` (the folder ``assets/`` of a
checkout), found with :mod:`importlib.resources`, so that every kind of install (a venv, pipx,
``pip install --user``, ``pip install --target``, editable) reads the same files."""

from __future__ import annotations

from importlib import resources
from pathlib import Path


def asset(*parts: str) -> Path:
    """The path of a data file or folder, e.g. ``asset("demos")``.

    The package is always installed as plain files (a wheel unpacked by pip), so the traversable
    ``importlib.resources`` gives is a real folder; a zipped install is refused here rather than
    read half."""
    root = resources.files("mechviz.assets")
    if not isinstance(root, Path):
        raise RuntimeError(f"mechviz's data must be installed as files, not inside {root!s}")
    return root.joinpath(*parts)
