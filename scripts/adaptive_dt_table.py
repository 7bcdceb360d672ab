#!/usr/bin/env python3
"""Table of the adaptive growth step study (docs/growth.md, "Adaptive growth step").

Reads the run directories made by scripts/adaptive_dt_study.sh, OUT/<protocol>/P0_<P0>/seed<S>,
protocol = nominal or adaptive, and prints a Markdown table: for every P0 and target Δφ, the mean
± standard error over seeds of P, Z, u, G (budjam moduli, target_<k>.moduli.json) and the divisions
since jamming, for both protocols, the number of runs that reached the target, and the verdict on "the
two protocols agree" by the one rule of the reports (scripts/verdicts.py, `paired`): for each quantity
the per-seed differences, z = |mean| / paired SE, confirmed when z ≤ z_c (Student t, never below 2) for every quantity, not confirmed
when one has z > z_c, inconclusive with fewer than 5 paired seeds (no ± is printed from fewer either).
Only seeds that reached the target with both protocols are compared; the status of every run and the
steps past jamming are summarised below the table.

Usage: python3 scripts/adaptive_dt_table.py OUT
"""
import json
import math
import pathlib
import statistics
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import verdicts  # noqa: E402

QUANTITIES = [("P", "P"), ("Z", "Z"), ("u", "u"), ("G", "G"), ("N_div", "divisions")]


def load_runs(root, protocol):
    runs = {}
    for summary in sorted((root / protocol).glob("P0_*/seed*/summary.json")):
        d = json.loads(summary.read_text())
        P0 = summary.parent.parent.name[len("P0_"):]
        seed = int(summary.parent.name[len("seed"):])
        targets = {}
        for t in d.get("targets", []):
            row = dict(t)
            moduli = summary.parent / "packings" / f"target_{t['index']}.moduli.json"
            if moduli.exists():
                m = json.loads(moduli.read_text())
                row["G"] = m["G"] if m.get("energy_minimum") else math.nan
            else:
                row["G"] = math.nan
            targets[t["dphi"]] = row
        runs[(P0, seed)] = {"status": d["status"], "targets": targets, "steps": d["accepted_steps"] +
                            d["rejected_steps"], "step_J": d.get("step_J")}
    return runs


def mean_se(values):
    values = [v for v in values if not math.isnan(v)]
    if not values:
        return math.nan, math.nan, 0
    m = statistics.fmean(values)
    se = statistics.stdev(values) / math.sqrt(len(values)) if len(values) >= verdicts.MIN_SAMPLES else math.nan
    return m, se, len(values)


def fmt(m, se):
    if math.isnan(m):
        return "–"
    return f"{m:.4g} ± {se:.2g}" if not math.isnan(se) else f"{m:.4g}"


def agreement(judged):
    """One verdict over the quantities (label, Verdict): not confirmed if one is, confirmed if all are."""
    words = [v.word for _, v in judged]
    if "not confirmed" in words:
        return "not confirmed: " + ", ".join(f"{label} ({v.why})" for label, v in judged if v.word == "not confirmed")
    if all(w == "confirmed" for w in words):
        return "confirmed"
    return "inconclusive: " + next(f"{label} ({v.why})" for label, v in judged if v.word == "inconclusive")


def family_line(family):
    """Many quantities at many targets are many tests: with no difference at all, each has z > z_c (the
    97.5 % quantile of Student's t, or 2 where that is less) with probability at most p = 0.05, so a few
    rows "not confirmed" are expected by chance. The line gives their count against that expectation and
    the binomial chance of as many or more."""
    n, k = len(family), sum(v.word == "not confirmed" for v in family)
    p = 0.05
    tail = math.fsum(math.comb(n, j) * p ** j * (1 - p) ** (n - j) for j in range(k, n + 1))
    return (f"Of the {n} paired tests that differ from identity, {k} have z > z_c; with no difference "
            f"{n * p:.1f} are expected by chance (p = {p:.4f} each), and {k} or more with probability {tail:.2f}.")


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: adaptive_dt_table.py OUT")
    root = pathlib.Path(sys.argv[1])
    nominal, adaptive = load_runs(root, "nominal"), load_runs(root, "adaptive")
    if not nominal or not adaptive:
        sys.exit(f"{root}: no nominal/ or adaptive/ run directories with summary.json")
    header = "| P0 | Δφ | runs n/a | " + " | ".join(f"{label} nominal | {label} adaptive" for _, label in QUANTITIES)
    print(header + " | agree |")
    family = []  # every quantity's verdict with a z (not the identical ones, not the inconclusive)
    print("|" + "---|" * (header.count("|")))
    for P0 in sorted({k[0] for k in nominal}, key=float, reverse=True):
        seeds = sorted(s for p, s in nominal if p == P0 and (p, s) in adaptive)
        dphis = sorted({dphi for s in seeds for dphi in adaptive[(P0, s)]["targets"]})
        for dphi in dphis:
            n_nom = sum(dphi in nominal[(P0, s)]["targets"] for s in seeds)
            n_ad = sum(dphi in adaptive[(P0, s)]["targets"] for s in seeds)
            both = [s for s in seeds if dphi in nominal[(P0, s)]["targets"] and dphi in adaptive[(P0, s)]["targets"]]
            cells, judged = [], []
            for key, label in QUANTITIES:
                x = [float(nominal[(P0, s)]["targets"][dphi][key]) for s in both]
                y = [float(adaptive[(P0, s)]["targets"][dphi][key]) for s in both]
                a, b = mean_se(x), mean_se(y)
                cells += [fmt(a[0], a[1]), fmt(b[0], b[1])]
                # a G that is not a minimum's (NaN) in either run leaves that seed out of G's test
                pairs = [(u, w) for u, w in zip(x, y) if not (math.isnan(u) and math.isnan(w))]
                judged.append((label, verdicts.paired([w - u for u, w in pairs])))
            family += [v for _, v in judged if v.why.startswith("z =")]
            print(f"| {P0} | {dphi:g} | {n_nom}/{n_ad} | " + " | ".join(cells) + f" | {agreement(judged)} |")
    print()
    print(family_line(family))
    print()
    for name, runs in (("nominal", nominal), ("adaptive", adaptive)):
        for P0 in sorted({k[0] for k in runs}, key=float, reverse=True):
            rs = [r for k, r in runs.items() if k[0] == P0]
            statuses = {}
            for r in rs:
                statuses[r["status"]] = statuses.get(r["status"], 0) + 1
            past = [r["steps"] - r["step_J"] for r in rs if r["step_J"] is not None]
            print(f"- {name}, P0 = {P0}: {len(rs)} runs, status {statuses}, growth steps past jamming "
                  f"median {statistics.median(past) if past else '–'}, max {max(past) if past else '–'}")


if __name__ == "__main__":
    main()
