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

import hashlib
import os
from pathlib import Path

# Left out of the hash: the atlas defines no cached function and nothing compiled imports it, so
# an edit there must not throw away (and make the next run recompile) every cached kernel. A
# cached function added there would have to come back in. (The benchmark, mechviz_bench, lives
# outside this package and is not hashed either.)
UNCACHED = ("atlas",)


def _source_hash(root: Path = Path(__file__).parent) -> str:
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        if path.relative_to(root).parts[0] in UNCACHED:
            continue
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _cache_dir() -> str:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "mechviz", f"numba-{_source_hash()}")


if "NUMBA_CACHE_DIR" not in os.environ:
    os.environ["NUMBA_CACHE_DIR"] = _cache_dir()

import numba  # noqa: E402  (must follow the environment set-up above)

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
