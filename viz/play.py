"""``mechviz play``: serve ``.viser`` recordings with the browser client in the viser wheel.

The server answers five kinds of request and nothing else:

``/``
    with ``?playbackPath=...`` viser's client (``index.html`` from the wheel), which then fetches
    the recording; without it, a redirect to the one recording, or to ``/list`` when there are
    several (the client opened without a recording would wait for a live server forever).
``/list``
    an HTML list of the recordings, every name escaped.
``/recordings/NAME``
    the bytes of recording ``NAME``: a file named ``*.viser`` found in the folder when the server
    started that, when requested, still resolves (symlinks followed) to a regular file inside
    that folder with a single name (a hard link may lead anywhere, so a file with more than one
    link is not served); anything else is 404, so a link to ``/etc/passwd`` is never served.
    A recording with a manifest beside it (``NAME.json``, as ``mechviz record`` writes it) is
    checked against it at start and at each request (:func:`mechviz.dynamics.fileset.check_beside`):
    a folder that holds a mix of two recordings is refused at start, and answered with 409 and
    the sentence naming the file that does not belong while it is served; a recording written
    again meanwhile is served anew.

The server (:mod:`mechviz.viz.play_server`) has header and answer timeouts, a normal listen backlog and
limits on connections per client and in all, so idle connections cannot starve a real request.
A client that closes its connection early is not an error (no traceback). Names are printed
with control characters escaped (:func:`mechviz.viz.printable.printable`). :func:`reachable_urls`
and :func:`exposure_note` say where a server bound to HOST can be reached; ``mechviz view`` prints
them too.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import html
import os
import socket
import stat
import urllib.parse
from pathlib import Path

from mechviz.dynamics import fileset

from .cli.errors import CliError, command, whole
from .play_server import GuardedHandler, GuardedServer
from .printable import printable

DEFAULT_PLAY_PORT = 8090
_WILDCARD = ("0.0.0.0", "", "::")


ABOUT = """\
serve a .viser recording (or a folder of them) with viser's client

Serve PATH (a .viser file or a folder of them) on HOST:PORT with the browser client that ships
in the viser wheel; prints the URLs; Ctrl-C stops. Only regular files inside the folder are
served (symlinks that lead out of it are not). A recording with its manifest beside it
(NAME.json, as mechviz record writes it) is served only while every file the manifest lists
matches it: a folder holding files of two recordings is refused, naming the file.
"""


def add_command(sub) -> None:
    """Register ``play`` on the ``mechviz`` sub-parser set."""
    q = command(sub, "play", ABOUT)
    q.add_argument("path", help=".viser file or folder")
    q.add_argument(
        "--host",
        default="127.0.0.1",
        help="interface to bind (default 127.0.0.1: this machine only; 0.0.0.0: every "
        "interface, exposed to the network)",
    )
    q.add_argument(
        "--port",
        type=whole,
        default=DEFAULT_PLAY_PORT,
        help=f"first port to try, 0 to 65535 (default {DEFAULT_PLAY_PORT}; 0: any free one)",
    )
    q.set_defaults(func=run_play)


# --------------------------------------------------------------------------- where it is reachable
def _local_addresses() -> list[str]:
    """This machine's IPv4 addresses other than loopback (best effort, no network traffic)."""
    found: list[str] = []
    try:
        found += socket.gethostbyname_ex(socket.gethostname())[2]
    except OSError:
        pass
    try:  # the address of the interface with the default route (a UDP connect sends nothing)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.connect(("192.0.2.1", 9))
            found.append(s.getsockname()[0])
    except OSError:
        pass
    return [a for a in dict.fromkeys(found) if not a.startswith("127.")]


def reachable_urls(host: str, port: int) -> list[str]:
    """``http://ADDRESS:PORT`` for every address a server bound to ``host`` answers at: for a
    wildcard host (``0.0.0.0``, ``::``, empty) 127.0.0.1 and this machine's other addresses."""
    if host in _WILDCARD:
        return [f"http://{a}:{port}" for a in ["127.0.0.1", *_local_addresses()]]
    shown = f"[{host}]" if ":" in host else host
    return [f"http://{shown}:{port}"]


def exposure_note(host: str) -> str | None:
    """One line saying that a server bound to ``host`` is reachable from the network, or None
    for a loopback host (this machine only)."""
    if host == "localhost" or host.startswith("127.") or host == "::1":
        return None
    what = "every interface" if host in _WILDCARD else host
    return (
        f"exposed to the network: bound to {what}, anyone who can reach this machine can "
        "open these URLs"
    )


# --------------------------------------------------------------------------- the server
def _client_index() -> bytes:
    import viser

    return (Path(viser.__file__).parent / "client" / "build" / "index.html").read_bytes()


def _regular_inside(path: Path, folder: Path) -> Path | None:
    """``path`` resolved, if it is a regular file with one link inside ``folder`` (resolved),
    else None."""
    try:
        real = path.resolve(strict=True)
        st = real.stat()
    except (OSError, RuntimeError):
        return None
    if not stat.S_ISREG(st.st_mode) or st.st_nlink != 1:
        return None
    return real if real.is_relative_to(folder) else None


def _read_served(path: Path, folder: Path) -> bytes | None:
    """The bytes of ``path`` if :func:`_regular_inside` allows it, read from the very file that
    was checked (opened without following links, then compared by device and inode)."""
    for _ in range(3):  # a recording switched to a new set between the check and the open
        real = _regular_inside(path, folder)
        if real is None:
            return None
        try:
            fd = os.open(real, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC)
        except OSError:
            continue
        with os.fdopen(fd, "rb") as fh:
            st = os.fstat(fd)
            with contextlib.suppress(OSError):
                same = real.stat()
                if st.st_nlink == 1 and (st.st_dev, st.st_ino) == (same.st_dev, same.st_ino):
                    return fh.read()
    return None


def _recordings(path: Path) -> tuple[Path, dict[str, Path]]:
    """The folder served and its recordings (name -> path) at ``path``."""
    shown = printable(str(path))
    try:
        if not path.exists():
            raise CliError(f"{shown}: no such file or folder")
        if path.is_file():
            if path.suffix != ".viser":
                raise CliError(f"{shown}: not a .viser recording")
            here = path.absolute()
            if _regular_inside(here, here.parent.resolve()) is not None:
                # Resolved again at each request: a recording written again is served anew.
                folder, found = here.parent.resolve(), {path.name: here}
            else:
                real = path.resolve()
                if _regular_inside(real, real.parent) is None:
                    raise CliError(f"{shown}: not a regular file with a single link")
                folder, found = real.parent, {path.name: real}
        else:
            folder = path.resolve()
            found = {}
            for p in sorted(folder.glob("*.viser")):
                if _regular_inside(p, folder) is not None:
                    found[p.name] = p
    except OSError as exc:  # a name too long, a folder we may not read
        raise CliError(f"{shown}: {exc.strerror or exc}") from None
    if not found:
        raise CliError(
            f"{shown}: no .viser recordings in this folder (regular files inside it, one link each)"
        )
    for p in found.values():
        try:
            with fileset.reading(p.parent):
                fileset.check_beside(p)
        except ValueError as exc:  # a mix of two recordings, or a manifest that is not one
            raise CliError(f"{printable(str(p))}: {exc}") from None
        except OSError as exc:
            raise CliError(f"{printable(str(p))}: {exc.strerror or exc}") from None
    return folder, found


def _read_checked(path: Path, folder: Path) -> tuple[bytes | None, str | None]:
    """``(bytes, None)`` of a recording to serve (:func:`_read_served`) that agrees with the
    manifest beside it, ``(None, sentence)`` naming the file that does not belong, or
    ``(None, None)`` when it is not served at all."""
    with fileset.reading(path.parent):
        data = _read_served(path, folder)
        if data is None:
            return None, None
        try:
            fileset.check_beside(path, data)
        except ValueError as exc:
            return None, str(exc)
        except OSError:
            return None, None
    return data, None


def make_play_server(path: Path, host: str = "127.0.0.1", port: int = DEFAULT_PLAY_PORT):
    """An HTTP server for the recordings at ``path`` (a ``.viser`` file or a folder of them) and
    viser's client, bound to ``host`` and the first free port from ``port`` (0: any).

    Returns ``(server, urls)``: ``urls`` maps each recording's name (and ``"(list)"`` when there
    are several) to its URL on the first reachable address. Raises :class:`CliError` for a bad
    path or port.
    """
    if not 0 <= port <= 65535:
        raise CliError(f"--port: must be from 0 to 65535, got {port}")
    folder, recordings = _recordings(Path(path))
    index = _client_index()

    def playback_url(name: str) -> str:
        return f"/?playbackPath=recordings/{urllib.parse.quote(name)}"

    class Handler(GuardedHandler):
        def do_GET(self) -> None:
            parts = urllib.parse.urlsplit(self.path)
            route = parts.path
            if route in ("/", "/index.html"):
                if "playbackPath" in urllib.parse.parse_qs(parts.query):
                    return self._send(index, "text/html; charset=utf-8")
                only = next(iter(recordings)) if len(recordings) == 1 else None
                return self._redirect(playback_url(only) if only else "/list")
            if route == "/list":
                items = "".join(
                    f'<li><a href="{html.escape(playback_url(n))}">{html.escape(n)}</a></li>'
                    for n in recordings
                )
                page = (
                    "<!doctype html><meta charset=utf-8><title>mechviz recordings</title>"
                    f"<h1>Recordings in {html.escape(folder.name)}</h1><ul>{items}</ul>"
                )
                return self._send(page.encode(), "text/html; charset=utf-8")
            if route.startswith("/recordings/"):
                name = urllib.parse.unquote(route.removeprefix("/recordings/"))
                data, mixed = (
                    _read_checked(recordings[name], folder) if name in recordings else (None, None)
                )
                if data is not None:
                    return self._send(data, "application/octet-stream")
                if mixed is not None:
                    return self._send(mixed.encode(), "text/plain; charset=utf-8", 409)
            self.send_error(404)

        def do_HEAD(self) -> None:
            self.send_error(405)

        def _redirect(self, location: str) -> None:
            self.send_response(302)
            self.send_header("Location", location)
            self.send_header("Content-Length", "0")
            self.end_headers()

        def _send(self, body: bytes, ctype: str, status: int = 200) -> None:
            self.send_response(status)
            self.send_header("Content-Type", ctype)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")
            self.send_header("X-Content-Type-Options", "nosniff")
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args) -> None:
            pass

    first = port
    for attempt in range(100):
        try:
            server = GuardedServer((host, port), Handler)
            break
        except OSError as exc:
            if exc.errno != errno.EADDRINUSE or port == 0 or attempt == 99 or port == 65535:
                raise CliError(f"--port: cannot listen on {host}:{port}: {exc.strerror}") from None
            port += 1
        except (OverflowError, socket.gaierror) as exc:
            raise CliError(f"--host: cannot listen on {host}:{port}: {exc}") from None
    actual = server.server_address[1]
    base = reachable_urls(host, actual)[0]
    urls = {n: f"{base}{playback_url(n)}" for n in recordings}
    if len(recordings) > 1:
        urls["(list)"] = f"{base}/list"
    server.requested_port = first  # type: ignore[attr-defined]
    return server, urls


def run_play(args: argparse.Namespace) -> int:
    server, urls = make_play_server(Path(args.path), args.host, args.port)
    port = server.server_address[1]
    if args.port not in (0, port):
        print(f"port {args.port} is busy; using {port}")
    for name, url in urls.items():
        print(f"{printable(name)}: {url}")
    others = reachable_urls(args.host, port)[1:]
    if others:
        print("also at: " + ", ".join(f"{u}/" for u in others))
    note = exposure_note(args.host)
    if note:
        print(note)
    print("Ctrl-C stops.", flush=True)
    try:
        server.serve_forever(poll_interval=0.2)
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
    print("stopped.")
    return 0
