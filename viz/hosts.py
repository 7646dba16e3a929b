"""Checking ``--host`` before a server starts: resolved with a time limit, then bound once.

A name that does not resolve (``example.invalid``), an address that is not one
(``999.999.999.999``), a name too long for DNS, or an address this machine does not have is
refused with one line naming ``--host``, before anything compiles or serves. Resolution runs in
a daemon thread so a resolver that never answers (a closed network) cannot hold the command:
after :data:`RESOLVE_SECONDS` the host is refused.
"""

from __future__ import annotations

import errno
import ipaddress
import socket
import threading
from dataclasses import dataclass

RESOLVE_SECONDS = 5.0
MAX_HOST_CHARS = 253  # the longest DNS name (RFC 1035), dots included
WILDCARDS = ("0.0.0.0", "::", "")


class HostError(ValueError):
    """A ``--host`` that cannot be served on; the message names the host, not the flag."""


@dataclass(frozen=True)
class CheckedHost:
    """A host that resolved and could be bound: its addresses (numeric, as the OS gave them)."""

    host: str
    addresses: tuple[str, ...]

    @property
    def loopback_only(self) -> bool:
        """True if every address is a loopback one (127.0.0.0/8, ::1): this machine only."""
        try:
            return all(ipaddress.ip_address(a.split("%")[0]).is_loopback for a in self.addresses)
        except ValueError:
            return False

    def exposure_note(self) -> str | None:
        """One line saying who can reach a server bound here, or None for loopback only."""
        if self.loopback_only:
            return None
        if self.host in WILDCARDS:
            what = "every interface"
        elif self.addresses == (self.host,):
            what = self.host
        else:
            what = f"{self.host} ({', '.join(self.addresses)})"
        return (
            f"exposed to the network: bound to {what}, anyone who can reach this machine can "
            "open these URLs"
        )


def _resolve(host: str, timeout: float) -> list[tuple]:
    """``getaddrinfo`` for a passive TCP socket on ``host``, given at most ``timeout`` s."""
    found: list = []
    failed: list[BaseException] = []

    def work() -> None:
        try:
            found.extend(
                socket.getaddrinfo(
                    host or None, 0, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
                )
            )
        except (OSError, UnicodeError, ValueError) as exc:
            failed.append(exc)

    worker = threading.Thread(target=work, name="mechviz-resolve-host", daemon=True)
    worker.start()
    worker.join(timeout)
    if worker.is_alive():
        raise HostError(f"{host} did not resolve within {timeout:g} s")
    if failed:
        exc = failed[0]
        if isinstance(exc, socket.gaierror):
            why = exc.strerror or str(exc)
        elif isinstance(exc, UnicodeError):
            why = "not a valid host name"
        else:
            why = str(exc)
        raise HostError(f"{host} is not a host this machine can serve on ({why})")
    if not found:
        raise HostError(f"{host} resolved to no address")
    return found


def check_host(host: str, timeout: float = RESOLVE_SECONDS) -> CheckedHost:
    """Resolve ``host`` (within ``timeout`` s) and bind a socket to its first address on a free
    port, then close it; :class:`HostError` saying why if either fails."""
    if not isinstance(host, str) or any(c.isspace() or ord(c) < 32 for c in host):
        raise HostError(f"{host!r} is not a host name or address")
    if len(host) > MAX_HOST_CHARS:
        raise HostError(f"a host name has at most {MAX_HOST_CHARS} characters, got {len(host)}")
    infos = _resolve(host, timeout)
    family, kind, proto, _, address = infos[0]
    try:
        with socket.socket(family, kind, proto) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.bind((address[0], 0, *address[2:]))
    except OSError as exc:
        if exc.errno == errno.EADDRNOTAVAIL:
            shown = host if host == address[0] else f"{host} ({address[0]})"
            raise HostError(f"{shown} is not an address of this machine") from None
        raise HostError(f"cannot listen on {host}: {exc.strerror or exc}") from None
    addresses = tuple(dict.fromkeys(str(info[4][0]) for info in infos))
    return CheckedHost(host, addresses)
