"""Validation shared by every setting of every system: one error type, one rule per kind of value,
and one rule for a number a person types.

Each system keeps its parameters in a frozen dataclass whose ``__post_init__`` calls these
helpers, so an invalid value is rejected where it is made. A refusal is a :class:`SettingError`:
a ``ValueError`` that carries the *field* it is about (``"mass"``, ``"dt"``, ``"initial.modes"``)
beside its message. Each front end maps the field to its own label (a flag ``--mass``, a demo key
``parameters.mass``, a panel label "Mass m [kg]") without reading the message.
"""

from __future__ import annotations

import math
import re
import sys
from collections.abc import Callable, Iterable
from dataclasses import fields
from typing import Any

import numpy as np

#: The smallest normal double (2.2e-308): a typed value closer to 0 has lost precision.
TINY = sys.float_info.min


#: A decimal number in ASCII (and the words float() knows for infinity and not-a-number, refused
#: afterwards with a message of their own).
_NUMBER = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf|infinity|nan)",
    re.IGNORECASE | re.ASCII,
)


class SettingError(ValueError):
    """A setting that cannot be used: ``field`` names it, ``str(err)`` says why in one line."""

    def __init__(self, field: str, message: str, *, fields: tuple[str, ...] = ()) -> None:
        super().__init__(message)
        self.field = field
        #: Every setting to blame, ``field`` first (several when only together they fail).
        self.fields = fields or (field,)


def parse_number(field: str, text: Any) -> float:
    """What a person typed as a number, read by the one rule every front end uses.

    The text is read as Python reads a float (``0.025``, ``2.5e-2``, ``2.5E-2``; a typographic
    minus ``−`` counts as ``-``) but in ASCII digits only and without underscores (``1_0`` and
    a full-width ``１`` are refused: neither is a number as a person writes it down);
    surrounding blanks are ignored. Refused with a
    :class:`SettingError` naming ``field``: anything else, ``nan`` and ``inf``, and a value so
    close to 0 that it is below the smallest normal double (a subnormal has lost its digits).
    A number (``int`` or ``float``) passes through the same checks."""
    if isinstance(text, bool):
        raise SettingError(field, f"{field} must be a number, got {text!r}")
    if isinstance(text, int | float):
        x = float(text)
    else:
        raw = str(text).strip().replace("\u2212", "-")
        try:
            if not _NUMBER.fullmatch(raw):  # float() alone takes 1_0 and non-ASCII digits
                raise ValueError(raw)
            x = float(raw)
        except ValueError:
            raise SettingError(
                field, f"{field} must be a number, got {str(text)!r} (write e.g. 0.025 or 2.5e-2)"
            ) from None
    if not math.isfinite(x):
        raise SettingError(field, f"{field} must be finite, got {text!r}")
    if 0.0 < abs(x) < TINY:
        raise SettingError(
            field,
            f"{field} {x:.3g} is below the smallest normal double ({TINY:.3g}); "
            "use 0 or a larger value",
        )
    return x


def guarded(fn: Callable[[], Any], fallback: Any = math.nan) -> Any:
    """``fn()``, or ``fallback`` (NaN) if its arithmetic overflows, divides by zero or leaves its
    domain: a derived result that cannot be represented then shows as NaN, which
    :func:`mechviz.dynamics.analysis.unrepresentable` reports, instead of a traceback."""
    try:
        with np.errstate(all="ignore"):
            return fn()
    except (OverflowError, ZeroDivisionError, ValueError, np.linalg.LinAlgError):
        return fallback  # ValueError: math domain, or a helper's finite-input check


def blamed(
    names: Iterable[str],
    fixed_without: Callable[[str], bool],
    errors: tuple[type[BaseException], ...] = (ValueError, ArithmeticError),
) -> list[str]:
    """Of the settings ``names`` a person gave, those whose default alone clears a problem their
    combination causes (``fixed_without(name)`` true): what a refusal of a consequence of several
    settings names. A trial that raises one of ``errors`` (a setting that cannot stand without
    the other) clears nothing. Empty when no one setting alone is to blame."""
    out = []
    for name in names:
        try:
            with np.errstate(all="ignore"):
                if fixed_without(name):
                    out.append(name)
        except errors:
            pass
    return out


def finite(name: str, value: Any) -> float:
    """``value`` as a finite float (:func:`parse_number`), else :class:`SettingError`."""
    if type(value) is float and (TINY <= abs(value) < math.inf or value == 0.0):
        # the common case, a plain float that passes every check below, decided in one test:
        # the tolerances of every solve come through here, and the general path costs 0.4 us
        return value
    try:
        x = float(value) if not isinstance(value, str | bool) else value
    except (TypeError, ValueError):
        raise SettingError(name, f"{name} must be a number, got {value!r}") from None
    if isinstance(x, float) and not math.isfinite(x):
        raise SettingError(name, f"{name} must be finite, got {x}")
    return parse_number(name, x)


def positive(name: str, value: Any) -> float:
    """A finite number > 0 (masses, lengths, gravity, steps)."""
    x = finite(name, value)
    if x <= 0.0:
        raise SettingError(name, f"{name} must be positive, got {x}")
    return x


def nonzero(name: str, value: Any) -> float:
    """A finite number != 0 (charge and field: their signs are physical, zero is degenerate)."""
    x = finite(name, value)
    if x == 0.0:
        raise SettingError(name, f"{name} must be nonzero, got {x}")
    return x


def below_one(name: str, value: Any) -> float:
    """A tolerance: a finite number in (0, 1)."""
    x = positive(name, value)
    if x >= 1.0:
        raise SettingError(name, f"{name} must be below 1, got {x}")
    return x


def numbers(name: str, values: Any, n: int) -> tuple[float, ...]:
    """``values`` as ``n`` finite floats, else :class:`SettingError` naming ``name``."""
    try:
        out = tuple(values)
    except TypeError:
        raise SettingError(name, f"{name} must be {n} numbers, got {values!r}") from None
    if len(out) != n or any(isinstance(v, str) for v in out):
        raise SettingError(name, f"{name} must be {n} numbers, got {values!r}")
    return tuple(finite(name, v) for v in out)


def coerce(obj: Any, rules: dict[str, Any]) -> None:
    """Validate and store every field of a frozen dataclass ``obj`` through its rule."""
    for f in fields(obj):
        rule = rules.get(f.name, finite)
        object.__setattr__(obj, f.name, rule(f.name, getattr(obj, f.name)))
