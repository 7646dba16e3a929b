"""The fourth system's view (:mod:`spherical_exhibit`'s model drawn with viser), defined in the
test suite only: a pivot and a bob on the sphere of the rod's length, enough for a recording's
scene. Registered beside the system and its model by :func:`registered`.
"""

from __future__ import annotations

import math

import numpy as np
import spherical_exhibit
from spherical import SPEC
from spherical_exhibit import PendulumModel

from mechviz.dynamics.registry import Registration
from mechviz.viz.scene import EXHIBITS
from mechviz.viz.scene.base import Exhibit, error_text

PIVOT = np.array([0.0, 0.0, 2.2])  # [m] above the exhibit's origin


class PendulumExhibit(Exhibit):
    """The spherical pendulum's model drawn: its pivot and its bob."""

    model_type = PendulumModel
    icon = "CIRCLE"

    def _build(self) -> None:
        s, r = self.scene, self.root
        s.add_frame(r, show_axes=False, position=self.origin)
        s.add_icosphere(f"{r}/pivot", radius=0.04, color=(90, 90, 90), position=PIVOT)
        self.bob = s.add_icosphere(f"{r}/bob", radius=0.08, color=(200, 60, 60), position=PIVOT)

    def _started(self) -> None:
        """A new run: nothing to rebuild (the bob is drawn from the state)."""

    def bob_position(self, state: np.ndarray) -> np.ndarray:
        """The bob [m] in the exhibit's frame: ``l (sin theta cos phi, sin theta sin phi,
        -cos theta)`` below the pivot."""
        th, ph = float(state[0]), float(state[1])
        l = self.model.config.physics().length
        return PIVOT + l * np.array(
            [math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), -math.cos(th)]
        )

    def draw(self) -> None:
        self.bob.position = tuple(self.bob_position(self.model.state))

    def readout(self) -> str:
        return f"t = {self.model.t:.2f} s; error {error_text(self.model.sample)}"

    def build_panel(self, panel) -> None:
        """The common settings only (the panel builds those)."""

    @property
    def camera(self):
        return (tuple(self.origin + (0.0, -6.0, 1.6)), tuple(self.origin + (0.0, 0.0, 1.2)))

    def _extent(self):
        l = self.model.config.physics().length + 0.1
        return (-l, -l, PIVOT[2] - l), (l, l, PIVOT[2] + 0.1)


def registered() -> Registration:
    """The spherical pendulum, its model and its view registered (undo with the result)."""
    reg = spherical_exhibit.registered()
    try:
        return reg.add(EXHIBITS, SPEC.name, PendulumExhibit)
    except BaseException:
        reg.unregister()
        raise
