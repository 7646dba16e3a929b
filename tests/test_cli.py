"""The headless command line: `mechviz analyze` and `mechviz simulate`."""

import json
import math
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from commands import mechviz
from waiting import descendants, scaled, wait_until


def answer(command: str) -> dict:
    """The JSON answer of ``mechviz COMMAND --json`` (COMMAND split at spaces), which must
    succeed."""
    out = mechviz(*command.split(), "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def test_analyze_cyclotron_json_gives_the_seed_results():
    r = answer("analyze cyclotron --charge 2 --mass 3 --field 1.5 --speed 4")
    assert r["gyrofrequency"] == pytest.approx(1.0)
    assert r["radius"] == pytest.approx(4.0)
    assert r["period"] == pytest.approx(2 * math.pi)
    assert r["radial_oscillation_frequency"] == pytest.approx(1.0)


def test_analyze_disk_json_gives_the_seed_results():
    r = answer("analyze disk --omega 1")
    np.testing.assert_allclose(r["inertia_tensor"], [[2.5, -1.25, 0], [-1.25, 1.5, 0], [0, 0, 4]])
    r29 = math.sqrt(29)
    assert r["principal_moments"] == pytest.approx([2 - r29 / 4, 2 + r29 / 4, 4])
    assert len(r["principal_axes"]) == 3 and all(len(a) == 3 for a in r["principal_axes"])
    assert r["axle_force_amplitude"] == pytest.approx(5 / 8)
    r = answer("analyze disk --omega 2 --radius 0.5 --disk-mass 4")
    assert r["axle_force_amplitude"] == pytest.approx(5 / 8 * 4 * 4 * 0.5)


def test_analyze_hoop_json_gives_the_seed_modes():
    r = answer("analyze hoop --hoop-mass 2 --bead-mass 1 --radius 0.5 --gravity 10")
    assert r["mode_frequencies"] == pytest.approx([math.sqrt(10), math.sqrt(1.5 * 20)])
    assert r["mode_shapes"][0] == pytest.approx([1, 1])
    assert r["mode_shapes"][1][0] / r["mode_shapes"][1][1] == pytest.approx(-1 / 3)


def test_analyze_prints_a_readable_table_without_json():
    out = mechviz("analyze", "hoop")
    assert out.returncode == 0 and "mode_frequencies" in out.stdout and "{" not in out.stdout


def test_simulate_hoop_json_reports_state_drift_work_and_exact_error():
    r = answer("simulate hoop --theta1 0.4 --theta2 0.4 --t-end 3 --method rk4 --dt 0.01")
    assert set(r["final_state"]) == {"theta1", "theta2", "omega1", "omega2"}
    assert r["steps"] == 300 and r["rhs_evaluations"] == 1200
    assert abs(r["energy_drift"]) < 1e-8
    assert r["error_vs_exact"] < 1e-7  # mode 1 has a closed form at any amplitude


def test_simulate_cyclotron_and_disk():
    r = answer("simulate cyclotron --vz 0.2 --t-end 6.283185307179586 --method boris --dt 0.01")
    assert r["error_vs_exact"] < 1e-3 and abs(r["energy_drift"]) < 1e-13
    assert r["final_state"]["z"] == pytest.approx(0.2 * 2 * math.pi, rel=1e-9)
    r = answer("simulate disk --t-end 2")
    omega = r["parameters"]["omega"]  # the description's default spin, driven by default
    assert r["method"] == "exact" and r["final_state"]["angle"] == pytest.approx(2.0 * omega)
    r = answer("simulate disk --motion released --wz 0.01 --t-end 5 --method splitting --dt 0.01")
    assert r["error_vs_reference"] < 1e-3 and r["steps"] == 500


def test_list_methods_shows_every_method_with_its_properties():
    out = mechviz("simulate", "--list-methods")
    assert out.returncode == 0
    for name in (
        "euler",
        "rk4",
        "dop853",
        "boris",
        "verlet",
        "splitting",
        "yoshida4",
        "midpoint",
        "exact",
        "scipy-rk45",
        "scipy-dop853",
        "scipy-radau",
        "scipy-lsoda",
        "odeint",
    ):
        assert name in out.stdout
    assert "symplectic" in out.stdout and "adaptive" in out.stdout


@pytest.mark.parametrize(
    ("command", "needle"),
    [
        ("analyze cyclotron --mass -1", "--mass"),
        ("analyze cyclotron --field 0", "--field"),
        ("analyze hoop --gravity nan", "--gravity"),
        ("analyze disk --radius abc", "--radius"),
        ("simulate hoop --t-end 1 --method rk4 --dt 0", "--dt"),
        ("simulate hoop --t-end 1 --method rk4 --dt -0.1", "--dt"),
        ("simulate hoop --t-end 1 --method boris --dt 0.1", "--method"),
        ("simulate hoop --t-end 1 --method warp --dt 0.1", "--method"),
        ("simulate hoop --t-end 1 --method rk4 --dt abc", "--dt"),
        ("simulate cyclotron --t-end 1 --method dop853 --rtol 5", "--rtol"),
        ("simulate cyclotron --t-end -1 --method rk4 --dt 0.1", "--t-end"),
        ("simulate cyclotron --t-end 1e4 --method euler --dt 0.9", "euler with dt="),
        ("analyze pendulum", "pendulum"),
        ("simulate disk --t-end 1 --wx 0.1", "--wx"),  # the disk is driven
        # valid numbers whose consequences do not fit a double
        ("analyze cyclotron --charge 1e308", "--charge"),
        ("analyze cyclotron --field 1e308", "--field"),
        ("analyze cyclotron --mass 1e-308", "--mass"),
        ("analyze cyclotron --mass 1e-300", "--mass"),
        ("analyze cyclotron --speed 1e-308", "--speed"),
        ("analyze cyclotron --speed 1e308", "--speed"),
        ("analyze cyclotron --charge 1e-300", "--charge"),
        ("analyze disk --disk-mass 1e308", "--disk-mass"),
        ("analyze disk --radius 1e308", "--radius"),
        ("analyze disk --omega 1e308", "--omega"),
        ("simulate hoop --t-end 1e308 --dt 0.1", "--t-end"),
        ("simulate hoop --t-end 1e308 --method dop853", "--t-end"),
        ("simulate disk --t-end 1e308", "--t-end"),
        ("simulate hoop --t-end 1e-308 --dt 0.1", "--t-end"),
        ("simulate hoop --t-end 10 --dt 1e-308", "--dt"),
        ("simulate cyclotron --t-end 10 --dt 0.1 --vx 1e200", "--vx"),
        ("simulate cyclotron --t-end 1e9 --dt 1e-6 --method rk4", "1e+15"),
        ("simulate hoop --t-end 10 --dt 0.1 --samples 10000000000", "--samples"),
        ("simulate hoop --theta1 0.5 --t-end 1 --method dop853 --rtol 1e-13", "--rtol"),
    ],
)
def test_bad_input_exits_2_with_one_line_naming_the_flag(command, needle):
    out = mechviz(*command.split())
    assert out.returncode == 2, out.stdout
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    assert needle in lines[0] and "Traceback" not in out.stderr


@pytest.mark.slow
def test_a_run_beyond_the_step_limit_is_refused_up_front_and_max_steps_raises_it():
    args = ["simulate", "cyclotron", "--t-end", "2e5", "--dt", "1e-3", "--method", "boris"]
    out = mechviz(*args)
    assert out.returncode == 2 and "2e+08 steps" in out.stderr and "--max-steps" in out.stderr
    out = mechviz(*args, "--max-steps", "3e8", "--samples", "3", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["steps"] == 200_000_000


@pytest.mark.slow
def test_a_long_run_shows_progress_on_a_terminal_and_ctrl_c_ends_it_within_a_second():
    import pty

    main, child = pty.openpty()  # stderr on a terminal: the progress line is shown
    run = "simulate hoop --theta1 0.3 --t-end 1e6 --dt 0.01 --method midpoint --max-steps 1e9"
    proc = subprocess.Popen(
        [sys.executable, "-m", "mechviz.viz.cli", *run.split()],
        stdout=subprocess.PIPE,
        stderr=child,
        text=True,
    )
    os.close(child)
    seen = b""
    deadline = time.monotonic() + scaled(120)
    while b"simulating hoop with midpoint" not in seen and time.monotonic() < deadline:
        if select.select([main], [], [], 0.2)[0]:  # never a read that blocks past the deadline
            seen += os.read(main, 1024)
    assert b"%" in seen and proc.poll() is None
    proc.send_signal(signal.SIGINT)
    # Read the terminal while the process ends, not after: what is left in a pseudo-terminal
    # whose last writer has closed it can be lost.
    rest = b""
    deadline = time.monotonic() + scaled(60)  # a hang detector: uninterrupted, minutes
    while time.monotonic() < deadline:
        if select.select([main], [], [], 0.2)[0]:
            try:
                chunk = os.read(main, 4096)
            except OSError:  # every writer has closed it
                break
            if not chunk:
                break
            rest += chunk
        elif proc.poll() is not None:
            break
    proc.wait(timeout=scaled(60))
    os.close(main)
    assert proc.returncode == 130
    lines = [x for x in rest.decode().replace("\x1b[K", "").replace("\r", "\n").split("\n")]
    assert [x for x in lines if x.strip() and "simulating" not in x] == ["mechviz: interrupted"], (
        rest
    )


def test_json_is_valid_even_when_a_result_is_not_finite():
    # Valid input whose derived numbers all fit: strict JSON, no NaN or Infinity tokens.
    out = mechviz("analyze", "cyclotron", "--charge", "1e-3", "--json")
    assert out.returncode == 0
    json.loads(out.stdout, parse_constant=lambda c: pytest.fail(f"invalid JSON token {c}"))
    out = mechviz("analyze", "cyclotron", "--charge", "1e-300", "--json")
    assert out.returncode == 2 and "NaN" not in out.stdout and "Infinity" not in out.stdout


def test_the_error_against_the_reference_is_measured_against_a_tighter_run():
    r = answer("simulate hoop --theta1 0.5 --theta2 -0.3 --t-end 10 --method dop853 --rtol 1e-12")
    assert 0.0 < r["error_vs_reference"] < 1e-9
    assert "3e-15" in r["reference"]


def test_the_hoop_energy_error_is_relative_to_the_energy_that_moves():
    # Mode 2 at 0.01 rad with rk4, dt = 0.05 to t = 10 s loses 1.4e-4 of its oscillation energy
    # (RK4 damps by about (w dt)^6 / 144 per step); divided by the total energy with the
    # potential's zero at the pivot, that read as -2e-9. From 90 degrees (E0 = 0 up to round-off)
    # it read as -5e10.
    rk4 = "--t-end 10 --method rk4 --dt 0.05"
    r = answer(f"simulate hoop --theta1 0.0033333333333333335 --theta2 -0.01 {rk4}")
    assert -3e-4 < r["energy_drift"] < -5e-5
    r = answer(f"simulate hoop --theta1 1.5707963267948966 --theta2 1.5707963267948966 {rk4}")
    assert abs(r["max_energy_error"]) < 1e-2


_SWALLOWING_CALLBACK = """
import ctypes, ctypes.util, sys, time
from mechviz.viz.interrupts import ctrl_c_within_a_second

libc = ctypes.CDLL(ctypes.util.find_library("c"))
CMP = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p)

@CMP
def slow(a, b):  # like numba's compiler: Python called from C, which drops its exceptions
    print("inside", flush=True)
    time.sleep(30)
    return 0

with ctrl_c_within_a_second():
    items = (ctypes.c_int * 2)(2, 1)
    libc.qsort(items, 2, ctypes.sizeof(ctypes.c_int), slow)
    time.sleep(30)
print("not interrupted")
"""


@pytest.mark.slow
def test_ctrl_c_inside_code_that_swallows_keyboard_interrupt_still_ends_the_run():
    proc = subprocess.Popen(
        [sys.executable, "-c", _SWALLOWING_CALLBACK],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout.readline().strip() == "inside"
    proc.send_signal(signal.SIGINT)
    # the script sleeps 60 s if the interrupt is lost: ending well before that is the check
    out, err = proc.communicate(timeout=min(scaled(20), 50))
    assert proc.returncode == 130
    assert err.strip() == "mechviz: interrupted" and "not interrupted" not in out


def _worker_importing(pid: int) -> bool:
    """A descendant of ``pid`` runs multiprocessing's spawn and has loaded numpy: it is in the
    middle of its imports (numba's and ours follow, for about half a second)."""
    for child in descendants(pid):
        try:
            if b"spawn_main" in Path(f"/proc/{child}/cmdline").read_bytes() and (
                b"_multiarray_umath" in Path(f"/proc/{child}/maps").read_bytes()
            ):
                return True
        except OSError:  # ended meanwhile
            pass
    return False


@pytest.mark.slow
@pytest.mark.parametrize("when", ["starting", "compiling"])
def test_ctrl_c_ends_a_bench_run_while_its_workers_start_or_compile_and_writes_nothing(
    tmp_path, when
):
    # From an empty compile cache the bench first compiles in worker processes; a terminal's
    # Ctrl-C goes to the whole process group. A worker still importing would print "Fatal Python
    # error" or a traceback if it handled Ctrl-C itself, and numba's compiler swallows
    # KeyboardInterrupt once it runs: the bench's one line is all a person sees either way.
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-m", "mechviz.viz.cli", "bench", "--quick", "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
    )
    if when == "starting":
        wait_until(lambda: _worker_importing(proc.pid), 60, "a worker's imports", poll_s=0.005)
    else:
        wait_until(
            lambda: (tmp_path / "cache").exists() and len(descendants(proc.pid)) >= 2,
            60,
            "the compile workers",
        )
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=scaled(30))  # a hang detector: the compiling takes minutes
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "mechviz: interrupted", err
    assert "Fatal Python error" not in err and "Traceback" not in err, err
    deadline = time.monotonic() + scaled(10)  # no worker is left compiling (reaped once ended)
    with pytest.raises(ProcessLookupError):
        while time.monotonic() < deadline:
            os.killpg(proc.pid, 0)
            time.sleep(0.2)
    assert not out.exists()
