"""Text from outside (file names, paths, recordings) made safe to print on one terminal line."""

from __future__ import annotations


def printable(text: str, limit: int = 200) -> str:
    """``text`` safe to print on a terminal: control characters (escape sequences included) and
    bytes that are not valid text shown escaped (``\\x1b``, ``\\udcff``); longer than ``limit``
    characters, the middle is elided."""
    out = "".join(
        c if c.isprintable() else c.encode("unicode_escape", "backslashreplace").decode("ascii")
        for c in text
    )
    if len(out) > limit:
        out = f"{out[: limit // 2]}...{out[-(limit // 2) :]}"
    return out
