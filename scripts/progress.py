#!/usr/bin/env python3
"""One progress line on stderr for a stage of Makefile.analysis, after each of its items is done:

    [moduli 12/48 runs, ETA 3m05s]

The items are the stage's stamp files (summary.json, moduli.done, dos.done of every run): the count is
of those that exist now, so it is right under make -j and in every Slurm task. The ETA extrapolates
the pace of this make (the stamps made since it started at START, epoch seconds, AT_START of them
existing then, timed from the first of them, so that a stage that waited for another does not count
the wait), with each run weighted by its expected cost: the runs of a grid differ by orders of
magnitude (the strong-feedback and large-box runs are the slow ones). A run's cost is its growth's
wall time (timing.json) in the grow stage and its final cell count in the others; a run not done yet
is expected to cost the mean of the done runs of its group (the directory above its own, as
L15/P0_1e-3 above seed4), else of its box (the directory above that), else of all; with no cost known
every run weighs alike.

    python3 scripts/progress.py STAGE START AT_START STAMP...
"""
import json
import os
import sys
import time
from statistics import fmean


def measured_cost(stamp, stage):
    """The cost of a done run from its timing.json, or None."""
    try:
        with open(os.path.join(os.path.dirname(stamp), "timing.json"), encoding="utf-8") as f:
            t = json.load(f)
        cost = t["wall_seconds"] if stage == "grow" else t["final_N"]
        return float(cost) if float(cost) > 0 else None
    except (OSError, ValueError, KeyError, TypeError):
        return None


def expected_costs(stamps, done, stage):
    """Every stamp's cost: measured where done, else the mean of its group's, its box's or all done runs'."""
    known = {s: measured_cost(s, stage) for s in stamps if s in done}
    known = {s: c for s, c in known.items() if c is not None}
    if not known:
        return {s: 1.0 for s in stamps}

    def up(s, levels):
        d = os.path.dirname(os.path.abspath(s))
        for _ in range(levels):
            d = os.path.dirname(d)
        return d

    means = [{}, {}]  # by group (one level above the run), by box (two levels)
    for level, table in enumerate(means, start=1):
        groups = {}
        for s, c in known.items():
            groups.setdefault(up(s, level), []).append(c)
        table.update({g: fmean(cs) for g, cs in groups.items()})
    overall = fmean(known.values())
    return {s: known.get(s) or means[0].get(up(s, 1)) or means[1].get(up(s, 2)) or overall for s in stamps}


def main(argv):
    stage, start, at_start, stamps = argv[0], int(argv[1]), int(argv[2]), argv[3:]
    made = {}
    for s in stamps:
        try:
            made[s] = int(os.stat(s).st_mtime)
        except OSError:
            pass
    line = f"[{stage} {len(made)}/{len(stamps)} runs"
    this_make = sorted((t, s) for s, t in made.items() if t >= start)
    if len(made) < len(stamps) and len(made) - at_start - 1 > 0 and this_make:
        first = this_make[0][0]
        elapsed = int(time.time()) - first
        cost = expected_costs(stamps, made, stage)
        # the work done at the pace measured: every stamp of this make after the first one
        paced = sum(cost[s] for _, s in this_make[1:])
        remaining = sum(cost[s] for s in stamps if s not in made)
        if paced > 0 and elapsed > 0:  # (a pace within one second is no pace)
            eta = int(elapsed * remaining / paced)
            line += f", ETA {eta // 3600}h{eta % 3600 // 60:02d}m" if eta >= 3600 else f", ETA {eta // 60}m{eta % 60:02d}s"
    print(line + "]", file=sys.stderr)


if __name__ == "__main__":
    main(sys.argv[1:])
