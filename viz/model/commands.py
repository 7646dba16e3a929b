"""The commands an exhibit's model takes (:meth:`mechviz.viz.model.base.ExhibitModel.apply`), each a
frozen typed value.

Python code builds them directly::

    model.apply(Reset())                                   # every run afresh from the start
    model.apply(Set(fields={"method": "rk4", "dt": 0.02})) # settings by name; restarts the run
    model.apply(Set(params={"field": 2.0}))                # physical parameters by name
    model.apply(Kick(dv=0.5))                              # cyclotron: radial kick [m/s]

A command written as a dict (``{"op": "kick", "dv": 0.5}``, from a file or another program)
becomes one through :func:`parse`, the only place a dict is read; a set's settings sit beside
its ``op`` there, as ``{"op": "set", "method": "rk4", "params": {"field": 2.0}}``, and
:func:`as_dict` writes that form back. Units are SI.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

import msgspec

from mechviz.dynamics import params as _v


class _Command(msgspec.Struct, frozen=True, tag_field="op", forbid_unknown_fields=True):
    """What every command shares: it is known by its ``op`` (the tag) and holds no other field
    than its class names."""

    @classmethod
    def op(cls) -> str:
        """The command's name, as ``op`` in its dict form."""
        return cls.__struct_config__.tag


class Reset(_Command, frozen=True, tag_field="op", tag="reset"):
    """Start every run afresh from the configured start: time back to 0, the charts and the
    figures cleared."""


class Set(_Command, frozen=True, tag_field="op", tag="set"):
    """Change settings of the exhibit's config: ``fields`` by setting name (``method``, ``dt``
    [s], ``rtol``, ``mode``, ...; the exhibit's config lists them) and ``params``, the system's
    physical parameters by name (SI units; those not named keep their value). The config
    validates every value (an invalid one raises ``ValueError`` naming it and changes nothing);
    whether the runs restart, jump to a new start or go on depends on which settings changed."""

    fields: dict[str, Any] = {}
    params: dict[str, float] = {}

    def __post_init__(self) -> None:
        if "params" in self.fields:  # the parameters have their own field, merged by name
            raise _v.SettingError("params", "params are given as Set.params, not in Set.fields")


class Kick(_Command, frozen=True, tag_field="op", tag="kick"):
    """Cyclotron: add ``dv`` [m/s] of radial velocity (outward if positive) to the charge and
    to every charge of a beam, now, without a restart: the clock and the runs go on. ``None``:
    the kick strength in force (the config's ``kick``)."""

    dv: float | None = None

    def __post_init__(self) -> None:
        if self.dv is not None:
            _v.finite("dv", self.dv)  # SettingError naming dv


#: Every command an exhibit's model can be given (each exhibit takes some of them).
Command = Reset | Set | Kick

COMMANDS: tuple[type[_Command], ...] = (Reset, Set, Kick)
_BY_OP = {c.op(): c for c in COMMANDS}


def parse(obj: Mapping[str, Any] | str) -> Command:
    """The command a dict stands for: ``op`` names it, the other keys are its fields (a set's
    settings by name, and ``params``); a bare op string is a command without fields
    (``"reset"``). Anything else raises ``ValueError`` in one line naming the op or the field."""
    if isinstance(obj, str):
        obj = {"op": obj}
    if not isinstance(obj, Mapping):
        raise ValueError(f"a command must be a dict with an op, got {type(obj).__name__}")
    op = obj.get("op")
    if op not in _BY_OP:
        raise ValueError(f"op must be one of {', '.join(_BY_OP)}; got {op!r}")
    if op == Set.op():  # its settings sit beside the op, as the viewer's commands always had them
        rest = {k: v for k, v in obj.items() if k not in ("op", "params")}
        obj = {"op": op, "fields": rest, **({"params": obj["params"]} if "params" in obj else {})}
    try:
        return msgspec.convert(obj, Command)
    except msgspec.ValidationError as exc:
        raise _error(op, exc, obj.get("params")) from None


def as_dict(command: Command) -> dict[str, Any]:
    """The dict form :func:`parse` reads: ``op`` and the fields (a set's settings beside it)."""
    out = msgspec.structs.asdict(command)
    if isinstance(command, Set):
        params = out.pop("params")
        out = {**out.pop("fields"), **({"params": params} if params else {})}
    return {"op": command.op(), **out}


def refused(key: str, takes: tuple[type[_Command], ...], command: object) -> ValueError:
    """The error for ``command`` given to the exhibit ``key``, which takes the commands
    ``takes``: it names the command, or the value that is none (a dict: :func:`parse` first)."""
    ops = ", ".join(c.op() for c in takes)
    if isinstance(command, COMMANDS):
        return ValueError(f"{key} takes no {command.op()} command; op must be one of {ops}")
    return ValueError(
        f"a command must be one of {ops} (mechviz.viz.model.commands); got {command!r}"
    )


def _error(op: str, exc: msgspec.ValidationError, params: Any) -> ValueError:
    """msgspec's message as one line that names the field: a ``SettingError`` from a command's
    own check as it is (it names its field, and the panel labels it); ``at `$.dv``` moves to
    the front; an unknown field is named with the fields the command takes."""
    cause = exc.__cause__
    if isinstance(cause, ValueError):
        return cause
    message = str(exc)
    unknown = re.fullmatch(r"Object contains unknown field `(.+)`", message)
    if unknown:
        takes = ", ".join(_BY_OP[op].__struct_fields__) or "no fields"
        return _v.SettingError(
            unknown[1], f"{unknown[1]} is not a field of {op} (it takes {takes})"
        )
    where = re.fullmatch(r"(.*) - at `\$\.([^`]+)`", message)
    if where:
        text, field = where[1], where[2].removeprefix("fields.")
        if field == "params[...]":  # msgspec does not name the key: the first that is no number
            bad = [
                k
                for k, v in params.items()
                if isinstance(v, bool | str) or not isinstance(v, int | float)
            ]
            field = f"params.{bad[0]}" if bad else "params"
        return _v.SettingError(field, f"{field}: {text[:1].lower()}{text[1:]} ({op})")
    return ValueError(f"{op}: {message}")
