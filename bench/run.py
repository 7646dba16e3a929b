"""Run the whole benchmark, write ``results.json`` and the charts, and summarise.

The result file records the machine, library versions, load average and date with every
figure; ratios between implementations come from this one run, timed in interleaved rounds.
With ``peers=True`` the integrators of :mod:`.peers` (CyRK, heyoka) are swept on the same
problems and timed head to head against our fastest method (``peer_ratios``).
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import os
import platform
import time
import warnings
from collections.abc import Callable
from pathlib import Path

from mechviz.dynamics.integrators.base import get_method
from mechviz.dynamics.simulation import Simulation
from mechviz.viz.progress import progress_bar

from . import exhibits, experiments
from . import generated_cost as gen
from .first_answer import JUDGED, first_answer_missed
from .first_answer import construction_costs as _construction_costs
from .first_answer import first_answer as _first_answer
from .peer_sweeps import flag_outliers, peer_table, sweep_peer
from .problems import (
    ADAPTIVE_OURS,
    ADAPTIVE_SCIPY,
    PROBLEMS,
    VARIANTS,
    load_references,
    variant_reference,
    versions,
)
from .report import SCIPY_FACTOR, markdown, summary  # noqa: F401  (summary: re-exported)
from .sweeps import (
    TARGETS,
    Settings,
    ratio_table,
    retime_ratios,
    sweep_adaptive,
    sweep_fixed,
)
from .tableau_cost import GOAL as TABLEAU_GOAL
from .tableau_cost import missed as tableau_missed
from .tableau_cost import tableau_cost


class Phases:
    """Wall seconds per phase of a run, in the order run: ``with timer("name"): ...``.
    What makes a run long is then in its own results file, not guessed afterwards."""

    def __init__(self, before: dict[str, float] | None = None) -> None:
        self.seconds: dict[str, float] = dict(before or {})

    @contextlib.contextmanager
    def __call__(self, name: str):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] = round(self.seconds.get(name, 0.0) + time.perf_counter() - t0, 2)


class Progress:
    """The bench's progress: a bar of its steps on stderr (tqdm, :func:`mechviz.viz.progress.progress_bar`)
    with the current step's label; silent off a terminal."""

    def __init__(self, total: int, enabled: bool | None = None) -> None:
        self.bar = progress_bar("mechviz bench", max(total, 1), enabled=enabled is not False)

    def set(self, label: str) -> None:
        self.bar.set_postfix_str(label[:40])

    def __call__(self, n: int = 1) -> None:
        self.bar.update(min(n, self.bar.total - self.bar.n))

    def close(self) -> None:
        self.bar.close()


def machine() -> dict:
    info = {
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
    }
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return info


def _load() -> list[float] | None:
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return None


def _fixed(pb, settings: Settings) -> tuple[str, ...]:
    return tuple(m for m in pb.fixed if m not in settings.skip_fixed)


def _compile_times(progress: Progress, settings: Settings) -> dict:
    """First call of every method on every problem (compilation or cache load), reported
    separately from the timings, which all come after it."""
    out = {}
    for key, pb in PROBLEMS.items():
        for m in _fixed(pb, settings) + ADAPTIVE_OURS + settings.scipy_methods:
            meth = get_method(m)
            kw = {"rtol": 1e-3, "atol": 1e-3} if meth.adaptive else {"dt": pb.t_end / 1000}
            sim = Simulation(pb.system, m, state=pb.y0, reference=None, **kw)
            t0 = time.perf_counter()
            sim.advance_to(pb.t_end / 100)
            out[f"{key}/{m}"] = time.perf_counter() - t0
        progress.set(f"compile {key}")
        progress()
    return out


def _quiet_scipy(run):
    """``run`` without scipy's warnings about the tolerances it is swept to.

    A sweep asks scipy for tolerances below what it accepts, and it warns at every such point
    (``solve_ivp``: rtol raised to 2.2e-14; ``odeint``: "excess accuracy requested", "illegal
    input"): dozens of lines that bury the progress of a full run. Each point's outcome is
    measured all the same: an ``odeint`` failure is read from its report and recorded as a
    failed point, a raised rtol shows as an error that stops falling (the sweep stops there).
    """

    @functools.wraps(run)
    def quiet(*args, **kwargs):
        from scipy.integrate import ODEintWarning

        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="At least one element of `rtol` is too small")
            warnings.filterwarnings("ignore", category=ODEintWarning)
            return run(*args, **kwargs)

    return quiet


def run_bench(
    *,
    quick: bool = False,
    out: str | Path = "docs/bench",
    extras: dict | None = None,
    show_progress: bool | None = None,
    charts: bool = True,
    peers: bool = False,
    extra: bool = True,
    exhibit_cases: dict | None = None,
    phases: dict | None = None,
    interruptible: Callable[[], contextlib.AbstractContextManager] = contextlib.nullcontext,
    seed: int | None = None,
    random_cases: int = 21,
) -> dict:
    """Run everything; write ``out/results.json``, ``tables.md`` and the charts as one set;
    return the result dict.

    ``peers``: sweep CyRK and heyoka too (skipped, with the reason, when not installed).
    ``extra``: the long runs, stability, per-step and exhibit measurements (``False`` runs only
    the work-precision part). ``exhibit_cases``: the viewer's exhibits as
    :func:`.exhibits.choose_defaults` takes them (the viewer owns its defaults; ``mechviz
    bench`` passes them); ``None`` skips that part. ``phases``: wall seconds of the caller's own
    measurements made before this call, listed first in ``phases_s``. ``interruptible``: a
    context manager around everything but the writing (the command line's makes Ctrl-C end
    the run even inside numba's compiler, which swallows ``KeyboardInterrupt``). ``seed`` and
    ``random_cases``: with ``peers``, the random cases of :mod:`.fastest` (a new seed when
    ``None``; the seed is in the results).
    """
    out = Path(out)
    with interruptible():
        result, pictures = _measure(
            quick, out, extras, show_progress, charts, peers, extra, exhibit_cases, phases
        )
        if peers:
            result["fastest_peers"] = _fastest(seed, random_cases, quick, result["phases_s"])
            result["duration_s"] = round(
                result["duration_s"] + result["phases_s"]["peers in their fastest form"], 1
            )
            result["targets"] = _targets(
                result["ratios"],
                result["per_step"],
                {},
                result["first_answer"],
                result["fastest_peers"],
                tableau=result.get("tableau_cost"),
                generated=result.get("generated_cost"),
            )
            # many short problems at once against heyoka's batch mode (mechviz bench --batch)
            from . import batch

            t0 = time.perf_counter()
            result["batch"] = batch.run(quick)
            result["phases_s"]["batch mode"] = round(time.perf_counter() - t0, 2)
            result["targets"]["missed"] += batch.missed(result["batch"])
    from mechviz.dynamics.files import write_files_atomically

    results = json.dumps(result, indent=1, default=_json_default) + "\n"
    try:  # the figures are measured: a table that cannot be made must not lose them
        tables = markdown(result)
    except Exception as exc:
        tables = (
            f"# Benchmark tables\n\nNot made ({exc.__class__.__name__}: {exc}); see results.json.\n"
        )
    # one set, results.json last: an interrupted run leaves the folder as it was
    write_files_atomically(
        out, {**pictures, "tables.md": tables.encode(), "results.json": results.encode()}
    )
    return result


@_quiet_scipy
def _measure(
    quick: bool,
    out: Path,
    extras: dict | None,
    show_progress: bool | None,
    charts: bool,
    peers: bool,
    extra: bool,
    exhibit_cases: dict | None,
    phases: dict | None,
) -> tuple[dict, dict[str, bytes]]:
    """``run_bench`` but the writing: (the result dict, chart name -> PNG bytes)."""
    from . import peers as _peers

    settings = Settings.for_mode(quick)
    refs = load_references()
    peer_names: list[str] = []
    peer_skipped: dict[str, str] = {}
    if peers:
        why = _peers.available()
        for name in _peers.PEERS:
            if quick and name in _peers.QUICK_SKIP:
                peer_skipped[name] = "not in --quick runs (never the fastest peer)"
            elif why[_peers.package_of(name)] is None:
                peer_names.append(name)
            else:
                peer_skipped[name] = why[_peers.package_of(name)]
    every = {**PROBLEMS, **VARIANTS}
    n_sweeps = sum(
        len(_fixed(pb, settings))
        + len(ADAPTIVE_OURS)
        + len(settings.scipy_methods)
        + len(peer_names)
        for pb in every.values()
    )
    total = (
        len(PROBLEMS)
        + n_sweeps
        + 2
        + (10 + 7 + len(experiments.STEP_CASES) + len(experiments.ENSEMBLE_SIZES) + 3) * extra
    )
    progress = Progress(total, show_progress)
    started = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    t_start = time.perf_counter()
    load_before = _load()

    timer = Phases(phases)
    with timer("compile"):
        compile_s = _compile_times(progress, settings)
    points = []
    for key, pb in every.items():
        with timer(f"sweeps: {key}, our fixed-step methods"):
            for m in _fixed(pb, settings):
                progress.set(f"{key}: {m}")
                points += sweep_fixed(pb, m, settings)
                progress()
        for side, methods in (("ours", ADAPTIVE_OURS), ("scipy", settings.scipy_methods)):
            with timer(f"sweeps: {key}, {side} adaptive"):
                for m in methods:
                    progress.set(f"{key}: {m}")
                    points += sweep_adaptive(pb, m, settings)
                    progress()
        with timer(f"sweeps: {key}, peers"):
            for m in peer_names:
                progress.set(f"{key}: {m}")
                points += sweep_peer(pb, m, settings)
                progress()
        flag_outliers([p for p in points if p.problem == key], pb, settings)
    ours = {m for pb in every.values() for m in pb.fixed} | set(ADAPTIVE_OURS)
    ratios = ratio_table(points, ours, set(ADAPTIVE_SCIPY))
    progress.set("ratios head to head")
    with timer("scipy head to head"):
        retime_ratios(ratios, points, every, settings)
    progress()
    progress.set("peers head to head")
    with timer("peers head to head"):
        peer_ratios = peer_table(points, ratios, peer_names, every, settings)
    progress()

    long_run = stab = per_step = exhibit = ensembles = tableau = generated = None
    if extra:
        progress.set("long runs (10^4 periods)")
        with timer("long runs"):
            long_run = experiments.long_run_energy(1e4, 400, progress)
        progress.set("stability")
        with timer("stability"):
            stab = experiments.stability_points(progress)
        progress.set("per-step cost (numba and C)")
        with timer("per-step cost"):
            per_step = experiments.per_step_costs(quick, progress)
        progress.set("generic Runge-Kutta runner against DOP853's own loop")
        with timer("generic runner cost"):
            tableau = tableau_cost(quick=quick)
        progress.set("generated forms against the hand-written ones")
        with timer("generated forms cost"):
            generated = gen.generated_cost(quick=quick)
        progress.set("ensembles (serial and parallel)")
        with timer("ensembles"):
            ensembles = experiments.ensemble_costs(quick, progress)
        progress.set("exhibit defaults")
        with timer("exhibit defaults"):
            exhibit = exhibits.choose_defaults(exhibit_cases, quick) if exhibit_cases else {}
        progress(3)
    with timer("construction"):
        construction = _construction_costs()
    with timer("first answer"):
        first_answer = _first_answer(2 if quick else 3) if extra else None
    progress.close()

    result = {
        "about": (
            "mechviz benchmark. Errors: relative 2-norm of the final state against the "
            "reference (charge: normalised by the transverse part (x, y, vx, vy) of the exact "
            "state). Times: median wall time of Simulation.advance_to(T) after one untimed call, "
            "gc disabled, short calls repeated to >= 2 ms per sample; compile times separate. "
            "Ratios: the contenders of each side re-timed head to head in interleaved rounds."
        ),
        "command": "mechviz bench" + (" --peers" if peers else "") + (" --quick" if quick else ""),
        "mode": "quick" if quick else "full",
        "date": started,
        "duration_s": round(time.perf_counter() - t_start, 1),
        "phases_s": timer.seconds,
        "machine": machine(),
        "versions": {**versions(), **_peers.versions()},
        "load_average": {"before": load_before, "after": _load()},
        "settings": {
            "repeats": settings.repeats,
            "min_sample_s": settings.min_sample,
            "cap_per_call_s": settings.cap,
            "energy_samples": settings.energy_samples,
            "fixed_step_factor": math.sqrt(2) if settings.half_steps else 2,
            "tolerances": list(settings.tolerances),
            "head_to_head_rounds": settings.head_to_head_rounds,
            "one_sample_from_s": None
            if math.isinf(settings.one_sample_from)
            else settings.one_sample_from,
            "scipy_methods": list(settings.scipy_methods),
            "skipped_fixed_methods": list(settings.skip_fixed),
            "targets": [f"{t:.0e}" for t in TARGETS],
            "peers": peer_names,
            "peers_skipped": peer_skipped,
        },
        "problems": {
            **{
                k: {
                    "title": pb.title,
                    "t_end": pb.t_end,
                    "state0": list(pb.state0),
                    "floor": pb.floor,
                    "reference": refs["problems"][k]["kind"],
                    "reference_cross_check": {
                        c: refs["problems"][k].get(c)
                        for c in ("mpmath_25_digits", "dop853_1e-13", "radau_1e-12")
                        if c in refs["problems"][k]
                    },
                }
                for k, pb in PROBLEMS.items()
            },
            **{
                k: {
                    "title": pb.title,
                    "t_end": pb.t_end,
                    "state0": list(pb.state0),
                    "floor": pb.floor,
                    "reference": variant_reference(pb)[1],
                    "untuned": True,
                }
                for k, pb in VARIANTS.items()
            },
        },
        "compile_s": compile_s,
        "points": [p.to_json() for p in points],
        "ratios": ratios,
        "peer_ratios": {
            peer: {
                k: {t: (None if e is None else e["ratio"]) for t, e in row.items()}
                for k, row in rows.items()
            }
            for peer, rows in peer_ratios.items()
        },
        "peer_head_to_head": peer_ratios,
        "construction_us": construction,
        "first_answer": first_answer,
        "targets": _targets(
            ratios, per_step, peer_ratios, first_answer, tableau=tableau, generated=generated
        ),
        "long_run": long_run,
        "stability": stab,
        "per_step": per_step,
        "tableau_cost": tableau,
        "generated_cost": generated,
        "ensembles": ensembles,
        "exhibits": exhibit,
    }
    if extras:
        result.update(extras)
    pictures: dict[str, bytes] = {}
    if charts:
        from . import charts as _charts

        with timer("charts"):  # result["phases_s"] is this same dict: the time lands in it
            pictures = _charts.render_charts(result)
        result["charts"] = [str(out / name) for name in pictures]
    return result, pictures


def _json_default(x):
    if hasattr(x, "item"):
        return x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    raise TypeError(f"not JSON serialisable: {type(x)}")


@_quiet_scipy
def _fastest(seed: int | None, n: int, quick: bool, phases: dict) -> dict:
    """The peers in their fastest form against ours (:mod:`.fastest`), with the load."""
    import secrets

    from . import fastest

    seed = secrets.randbits(32) if seed is None else seed
    before = _load()
    t0 = time.perf_counter()
    out = fastest.run(seed, n, rounds=3 if quick else 5)
    phases["peers in their fastest form"] = round(time.perf_counter() - t0, 2)
    out["load_average"] = {"before": before, "after": _load()}
    return out


def _targets(
    ratios: dict,
    per_step: dict | None,
    peer_ratios: dict,
    first_answer: dict | None = None,
    fastest: dict | None = None,
    tableau: dict | None = None,
    generated: dict | None = None,
) -> dict:
    """Each speed target, met (True), missed (False) or not measurable (None), and the lists of
    what was missed with the figure that missed. With ``fastest`` (:mod:`.fastest`'s results)
    the peers' verdict is its own: every case where a peer in its fastest form is faster than
    ours, kept or fresh, under either rule for picking a tolerance (the sweeps' peer figures,
    ``peer_ratios``, are then not judged)."""
    speed = {}
    missed = []
    for key, row in ratios.items():
        for target, entry in row.items():
            r = entry.get("ratio")
            ok = None if r is None else r >= SCIPY_FACTOR
            speed[f"{key} {target}"] = ok
            if ok is False:
                missed.append(f"{key} {target}: scipy / ours = {r:.1f} < {SCIPY_FACTOR:g}")
    peers = {}
    for peer, rows in peer_ratios.items():
        for key, row in rows.items():
            for target, e in row.items():
                ok = None if e is None else e["ratio"] >= 1.0
                peers[f"{peer} {key} {target}"] = ok
                if ok is False:
                    missed.append(f"{peer} {key} {target}: {peer} / ours = {e['ratio']:.2f} < 1")
    if fastest is not None:
        from .fastest_picks import RULES, has_rule, rule_row
        from .fastest_report import loss_lines

        # each rule for picking a tolerance is judged: a loss under either is a miss
        for rule in (r for r in RULES if has_rule(fastest, r)):
            said = "" if rule == "loosest" else f" ({rule})"
            for key, case in fastest["cases"].items():
                for target, full in case["targets"].items():
                    for name, r in ((rule_row(full, rule) or {}).get("ratios") or {}).items():
                        peers[f"{name.replace('/', ' ')} {key} {target}{said}"] = (
                            None if r is None else r >= 1.0
                        )
            missed += [f"fastest form{said}: {line}" for line in loss_lines(fastest, rule)]
    first = None
    if first_answer and JUDGED in first_answer:  # Simulation(..., "taylor"), as a user runs it
        lost = first_answer_missed(first_answer)
        first = not lost
        missed += lost
    generic = None
    if tableau is not None:
        lost = tableau_missed(tableau)
        generic = not lost
        missed += lost
    written_once = None
    if generated is not None:
        lost = gen.missed(generated)
        written_once = not lost
        missed += lost
    cost = (
        {}
        if per_step is None
        else {name: row.get("within_2x_of_c") for name, row in per_step["rows"].items()}
    )
    return {
        f"ours_{SCIPY_FACTOR:g}x_faster_than_scipy": speed,
        f"all_{SCIPY_FACTOR:g}x": all(v is True for v in speed.values()) and bool(speed),
        "ours_at_least_as_fast_as_every_peer": peers,
        "all_peers": all(v is True for v in peers.values()) if peers else None,
        "step_within_2x_of_c": cost,
        "first_answer_at_least_as_fast_as_odeint": first,
        f"generic_runner_within_{round(100 * (TABLEAU_GOAL - 1))}pct_of_dop853_loop": generic,
        f"generated_forms_within_{round(100 * (gen.GOAL - 1))}pct_of_hand_written": written_once,
        "missed": missed,
    }
