"""Text from outside (file names, paths, recordings) made safe to print on one terminal line."""

from __future__ import annotations

import unicodedata


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


def has_control_characters(text: str) -> bool:
    """``text`` holds a control character (an escape sequence, a NUL, a bell): text a file
    carries is shown on a terminal and drawn into pages and frames, where these do harm or
    nothing good. Line breaks and tabs are not counted."""
    return any(unicodedata.category(c) == "Cc" and c not in "\n\t" for c in text)
