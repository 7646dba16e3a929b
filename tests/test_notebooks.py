"""The example notebooks (``examples/``) run headless in a fresh kernel of this environment, each
embedded demo ends up in the output once, small, as a still of the scene and a playable page, and
the committed files carry no outputs (they stay small). Opened in JupyterLab without being
trusted, an executed example still shows its scene; trusted, it plays."""

from __future__ import annotations

import base64
import contextlib
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from browser import require_browser
from waiting import scaled, wait_until

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
NOTEBOOKS = sorted(EXAMPLES.glob("*.ipynb"))
MB = 1_000_000


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
def test_an_example_uses_only_the_documented_api(path):
    """mechviz reached only through mechviz.dynamics.api and mechviz.viz.notebook (the surface the README
    documents), never a module behind them."""
    import ast

    nb = json.loads(path.read_text())
    used = set()
    for cell in nb["cells"]:
        if cell["cell_type"] == "code":
            for node in ast.walk(ast.parse("".join(cell["source"]))):
                if isinstance(node, ast.ImportFrom):
                    used |= {f"{node.module}.{a.name}" for a in node.names}
                elif isinstance(node, ast.Import):
                    used |= {a.name for a in node.names}
    ours = {u for u in used if u.split(".")[0] == "mechviz"}
    assert ours <= {"mechviz.dynamics.api", "mechviz.viz.notebook"}, ours


_executed: dict[Path, Path] = {}


def executed(path: Path, tmp_path_factory) -> Path:
    """``path`` run by nbclient in a fresh kernel, in a scratch folder (nothing a notebook writes
    lands in the checkout), and saved there with its outputs; once per test session."""
    if path not in _executed:
        nbformat = pytest.importorskip("nbformat")
        nbclient = pytest.importorskip("nbclient")
        folder = tmp_path_factory.mktemp(path.stem)
        nb = nbformat.read(path, as_version=4)
        client = nbclient.NotebookClient(
            nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": str(folder)}}
        )
        client.execute()
        nbformat.write(nb, folder / path.name)  # unsigned: untrusted wherever it is opened
        _executed[path] = folder / path.name
    return _executed[path]


def _show_cells(nb: dict) -> list[dict]:
    return [
        c
        for c in nb["cells"]
        if c["cell_type"] == "code" and "notebook.show(" in "".join(c["source"])
    ]


@pytest.mark.slow
@pytest.mark.browser  # the still is taken by Chromium
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs_and_shows_its_demo_once_small_with_a_still(path, tmp_path_factory):
    require_browser()
    nb = json.loads(executed(path, tmp_path_factory).read_text())
    errors = [
        o
        for c in nb["cells"]
        if c["cell_type"] == "code"
        for o in c["outputs"]
        if o["output_type"] == "error"
    ]
    assert not errors
    shows = _show_cells(nb)
    assert shows, "each example embeds a recorded demo"
    for cell in shows:
        outs = cell["outputs"]
        # no banner or any other print: the still, then the player, nothing else
        assert [o["output_type"] for o in outs] == ["display_data", "display_data"], outs
        still, player = (o["data"] for o in outs)
        assert set(still) == {"image/png", "text/plain"}
        assert set(player) == {"text/html", "text/plain"}
        html = "".join(player["text/html"])
        assert "mechviz-embed" in html and html.count("__VISER_EMBED_DATA__") == 1
        for data in (still, player):
            assert len("".join(data["text/plain"])) < 200  # a line, not the page again
        assert len(json.dumps(outs)) < 1 * MB
        picture = _png(base64.b64decode("".join(still["image/png"])))
        assert _colours(picture) > 200  # a drawn scene, not a blank canvas


@pytest.mark.slow
@pytest.mark.browser
def test_an_executed_example_rendered_as_a_static_page_keeps_its_still(tmp_path_factory):
    """nbconvert's HTML, as nbviewer renders a notebook: the still and the player; with its
    HTML outputs sanitized, as GitHub renders them: the still without the player."""
    require_browser()
    nbformat = pytest.importorskip("nbformat")
    nbconvert = pytest.importorskip("nbconvert")
    nb = nbformat.read(executed(EXAMPLES / "01-cyclotron.ipynb", tmp_path_factory), 4)
    still = "".join(_show_cells(nb)[0]["outputs"][0]["data"]["image/png"]).replace("\n", "")
    for sanitized in (False, True):
        page, _ = nbconvert.HTMLExporter(sanitize_html=sanitized).from_notebook_node(nb)
        assert f"data:image/png;base64,{still}" in page.replace("\n", "")
        assert ("<iframe" in page) is not sanitized


def _png(data: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))


def _colours(img: np.ndarray) -> int:
    return len(np.unique(img.reshape(-1, 3), axis=0))


@pytest.mark.slow
@pytest.mark.browser
def test_an_executed_example_opened_untrusted_in_jupyterlab_shows_its_scene(
    tmp_path_factory, tmp_path
):
    """JupyterLab drops the player's ``<iframe>`` from an untrusted notebook: the still (a
    PNG output) shows the scene there. Once trusted, the player is there too."""
    require_browser()
    pytest.importorskip("jupyterlab")
    from playwright.sync_api import sync_playwright

    from mechviz.viz.chromium import find_chromium, first_page, launch

    nb_path = executed(EXAMPLES / "01-cyclotron.ipynb", tmp_path_factory)
    with _jupyterlab(nb_path.parent, tmp_path) as (url, token, env):
        page_url = f"{url}lab/tree/{nb_path.name}?token={token}"
        # a short profile path: Chromium's socket inside it must fit a Unix socket's 108 bytes
        profile = tempfile.mkdtemp(prefix="mechviz-chromium-")
        with sync_playwright() as pw, contextlib.ExitStack() as clean:
            clean.callback(shutil.rmtree, profile, ignore_errors=True)
            ctx = launch(pw, profile, find_chromium(), 1280, 2400)
            ctx.set_default_timeout(scaled(60) * 1000)
            try:
                page = first_page(ctx)
                page.goto(page_url)
                embed = page.locator(".jp-OutputArea-output .mechviz-embed")
                embed.wait_for()
                still = page.locator(".jp-OutputArea-output.jp-RenderedImage img")
                wait_until(
                    lambda: still.count() and still.first.evaluate("i => i.naturalWidth") > 0,
                    60,
                    "the still to be shown",
                )
                assert page.locator(".jp-OutputArea-output iframe").count() == 0  # untrusted
                shot = _png(still.first.screenshot())
                assert _colours(shot) > 200
                page.screenshot(path=str(tmp_path / "untrusted.png"))
                # trusted (as after `jupyter trust`): the player is shown as well
                subprocess.run(
                    [sys.executable, "-m", "jupyter", "trust", str(nb_path)],
                    check=True,
                    env=env,
                    capture_output=True,
                    timeout=scaled(120),
                )
                page.reload()
                frames = page.locator(".jp-OutputArea-output .mechviz-embed iframe")
                frames.first.wait_for()
                assert still.count() >= 1
            finally:
                ctx.close()


@contextlib.contextmanager
def _jupyterlab(root: Path, tmp: Path):
    """A JupyterLab server on 127.0.0.1 serving ``root``, with configuration, data (the trust
    database) and runtime folders of its own under ``tmp``: yields its URL, token and env."""
    token = os.urandom(12).hex()
    dirs = {
        k: tmp / k.lower()
        for k in (
            "JUPYTER_CONFIG_DIR",
            "JUPYTER_DATA_DIR",
            "JUPYTER_RUNTIME_DIR",
            "JUPYTERLAB_SETTINGS_DIR",
            "JUPYTERLAB_WORKSPACES_DIR",
        )
    }
    for d in dirs.values():
        d.mkdir()
    env = {**os.environ, **{k: str(v) for k, v in dirs.items()}}
    log = open(tmp / "jupyterlab.log", "wb")  # closed below
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "jupyterlab",
            "--no-browser",
            "--allow-root",  # CI runs as root
            "--ServerApp.ip=127.0.0.1",
            "--ServerApp.port=0",
            f"--IdentityProvider.token={token}",
            f"--ServerApp.root_dir={root}",
        ],
        env=env,
        stdout=log,
        stderr=subprocess.STDOUT,
        cwd=tmp,
    )
    try:

        def served():
            for f in dirs["JUPYTER_RUNTIME_DIR"].glob("jpserver-*.json"):
                with contextlib.suppress(ValueError, OSError):
                    info = json.loads(f.read_text())
                    with urllib.request.urlopen(
                        f"{info['url']}api/status?token={token}", timeout=5
                    ) as r:
                        if r.status == 200:
                            return info["url"]
            assert proc.poll() is None, (tmp / "jupyterlab.log").read_text()[-2000:]
            return None

        url = wait_until(served, 120, "JupyterLab to serve")
        yield url, token, env
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=scaled(30))
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()


@pytest.mark.slow
def test_an_embed_is_stored_once_and_a_saved_one_links_to_its_files(tmp_path, capfd, monkeypatch):
    from mechviz.viz import notebook

    monkeypatch.chdir(tmp_path)  # a notebook's folder: the page is saved beside it

    inline = notebook.show("helix", duration=1.0, fps=5, still=False)
    assert 0.5 * MB < inline.size_bytes < 1 * MB
    assert len(repr(inline)) < 200  # the text form Jupyter keeps beside the page
    assert "__VISER_EMBED_DATA__" in inline._repr_html_()
    assert [f["name"] for f in inline.figures]  # measured against predicted, below the player
    saved = notebook.show("helix", duration=1.0, fps=5, still=False, save="helix.html")
    assert saved.size_bytes < 1_000
    assert (tmp_path / "helix.html").read_bytes() == saved.page
    out, err = capfd.readouterr()
    assert "viser" not in out + err  # no server banner, no "Server stopped"


@pytest.mark.slow
@pytest.mark.browser
def test_a_saved_embed_writes_its_still_beside_the_page(tmp_path, monkeypatch):
    require_browser()
    from mechviz.viz import notebook

    monkeypatch.chdir(tmp_path)
    saved = notebook.show("helix", duration=1.0, fps=5, save="demos/helix.html")
    picture = _png((tmp_path / "demos" / "helix.png").read_bytes())
    assert picture.shape == (450, 800, 3) and _colours(picture) > 200
    html = saved._repr_html_()
    assert '<img src="demos/helix.png"' in html and '<a href="demos/helix.html"' in html
    assert saved.size_bytes < 1_000


def test_show_refuses_a_change_the_demo_cannot_take(tmp_path):
    from mechviz.viz import notebook

    with pytest.raises(ValueError, match="dv"):
        notebook.show("helix", dv=0.5)
    with pytest.raises(ValueError, match="fps"):
        notebook.show("helix", fps=0)
    with pytest.raises(ValueError, match="save"):
        notebook.show("helix", save=tmp_path / "helix.png")


def test_live_embeds_the_running_viewer_and_stops_it(capfd):
    import re

    from mechviz.viz import notebook

    view = notebook.live(port=0)
    try:
        url = re.search(r'src="([^"]+)"', view._repr_html_()).group(1)
        assert url.startswith("http://127.0.0.1:")
        assert notebook.live(port=0)._repr_html_() == view._repr_html_()  # one viewer per kernel
        with urllib.request.urlopen(url, timeout=10) as resp:
            assert resp.status == 200 and b"<html" in resp.read(2000).lower()
    finally:
        notebook.stop()
    out, err = capfd.readouterr()
    assert "viser" not in out + err
