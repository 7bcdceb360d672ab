#!/usr/bin/env python3
"""Ensemble of two protocols (docs/jamming.md): the same seeds grown with two values
of one scene key (jamming.search unless --key says otherwise), and the mean ± standard error over
seeds of φ_J, u_J, Z_J, P, Z and G (`budjam moduli` on the packing saved there) at every target, φ_2,
with whether each difference is within the combined standard error |Δ| ≤ √(se_a² + se_b²) (runs are not paired: φ_J depends on the path, which the protocol changes).

Each difference is also given in units of that combined error, z = Δ / √(se_a² + se_b²): with many
quantities compared, some |z| > 1 are expected by chance alone (about one in three), |z| > 2 about one in
twenty. No mean, error or verdict is printed for a side with fewer than 5 finished runs.

Usage: python3 bench/search_ensemble.py OUT [--L 8] [--seeds 20] [--first-seed 1] [--P0 1e-3]
           [--targets '[1e-3,1e-2]'] [--jamming-only] [--key jamming.search] [--values secant,bracket]
           [--budjam build/budjam] [--builds OLD/budjam,NEW/budjam]
e.g. --key minimiser.energy_floor --values 1e-20,0.5e-16. With --builds the two sides are two builds,
each with its scene defaults (for a change of the code that changes every path). --jamming-only stops
every run at its jamming point (no targets, no φ_2: cheap, so hundreds of seeds). Give each box side
its own seeds (--first-seed 1000·L + 1, say) when ensembles of several sizes are compared with each
other. Runs are made two at a time under nice (an existing OUT/<side>/seed<S>/summary.json is kept).
"""
import argparse
import concurrent.futures
import datetime
import json
import math
import pathlib
import statistics
import subprocess


def sides(args):
    """(label, budjam executable, extra scene settings) of the two sides compared."""
    if args.builds:
        return [(f"build{k + 1}", exe, []) for k, exe in enumerate(args.builds.split(","))]
    return [(value, args.budjam, ["--set", f"{args.key}={value}"]) for value in args.values.split(",")]


def grow(args, side, seed):
    label, budjam, settings = side
    out = pathlib.Path(args.out) / label / f"seed{seed}"
    if not (out / "summary.json").exists():
        subprocess.run(["nice", "-n", "5", budjam, "grow", "data/scenes/paper-L15.toml", "--out", str(out),
                        "--overwrite", "--quiet", "--seed", str(seed), "--set", f"box.L={args.L}", "--set",
                        f"growth.P0={args.P0}", "--set", f"jamming.targets={args.targets}", "--set",
                        f"jamming.continue_to_phi2={'false' if args.jamming_only else 'true'}", *settings, "--set",
                        "observe.checkpoint_every=0"],
                       check=True)
    summary = json.loads((out / "summary.json").read_text())
    for t in summary["targets"]:
        moduli = subprocess.run([budjam, "moduli", str(out / "packings" / f"target_{t['index']}.pack"), "--json"],
                                check=True, capture_output=True, text=True).stdout
        t["G"] = json.loads(moduli)["G"]
    return summary


def quantities(summary):
    q = {"phi_J": summary["phi_J"], "u_J": summary["u_J"], "n_J": summary["n_J"], "Z_J": summary["Z_J"]}
    if summary.get("phi_2") is not None:
        q["phi_2"] = summary["phi_2"]
    for t in summary["targets"]:
        q[f"P at {t['dphi']:g}"] = t["P"]
        q[f"Z at {t['dphi']:g}"] = t["Z"]
        q[f"G at {t['dphi']:g}"] = t["G"]
    return q


def mean_se(values):
    values = [v for v in values if v is not None]
    if len(values) < 5:
        return math.nan, math.nan, len(values)
    return statistics.fmean(values), statistics.stdev(values) / math.sqrt(len(values)), len(values)


def print_tsv(args, table, values, seeds):
    """Rows of bench/results/search_ensemble.tsv: date, host, L, protocol, seeds, quantity, mean, SE, command."""
    compared = [("builds", args.builds)] if args.builds else [("key", args.key), ("values", args.values)]
    command = "python3 bench/search_ensemble.py OUT " + " ".join(
        f"--{k.replace('_', '-')} {v}" for k, v in [("L", args.L), ("seeds", args.seeds), ("first_seed", args.first_seed),
                                                     ("P0", args.P0)] + compared)
    command += " --jamming-only" if args.jamming_only else f" --targets '{args.targets}'"
    names = list(dict.fromkeys(name for s in values for q in table[s] for name in q))
    for s in values:
        protocol = s if args.builds else f"{args.key}={s}"
        for name in names:
            m, se, n = mean_se([q.get(name) for q in table[s]])
            if math.isnan(m):
                continue
            print("\t".join([datetime.date.today().isoformat(), args.tsv, args.L, protocol, f"{seeds[0]}-{seeds[-1]}",
                             name.replace(" at ", "_"), f"{m:.6g}", f"{se:.2g}", command]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--L", default="8")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--P0", default="1e-3")
    ap.add_argument("--targets", default="[1e-3,1e-2]")
    ap.add_argument("--jamming-only", action="store_true")
    ap.add_argument("--key", default="jamming.search")
    ap.add_argument("--values", "--searches", dest="values", default="secant,bracket")
    ap.add_argument("--budjam", default="build/budjam")
    ap.add_argument("--builds", help="two budjam executables, compared with their scene defaults")
    ap.add_argument("--tsv", metavar="HOST", help="print the rows of bench/results/search_ensemble.tsv "
                    "(dated today, on HOST) instead of the table")
    args = ap.parse_args()
    if args.jamming_only:
        args.targets = "[]"
    compared = sides(args)
    values = [label for label, _, _ in compared]
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        jobs = {(side[0], k): pool.submit(grow, args, side, k) for side in compared for k in seeds}
        runs = {key: job.result() for key, job in jobs.items()}
    table = {s: [quantities(runs[(s, k)]) for k in seeds if runs[(s, k)]["status"] == "finished"] for s in values}
    names = list(dict.fromkeys(name for s in values for q in table[s] for name in q))
    if args.tsv:
        print_tsv(args, table, values, seeds)
        return
    print(f"L = {args.L}, P0 = {args.P0}, seeds {seeds[0]}-{seeds[-1]}; finished: " +
          ", ".join(f"{s} {len(table[s])}" for s in values))
    if args.builds:
        print("; ".join(f"{label} = {exe}" for label, exe, _ in compared))
    print("| quantity | " + " | ".join(values) + " | z | within SE |")
    print("|---" * (len(values) + 3) + "|")
    for name in names:
        stats = [mean_se([q.get(name) for q in table[s]]) for s in values]
        (ma, sa, _), (mb, sb, _) = stats[0], stats[-1]
        cells = " | ".join(f"{m:.6g} ± {se:.2g} (n={n})" if not math.isnan(m) else f"– (n={n})" for m, se, n in stats)
        se = math.hypot(sa, sb)
        if math.isnan(se):
            print(f"| {name} | {cells} | – | too few runs |")
        elif se == 0:
            print(f"| {name} | {cells} | – | {'yes' if ma == mb else 'NO'} |")
        else:
            z = (mb - ma) / se
            print(f"| {name} | {cells} | {z:+.2f} | {'yes' if abs(z) <= 1 else 'NO'} |")


if __name__ == "__main__":
    main()
