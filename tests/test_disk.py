"""Spinning disk with a bead: inertia, principal axes, bearing forces, released free body."""

import math

import numpy as np
import pytest
import sympy as sp

from mechviz.dynamics import ReleasedDisk, Simulation, disk
from mechviz.dynamics.disk import DiskParams

SEED = DiskParams()
OTHERS = [DiskParams(2.0, 0.5, 0.3, 3.0), DiskParams(1.0, 1.5, 4.0, -2.0)]


def _symbolic_disk_inertia_about_A():
    """Integrate (r^2 delta - r r^T) dm over the uniform disk centred at (0, R, 0)."""
    M, R, rho, phi = sp.symbols("M R rho phi", positive=True)
    x = rho * sp.cos(phi)
    y = R + rho * sp.sin(phi)
    r = [x, y, 0]
    sigma = M / (sp.pi * R**2)
    tensor = sp.zeros(3, 3)
    for i in range(3):
        for j in range(3):
            integrand = (sum(c**2 for c in r) * (1 if i == j else 0) - r[i] * r[j]) * sigma * rho
            tensor[i, j] = sp.integrate(integrand, (rho, 0, R), (phi, 0, 2 * sp.pi))
    return M, R, sp.simplify(tensor)


def test_disk_inertia_about_A_matches_direct_integration_and_the_seed():
    M, R, tensor = _symbolic_disk_inertia_about_A()
    assert sp.simplify(tensor - M * R**2 / 4 * sp.diag(5, 1, 6)) == sp.zeros(3, 3)
    for p in [SEED, *OTHERS]:
        numeric = np.array(tensor.subs({M: p.disk_mass, R: p.radius}), dtype=float)
        np.testing.assert_allclose(disk.inertia_tensor_disk(p), numeric, rtol=1e-14, atol=1e-14)


def test_seed_total_inertia_tensor_about_A():
    expected = np.array([[5 / 2, -5 / 4, 0], [-5 / 4, 3 / 2, 0], [0, 0, 4]])
    np.testing.assert_allclose(disk.inertia_tensor(SEED), expected, rtol=1e-15)
    np.testing.assert_allclose(
        disk.inertia_tensor_bead(SEED), 5 / 4 * np.array([[1, -1, 0], [-1, 1, 0], [0, 0, 2]])
    )


def test_seed_principal_moments_and_axes():
    moments, axes = disk.principal_axes(SEED)
    r29 = math.sqrt(29)
    np.testing.assert_allclose(moments, [2 - r29 / 4, 2 + r29 / 4, 4], rtol=1e-14)
    x1 = np.array([r29 - 2, 5, 0]) / math.sqrt(58 - 4 * r29)
    y1 = np.array([-2 - r29, 5, 0]) / math.sqrt(58 + 4 * r29)
    np.testing.assert_allclose(axes, [x1, y1, [0, 0, 1]], atol=1e-14)


@pytest.mark.parametrize("p", [SEED, *OTHERS])
def test_principal_axes_diagonalise_the_tensor(p):
    moments, axes = disk.principal_axes(p)
    np.testing.assert_allclose(axes @ disk.inertia_tensor(p) @ axes.T, np.diag(moments), atol=1e-12)
    np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-14)
    assert np.all(np.diff(moments) >= 0)


def test_seed_spin_components_in_the_principal_frame_are_swapped_in_the_seed():
    """omega y projected on x' is 5 omega / sqrt(58 - 4 sqrt29) (the seed prints + under the root)
    and on y' 5 omega / sqrt(58 + 4 sqrt29); their product, all the force needs, is unchanged."""
    _, axes = disk.principal_axes(SEED)
    r29 = math.sqrt(29)
    w = axes @ np.array([0.0, 1.0, 0.0])
    np.testing.assert_allclose(w[:2], [5 / math.sqrt(58 - 4 * r29), 5 / math.sqrt(58 + 4 * r29)])
    moments, _ = disk.principal_axes(SEED)
    assert (moments[1] - moments[0]) * w[0] * w[1] == pytest.approx(5 / 4)


def test_seed_bearing_force_at_B():
    """F = 5/8 M omega^2 R (-cos wt x + sin wt z) (seed 2c), for several omega and times."""
    for omega in (1.0, 2.5, -3.0):
        p = DiskParams(omega=omega)
        for t in (0.0, 0.3, 2.0):
            wt = omega * t
            expected = 5 / 8 * omega**2 * np.array([-math.cos(wt), 0.0, math.sin(wt)])
            np.testing.assert_allclose(disk.bearing_force_b(p, t), expected, atol=1e-14)
        assert disk.axle_force_amplitude(p) == pytest.approx(5 / 8 * omega**2)


@pytest.mark.parametrize("p", [SEED, *OTHERS])
def test_bearing_forces_supply_the_centripetal_force_and_the_torque(p):
    """Numerically along the driven motion: d(sum m v)/dt = F_A + F_B and dL_A/dt = r_B x F_B,
    with momentum and angular momentum summed over the disk (quadrature) and the bead."""
    rho, phi = np.meshgrid(
        np.linspace(0, p.radius, 60)[1:] - p.radius / 118, np.linspace(0, 2 * np.pi, 121)[:-1]
    )
    area = (p.radius / 59) * rho * (2 * np.pi / 120)
    pts = np.stack([rho * np.cos(phi), p.radius + rho * np.sin(phi), 0 * rho], -1).reshape(-1, 3)
    masses = (area / area.sum() * p.disk_mass).ravel()
    pts = np.vstack([pts, disk.bead_position(p)])
    masses = np.append(masses, p.bead_mass)
    w = p.omega * np.array([0.0, 1.0, 0.0])

    def momenta(t):
        r = pts @ disk.rotation_about_axle(p.omega * t).T
        v = np.cross(w, r)
        return (masses[:, None] * v).sum(0), (masses[:, None] * np.cross(r, v)).sum(0)

    h = 1e-4
    for t in (0.0, 0.4, 1.7):
        (P1, L1), (P0, L0) = momenta(t + h), momenta(t - h)
        dP, dL = (P1 - P0) / (2 * h), (L1 - L0) / (2 * h)
        scale = p.bead_mass * p.radius * p.omega**2
        np.testing.assert_allclose(
            dP, disk.bearing_force_a(p, t) + disk.bearing_force_b(p, t), atol=1e-6 * scale
        )
        torque = np.cross(disk.axle_points(p)[1], disk.bearing_force_b(p, t))
        np.testing.assert_allclose(dL, torque, atol=1e-6 * scale * p.radius)
        np.testing.assert_allclose(
            torque, disk.required_torque(p, t), atol=1e-12 * scale * p.radius
        )
        # No torque along the axle is needed to keep the rate uniform.
        assert abs(disk.required_torque(p, t)[1]) < 1e-12


def test_bead_opposite_the_axle_midpoint_loads_both_bearings_equally():
    for p in [SEED, *OTHERS]:
        np.testing.assert_allclose(
            disk.bearing_force_a(p, 0.7), disk.bearing_force_b(p, 0.7), atol=1e-12
        )
        assert disk.axle_force_amplitude(p) == pytest.approx(
            p.bead_mass * p.radius * p.omega**2 / 2
        )


def test_seed_moments_about_the_centre_of_mass_make_the_axle_the_intermediate_axis():
    moments, axes = disk.principal_axes_cm(SEED)
    np.testing.assert_allclose(moments, [1 / 4, 29 / 36, 19 / 18], rtol=1e-13)
    np.testing.assert_allclose(np.abs(axes), np.eye(3), atol=1e-14)


def test_quaternion_conversion_round_trips():
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        q *= np.sign(q[0])
        R = disk.quaternion_to_matrix(q)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
        np.testing.assert_allclose(disk._matrix_to_quaternion(R), q, atol=1e-12)


def test_released_disk_starts_in_the_driven_pose_with_the_driven_velocities():
    sysm = ReleasedDisk(SEED)
    s0 = sysm.default_state()
    rot, a = disk.released_pose(SEED, s0, 0.0)
    np.testing.assert_allclose(rot, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(a, 0.0, atol=1e-14)
    # Angular momentum about the CM plus that of the CM's motion equals L about A when driven.
    L_cm = disk.free_angular_momentum_space(sysm.kernel_params(), s0)
    r_cm = disk.centre_of_mass(SEED)
    v_cm = np.cross(SEED.omega * np.array([0, 1.0, 0]), r_cm)
    np.testing.assert_allclose(
        L_cm + SEED.total_mass * np.cross(r_cm, v_cm), disk.angular_momentum(SEED), atol=1e-14
    )


def test_released_disk_conserves_energy_and_angular_momentum_and_tumbles():
    sysm = ReleasedDisk(SEED, (0.0, 0.0, 0.01))
    traj = Simulation(sysm, "dop853", rtol=1e-11, atol=1e-11).run(60.0, 601)
    states = traj.states[:, 0]
    E = sysm.energy(states)
    L = disk.free_angular_momentum_space(sysm.kernel_params(), states)
    assert np.max(np.abs(E / E[0] - 1)) < 1e-9
    assert np.max(np.linalg.norm(L - L[0], axis=1)) < 1e-9 * np.linalg.norm(L[0])
    # Spin about the intermediate axis is unstable: w2 reverses (the Dzhanibekov flip).
    assert states[:, 1].min() < -0.5 * SEED.omega
    assert traj.error is not None and traj.error[-1, 0] < 1e-7  # against the 1e-12 reference


def test_released_disk_rk4_matches_the_tight_reference():
    sysm = ReleasedDisk(SEED, (0.01, 0.0, 0.01))
    sim = Simulation(sysm, "rk4", dt=0.005)
    sim.advance_to(30.0)
    assert sim.sample().error[0] < 1e-7


@pytest.mark.parametrize(
    ("field", "value"),
    [("disk_mass", 0.0), ("radius", -1.0), ("bead_mass", float("nan")), ("omega", float("inf"))],
)
def test_bad_parameters_are_rejected_naming_the_field(field, value):
    with pytest.raises(ValueError, match=rf"^{field} must be"):
        DiskParams(**{field: value})


def test_poinsot_the_ellipsoid_touches_the_invariable_plane_where_its_normal_is_along_l():
    """Poinsot: the contact point w/sqrt(2T) lies on the inertia ellipsoid and on the plane
    normal to L at sqrt(2T)/|L|, and the ellipsoid's normal there (I x) is parallel to L, at
    every moment of a tumble."""
    p = DiskParams(omega=2.0)
    system = ReleasedDisk(p, extra_spin=(0.01, 0.0, 0.05))
    moments = system.kernel_params()
    sim = Simulation(system, "dop853", rtol=1e-10, reference=None)
    plane = None
    for t in np.linspace(0.5, 20.0, 40):
        sim.advance_to(float(t))
        pc = disk.poinsot(moments, sim.state[0])
        x = pc["contact_body"]
        assert x @ (moments * x) == pytest.approx(1.0, rel=1e-12)  # on the ellipsoid
        assert pc["contact_space"] @ pc["normal"] == pytest.approx(pc["distance"], rel=1e-12)
        n_body = moments * x / np.linalg.norm(moments * x)
        np.testing.assert_allclose(pc["rotation"] @ n_body, pc["normal"], atol=1e-12)
        if plane is None:
            plane = (pc["normal"], pc["distance"])
        np.testing.assert_allclose(pc["normal"], plane[0], atol=1e-8)  # the plane is fixed
        assert pc["distance"] == pytest.approx(plane[1], rel=1e-8)


@pytest.mark.parametrize("extra_spin", [(0.05, 0.0, 0.1), (0.6, 0.0, -0.1), (0.02, 0.3, 1.5)])
def test_the_polhode_closes_with_the_period_of_the_jacobi_elliptic_solution(extra_spin):
    """Euler's equations integrated to the period 4K(k)/lambda of their Jacobi elliptic
    solution bring the body-frame angular velocity back to its start (to the integrator's
    tolerance), and not before: at every earlier sample it is far from it. The three starts
    circle the largest axis, the smallest axis (M^2 < 2EB), and the largest again at k near 0."""
    system = ReleasedDisk(DiskParams(omega=2.0), extra_spin=extra_spin)
    moments = system.kernel_params()
    sim = Simulation(system, "taylor", rtol=1e-13, reference=None)
    w0 = sim.state[0, :3].copy()
    period = disk.polhode_period(moments, w0)
    assert math.isfinite(period) and period > 0
    closest = math.inf
    for t in np.linspace(0.05, 0.95, 60) * period:
        sim.advance_to(float(t))
        closest = min(closest, float(np.linalg.norm(sim.state[0, :3] - w0)))
    assert closest > 1e-3 * np.linalg.norm(w0)  # not closed before T
    sim.advance_to(period)
    np.testing.assert_allclose(sim.state[0, :3], w0, atol=1e-10 * np.linalg.norm(w0))


def test_the_polhode_period_is_infinite_on_the_separatrix_and_the_wobble_period_on_an_axis():
    """On the intermediate axis (the seed's released disk) the polhode is the separatrix: it
    never closes. Exactly on the largest axis the period is that of small wobbles about it,
    2 pi / (w sqrt((C - A)(C - B) / AB))."""
    a, b, c = 0.25, 29 / 36, 19 / 18
    moments = np.array([a, b, c])
    assert disk.polhode_period(moments, np.array([0.0, 2.0, 0.0])) == math.inf
    wobble = 2.0 * math.sqrt((c - a) * (c - b) / (a * b))
    assert disk.polhode_period(moments, np.array([0.0, 0.0, 2.0])) == pytest.approx(
        2 * math.pi / wobble, rel=1e-14
    )


def _polhode_period_mp(moments, w):
    """4K(k)/lambda in 50-digit arithmetic from the exact values of the given doubles, with
    ``1 - k^2`` formed as ``(C - A)(M^2 - 2EB) / ((C - B)(M^2 - 2EA))`` and K from mpmath."""
    import mpmath

    with mpmath.workdps(50):
        order = np.argsort(moments)
        a, b, c = (mpmath.mpf(float(x)) for x in np.asarray(moments)[order])
        wa, wb, wc = (mpmath.mpf(float(x)) for x in np.asarray(w)[order])
        two_e = a * wa**2 + b * wb**2 + c * wc**2
        m2 = (a * wa) ** 2 + (b * wb) ** 2 + (c * wc) ** 2
        if m2 < two_e * b:
            a, c = c, a
        lam2 = (c - b) * (m2 - two_e * a) / (a * b * c)
        k2c = (c - a) * (m2 - two_e * b) / ((c - b) * (m2 - two_e * a))
        return float(4 * mpmath.ellipk(1 - k2c) / mpmath.sqrt(lam2)), float(k2c)


@pytest.mark.parametrize("side", ["smallest", "largest", "both"])
def test_the_polhode_period_keeps_its_digits_next_to_the_separatrix(side):
    """A spin along the intermediate axis tipped so that 1 - k^2 is about 1e-7: the period
    within 1e-12 of a 50-digit mpmath evaluation of 4K(k)/lambda for the same doubles. In
    doubles M^2 - 2EB loses the digits 1 - k^2 is made of (3.3e-10 off before)."""
    a, b, c = ReleasedDisk(OTHERS[0]).kernel_params()
    wb = 3.0
    wa2 = 1e-7 * b * (c - b) * wb**2 / (a * (c - a))  # circles the smallest axis
    wc2 = 1e-7 * b * (b - a) * wb**2 / (c * (c - a))  # circles the largest axis
    if side == "smallest":
        w = np.array([math.sqrt(wa2), wb, 0.0])
    elif side == "largest":
        w = np.array([0.0, wb, math.sqrt(wc2)])
    else:  # both tipped, their contributions to M^2 - 2EB nearly cancelling
        wa = 0.01
        wc = math.sqrt(a * (b - a) * wa**2 / (c * (c - b)) + wc2)
        w = np.array([wa, wb, wc])
    reference, k2c = _polhode_period_mp(np.array([a, b, c]), w)
    assert 3e-8 < k2c < 3e-7
    assert disk.polhode_period(np.array([a, b, c]), w) == pytest.approx(reference, rel=1e-12)
