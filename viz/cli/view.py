"""``mechviz view``: serve the live viewer (imports viser only when the command runs)."""

from __future__ import annotations

import argparse

from .errors import command, whole

ABOUT = """\
serve the live 3-D viewer of the three systems

Serve the live viewer at http://HOST:PORT/ until Ctrl-C.
"""


def add_commands(sub) -> None:
    p = command(sub, "view", ABOUT)
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="interface to bind (default 127.0.0.1: this machine only; 0.0.0.0: every "
        "interface, exposed to the network)",
    )
    p.add_argument(
        "--port", type=whole, default=8080, help="port (default 8080; the next free one if busy)"
    )
    p.add_argument(
        "--warm",
        choices=("defaults", "all"),
        default="defaults",
        help="compile the default methods' kernels before serving and the others in the "
        "background while it serves (default), or every method before serving (all)",
    )
    p.add_argument(
        "--no-env-map", action="store_true", help="no environment lighting (faster software GL)"
    )
    p.add_argument(
        "--theme",
        choices=("light", "dark"),
        default="light",
        help="page theme (default light; the panel switches it too)",
    )
    p.add_argument(
        "--dev",
        action="store_true",
        help="show viser's share button (for developers; hidden in a lecture by default)",
    )
    p.set_defaults(func=_view)


def _view(args: argparse.Namespace) -> int:
    import os
    import signal
    import threading
    import time

    from ..hosts import HostError, check_host
    from ..play import reachable_urls
    from .errors import CliError

    if not 0 <= args.port <= 65535:
        raise CliError(f"--port must be in 0..65535, got {args.port}")
    try:  # before anything compiles: a host that cannot be served on is one line, at once
        host = check_host(args.host)
    except HostError as exc:
        raise CliError(f"--host: {exc}") from None

    # Ctrl-C only sets a flag: the loop and the compiler are never interrupted mid-call, so
    # the server always stops cleanly (a second Ctrl-C exits at once).
    interrupted = threading.Event()

    def on_sigint(_signum, _frame) -> None:
        if interrupted.is_set():
            os._exit(130)
        interrupted.set()

    previous = signal.signal(signal.SIGINT, on_sigint)
    try:
        from ..app import MechvizApp, warm_up

        t0 = time.perf_counter()
        print(f"mechviz: compiling integrators ({args.warm}) ...", flush=True)
        warm_up(args.warm, should_stop=interrupted.is_set)
        if interrupted.is_set():
            print("mechviz: interrupted", flush=True)
            return 130
        app = MechvizApp(
            host=args.host,
            port=args.port,
            environment_map=not args.no_env_map,
            theme=args.theme,
            dev=args.dev,
        )
        # The other methods compile while the viewer already runs, so a later switch of method
        # starts at once (the frame rate holds while they compile, but for a few late frames).
        background = threading.Thread(
            target=warm_up,
            args=("all",),
            kwargs={"should_stop": interrupted.is_set},
            name="mechviz-warm-up",
            daemon=True,
        )
        try:
            used = app.port
            if args.port and used != args.port:
                print(f"mechviz: port {args.port} is busy; using port {used} instead", flush=True)
            urls = [f"{u}/" for u in reachable_urls(args.host, used)]
            print(
                f"mechviz: viewer ready in {time.perf_counter() - t0:.1f} s at {', '.join(urls)}",
                flush=True,
            )
            note = host.exposure_note()
            if note:
                print(f"mechviz: {note}", flush=True)
            print("mechviz: press Ctrl-C to stop", flush=True)
            if args.warm != "all":
                background.start()
            app.run_forever(until=interrupted)
        finally:
            app.stop()
            if background.is_alive():  # let a compilation in progress finish: a clean exit
                background.join(timeout=10.0)
        print("mechviz: viewer stopped", flush=True)
        return 0
    finally:
        signal.signal(signal.SIGINT, previous)
