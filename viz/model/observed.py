"""A headless model that its views observe: :meth:`Observed.observe` registers a callback,
:meth:`Observed.changed` calls every one after a change (the model's own thread: the viewer's
loop). A view draws when told, rather than comparing counters each frame."""

from __future__ import annotations

from collections.abc import Callable


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
