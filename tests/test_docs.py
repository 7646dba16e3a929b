"""The site (``make docs``): built from docs/ with warnings as errors, then read in headless
Chromium as a visitor would: the home page, a physics page with its equations typeset, the API
page of ``simulate``, a tutorial with the output its cells printed, and a gallery entry whose
recording plays. Also: the README is a front door whose every link resolves, and quotes no
benchmark figure."""

from __future__ import annotations

import http.server
import os
import re
import subprocess
import sys
import threading
from functools import partial
from pathlib import Path

import pytest
from browser import open_page, require_browser
from waiting import scaled, wait_until

ROOT = Path(__file__).resolve().parents[1]


def test_the_readme_is_a_front_door_whose_links_resolve():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= 200
    assert "<!-- bench:" not in readme  # the benchmark's figures live on the speed page
    links = re.findall(r"\]\(([^)#\s]+)", readme)
    local = [link for link in links if not re.match(r"[a-z]+://", link)]
    assert len(local) >= 10, local
    missing = [link for link in local if not (ROOT / link).exists()]
    assert not missing, missing
    for page in (ROOT / "docs").glob("*.md"):  # every page the README names is on the site
        if page.name in readme:
            assert page.stem in (ROOT / "docs" / "index.md").read_text(), page.name


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "MECHVIZ_DOCS_DEMOS": "helix"}  # one gallery entry is enough here
    build = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-W",
            "--keep-going",
            "-q",
            "-b",
            "html",
            "docs",
            str(out),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=scaled(3000),
        env=env,
    )
    assert build.returncode == 0, build.stdout[-3000:] + build.stderr[-3000:]
    return out


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args) -> None:
        pass


@pytest.fixture(scope="module")
def served(site):
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), partial(_Quiet, directory=str(site)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{server.server_address[1]}"
    server.shutdown()


@pytest.mark.slow
@pytest.mark.browser
def test_the_site_reads_as_a_visitor_sees_it(served):
    require_browser()
    with open_page(f"{served}/index.html", wait_connected=False) as page:
        _read_the_site(page, served)


def _read_the_site(page, served: str) -> None:
    assert "mechviz" in page.title()
    for name in (
        "Getting started",
        "The viewer",
        "Python API",
        "Tutorials",
        "Gallery",
        "Changelog",
    ):
        assert page.get_by_role("link", name=name).first.is_visible(), name

    # the physics page: its equations typeset by MathJax (served with the site, offline)
    page.goto(f"{served}/physics.html")
    wait_until(
        lambda: page.evaluate("document.querySelectorAll('mjx-container').length") >= 5,
        scaled(60),
        "MathJax to typeset the physics page's equations",
    )

    # the API page documents simulate with its signature and its units
    page.goto(f"{served}/api.html")
    sig = page.locator("#mechviz\\.dynamics\\.api\\.simulate")
    assert sig.count() == 1 and "t_end" in sig.inner_text()

    # a tutorial shows what its cells printed when the site was built
    page.goto(f"{served}/_generated/tutorials/01-cyclotron.html")
    outputs = page.locator(".cell_output").all_inner_texts()
    assert any("measured gyrofrequency" in text for text in outputs), outputs[:3]

    # a gallery entry's recording plays: its time advances in the embedded player
    page.goto(f"{served}/_generated/gallery/helix.html")
    box = page.locator("iframe.mechviz-recording").bounding_box()
    assert box and box["height"] > 300
    frame = page.frame_locator("iframe.mechviz-recording")

    def playhead() -> float | None:
        # the player's time box (seconds) beside its play button
        texts = frame.locator("input").evaluate_all("els => els.map(e => e.value)")
        times = [float(t) for t in texts if re.fullmatch(r"\d+(\.\d+)?", t or "")]
        return times[0] if times else None

    first = wait_until(playhead, scaled(90), "the recording's player to show its time")
    wait_until(
        lambda: (t := playhead()) is not None and t != first,
        scaled(90),
        "the recording to play (its time to move)",
    )


@pytest.mark.parametrize("module", ["mechviz.dynamics.api"])
def test_the_examples_in_the_api_reference_run(module):
    """The docstrings' examples (``>>>``) the API reference shows give what they say."""
    import doctest
    import importlib

    mod = importlib.import_module(module)
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted >= 5 and result.failed == 0, result
