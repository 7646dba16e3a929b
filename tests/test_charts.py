"""A recording's chart as a person sees it on a slide: pictures whose axes share a unit drawn
with one unit as long on both (the orbit's circle is round), and the chart also as SVG and PDF
when asked for, written with the rest of the recording and listed in its manifest."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from mechviz.viz import record as rec
from mechviz.viz.record import charts
from mechviz.viz.record.outputs import chart_figure
from mechviz.viz.record.run import trace_demo


def _chart(name: str, **overrides):
    d = rec.load_demo(name).with_overrides(**overrides)
    tr = trace_demo(d)
    fig = chart_figure(d, tr, rec.figures(d, tr))
    fig.draw_without_rendering()  # the layout and the aspect are settled at drawing
    return fig


def _axes(fig, xlabel: str):
    found = [ax for ax in fig.get_axes() if ax.get_xlabel() == xlabel]
    assert len(found) == 1, [ax.get_xlabel() for ax in fig.get_axes()]
    return found[0]


def _pixels_per_unit(ax) -> tuple[float, float]:
    o, ex, ey = ax.transData.transform([(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])
    return float(np.hypot(*(ex - o))), float(np.hypot(*(ey - o)))


def test_the_orbit_is_drawn_round_and_the_well_is_not_squeezed():
    fig = _chart("helix", duration=2.0, fps=10)
    orbit = _axes(fig, "x [m]")
    px, py = _pixels_per_unit(orbit)
    assert px == pytest.approx(py, rel=1e-6)
    # the predicted circle, in the picture's pixels: as wide as it is high
    circle = next(ln for ln in orbit.get_lines() if ln.get_label() == "predicted circle")
    pts = orbit.transData.transform(np.column_stack(circle.get_data()))
    width, height = np.ptp(pts, axis=0)
    assert width == pytest.approx(height, rel=1e-3)
    well = _axes(fig, "distance from the axis r [m]")  # r [m] against V_eff [J]: no shared unit
    assert well.get_aspect() == "auto"


@pytest.mark.parametrize(
    ("labels", "shared"),
    [
        (("x [m]", "y [m]"), True),
        (("L_x about A [kg m²/s]", "L_z about A [kg m²/s]"), True),
        (("hoop angle θ1 [rad]", "hoop rate θ1' [rad/s]"), False),
        (("quaternion q0", "quaternion q1"), False),
    ],
)
def test_equal_aspect_goes_with_a_shared_unit(labels, shared):
    assert charts.shared_unit(*labels) is shared


@pytest.mark.slow
def test_the_chart_is_written_as_svg_and_pdf_when_asked(tmp_path):
    d = rec.load_demo("hoop-mode1").with_overrides(duration=1.0, fps=10)
    res = rec.record(d, tmp_path, plots=("svg", "pdf"))
    svg = (tmp_path / "hoop-mode1.svg").read_bytes()
    assert ET.fromstring(svg).tag.endswith("svg")
    pdf = (tmp_path / "hoop-mode1.pdf").read_bytes()
    assert pdf.startswith(b"%PDF") and b"%%EOF" in pdf[-64:]
    manifest = json.loads((tmp_path / "hoop-mode1.json").read_text())
    assert {"hoop-mode1.svg", "hoop-mode1.pdf", "hoop-mode1.png"} <= set(manifest["files"])
    assert res.paths[".svg"].exists() and res.paths[".pdf"].exists()
    # recorded again without them: no name is left pointing at the replaced recording
    rec.record(d, tmp_path)
    assert not any(p.name.endswith((".svg", ".pdf")) for p in tmp_path.iterdir())
    with pytest.raises(ValueError, match="plots"):
        rec.record(d, tmp_path, plots=("eps",))


def test_record_refuses_an_unknown_plot_format_in_one_line(tmp_path):
    from test_cli import mechviz

    r = mechviz("record", "helix", "--out", str(tmp_path), "--plots", "svg,eps")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "--plots" in r.stderr
    assert not any(tmp_path.iterdir())
