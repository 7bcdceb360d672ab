#!/usr/bin/env python3
"""Tables and log-log fits for the scaling benchmark (docs/speed.md).

Reads runs of build/bench_scaling, each as a pair DIR/NAME.csv (its --csv, one row per growth
attempt) and DIR/NAME.txt (its standard output: box side, status, peak RSS), and prints
  1. whole runs (status finished): N_J, steps, evaluations/step, CPU s/step, wall, peak RSS;
  2. windows measured the same way in every run (also in runs stopped by --stop-after-rejections):
     the accepted steps with phi in [lo, hi), the last W accepted steps before the first rejected
     trial (the densest unjammed states), and the first rejected trial (the start of the bisection
     onto phi_J);
  3. least-squares fits of log(quantity) against log(N), exponent +- standard error.

  python3 scripts/scaling_fit.py [--window LO HI] [--last W] RUN.csv...
Standard library only.
"""
import csv
import math
import re
import statistics
import sys


def fit(xs, ys):
    """Exponent k, its standard error and prefactor c of y = c N^k (least squares in log-log)."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    n = len(lx)
    mx, my = sum(lx) / n, sum(ly) / n
    sxx = sum((a - mx) ** 2 for a in lx)
    k = sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sxx
    res = [b - (my + k * (a - mx)) for a, b in zip(lx, ly)]
    se = math.sqrt(sum(r * r for r in res) / (n - 2) / sxx) if n > 2 else float("nan")
    return k, se, math.exp(my - k * mx)


def linear(xs, ys):
    """a + b x by least squares."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    return my - b * mx, b


def load(path, lo, hi, last):
    rows = list(csv.DictReader(open(path)))
    txt = open(path[: -len(".csv")] + ".txt").read()
    run = {"name": path.rsplit("/", 1)[-1][: -len(".csv")]}
    run["L"] = float(re.search(r"L = ([0-9.]+)", txt).group(1))
    run["status"] = re.search(r"^status (\w+)", txt, re.M).group(1)
    m = re.search(r"peak RSS (\d+) KiB \(at start (\d+) KiB\)", txt)
    run["rss"], run["rss0"] = int(m.group(1)), int(m.group(2))
    run.update(cost_counters(txt))
    m = re.search(r"N_J (\d+)", txt)
    run["N_J"] = int(m.group(1)) if m else None
    run["stages"] = {m.group(1): {"accepted": int(m.group(2)), "rejected": int(m.group(3)), "evals": int(m.group(4)),
                                  "cpu": float(m.group(5))}
                     for m in re.finditer(r"^\s+(approach|bisect|above)\s+accepted\s+(\d+)\s+rejected\s+(\d+)\s+"
                                          r"evals\s+(\d+).*?cpu\s+([0-9.]+) s", txt, re.M)}
    tries = rows[1:]  # row 0: the relaxed initial state
    cpu = [float(r["cpu_s"]) for r in rows]
    step_cpu = [cpu[i + 1] - cpu[i] for i in range(len(tries))]
    run["accepted"] = sum(int(r["accepted"]) for r in tries)
    run["rejected"] = len(tries) - run["accepted"]
    run["evals"] = sum(int(r["evals"]) for r in rows)
    run["cpu"] = cpu[-1]
    run["wall"] = float(rows[-1]["wall_s"])
    run["N_final"] = int(rows[-1]["N"])
    first = next((i for i, r in enumerate(tries) if r["accepted"] == "0"), len(tries))
    run["per_search"] = marginal_per_search(tries)

    def window(idx):
        ev = sum(int(tries[i]["evals"]) for i in idx)
        c = sum(step_cpu[i] for i in idx)
        n = sum(int(tries[i]["N"]) for i in idx) / len(idx)
        return {"steps": len(idx), "N": n, "evals": ev / len(idx), "cpu": c / len(idx), "us": 1e6 * c / ev / n,
                "phi": (float(tries[idx[0]]["phi"]), float(tries[idx[-1]]["phi"]))}

    run["phi_window"] = window([i for i in range(first) if lo <= float(tries[i]["phi"]) < hi])
    run["last"] = window(list(range(max(0, first - last), first)))
    run["first_rejected"] = (
        {"evals": int(tries[first]["evals"]), "cpu": step_cpu[first], "N": int(tries[first]["N"]),
         "phi_accepted": float(tries[first]["phi"])} if first < len(tries) else None)
    return run


def cost_counters(txt):
    """The counters of bench_scaling's cost lines; None where an older output lacks the line."""
    m = re.search(r"search trials\s+(\d+)\s+marginal relaxations\s+(\d+)\s+Newton factorisations\s+(\d+)", txt)
    counters = dict(zip(("search_trials", "marginal", "newton_factorisations"),
                        map(int, m.groups()) if m else (None,) * 3))
    m = re.search(r"active set steps\s+(\d+)\s+factorisations\s+(\d+)\s+updates\s+(\d+)", txt)
    counters.update(zip(("active_set_steps", "active_set_factorisations", "active_set_updates"),
                        map(int, m.groups()) if m else (None,) * 3))
    return counters


def marginal_per_search(tries):
    """Marginal relaxations (attempts of more than 1e5 force evaluations, as summary.json counts them) in
    each search onto phi_J. A search starts at a rejected trial of the unjammed phase and ends at the
    next accepted attempt, the jammed state or a state below the window that growth goes on from, so a
    bracket settled there starts the next search; a search the run did not end is counted too."""
    counts, current = [], None
    for r in tries:
        marginal = int(int(r["evals"]) > 100000)
        if current is None:
            if r["accepted"] == "0" and r["phase"] == "unjammed":
                current = marginal
            continue
        current += marginal
        if r["accepted"] == "1":
            counts.append(current)
            current = None
    return counts + ([current] if current is not None else [])


def spans_sizes(xs):
    """Runs of one box side span a few per cent in N: no exponent or slope can be read from them."""
    return len(xs) > 1 and max(xs) >= 2 * min(xs)


def show_fit(label, xs, ys):
    if not spans_sizes(xs):
        return
    k, se, c = fit(xs, ys)
    print(f"  {label:<44s} ~ N^{k:.2f} ± {se:.2f}   (prefactor {c:.3g}, {len(xs)} runs, N = {min(xs):.0f}..{max(xs):.0f})")


def main(argv):
    lo, hi, last, paths = 0.78, 0.82, 20, []
    i = 0
    while i < len(argv):
        if argv[i] == "--window":
            lo, hi = float(argv[i + 1]), float(argv[i + 2])
            i += 3
        elif argv[i] == "--last":
            last = int(argv[i + 1])
            i += 2
        else:
            paths.append(argv[i])
            i += 1
    if not paths:
        print(__doc__)
        return 2
    runs = [load(p, lo, hi, last) for p in paths]

    whole = [r for r in runs if r["status"] == "finished"]
    if whole:
        print("Whole runs")
        print(f"  {'run':<10s} {'L':>5s} {'N_J':>6s} {'accepted':>8s} {'rejected':>8s} {'evals':>10s} {'evals/step':>10s} "
              f"{'CPU s':>8s} {'CPU s/step':>10s} {'wall s':>8s} {'peak RSS KiB':>12s}")
        for r in whole:
            print(f"  {r['name']:<10s} {r['L']:5g} {r['N_J']:6d} {r['accepted']:8d} {r['rejected']:8d} {r['evals']:10d} "
                  f"{r['evals'] / r['accepted']:10.1f} {r['cpu']:8.2f} {r['cpu'] / r['accepted']:10.5f} {r['wall']:8.1f} "
                  f"{r['rss']:12d}")
        print("  stages (approach: before the first rejected trial; bisect: on to the jammed state; above: targets)")
        for r in whole:
            st = r["stages"]
            print(f"  {r['name']:<10s} " + "  ".join(
                f"{k} {st[k]['accepted']}+{st[k]['rejected']} steps, {st[k]['evals']} evals, {st[k]['cpu']:.2f} s "
                f"({100 * st[k]['cpu'] / r['cpu']:.0f} %)" for k in ("approach", "bisect", "above")))
        print("  by box side: runs, median CPU s (range), median search trials and marginal relaxations "
              "(trials above 1e5 evaluations) per run, factorisations per run, and marginal relaxations per "
              "search onto phi_J")
        for side in sorted({r["L"] for r in whole}):
            at = [r for r in whole if r["L"] == side]
            cpu = [r["cpu"] for r in at]
            counted = [r for r in at if r["marginal"] is not None]
            counts = (f"{statistics.median(r['search_trials'] for r in counted):g} trials, "
                      f"{statistics.median(r['marginal'] for r in counted):g} marginal "
                      f"({', '.join(str(r['marginal']) for r in counted)})" if counted else "no cost line")
            factored = [r for r in at if r["active_set_steps"] is not None]
            if factored:
                counts += (f", factorisations: Newton {statistics.median(r['newton_factorisations'] for r in factored):g}"
                           f", active set {statistics.median(r['active_set_factorisations'] for r in factored):g}"
                           f" ({statistics.median(r['active_set_steps'] for r in factored):g} linearisations, "
                           f"{statistics.median(r['active_set_updates'] for r in factored):g} rank-1 updates)")
            searches = [c for r in at for c in r["per_search"]]
            # A median of fewer than five searches is no statistic (the same rule as every ensemble).
            per_search = (f"per search median {statistics.median(searches):g}, mean {statistics.fmean(searches):.2f} "
                          f"({len(searches)} searches)" if len(searches) >= 5 else f"{len(searches)} searches")
            print(f"    L = {side:<5g} {len(at):3d} runs  CPU {statistics.median(cpu):9.2f} s "
                  f"({min(cpu):.2f}-{max(cpu):.2f})  {counts}; {per_search}")
        n = [r["N_J"] for r in whole]
        show_fit("whole run: CPU s per accepted step", n, [r["cpu"] / r["accepted"] for r in whole])
        show_fit("whole run: evaluations per accepted step", n, [r["evals"] / r["accepted"] for r in whole])
        show_fit("whole run: total CPU s", n, [r["cpu"] for r in whole])
        show_fit("whole run: CPU s of the bisection onto phi_J", n, [r["stages"]["bisect"]["cpu"] for r in whole])

    print(f"Windows (phi in [{lo}, {hi}) before the first rejection; last {last} accepted steps before it; "
          "first rejected trial)")
    print(f"  {'run':<10s} {'L':>5s} {'N':>7s} | {'steps':>5s} {'evals/step':>10s} {'CPU s/step':>10s} {'us/eval/cell':>12s} | "
          f"{'phi range':>15s} {'evals/step':>10s} {'CPU s/step':>10s} | {'evals':>8s} {'CPU s':>8s} | {'peak RSS KiB':>12s}")
    for r in runs:
        w, l, f = r["phi_window"], r["last"], r["first_rejected"]
        print(f"  {r['name']:<10s} {r['L']:5g} {w['N']:7.0f} | {w['steps']:5d} {w['evals']:10.1f} {w['cpu']:10.5f} "
              f"{w['us']:12.3f} | {l['phi'][0]:.4f}-{l['phi'][1]:.4f} {l['evals']:10.1f} {l['cpu']:10.5f} | "
              f"{f['evals'] if f else 0:8d} {f['cpu'] if f else 0:8.2f} | {r['rss']:12d}")
    n = [r["phi_window"]["N"] for r in runs]
    show_fit(f"phi in [{lo},{hi}): CPU s per accepted step", n, [r["phi_window"]["cpu"] for r in runs])
    show_fit(f"phi in [{lo},{hi}): evaluations per step", n, [r["phi_window"]["evals"] for r in runs])
    show_fit(f"phi in [{lo},{hi}): CPU per evaluation per cell", n, [r["phi_window"]["us"] for r in runs])
    show_fit(f"last {last} before rejection: CPU s per step", [r["last"]["N"] for r in runs],
             [r["last"]["cpu"] for r in runs])
    show_fit(f"last {last} before rejection: evaluations/step", [r["last"]["N"] for r in runs],
             [r["last"]["evals"] for r in runs])
    rej = [r for r in runs if r["first_rejected"]]
    show_fit("first rejected trial: CPU s", [r["first_rejected"]["N"] for r in rej],
             [r["first_rejected"]["cpu"] for r in rej])
    show_fit("first rejected trial: evaluations", [r["first_rejected"]["N"] for r in rej],
             [r["first_rejected"]["evals"] for r in rej])
    nm = [float(r["N_J"] or r["N_final"]) for r in runs]
    extra = [float(r["rss"] - r["rss0"]) for r in runs]
    show_fit("peak RSS - RSS at start", nm, extra)
    if spans_sizes(nm):
        a, b = linear(nm, extra)
        print(f"  peak RSS - RSS at start, linear: {a:.0f} KiB + {1024 * b:.0f} bytes x N")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
