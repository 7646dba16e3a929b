"""The example notebooks (``examples/``) run headless in a fresh kernel of this environment, each
embedded demo ends up in the output as a playable scene, and the committed files carry no
outputs (they stay small)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
NOTEBOOKS = sorted(EXAMPLES.glob("*.ipynb"))


def test_there_is_a_notebook_per_system_and_one_on_methods():
    names = " ".join(p.stem for p in NOTEBOOKS)
    for word in ("cyclotron", "disk", "hoop", "methods"):
        assert word in names


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_committed_notebook_has_no_outputs(path):
    nb = json.loads(path.read_text())
    for cell in nb["cells"]:
        if cell["cell_type"] == "code":
            assert cell["outputs"] == [] and cell["execution_count"] is None, path.name
    assert path.stat().st_size < 20_000


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs_and_shows_its_demo(path, tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(path, as_version=4)
    # Run in a scratch folder, so nothing a notebook writes lands in the checkout.
    client = nbclient.NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
    shows = [c for c in nb.cells if c.cell_type == "code" and "notebook.show(" in c.source]
    assert shows, "each example embeds a recorded demo"
    for cell in shows:
        html = "".join(
            o.get("data", {}).get("text/html", "") for o in cell.outputs if "data" in o
        )
        assert "mechviz-embed" in html and "__VISER_EMBED_DATA__" in html, cell.source
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert not errors
