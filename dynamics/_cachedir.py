"""Where compiled code is cached: a folder per version of the package's sources (no numba here,
so that code loading a module compiled ahead of time, :mod:`mechviz.dynamics.aot`, finds it without
importing numba)."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

# Left out of the hash: the atlas defines no cached function and nothing compiled imports it, so
# an edit there must not throw away (and make the next run recompile) every cached kernel. A
# cached function added there would have to come back in. (The benchmark, mechviz.bench, lives
# outside this package and is not hashed either.)
UNCACHED = ("atlas",)


def source_hash(root: Path = Path(__file__).parent) -> str:
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        if path.relative_to(root).parts[0] in UNCACHED:
            continue
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


#: The package's own sources' hash, worked out once per process (reading every source file is
#: a few milliseconds, and a fresh process's first answer asks for the folder more than once).
_OWN: list[str] = []


def cache_dir() -> str:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    if not _OWN:
        _OWN.append(source_hash())
    return os.path.join(base, "mechviz", f"numba-{_OWN[0]}")
