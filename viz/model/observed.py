"""A headless model that its views observe: :meth:`Observed.observe` registers a callback,
:meth:`Observed.changed` calls every one after a change (the model's own thread: the viewer's
loop). A view draws when told, rather than comparing counters each frame.

Some changes a view must act on at once, not only draw again: a new start (its nodes are built
for other settings), the estimators' samples starting afresh (its trails break), the runs put
back in time. The model *announces* those by name (:data:`Event`); :meth:`Observed.on`
registers a callback for one. A model never calls its views: it announces, and whatever view
observes it decides what that means for its picture.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal

#: What a model announces: ``"started"`` a new start (new runs from the config), ``"segment"``
#: the motion's samples start afresh within the run (a kick), ``"jumped"`` the runs jumped to a
#: new start without restarting, ``"rewound"`` the runs were put back (scrubbed, or resumed
#: from there), ``"beam"`` the cyclotron's beam came, went or changed.
Event = Literal["started", "segment", "jumped", "rewound", "beam"]


class Observed:
    """What an observed model has: ``revision``, a count of its changes (a recording or a test
    can compare two), and the callbacks to call on each."""

    revision: int = 0

    def observe(self, callback: Callable[[Observed], None]) -> Callable[[], None]:
        """Call ``callback(model)`` after every change from now on; returns the function that
        stops it."""
        observers = self.__dict__.setdefault("_observers", [])
        observers.append(callback)
        return lambda: observers.remove(callback)

    def changed(self) -> None:
        """Note a change (what a view draws may differ): count it and tell every observer."""
        self.revision += 1
        for callback in tuple(self.__dict__.get("_observers", ())):
            callback(self)

    def on(self, event: Event, callback: Callable[[], None]) -> Callable[[], None]:
        """Call ``callback()`` each time the model announces ``event``, from now on; returns the
        function that stops it."""
        listeners = self.__dict__.setdefault("_listeners", {}).setdefault(event, [])
        listeners.append(callback)
        return lambda: listeners.remove(callback)

    def announce(self, event: Event) -> None:
        """Tell whoever listens for ``event`` that it has just happened (the model's state is
        already the new one)."""
        for callback in tuple(self.__dict__.get("_listeners", {}).get(event, ())):
            callback()
