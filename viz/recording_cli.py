"""``mechviz record`` and ``mechviz play``: record built-in demos headless, serve recordings.

Registered on the ``mechviz`` parser by :mod:`viz.cli`; viser and matplotlib are imported only
when a command runs.
"""

from __future__ import annotations

import argparse
import errno
import http.server
import sys
import time
import urllib.parse
from pathlib import Path

from dynamics.cli import CliError, number

DEFAULT_PLAY_PORT = 8090


def add_commands(sub) -> None:
    p = sub.add_parser(
        "record",
        help="record a built-in demo headless: .viser, .html, .csv, .png, .json",
        description="Run a demo headless, faster than real time, and write DEMO.viser (scene "
        "recording), DEMO.html (plays from file://), DEMO.csv (traces), DEMO.png (chart) and "
        "DEMO.json (manifest) into --out. Files are replaced atomically.",
    )
    p.add_argument("demo", nargs="?", help="demo name (see --list) or path of a demo .toml file")
    p.add_argument("--list", action="store_true", help="list the built-in demos and exit")
    p.add_argument("--all", action="store_true", help="record every built-in demo")
    p.add_argument("--out", metavar="DIR", help="output folder (created if missing)")
    p.add_argument("--duration", type=number, metavar="S", help="seconds of playback")
    p.add_argument("--fps", type=int, metavar="N", help="frames per second of playback")
    p.add_argument(
        "--method", metavar="NAME", help="integration method (mechviz simulate --list-methods)"
    )
    p.add_argument("--dt", type=number, metavar="DT", help="step size [s] for fixed-step methods")
    from .video_cli import add_record_options

    add_record_options(p)  # --video, --size
    p.set_defaults(func=run_record)

    q = sub.add_parser(
        "play",
        help="serve a .viser recording (or a folder of them) with viser's client",
        description="Serve PATH (a .viser file or a folder of them) on HOST:PORT with the browser "
        "client that ships in the viser wheel; prints the URL; Ctrl-C stops.",
    )
    q.add_argument("path", help=".viser file or folder")
    q.add_argument("--host", default="127.0.0.1", help="interface to bind (default 127.0.0.1)")
    q.add_argument("--port", type=int, default=DEFAULT_PLAY_PORT, help="first port to try")
    q.set_defaults(func=run_play)


# =========================================================================== record
def _option_error(exc: ValueError, args) -> CliError:
    msg = str(exc)
    for opt in ("duration", "fps", "method", "dt"):
        if getattr(args, opt) is not None and msg.startswith(opt):
            return CliError(f"--{opt}: {msg}")
    return CliError(msg)


class ProgressBar:
    """A one-line progress bar on a terminal (stderr); silent otherwise."""

    def __init__(self, label: str, stream=None, width: int = 30):
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty()
        self.label, self.width = label, width
        self.last = -1.0

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if done < total and now - self.last < 0.05:
            return
        self.last = now
        filled = int(self.width * done / total)
        bar = "#" * filled + "." * (self.width - filled)
        self.stream.write(
            f"\r{self.label:<22} [{bar}] {100 * done // total:3d}%  {done}/{total} frames"
        )
        if done >= total:
            self.stream.write("\n")
        self.stream.flush()


def run_record(args: argparse.Namespace) -> int:
    from . import record as rec

    if args.list:
        demos = rec.list_demos()
        width = max(len(d.name) for d in demos)
        for d in demos:
            print(f"{d.name:<{width}}  {d.description}")
        return 0
    if args.all == bool(args.demo):
        raise CliError("give one DEMO or --all (mechviz record --list shows the demos)")
    if not args.out:
        raise CliError("--out DIR is required")
    names = rec.demo_names() if args.all else [args.demo]
    demos = []
    for name in names:
        try:
            demo = rec.load_demo(name)
        except ValueError as exc:
            raise CliError(str(exc)) from None
        try:
            demos.append(
                demo.with_overrides(
                    duration=args.duration, fps=args.fps, method=args.method, dt=args.dt
                )
            )
        except ValueError as exc:
            raise _option_error(exc, args) from None
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise CliError(f"--out: {out} exists and is not a folder")
    if args.video or args.size:
        from .video_cli import check_record_options, film_record

        check_record_options(args, demos)
    for demo in demos:
        try:
            res = rec.record(demo, out, progress=ProgressBar(demo.name))
        except rec.RecordingFailed as exc:
            if sys.stderr.isatty():
                sys.stderr.write("\n")
            print(f"mechviz: error: {exc}", file=sys.stderr)
            return 130 if getattr(exc, "interrupted", False) else 1
        _report(res)
        if args.video and (status := film_record(res, args)):
            return status
    return 0


def _report(res) -> None:
    d, man = res.demo, res.manifest
    size = res.paths[".viser"].stat().st_size
    print(
        f"{d.name}: {res.frames} frames ({d.duration:g} s at {d.fps} fps, "
        f"{man['simulated_time']:.4g} s simulated) in {res.wall_seconds:.2f} s "
        f"({d.duration / res.wall_seconds:.2g}x real time); {d.name}.viser {size / 1e6:.3f} MB"
    )
    print(f"  -> {res.paths['.viser'].parent}/{d.name}.{{viser,html,csv,png,json}}")
    for f in man["figures"]:
        if f["measured"] is None:
            continue
        pred = "" if f["predicted"] is None else f", predicted {f['predicted']:.6g}"
        print(f"  {f['name']}: {f['measured']:.6g} {f['unit']}{pred}".rstrip())


# =========================================================================== play
def _client_index() -> bytes:
    import viser

    return (Path(viser.__file__).parent / "client" / "build" / "index.html").read_bytes()


def _recordings(path: Path) -> dict[str, Path]:
    if not path.exists():
        raise CliError(f"{path}: no such file or folder")
    if path.is_file():
        if path.suffix != ".viser":
            raise CliError(f"{path}: not a .viser recording")
        return {path.name: path}
    found = {p.name: p for p in sorted(path.glob("*.viser"))}
    if not found:
        raise CliError(f"{path}: no .viser recordings in this folder")
    return found


def make_play_server(path: Path, host: str = "127.0.0.1", port: int = DEFAULT_PLAY_PORT):
    """An HTTP server for the recordings at ``path`` and viser's client, bound to the first
    free port from ``port`` (0: any). Returns ``(server, urls)``."""
    recordings = _recordings(path)
    index = _client_index()

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            route = urllib.parse.urlsplit(self.path).path
            if route in ("/", "/index.html"):
                return self._send(index, "text/html; charset=utf-8")
            if route == "/list":
                items = "".join(
                    f'<li><a href="/?playbackPath=recordings/{urllib.parse.quote(n)}">{n}</a></li>'
                    for n in recordings
                )
                page = f"<!doctype html><title>mechviz recordings</title><ul>{items}</ul>"
                return self._send(page.encode(), "text/html; charset=utf-8")
            if route.startswith("/recordings/"):
                name = urllib.parse.unquote(route.removeprefix("/recordings/"))
                if name in recordings:
                    return self._send(recordings[name].read_bytes(), "application/octet-stream")
            self.send_error(404)

        def _send(self, body: bytes, ctype: str) -> None:
            self.send_response(200)
            self.send_header("Content-Type", ctype)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args) -> None:
            pass

    first = port
    for attempt in range(100):
        try:
            server = http.server.ThreadingHTTPServer((host, port), Handler)
            break
        except OSError as exc:
            if exc.errno != errno.EADDRINUSE or port == 0 or attempt == 99:
                raise CliError(f"--port: cannot listen on {host}:{port}: {exc.strerror}") from None
            port += 1
    server.daemon_threads = True
    actual = server.server_address[1]
    shown = "127.0.0.1" if host in ("0.0.0.0", "") else host
    base = f"http://{shown}:{actual}"
    urls = {n: f"{base}/?playbackPath=recordings/{urllib.parse.quote(n)}" for n in recordings}
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
        print(f"{name}: {url}")
    print("Ctrl-C stops.", flush=True)
    try:
        server.serve_forever(poll_interval=0.2)
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
    print("stopped.")
    return 0
