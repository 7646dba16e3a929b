"""The controls an exhibit's tab is built from: readout, chart, parameter inputs, integrator.

A :class:`Panel` is what :meth:`viz.scene.base.Exhibit.build_panel` receives: the GUI, the app's
widget table and a ``send`` that queues a command for the exhibit. Callbacks run on viser's
threads and only queue commands; the app applies them between frames and then calls
:meth:`Panel.sync` so every widget shows the setting actually in force (a refused value
springs back).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

import dynamics

from ..warm import warm_method
from .base import LOG_FLOOR


def rtol_label(rtol: float) -> str:
    """``1e-09`` -> ``"1e-9"``; other values with three significant digits."""
    return f"{rtol:.3g}".replace("e-0", "e-")


def rtol_options(current: float) -> tuple[str, ...]:
    """The tolerance dropdown's choices: every decade from 1e-3 to 1e-13, and the current value
    if it is not one of them (set by a demo or the command line)."""
    decades = tuple(f"1e-{k}" for k in range(3, 14))
    label = rtol_label(current)
    return decades if label in decades else (*decades, label)


def method_text(name: str) -> str:
    m = dynamics.get_method(name)
    text = m.describe()
    if m.stability:
        text += f". Stability: {m.stability}"
    return f"<small>{text}</small>"


class Panel:
    """One exhibit's controls. ``w`` is the app's widget table, keyed ``"<exhibit>.<name>"``."""

    SYNCED = ("method", "dt", "beam", "beam_size", "mode", "follow_cm", "amplitude")

    def __init__(self, app, exhibit) -> None:
        self.app = app
        self.gui = app.server.gui
        self.viser = app._viser
        self.exhibit = exhibit
        self.key = exhibit.key
        self.w: dict[str, Any] = app.w

    def send(self, command) -> None:
        self.app.enqueue(self.key, command)

    def on(self, widget, fn: Callable[[Any], None]) -> None:
        """``on_update`` that ignores the app's own widget syncs and passes the new value."""
        self.app._on(widget, fn)

    def put(self, name: str, widget):
        self.w[f"{self.key}.{name}"] = widget
        return widget

    # ------------------------------------------------------------------ building blocks
    def readout_and_chart(self, compare: bool) -> None:
        viser = self.viser
        self.put("readout", self.gui.add_markdown(""))
        series = [
            viser.uplot.Series(label="t [s]"),
            viser.uplot.Series(label="log10 |ΔE/E₀|", stroke="#d03030", width=1.5),
            viser.uplot.Series(label="log10 error", stroke="#3060d0", width=1.5),
        ]
        if compare:
            series += [
                viser.uplot.Series(
                    label="compare log10 |ΔE/E₀|", stroke="#e08080", width=1.0, dash=[4, 3]
                ),
                viser.uplot.Series(
                    label="compare log10 error", stroke="#80a0e0", width=1.0, dash=[4, 3]
                ),
            ]
        self.put(
            "chart",
            self.gui.add_uplot(
                data=tuple(np.zeros(2) for _ in series),
                series=tuple(series),
                scales={
                    "x": viser.uplot.Scale(time=False),
                    "y": viser.uplot.Scale(auto=False, range=(LOG_FLOOR, 2.0)),
                },
                aspect=1.6,
            ),
        )

    def param_inputs(self, labels: dict[str, str], step: float = 0.01) -> None:
        with self.gui.add_folder("Physical parameters"):
            for name, label in labels.items():
                value = self.exhibit.config.params[name]
                h = self.put(
                    f"params.{name}",
                    self.gui.add_number(label, initial_value=float(value), step=step),
                )
                self.on(h, lambda v, n=name: self.send({"op": "set", "params": {n: v}}))

    def integrator_inputs(self, *, compare: bool) -> None:
        gui, ex = self.gui, self.exhibit
        system_name = ex.Config.system_name
        names = [m.name for m in dynamics.methods_for(system_name)]
        with gui.add_folder("Integrator"):
            method = self.put(
                "method", gui.add_dropdown("Method", options=names, initial_value=ex.config.method)
            )
            self.put("about", gui.add_markdown(method_text(ex.config.method)))
            dt = self.put(
                "dt", gui.add_number("Step dt [s]", initial_value=float(ex.config.dt), step=0.0001)
            )
            self.put("limit", gui.add_markdown(ex.stability_text()))
            # a dropdown of decades: a number input shows 1e-9 as 0.0000000
            rtol = self.put(
                "rtol",
                gui.add_dropdown(
                    "Tolerance rtol",
                    options=rtol_options(ex.config.rtol),
                    initial_value=rtol_label(ex.config.rtol),
                    hint="Relative (and absolute) tolerance of the adaptive methods",
                ),
            )

            def choose(v, field="method"):
                # compile the method's kernels here, in the callback's thread, not in a frame
                if v in names:
                    warm_method(system_name, v)
                self.send({"op": "set", field: v})

            self.on(method, choose)
            self.on(dt, lambda v: self.send({"op": "set", "dt": v}))
            self.on(rtol, lambda v: self.send({"op": "set", "rtol": float(v)}))
            if compare:
                cmp_ = self.put(
                    "compare_method",
                    gui.add_dropdown(
                        "Compare with",
                        options=["none", *names],
                        initial_value=ex.config.compare_method or "none",
                    ),
                )

                def choose_cmp(v):
                    if v != "none":
                        warm_method(system_name, v)
                    self.send({"op": "set", "compare_method": None if v == "none" else v})

                self.on(cmp_, choose_cmp)
            reset = gui.add_button(f"Reset {ex.title.lower()}", icon=self.viser.Icon.REFRESH)
            reset.on_click(lambda _: self.send("reset"))

    # ------------------------------------------------------------------ keeping widgets true
    def sync(self) -> None:
        """Make the widgets show the exhibit's actual config (after a change or a refusal)."""
        c = self.exhibit.config
        w, key = self.w, self.key
        for name, value in c.params.items():
            h = w.get(f"{key}.params.{name}")
            if h is not None and value is not None:
                h.value = float(value)
        h = w.get(f"{key}.rtol")
        if h is not None:
            h.options = rtol_options(c.rtol)
            h.value = rtol_label(c.rtol)
        for name in self.SYNCED:
            h = w.get(f"{key}.{name}")
            if h is not None and hasattr(c, name):
                h.value = getattr(c, name)
        h = w.get(f"{key}.compare_method")
        if h is not None:
            h.value = c.compare_method or "none"
        w[f"{key}.about"].content = method_text(c.method)
        w[f"{key}.limit"].content = self.exhibit.stability_text()
        self.exhibit.sync_panel(self)
