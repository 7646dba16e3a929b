"""What a recording writes besides the scene: the traces as CSV, a chart, the manifest.

``DEMO.csv`` holds one row per run, member and frame: ``run, member, t``, the state (names from
:mod:`dynamics`), the energy, the relative energy error and the error against the exact
solution or the tight reference (:class:`mechviz.dynamics.Simulation`), then the exhibit's other
quantities, as the viewer's plot names them (:meth:`mechviz.viz.model.base.ExhibitModel.plot_variables`: the
charge's ``r``, ``p_r``, ``p_phi``, ``V_eff``; the hoop's modal coordinates ``q1``, ``q2``; the
disk's ``L``). ``DEMO.png`` charts the motion with the predictions marked, the energy error and
the error, and below them the exhibit's pictures (:meth:`~mechviz.viz.model.base.ExhibitModel.pictures`:
the well, configuration space, the phase portrait, the polhode) with their exact curves, drawn
by the viewer's own :func:`mechviz.viz.model.plot.draw_xy`. ``DEMO.json`` is the manifest; its
``csv_columns`` gives each CSV column's ``units`` and ``long_name`` (:func:`csv_columns`). Every
number in the CSV is written as a float (``1.0``, never ``1``), so a reader that guesses types
reads each measured column as floating point.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import platform
import re
import time
from importlib import metadata
from typing import Any

import msgspec
import numpy as np

from mechviz import dynamics
from mechviz.dynamics.simulation import RESOLVED_FACTOR

from ..model import MODELS
from ..model.hooks import CHART_COLOURS, MAX_PERIOD_MARKS  # noqa: F401  (re-exported)
from ..model.hooks import mark_periods as _mark_periods  # noqa: F401  (re-exported)
from ..model.plot import Curve, Samples, draw_xy
from . import charts
from .demo import Demo
from .run import Traces


def samples(tr: Traces, label: str, member: int = 0) -> Samples:
    """One member of one run of the traces as the viewer's plot takes them."""
    err = tr.error[label]
    K = len(tr.times[label])
    return Samples(
        tr.times[label],
        tr.states[label][:, member],
        tr.energy[label][:, member],
        tr.energy_error[label][:, member],
        np.full(K, np.nan) if err is None else err[:, member],
    )


def ghost_samples(tr: Traces) -> Samples | None:
    """Linear theory's states (the hoop's ghost) as plot samples; no energy or error."""
    if tr.ghost is None:
        return None
    nan = np.full(len(tr.t), np.nan)
    return Samples(tr.t, tr.ghost[:, 0], nan, nan, nan)


def derived_variables(d: Demo) -> dict:
    """The exhibit's plot quantities beyond the state, energy and errors (the CSV's last columns)."""
    names = set(dynamics.SYSTEMS[_system_name(d)].state_names) | {
        "t",
        "energy",
        "energy_error",
        "error",
    }
    variables = MODELS[d.exhibit].plot_variables(d.config())
    return {n: v for n, v in variables.items() if n not in names}


_LABEL_UNIT = re.compile(r"^(.*?)\s*\[([^\]]*)\]$")


def _split_label(label: str) -> tuple[str, str]:
    """``"x [m]"`` -> ``("x", "m")``; a label without a unit has ``""``."""
    m = _LABEL_UNIT.match(label)
    return (m.group(1), m.group(2)) if m else (label, "")


def csv_columns(d: Demo) -> dict[str, dict[str, str]]:
    """Each column of ``DEMO.csv`` in order: its ``units`` (SI; ``""`` for a label, a count or
    a ratio) and ``long_name``."""
    system = dynamics.SYSTEMS[_system_name(d)]
    cols = {
        "run": ("the run: its method, or linear-theory", ""),
        "member": ("member of the run's ensemble (0 for a single start)", ""),
        "t": ("simulated time", "s"),
    }
    for n in system.state_names:
        cols[n] = _split_label(system.state_labels.get(n, n))
    cols["energy"] = ("total energy", "J")
    cols["energy_error"] = ("relative energy error (E - E0) / |E0|", "")
    cols["error"] = ("relative error against the exact solution or the tight reference", "")
    for n, v in derived_variables(d).items():
        cols[n] = _split_label(v.label)
    return {n: {"units": u, "long_name": name} for n, (name, u) in cols.items()}


def _number(x: float) -> str:
    """``x`` in 10 significant digits, always as a float: ``1.0``, ``2.5e-08``, ``nan``."""
    s = f"{x:.10g}"
    return s if any(c in s for c in ".eEn") else f"{s}.0"  # "n": nan and inf


def traces_csv(d: Demo, tr: Traces) -> bytes:
    """The traces as CSV (long format, one row per run, member and frame); the columns are
    :func:`csv_columns`."""
    names = list(dynamics.SYSTEMS[_system_name(d)].state_names)
    extra = derived_variables(d)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["run", "member", "t", *names, "energy", "energy_error", "error", *extra])
    fmt = _number

    def columns(smp: Samples) -> np.ndarray:
        if not extra:
            return np.zeros((len(smp), 0))
        with np.errstate(all="ignore"):
            return np.column_stack([v.values(smp) for v in extra.values()])

    K = len(tr.t)
    for label, S in tr.states.items():
        err = tr.error[label]
        for j in range(S.shape[1]):
            more = columns(samples(tr, label, j))
            for k in range(K):
                w.writerow(
                    [
                        label,
                        j,
                        fmt(tr.times[label][k]),
                        *map(fmt, S[k, j]),
                        fmt(tr.energy[label][k, j]),
                        fmt(tr.energy_error[label][k, j]),
                        "" if err is None else fmt(err[k, j]),
                        *map(fmt, more[k]),
                    ]
                )
    ghost = ghost_samples(tr)
    if ghost is not None:
        more = columns(ghost)
        for k in range(K):
            w.writerow(
                [
                    "linear-theory",
                    0,
                    fmt(tr.t[k]),
                    *map(fmt, tr.ghost[k, 0]),
                    "",
                    "",
                    "",
                    *map(fmt, more[k]),
                ]
            )
    return buf.getvalue().encode()


def draw_pictures(d: Demo, tr: Traces, axes) -> None:
    """The exhibit's pictures on ``axes`` (one each): the main run's path, linear theory's
    where there is a ghost, and the exact curves, as the viewer's plot draws them."""
    cls, config = MODELS[d.exhibit], d.config()
    variables = cls.plot_variables(config)
    main = samples(tr, tr.main)
    ghost = ghost_samples(tr)
    for ax, (x, y) in zip(axes, cls.pictures(config), strict=True):
        curves = list(cls.plot_curves(config, x, y, main))
        if ghost is not None:
            with np.errstate(all="ignore"):
                curves.append(
                    Curve(
                        variables[x].values(ghost),
                        variables[y].values(ghost),
                        "linear theory",
                        dashed=True,
                    )
                )
        draw_xy(ax, variables, x, y, main, curves, path_label=tr.main)
        if charts.shared_unit(variables[x].label, variables[y].label):
            charts.equal_aspect(ax)
        ax.xaxis.label.set_fontsize(8)
        ax.yaxis.label.set_fontsize(8)
        ax.tick_params(labelsize=7)


def chart_png(d: Demo, tr: Traces, figs: list[dict[str, Any]]) -> bytes:
    """:func:`chart_figure` as PNG (:mod:`mechviz.viz.record.charts` saves it in other formats too)."""
    return charts.save(chart_figure(d, tr, figs))[".png"]


def chart_figure(d: Demo, tr: Traces, figs: list[dict[str, Any]]):
    """Three panels: the motion with the predictions marked, the energy error, the error."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    p = d.config().physics()
    pictures = MODELS[d.exhibit].pictures(d.config())
    fig = Figure(figsize=(9, 9.5 + 4.0 * bool(pictures)), dpi=100, layout="constrained")
    top, bottom = fig.subfigures(2, 1, height_ratios=(9.5, 4.0)) if pictures else (fig, None)
    ax1, ax2, ax3, ax4 = top.subplots(4, 1, height_ratios=(3, 2, 2, 1.1))
    if bottom is not None:
        draw_pictures(d, tr, np.atleast_1d(bottom.subplots(1, len(pictures))))
    ax2.sharex(ax1)
    ax3.sharex(ax1)
    ax4.axis("off")
    colours = CHART_COLOURS
    # the first panel is the system's own: its model draws it (.model.hooks)
    MODELS[d.exhibit].draw_motion_chart(ax1, d, tr, p)
    ax1.legend(fontsize=7, loc="upper right")
    for lbl, c in zip(tr.states, colours, strict=False):
        E = np.abs(tr.energy_error[lbl]).max(axis=1)
        ax2.semilogy(tr.times[lbl], np.maximum(E, 1e-17), color=c, lw=1, label=lbl)
        if tr.error[lbl] is not None:
            e = np.nanmax(tr.error[lbl], axis=1)
            ax3.semilogy(
                tr.times[lbl],
                np.maximum(e, 1e-17),
                color=c,
                lw=1,
                label=f"{lbl} vs {tr.reference[lbl]}",
            )
    for fg in figs:
        if fg["name"].startswith("final energy error") and fg["predicted"]:
            ax2.axhline(
                abs(fg["predicted"]),
                color="k",
                ls="--",
                lw=1,
                label="predicted final, " + fg["name"].split(", ")[-1],
            )
    ax2.set_ylabel("|relative energy error|")
    ax2.legend(fontsize=7)
    ax3.set_ylabel("relative error")
    ax3.set_xlabel("simulated time t [s]")
    if ax3.lines:
        ax3.legend(fontsize=7)
    else:
        ax3.text(
            0.5, 0.5, "no reference solution", ha="center", va="center", transform=ax3.transAxes
        )
    lines = [
        f"{f['name']}: {f['measured']:.6g}"
        + (
            ""
            if f["predicted"] is None
            else f"  ({f.get('theory', 'theory')} {f['predicted']:.6g})"
        )
        for f in figs
        if f["measured"] is not None
    ]
    fig.suptitle(f"{d.title}\n{step_text(tr)}", fontsize=11)
    if lines:
        ax4.text(
            0.0,
            1.0,
            "measured against predicted\n" + "\n".join(lines[:7]),
            transform=ax4.transAxes,
            fontsize=8,
            va="top",
            family="monospace",
        )
    return fig


def step_text(tr: Traces) -> str:
    """Each run's method and step, in words."""
    return "; ".join(f"{label}: {r['title']}, {r['step']}" for label, r in tr.runs.items())


def package_versions() -> dict[str, str]:
    out = {"python": platform.python_version()}
    for dist in ("mechviz", "numpy", "scipy", "numba", "viser", "trimesh", "matplotlib"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    return out


def manifest(d: Demo, tr: Traces, figs: list[dict[str, Any]], *, wall: float) -> dict[str, Any]:
    """The manifest: the demo, what ran (methods, steps, work), measured against predicted
    figures, final errors and package versions."""
    return {
        "demo": d.name,
        "title": d.title,
        "description": d.description,
        "exhibit": d.exhibit,
        "motion": d.motion,
        "parameters": dataclasses.asdict(d.config().physics()),
        "initial": msgspec.to_builtins(d.initial),
        "method": d.method,
        "step": step_text(tr),
        "dt": d.dt,
        "rtol": d.rtol,
        "runs": tr.runs,
        "events": [{"t": e["t"], "action": e["action"], "dv": e["dv"]} for e in tr.event_log],
        "duration": d.duration,
        "fps": d.fps,
        "frames": d.frames,
        "speed": d.speed,
        "simulated_time": float(tr.t[-1]),
        "camera": msgspec.to_builtins(d.camera),
        "csv_columns": csv_columns(d),
        "figures": figs,
        "final_errors": final_errors(tr),
        "versions": package_versions(),
        "recorded_at": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "record_seconds": round(wall, 3),
        "demo_file": d.as_dict(),
    }


def final_errors(tr: Traces) -> dict[str, dict[str, Any]]:
    out = {}
    for label in tr.states:
        E = tr.energy_error[label]
        e = tr.error[label]
        bar = tr.reference_error.get(label)
        bar_final = None if bar is None or e is None else float(np.nanmax(bar[-1]))
        out[label] = {
            "energy_error_final": float(np.max(np.abs(E[-1]))),
            "energy_error_max": float(np.max(np.abs(E))),
            "error_final": None if e is None else float(np.nanmax(e[-1])),
            "error_max": None if e is None else float(np.nanmax(e)),
            "error_against": tr.reference[label],
            # the reference's own error at the end, as measured, and whether the error is a
            # figure about the method (well above it) rather than about the reference
            "reference_error_final": bar_final,
            "error_resolved": None
            if bar_final is None
            else float(np.nanmax(e[-1])) >= RESOLVED_FACTOR * bar_final,
            "steps": tr.steps[label],
            "rhs_evaluations": tr.nfev[label],
        }
    return out


def _system_name(d: Demo) -> str:
    """The driver's name of the system a demo runs (the disk's depends on its motion)."""
    spec = dynamics.SPECS[d.exhibit]
    start = spec.start_values({"motion": d.motion} if d.motion else {})
    return spec.build(spec.parameters(d.parameters), start)[0].name
