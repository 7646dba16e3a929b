"""The HTTP server under ``mechviz play``: the standard library's ``ThreadingHTTPServer`` with the
limits a server open to a network needs.

- **Header timeout.** A connection must deliver its request line and headers within
  :attr:`GuardedServer.header_timeout` seconds of being accepted (idle connections included);
  otherwise it is closed. A connection answering a request is closed after
  :attr:`~GuardedServer.answer_timeout` seconds, and every socket operation times out after
  :attr:`~GuardedServer.socket_timeout`.
- **Connection limits.** At most :attr:`~GuardedServer.max_connections` open connections, and
  :attr:`~GuardedServer.max_per_client` per client address. When a new connection would pass
  either limit, the oldest connection that has not yet sent its request (of that client, or of
  all) is closed to make room, so idle or slow connections can never lock out a real request;
  if every connection is busy answering, the new one is closed instead.
- **Backlog.** The listening socket queues up to :attr:`~GuardedServer.request_queue_size`
  connections not yet accepted (the standard library's default is 5).

A connection is one request (HTTP/1.0, no keep-alive): the browser client fetches two files.
"""

from __future__ import annotations

import contextlib
import http.server
import socket
import sys
import threading
import time
from dataclasses import dataclass


@dataclass
class _Connection:
    client: str
    accepted: float  # time.monotonic() at accept
    answering: bool = False


class GuardedServer(http.server.ThreadingHTTPServer):
    """``ThreadingHTTPServer`` with timeouts and connection limits (module docstring). The
    handler calls :meth:`answering` once it has read a whole request."""

    daemon_threads = True
    block_on_close = False
    request_queue_size = min(socket.SOMAXCONN, 512)
    max_connections = 256
    max_per_client = 32
    header_timeout = 10.0  # s, from accept to the end of the headers
    answer_timeout = 120.0  # s, from accept to the last byte of the answer
    socket_timeout = 10.0  # s, any one send or receive
    sweep_interval = 0.5  # s, how often expired connections are looked for

    def __init__(self, address, handler) -> None:
        self._lock = threading.Lock()
        self._open: dict[socket.socket, _Connection] = {}  # oldest first
        self._closed = threading.Event()
        super().__init__(address, handler)
        self._sweeper = threading.Thread(target=self._sweep, name="play-sweeper", daemon=True)
        self._sweeper.start()

    # ----------------------------------------------------------------- connection bookkeeping
    def process_request(self, request, client_address) -> None:
        client = str(client_address[0]) if client_address else ""
        with self._lock:
            if not self._make_room(client):
                refused = True
            else:
                refused = False
                self._open[request] = _Connection(client, time.monotonic())
        if refused:
            self.shutdown_request(request)
            return
        request.settimeout(self.socket_timeout)
        super().process_request(request, client_address)

    def _make_room(self, client: str) -> bool:
        """Close the oldest waiting connections until ``client`` may open one more (lock held)."""
        mine = [s for s, c in self._open.items() if c.client == client]
        if len(mine) >= self.max_per_client and not self._evict_oldest_waiting(mine):
            return False
        if len(self._open) >= self.max_connections and not self._evict_oldest_waiting(
            list(self._open)
        ):
            return False
        return True

    def _evict_oldest_waiting(self, candidates: list[socket.socket]) -> bool:
        for sock in candidates:
            if not self._open[sock].answering:
                self._drop(sock)
                return True
        return False

    def _drop(self, sock: socket.socket) -> None:
        """Forget ``sock`` and wake its thread (lock held). ``shutdown`` rather than ``close``:
        the thread still owns the descriptor and closes it itself."""
        self._open.pop(sock, None)
        with contextlib.suppress(OSError):
            sock.shutdown(socket.SHUT_RDWR)

    def answering(self, sock: socket.socket) -> None:
        """The connection has sent a whole request: it is no longer evicted to make room."""
        with self._lock:
            conn = self._open.get(sock)
            if conn is not None:
                conn.answering = True

    def shutdown_request(self, request) -> None:
        with self._lock:
            self._open.pop(request, None)
        super().shutdown_request(request)

    def open_connections(self) -> int:
        with self._lock:
            return len(self._open)

    def _sweep(self) -> None:
        while not self._closed.wait(self.sweep_interval):
            now = time.monotonic()
            with self._lock:
                for sock, conn in list(self._open.items()):
                    limit = self.answer_timeout if conn.answering else self.header_timeout
                    if now - conn.accepted > limit:
                        self._drop(sock)

    def server_close(self) -> None:
        self._closed.set()
        super().server_close()
        with self._lock:
            for sock in list(self._open):
                self._drop(sock)

    def handle_error(self, request, client_address) -> None:
        if isinstance(sys.exc_info()[1], OSError):
            return  # a browser that went away, a timeout, a connection closed to make room
        super().handle_error(request, client_address)


class GuardedHandler(http.server.BaseHTTPRequestHandler):
    """A request handler that tells :class:`GuardedServer` when its request is read."""

    server: GuardedServer

    def parse_request(self) -> bool:
        ok = super().parse_request()
        if ok:
            self.server.answering(self.connection)
        return ok
