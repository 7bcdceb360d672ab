#!/usr/bin/python3
"""Fig. 2B from Python: the fraction of the buds free at jamming that are still free, against
φ − φ_J, with and without growth feedback (the quantity of remaining.csv, `budjam analyse`).

    PYTHONPATH=build/python /usr/bin/python3 examples/buds_still_free.py --out fig2B.png

Grows every (P0, seed) with budjam.grow (nothing written to disk) and follows the bud events:
a tagged bud stops being free when it completes (gets a load-bearing contact) or its cell divides.
Defaults: L = 8, 4 seeds, P0 ∈ {none, 1e-3}: a few seconds on one core.
"""
import argparse
import pathlib

import numpy as np

import budjam

SCENE = pathlib.Path(__file__).resolve().parents[1] / "data" / "scenes" / "demo.toml"
GRID = np.logspace(-4, -1, 31)  # φ − φ_J


def still_free(scene, P0, seed):
    """(φ − φ_J, fraction still free) after each change, for the first jamming episode."""
    phi_J, tagged, left, curve = None, 0, 0, []
    # To φ_2 (after which at most one tagged bud is free) or φ_J + 0.1, whichever comes first.
    settings = [f"growth.P0={P0}", "jamming.targets=[1e-4]", "jamming.continue_to_phi2=true", "jamming.max_dphi=0.1"]
    for event in budjam.grow(scene, seed=seed, set=settings):
        if event["kind"] == "jammed" and phi_J is None:
            phi_J, tagged = event["phi_J"], event["tagged_J"]
        elif event["kind"] == "unjammed":
            break  # the buds were tagged in an episode that ended
        elif event["kind"] in ("bud_completed", "bud_divided") and tagged:
            left += 1
            curve.append((event["phi"] - phi_J, 1 - left / tagged))
    end = event["phi"] - phi_J if phi_J is not None else 0.0
    return curve, end


def on_grid(curve, end):
    """The step function sampled on GRID; NaN beyond the end of the run."""
    values = np.full(len(GRID), np.nan)
    for k, d in enumerate(GRID):
        if d <= end:
            values[k] = min([f for x, f in curve if x <= d], default=1.0)
    return values


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--P0", nargs="+", default=["none", "1e-3"])
    parser.add_argument("--out", default="fig2B.png")
    args = parser.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SystemExit("examples/buds_still_free.py: drawing needs matplotlib (Debian: python3-matplotlib)")

    fig, ax = plt.subplots(figsize=(4.5, 3.5))
    for P0 in args.P0:
        runs = np.array([on_grid(*still_free(SCENE, P0, seed)) for seed in range(1, args.seeds + 1)])
        counted = np.sum(~np.isnan(runs), axis=0)
        keep = 2 * counted >= counted.max()  # where at least half the runs still contribute, as Fig. 2B
        mean = np.nanmean(runs[:, keep], axis=0)
        ax.plot(GRID[keep], mean, "-", label="no feedback" if P0 == "none" else f"$P_0$ = {P0}")
        print(f"P0 = {P0}: fraction still free at dphi = {GRID[keep][-1]:.3g}: {mean[-1]:.3f}")
    ax.set_xscale("log")
    ax.set_xlabel(r"$\phi-\phi_J$")
    ax.set_ylabel(r"$u/u_J$ (buds free at $\phi_J$ still free)")
    ax.legend(frameon=False, fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=150)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
