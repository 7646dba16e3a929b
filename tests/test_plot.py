"""Any variable against any other (mechviz.viz.model.plot): the quantities each exhibit plots, the exact
curves drawn with them, and the panel that picks the pair. Each curve is checked against the
physics it draws: the motion lies on it, or on the side of it theory says."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechviz import dynamics
from mechviz.dynamics import hoop as hp
from mechviz.viz.model import (
    CyclotronConfig,
    CyclotronModel,
    DiskConfig,
    DiskModel,
    HoopConfig,
    HoopModel,
)
from mechviz.viz.model.commands import Set
from mechviz.viz.model.plot import PlotImage, Samples

CASES = [
    (CyclotronModel, CyclotronConfig(centre=(0.6, 0.0), vz=0.1)),
    (HoopModel, HoopConfig(mode="mix", amplitude=0.8)),
    (DiskModel, DiskConfig(mode="driven")),
    (DiskModel, DiskConfig(mode="released", extra_spin=(0.0, 0.0, 0.05))),
]


def samples_of(cls, config, t_end: float, n: int = 400, state=None, rtol: float = 1e-12) -> Samples:
    """A tight run of ``config``'s system as the plot takes it (member 0, ``n`` samples)."""
    system = dynamics.SYSTEMS[cls.system_for(config)]
    if system is dynamics.ReleasedDisk:
        sys = system(config.physics(), tuple(config.extra_spin))
    else:
        sys = system(config.physics())
    method = "exact" if system is dynamics.DrivenDisk else "taylor"
    s0 = config.initial_state() if state is None and hasattr(config, "initial_state") else state
    kw = {} if method == "exact" else {"rtol": rtol}
    sim = dynamics.Simulation(sys, method, state=s0, reference=None, **kw)
    rows = []
    for t in np.linspace(0.0, t_end, n):
        sim.advance_to(float(t))
        smp = sim.sample()
        rows.append([sim.t, *smp.state[0], smp.energy[0], smp.energy_error[0], math.nan])
    return Samples.from_rows(np.array(rows), sim.state.shape[1])


@pytest.mark.parametrize(("cls", "config"), CASES, ids=["cyclotron", "hoop", "driven", "released"])
def test_every_quantity_is_finite_and_every_picture_draws(cls, config):
    smp = samples_of(cls, config, 5.0, n=60)
    variables = cls.plot_variables(config)
    assert {"t", "energy", "energy_error", "error"} <= set(variables)
    for name, v in variables.items():
        values = v.values(smp)
        assert values.shape == (len(smp),), name
        assert name == "error" or np.all(np.isfinite(values)), name
    image = PlotImage()
    pairs = (*cls.pictures(config), cls.default_plot(config))
    assert pairs and all(set(p) <= set(variables) for p in pairs)
    for x, y in pairs:
        curves = cls.plot_curves(config, x, y, smp)
        rgb = image.render(variables=variables, x=x, y=y, samples=smp, curves=curves)
        assert rgb.shape == (500, 560, 3) and rgb.std() > 10  # something is drawn


def test_the_charge_sits_in_its_well_at_the_level_of_its_transverse_energy():
    """After a kick off-centre: every sample's ``E_perp - V_eff(r) = p_r^2 / 2m`` (to round-off,
    on the exact flow), so the point is on the drawn level only at the turning points; the
    drawn level and well are those of the newest sample."""
    cfg = CyclotronConfig(centre=(0.6, 0.0), vz=0.0)
    p = cfg.physics()
    state = cfg.initial_state()
    state[3] += 0.4  # a radial kick: the circle no longer holds the axis's centre
    smp = samples_of(CyclotronModel, cfg, 12.0, state=state)
    v = CyclotronModel.plot_variables(cfg)
    e_perp = 0.5 * p.mass * (smp.states[:, 3] ** 2 + smp.states[:, 4] ** 2)
    gap = e_perp - v["V_eff"].values(smp)
    np.testing.assert_allclose(
        gap, v["p_r"].values(smp) ** 2 / (2 * p.mass), atol=1e-12 * e_perp.max()
    )
    assert np.ptp(v["r"].values(smp)) > 0.1  # r swings: the point moves in the well
    well, level, bottom = CyclotronModel.plot_curves(cfg, "r", "V_eff", smp)
    assert level.y[0] == pytest.approx(e_perp[-1], rel=1e-12)
    assert np.nanmin(well.y) == pytest.approx(bottom.y[0], rel=1e-9)  # r0 at the bottom


@pytest.mark.parametrize("where", ["panel", "recording"])
def test_the_well_is_drawn_whole_on_the_default_orbit_where_r_never_moves(where):
    """The default start circles the axis: r is constant, the path one point, the charge at the
    bottom of its well. The axes still show the well from near r = 0 to beyond the turning
    point, over at least half of E_perp, with the walls rising through the level: the live
    panel's image and a recording's picture (both through mechviz.viz.model.plot.draw_xy)."""
    from matplotlib.figure import Figure

    from mechviz.viz.model.plot import draw_xy

    cfg = CyclotronConfig()
    p = cfg.physics()
    smp = samples_of(CyclotronModel, cfg, 6.0, n=120)
    v = CyclotronModel.plot_variables(cfg)
    r = v["r"].values(smp)
    assert np.ptp(r) < 1e-9 * r.max()  # r does not move
    e_perp = 0.5 * p.mass * (smp.states[-1, 3] ** 2 + smp.states[-1, 4] ** 2)
    curves = CyclotronModel.plot_curves(cfg, "r", "V_eff", smp)
    if where == "panel":
        image = PlotImage()
        image.render(variables=v, x="r", y="V_eff", samples=smp, curves=curves)
        ax = image.ax
    else:
        ax = Figure().add_subplot()
        draw_xy(ax, v, "r", "V_eff", smp, curves)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert y1 - y0 >= 0.5 * e_perp, (y0, y1, e_perp)
    assert x0 <= 0.1 * r[-1] and x1 >= 1.2 * r[-1]  # near 0 to beyond the turning point
    well = curves[0]
    shown = (well.x >= x0) & (well.x <= x1) & (well.y >= y0) & (well.y <= y1)
    assert shown.sum() > 0.5 * len(well.x)  # most of the well is on the axes
    inner, outer = well.x < 0.7 * r[-1], well.x > 1.15 * r[-1]
    assert well.y[inner].max() > e_perp and well.y[outer].max() > e_perp  # both walls rise


def test_the_hoop_phase_portrait_is_split_by_the_separatrix_of_the_mode_1_pendulum():
    """Mode 1 is the pendulum theta'' = -w1^2 sin theta: the drawn separatrix has the energy of
    the upright pendulum, a swing of 3 rad stays inside it on its own exact orbit, and a start
    at the bottom with theta' = 2.05 w1 stays outside (over the top)."""
    cfg = HoopConfig()
    w1 = float(hp.normal_modes(cfg.physics())[0][0])
    sep = HoopModel.plot_curves(cfg, "theta1", "omega1", samples_of(HoopModel, cfg, 0.1, n=2))[0]
    np.testing.assert_allclose(0.5 * sep.y**2 - w1**2 * np.cos(sep.x), w1**2, atol=1e-12)

    period = hp.mode1_period(cfg.physics(), 3.0)
    inside = samples_of(HoopModel, cfg, period, state=np.array([3.0, 3.0, 0.0, 0.0]))
    th, rate = inside.states[:, 0], inside.states[:, 2]
    assert np.all(np.abs(rate) < 2 * w1 * np.cos(th / 2) + 1e-9)
    orbit = HoopModel.plot_curves(cfg, "theta1", "omega1", inside)[1]
    assert orbit.label == "exact pendulum orbit"
    e_path = 0.5 * rate**2 - w1**2 * np.cos(th)  # the pendulum's energy per unit inertia
    np.testing.assert_allclose(e_path, e_path[0], atol=1e-9 * w1**2)
    ok = np.isfinite(orbit.y)
    assert ok.sum() > 100  # the swing's orbit, not the whole circle
    np.testing.assert_allclose(
        0.5 * orbit.y[ok] ** 2 - w1**2 * np.cos(orbit.x[ok]), e_path[-1], atol=1e-12 * w1**2
    )

    over = samples_of(HoopModel, cfg, 3.0, state=np.array([0.0, 0.0, 2.05 * w1, 2.05 * w1]))
    th, rate = over.states[:, 0], over.states[:, 2]
    assert np.all(np.abs(rate) > 2 * w1 * np.abs(np.cos(th / 2)))
    assert np.ptp(th) > 2 * math.pi  # it went over the top


def test_configuration_space_draws_the_mode_lines_a_small_mode_1_start_stays_on():
    cfg = HoopConfig(mode="mode 1", amplitude=0.05)
    smp = samples_of(HoopModel, cfg, 10.0)
    line1, line2 = HoopModel.plot_curves(cfg, "theta1", "theta2", smp)
    _, shapes = hp.normal_modes(cfg.physics())
    for line, shape in ((line1, shapes[0]), (line2, shapes[1])):
        d = np.array([line.x[1] - line.x[0], line.y[1] - line.y[0]])
        assert abs(d[0] * shape[1] - d[1] * shape[0]) < 1e-12 * np.linalg.norm(d)  # along the shape
    q = HoopModel.plot_variables(cfg)["q2"].values(smp)
    assert np.abs(q).max() < 1e-9  # on the (1, 1) line: no mode-2 part


def test_the_released_disk_runs_on_the_drawn_polhode_and_its_asymptotes_are_the_separatrix():
    """E and |L| fixed: eliminating w_k leaves sum_(i != k) I_i (I_k - I_i) w_i^2 = 2E I_k - L^2.
    Every sample of a tumble satisfies the conic of the drawn curve (from the first sample's E
    and L), and the curve's points satisfy it too."""
    cfg = DiskConfig(mode="released", extra_spin=(0.0, 0.0, 0.05))
    smp = samples_of(DiskModel, cfg, 20.0)
    moments = dynamics.disk.free_kernel_params(cfg.physics())
    w0 = smp.states[0, :3]
    two_e, l2 = np.sum(moments * w0**2), np.sum((moments * w0) ** 2)
    for x, y in (("w1", "w3"), ("w2", "w3"), ("w1", "w2")):
        i, j = int(x[1]) - 1, int(y[1]) - 1
        k = 3 - i - j
        a, b = moments[i] * (moments[k] - moments[i]), moments[j] * (moments[k] - moments[j])
        c = two_e * moments[k] - l2
        w = smp.states[:, :3]
        np.testing.assert_allclose(
            a * w[:, i] ** 2 + b * w[:, j] ** 2, c, atol=1e-9 * two_e * moments[k]
        )
        (curve,) = DiskModel.plot_curves(cfg, x, y, smp)
        ok = np.isfinite(curve.x)
        on_curve = a * curve.x[ok] ** 2 + b * curve.y[ok] ** 2
        np.testing.assert_allclose(on_curve, c, atol=1e-9 * two_e * moments[k])
        reach = np.abs(np.column_stack([curve.x[ok], curve.y[ok]])).max()
        assert reach >= np.abs(w[:, [i, j]]).max()  # the curve reaches as far as the motion


@pytest.mark.slow
def test_the_panel_plots_the_pair_a_person_picks_and_follows_the_disk_to_its_other_motion(server):
    from mechviz.viz.app import MechvizApp

    app = MechvizApp(port=0, start_loop=False, environment_map=False)
    try:
        for _ in range(60):
            app.step_frame()
        panel = app.panels["hoop"]
        variables = HoopModel.plot_variables(app.exhibits["hoop"].model.config)
        app.w["hoop.plot_y"].value = variables["theta2"].label  # as the dropdown does
        app.w["hoop.plot_x"].value = variables["theta1"].label
        app.step_frame()
        assert panel.plot_choice == ("theta1", "theta2")
        before = app.w["hoop.plot"].image.copy()
        app.w["hoop.plot_y"].value = variables["q1"].label
        app.step_frame()
        assert panel.plot_choice == ("theta1", "q1")
        assert np.abs(app.w["hoop.plot"].image.astype(int) - before).mean() > 1  # drawn anew

        disk = app.panels["disk"]
        app.exhibits["disk"].model.apply(Set(fields={"mode": "released"}))
        disk.refresh_plot(force=True)
        released = DiskModel.plot_variables(app.exhibits["disk"].model.config)
        assert (
            disk.plot_choice
            == DiskModel.default_plot(app.exhibits["disk"].model.config)
            == ("w2", "w3")
        )
        assert tuple(app.w["disk.plot_x"].options) == tuple(v.label for v in released.values())
    finally:
        app.stop()
