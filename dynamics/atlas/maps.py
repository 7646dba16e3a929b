"""The atlas drawn: one panel per method, labelled axes, a colour bar, and theory's lines on top.

- stability: ``log10 |energy error|`` over (amplitude, dt), the measured boundary (the contour
  between bounded and unbounded cells) in white and the linear theory's limit ``dt = x_max /
  omega_fast`` dashed in black;
- chaos: the largest Lyapunov exponent over a section of the hoop's starts; on the plane at rest
  also the two normal-mode lines, and the mode-1 line drawn thick where the nonlinear mode 1 is
  unstable;
- accuracy: ``log10`` of the error after the run over (amplitude, step or tolerance).

Cells not computed (an interrupted run) are left blank. matplotlib's Agg backend: no display.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

from .store import spec_of
from .theory import amplitude_label, normal_mode_slopes

AXIS_LABELS = {
    "dt": "step dt [s]",
    "rtol": "tolerance rtol",
    "theta1": "hoop angle theta1 at rest [rad]",
    "theta2": "bead angle theta2 at rest [rad]",
}
#: Other sections of the chaos map: the axes' labels, and what the other coordinates are.
SECTION_LABELS = {
    "theta1": ("hoop angle theta1 [rad]", "hoop rate theta1' [rad/s]", "theta2 = theta2' = 0"),
    "theta2": ("bead angle theta2 [rad]", "bead rate theta2' [rad/s]", "theta1 = theta1' = 0"),
}


def _log10_abs(a: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.log10(np.abs(a))
    return np.where(np.isfinite(a), out, np.where(np.isnan(a), np.nan, np.inf))


def figure(ds: xr.Dataset):
    """The map of ``ds`` as a matplotlib Figure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    spec = spec_of(ds)
    y, x = spec.y.name, spec.x.name
    methods = [str(m) for m in ds["method"].values]
    n = len(methods)
    cols = min(n, 3)
    rows = -(-n // cols)
    fig, grid = plt.subplots(
        rows, cols, figsize=(4.6 * cols + 1.0, 4.2 * rows), squeeze=False, layout="constrained"
    )
    axes = grid.ravel()
    for ax in axes[n:]:
        ax.set_visible(False)
    xs, ys = ds[x].values, ds[y].values
    xlabel = amplitude_label(spec.system) if x == "amplitude" else AXIS_LABELS.get(x)
    ylabel, note = AXIS_LABELS.get(y), ""
    if spec.kind == "chaos" and spec.section in SECTION_LABELS:
        xlabel, ylabel, note = SECTION_LABELS[spec.section]
    for k, (ax, method) in enumerate(zip(axes[:n], methods, strict=True)):
        if spec.kind == "stability":
            values = _log10_abs(ds["energy_error"].values[k])
            shown = np.clip(np.where(np.isinf(values), 6.0, values), -16, 6)
            mesh = ax.pcolormesh(xs, ys, shown, shading="nearest", cmap="magma", vmin=-16, vmax=6)
            label = "log10 |relative energy error| (6: blew up)"
            bounded = ds["bounded"].values[k].astype(float)
            bounded[bounded < 0] = np.nan
            if len(xs) > 1 and len(ys) > 1 and np.nanmin(bounded) < 0.5 < np.nanmax(bounded):
                ax.contour(xs, ys, bounded, levels=[0.5], colors="white", linewidths=1.5)
                ax.plot([], [], color="white", label="measured boundary")
            limit = ds["linear_limit_dt"].values[k]
            if np.all(np.isfinite(limit)) and np.all(limit > 0):
                ax.plot(xs, limit, "k--", linewidth=1.5, label="linear theory")
            else:
                words = "stable at every step" if np.all(limit > 0) else "unstable at every step"
                ax.plot([], [], "k--", label=f"linear theory: {words}")
            ax.set_ylim(ys.min(), ys.max())
            ax.legend(loc="upper right", fontsize=8, facecolor="0.8")
        elif spec.kind == "chaos":
            lyap = ds["lyapunov"].values[k]
            top = max(0.5, float(np.nanpercentile(lyap, 99))) if np.isfinite(lyap).any() else 1.0
            mesh = ax.pcolormesh(xs, ys, lyap, shading="nearest", cmap="viridis", vmin=0, vmax=top)
            label = f"largest Lyapunov exponent [1/s] ({method}, dt = {spec.step:g} s)"
            if spec.section == "rest":
                _chaos_lines(ax, spec, ds, xs)
            else:
                ax.set_title(f"{method}, {note}", fontsize=9)
        else:
            values = _log10_abs(ds["error"].values[k])
            shown = np.clip(np.where(np.isinf(values), 1.0, values), -16, 1)
            mesh = ax.pcolormesh(xs, ys, shown, shading="nearest", cmap="cividis", vmin=-16, vmax=1)
            label = f"log10 error after {spec.duration:g} s (1: blew up)"
        if y in ("dt", "rtol") and spec.y.scale == "log":
            ax.set_yscale("log")
        if not ax.get_title():
            ax.set_title(method)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        fig.colorbar(mesh, ax=ax, label=label, shrink=0.9)
    fig.suptitle(ds.attrs.get("title", "mechviz atlas"))
    return fig


def _chaos_lines(ax, spec, ds, xs) -> None:
    system = spec.make_system()
    s1, s2 = normal_mode_slopes(system.params)
    lo, hi = float(np.min(xs)), float(np.max(xs))
    t = np.linspace(lo, hi, 200)
    ax.plot(t, s1 * t, color="white", linewidth=1, label="mode 1 (theta2 = theta1)")
    mode2 = f"mode 2 (theta2 = {s2:.3g} theta1)"
    ax.plot(t, s2 * t, color="white", linestyle=":", linewidth=1.2, label=mode2)
    first = True
    for a0, a1 in json.loads(ds.attrs.get("mode1_unstable", "[]")):
        for sign in (1.0, -1.0):
            seg = sign * np.linspace(a0, min(a1, hi if sign > 0 else -lo), 50)
            label = "mode 1 unstable (Floquet)" if first else None
            ax.plot(seg, s1 * seg, color="red", linewidth=3, solid_capstyle="butt", label=label)
            ax.plot([sign * a0], [sign * s1 * a0], "o", color="red", markersize=5)
            first = False
    ax.set_xlim(lo, hi)
    ax.set_ylim(float(ds[spec.y.name].min()), float(ds[spec.y.name].max()))
    ax.set_aspect("equal")
    ax.legend(loc="lower right", fontsize=7, facecolor="0.85")


def save_maps(ds: xr.Dataset, out: str | Path, stem: str) -> list[Path]:
    """Write ``stem.png`` and ``stem.svg`` into ``out``; returns their paths."""
    import matplotlib.pyplot as plt

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    fig = figure(ds)
    paths = []
    for ext in ("png", "svg"):
        path = out / f"{stem}.{ext}"
        partial = path.with_suffix(f".partial.{ext}")
        fig.savefig(partial, dpi=110)
        partial.replace(path)
        paths.append(path)
    plt.close(fig)
    return paths
