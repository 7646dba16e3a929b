"""``mechviz play`` (:mod:`viz.play`): serves the recordings in a folder, and nothing else."""

from __future__ import annotations

import http.client
import os
import socket
import subprocess
import sys
import threading
import urllib.error
import urllib.request

import pytest

from viz import play

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


def test_a_client_that_goes_away_is_not_an_error(tmp_path):
    (tmp_path / "big.viser").write_bytes(os.urandom(8 << 20))
    proc = subprocess.Popen(
        [sys.executable, "-m", "viz.cli", "play", str(tmp_path), "--port", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
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


def test_a_port_out_of_range_is_refused_with_status_2(tmp_path):
    (tmp_path / "a.viser").write_bytes(RECORDING)
    out = subprocess.run(
        [sys.executable, "-m", "viz.cli", "play", str(tmp_path), "--port", "70000"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
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
