"""The controls an exhibit's tab is built from: readout, chart, parameter inputs, integrator.

A :class:`Panel` is what :meth:`mechviz.viz.scene.base.Exhibit.build_panel` receives: the GUI, the app's
widget table and a ``send`` that queues a command for the exhibit. Callbacks run on viser's
threads and only queue commands; the app applies them between frames and then calls
:meth:`Panel.sync` so every widget shows the setting actually in force (a refused value
springs back).

One rule for every number a person types, the command line's and the demo files' too
(:func:`mechviz.dynamics.params.parse_number`): what a person writes is read as Python reads a
float (``0.025``, ``2.5e-2``, ``2.5E-2``, ``−1`` with a typographic minus); anything else, a
non-finite or subnormal value or one outside the control's range is refused with a notification
that names the field as the panel labels it; the box shows the value in force again once the
person moves on to another control (never while they may still be typing in it). Number fields
are text boxes read on Enter (:mod:`mechviz.viz.scene.fields`), with a stepper or a slider
track beside each: the browser's own number input rewrites scientific notation as it is typed.
A parameter's range is the one its system's description gives for a live exhibit
(:attr:`mechviz.dynamics.spec.Setting.span`); a step is refused beyond one period of the fastest
motion (the exhibit would stand still) and taken with a warning beyond the method's stability
limit (:mod:`mechviz.dynamics.stability`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from mechviz import dynamics

from ..model.commands import Command, Reset, Set
from ..model.plot import PlotImage
from ..warm import warm_method
from .base import LOG_FLOOR
from .fields import NumberField, number_text  # noqa: F401  (number_text re-exported)


def rtol_label(rtol: float) -> str:
    """``1e-09`` -> ``"1e-9"``; other values with three significant digits."""
    return f"{rtol:.3g}".replace("e-0", "e-")


def rtol_options(current: float) -> tuple[str, ...]:
    """The tolerance dropdown's choices: every decade from 1e-3 to 1e-12 (the tightest a run is
    still compared with the reference at), and the current value if it is not one of them (set
    by a demo or the command line)."""
    decades = tuple(f"1e-{k}" for k in range(3, 13))
    label = rtol_label(current)
    return decades if label in decades else (*decades, label)


def parse_number(
    label: str, text, lo: float | None = None, hi: float | None = None, why: str = ""
) -> float:
    """The number typed into the field ``label``, read by the one rule for typed numbers
    (:func:`mechviz.dynamics.params.parse_number`) and held to the control's range, or a
    :class:`mechviz.dynamics.params.SettingError` with one line naming the field as the panel labels it."""
    x = dynamics.parse_number(label, text)
    if (lo is not None and x < lo) or (hi is not None and x > hi):
        raise dynamics.SettingError(
            label, f"{label} must lie between {lo:g} and {hi:g}{why}, got {x:g}"
        )
    return x


def method_text(name: str) -> str:
    m = dynamics.get_method(name)
    if m.closed_form:
        return f"<small>{m.title}: the closed-form solution, exact at any time; no step</small>"
    text = m.describe(dynamics.SYSTEMS.values())
    if m.stability:
        text += f". Stability: {m.stability}"
    return f"<small>{text}</small>"


class Panel:
    """One exhibit's controls. ``w`` is the app's widget table, keyed ``"<exhibit>.<name>"``."""

    SYNCED = ("method", "dt", "beam", "beam_size", "kick", "mode", "follow_cm", "amplitude")

    def __init__(self, app, exhibit) -> None:
        self.app = app
        self.gui = app.server.gui
        self.viser = app._viser
        self.exhibit = exhibit
        self.key = exhibit.key
        self.w: dict[str, Any] = app.w
        self.labels: dict[str, str] = {}  # setting name (as in messages) -> the field's label
        self.fields: dict[str, NumberField] = {}  # the number fields, by their name in ``w``
        self._time_axes: dict[str, tuple[float, float, float]] = {}  # chart -> (t0, t1, window)
        self.plot_choice = exhibit.model.default_plot(
            exhibit.model.config
        )  # (x, y) of the panel's plot
        self._plot_image: PlotImage | None = None
        self._plot_names: tuple[str, ...] | None = None  # the quantities of the motion shown
        self._plot_drawn: tuple | None = (
            None  # what the image shows: (choice, trace version, theme)
        )
        self._plot_time = -math.inf  # when it was drawn (time.monotonic)

    def send(self, command: Command) -> None:
        self.app.enqueue(self.key, command)

    def change(self, **fields) -> None:
        """Send the settings ``fields`` by name (:class:`mechviz.viz.model.commands.Set`)."""
        self.send(Set(fields=fields))

    def on(self, widget, fn: Callable[[Any], None]) -> None:
        """``on_update`` that ignores the app's own widget syncs and passes the new value."""
        self.app._on(widget, fn)

    def put(self, name: str, widget):
        self.w[f"{self.key}.{name}"] = widget
        return widget

    def refuse(self, message: str) -> None:
        """Tell the user why a value was not taken, and put the widgets back to what is in force."""
        self.app.notify(f"Invalid value ({self.exhibit.model.title})", message)
        self.app.enqueue("call", lambda app: app._sync_widgets(self.key))

    def number(
        self,
        name: str,
        label: str,
        value: float,
        apply,
        *,
        current,
        lo=None,
        hi=None,
        hint=None,
        check=None,
        track=None,
        why="",
    ):
        """A number field (:class:`mechviz.viz.scene.fields.NumberField`): ``apply(x)`` gets the value
        entered (Enter), read by :func:`parse_number` and held to ``lo``..``hi``; ``check(x)``
        may refuse it further (``ValueError``) or warn (returns a message). ``current()`` is the
        value in force. With ``track = (lo, hi, step)`` a slider track under the box sets it
        too, else a stepper (− / +) whose values are checked as typed ones."""
        self.labels[name.split(".")[-1]] = label

        def read(text):
            try:
                x = parse_number(label, text, lo, hi, why)
                warning = check(x) if check is not None else None
            except ValueError as exc:
                self.refuse(str(exc))
                return
            apply(x)
            if warning:
                self.app.notify(f"Warning ({self.exhibit.model.title})", warning, color="orange")

        field = NumberField(
            self.gui,
            label,
            value,
            read=read,
            current=current,
            hint=hint,
            track=track,
            track_apply=apply,
            lo=lo,
            hi=hi,
            **self.app.field_hooks(),
        )
        self.fields[name] = field
        self.app.number_fields[f"{self.key}.{name}"] = field
        self.put(name, field.box)
        if field.track is not None:
            self.put(f"{name}_track", field.track)
        if field.stepper is not None:
            self.put(f"{name}_stepper", field.stepper)
        return field

    def slider(self, name: str, label: str, lo: float, hi: float, step: float, value, apply, **kw):
        """A number field over a slider track; typed values obey the same range as the track.
        The value in force is ``current()``, by default the exhibit's config field ``name``."""
        current = kw.pop("current", lambda: getattr(self.exhibit.model.config, name))
        return self.number(
            name,
            label,
            value,
            apply,
            current=current,
            lo=lo,
            hi=hi,
            track=(lo, hi, step),
            **kw,
        )

    def show(self, name: str, value) -> None:
        """Show ``value`` in the field ``name`` (box and track); the caller holds the app's
        syncing flag (:meth:`sync` does)."""
        self.fields[name].show(value)

    def keep_time_axis(self, name: str, t: float, window: float, y_range) -> None:
        """Give the chart ``name`` an explicit time axis: the ``window`` [s] ending a quarter
        window ahead of ``t``, moved on once ``t`` passes its end, and the y range ``y_range``
        (changed when it changes: the error chart's follows its data in whole decades).
        The browser's chart keeps the time range it had when it was drawn; one drawn again
        (after a resize and a tab switch) would keep a stale range and show no lines. Moving
        the range redraws the chart, so it moves in quarter-window steps, not every update."""
        lo, hi, win, ys = self._time_axes.get(name, (math.inf, -math.inf, 0.0, None))
        y_range = tuple(float(y) for y in y_range)
        if lo <= t <= hi and win == window and ys == y_range:
            return
        if not (lo <= t <= hi and win == window):
            hi = t + 0.25 * window
            lo = hi - 1.25 * window
        self._time_axes[name] = (lo, hi, window, y_range)
        uplot = self.viser.uplot
        self.w[f"{self.key}.{name}"].scales = {
            "x": uplot.Scale(time=False, auto=False, range=(lo, hi)),
            "y": uplot.Scale(auto=False, range=y_range),
        }

    def explain(self, exc: ValueError) -> str:
        """A settings error as the panel names things: the field of a
        :class:`mechviz.dynamics.params.SettingError` (``mass``) by its label (``Mass m [kg]``)."""
        message = str(exc)
        field = getattr(exc, "field", "").removeprefix("initial.")
        label = self.labels.get(field)
        if label is None:
            return message
        return label + message[len(field) :] if message.startswith(field) else f"{label}: {message}"

    # ------------------------------------------------------------------ building blocks
    def readout_and_chart(self, compare: bool) -> None:
        viser = self.viser
        self.put("readout", self.gui.add_markdown(""))
        series = [
            viser.uplot.Series(label="t [s]"),
            viser.uplot.Series(
                label="log10 |energy error| (y axis fitted to the data)",
                stroke="#d03030",
                width=1.5,
            ),
            viser.uplot.Series(label="log10 error", stroke="#3060d0", width=1.5),
        ]
        if compare:
            series += [
                viser.uplot.Series(
                    label="compare log10 |energy error|", stroke="#e08080", width=1.0, dash=[4, 3]
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
                # the series' names only: a live legend shows "--" for the value under a cursor
                # that is not on the chart
                legend=viser.uplot.Legend(live=False),
                aspect=1.6,
            ),
        )

    def check_step(self, dt: float) -> str | None:
        """Refuse a step ``dt`` [s] longer than one period of the exhibit's fastest motion (each
        step would jump over a whole turn, and at the viewer's speeds the exhibit would stand
        still for seconds between steps); return a warning if it is beyond the running method's
        stability limit (the run will blow up: worth showing, not worth hiding)."""
        from mechviz.dynamics import stability

        sim = self.exhibit.model.sim
        label = self.labels.get("dt", "dt")
        omega = stability.fastest_frequency(sim.system, self.exhibit.model.state)
        if omega > 0 and dt > 2 * math.pi / omega:
            raise dynamics.SettingError(
                "dt",
                f"{label} = {dt:g} s is longer than one period of the fastest motion "
                f"({2 * math.pi / omega:.3g} s): the exhibit would stand still between steps",
            )
        m = sim.method
        if m.adaptive or m.closed_form:
            return None
        limit = stability.stability_limit(m.name, sim.system, self.exhibit.model.state)
        if limit is not None and dt > limit:
            where = "at every step size" if limit == 0.0 else f"above dt = {limit:.3g} s"
            return f"{label} = {dt:g} s: {m.name} is unstable {where}; expect the run to blow up"
        return None

    def param_inputs(self) -> None:
        """A number field for each physical parameter of the exhibit's system, labelled as its
        description says (:attr:`mechviz.dynamics.spec.SystemSpec.params`)."""
        with self.gui.add_folder("Physical parameters"):
            for setting in self.exhibit.model.Config.spec.params:
                name, label = setting.name, setting.panel_label
                value = self.exhibit.model.config.params[name]
                lo, hi = setting.span or (None, None)
                self.number(
                    f"params.{name}",
                    label,
                    value,
                    lambda x, n=name: self.send(Set(params={n: x})),
                    current=lambda n=name: self.exhibit.model.config.params[n],
                    lo=lo,
                    hi=hi,
                    hint=setting.help or None,
                    why=" (where the exhibit stays meaningful on screen)",
                )

    def integrator_inputs(self, *, compare: bool) -> None:
        gui, ex = self.gui, self.exhibit
        system_name = ex.model.Config.system_name
        names = [m.name for m in dynamics.methods_for(dynamics.SYSTEMS[system_name])]
        with gui.add_folder("Integrator"):
            method = self.put(
                "method",
                gui.add_dropdown("Method", options=names, initial_value=ex.model.config.method),
            )
            self.put("about", gui.add_markdown(method_text(ex.model.config.method)))
            self.number(
                "dt",
                "Step dt [s]",
                ex.model.config.dt,
                lambda x: self.change(dt=x),
                current=lambda: self.exhibit.model.config.dt,
                check=self.check_step,
            )
            self.put("limit", gui.add_markdown(ex.model.stability_text()))
            # a dropdown of decades: a number input shows 1e-9 as 0.0000000
            rtol = self.put(
                "rtol",
                gui.add_dropdown(
                    "Tolerance rtol",
                    options=rtol_options(ex.model.config.rtol),
                    initial_value=rtol_label(ex.model.config.rtol),
                    hint="Tolerance of the adaptive methods, relative and absolute alike (atol = "
                    "rtol): a swing of A rad is held to rtol/A of itself, so errors relative to a "
                    "small motion are larger than rtol",
                ),
            )

            def choose(v, field="method"):
                # compile the method's kernels here, in the callback's thread, not in a frame
                if v in names:
                    warm_method(system_name, v)
                self.change(**{field: v})

            self.on(method, choose)
            self.on(rtol, lambda v: self.change(rtol=float(v)))
            if compare:
                cmp_ = self.put(
                    "compare_method",
                    gui.add_dropdown(
                        "Compare with",
                        options=["none", *names],
                        initial_value=ex.model.config.compare_method or "none",
                    ),
                )

                def choose_cmp(v):
                    if v != "none":
                        warm_method(system_name, v)
                    self.change(compare_method=None if v == "none" else v)

                self.on(cmp_, choose_cmp)
            reset = gui.add_button(f"Reset {ex.model.title.lower()}", icon=self.viser.Icon.REFRESH)
            reset.on_click(lambda _: self.send(Reset()))
        self.show_step_controls()

    PLOT_INTERVAL = 0.2  # s between updates of the plot: drawing new axes costs frames

    def plot(self, note: str) -> None:
        """The plot of any variable against any other: two dropdowns naming the quantities as
        their axes do, and the image (:mod:`mechviz.viz.model.plot`), over the chart window; ``note``
        says what the exhibit's first pair shows."""
        ex = self.exhibit
        variables = ex.model.plot_variables(ex.model.config)
        labels = tuple(v.label for v in variables.values())
        x, y = self.plot_choice
        with self.gui.add_folder("Plot any two variables"):
            self.put(
                "plot_note",
                self.gui.add_markdown(
                    f"<small>{note} Blue: the main run over the chart window, red: now; the other "
                    "lines are exact curves of the theory (see the legend).</small>"
                ),
            )
            self.put(
                "plot_y",
                self.gui.add_dropdown("y", options=labels, initial_value=variables[y].label),
            )
            self.put(
                "plot_x",
                self.gui.add_dropdown("x", options=labels, initial_value=variables[x].label),
            )
            self.put(
                "plot", self.gui.add_image(np.full((500, 560, 3), 255, np.uint8), format="jpeg")
            )

        def choose(axis: int, label: str) -> None:
            variables = ex.model.plot_variables(ex.model.config)
            name = next((n for n, v in variables.items() if v.label == label), None)
            if name is None:
                self.refuse(f"{'xy'[axis]}: {label!r} is not a quantity of this exhibit")
                return
            choice = list(self.plot_choice)
            choice[axis] = name
            self.plot_choice = (choice[0], choice[1])
            self.app.enqueue("call", lambda app: self.refresh_plot(force=True))

        self.on(self.w[f"{self.key}.plot_x"], lambda v: choose(0, v))
        self.on(self.w[f"{self.key}.plot_y"], lambda v: choose(1, v))

    def refresh_plot(self, force: bool = False) -> None:
        """Redraw the plot if something new is to be shown, at most every ``PLOT_INTERVAL``
        seconds unless ``force``d (a new choice)."""
        image = self.w.get(f"{self.key}.plot")
        if image is None:
            return
        now = time.monotonic()
        if not force and now - self._plot_time < self.PLOT_INTERVAL:
            return
        ex = self.exhibit
        variables = ex.model.plot_variables(ex.model.config)
        if tuple(variables) != self._plot_names:  # another motion, other quantities: its own first
            if self._plot_names is not None or not set(self.plot_choice) <= set(variables):
                self.plot_choice = ex.model.default_plot(ex.model.config)
            self._plot_names = tuple(variables)
        dark = getattr(self.app, "theme", "light") == "dark"
        drawn = (self.plot_choice, ex.model.trace.version, ex.model.config, dark)
        if drawn == self._plot_drawn:
            return
        self.sync_plot(variables)
        if self._plot_image is None:
            self._plot_image = PlotImage()
        x, y = self.plot_choice
        samples = ex.model.plot_samples()
        image.image = self._plot_image.render(
            dark,
            variables=variables,
            x=x,
            y=y,
            samples=samples,
            curves=ex.model.plot_curves(ex.model.config, x, y, samples),
            path_label=ex.model.sim.method.name,
        )
        self._plot_drawn, self._plot_time = drawn, now

    def sync_plot(self, variables) -> None:
        """The plot's dropdowns show the quantities of the running motion and the choice."""
        labels = tuple(v.label for v in variables.values())
        hx, hy = self.w[f"{self.key}.plot_x"], self.w[f"{self.key}.plot_y"]
        syncing, self.app._syncing = self.app._syncing, True
        try:
            for h, name in ((hx, self.plot_choice[0]), (hy, self.plot_choice[1])):
                if tuple(h.options) != labels:
                    h.options = labels
                if h.value != variables[name].label:
                    h.value = variables[name].label
        finally:
            self.app._syncing = syncing

    # ------------------------------------------------------------------ keeping widgets true
    def sync(self) -> None:
        """Make the widgets show the exhibit's actual config (after a change or a refusal)."""
        c = self.exhibit.model.config
        w, key = self.w, self.key
        for name, value in c.params.items():
            if f"params.{name}" in self.fields and value is not None:
                self.show(f"params.{name}", value)
        h = w.get(f"{key}.rtol")
        if h is not None:
            h.options = rtol_options(c.rtol)
            h.value = rtol_label(c.rtol)
        for name in self.SYNCED:
            if name in self.fields and hasattr(c, name):
                self.show(name, getattr(c, name))
                continue
            h = w.get(f"{key}.{name}")
            if h is not None and hasattr(c, name):
                h.value = getattr(c, name)
        self.show_step_controls()
        h = w.get(f"{key}.compare_method")
        if h is not None:
            h.value = c.compare_method or "none"
        w[f"{key}.about"].content = method_text(c.method)
        w[f"{key}.limit"].content = self.exhibit.model.stability_text()
        self.exhibit.sync_panel(self)

    def show_step_controls(self) -> None:
        """Show the step box for fixed-step methods and the tolerance for adaptive ones only."""
        m = self.exhibit.model.sim.method
        dt, rtol = self.fields.get("dt"), self.w.get(f"{self.key}.rtol")
        if dt is not None:
            dt.visible = not m.adaptive and not m.closed_form
        if rtol is not None:
            rtol.visible = m.adaptive
