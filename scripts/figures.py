#!/usr/bin/python3
"""Draws the paper's figures from the tables written by `budjam analyse` (docs/analysis.md).

Drawing only: every number plotted here was computed by budjam (analysis.json and the CSV tables).
Run with Debian's python3 and python3-matplotlib:

    /usr/bin/python3 scripts/figures.py --tables analysis/quick/tables --out analysis/quick/figures fig2 fig3 ...

Each figure is written as <name>.png and <name>.pdf. A figure whose inputs are missing (no moduli,
no spectra, too few runs for a branch, a target the grid lacks) stops with an error naming what is
missing instead of drawing an empty plot. With --record-not-drawn (the pipeline's mode: a user's grid
need not hold every figure's inputs) it writes <name>.not-drawn with that reason instead, removes an
earlier <name>.png/.pdf, and goes on; the report names the reason.
"""
import argparse
import csv
import json
import math
import os
import sys

try:
    import matplotlib
except ImportError:
    print(f"figures.py: {sys.executable} has no matplotlib (Debian: apt-get install python3-matplotlib)", file=sys.stderr)
    sys.exit(2)

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
from matplotlib import cm, colors  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from verdicts import MIN_SAMPLES  # noqa: E402

PMAX = 0.1  # confluence pressure scale P_max (paper Eq. D25), also in analysis.json

# Okabe–Ito colours (distinguishable with every common colour-vision deficiency) for the categorical
# series; ordered scales use viridis / plasma, which stay ordered in grey and for colour-blind readers.
OKABE_ITO = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000"]
BLUE, VERMILLION = OKABE_ITO[0], OKABE_ITO[1]
plt.rcParams["axes.prop_cycle"] = matplotlib.cycler(color=OKABE_ITO)  # series without a colour of their own

# Axis units (docs/columns.md): stresses, pressures and 2D moduli in k, lengths
# in D0, frequencies in sqrt(k/m0).
K = r" [$k$]"
OMEGA = r" [$\sqrt{k/m_0}$]"


class Missing(Exception):
    pass


def read_csv(path):
    """Rows as dicts of text; an empty P0 field (no feedback; "none" in tables of earlier versions)
    becomes the label "none"."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        if r.get("P0") == "":
            r["P0"] = "none"
    return rows


def num(s):
    if s is None or s == "":
        return math.nan
    return float(s)



def err(*errors):
    """Error bars for errorbar(): a missing error (None, NaN: fewer than 5 samples, see `budjam analyse`)
    draws no bar (NaN, not a zero-length bar that reads as an exact value); None when no bar is left
    (matplotlib refuses an all-NaN error). Several lists: an asymmetric error [below, above]."""
    lists = [[e if isinstance(e, (int, float)) and math.isfinite(e) else math.nan for e in es] for es in errors]
    if not any(math.isfinite(e) for es in lists for e in es):
        return None
    return lists[0] if len(lists) == 1 else lists


def p0_value(label):
    """P0 label → x position on a log axis: 'none' sits one decade above the weakest feedback (at 1)."""
    return 1.0 if label == "none" else float(label)


def p0_text(label):
    return "no feedback" if label == "none" else r"$P_0=10^{%d}$" % round(math.log10(float(label)))


def p0_axis(ax, labels):
    xs = sorted({p0_value(l) for l in labels})
    ax.set_xscale("log")
    ax.set_xticks(xs)
    ax.set_xticklabels(["none" if x == 1.0 else r"$10^{%d}$" % round(math.log10(x)) for x in xs])
    ax.set_xlabel(r"$P_0$" + K)
    ax.minorticks_off()


def p0_colour(label, labels):
    """Strong feedback dark, weak light; no feedback black."""
    if label == "none":
        return "black"
    vals = sorted({float(l) for l in labels if l != "none"})
    if len(vals) <= 1:
        return cm.viridis(0.3)
    k = vals.index(float(label))
    return cm.viridis(0.05 + 0.85 * k / (len(vals) - 1))


def save(fig, out, name):
    os.makedirs(out, exist_ok=True)
    # Room for every panel's axis labels (a log axis' label can otherwise reach into its neighbour).
    fig.subplots_adjust(wspace=0.32)
    # No creation date in the files: the same tables give byte-identical figures.
    metadata = {"png": {"Software": None}, "pdf": {"CreationDate": None, "Producer": None}}
    for ext in ("png", "pdf"):
        fig.savefig(os.path.join(out, f"{name}.{ext}"), dpi=150, bbox_inches="tight",
                    metadata=metadata[ext])
    plt.close(fig)
    print(f"figure: {os.path.join(out, name)}.png/.pdf")


class Tables:
    def __init__(self, d):
        self.dir = d
        with open(os.path.join(d, "analysis.json")) as f:
            self.analysis = json.load(f)
        self.main_L = self.analysis["main_L"]

    def csv(self, name):
        return read_csv(os.path.join(self.dir, name))

    def groups(self, L=None):
        g = self.analysis["groups"]
        return [x for x in g if L is None or x["L"] == L]

    def need_moduli(self, what):
        if self.analysis["inputs"]["moduli_files"] == 0:
            raise Missing(f"{what} needs the elastic moduli: no .moduli.json files were found "
                          "(run `make -f Makefile.analysis moduli`, which needs `budjam moduli`)")

    def need_dos(self, what):
        if self.analysis["inputs"]["dos_files"] == 0:
            raise Missing(f"{what} needs the vibrational spectra: no .dos.json files were found "
                          "(run `make -f Makefile.analysis dos`, which needs `budjam dos`)")


def same_L(rows, L):
    return [r for r in rows if float(r["L"]) == float(L)]


def identity_line(ax, xs, ys, log=False):
    v = [x for x in list(xs) + list(ys) if math.isfinite(x) and (x > 0 or not log)]
    if not v:
        return
    lo, hi = min(v), max(v)
    ax.plot([lo, hi], [lo, hi], "k--", lw=1, zorder=0)


def panel(ax, letter):
    ax.text(-0.16, 1.04, letter, transform=ax.transAxes, fontweight="bold", fontsize=13)


# ---- Fig. 2: structure -------------------------------------------------------------------------------

def identity_scatter(ax, points, colour_of, label_of, missing, log=False):
    """A marker per (row, x, y), each legend label once, and the line y = x; Missing if no point."""
    if not points:
        raise Missing(missing)
    seen = set()
    for r, x, y in points:
        key = label_of(r)
        ax.plot(x, y, "o", ms=4, color=colour_of(r), alpha=0.8, label=None if key in seen else key)
        seen.add(key)
    identity_line(ax, [x for _, x, _ in points], [y for _, _, y in points], log=log)


def dz_identity(ax, targets, colour_of, label_of):
    points = []
    for r in targets:
        x, y = num(r["dZ_pred"]), num(r["dZ"])
        if math.isfinite(x) and math.isfinite(y):
            points.append((r, x, y))
    identity_scatter(ax, points, colour_of, label_of,
                     "ΔZ identity: no target has a ΔZ_0(P) prediction (the branch ΔZ_0(P) is the mean of a "
                     f"target's no-feedback runs, {MIN_SAMPLES} or more of them)")
    ax.set_xlabel(r"$\Delta Z_0(P)+2(u_J-u)$")
    ax.set_ylabel(r"$\Delta Z$")
    ax.legend(fontsize=7, frameon=False)


def fig2(T):
    L = T.main_L
    targets = same_L(T.csv("targets.csv"), L)
    labels = sorted({r["P0"] for r in targets}, key=p0_value, reverse=True)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    dz_identity(axes[0], targets, lambda r: p0_colour(r["P0"], labels), lambda r: p0_text(r["P0"]))
    panel(axes[0], "A")

    ax = axes[1]
    rem = same_L(T.csv("remaining.csv"), L)
    for lab in labels:
        rows = [r for r in rem if r["P0"] == lab]
        most = max([int(r["runs"]) for r in rows] or [0])
        rows = [r for r in rows if 2 * int(r["runs"]) >= most]  # where at least half the runs still contribute
        x = [num(r["dphi"]) for r in rows]
        y = [num(r["mean"]) for r in rows]
        e = [num(r["se"]) if r["se"] else math.nan for r in rows]
        c = p0_colour(lab, labels)
        ax.plot(x, y, "-", color=c, label=p0_text(lab))
        ax.fill_between(x, [a - b for a, b in zip(y, e)], [a + b for a, b in zip(y, e)], color=c, alpha=0.2, lw=0)
    ax.set_xscale("log")
    ax.set_xlabel(r"$\phi-\phi_J$")
    ax.set_ylabel(r"$u/u_J$ (buds free at $\phi_J$ still free)")
    ax.legend(fontsize=7, frameon=False)
    panel(ax, "B")

    ax = axes[2]
    gs = T.groups(L)
    for key, style, lab in (("dphi_2", "ko", "simulation"),
                            ("dphi_2_pred_area", "s", r"Eq. (14), $a$ as area"),
                            ("dphi_2_pred_diameter_sq", "^", r"Eq. (14), $a$ as diameter$^2$")):
        x = [p0_value(g["P0_label"]) for g in gs if g[key]["mean"] is not None]
        y = [g[key]["mean"] for g in gs if g[key]["mean"] is not None]
        e = err([g[key]["se"] for g in gs if g[key]["mean"] is not None])
        ax.errorbar(x, y, yerr=e, fmt=style if style != "ko" else "o", color="black" if style == "ko" else None,
                    mfc="none" if style != "ko" else "black", capsize=3, label=lab, ls="none")
    p0_axis(ax, [g["P0_label"] for g in gs])
    ax.set_yscale("log")
    ax.set_ylabel(r"$\phi_2-\phi_J$")
    ax.legend(fontsize=7, frameon=False)
    panel(ax, "C")
    fig.suptitle(f"Structure, L = {L:g}", fontsize=10)
    save(fig, T.out, "fig2")


def figS(T):
    """Kaplan–Meier S(a) with 95 % bands clustered by run (the input of Eq. 14)."""
    L = T.main_L
    rows = same_L(T.csv("survival.csv"), L)
    labels = sorted({r["P0"] for r in rows}, key=p0_value, reverse=True)
    fig, ax = plt.subplots(figsize=(5.5, 4))
    for lab in labels:
        rr = [r for r in rows if r["P0"] == lab]
        a = [num(r["a"]) * math.pi / 4 for r in rr]
        S = [num(r["S"]) for r in rr]
        c = p0_colour(lab, labels)
        ax.step(a, S, where="post", color=c, label=p0_text(lab))
        ax.fill_between(a, [num(r["lo"]) for r in rr], [num(r["hi"]) for r in rr], step="post", color=c, alpha=0.15, lw=0)
    ax.set_xscale("symlog", linthresh=1e-4)
    ax.set_xlabel(r"added bud area $a$ [$D_0^2$] (true area $\pi a/4$)")
    ax.set_ylabel(r"$S(a)$")
    ax.legend(fontsize=7, frameon=False)
    save(fig, T.out, "figS")


# ---- Fig. 3: mechanics -------------------------------------------------------------------------------

# Below this λ_c the compressed buds take no measurable part of the growth (arrested growth: their
# exp(−p/P0) down to 1e-159) and B_grow is zero within its fit error: on log axes such a target would
# sit 10^100 away from the rest (docs/analysis.md, "The paper preset"), so it is counted, not drawn.
ARRESTED_LAMBDA_C = 1e-6


def bgrow_identity(ax, targets, colour_of, label_of):
    points = []
    arrested = nonpositive = 0
    for r in targets:
        x = num(r["lambda_c"]) * num(r["B"])
        y = num(r["B_grow"])
        if not (math.isfinite(x) and math.isfinite(y) and x > 0):
            continue
        if num(r["lambda_c"]) < ARRESTED_LAMBDA_C:
            arrested += 1
            continue
        if y <= 0:
            nonpositive += 1
            continue
        points.append((r, x, y))
    identity_scatter(ax, points, colour_of, label_of, "B_grow identity: no target with both B_grow and B", log=True)
    ax.text(0.97, 0.03, f"not shown: {arrested} with $\\lambda_c < 10^{{-6}}$,\n{nonpositive} with $B_{{\\rm grow}} \\leq 0$",
            transform=ax.transAxes, ha="right", va="bottom", fontsize=7)
    ax.legend(fontsize=7, frameon=False, loc="upper left")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(r"$\lambda_c B_{\rm ext}$" + K)
    ax.set_ylabel(r"$B_{\rm grow}=\phi\,(\partial P/\partial\phi)_{\rm grow}$" + K)


def fig3(T):
    T.need_moduli("Fig. 3")
    L = T.main_L
    targets = same_L(T.csv("targets.csv"), L)
    runs = same_L(T.csv("runs.csv"), L)
    labels = sorted({r["P0"] for r in targets}, key=p0_value, reverse=True)
    gs = T.groups(L)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    bgrow_identity(axes[0], targets, lambda r: p0_colour(r["P0"], labels), lambda r: p0_text(r["P0"]))
    panel(axes[0], "A")

    ax = axes[1]
    g2 = [g for g in gs if g["P_2_over_Pmax"]["mean"] is not None]
    ax.errorbar([p0_value(g["P0_label"]) for g in g2], [g["P_2_over_Pmax"]["mean"] for g in g2],
                yerr=err([g["P_2_over_Pmax"]["se"] for g in g2]), fmt="ko", capsize=3)
    p0_axis(ax, [g["P0_label"] for g in gs])
    ax.set_yscale("log")
    ax.set_ylabel(r"$P_2/P_{\max}$")
    ins = ax.inset_axes([0.58, 0.12, 0.38, 0.35])
    lb = [g for g in gs if g["lambda_bar"]["mean"] is not None]
    ins.errorbar([p0_value(g["P0_label"]) for g in lb], [g["lambda_bar"]["mean"] for g in lb],
                 yerr=err([g["lambda_bar"]["se"] for g in lb]), fmt="s", ms=3, color=BLUE, capsize=2)
    ins.set_xscale("log")
    ins.set_yscale("log")
    ins.set_xlabel(r"$P_0$" + K, fontsize=7)
    ins.set_ylabel(r"$\bar\lambda_c$", fontsize=7)
    ins.tick_params(labelsize=6)
    panel(ax, "B")

    ax = axes[2]
    for r in runs:
        if math.isfinite(num(r["G_2"])):
            ax.plot(p0_value(r["P0"]), num(r["G_2"]), "o", color="0.7", ms=3, zorder=1)
    gm = [g for g in gs if g["G_2"]["median"] is not None]
    ax.errorbar([p0_value(g["P0_label"]) for g in gm], [g["G_2"]["median"] for g in gm],
                yerr=err([g["G_2"]["se"] for g in gm]), fmt="ko", capsize=3, zorder=2, label="median ± bootstrap SE")
    p0_axis(ax, [g["P0_label"] for g in gs])
    ax.set_ylabel(r"$G_2=G(\phi_2)$" + K)
    # symlog: a run near a shear instability of its box (G_2 ≪ 0) stays visible without flattening the rest
    ax.set_yscale("symlog", linthresh=1e-2, linscale=0.5)
    ax.legend(fontsize=7, frameon=False)
    panel(ax, "C")
    fig.suptitle(f"Mechanics, L = {L:g}", fontsize=10)
    save(fig, T.out, "fig3")


# ---- Fig. 4: state diagram ---------------------------------------------------------------------------

def fig4(T):
    T.need_moduli("Fig. 4")
    L = T.main_L
    rows = same_L(T.csv("trajectory.csv"), L)
    labels = sorted({r["P0"] for r in rows}, key=p0_value, reverse=True)
    # Medians over runs (the paper: means): a packing near a shear instability of its box can have
    # G ≪ 0 and dominate the mean of a few runs (docs/moduli.md, "Shear stability").
    P, G = "P_median", "G_median"
    fig, ax = plt.subplots(figsize=(5.8, 4.5))
    for lab in labels:
        rr = sorted([r for r in rows if r["P0"] == lab and r["endpoint"] == "false"], key=lambda r: num(r["dphi"]))
        end = [r for r in rows if r["P0"] == lab and r["endpoint"] == "true"]
        pts = [(num(r[P]) / PMAX, num(r[G]) / PMAX) for r in rr if math.isfinite(num(r[G])) and num(r[P]) > 0]
        if end and math.isfinite(num(end[0][G])) and num(end[0][P]) > 0:
            pts.append((num(end[0][P]) / PMAX, num(end[0][G]) / PMAX))
        c = p0_colour(lab, labels)
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", color=c, label=p0_text(lab))
        if end and math.isfinite(num(end[0][G])):
            ax.plot(num(end[0][P]) / PMAX, num(end[0][G]) / PMAX, "o", color=c, ms=7)
    plateau = T.analysis["main"].get("G2_plateau_over_Pmax")
    if plateau:
        ax.axhline(plateau, ls="--", color="0.4", lw=1, label=r"$G_2(0^+)=n_Jk\ell_c^2M_4u_J$")
    ax.set_xscale("log")
    ax.set_xlabel(r"$P/P_{\max}$")
    ax.set_ylabel(r"$G/P_{\max}$")
    ax.legend(fontsize=7, frameon=False)
    ax.set_title(f"Post-jamming state diagram, L = {L:g} (medians over runs)", fontsize=10)
    save(fig, T.out, "fig4")


# ---- Appendix B: finite size -------------------------------------------------------------------------

def figB1(T):
    T.need_moduli("Fig. B1 (panels C, D)")
    targets = T.csv("targets.csv")
    Ls = sorted({float(r["L"]) for r in targets})
    col = {L: OKABE_ITO[k % len(OKABE_ITO)] for k, L in enumerate(Ls)}
    fig, axes = plt.subplots(1, 4, figsize=(18, 4.2))
    dz_identity(axes[0], targets, lambda r: col[float(r["L"])], lambda r: f"L = {float(r['L']):g}")
    panel(axes[0], "A")
    ax = axes[1]
    # every run (filled), the runs the paper's selection admits (open), Eq. 14 with a as area (dashed)
    for L in Ls:
        for key, fmt, lab in (("dphi_2", "o-", f"L = {L:g}"), ("dphi_2_paper", "o:", None)):
            gs = [g for g in T.groups(L) if g[key]["mean"] is not None]
            ax.errorbar([p0_value(g["P0_label"]) for g in gs], [g[key]["mean"] for g in gs],
                        yerr=err([g[key]["se"] for g in gs]), fmt=fmt, color=col[L], capsize=3, label=lab,
                        mfc=col[L] if key == "dphi_2" else "none")
        gs = [g for g in T.groups(L) if g["dphi_2_pred_area"]["mean"] is not None]
        ax.plot([p0_value(g["P0_label"]) for g in gs], [g["dphi_2_pred_area"]["mean"] for g in gs], "--",
                color=col[L], lw=1)
    ax.plot([], [], "ko-", label="every run")
    ax.plot([], [], "o:", color="k", mfc="none", label="paper's selection")
    ax.plot([], [], "k--", lw=1, label="Eq. (14), $a$ as area")
    p0_axis(ax, [g["P0_label"] for g in T.groups()])
    ax.set_yscale("log")
    ax.set_ylabel(r"$\phi_2-\phi_J$")
    ax.legend(fontsize=7, frameon=False)
    panel(ax, "B")
    bgrow_identity(axes[2], targets, lambda r: col[float(r["L"])], lambda r: f"L = {float(r['L']):g}")
    panel(axes[2], "C")
    ax = axes[3]
    for L in Ls:
        gs = [g for g in T.groups(L) if g["G_2"]["median"] is not None]
        ax.errorbar([p0_value(g["P0_label"]) for g in gs], [g["G_2"]["median"] for g in gs],
                    yerr=err([g["G_2"]["se"] for g in gs]), fmt="o-", color=col[L], capsize=3, label=f"L = {L:g}")
    p0_axis(ax, [g["P0_label"] for g in T.groups()])
    ax.set_ylabel(r"median $G_2$" + K)
    ax.legend(fontsize=7, frameon=False)
    panel(ax, "D")
    save(fig, T.out, "figB1")


# ---- Appendix D: divisions and paired mechanics --------------------------------------------------------

def figD1(T):
    L = T.main_L
    rows = same_L(T.csv("division_curve.csv"), L)
    gs = T.groups(L)
    labels = sorted({r["P0"] for r in rows}, key=p0_value, reverse=True)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    ax = axes[0]
    for lab in labels:
        rr = [r for r in rows if r["P0"] == lab]
        most = max([int(r["runs"]) for r in rr] or [0])
        rr = [r for r in rr if 2 * int(r["runs"]) >= most]  # where at least half the runs still contribute
        x = [num(r["dphi"]) for r in rr]
        c = p0_colour(lab, labels)
        ax.plot(x, [num(r["median"]) for r in rr], "-", color=c, label=p0_text(lab))
        # The quartile band only where it rests on MIN_SAMPLES runs or more (no spread from fewer).
        few = [int(r["runs"]) < MIN_SAMPLES for r in rr]
        ax.fill_between(x, [math.nan if f else num(r["q25"]) for r, f in zip(rr, few)],
                        [math.nan if f else num(r["q75"]) for r, f in zip(rr, few)], color=c, alpha=0.2, lw=0)
        g = [g for g in gs if g["P0_label"] == lab]
        if g and g[0]["dphi_2_median"]["median"] is not None:
            ax.axvline(g[0]["dphi_2_median"]["median"], ls="--", color=c, lw=1)
    ax.set_xscale("log")
    ax.set_xlabel(r"$\Delta\phi=\phi-\phi_J$")
    ax.set_ylabel(r"$N_{\rm div}^{\rm all}(\Delta\phi)/\langle N_J\rangle$")
    ax.legend(fontsize=7, frameon=False)
    panel(ax, "A")
    ax = axes[1]
    # φ_2 as the paper's figure takes it (no tagged bud left), and budjam's (at most one left)
    top = [1e-2]
    for key, filled, text in (("N_div_2_over_N_J_paper", True, "no tagged bud left"),
                              ("N_div_2_over_N_J", False, "at most one left")):
        gm = [g for g in gs if g.get(key, {}).get("median") is not None]
        med = [g[key]["median"] for g in gm]
        ci = [g[key].get("ci95") or [None, None] for g in gm]
        lo = [m - c[0] if c[0] is not None else None for m, c in zip(med, ci)]
        hi = [c[1] - m if c[1] is not None else None for m, c in zip(med, ci)]
        ax.errorbar([p0_value(g["P0_label"]) for g in gm], med, yerr=err(lo, hi), fmt="o" if filled else "s", capsize=3,
                    mfc="k" if filled else "none", color="k" if filled else "0.5", label=r"$\phi_2$: " + text)
        top += [c[1] if c[1] is not None else m for m, c in zip(med, ci)]
    p0_axis(ax, [g["P0_label"] for g in gs])
    ax.legend(fontsize=7, frameon=False)
    ax.set_yscale("symlog", linthresh=1e-3)
    ax.set_ylim(0, 3 * max(top))
    ax.set_ylabel(r"median $N_{\rm div}^{\rm all}(\phi_2)/\langle N_J\rangle$")
    panel(ax, "B")
    save(fig, T.out, "figD1")


def figD2(T):
    T.need_moduli("Fig. D2")
    L = T.main_L
    runs = same_L(T.csv("runs.csv"), L)
    gs = T.groups(L)
    labels = sorted({r["P0"] for r in runs}, key=p0_value, reverse=True)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    ax = axes[0]
    for lab in labels:
        rr = [r for r in runs if r["P0"] == lab and math.isfinite(num(r["G_2"])) and num(r["P_2"]) > 0]
        c = p0_colour(lab, labels)
        ax.plot([num(r["P_2"]) for r in rr], [num(r["G_2"]) for r in rr], "o", ms=3, color=c, alpha=0.5)
        g = [g for g in gs if g["P0_label"] == lab]
        if g and g[0]["G_2"]["median"] is not None and g[0]["P_2_median"]["median"] is not None:
            ax.errorbar(g[0]["P_2_median"]["median"], g[0]["G_2"]["median"], xerr=err([g[0]["P_2_median"]["se"]]),
                        yerr=err([g[0]["G_2"]["se"]]), fmt="o", ms=8, color=c, mec="k", capsize=3, label=p0_text(lab))
    ax.set_xscale("log")
    ax.set_xlabel(r"$P_2$" + K)
    ax.set_ylabel(r"$G_2$" + K)
    ax.legend(fontsize=7, frameon=False)
    panel(ax, "A")
    ax = axes[1]
    gm = [g for g in gs if g["G_2_over_P_2"]["median"] is not None]
    ax.errorbar([p0_value(g["P0_label"]) for g in gm], [g["G_2_over_P_2"]["median"] for g in gm],
                yerr=err([g["G_2_over_P_2"]["se"] for g in gm]), fmt="ko", capsize=3)
    p0_axis(ax, [g["P0_label"] for g in gs])
    ax.set_yscale("log")
    ax.set_ylabel(r"median $G_2/P_2$")
    panel(ax, "B")
    save(fig, T.out, "figD2")


# ---- Appendix E: growth-rate crossover -------------------------------------------------------------------

def figE1(T):
    L = T.main_L
    gs = [g for g in T.groups(L) if g["h_gamma"]["median"] is not None]
    if not gs:
        raise Missing("Fig. E1: no run has a target at Δφ = 3·10⁻³ (add it to TARGETS)")
    hist = same_L(T.csv("growth_rates.csv"), L)
    shown = [l for l in sorted({r["P0"] for r in hist if r["P0"] != "none"}, key=float, reverse=True)
             if float(l) in (1e-1, 1e-2, 1e-3, 1e-4)]
    fig = plt.figure(figsize=(10, 6.5))
    grid = fig.add_gridspec(2, max(1, len(shown)), height_ratios=[1.5, 1], hspace=0.45)
    ax = fig.add_subplot(grid[0, :])
    x = [p0_value(g["P0_label"]) for g in gs]
    y = [g["h_gamma"]["median"] for g in gs]
    ax.errorbar(x, y, yerr=err([g["h_gamma"]["se"] for g in gs]), fmt="ko-", capsize=3)
    p0_axis(ax, [g["P0_label"] for g in gs])
    ax.set_yscale("symlog", linthresh=1e-5)
    ax.set_ylim(0, 3 * max(y))
    ax.set_ylabel(r"$h_\gamma=\mathrm{Var}(g)/\langle g\rangle^2$ (median)")
    ax.set_title(r"Growth-rate crossover, $\Delta\phi=3\times10^{-3}$, L = %g" % L, fontsize=10)
    panel(ax, "A")
    for k, lab in enumerate(shown):
        ins = fig.add_subplot(grid[1, k])
        rr = [r for r in hist if r["P0"] == lab]
        bars = [r for r in rr if r["delta_at_1"] == "false"]
        ins.bar([num(r["g_lo"]) for r in bars], [num(r["density"]) for r in bars],
                width=[num(r["g_hi"]) - num(r["g_lo"]) for r in bars], align="edge", color=BLUE,
                label="compressed buds")
        delta = [num(r["density"]) for r in rr if r["delta_at_1"] == "true"]
        if delta:
            ins.annotate("", xy=(1.0, 0.95), xytext=(1.0, 0.0), xycoords=("data", "axes fraction"),
                         arrowprops=dict(arrowstyle="->", color=VERMILLION, lw=1.5))
            ins.text(0.97, 0.85, r"$u\,\delta(g-1)$: %.2f" % delta[0], color=VERMILLION, fontsize=7, ha="right",
                     transform=ins.transAxes)
        ins.set_xlim(0, 1.05)
        ins.set_title(p0_text(lab), fontsize=8)
        ins.set_xlabel(r"$g=\gamma/\gamma_0$", fontsize=8)
        if k == 0:
            ins.set_ylabel(r"$\Pi(g)$", fontsize=8)
        ins.tick_params(labelsize=6)
    save(fig, T.out, "figE1")


# ---- Appendix F: vibrational spectrum -------------------------------------------------------------------

def read_eigenvalues(path):
    rows = read_csv(path)
    if not rows:
        return []
    key = "lambda" if "lambda" in rows[0] else ("omega2" if "omega2" in rows[0] else None)
    if key is not None:
        return [math.sqrt(max(num(r[key]), 0.0)) for r in rows]
    if "omega" in rows[0]:
        return [num(r["omega"]) for r in rows]
    raise Missing(f"{path}: no 'lambda', 'omega2' or 'omega' column")


def figF1(T):
    T.need_dos("Fig. F1")
    L = T.main_L
    rows = same_L(T.csv("dos.csv"), L)
    labels = sorted({r["P0"] for r in rows}, key=p0_value, reverse=True)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    ax = axes[0]
    # the paper's panel A is at P0 = 1e-4; the strongest feedback present stands in without it
    fed = [l for l in labels if l != "none"]
    strong = next((l for l in fed if float(l) == 1e-4), min(fed, key=float, default=None))
    if strong is not None:
        # pooled over the runs of that P0, one curve per saved state φ_J … φ_2
        rr = [r for r in rows if r["P0"] == strong]
        names = sorted({r["packing"] for r in rr}, key=lambda n: (n != "jammed", n == "phi2", n))
        for k, name in enumerate(names):
            w, ws = [], []
            for r in (r for r in rr if r["packing"] == name):
                path = os.path.join(r["run"], "packings", r["packing"] + ".dos.csv")
                if not os.path.exists(path):
                    raise Missing(f"{path}: eigenvalues missing (`budjam dos` writes them)")
                w += [x for x in read_eigenvalues(path) if x > 1e-3]  # the band; quasi-zero modes in panel C
                ws.append(num(r["omega_star"]))
            if not w:
                continue
            c = cm.plasma(0.85 * k / max(1, len(names) - 1))
            dphi = [num(r["dphi"]) for r in rr if r["packing"] == name]
            lab = r"$\phi_J$" if name == "jammed" else (r"$\phi_2$" if name == "phi2" else
                                                       r"$\Delta\phi=%g$" % dphi[0])
            ax.hist(w, bins=30, density=True, histtype="step", color=c, label=lab)
            # ω* of that state (mean over the runs): a dashed line through the panel and a marker on
            # its top edge, both visible in print and in grey.
            omega_star = sum(ws) / len(ws)
            ax.axvline(omega_star, color=c, ls="--", lw=1.5)
            ax.plot(omega_star, 1, "v", transform=ax.get_xaxis_transform(), color=c, mec="k", ms=10, clip_on=False)
        ax.set_title(p0_text(strong) + f", {len({r['run'] for r in rr})} runs pooled", fontsize=8)
    ax.plot([], [], "k--", lw=1.5, label=r"$\omega^\ast$ (mean over runs)")
    ax.set_xlabel(r"$\omega$" + OMEGA)
    ax.set_ylabel(r"$D(\omega)$" + r" [$\sqrt{m_0/k}$]")
    ax.legend(fontsize=6, frameon=False)
    panel(ax, "A")
    ax = axes[1]
    # the paper's test: Δφ-target packings, ω* proportional to ΔZ (fit through the origin)
    tg = [r for r in rows if r["packing"].startswith("target_")]
    ax.plot([num(r["dZ"]) for r in tg], [num(r["omega_star"]) for r in tg], "o", ms=4, label=r"$\Delta Z=Z-Z_{\rm iso}(u)$")
    ax.plot([num(r["Z_minus_6"]) for r in tg], [num(r["omega_star"]) for r in tg], "x", ms=4, color="0.5",
            label=r"naive $Z-6$")
    fit = (T.analysis["main"].get("dos") or {}).get("paper")
    if fit and tg:
        xs = [0.0, max(num(r["dZ"]) for r in tg)]
        ax.plot(xs, [fit["through_origin_dZ"]["slope"] * x for x in xs], "-", color=BLUE, lw=1,
                label=r"$\omega^\ast\propto\Delta Z$")
    ax.axvline(0, color="0.8", lw=1)
    ax.set_xlabel(r"$\Delta Z$")
    ax.set_ylabel(r"$\omega^\ast$" + OMEGA)
    ax.legend(fontsize=7, frameon=False)
    panel(ax, "B")
    ax = axes[2]
    x = [num(r["N_u"]) for r in rows]
    y = [num(r["N_zero"]) for r in rows]
    ax.plot(x, y, "o", ms=4)
    identity_line(ax, x, y)
    ax.set_xlabel(r"$N_u$")
    ax.set_ylabel(r"$N_{\rm zero}$")
    panel(ax, "C")
    save(fig, T.out, "figF1")


# ---- accuracy against cost -----------------------------------------------------------------------

def accuracy(T):
    """Error against cost per quantity and setting set; each knob's non-dominated settings for that
    quantity (computed by `budjam accuracy`) joined by a line, the default as a red star. Zero errors
    sit at the bottom of the axis (open markers). The cost is what the front compares (`cost`)."""
    path = os.path.join(T.dir, "accuracy.json")
    if not os.path.exists(path):
        raise Missing(f"{path} missing: run `budjam accuracy` first")
    with open(path) as f:
        acc = json.load(f)
    rows = [r for r in acc["rows"] if not r["reference"] and r["knob"] != "repeat"]
    labels = {"phi_J": r"$|\Delta\phi_J|$", "u_J": r"$|\Delta u_J|$", "Z_J": r"$|\Delta Z_J|$",
              "phi_2": r"$|\Delta\phi_2|$", "P": r"$|\Delta P|/P$", "B": r"$|\Delta B|/B$", "G": r"$|\Delta G|/|G|$",
              "omega_star": r"$|\Delta\omega^*|/\omega^*$", "band": r"band $\max|\Delta\lambda|/\lambda$"}
    panels = []  # (family, set, quantity)
    for r in rows:
        for q in labels:
            v = r.get("err_" + q)
            if v is not None and (r["family"], r["set"], q) not in panels:
                panels.append((r["family"], r["set"], q))
    if not panels:
        raise Missing("accuracy.json has no measured errors")
    knobs = sorted({g["knob"] for g in acc["groups"]})
    colour = {k: OKABE_ITO[i % len(OKABE_ITO)] for i, k in enumerate(knobs)}
    cols = 4
    nrow = (len(panels) + cols - 1) // cols
    fig, axes = plt.subplots(nrow, cols, figsize=(4.2 * cols, 3.3 * nrow), squeeze=False)
    floor = 1e-17
    for ax, (fam, st, q) in zip(axes.flat, panels):
        mine = [r for r in rows if r["family"] == fam and r["set"] == st and r.get("err_" + q) is not None]
        errs = [r["err_" + q] for r in mine if r["err_" + q] > 0]
        lo = min(errs) / 10 if errs else floor
        byname = {r["variant"]: r for r in mine}
        for g in acc["groups"]:
            if g["family"] != fam or g["set"] != st:
                continue
            c = colour[g["knob"]]
            for name in g["variants"]:
                r = byname.get(name)
                if r is None or r["default"]:
                    continue
                e = r["err_" + q]
                ax.plot(r["cost"], max(e, lo), "o" if e > 0 else "o", mfc=c if e > 0 else "none", mec=c, ms=5,
                        label=g["knob_label"] if name == g["variants"][1] else None)
                ax.annotate(name.replace("arpack ", "").replace(" ", "\n"), (r["cost"], max(e, lo)), fontsize=5,
                            xytext=(3, 2), textcoords="offset points")
            front = [byname[n] for n in g["front_by_quantity"].get(q, []) if n in byname]
            front.sort(key=lambda r: r["cost"])
            if len(front) > 1:
                ax.plot([r["cost"] for r in front], [max(r["err_" + q], lo) for r in front], "-", color=c, lw=1, alpha=0.8)
        for r in mine:
            if r["default"]:
                e = r["err_" + q]
                ax.plot(r["cost"], max(e, lo), "*", color=VERMILLION, ms=11, zorder=5, label="default")
        ax.set_xscale("log")
        ax.set_yscale("log")
        # Errors that differ by less than a factor error_ratio, or lie below error_floor, tie (the
        # front rule): show at least three decades so that rounding-level differences do not look big.
        fl = max([g.get("error_floor", acc["front_rule"]["error_floor"]) for g in acc["groups"]
                  if g["family"] == fam and g["set"] == st] or [acc["front_rule"]["error_floor"]])
        y0, y1 = ax.get_ylim()
        if y1 / y0 < 1e3:
            mid = math.sqrt(y0 * y1)
            y0, y1 = mid / 10 ** 1.5, mid * 10 ** 1.5
            ax.set_ylim(y0, y1)
        if fl > y0:
            ax.axhspan(y0, min(fl, y1), color="0.92", zorder=0)
            ax.text(0.98, 0.02, "below error floor: ties", transform=ax.transAxes, fontsize=5, ha="right", va="bottom",
                    color="0.4")
        ax.xaxis.set_major_locator(matplotlib.ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.tick_params(axis="x", labelsize=6)
        ax.set_xlabel("cost per run [CPU s]\n(force evaluations × mean CPU s per evaluation)" if fam == "growth"
                      else "CPU seconds per computation (best of interleaved repeats)", fontsize=7)
        ax.set_ylabel(labels[q])
        ax.set_title(f"{st}: {fam}", fontsize=8)
        ax.legend(fontsize=5, frameon=False, loc="best")
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    verdict = "every default is on its knob's front" if acc["defaults_on_front"] else \
        "NOT on the front: " + "; ".join(acc["not_on_front"])
    fig.suptitle(f"Accuracy against cost ({verdict}); lines: non-dominated settings per knob", fontsize=10)
    fig.tight_layout()
    save(fig, T.out, "accuracy")


FIGURES = {"fig2": fig2, "fig3": fig3, "fig4": fig4, "figB1": figB1, "figD1": figD1, "figD2": figD2,
           "figE1": figE1, "figF1": figF1, "figS": figS, "accuracy": accuracy}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tables", required=True, help="directory with analysis.json and the CSV tables")
    ap.add_argument("--out", required=True, help="directory for the figures")
    ap.add_argument("--record-not-drawn", action="store_true",
                    help="a figure whose inputs the tables lack is recorded in <name>.not-drawn, not an error")
    ap.add_argument("figures", nargs="+", choices=sorted(FIGURES))
    a = ap.parse_args()
    if a.figures == ["accuracy"]:
        T = type("Acc", (), {})()
        T.dir, T.out = a.tables, a.out
    else:
        T = Tables(a.tables)
        T.out = a.out
    plt.rcParams.update({"font.size": 9, "axes.labelsize": 10})
    for name in a.figures:
        reason = os.path.join(a.out, f"{name}.not-drawn")
        try:
            FIGURES[name](T)
        except Missing as e:
            print(f"figures.py: {name}: {'not drawn: ' if a.record_not_drawn else ''}{e}", file=sys.stderr)
            if not a.record_not_drawn:
                sys.exit(2)
            plt.close("all")
            for ext in ("png", "pdf"):
                if os.path.exists(os.path.join(a.out, f"{name}.{ext}")):
                    os.remove(os.path.join(a.out, f"{name}.{ext}"))
            os.makedirs(a.out, exist_ok=True)
            with open(reason + ".tmp", "w") as f:
                f.write(f"{e}\n")
            os.replace(reason + ".tmp", reason)
            continue
        if os.path.exists(reason):
            os.remove(reason)


if __name__ == "__main__":
    main()
