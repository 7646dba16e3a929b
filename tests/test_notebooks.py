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


@pytest.mark.slow
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
        html = "".join(o.get("data", {}).get("text/html", "") for o in cell.outputs if "data" in o)
        assert "mechviz-embed" in html and "__VISER_EMBED_DATA__" in html, cell.source
    errors = [
        o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"
    ]
    assert not errors


def test_an_embedded_demo_weighs_about_0_8_mb_and_a_saved_one_a_few_hundred_bytes(tmp_path):
    from viz import notebook

    inline = notebook.show("helix", duration=1.0, fps=5)
    assert 0.5e6 < inline.size_bytes < 1.5e6
    assert "__VISER_EMBED_DATA__" in inline._repr_html_()
    assert [f["name"] for f in inline.figures]  # measured against predicted, below the player
    saved = notebook.show("helix", duration=1.0, fps=5, save=tmp_path / "helix.html")
    assert saved.size_bytes < 2_000
    assert (tmp_path / "helix.html").read_bytes() == saved.page


def test_show_refuses_a_change_the_demo_cannot_take():
    from viz import notebook

    with pytest.raises(ValueError, match="dv"):
        notebook.show("helix", dv=0.5)
    with pytest.raises(ValueError, match="fps"):
        notebook.show("helix", fps=0)


def test_live_embeds_the_running_viewer_and_stops_it():
    import re
    import urllib.request

    from viz import notebook

    view = notebook.live(port=0)
    try:
        url = re.search(r'src="([^"]+)"', view._repr_html_()).group(1)
        assert url.startswith("http://127.0.0.1:")
        assert notebook.live(port=0)._repr_html_() == view._repr_html_()  # one viewer per kernel
        with urllib.request.urlopen(url, timeout=10) as resp:
            assert resp.status == 200 and b"<html" in resp.read(2000).lower()
    finally:
        notebook.stop()
