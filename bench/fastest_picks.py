"""The tolerance grid of :mod:`.fastest`, its two rules for picking a contender's tolerance at an
accuracy target, and the losses and distributions of its results under each rule.

The grid runs from ``1e-2`` to ``1e-15`` in eighths of a decade (:data:`GRID`). A sweep runs
down the half-decades (:data:`COARSE`, every fourth grid tolerance) and then fills in the
eighths only where a pick could move: between each pick and the swept tolerance just looser
than it (:func:`to_refine`), until no pick does. The error an adaptive method reaches is not
smooth in its tolerance, so the eighths charge each contender less for accuracy it was not
asked for; sweeping all of them would take four times as long, most of it far from any pick.

The rules, over a contender's swept points (``{"tol", "error", "seconds"}``):

- **loosest** (:func:`loosest`): the loosest tolerance whose error meets the target;
- **every tighter** (:func:`every_tighter`): the loosest tolerance from which every tighter
  swept tolerance, to the end of the sweep, meets the target too: a user who asks for any
  tolerance at or below it gets the accuracy, where the loosest rule may have found a lucky
  point above tolerances that miss.

A solve that gives no answer (the solver refuses the tolerance, as ``odeint`` does below about
1e-13, or fails: ``"failed"`` in its point) or a non-finite one has an infinite error: it meets
no target. The every-tighter rule leaves out the tolerances without an answer (it judges the
answers a user gets, and a refusal is not a wrong answer); a non-finite answer counts as a miss.
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Iterable

TARGETS = (1e-3, 1e-6, 1e-9, 1e-12)
#: 1e-2 ... 1e-15 in eighths of a decade (105 tolerances); ``10 ** (-k / 8)`` for a multiple
#: ``k`` of 4 is the same double as the half-decade ``10 ** (-(k / 4) / 2)``.
GRID = tuple(10.0 ** (-k / 8) for k in range(16, 121))
COARSE_EVERY = 4  # the first sweep's step along GRID: half-decades
COARSE = GRID[::COARSE_EVERY]
PEERS = ("heyoka", "cyrk", "odeint")
#: Each rule, by name, and the key its figures are stored under (the loosest rule's figures
#: where the results always had them: ``row["fastest"]``, ``result["losses"]``).
RULES = {"loosest": "", "every-tighter": "every_tighter"}
RULE_TITLES = {
    "loosest": "the loosest tolerance meeting the target",
    "every-tighter": "the loosest tolerance from which every tighter one meets the target too",
}


def ordered(points: Iterable[dict]) -> list[dict]:
    """``points`` from the loosest tolerance to the tightest."""
    return sorted(points, key=lambda p: -p["tol"])


def loosest(points: list[dict], target: float) -> dict | None:
    """The loosest point whose error meets ``target`` (``None``: none did)."""
    return next((p for p in ordered(points) if p["error"] <= target), None)


def every_tighter(points: list[dict], target: float) -> dict | None:
    """The loosest point whose error and every tighter answered point's meet ``target``
    (``None``: the tightest answered point misses it)."""
    best = None
    for p in reversed(ordered(points)):
        if p.get("failed"):
            continue
        if not p["error"] <= target:
            break
        best = p
    return best


PICKS: dict[str, Callable[[list[dict], float], dict | None]] = {
    "loosest": loosest,
    "every-tighter": every_tighter,
}


def to_refine(points: list[dict], targets: Iterable[float], grid: tuple[float, ...]) -> list[float]:
    """The grid tolerances not yet swept that lie strictly between a pick (either rule, any of
    ``targets``) and the swept tolerance just looser than it, loosest first: where a pick could
    still move looser. A pick at the loosest swept tolerance has nothing above it to fill."""
    pts = ordered(points)
    swept = {p["tol"] for p in pts}
    out: set[float] = set()
    for target in targets:
        for rule in PICKS.values():
            p = rule(pts, target)
            if p is None:
                continue
            i = next(k for k, q in enumerate(pts) if q is p)
            if i == 0:
                continue
            hi, lo = pts[i - 1]["tol"], p["tol"]
            out |= {g for g in grid if lo < g < hi and g not in swept}
    return sorted(out, reverse=True)


def rule_row(row: dict, rule: str) -> dict | None:
    """A target's row of a case under ``rule``: ``{"fastest", "ratios"}`` (``None``: the row is
    unresolved, or the results predate the rule)."""
    if "unresolved" in row:
        return None
    key = RULES[rule]
    return row if not key else row.get(key)


def result_key(name: str, rule: str) -> str:
    """Where ``name`` (``"losses"``, ``"distribution"``) of ``rule`` is stored in the results."""
    return name if not RULES[rule] else f"{name}_{RULES[rule]}"


def has_rule(result: dict, rule: str) -> bool:
    """Whether ``result`` has figures under ``rule`` (a run before the every-tighter rule has
    the loosest rule's only)."""
    return result_key("losses", rule) in result


def peer_entry(fastest: dict, peer: str, form: str) -> dict | None:
    """The peer's timed pick a ratio over ours ``form`` (``"kept"``, ``"fresh"``) uses: against
    ours fresh, its time counts the construction of a form built per case (``<peer>-fresh``;
    results without it time every form alike)."""
    if form == "fresh" and f"{peer}-fresh" in fastest:
        return fastest[f"{peer}-fresh"]
    return fastest.get(peer)


def losses(result: dict, rule: str = "loosest") -> list[dict]:
    """Every case, accuracy, peer and form where the peer is faster than ours (ratio < 1), under
    ``rule``."""
    out = []
    for key, case in result["cases"].items():
        for target, full in case["targets"].items():
            row = rule_row(full, rule)
            if row is None:
                continue
            for name, r in (row.get("ratios") or {}).items():
                if r is not None and r < 1.0:
                    peer, form = name.split("/")
                    f = row["fastest"]
                    ours = f.get(f"ours-{form}")
                    theirs = peer_entry(f, peer, form)
                    out.append(
                        {
                            "case": key,
                            "target": target,
                            "peer": peer,
                            "form": form,
                            "ratio": r,
                            "peer_who": theirs["who"],
                            "peer_seconds": theirs["seconds"],
                            "ours_who": None if ours is None else ours["who"],
                            "ours_seconds": None if ours is None else ours["seconds"],
                        }
                    )
    return out


def distribution(result: dict, rule: str = "loosest") -> dict:
    """Per accuracy, peer and form, over the random cases, under ``rule``: how many ratios, how
    many below 1, and the minimum, quartiles and maximum of the ratios (a peer that did not
    reach the target counts as a win and is counted apart)."""
    out: dict = {}
    for target in (f"{t:.0e}" for t in TARGETS):
        out[target] = {}
        for peer in PEERS:
            for form in ("kept", "fresh"):
                rs, not_reached = [], 0
                for key, case in result["cases"].items():
                    if not key.startswith("random-"):
                        continue
                    row = rule_row(case["targets"].get(target) or {}, rule) or {}
                    ratios = row.get("ratios") or {}
                    if f"{peer}/{form}" not in ratios:
                        continue
                    r = ratios[f"{peer}/{form}"]
                    if r is None:
                        not_reached += 1
                    else:
                        rs.append(r)
                if not rs and not not_reached:
                    continue
                q = statistics.quantiles(rs, n=4, method="inclusive") if len(rs) >= 2 else rs * 3
                out[target][f"{peer}/{form}"] = {
                    "n": len(rs),
                    "below_1": sum(r < 1.0 for r in rs),
                    "peer_not_reached": not_reached,
                    "min": min(rs) if rs else None,
                    "q1": q[0] if rs else None,
                    "median": q[1] if rs else None,
                    "q3": q[2] if rs else None,
                    "max": max(rs) if rs else None,
                }
    return out


def ratios(times: dict, families: set[str]) -> dict[str, float | None]:
    """Peer / ours per peer in ``families`` and form: ``None`` when the peer did not reach the
    target (ours wins), 0 when only the peer did."""
    out: dict[str, float | None] = {}
    for peer in PEERS:
        if peer not in families:
            continue
        for form in ("kept", "fresh"):
            ours = times.get(f"ours-{form}")
            theirs = peer_entry(times, peer, form)
            if theirs is None:
                out[f"{peer}/{form}"] = None
            elif ours is None:
                out[f"{peer}/{form}"] = 0.0
            else:
                out[f"{peer}/{form}"] = theirs["seconds"] / ours["seconds"]
    return out
