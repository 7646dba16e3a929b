"""Markdown and terminal text for :mod:`mechviz.bench.fastest`'s results: the ratios per case,
their distribution over the random cases, and every case where a peer is faster; and the
comparison alone from the command line (``python -m mechviz.bench.fastest_report``: exit
status 1 when a peer is faster in any case)."""

from __future__ import annotations

from .fastest import PEERS, run


def _r(r) -> str:
    if r is None:
        return "peer n/a"
    if r == 0.0:
        return "**ours n/a**"
    s = f"{r:.2f}"
    return f"**{s}**" if r < 1.0 else s


def _us(e: dict | None) -> str:
    return "n/a" if e is None else f"{e['who']} {1e6 * e['seconds']:.0f} us"


def case_table(result: dict, random: bool = False) -> str:
    """Per case and accuracy: our time (kept, fresh) and each peer's ratio over it
    (``kept / fresh``: over our kept Simulation, over a fresh one)."""
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
        for target, row in case["targets"].items():
            if "unresolved" in row:
                lines.append(
                    f"| {key} | {target} | {row['unresolved']} |" + " |" * (len(peers) + 1)
                )
                continue
            f, r = row["fastest"], row["ratios"]
            cells = [
                f"{_r(r.get(f'{p}/kept'))}, {_r(r.get(f'{p}/fresh'))}"
                + (f" ({_us(f.get(p))})" if f.get(p) else "")
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


def distribution_table(result: dict) -> str:
    """Over the random cases, per accuracy, peer and form: the ratios' spread and how many are
    below 1."""
    lines = [
        "| accuracy | peer / ours | cases | below 1 | min | q1 | median | q3 | max | peer n/a |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for target, row in result["distribution"].items():
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


def loss_lines(result: dict) -> list[str]:
    """One line per case where a peer is faster than ours, with its figure."""
    out = []
    for e in result["losses"]:
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


def markdown(result: dict) -> str:
    n_loss = len(result["losses"])
    return "\n\n".join(
        [
            f"Seed {result['seed']}, {result['n_random']} random cases, {result['rounds']} "
            f"interleaved rounds; load average {result.get('load_average')}.",
            case_table(result, random=False),
            "Random cases, the distribution of peer / ours:",
            distribution_table(result),
            f"Every case where a peer is faster ({n_loss}):" + ("" if n_loss else " none."),
            "\n".join(f"- {line}" for line in loss_lines(result)),
            "Every random case:",
            case_table(result, random=True),
        ]
    )


def verdict_line(result: dict) -> str:
    """The peers' target in one line: comparisons met; each loss on the three problems with its
    figure, the random cases' losses by peer (how many, their range, the worst with its figure);
    every one is listed by :func:`loss_lines` (``tables.md``)."""
    rows = [
        r
        for case in result["cases"].values()
        for row in case["targets"].values()
        for r in (row.get("ratios") or {}).values()
    ]
    met = sum(r is None or r >= 1.0 for r in rows)
    losses = list(zip(result["losses"], loss_lines(result), strict=True))
    head = (
        f"- **Peers in their fastest form (seed {result['seed']}, {result['n_random']} random "
        f"cases and the three problems): ours at least as fast in {met} of {len(rows)} "
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
    losses_ = loss_lines(result)
    if losses_:
        print(f"\ntargets missed ({len(losses_)}):")
        print("\n".join(f"  {line}" for line in losses_))
    print(json.dumps({"seed": seed, "losses": len(losses_)}))
    return 1 if losses_ else 0


if __name__ == "__main__":
    raise SystemExit(main())
