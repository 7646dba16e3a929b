"""Markdown and terminal text for :mod:`mechviz.bench.fastest`'s results: the ratios per case,
their distribution over the random cases, and every case where a peer is faster, under each
rule for picking a tolerance (:mod:`.fastest_picks`); and the comparison alone from the command
line (``python -m mechviz.bench.fastest_report``: exit status 1 when a peer is faster in any
case under either rule).

Results from before the every-tighter rule render as they always did (the loosest rule's
figures alone)."""

from __future__ import annotations

from .fastest import PEERS, run
from .fastest_picks import RULE_TITLES, RULES, has_rule, result_key, rule_row


def _r(r) -> str:
    if r is None:
        return "peer n/a"
    if r == 0.0:
        return "**ours n/a**"
    s = f"{r:.2f}"
    return f"**{s}**" if r < 1.0 else s


def _us(e: dict | None) -> str:
    return "n/a" if e is None else f"{e['who']} {1e6 * e['seconds']:.0f} us"


def _peer_cell(f: dict, p: str) -> str:
    """The peer's timed pick, and its pick against ours fresh where that differs (a form built
    per case counts its construction there)."""
    kept, fresh = f.get(p), f.get(f"{p}-fresh")
    if not kept:
        return ""
    if fresh is None or (fresh["who"], fresh["seconds"]) == (kept["who"], kept["seconds"]):
        return f" ({_us(kept)})"
    return f" ({_us(kept)}; against fresh: {_us(fresh)})"


def case_table(result: dict, random: bool = False, rule: str = "loosest") -> str:
    """Per case and accuracy, under ``rule``: our time (kept, fresh) and each peer's ratio over
    it (``kept / fresh``: over our kept Simulation, over a fresh one)."""
    peers = [p for p in PEERS if p not in {"heyoka", "cyrk"} or p not in _missing(result)]
    lines = [
        "| case | accuracy | ours, kept | ours, fresh | "
        + " | ".join(f"{p} / ours (kept, fresh)" for p in peers)
        + " |",
        "|---|---|---|---|" + "---|" * len(peers),
    ]
    for key, case in result["cases"].items():
        if key.startswith("random-") != random:
            continue
        for target, full in case["targets"].items():
            if "unresolved" in full:
                lines.append(
                    f"| {key} | {target} | {full['unresolved']} |" + " |" * (len(peers) + 1)
                )
                continue
            row = rule_row(full, rule)
            f, r = row["fastest"], row["ratios"]
            cells = [
                f"{_r(r.get(f'{p}/kept'))}, {_r(r.get(f'{p}/fresh'))}" + _peer_cell(f, p)
                for p in peers
            ]
            lines.append(
                f"| {key} | {target} | {_us(f.get('ours-kept'))} | {_us(f.get('ours-fresh'))} | "
                + " | ".join(cells)
                + " |"
            )
    return "\n".join(lines)


def _missing(result: dict) -> set[str]:
    return {k.lower() for k in (result.get("peers_missing") or {})}


def distribution_table(result: dict, rule: str = "loosest") -> str:
    """Over the random cases, per accuracy, peer and form, under ``rule``: the ratios' spread
    and how many are below 1."""
    lines = [
        "| accuracy | peer / ours | cases | below 1 | min | q1 | median | q3 | max | peer n/a |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for target, row in result[result_key("distribution", rule)].items():
        for name, d in row.items():
            vals = [
                "n/a" if d[k] is None else f"{d[k]:.2f}"
                for k in ("min", "q1", "median", "q3", "max")
            ]
            lines.append(
                f"| {target} | {name} | {d['n']} | {d['below_1']} | "
                + " | ".join(vals)
                + f" | {d['peer_not_reached']} |"
            )
    return "\n".join(lines)


def loss_lines(result: dict, rule: str = "loosest") -> list[str]:
    """One line per case where a peer is faster than ours under ``rule``, with its figure."""
    out = []
    for e in result[result_key("losses", rule)]:
        ours = (
            "ours did not reach it"
            if e["ours_who"] is None
            else f"ours {e['ours_who']} {1e6 * e['ours_seconds']:.0f} us"
        )
        out.append(
            f"{e['case']} {e['target']} {e['form']}: {e['peer']} / ours = {e['ratio']:.2f} "
            f"({e['peer_who']} {1e6 * e['peer_seconds']:.0f} us, {ours})"
        )
    return out


def _rule_sections(result: dict, rule: str) -> list[str]:
    n_loss = len(result[result_key("losses", rule)])
    return [
        case_table(result, random=False, rule=rule),
        "Random cases, the distribution of peer / ours:",
        distribution_table(result, rule),
        f"Every case where a peer is faster ({n_loss}):" + ("" if n_loss else " none."),
        "\n".join(f"- {line}" for line in loss_lines(result, rule)),
        "Every random case:",
        case_table(result, random=True, rule=rule),
    ]


def markdown(result: dict) -> str:
    parts = [
        f"Seed {result['seed']}, {result['n_random']} random cases, {result['rounds']} "
        f"interleaved rounds; load average {result.get('load_average')}."
    ]
    if not has_rule(result, "every-tighter"):  # a run from before the second rule
        return "\n\n".join(parts + _rule_sections(result, "loosest"))
    for rule in RULES:
        parts += [f"### Each contender's pick: {RULE_TITLES[rule]}", *_rule_sections(result, rule)]
    return "\n\n".join(parts)


def verdict_lines(result: dict) -> list[str]:
    """:func:`verdict_line` under each rule the results have."""
    if not has_rule(result, "every-tighter"):
        return [verdict_line(result)]
    return [verdict_line(result, rule) for rule in RULES]


def verdict_line(result: dict, rule: str | None = None) -> str:
    """The peers' target in one line, under ``rule`` (``None``: the loosest, unnamed, as results
    from before the second rule read): comparisons met; each loss on the three problems with its
    figure, the random cases' losses by peer (how many, their range, the worst with its figure);
    every one is listed by :func:`loss_lines` (``tables.md``)."""
    rows = [
        r
        for case in result["cases"].values()
        for full in case["targets"].values()
        for r in ((rule_row(full, rule or "loosest") or {}).get("ratios") or {}).values()
    ]
    met = sum(r is None or r >= 1.0 for r in rows)
    found = result[result_key("losses", rule or "loosest")]
    losses = list(zip(found, loss_lines(result, rule or "loosest"), strict=True))
    named = "" if rule is None else f", each pick {RULE_TITLES[rule]}"
    head = (
        f"- **Peers in their fastest form{named} (seed {result['seed']}, {result['n_random']} "
        f"random cases and the three problems): ours at least as fast in {met} of {len(rows)} "
        "comparisons"
    )
    if not losses:
        return head + ".**"
    fixed = [line for e, line in losses if not e["case"].startswith("random-")]
    by_peer: dict[str, list[tuple[dict, str]]] = {}
    for e, line in losses:
        if e["case"].startswith("random-"):
            by_peer.setdefault(e["peer"], []).append((e, line))
    parts = []
    if fixed:
        parts.append("on the three problems: " + "; ".join(fixed))
    for peer, pairs in by_peer.items():
        ratios = [e["ratio"] for e, _ in pairs]
        worst = min(pairs, key=lambda pair: pair[0]["ratio"])[1]
        cases = len({e["case"] for e, _ in pairs})
        parts.append(
            f"on random cases, {peer} in {len(pairs)} comparisons ({cases} cases), "
            f"{min(ratios):.2f}-{max(ratios):.2f}, at worst {worst}"
        )
    return (
        head
        + f", slower in {len(losses)}**: "
        + "; ".join(parts)
        + ". Every one with its figure: `docs/bench/tables.md`."
    )


def main(argv: list[str] | None = None) -> int:
    """``python -m mechviz.bench.fastest_report``: :mod:`.fastest`'s comparison alone; exit
    status 1 if a peer is faster in any case (each listed), 2 on bad input."""
    import argparse
    import json
    import os
    import secrets
    import sys

    from mechviz.dynamics.files import write_json_atomically

    parser = argparse.ArgumentParser(
        prog="python -m mechviz.bench.fastest_report", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--seed", type=int, default=None, help="random cases' seed (default: new)")
    parser.add_argument("--cases", type=int, default=21, help="random cases (default 21)")
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds (default 5)")
    parser.add_argument("--out", default=None, help="write the results here (JSON)")
    args = parser.parse_args(argv)
    if args.cases < 0:
        parser.error("--cases: must be 0 or more")
    if args.rounds < 1:
        parser.error("--rounds: must be 1 or more")
    seed = secrets.randbits(32) if args.seed is None else args.seed
    load = [round(x, 2) for x in os.getloadavg()]
    result = run(seed, args.cases, args.rounds, progress=lambda k: print(k, file=sys.stderr))
    result["load_average"] = {"before": load, "after": [round(x, 2) for x in os.getloadavg()]}
    if args.out:
        write_json_atomically(args.out, result, indent=1)
    print(markdown(result))
    losses_ = [f"{rule}: {line}" for rule in RULES for line in loss_lines(result, rule)]
    if losses_:
        print(f"\ntargets missed ({len(losses_)}):")
        print("\n".join(f"  {line}" for line in losses_))
    print(json.dumps({"seed": seed, "losses": len(losses_)}))
    return 1 if losses_ else 0


if __name__ == "__main__":
    raise SystemExit(main())
