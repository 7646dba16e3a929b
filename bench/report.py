"""Markdown tables of a benchmark result (written beside ``results.json`` as ``tables.md``)."""

from __future__ import annotations

from collections.abc import Iterable

#: Our fastest must be at least this many times faster than scipy's fastest.
SCIPY_FACTOR = 50.0


#: The first-answer runs that are not one of our methods by name.
OTHER_FIRST_RUNS = ("taylor-aot", "scipy-odeint")


def our_first_runs(fa: dict) -> list[str]:
    """Our methods the first-answer runs timed: as the result records them (``methods``), or,
    in an older result, every run not among :data:`OTHER_FIRST_RUNS`."""
    if "methods" in fa:
        return list(fa["methods"])
    return [k for k, v in fa.items() if isinstance(v, dict) and k not in OTHER_FIRST_RUNS]


def _ms(x: float | None) -> str:
    if x is None:
        return "-"
    return f"{1e3 * x:.3g} ms"


def _table(header: list[str], rows: Iterable[list]) -> str:
    """A markdown table: the header, its rule, then one line per row (each cell as ``str``)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(map(str, cells)) + " |" for cells in rows])


def ratio_table(result: dict) -> str:
    rows = []
    for key, row in result["ratios"].items():
        for target, e in row.items():
            ours = e.get("ours") or {}
            sci = e.get("scipy") or {}
            r = e.get("ratio")
            rs = (
                "-" if r is None else (">= " if e.get("ratio_is_lower_bound") else "") + f"{r:.0f}x"
            )
            sci_s = (
                f"{sci['method']} {_ms(sci['seconds'])}" if sci else "not reached within the cap"
            )
            sw = e.get("sweep_ratio")
            sws = "-" if sw is None else f"{sw:.0f}x"
            ours_s = f"{ours.get('method', '-')} {_ms(ours.get('seconds'))}"
            rows.append([key, target, ours_s, sci_s, rs, sws])
    header = ["problem", "accuracy", "fastest of ours", "fastest scipy", "scipy / ours"]
    return _table([*header, "sweep ratio"], rows)


def peer_table(result: dict) -> str:
    """Per problem and accuracy: each peer's time over our fastest, timed head to head."""
    h2h = result.get("peer_head_to_head") or {}
    if not h2h:
        skipped = (result.get("settings") or {}).get("peers_skipped") or {}
        why = "; ".join(f"{k}: {v}" for k, v in skipped.items())
        return "No peers were run" + (f" ({why})." if why else " (`mechviz bench --peers`).")
    peers = list(h2h)
    rows = []
    keys = list(next(iter(h2h.values())))
    for key in keys:
        targets = list(h2h[peers[0]][key])
        for t in targets:
            ours = next((h2h[p][key][t]["ours"] for p in peers if h2h[p][key][t]), None)
            ours_s = "-" if ours is None else f"{ours['method']} {_ms(ours['seconds'])}"
            cells = []
            for p in peers:
                e = h2h[p][key][t]
                if e is None:
                    cells.append("not reached")
                else:
                    mark = "**" if e["ratio"] < 1.0 else ""
                    cells.append(f"{mark}{e['ratio']:.2f}{mark} ({_ms(e['peer']['seconds'])})")
            rows.append([key, t, ours_s, *cells])
    return _table(["problem", "accuracy", "fastest of ours", *peers], rows)


def targets_list(result: dict) -> str:
    missed = result["targets"].get("missed") or []
    if not missed:
        return "Every target met."
    return "\n".join(f"- missed: {m}" for m in missed)


def _near(r: float, limit: float, digits: int) -> str:
    """``r`` to ``digits`` decimals, or more where that would print the limit it missed
    (49.96 is "49.96", not "50")."""
    while f"{r:.{digits}f}" == f"{limit:.{digits}f}" and digits < 6:
        digits += 1
    return f"{r:.{digits}f}"


def _span(values: list[float], unit: str = "x") -> str:
    lo, hi = min(values), max(values)
    return f"{lo:.2f}{unit}" if f"{lo:.2f}" == f"{hi:.2f}" else f"{lo:.2f}-{hi:.2f}{unit}"


def _more(n: int) -> str:
    return f"{n} more {'has' if n == 1 else 'have'}"


def _tally(verdicts: dict) -> tuple[int, list[str], int]:
    """``(met, names missed, unmeasured)`` of a verdict table of :func:`.run._targets`."""
    missed = [name for name, ok in verdicts.items() if ok is False]
    met = sum(ok is True for ok in verdicts.values())
    return met, missed, sum(ok is None for ok in verdicts.values())


def targets_summary(result: dict) -> str:
    """The targets in three lines (peers, scipy, first answer): how many measured cases met each,
    every miss with its figure, and the range of the cases met. Met or missed is the run's own
    verdict (``result["targets"]``, :func:`.run._targets`); only the figures are looked up here."""

    t = result["targets"]
    lines = []
    h2h = result.get("peer_head_to_head") or {}
    if result.get("fastest_peers"):
        from .fastest_report import verdict_lines

        lines += verdict_lines(result["fastest_peers"])
    elif h2h:
        met, missed, unmeasured = _tally(t["ours_at_least_as_fast_as_every_peer"])
        figures = []
        for name in missed:
            peer, key, acc = name.split(" ")
            e = (h2h.get(peer, {}).get(key) or {}).get(acc) or {}
            shown = "no figure" if e.get("ratio") is None else _near(e["ratio"], 1.0, 2)
            figures.append(f"{peer} on {key} at {acc} ({shown})")
        spans = []
        for peer, rows in h2h.items():
            ratios = [
                r
                for row in rows.values()
                for e in row.values()
                if (r := (e or {}).get("ratio")) is not None and r >= 1.0
            ]
            if ratios:
                spans.append(f"{peer} {_span(ratios)}")
        lines.append(
            f"- **Peers: met in {met} of {met + len(missed)} measured cases"
            + (f", missed in {len(missed)}**: " + "; ".join(figures) + "." if missed else ".**")
            + (
                f" {_more(unmeasured)} no figure (a sweep did not reach that accuracy)."
                if unmeasured
                else ""
            )
            + " Where met, the peer takes this many times our time: "
            + "; ".join(spans)
            + "."
        )
    met, missed, unmeasured = _tally(t[f"ours_{SCIPY_FACTOR:g}x_faster_than_scipy"])
    figures = []
    for name in missed:  # a figure left out of the run (no scipy answer) is said, not looked up
        key, acc = name.split(" ")
        e = (result.get("ratios", {}).get(key) or {}).get(acc) or {}
        bound = ">=" if e.get("ratio_is_lower_bound") else ""
        shown = "no figure"
        if e.get("ratio") is not None:
            shown = f"{bound}{_near(e['ratio'], SCIPY_FACTOR, 0)}x"
        against = (e.get("scipy") or {}).get("method", "no scipy option reaching it")
        figures.append((f"{key} at {acc} ({shown}", against))
    against = {m for _, m in figures}
    if len(against) == 1:  # name the scipy option once
        missed_s = "; ".join(f"{w})" for w, _ in figures) + f", all against {against.pop()}"
    else:
        missed_s = "; ".join(f"{w}, against {m})" for w, m in figures)
    lines.append(
        f"- **scipy: {SCIPY_FACTOR:g}x met in {met} of {met + len(missed)} measured cases"
        + (f", missed in {len(missed)}**: {missed_s}." if missed else ".**")
        + (
            f" {_more(unmeasured)} no figure (no method of ours reached that accuracy)."
            if unmeasured
            else ""
        )
    )
    fa = result.get("first_answer")
    first = t.get("first_answer_at_least_as_fast_as_odeint")
    measured = fa and all(
        "median_s" in fa.get(k, {}) for k in (*our_first_runs(fa), "scipy-odeint")
    )
    if measured and first is not None:
        ours = min(fa[k]["median_s"] for k in (*our_first_runs(fa), "taylor-aot") if k in fa)
        theirs = fa["scipy-odeint"]["median_s"]
        verdict = "met" if first else f"missed by {ours / theirs:.1f}x"
        aot = (
            f", {fa['taylor-aot']['median_s']} s with `taylor` compiled ahead of time "
            "(`mechviz.dynamics.aot`)"
            if "taylor-aot" in fa
            else ""
        )
        each = " and ".join(f"{fa[m]['median_s']} s with `{m}`" for m in our_first_runs(fa))
        lines.append(
            f"- **First answer: {verdict}.** A fresh process reaches the hoop's state at 20 s at "
            f"1e-9 in {each}{aot}, against {theirs} s with scipy's `odeint` (median of "
            f"{len(fa[our_first_runs(fa)[0]]['runs_s'])} processes each)."
        )
    return "\n".join(lines)


def method_table(result: dict) -> str:
    """Time each method needs to reach each accuracy (with its evaluations)."""
    parts = []
    for key, row in result["ratios"].items():
        methods = sorted({m for e in row.values() for m in e["per_method"]})
        rows = []
        for m in methods:
            cells = []
            for e in row.values():
                v = e["per_method"].get(m)
                cells.append("-" if v is None else f"{_ms(v['seconds'])} ({v['nfev']} fev)")
            rows.append([m, *cells])
        parts.append(f"\n**{key}**\n\n" + _table(["method", *row], rows))
    return "\n".join(parts)


def first_answer_table(result: dict) -> str:
    fa = result.get("first_answer")
    cons = result.get("construction_us") or {}
    tables = []
    if fa:
        header = ["fresh process to the hoop's state at 20 s, 1e-9", "median [s]", "runs [s]"]
        runs = (*our_first_runs(fa), "taylor-aot", "scipy-odeint")
        rows = [[k, fa[k]["median_s"], fa[k]["runs_s"]] for k in runs if k in fa]
        tables.append(_table(header, rows))
    if cons:
        header = ["problem", "new Simulation [us]", "restart() [us]"]
        extra = {
            "new_simulation_dop853": "new Simulation, dop853 [us]",
            "new_solver": "new Solver [us]",
        }
        shown = [k for k in extra if all(k in v for v in cons.values())]
        header += [extra[k] for k in shown]
        rows = [
            [k, v["new_simulation"], v["restart"], *(v[x] for x in shown)] for k, v in cons.items()
        ]
        tables.append(_table(header, rows))
    return "\n\n".join(tables) or "-"


def step_table(result: dict) -> str:
    rows = []
    for name, r in result["per_step"]["rows"].items():
        c = r.get("c_ns")
        ratio = r.get("ratio_to_c")
        rows.append(
            [
                name,
                f"{r['numba_ns']:.1f}",
                "-" if c is None else f"{c:.1f}",
                "-" if ratio is None else f"{ratio:.2f}",
                r.get("c_notes_ns") or "-",
            ]
        )
    header = ["step", "numba ns/step", "C -O2 ns/step (same run)", "numba / C"]
    return _table([*header, "C, earlier run"], rows)


def _goal(r: float, goal: float = 1.05) -> str:
    text = _near(r, goal, 3)
    return f"**{text}**" if r > goal else text


def form_cost_table(result: dict) -> str:
    """Per step, each form generated from the equations against the hand-written one it
    replaced (:mod:`.generated_cost`), and the generic Runge-Kutta runner given DOP853's tableau
    against DOP853's own loop (:mod:`.tableau_cost`): CPU time of the thread, paired rounds."""
    rows = []
    for name, r in (result.get("generated_cost") or {}).items():
        for form, f in r.items():
            if isinstance(f, dict):
                rows.append(
                    [
                        name,
                        f"generated {form}",
                        f"{f['ns_per_step_generated']:.1f}",
                        f"{f['ns_per_step_hand']:.1f}",
                        _goal(f["ratio"]),
                        f"{f['max_state_difference']:.1e}",
                    ]
                )
    for name, r in (result.get("tableau_cost") or {}).items():
        rows.append(
            [
                name,
                "generic runner, DOP853's tableau",
                f"{r['ns_per_step_generic']:.1f}",
                f"{r['ns_per_step_before']:.1f}",
                _goal(r["ratio"]),
                f"{r['max_state_difference']:.1e}",
            ]
        )
    header = ["problem", "form", "ns/step", "hand-written ns/step", "ratio", "state difference"]
    return _table(header, rows)


def exhibit_table(result: dict) -> str:
    rows = []
    for name, ex in result["exhibits"].items():
        for r in ex["rows"]:
            rel = "failed" if r["relative_error"] is None else f"{r['relative_error']:.2e}"
            lim = r["stability_limit_dt"]
            mark = (
                "**yes (chosen)**"
                if ex["chosen"] is r or ex["chosen"] == r
                else ("yes" if r["passes"] else "no")
            )
            rows.append(
                [
                    name,
                    r["method"],
                    f"{r['dt']:.5g}",
                    r["steps_per_frame"],
                    rel,
                    f"{1e6 * r['seconds_per_simulated_second']:.3g} us",
                    "none" if lim is None else f"{lim:.3g}",
                    mark,
                ]
            )
    header = ["exhibit", "method", "dt [s]", "steps/frame", "max error / size (600 s)"]
    return _table([*header, "compute per simulated s", "stability limit dt", "passes"], rows)


def long_run_table(result: dict) -> str:
    rows = [
        [
            key,
            f"{res['dt']:g}",
            m,
            f"{r['max_abs']:.2e}",
            f"{r['mean_first_10pc']:.2e}",
            f"{r['mean_last_10pc']:.2e}",
        ]
        for key, res in result["long_run"].items()
        for m, r in res["methods"].items()
    ]
    header = ["problem", "dt", "method", "max abs dE/E", "mean first 10 %", "mean last 10 %"]
    return _table(header, rows)


def ensemble_table(result: dict) -> str:
    e = result["ensembles"]
    rows = [
        [
            r["members"],
            r["member_steps"],
            f"{r['serial_ns']:.0f}",
            f"{r['parallel_ns']:.0f}",
            f"{r['speedup']:.2f}",
            "yes" if r["bitwise_equal"] else "**no**",
        ]
        for r in e["rows"].values()
    ]
    header = ["members N", "member-steps per run", "serial ns/member-step"]
    header += ["parallel ns/member-step", "serial / parallel", "bitwise equal"]
    return (
        f"{e['note']}; {e['cores']} cores, {e['threads']} numba threads "
        f"({e['threading_layer'] or 'no threading layer'}).\n\n" + _table(header, rows)
    )


def peers_block(result: dict) -> str:
    """The speed page's peers block: the peers in their fastest form when the run has them, else
    the sweeps' head-to-head table."""
    if result.get("fastest_peers"):
        from .fastest_picks import RULE_TITLES, RULES, has_rule
        from .fastest_report import case_table, distribution_table

        fast = result["fastest_peers"]
        if not has_rule(fast, "every-tighter"):  # a run from before the second rule
            return "\n\n".join(
                [
                    case_table(fast),
                    f"Random untuned cases (seed {fast['seed']}), peer / ours:",
                    distribution_table(fast),
                ]
            )
        parts = []
        for rule in RULES:
            parts += [
                f"Each contender's pick {RULE_TITLES[rule]}:",
                case_table(fast, rule=rule),
                f"Random untuned cases (seed {fast['seed']}), peer / ours, each pick "
                f"{RULE_TITLES[rule]}:",
                distribution_table(fast, rule),
            ]
        return "\n\n".join(parts)
    return peer_table(result)


def _peer_sections(result: dict) -> list[str]:
    """The peers' sections: in their fastest form (when run), then their sweeps."""
    sweeps = [
        "Our contenders and the peer's fastest point at each accuracy re-timed head to head in "
        "interleaved rounds.",
        peer_table(result),
    ]
    if not result.get("fastest_peers"):
        return [
            "## Peers: their time over our fastest (below 1, in bold: the peer is faster)"
        ] + sweeps
    return [
        "## Peers in their fastest form: their time over ours (below 1, in bold: the peer is "
        "faster)",
        fastest_section(result),
        "## Peers' sweeps (CyRK called from Python, heyoka without fast_math; the verdict is "
        "the fastest form's, above)",
        *sweeps,
    ]


#: How :mod:`.fastest` measured before its results said so themselves (``"how"``), for the
#: runs made then.
_FASTEST_HOW_BEFORE = (
    "For every case (the three benchmark problems and :func:`mechviz.bench.untuned.draw`'s "
    "random cases) and every contender, the tolerance ``rtol = atol = tol`` is swept down a grid "
    "of half-decades (:data:`GRID`) and each solve's error is measured against the case's "
    "reference (the same for every contender). At each accuracy target a contender's pick is its "
    "loosest tolerance whose error meets the target. The picks of all contenders are then timed "
    "in interleaved rounds in this one process (every round times every pick once, in rotating "
    "order; each pick's fastest round is kept), and the ratios are peer / ours: below 1 the peer "
    "is faster."
)


def fastest_section(result: dict) -> str:
    """The peers in their fastest form (:mod:`.fastest`): how they were measured, as the run
    says, and its figures."""
    from .fastest_report import markdown as fastest_markdown

    fast = result["fastest_peers"]
    return fast.get("how", _FASTEST_HOW_BEFORE) + "\n\n" + fastest_markdown(fast)


def markdown(result: dict) -> str:
    head = (
        f"Command: `{result['command']}`; date {result['date']}; {result['duration_s']} s; "
        f"load average {result['load_average']}; {result['machine'].get('cpu', '')}, "
        f"{result['machine']['cpus']} CPUs; versions {result['versions']}."
    )
    parts = [
        "# Benchmark tables",
        head,
        "## Targets",
        targets_summary(result),
        targets_list(result),
        "## Time to reach each accuracy: fastest scipy over fastest of ours",
        "Each side's contenders (within 1.5x of its fastest sweep time) re-timed head to head in "
        "interleaved rounds; *sweep ratio* is the figure from the sweeps alone. Problems ending "
        "in `-untuned` are the cases the methods were not tuned on.",
        ratio_table(result),
        *_peer_sections(result),
        "## First answer and construction",
        first_answer_table(result),
        "## Time per method to reach each accuracy",
        method_table(result),
    ]
    if result.get("batch"):
        from .batch import markdown as batch_table

        parts += [
            "## Many short problems: batch mode against heyoka's",
            batch_table(result["batch"]),
        ]
    if result.get("per_step"):
        parts += ["## Cost of one compiled step", step_table(result)]
    if result.get("generated_cost") or result.get("tableau_cost"):
        parts += [
            "## Generated and generic code against the hand-written code, per step",
            "Each form generated from the equations (the right-hand side inside DOP853, RK4's "
            "step, Taylor's series) and the generic Runge-Kutta runner given DOP853's tableau, "
            "timed beside the hand-written code they replaced in paired rounds (CPU time of the "
            "thread); *ratio* is the median of the rounds' ratios, at most 1.05 the goal (in "
            "bold above it); *state difference* the largest between the final states.",
            form_cost_table(result),
        ]
    if result.get("ensembles"):
        parts += ["## Ensembles: cost per member-step against N", ensemble_table(result)]
    if result.get("long_run"):
        parts += ["## Energy error over 10^4 periods", long_run_table(result)]
    if result.get("exhibits"):
        parts += [
            "## Exhibit defaults (10 min of simulated time, error below 1e-3 of the size)",
            exhibit_table(result),
        ]
    return "\n\n".join(parts) + "\n"


def summary(result: dict) -> dict:
    """The short form ``mechviz bench --json`` prints."""
    ratios = {
        key: {t: (None if e.get("ratio") is None else round(e["ratio"], 1)) for t, e in row.items()}
        for key, row in result["ratios"].items()
    }
    fastest = {
        key: {
            t: {
                "ours": e.get("ours"),
                "scipy": e.get("scipy"),
                "lower_bound": e.get("ratio_is_lower_bound"),
            }
            for t, e in row.items()
        }
        for key, row in result["ratios"].items()
    }
    return {
        "mode": result["mode"],
        "date": result["date"],
        "duration_s": result["duration_s"],
        "load_average": result["load_average"],
        "ratios": ratios,
        "peer_ratios": {
            peer: {
                k: {t: (None if r is None else round(r, 2)) for t, r in row.items()}
                for k, row in rows.items()
            }
            for peer, rows in result["peer_ratios"].items()
        },
        "peers_skipped": result["settings"]["peers_skipped"],
        "fastest": fastest,
        "targets": result["targets"],
        "construction_us": result["construction_us"],
        "first_answer": result["first_answer"],
        "per_step_ns": None
        if result["per_step"] is None
        else {
            k: {"numba": round(v["numba_ns"], 1), "c": v.get("c_ns")}
            for k, v in result["per_step"]["rows"].items()
        },
        "ensemble_ns_per_member_step": None
        if result.get("ensembles") is None
        else {
            k: {"serial": round(v["serial_ns"], 1), "parallel": round(v["parallel_ns"], 1)}
            for k, v in result["ensembles"]["rows"].items()
        },
        "exhibit_defaults": None
        if result["exhibits"] is None
        else {
            k: None
            if v["chosen"] is None
            else {"method": v["chosen"]["method"], "dt": v["chosen"]["dt"]}
            for k, v in result["exhibits"].items()
        },
        "viewer": result.get("viewer"),
        "charts": result.get("charts"),
        "fastest_peers": None
        if not result.get("fastest_peers")
        else {
            "seed": result["fastest_peers"]["seed"],
            "distribution": result["fastest_peers"]["distribution"],
            "losses": len(result["fastest_peers"]["losses"]),
            "losses_every_tighter": len(result["fastest_peers"].get("losses_every_tighter", [])),
        },
    }
