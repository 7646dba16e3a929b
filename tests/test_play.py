"""``mechviz play`` (:mod:`mechviz.viz.play`): serves the recordings in a folder, and nothing else."""

from __future__ import annotations

import http.client
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request

import pytest
from waiting import scaled

from mechviz.viz import play

RECORDING = b"\x10\x00\x00\x00\x00\x00\x00\x00not really zstd"


def _serve(folder, host="127.0.0.1"):
    server, _ = play.make_play_server(folder, host, 0)
    threading.Thread(
        target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True
    ).start()
    return server, f"http://127.0.0.1:{server.server_address[1]}"


def _get(url):
    try:
        with urllib.request.urlopen(url, timeout=10) as r:
            return r.status, r.geturl(), r.read()
    except urllib.error.HTTPError as exc:
        return exc.code, url, b""


@pytest.fixture
def served(tmp_path):
    (tmp_path / "a.viser").write_bytes(RECORDING)
    (tmp_path / "b.viser").write_bytes(RECORDING + b"b")
    secret = tmp_path.parent / f"{tmp_path.name}-secret.txt"
    secret.write_text("root:x:0:0\n")
    (tmp_path / "evil.viser").symlink_to(secret)
    (tmp_path / "<img src=x onerror=alert(1)>.viser").write_bytes(RECORDING)
    server, base = _serve(tmp_path)
    yield tmp_path, base, secret
    server.shutdown()
    server.server_close()


def test_a_symlink_out_of_the_folder_is_not_served(served):
    folder, base, secret = served
    status, _, body = _get(f"{base}/recordings/evil.viser")
    assert status == 404 and b"root:" not in body
    # Nor a recording replaced by such a link after the server started.
    (folder / "b.viser").unlink()
    (folder / "b.viser").symlink_to(secret)
    status, _, body = _get(f"{base}/recordings/b.viser")
    assert status == 404 and b"root:" not in body
    assert _get(f"{base}/recordings/a.viser")[2] == RECORDING


def test_the_list_escapes_every_file_name(served):
    _, base, _ = served
    status, _, page = _get(f"{base}/list")
    assert status == 200
    assert b"<img" not in page and b"&lt;img src=x onerror=alert(1)&gt;.viser" in page
    assert b"evil.viser" not in page


def test_the_root_url_redirects_to_the_list_or_the_only_recording(served, tmp_path_factory):
    _, base, _ = served
    status, url, _ = _get(f"{base}/")
    assert status == 200 and url.endswith("/list")
    one = tmp_path_factory.mktemp("one")
    (one / "only.viser").write_bytes(RECORDING)
    server, base1 = _serve(one)
    try:
        status, url, page = _get(f"{base1}/")
        assert status == 200 and url.endswith("/?playbackPath=recordings/only.viser")
        assert b"<html" in page.lower()[:300] or b"<!doctype html" in page.lower()[:300]
    finally:
        server.shutdown()
        server.server_close()


def start_play(folder, **popen) -> subprocess.Popen:
    """``mechviz play FOLDER --port 0`` in a child process, its output as text."""
    return subprocess.Popen(
        [sys.executable, "-m", "mechviz.viz.cli", "play", str(folder), "--port", "0"],
        stdout=subprocess.PIPE,
        text=True,
        **({"stderr": subprocess.PIPE} | popen),
    )


@pytest.mark.slow
def test_a_client_that_goes_away_is_not_an_error(tmp_path):
    (tmp_path / "big.viser").write_bytes(os.urandom(8 << 20))
    proc = start_play(tmp_path)
    try:
        line = proc.stdout.readline()
        port = int(line.split("http://127.0.0.1:", 1)[1].split("/", 1)[0])
        for _ in range(3):
            s = socket.create_connection(("127.0.0.1", port))
            s.sendall(b"GET /recordings/big.viser HTTP/1.1\r\nHost: x\r\n\r\n")
            s.recv(100)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")
            s.close()  # reset mid-transfer
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        conn.request("GET", "/list")
        assert conn.getresponse().status == 200
    finally:
        proc.send_signal(2)
        _, err = proc.communicate(timeout=20)
    assert "Traceback" not in err and "Error" not in err, err


@pytest.mark.slow
def test_a_port_out_of_range_is_refused_with_status_2(tmp_path):
    (tmp_path / "a.viser").write_bytes(RECORDING)
    out = subprocess.run(
        [sys.executable, "-m", "mechviz.viz.cli", "play", str(tmp_path), "--port", "70000"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        "mechviz: error: --port: must be from 0 to 65535, got 70000"
    ]


def test_binding_every_interface_says_so_and_lists_the_addresses():
    assert play.exposure_note("127.0.0.1") is None
    assert "exposed to the network" in play.exposure_note("0.0.0.0")
    urls = play.reachable_urls("0.0.0.0", 8090)
    assert urls[0] == "http://127.0.0.1:8090"
    assert all(u.startswith("http://") and u.endswith(":8090") for u in urls)
    assert play.reachable_urls("::1", 80) == ["http://[::1]:80"]


def test_a_hard_link_to_a_file_outside_the_folder_is_not_served(served):
    folder, base, secret = served
    (folder / "c.viser").unlink(missing_ok=True)
    os.link(secret, folder / "hard.viser")
    assert _get(f"{base}/recordings/hard.viser")[0] == 404
    # Nor a recording that became a hard link after the server started.
    (folder / "a.viser").unlink()
    os.link(secret, folder / "a.viser")
    status, _, body = _get(f"{base}/recordings/a.viser")
    assert status == 404 and b"root:" not in body


def test_a_recording_made_by_record_is_served_anew_after_it_is_written_again(tmp_path):
    from mechviz.dynamics import fileset

    fileset.write_set(tmp_path, "demo", {"demo.viser": RECORDING, "demo.json": b"{}"})
    server, base = _serve(tmp_path)
    try:
        assert _get(f"{base}/recordings/demo.viser")[2] == RECORDING
        fileset.write_set(tmp_path, "demo", {"demo.viser": RECORDING + b"2", "demo.json": b"{}"})
        assert _get(f"{base}/recordings/demo.viser")[2] == RECORDING + b"2"
    finally:
        server.shutdown()
        server.server_close()


def _raise_descriptor_limit(needed: int) -> None:
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft != resource.RLIM_INFINITY and soft < needed:
        if hard != resource.RLIM_INFINITY and hard < needed:
            pytest.skip(f"needs {needed} file descriptors; the hard limit is {hard}")
        resource.setrlimit(resource.RLIMIT_NOFILE, (needed, hard))


@pytest.mark.slow
def test_a_request_is_answered_while_1100_idle_connections_are_open(tmp_path):
    import re
    import resource

    (tmp_path / "a.viser").write_bytes(RECORDING)
    _raise_descriptor_limit(2048)  # this process holds the client end of every connection
    hard = resource.getrlimit(resource.RLIMIT_NOFILE)[1]

    def usual_limit():  # the server runs with the usual 1,024 descriptors
        resource.setrlimit(resource.RLIMIT_NOFILE, (1024, hard))

    server = start_play(tmp_path, stderr=None, preexec_fn=usual_limit)
    idle = []
    try:
        port = int(re.search(r":(\d+)/", server.stdout.readline()).group(1))
        for _ in range(1100):
            idle.append(socket.create_connection(("127.0.0.1", port), timeout=10))
        # 2 s on a quiet machine (scaled by the load per core: a limit that only catches a
        # starved server, not a busy machine)
        url = f"http://127.0.0.1:{port}/recordings/a.viser"
        with urllib.request.urlopen(url, timeout=scaled(2.0)) as r:
            assert r.status == 200 and r.read() == RECORDING
    finally:
        for s in idle:
            s.close()
        server.terminate()
        server.wait(timeout=30)
        server.stdout.close()


def test_a_connection_that_sends_no_request_is_closed_after_the_header_timeout(tmp_path):
    (tmp_path / "a.viser").write_bytes(RECORDING)
    server, _ = _serve(tmp_path)
    server.header_timeout = 0.5
    try:
        with socket.create_connection(("127.0.0.1", server.server_address[1]), timeout=30) as s:
            s.sendall(b"GET /recordings/a.viser HTTP/1.0\r\n")  # the headers never end
            assert s.recv(100) == b""  # closed by the server, not by our 30 s timeout
    finally:
        server.shutdown()
        server.server_close()


def test_file_names_with_terminal_escapes_are_printed_escaped(tmp_path, capsys):
    evil = "a\x1b]0;pwned\x07\x1b[2J.viser"
    (tmp_path / evil).write_bytes(RECORDING)
    assert "\x1b" not in play.printable(evil) and "\\x1b" in play.printable(evil)
    args = type("Args", (), {"path": str(tmp_path), "host": "127.0.0.1", "port": 0})()
    server_started = threading.Event()
    real_make = play.make_play_server

    def make_then_stop(*a, **k):
        server, urls = real_make(*a, **k)
        server.serve_forever = lambda **kw: server_started.set()
        return server, urls

    play.make_play_server = make_then_stop
    try:
        assert play.run_play(args) == 0
    finally:
        play.make_play_server = real_make
    out = capsys.readouterr().out
    assert server_started.is_set() and "\x1b" not in out and "\\x1b]0;pwned" in out


def test_a_path_too_long_is_one_line_with_status_2(tmp_path, capsys):
    from mechviz.viz.cli import main

    assert main(["play", str(tmp_path / ("p" * 5000))]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "File name too long" in err, err


def test_one_recording_made_by_record_is_served_anew_after_it_is_recorded_again(tmp_path):
    from mechviz.dynamics import fileset

    fileset.write_set(tmp_path, "demo", {"demo.viser": RECORDING, "demo.json": b"{}"})
    server, _ = play.make_play_server(tmp_path / "demo.viser", "127.0.0.1", 0)
    threading.Thread(
        target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True
    ).start()
    base = f"http://127.0.0.1:{server.server_address[1]}"
    try:
        fileset.write_set(tmp_path, "demo", {"demo.viser": RECORDING + b"2", "demo.json": b"{}"})
        assert _get(f"{base}/recordings/demo.viser")[2] == RECORDING + b"2"
    finally:
        server.shutdown()
        server.server_close()


@pytest.mark.slow
def test_play_serves_the_client_and_the_recording_then_stops_on_ctrl_c(tmp_path):
    from mechviz.viz import record as rec

    res = rec.record(rec.load_demo("helix").with_overrides(duration=1.0, fps=10), tmp_path)
    proc = start_play(tmp_path)
    try:
        url = None
        deadline = time.monotonic() + scaled(30)
        while url is None and time.monotonic() < deadline:
            line = proc.stdout.readline()
            if line.startswith("helix.viser: "):
                url = line.split(": ", 1)[1].strip()
        assert url and url.startswith("http://127.0.0.1:")
        page = urllib.request.urlopen(url, timeout=scaled(10)).read()
        assert b"<html" in page.lower()[:200] or b"<!doctype html" in page.lower()[:200]
        base, query = url.split("/?playbackPath=")
        data = urllib.request.urlopen(f"{base}/{query}", timeout=scaled(10)).read()
        assert data == res.paths[".viser"].read_bytes()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=scaled(10))
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    assert "stopped" in out
