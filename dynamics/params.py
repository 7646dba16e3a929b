"""Validation shared by the parameter dataclasses of every system.

Each system keeps its parameters in a frozen dataclass whose ``__post_init__`` calls these
helpers, so an invalid value is rejected where it is made, with a message that names the field
and the value (the CLI and the viewer show that message as is).
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any


def finite(name: str, value: Any) -> float:
    """Return ``value`` as a float, or raise ``ValueError`` if it is not a finite real number."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {x}")
    return x


def positive(name: str, value: Any) -> float:
    """A finite number > 0 (masses, lengths, gravity)."""
    x = finite(name, value)
    if x <= 0.0:
        raise ValueError(f"{name} must be positive, got {x}")
    return x


def nonzero(name: str, value: Any) -> float:
    """A finite number != 0 (charge and field: their signs are physical, zero is degenerate)."""
    x = finite(name, value)
    if x == 0.0:
        raise ValueError(f"{name} must be nonzero, got {x}")
    return x


def coerce(obj: Any, rules: dict[str, Any]) -> None:
    """Validate and store every field of a frozen dataclass ``obj`` through its rule."""
    for f in fields(obj):
        rule = rules.get(f.name, finite)
        object.__setattr__(obj, f.name, rule(f.name, getattr(obj, f.name)))
