"""Our right-hand sides in heyoka's expression system, written once for every heyoka run.

The parameters enter as the combinations the right-hand sides use (:func:`heyoka_pars`), as
heyoka's runtime parameters ``hy.par[i]``: one compiled integrator then serves every case of a
system. The combinations are formed in double precision, as our kernels form them, so that a
run in extended precision (the references) solves the very equations our methods solve. The
equations are those of :mod:`mechviz.dynamics.cyclotron`, :mod:`mechviz.dynamics.hoop` and the free body of
:mod:`mechviz.dynamics.disk` (kernel parameters as in :mod:`mechviz.dynamics.integrators.kernels`).
"""

from __future__ import annotations

import numpy as np

from mechviz.dynamics.integrators.kernels import CYCLOTRON, HOOP


def heyoka_pars(sys_id: int, params: np.ndarray) -> np.ndarray:
    """The runtime parameters of :func:`heyoka_equations` from our kernel parameters: the
    combinations the right-hand side uses, so that no expression of parameters is expanded."""
    p = np.asarray(params, dtype=float)
    if sys_id == CYCLOTRON:
        return np.array([p[0]])
    if sys_id == HOOP:
        M, m, ga = p[0], p[1], p[3] / p[2]
        return np.array([m, ga, 2.0 * M + m, (M + m) * ga])
    i1, i2, i3 = p
    return np.array([(i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3])


def heyoka_equations(sys_id: int):
    """Our right-hand sides in heyoka's expressions, parameters as ``hy.par[i]``."""
    import heyoka as hy

    par = hy.par
    if sys_id == CYCLOTRON:
        x, y, z, vx, vy, vz = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
        return [(x, vx), (y, vy), (z, vz), (vx, par[0] * vy), (vy, -par[0] * vx), (vz, 0.0 * vz)]
    if sys_id == HOOP:
        th1, th2, w1, w2 = hy.make_vars("th1", "th2", "w1", "w2")
        m, ga, m11, mg = par[0], par[1], par[2], par[3]
        s, c = hy.sin(th1 - th2), hy.cos(th1 - th2)
        r1 = -m * s * w2 * w2 - mg * hy.sin(th1)
        r2 = s * w1 * w1 - ga * hy.sin(th2)
        det = m11 - m * c * c
        return [
            (th1, w1),
            (th2, w2),
            (w1, (r1 - m * c * r2) / det),
            (w2, (m11 * r2 - c * r1) / det),
        ]
    w1, w2, w3, q0, q1, q2, q3 = hy.make_vars("w1", "w2", "w3", "q0", "q1", "q2", "q3")
    return [
        (w1, par[0] * w2 * w3),
        (w2, par[1] * w3 * w1),
        (w3, par[2] * w1 * w2),
        (q0, 0.5 * (-q1 * w1 - q2 * w2 - q3 * w3)),
        (q1, 0.5 * (q0 * w1 + q2 * w3 - q3 * w2)),
        (q2, 0.5 * (q0 * w2 + q3 * w1 - q1 * w3)),
        (q3, 0.5 * (q0 * w3 + q1 * w2 - q2 * w1)),
    ]
