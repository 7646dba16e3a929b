"""PNG charts of a benchmark result (matplotlib, imported here only, Agg backend)."""

from __future__ import annotations

import io

from mechviz.dynamics.integrators import METHODS

from .sweeps import TARGETS

OURS_STYLE = {"linestyle": "-", "marker": "o"}
# A method's colour is on its description (Method.chart_color); the peers' are here.
PEER_COLORS = {
    "heyoka": "black",
    "cyrk-dop853": "0.45",
    "cyrk-vern8": "0.6",
    "cyrk-vern7": "0.7",
    "cyrk-py-dop853": "0.8",
}


def color(name: str) -> str | None:
    """The colour of method or peer ``name`` across every chart; ``KeyError`` for a name that
    is neither (a result from another version of the benchmark)."""
    method = METHODS.get(name)
    if method is not None:
        return method.chart_color
    if name not in PEER_COLORS:
        raise KeyError(f"no chart colour for {name!r}: neither a method nor a peer")
    return PEER_COLORS[name]


SCIPY_STYLE = {"linestyle": "--", "marker": "s"}
PEER_STYLE = {"linestyle": ":", "marker": "D", "linewidth": 1.6}
ERROR_CEILING = 1.0  # a relative error above 1 is a failed run: the error axis stops there


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _png(plt, fig) -> bytes:
    """``fig`` as PNG bytes (closed after): charts are written with the results they show, as
    one set, so an interrupted run never leaves new charts beside old results."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    return buf.getvalue()


def _style(m: str) -> dict:
    from .peers import PEERS

    if m in PEERS:
        return PEER_STYLE
    if m in METHODS and METHODS[m].backend == "scipy":
        return SCIPY_STYLE
    return OURS_STYLE


def work_precision(result: dict) -> dict[str, bytes]:
    plt = _plt()
    files: dict[str, bytes] = {}
    for key, pb in result["problems"].items():
        fig, axes = plt.subplots(1, 2, figsize=(13, 7.2))
        by_method: dict[str, list] = {}
        outliers: dict[str, list] = {}
        above: dict[str, int] = {}
        for p in result["points"]:
            if p["problem"] != key or p["error"] is None or not p["seconds"]:
                continue
            if p["error"] > ERROR_CEILING:
                above[p["method"]] = above.get(p["method"], 0) + 1
            elif p.get("status") == "outlier":
                outliers.setdefault(p["method"], []).append(p)
            else:
                by_method.setdefault(p["method"], []).append(p)
        for m, pts in sorted(by_method.items()):
            pts = sorted(pts, key=lambda p: (p["tol"] or 0, -(p["dt"] or 0)), reverse=True)
            err = [max(p["error"], 1e-16) for p in pts]
            n_above = f", {above[m]} above 1 not shown" if m in above else ""
            kw = dict(label=m + n_above, markersize=3.5, color=color(m), **_style(m))
            axes[0].loglog([p["seconds"] for p in pts], err, **kw)
            # evaluations of ours only: a peer counts its own way, a series step is no evaluation
            if m in METHODS and not METHODS[m].series:
                axes[1].loglog([max(p["nfev"], 1) for p in pts], err, **kw)
        for m, pts in outliers.items():
            axes[0].loglog(
                [p["seconds"] for p in pts],
                [p["error"] for p in pts],
                "x",
                color=color(m),
                markersize=7,
                label=f"{m}: timing outlier (flagged, not in the curve)",
            )
        single = result["settings"].get("one_sample_from_s")
        timing = "median" + (f"; one call from {1e3 * single:g} ms" if single else "")
        for ax, xl in zip(
            axes,
            (
                f"wall time per run [s] ({timing})",
                "right-hand-side evaluations (Runge-Kutta and fixed-step)",
            ),
            strict=True,
        ):
            for t in TARGETS:
                ax.axhline(t, color="0.6", linewidth=0.8, linestyle=":")
            ax.axhline(pb["floor"], color="tab:red", linewidth=0.8, linestyle=":")
            ax.set_ylim(top=ERROR_CEILING)
            ax.set_xlabel(xl)
            ax.set_ylabel("relative final error")
            ax.grid(True, which="major", alpha=0.3)
        # One legend under both panels: inside an axis it hid the fastest curves at the
        # tightest errors, the corner a reader looks at first.
        handles, labels = axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=5, fontsize=8, frameon=False)
        fig.suptitle(
            f"{pb['title']}: final error against wall time and evaluations (solid: ours, "
            f"dashed: scipy, dotted: CyRK and heyoka); {result['date']}, "
            f"{result['mode']} run",
            fontsize=10,
        )
        rows = -(-len(labels) // 5)
        fig.tight_layout(rect=(0, 0.02 + 0.027 * rows, 1, 1))
        files[f"work_precision_{key}.png"] = _png(plt, fig)
    return files


def long_run(result: dict) -> dict[str, bytes]:
    plt = _plt()
    data = result["long_run"]
    fig, axes = plt.subplots(1, len(data), figsize=(16, 4.6))
    for ax, (key, res) in zip(axes, data.items(), strict=True):
        for m, r in res["methods"].items():
            err = [max(abs(e), 1e-17) for e in r["energy_error"][1:]]
            ax.semilogy(r["t"][1:], err, label=f"{m} (max {r['max_abs']:.1e})", linewidth=1)
        bounded = [m for m, r in res["methods"].items() if r.get("bounded")]
        grows = [m for m in res["methods"] if m not in bounded]
        what = "; ".join(
            s
            for s in (
                f"bounded: {', '.join(bounded)}" if bounded else "",
                f"growing: {', '.join(grows)}" if grows else "",
            )
            if s
        )
        ax.set_title(
            f"{key}: dt = {res['dt']:g} s, {res['periods']:.0e} periods\n{what}", fontsize=9
        )
        ax.set_xlabel("t [s]")
        ax.set_ylabel("|E - E0| / |E0|")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(
        "Relative energy error over 10^4 periods at one loose step (bounded: the mean "
        "of the last 10 % of samples within 2x of the first 10 %)"
    )
    fig.tight_layout()
    return {"energy_long_run.png": _png(plt, fig)}


def stability(result: dict) -> dict[str, bytes]:
    plt = _plt()
    data = result["stability"]
    fig, ax = plt.subplots(figsize=(10, 6))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, ((m, r), c) in enumerate(zip(data["methods"].items(), colors, strict=False)):
        ax.plot(data["x"], r["theory"], color=c, linewidth=1.2, label=f"{m} ({r['on']})")
        ok = [p for p in r["points"] if p["measured"] is not None]
        ax.plot(
            [p["x"] for p in ok],
            [p["measured"] for p in ok],
            "o",
            color=c,
            markersize=5,
            markerfacecolor="none",
        )
        bad = [p for p in r["points"] if p["measured"] is None]
        if bad:
            ax.plot([p["x"] for p in bad], [1.0] * len(bad), "x", color=c, markersize=6)
        if r["limit"]:
            ax.axvline(r["limit"], color=c, linestyle="--", linewidth=0.9)
            ax.text(
                r["limit"],
                12.0 / 1.35 ** (i % 3),
                f" {m} {r['limit']:.3f}",
                color=c,
                fontsize=7,
                va="top",
            )
    ax.axhline(1.0, color="k", linewidth=0.6)
    ax.set_yscale("log")
    ax.set_ylim(0.4, 15)
    ax.set_xlim(0, 4)
    ax.set_xlabel("omega dt")
    ax.set_ylabel("amplification factor per step (spectral radius)")
    ax.set_title(
        "Stability: theory (lines), measured (circles; x: implicit solve failed), limits (dashed)"
    )
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return {"stability.png": _png(plt, fig)}


def per_step(result: dict) -> dict[str, bytes]:
    plt = _plt()
    rows = result["per_step"]["rows"]
    names = list(rows)
    fig, ax = plt.subplots(figsize=(9, 4.5))
    xs = range(len(names))
    ax.bar([x - 0.2 for x in xs], [rows[n]["numba_ns"] for n in names], 0.4, label="numba")
    ax.bar(
        [x + 0.2 for x in xs],
        [rows[n].get("c_ns") or 0 for n in names],
        0.4,
        label="C -O2 (same run)",
    )
    ax.set_xticks(list(xs), names, rotation=20)
    ax.set_yscale("log")
    ax.set_ylabel("ns per step")
    ax.set_title("Cost of one compiled step")
    ax.legend()
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    return {"per_step.png": _png(plt, fig)}


def render_charts(result: dict) -> dict[str, bytes]:
    """Every chart of ``result``, file name -> PNG bytes, for the caller to write with the
    files they belong with (:func:`mechviz.dynamics.files.write_files_atomically`)."""
    files = work_precision(result)
    for part, chart in (("long_run", long_run), ("stability", stability), ("per_step", per_step)):
        if result.get(part):
            files.update(chart(result))
    return files
