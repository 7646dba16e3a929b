"""``mechviz bench``: speed against accuracy.

Runs :func:`mechviz.bench.run_bench` (work-precision sweeps of our methods and scipy's, long-run
energy, stability, compiled step costs, exhibit defaults) and adds the viewer's frame cost and
the recording speed when those measurements exist. Writes ``results.json`` and PNG charts to
``--out`` (default a temporary folder, ``TMP/mechviz-bench``; ``make bench-docs`` writes the
committed ``docs/bench``). ``--peers`` adds CyRK and heyoka (``pip install
'mechviz-lab[peers]'``; a peer not installed is skipped with the reason). The speed targets (ours at
least 50x faster than scipy's fastest and at least as fast as every peer, at each accuracy) are
checked: the exit status is 1 if one is missed, and each miss is printed with its figure.

``--video`` runs only the video benchmark (:mod:`mechviz.bench.video_speed`: a 10 s helix at
960x540 and 30 fps, today's path beside one page with and without shadow maps, as ratios to real
time; 3 s with ``--quick``), writes ``video.json`` to ``--out``; the exit status is 1 if videos
are made slower than real time.

``--endurance SECONDS`` runs only the viewer's endurance benchmark instead
(:func:`mechviz.bench.endurance.run_endurance`: the live viewer with ``--clients`` headless Chromium pages
for SECONDS, frame rate per 10 s window, memory trend) and writes ``endurance.json`` to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from .errors import whole

MAX_ENDURANCE_S = 86_400.0
MAX_CLIENTS = 16  # each is a headless Chromium: a few hundred MB and a share of the cores


def _viewer_measurements(quick: bool) -> dict:
    """Frame cost of the viewer and speed of the recorder, or why they are not available."""
    out: dict = {}
    try:
        from mechviz.bench.frame_cost import measure_frame_cost

        out["frame_cost"] = measure_frame_cost(100 if quick else 300)
    except (ImportError, AttributeError) as exc:
        out["frame_cost"] = f"not available ({exc.__class__.__name__}: {exc})"
    except Exception as exc:  # a measurement that breaks must not lose the whole benchmark
        out["frame_cost"] = f"failed ({exc.__class__.__name__}: {exc})"
    try:
        from mechviz.viz.record import measure_record_speed

        out["record_speed"] = measure_record_speed(duration=5.0 if quick else 30.0)
    except (ImportError, AttributeError) as exc:
        out["record_speed"] = f"not available ({exc.__class__.__name__}: {exc})"
    except Exception as exc:
        out["record_speed"] = f"failed ({exc.__class__.__name__}: {exc})"
    return out


def _endurance(args: argparse.Namespace) -> int:
    from pathlib import Path

    from mechviz.bench.endurance import EnduranceUnavailable, format_summary, run_endurance

    from .errors import CliError

    if not 1 <= args.endurance <= MAX_ENDURANCE_S:
        raise CliError(
            f"--endurance: must be a number of seconds from 1 to {MAX_ENDURANCE_S:g} "
            f"(a day), got {args.endurance:g}"
        )
    out = Path(args.out) / "endurance.json"
    try:
        result = run_endurance(
            args.endurance,
            args.clients,
            out=out,
            progress=_say_progress if not args.no_progress else None,
        )
    except EnduranceUnavailable as exc:
        raise CliError(str(exc)) from None
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print(format_summary(result))
    return 0 if result["targets"]["met"] else 1


def _say_progress(text: str) -> None:
    """The endurance run's progress lines, on stderr: stdout holds only the result (--json)."""
    print(f"mechviz bench: {text}", file=sys.stderr, flush=True)


def _video(args: argparse.Namespace) -> int:
    from mechviz.bench.video_speed import format_video_speed, measure_video_speed

    from .errors import CliError

    try:
        result = measure_video_speed(duration=3.0 if args.quick else 10.0)
    except RuntimeError as exc:
        raise CliError(f"--video: {exc}") from None
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "video.json").write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1) if args.json else format_video_speed(result))
    return 0 if result["targets"]["met"] else 1


def _tableau_cost(args: argparse.Namespace) -> int:
    """The generic Runge-Kutta runner against DOP853's own loop, per step on each system."""
    from mechviz.bench.tableau_cost import GOAL, missed, tableau_cost

    result = tableau_cost(quick=args.quick)
    if args.json:
        print(json.dumps(result, indent=1))
        return 1 if missed(result) else 0
    print(f"DOP853 per step: generic runner / its own loop (goal <= {GOAL}), side by side:")
    for name, r in result.items():
        print(
            f"  {name:7s} {r['ns_per_step_generic']:8.1f} / {r['ns_per_step_before']:8.1f} ns, "
            f"median of round ratios {r['ratio']:.3f} (of medians {r['ratio_of_medians']:.3f}; "
            f"{r['steps']} steps, same counts {r['same_counts']}, largest state difference "
            f"{r['max_state_difference']:.1e})"
        )
    lost = missed(result)
    for line in lost:
        print(f"missed: {line}")
    return 1 if lost else 0


def _generated_cost(args: argparse.Namespace) -> int:
    """Generated compiled forms against the hand-written ones, per step on each system."""
    from mechviz.bench.generated_cost import generated_cost, missed, report

    result = generated_cost(quick=args.quick)
    print(json.dumps(result, indent=1) if args.json else "\n".join(report(result)))
    return 1 if missed(result) else 0


def _batch(args: argparse.Namespace) -> int:
    """Many short problems: our batch mode against our one-problem solves and heyoka's batch."""
    from mechviz.bench import batch

    result = batch.run(quick=args.quick)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "batch.json").write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1) if args.json else batch.report(result))
    return 1 if batch.missed(result) else 0


def _whole(flag: str, text: str, lo: int, hi: int) -> int:
    from .errors import CliError

    try:
        value = int(text, 10)
    except ValueError:
        raise CliError(f"{flag}: must be a whole number, got {text!r}") from None
    if not lo <= value <= hi:
        raise CliError(f"{flag}: must be from {lo} to {hi}, got {value}")
    return value


def _run(args: argparse.Namespace) -> int:
    from .errors import CliError

    if not 1 <= args.clients <= MAX_CLIENTS:
        raise CliError(
            f"--clients: must be a whole number from 1 to {MAX_CLIENTS}, got {args.clients}"
        )
    # Whole numbers read here (any value of either can be meant, 0 included), refused by name.
    args.random_cases = _whole("--random-cases", args.random_cases, 0, 1000)
    if args.seed is not None:
        args.seed = _whole("--seed", args.seed, 0, 2**32 - 1)
    if args.endurance is not None:
        return _endurance(args)
    if args.video:
        return _video(args)
    if args.tableau_cost:
        return _tableau_cost(args)
    if args.generated_cost:
        return _generated_cost(args)
    if args.batch:
        return _batch(args)
    from mechviz.bench import PROBLEMS, peers, run_bench, summary
    from mechviz.bench.report import our_first_runs

    from ..interrupts import ctrl_c_within_a_second
    from ..warm import fill_cache_in_parallel

    with ctrl_c_within_a_second():  # nothing is written before run_bench's last step
        # Compilation is never timed, but from an empty cache it was a third of a quick run:
        # compile ours on every core, and the peers' uncacheable code in this process meanwhile
        fill_s, processes = fill_cache_in_parallel(
            # (on the first problem: CyRK's solver compiles the same for any)
            meanwhile=(lambda: peers.compile_ahead(next(iter(PROBLEMS.values()))))
            if args.peers
            else None
        )
        t0 = time.perf_counter()
        viewer = _viewer_measurements(args.quick)
        viewer_s = time.perf_counter() - t0
    from mechviz.bench.exhibits import bench_cases

    result = run_bench(
        quick=args.quick,
        out=args.out,
        extras={"viewer": viewer},
        peers=args.peers,
        exhibit_cases=bench_cases(),
        interruptible=ctrl_c_within_a_second,
        seed=args.seed,
        random_cases=args.random_cases,
        phases={
            (
                f"compile ahead ({processes} processes and this one)"
                if processes
                else "compile ahead (this process; the cache was filled)"
            ): round(fill_s, 2),
            "viewer frame cost and recording speed": round(viewer_s, 2),
        },
    )
    s = summary(result)
    missed = s["targets"]["missed"]
    if args.json:
        from mechviz.dynamics.files import json_safe

        # NumPy numbers as JSON numbers (default=str alone would quote them), NaN as null
        print(json.dumps(json_safe(s), indent=1, default=str, allow_nan=False))
        return 1 if missed else 0
    print(
        f"mechviz bench ({s['mode']}, {s['date']}, {s['duration_s']} s, load {s['load_average']})"
    )
    print("time to reach each accuracy: fastest scipy option / fastest of ours")
    for key, row in result["ratios"].items():
        cells = []
        for t, e in row.items():
            if e.get("ratio") is None:
                cells.append(f"{t}: n/a")
                continue
            bound = ">=" if e.get("ratio_is_lower_bound") else ""
            ours = e.get("ours", {})
            cells.append(
                f"{t}: {bound}{e['ratio']:.0f}x ({ours.get('method')} "
                f"{1e3 * ours.get('seconds', 0):.3g} ms)"
            )
        print(f"  {key:7s} " + "; ".join(cells))
    for name, why in s["peers_skipped"].items():
        print(f"peer {name} skipped: {why}")
    if s["peer_ratios"]:
        print("time of each peer over our fastest (below 1: the peer is faster)")
        for peer, rows in s["peer_ratios"].items():
            for key, row in rows.items():
                cells = "; ".join(
                    f"{t}: {'n/a' if r is None else f'{r:.2f}'}" for t, r in row.items()
                )
                print(f"  {peer:14s} {key:7s} {cells}")
    if result.get("fastest_peers"):
        from mechviz.bench.fastest_picks import RULE_TITLES, RULES, has_rule
        from mechviz.bench.fastest_report import case_table, distribution_table

        fast = result["fastest_peers"]
        for rule in (r for r in RULES if has_rule(fast, r)):
            print(
                f"peers in their fastest form (seed {fast['seed']}; peer / ours, kept, fresh), "
                f"each pick {RULE_TITLES[rule]}:"
            )
            print(case_table(fast, rule=rule))
            print(distribution_table(fast, rule))
    fa = s.get("first_answer")
    if fa:
        print(
            "first answer in a fresh process (hoop, 1e-9): "
            + "".join(f"{m} {fa[m]['median_s']} s, " for m in our_first_runs(fa))
            + "taylor compiled ahead of time "
            f"{fa['taylor-aot']['median_s']} s, scipy odeint {fa['scipy-odeint']['median_s']} s"
        )
    print("ns per compiled step (numba / C, same run):")
    for k, v in s["per_step_ns"].items():
        print(f"  {k:14s} {v['numba']:8.1f} / {v['c'] if v['c'] is not None else 'n/a'}")
    print(f"viewer: {viewer}")
    print(f"results: {args.out}/results.json; charts: {', '.join(s['charts'] or [])}")
    if missed:
        print(f"targets missed ({len(missed)}):")
        for line in missed:
            print(f"  {line}")
    else:
        print("targets: all met")
    return 1 if missed else 0


ABOUT = """\
benchmark speed against accuracy; write results.json and charts

Work-precision sweeps of our methods and scipy's (and, with --peers, CyRK and heyoka), long-run
energy, stability limits and compiled step costs, written as results.json and PNG charts into
--out. The exit status is 1 if a speed target is missed; each miss is printed with its figure.
"""


def add_commands(sub) -> None:
    from .errors import command, number

    p = command(sub, "bench", ABOUT)
    p.add_argument("--quick", action="store_true", help="fewer points and repeats (< 3 min)")
    p.add_argument(
        "--json",
        action="store_true",
        help="print a JSON summary (with 'ratios' and, with --peers, 'peer_ratios')",
    )
    p.add_argument(
        "--peers",
        action="store_true",
        help="also run CyRK and heyoka (pip install 'mechviz-lab[peers]'); each not installed is skipped "
        "with the reason",
    )
    p.add_argument(
        "--seed",
        default=None,
        help="with --peers: the seed of the random untuned cases (default: a new one, recorded "
        "in results.json)",
    )
    p.add_argument(
        "--random-cases",
        default="21",
        help="with --peers: how many random untuned cases (default 21)",
    )
    p.add_argument(
        "--out",
        default=str(Path(tempfile.gettempdir()) / "mechviz-bench"),
        help="output directory (default TMP/mechviz-bench; `make bench-docs` writes docs/bench)",
    )
    p.add_argument(
        "--endurance",
        type=number,
        metavar="SECONDS",
        help="run only the viewer endurance benchmark for SECONDS, up to a day (600 for the "
        "10-minute endurance target) with --clients headless Chromium pages; writes "
        "endurance.json; exit status 1 if a target is missed",
    )
    p.add_argument(
        "--video",
        action="store_true",
        help="run only the video benchmark (Chromium; pip install 'mechviz-lab[video]'): a 10 s "
        "960x540 video, as a ratio to real time beside one page with and without shadow maps; "
        "writes video.json; exit status 1 if slower than real time",
    )
    p.add_argument(
        "--tableau-cost",
        action="store_true",
        help="run only the cost per step of DOP853 through the generic Runge-Kutta runner against "
        "its own loop, side by side on each system; exit status 1 if above 1.05",
    )
    p.add_argument(
        "--generated-cost",
        action="store_true",
        help="run only the cost per step of the compiled forms generated from the equations "
        "(right-hand side, RK4, Taylor's recurrences) against the hand-written ones, side by side "
        "on each system; exit status 1 if one is above 1.05",
    )
    p.add_argument(
        "--batch",
        action="store_true",
        help="run only the batch benchmark: 1000 two-second problems of the hoop and the free "
        "body solved by our batch mode, our one-problem solves and heyoka's batch integrator "
        "(if installed), per problem; writes batch.json; exit status 1 if ours is slower than "
        "heyoka's fastest",
    )
    p.add_argument(
        "--clients",
        type=whole,
        default=3,
        help=f"browser clients for --endurance, 1 to {MAX_CLIENTS} (default 3)",
    )
    from ..progress import add_option

    add_option(p)
    p.set_defaults(func=_run)
