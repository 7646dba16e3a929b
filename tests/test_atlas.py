"""The stability atlas on a real Dask cluster: a ``distributed.LocalCluster`` with a TCP scheduler
and two single-threaded worker processes, small grids.

What is checked: the distributed map equals the serial one bit for bit (and a chunk equals its
cells run one at a time); a run interrupted (Ctrl-C) or killed outright and resumed gives the
same dataset with no chunk computed twice; a worker killed mid-run still leaves a complete and
correct map; the RK4 boundary of the small-amplitude hoop sits where linear theory puts it
(``omega_2 dt = 2 sqrt 2``); the chaos map is near zero near the hanging rest and clearly
positive for large swings; bad input is one line naming the flag.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")
pytest.importorskip("xarray")
pytest.importorskip("zarr")

from waiting import scaled, wait_until

from mechviz.dynamics import hoop
from mechviz.dynamics.atlas import store
from mechviz.dynamics.atlas.driver import compute_serial, run_atlas
from mechviz.dynamics.atlas.grid import AtlasSpec, Axis
from mechviz.dynamics.atlas.kernels import VARIABLES
from mechviz.viz.cli import main

# every test here starts a Dask cluster or an interpreter, or runs the maps for seconds
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent
OMEGA2 = float(hoop.normal_modes(hoop.HoopParams())[0][1])


@pytest.fixture(scope="module")
def client():
    import logging

    from distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        protocol="tcp",
        dashboard_address=None,
        silence_logs=logging.CRITICAL,
    )
    c = Client(cluster)
    c.wait_for_workers(2, timeout=scaled(120))
    yield c
    c.close()
    cluster.close()


def chaos_spec(n: int = 8, chunk=(2, 8), duration: float = 10.0) -> AtlasSpec:
    return AtlasSpec(
        "chaos",
        "hoop",
        ("rk4",),
        Axis("theta2", -3.0, 3.0, n),
        Axis("theta1", -3.0, 3.0, n),
        duration=duration,
        chunk=chunk,
    )


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def assert_same_map(ds, reference, spec: AtlasSpec) -> None:
    for name in VARIABLES[spec.kind]:
        assert same_bits(ds[name].values, reference[name].values), name
    assert ds["chunk_done"].values.all()


def test_distributed_map_equals_serial_bit_for_bit(client, tmp_path):
    spec = chaos_spec()
    report = run_atlas(spec, tmp_path / "a.zarr", client=client)
    assert report.complete and sorted(report.computed) == spec.chunks()
    assert_same_map(store.load(tmp_path / "a.zarr"), compute_serial(spec), spec)
    import xarray as xr

    # finished: consolidated metadata (open_zarr refuses consolidated=True without it), and
    # every variable and axis says its units and what it is
    with xr.open_zarr(tmp_path / "a.zarr", consolidated=True) as ds:
        for name in [*ds.data_vars, spec.x.name, spec.y.name]:
            assert {"units", "long_name"} <= ds[name].attrs.keys(), name
        assert ds["lyapunov"].attrs["units"] == "1/s" and ds["theta1"].attrs["units"] == "rad"


def test_chunk_equals_its_cells_run_one_at_a_time():
    """Ensembles advance each member on its own: cutting the grid differently changes no bit."""
    spec = chaos_spec(n=4, chunk=(4, 4))
    single = AtlasSpec(**{**spec.__dict__, "chunk": (1, 1)})
    a, b = compute_serial(spec), compute_serial(single)
    assert_same_map(a.assign(chunk_done=a.chunk_done + 1), b, spec)
    stab = AtlasSpec(
        "stability",
        "hoop",
        ("rk4", "verlet"),
        Axis("dt", 2.0 / OMEGA2, 3.4 / OMEGA2, 4),
        Axis("amplitude", 0.01, 1.2, 3),
        periods=20,
        chunk=(4, 3),
    )
    one = AtlasSpec(**{**stab.__dict__, "chunk": (1, 1)})
    for name in VARIABLES["stability"]:
        assert same_bits(compute_serial(stab)[name].values, compute_serial(one)[name].values)


def _cli_args(spec: AtlasSpec, out: Path) -> list[str]:
    return [
        "atlas",
        "chaos",
        f"--theta1={spec.x.start}:{spec.x.stop}:{spec.x.n}",
        f"--theta2={spec.y.start}:{spec.y.stop}:{spec.y.n}",
        "--duration",
        str(spec.duration),
        "--chunk",
        f"{spec.chunk[0]}x{spec.chunk[1]}",
        "--out",
        str(out),
        "--no-progress",
    ]


@pytest.mark.slow
@pytest.mark.parametrize("how", ["ctrl-c", "kill"])
def test_interrupted_run_resumes_to_the_same_map_computing_no_chunk_twice(client, tmp_path, how):
    # chunks of a few tenths of a second each: a signal lands while most are still to run
    spec = chaos_spec(n=24, chunk=(1, 24), duration=300.0)
    out = tmp_path / "atlas"
    path = out / "atlas.zarr"
    cmd = [sys.executable, "-m", "mechviz.viz.cli", *_cli_args(spec, out), "--workers", "1"]
    proc = subprocess.Popen(
        cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True
    )
    try:
        wait_until(lambda: path.exists() and (path / "zarr.json").exists(), 120, "the store")
        wait_until(lambda: store.done_chunks(path).sum() >= 3, 120, "three chunks to land")
        if how == "ctrl-c":
            os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole group
            _, err = proc.communicate(timeout=scaled(60))
            assert proc.returncode == 130, err.decode()
            assert b"--resume" in err and b"Traceback" not in err, err.decode()
        else:
            os.killpg(proc.pid, signal.SIGKILL)  # the command and its cluster, all at once
            proc.communicate(timeout=scaled(60))
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    before = store.load(path)
    landed = {c for c in spec.chunks() if before["chunk_done"].values[c]}
    assert 3 <= len(landed) < len(spec.chunks()), "the run must stop midway"
    report = run_atlas(spec, path, client=client, resume=True)
    assert set(report.skipped) == landed
    assert not landed & set(report.computed), "a chunk was computed twice"
    assert landed | set(report.computed) == set(spec.chunks())
    after = store.load(path)
    for c in landed:  # what the first run wrote is kept, not redone
        assert after["chunk_session"].values[c] == before["chunk_session"].values[c]
    for c in report.computed:
        assert after["chunk_session"].values[c] == report.session
    assert_same_map(after, compute_serial(spec), spec)


def test_worker_killed_mid_run_leaves_a_complete_and_correct_map(client, tmp_path):
    # chunks of about 0.2 s: when the first one has been written, most are still to run (with
    # 15 s spans a chunk took 10 ms, and on a loaded machine the whole map could be done before
    # the first chunk's write returned, leaving no worker busy to kill)
    spec = chaos_spec(n=16, chunk=(1, 16), duration=300.0)
    killed = []

    def kill_a_busy_worker(_chunk, _report):
        if killed:
            return
        busy = [w for w, keys in client.processing().items() if keys]
        if not busy:
            return
        pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
        os.kill(pid, signal.SIGKILL)
        killed.append(pid)

    report = run_atlas(spec, tmp_path / "a.zarr", client=client, on_chunk=kill_a_busy_worker)
    assert killed, "no worker was busy to kill"
    assert report.complete and sorted(report.computed) == spec.chunks()
    assert_same_map(store.load(tmp_path / "a.zarr"), compute_serial(spec), spec)
    client.wait_for_workers(2, timeout=scaled(120))  # the nanny brings it back for the next test
    assert killed[0] not in client.run(os.getpid).values()


def test_rk4_boundary_of_the_small_amplitude_hoop_is_the_linear_limit(client, tmp_path):
    """Measured: halfway between the last bounded and the first unbounded step of a 0.4 %
    grid; theory: ``omega_2 dt = 2 sqrt 2``. Bounded below it, unbounded above, within 2 %."""
    x = np.linspace(2.5, 3.2, 71)
    spec = AtlasSpec(
        "stability",
        "hoop",
        ("rk4",),
        Axis("dt", x[0] / OMEGA2, x[-1] / OMEGA2, 71),
        Axis("amplitude", 0.005, 0.02, 2),
        periods=50,
        chunk=(18, 2),
    )
    run_atlas(spec, tmp_path / "s.zarr", client=client)
    ds = store.load(tmp_path / "s.zarr")
    dts = ds["dt"].values
    theory = 2.0 * math.sqrt(2.0) / OMEGA2
    assert ds["linear_limit_dt"].values[0] == pytest.approx(theory, rel=1e-12)
    for j in range(2):
        bounded = ds["bounded"].values[0, :, j].astype(bool)
        edge = int(np.argmin(bounded))  # the first unbounded step
        assert bounded[:edge].all() and not bounded[edge:].any(), "one boundary"
        measured = 0.5 * (dts[edge - 1] + dts[edge])
        assert abs(measured / theory - 1.0) < 0.02


def test_chaos_map_is_near_zero_near_rest_and_positive_for_large_swings(client, tmp_path):
    spec = chaos_spec(n=13, chunk=(13, 13), duration=60.0)
    run_atlas(spec, tmp_path / "c.zarr", client=client)
    ds = store.load(tmp_path / "c.zarr")
    lyap = ds["lyapunov"].values[0]
    t1, t2 = np.meshgrid(ds["theta1"].values, ds["theta2"].values)
    near = np.maximum(abs(t1), abs(t2)) <= 0.51
    large = np.maximum(abs(t1), abs(t2)) >= 2.49
    assert near.sum() >= 9 and large.sum() >= 40
    # Regular motion separates twins at most linearly in time: a finite-time exponent of the
    # order of log(omega t) / t (0.06 1/s here); chaotic swings an order of magnitude above.
    assert lyap[near].max() < 0.1
    assert np.median(lyap[large]) > 0.4
    assert np.isfinite(lyap).all() and np.abs(ds["energy_error"].values).max() < 1e-3


def test_maps_have_labelled_axes_and_colour_bars(tmp_path):
    from mechviz.dynamics.atlas.maps import save_maps

    spec = chaos_spec(n=6, chunk=(6, 6), duration=4.0)
    png, svg = save_maps(compute_serial(spec), tmp_path, "chaos")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    text = svg.read_text()
    for label in ("hoop angle theta1", "bead angle theta2", "Lyapunov exponent", "mode 1"):
        assert label in text


def test_resume_of_another_run_is_refused_in_one_line_and_changes_nothing(tmp_path, capsys):
    spec = chaos_spec(n=4, chunk=(4, 4), duration=1.0)
    out = tmp_path / "atlas"
    out.mkdir()
    store.create(out / "atlas.zarr", spec)
    before = sorted((p.name, p.stat().st_mtime_ns) for p in (out / "atlas.zarr").rglob("*"))
    args = _cli_args(AtlasSpec(**{**spec.__dict__, "duration": 2.0}), out)
    assert main([*args, "--resume"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mechviz: error: --resume:")
    assert "another run" in err[0]
    after = sorted((p.name, p.stat().st_mtime_ns) for p in (out / "atlas.zarr").rglob("*"))
    assert before == after


def run_cli(args: list[str]) -> int:
    try:
        return main(args)
    except SystemExit as exc:  # argparse's own usage errors
        return int(exc.code)


@pytest.mark.parametrize(
    "flags, field",
    [
        (["--methods", "rk5"], "--methods"),
        (["--periods", "-1"], "--periods"),
        (["--dt", "0:1:3"], "--dt"),
        (["--param", "hoop_mass=-1"], "--param"),
        (["--chunk", "0x3"], "--chunk"),
    ],
)
def test_bad_input_is_one_line_naming_the_flag(tmp_path, capsys, flags, field):
    assert run_cli(["atlas", "stability", "--out", str(tmp_path / "a"), *flags]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0], err
    assert not (tmp_path / "a").exists()


def _damage(path: Path, var: str, chunk: str, how: str) -> None:
    f = path / var / "c" / Path(*chunk.split("/"))
    assert f.is_file(), f
    if how == "delete":
        f.unlink()
    elif how == "truncate":
        with open(f, "r+b") as fh:
            fh.truncate(3)
    else:
        f.write_bytes(np.random.default_rng(1).bytes(40))


def test_resume_verifies_every_chunk_and_recomputes_the_damaged_ones_bit_for_bit(
    client, tmp_path, capsys
):
    spec = chaos_spec(n=8, chunk=(2, 4), duration=2.0)
    out = tmp_path / "atlas"
    path = out / "atlas.zarr"
    args = [*_cli_args(spec, out), "--scheduler", client.scheduler.address]
    assert main(args) == 0
    before = store.load(path)
    damage = {
        ("lyapunov", "0/0/0", "delete"): "0/0/0",
        ("energy_error", "0/1/1", "truncate"): "0/1/1",
        ("lyapunov", "0/2/0", "random"): "0/2/0",
        ("chunk_done", "0/3/1", "random"): "0/3/1",
        ("chunk_done", "0/3/0", "delete"): "0/3/0",
        ("chunk_checksum", "0/0/1", "truncate"): "0/0/1",
    }
    for var, chunk, how in damage:
        _damage(path, var, chunk, how)
    capsys.readouterr()
    assert main([*args, "--resume"]) == 0
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "damaged" in line]
    assert len(lines) == 1, err
    named = {c for c in damage.values() if f"{c} (" in lines[0]}
    assert named == set(damage.values()), lines[0]
    assert f"{len(damage)} damaged chunks" in lines[0]
    after = store.load(path)
    assert_same_map(after, compute_serial(spec), spec)
    redone = {tuple(int(v) for v in c.split("/")) for c in damage.values()}
    for c in spec.chunks():  # the sound chunks were kept, not computed again
        same = after["chunk_session"].values[c] == before["chunk_session"].values[c]
        assert same == (c not in redone), c
    # and a resume of the repaired store keeps every chunk
    assert main([*args, "--resume"]) == 0
    assert "8 kept from before" in capsys.readouterr().out


def test_damaged_metadata_is_refused_in_one_line_and_fresh_starts_again(client, tmp_path, capsys):
    spec = chaos_spec(n=4, chunk=(4, 4), duration=1.0)
    out = tmp_path / "atlas"
    args = [*_cli_args(spec, out), "--scheduler", client.scheduler.address]
    assert main(args) == 0
    (out / "atlas.zarr" / "lyapunov" / "zarr.json").unlink()
    capsys.readouterr()
    assert main([*args, "--resume"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "lyapunov/zarr.json" in err[0], err
    assert "--fresh" in err[0] and "another --out" in err[0]
    assert main([*args, "--fresh"]) == 0
    assert_same_map(store.load(out / "atlas.zarr"), compute_serial(spec), spec)


def test_a_second_run_in_the_same_folder_is_refused_while_the_first_works(tmp_path, capsys):
    spec = chaos_spec(n=4, chunk=(4, 4), duration=1.0)
    out = tmp_path / "atlas"
    out.mkdir()
    store.create(out / "atlas.zarr", spec)
    with store.locked(out):  # as a run in another process holds it
        assert main([*_cli_args(spec, out), "--resume"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "another mechviz atlas is working" in err[0], err
    assert not store.done_chunks(out / "atlas.zarr").any()


def test_a_store_whose_creation_was_cut_short_is_resumed_from_the_start(client, tmp_path, capsys):
    """A run killed while it created the store leaves only the copy beside it, half written."""
    spec = chaos_spec(n=4, chunk=(4, 4), duration=1.0)
    out = tmp_path / "atlas"
    partial = out / "atlas.zarr.partial"
    (partial / "lyapunov").mkdir(parents=True)
    (partial / "zarr.json").write_text('{"zarr_format": 3, "node_ty')
    args = [*_cli_args(spec, out), "--scheduler", client.scheduler.address, "--resume"]
    assert main(args) == 0
    assert "never completed" in capsys.readouterr().err
    assert not partial.exists()
    assert_same_map(store.load(out / "atlas.zarr"), compute_serial(spec), spec)


@pytest.mark.parametrize(
    "kind, flags, named",
    [
        # endless or huge: refused from the estimate, before any work
        ("chaos", ["--duration", "1e12"], "--max-steps"),
        ("chaos", ["--step", "1e-12"], "--max-steps"),
        ("accuracy", ["--duration", "1e9"], "--max-steps"),
        ("accuracy", ["--methods", "dop853", "--rtol", "1e-300:1e-3:3:log"], "--rtol"),
        ("accuracy", ["--methods", "taylor", "--rtol", "1e-300:1e-3:3:log"], "--rtol"),
        (
            "accuracy",
            ["--methods", "dop853", "--rtol", "1e-6:1e-3:3:log", "--max-steps", "10"],
            "--max-steps",
        ),
        ("stability", ["--periods", "1e15"], "--max-steps"),
        ("chaos", ["--theta1=-1:1:100000", "--theta2=-1:1:100000"], "--theta1"),
        # values that cannot be used
        ("chaos", ["--theta1=-1e308:1e308:4"], "--theta1"),
        ("chaos", ["--param", "radius=1e308"], "--param radius"),
        ("stability", ["--param", "radius=1e308"], "--param radius"),
        ("chaos", ["--scheduler", "garbage://x"], "--scheduler"),
        ("chaos", ["--scheduler", ""], "--scheduler"),
        ("chaos", ["--scheduler", "tcp://127.0.0.1:1"], "--scheduler"),
        ("stability", ["--methods", ""], "--methods"),
        ("chaos", ["--duration", "0"], "--duration"),
        ("chaos", ["--separation", "1e10"], "--separation"),
        ("chaos", ["--duration", "1_0"], "--duration"),
        ("chaos", ["--duration", "\uff11"], "--duration"),
        ("chaos", ["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "--workers"),
        # flags the map does not take
        ("chaos", ["--rtol", "1e-6:1e-3:3:log"], "--rtol"),
        ("chaos", ["--periods", "5"], "--periods"),
        ("chaos", ["--system", "cyclotron"], "--system"),
        ("stability", ["--duration", "5"], "--duration"),
        ("stability", ["--step", "0.1"], "--step"),
        ("accuracy", ["--threshold", "2"], "--threshold"),
    ],
)
def test_every_bad_flag_is_one_line_naming_it_before_any_work(tmp_path, capsys, kind, flags, named):
    import time

    t0 = time.monotonic()
    assert run_cli(["atlas", kind, "--out", str(tmp_path / "a"), "--no-progress", *flags]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and named in err[0], err
    assert "Traceback" not in err[0]
    assert not (tmp_path / "a").exists()
    assert time.monotonic() - t0 < scaled(30)  # no time limit of a client waited out


@pytest.mark.parametrize("out", ["/proc/mechviz-atlas", "a" * 300])
def test_an_out_that_cannot_be_made_is_one_line(tmp_path, capsys, monkeypatch, out):
    monkeypatch.chdir(tmp_path)
    args = ["atlas", "chaos", "--theta1=-1:1:2", "--theta2=-1:1:2", "--duration", "1"]
    assert run_cli([*args, "--out", out, "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mechviz: error: --out"), err


@pytest.mark.parametrize("where", ["create", "write_chunk"])
def test_a_full_disk_is_one_line(client, tmp_path, capsys, monkeypatch, where):
    import errno

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(tmp_path / "atlas"))

    monkeypatch.setattr(store, where, full)
    spec = chaos_spec(n=4, chunk=(4, 4), duration=1.0)
    args = [*_cli_args(spec, tmp_path / "atlas"), "--scheduler", client.scheduler.address]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "No space left on device" in err[-1] and err[-1].startswith("mechviz: error: --out")
    assert not any("Traceback" in line for line in err)
