"""A recording's chart as files: PNG always, SVG and PDF on request (slides and papers), and
the rule for equal aspect in its pictures.

The chart is drawn once (:func:`mechviz.viz.record.outputs.chart_figure`) and saved in each format
asked for; vector formats are on request because each is a full second drawing of a figure
with every frame's samples. A picture whose two axes share a unit (the orbit ``x``-``y``, the
disk's ``L_x``-``L_z``, the body rates of the polhode, the hoop's configuration space) is drawn
with equal aspect: a circle is a circle.
"""

from __future__ import annotations

import io
import re

#: The formats a chart is written in: PNG always, the others on request.
FORMATS = ("png", "svg", "pdf")
VECTOR_FORMATS = ("svg", "pdf")

_UNIT = re.compile(r"\[([^\]]+)\]\s*$")


def unit_of(label: str) -> str | None:
    """The unit an axis label ends with in brackets (``"x [m]"`` -> ``"m"``), or ``None``."""
    m = _UNIT.search(label)
    return m.group(1).strip() if m else None


def shared_unit(x_label: str, y_label: str) -> bool:
    """Whether two axis labels name the same unit (then one unit is as long on both axes)."""
    u = unit_of(x_label)
    return u is not None and u == unit_of(y_label)


def equal_aspect(ax) -> None:
    """One unit as long on both axes of ``ax``: the data limits widen around what is drawn
    (the axes' box keeps its place in the layout)."""
    ax.set_autoscale_on(True)  # the limits may move to give the aspect
    ax.set_aspect("equal", adjustable="datalim")


def check_formats(formats) -> tuple[str, ...]:
    """``formats`` (names from :data:`VECTOR_FORMATS`, or a comma-separated string of them)
    as a tuple, or ``ValueError`` naming ``plots``."""
    if isinstance(formats, str):
        formats = [f.strip() for f in formats.split(",") if f.strip()]
    out = tuple(dict.fromkeys(str(f).lower() for f in formats))
    bad = [f for f in out if f not in VECTOR_FORMATS]
    if bad:
        raise ValueError(
            f"plots must be among {', '.join(VECTOR_FORMATS)} (PNG is always written); "
            f"got {', '.join(bad)}"
        )
    return out


def save(figure, formats=("png",)) -> dict[str, bytes]:
    """``figure`` saved in each of ``formats``: ``{".png": bytes, ...}``."""
    out = {}
    for fmt in formats:
        buf = io.BytesIO()
        # no creation date in the vector files: the same recording gives the same bytes
        metadata = {"svg": {"Date": None}, "pdf": {"CreationDate": None}}.get(fmt)
        figure.savefig(buf, format=fmt, metadata=metadata)
        out[f".{fmt}"] = buf.getvalue()
    return out
