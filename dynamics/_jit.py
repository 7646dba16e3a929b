"""numba set-up shared by every compiled module of :mod:`dynamics`.

Compiled kernels are cached on disk (``njit(cache=True)``), but numba invalidates a cached
function only when *its own* source file changes: an integrator in one module that calls a
right-hand side defined in another would keep running stale machine code after the right-hand
side is edited. We therefore key the cache directory on a hash of every source file of the
package but the atlas's, so any edit to the dynamics starts a fresh cache. Set
``NUMBA_CACHE_DIR`` yourself to override, and ``NUMBA_DISABLE_JIT=1`` to run the same source as
plain Python for debugging.

numba itself is imported when first needed, not here: importing it costs about a third of a
second, and a process whose Taylor run is answered by the module compiled ahead of time
(:mod:`mechviz.dynamics.aot`) never needs it. The physics modules, whose Python side every run
uses, mark their few compiled steps with :func:`deferred_njit`: handed to numba only when
something compiled is first used.
"""

from __future__ import annotations

import functools
import os
import sys

from ._cachedir import UNCACHED  # noqa: F401  (re-exported: what the hash leaves out)
from ._cachedir import cache_dir as _cache_dir
from ._cachedir import source_hash as _source_hash  # noqa: F401  (re-exported)

if "NUMBA_CACHE_DIR" not in os.environ:
    os.environ["NUMBA_CACHE_DIR"] = _cache_dir()

#: The functions marked with :func:`deferred_njit` not yet handed to numba.
_DEFERRED: list[_Deferred] = []


def numba():
    """numba, imported (once) with the cache folder set, and every deferred function handed to
    it (in its module's place)."""
    module = sys.modules.get("numba")
    if module is None:
        import numba as module  # (NUMBA_CACHE_DIR is set above)

        # numba reads NUMBA_CACHE_DIR at import; if it was imported before us, set it directly.
        if not module.config.CACHE_DIR:
            module.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]
    # All at once: compiled code that calls one of them (the hoop's step calls its forces)
    # finds the others under their names as numba's dispatchers.
    while _DEFERRED:
        deferred = _DEFERRED.pop()
        deferred._dispatcher = module.njit(**deferred._kwargs)(deferred.py_func)
        where = deferred.py_func.__globals__
        if where.get(deferred.__name__) is deferred:
            where[deferred.__name__] = deferred._dispatcher
    return module


def _options(kwargs: dict) -> dict:
    # error_model="numpy": a division by zero gives inf or nan (which the drivers report as a
    # non-finite state) instead of raising. The raising branch is not just semantics: it splits
    # every right-hand side into blocks across which numba cannot prune the reference counts of
    # its array arguments, and the two atomic operations per evaluation that remain cost about a
    # third of the hoop's right-hand side inside DOP853.
    kwargs.setdefault("error_model", "numpy")
    return kwargs


def njit(*args, **kwargs):
    """``numba.njit`` with ``error_model="numpy"`` (see :func:`_options`)."""
    return numba().njit(*args, **_options(kwargs))


class _Deferred:
    """A function to be compiled by numba, not yet handed to it. Calling it hands it over (and
    every other deferred function with it); so does anything that imports numba through
    :func:`numba`, after which the module's name for it is numba's dispatcher."""

    def __init__(self, func, kwargs: dict) -> None:
        functools.update_wrapper(self, func)
        self.py_func = func
        self._kwargs = kwargs
        self._dispatcher = None

    def dispatcher(self):
        """numba's dispatcher for the function (numba imported now if it was not)."""
        if self._dispatcher is None:
            numba()
        return self._dispatcher

    def __call__(self, *args):
        return self.dispatcher()(*args)


def deferred_njit(**kwargs):
    """:func:`njit` for a module imported without numba: the function is handed to numba when
    numba is first needed (module docstring); once numba is loaded, at once."""

    def mark(func):
        if "numba" in sys.modules and not _DEFERRED:
            return numba().njit(**_options(kwargs))(func)
        deferred = _Deferred(func, _options(kwargs))
        _DEFERRED.append(deferred)
        return deferred

    return mark


__all__ = ["deferred_njit", "njit", "numba"]
