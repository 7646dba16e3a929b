"""The peers' work-precision sweeps: heyoka's and CyRK's runs at each tolerance, their
accuracy measured against the same references as ours, and the table of how our fastest
compares with each peer's fastest at the accuracy targets."""

from __future__ import annotations

import time

from .peers import prepare as prepare_peer
from .problems import Problem
from .sweeps import (
    _PREPARED,
    Point,
    PointFailed,
    Settings,
    Solved,
    head_to_head,
    measure_point,
    sweep_tolerances,
    swept_point,
    time_to_reach,
)


def run_peer_point(problem: Problem, peer: str, settings: Settings, tol: float) -> Point:
    """One peer at one tolerance: built and run once untimed (heyoka compiles when built, a
    CyRK callback at its first call), then timed as ours (:func:`mechviz.bench.timing.time_calls`),
    its error against the same reference."""

    def solve() -> Solved:
        try:
            prepared = prepare_peer(peer, problem, tol)
            y = prepared.run()  # untimed: the first call compiles CyRK's C callback
            t0 = time.perf_counter()
            y = prepared.run()
            first = time.perf_counter() - t0
        except Exception as exc:  # a peer failing at one tolerance is a result, not a crash
            raise PointFailed(f"failed: {exc.__class__.__name__}: {exc}") from exc
        _PREPARED[(problem.key, peer, None, tol)] = prepared.run
        return Solved(y, prepared.nfev(), 0, first, True, None, lambda: prepared.run)

    return measure_point(problem, peer, True, None, tol, settings, solve)


def sweep_peer(problem: Problem, peer: str, settings: Settings) -> list[Point]:
    return sweep_tolerances(
        problem, settings, lambda tol: run_peer_point(problem, peer, settings, tol)
    )


def peer_table(
    points: list[Point],
    table: dict,
    peers: list[str],
    problems: dict[str, Problem],
    settings: Settings,
) -> dict:
    """Per peer, problem and target: the peer's time over our fastest, timed head to head.

    Our contenders are those of the ratio table (within 1.5x of our fastest, after its own
    head-to-head); the peer's is its fastest sweep point at the target. All are re-timed here
    in interleaved rounds and the ratio is peer / ours. ``None``: the peer (or we) did not
    reach the target within the cap.
    """
    out: dict = {}
    for peer in peers:
        out[peer] = {}
        for key, row in table.items():
            problem = problems[key]
            out[peer][key] = {}
            for target, entry in row.items():
                mine = [p for p in points if p.problem == key and p.method == peer]
                best = time_to_reach(mine, float(target))
                if best is None or "ours" not in entry:
                    out[peer][key][target] = None
                    continue
                fastest = entry["ours"]["seconds"]
                ours = []
                for m in entry["ours_methods"]:
                    v = entry["per_method"].get(m)
                    if v and v["seconds"] <= 1.5 * (entry.get("sweep", entry)["ours"]["seconds"]):
                        ours.append(swept_point(points, key, m, v))
                pts = [*ours, best]
                secs = head_to_head(problem, pts, settings.head_to_head_rounds, settings.min_sample)
                i_best = min(range(len(ours)), key=lambda i: secs[i])
                out[peer][key][target] = {
                    "ratio": secs[-1] / secs[i_best],
                    "peer": {"tol": best.tol, "seconds": secs[-1], "error": best.error},
                    "ours": {
                        "method": ours[i_best].method,
                        "seconds": secs[i_best],
                        "dt": ours[i_best].dt,
                        "tol": ours[i_best].tol,
                        "error": ours[i_best].error,
                    },
                    "sweep_ours_seconds": fastest,
                }
    return out


def flag_outliers(
    points: list[Point], problem: Problem, settings: Settings, slack: float = 1.3
) -> None:
    """Mark points slower than a point of the same method that does more work, re-timed once.

    Along one method's sweep more steps (or a tighter tolerance) never cost less time; a point
    that is more than ``slack`` times slower than a point further along was timed under a burst
    of other load. It is re-timed with up to three times the repeats (fewer for a slow point);
    if it still breaks the order it is flagged (``status = "outlier"``) and left off the charts
    and the tables.
    """

    def later(a: Point, b: Point) -> bool:  # b does more work than a
        if a.adaptive:
            return (b.tol or 0) < (a.tol or 0)
        return (b.dt or 0) < (a.dt or 0)

    for i, p in enumerate(points):
        if p.seconds is None or p.status != "ok":
            continue
        more = [q for q in points if q.method == p.method and q.seconds and later(p, q)]
        if not more or p.seconds <= slack * min(q.seconds for q in more):
            continue
        # Re-time with three times the repeats, within about 0.5 s: a slow point gets fewer.
        rounds = max(3, min(3 * settings.repeats, int(0.5 / max(p.seconds, 1e-9))))
        t = head_to_head(problem, [p], rounds, settings.min_sample)[0]
        p.seconds = min(p.seconds, t)
        if p.seconds > slack * min(q.seconds for q in more):
            points[i].status = "outlier"
