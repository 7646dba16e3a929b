"""Sphinx configuration of mechviz's site: ``make docs`` builds it (offline, warnings as errors)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

from mechviz import __version__  # noqa: E402

project = "mechviz"
author = "the mechviz developers"
copyright = "the mechviz developers, MIT licence"
version = release = __version__

extensions = [
    "myst_nb",  # Markdown pages (MyST) and the example notebooks, executed
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",  # the docstrings' NumPy-style sections
    "sphinx.ext.mathjax",
    "sphinx.ext.intersphinx",
    "mechviz_docs",  # the command-line and demo-file references, the gallery
]

# Pages only: the benchmark's generated folder, the images and the tools are not pages.
exclude_patterns = ["_build", "bench/**", "img/**", "_ext/**", "**.ipynb_checkpoints", "Thumbs.db"]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# The tutorials run when the site is built (a failing cell fails the build).
nb_execution_mode = os.environ.get("MECHVIZ_DOCS_EXECUTE", "force")
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True

autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
intersphinx_mapping: dict[str, tuple[str, str | None]] = {}  # offline: nothing fetched

html_theme = "furo"
html_title = f"mechviz {release}"
html_static_path: list[str] = []  # the extension adds MathJax and the gallery's recordings
# MathJax is served with the site (the extension fetches it once from the npm registry into
# build/docs-tools), never from a CDN: the site works offline, in a hall without a network.
mathjax_path = "mathjax/es5/tex-chtml.js"

suppress_warnings = ["myst.header"]
