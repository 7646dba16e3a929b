"""numba set-up shared by every compiled module of :mod:`dynamics`.

Compiled kernels are cached on disk (``njit(cache=True)``), but numba invalidates a cached
function only when *its own* source file changes: an integrator in one module that calls a
right-hand side defined in another would keep running stale machine code after the right-hand
side is edited. We therefore key the cache directory on a hash of every source file of the
package but the atlas's, so any edit to the dynamics starts a fresh cache. Set
``NUMBA_CACHE_DIR`` yourself to override, and ``NUMBA_DISABLE_JIT=1`` to run the same source as
plain Python for debugging.
"""

from __future__ import annotations

import os

from ._cachedir import UNCACHED  # noqa: F401  (re-exported: what the hash leaves out)
from ._cachedir import cache_dir as _cache_dir
from ._cachedir import source_hash as _source_hash  # noqa: F401  (re-exported)

if "NUMBA_CACHE_DIR" not in os.environ:
    os.environ["NUMBA_CACHE_DIR"] = _cache_dir()

import numba  # (must follow the environment set-up above)

# numba reads NUMBA_CACHE_DIR at import; if it was imported before us, set it directly.
if not numba.config.CACHE_DIR:
    numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]


def njit(*args, **kwargs):
    """``numba.njit`` with ``error_model="numpy"``: a division by zero gives inf or nan (which the
    drivers report as a non-finite state) instead of raising. The raising branch is not just
    semantics: it splits every right-hand side into blocks across which numba cannot prune the
    reference counts of its array arguments, and the two atomic operations per evaluation that
    remain cost about a third of the hoop's right-hand side inside DOP853."""
    kwargs.setdefault("error_model", "numpy")
    return numba.njit(*args, **kwargs)


__all__ = ["njit"]
