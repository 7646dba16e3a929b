"""Default settings of every exhibit, in one place.

``DEFAULTS[exhibit]`` holds the method, step size / tolerance, physical parameters and initial
condition the viewer (and the recorder) start from. Exact solutions are the default where they
exist (the charge, the driven disk); the bench may update ``method`` / ``dt`` of the others from
measurements. Units are SI (see the :mod:`dynamics` module docstrings).
"""

from __future__ import annotations

DEFAULTS: dict[str, dict] = {
    "app": {
        "speed": 1.0,  # simulated seconds per real second
        "fps": 60.0,  # display rate of the simulation loop
    },
    "cyclotron": {
        "method": "exact",
        "dt": 0.01,  # used when a fixed-step method is chosen [s]
        "rtol": 1e-9,  # used when an adaptive method is chosen
        "params": {"charge": 1.0, "mass": 1.0, "field": 1.0},
        "speed": 1.0,  # transverse speed at start [m/s]
        "vz": 0.05,  # speed along B [m/s]: the helix pitch
        "beam": False,
        "beam_size": 16,
        "beam_speeds": (0.25, 1.75),  # spread of transverse speeds in the beam [m/s]
        "kick": 0.5,  # default radial kick [m/s]
        "compare_method": None,
        "trail_cap": 600,  # segments
        "height": 2.0,  # displayed height of the field region; z wraps inside it [m]
    },
    "disk": {
        "mode": "driven",  # "driven" (exact uniform rotation) or "released" (free body)
        # used when released; the cheapest method keeping the on-screen error below 1e-3 of the
        # exhibit over 10 minutes (docs/bench/defaults.md)
        "method": "rk4",
        "dt": 1 / 60,
        "rtol": 1e-9,
        "params": {"disk_mass": 1.0, "radius": 1.0, "bead_mass": 1.25, "omega": 2.0},
        "extra_spin": (0.0, 0.0, 0.02),  # rad/s added at release (disk frame): seeds the tumble
        "follow_cm": True,  # draw the released body in the frame moving with its centre of mass
    },
    "hoop": {
        "method": "rk4",  # as cheap as it gets below 1e-3 over 10 minutes (docs/bench/defaults.md)
        "dt": 1 / 60,
        "rtol": 1e-9,
        "params": {"hoop_mass": 1.0, "bead_mass": 0.5, "radius": 1.0, "gravity": 9.81},
        "mode": "mix",  # "mode 1", "mode 2", "mix" or "custom"
        "amplitude": 0.5,  # rad
        "angles": (0.4, -0.3),  # (theta1, theta2) for "custom" [rad]
        "compare_method": None,
        "trail_cap": 240,
    },
}
