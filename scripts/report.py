#!/usr/bin/python3
"""Writes REPRODUCTION.md: each quantitative claim of the paper beside the value budjam measured.

Formatting only: every measured number is read from `budjam analyse` output (analysis.json and
runs.csv); nothing is computed here beyond choosing which group a claim refers to. The output of
`budjam analyse --tables` (the estimators re-applied to stored tables when the run directories are
gone) is reported the same way; a cell whose inputs those tables lack says what it needs.

    /usr/bin/python3 scripts/report.py --tables analysis/quick/tables --figures analysis/quick/figures \
        --preset quick --moduli 1 --dos 1 --out analysis/quick/REPRODUCTION.md
"""
import argparse
import csv
import datetime
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import verdicts  # noqa: E402


def write_lines(path, lines):
    """The report as a whole or not at all (temporary file, then rename)."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines))
    os.replace(tmp, path)


def fmt(v, digits=3):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "—"
    if v == 0:
        return "0"
    a = abs(v)
    if 1e-3 <= a < 1e4:
        return f"{v:.{digits}g}"
    return f"{v:.{digits - 1}e}"


def error_bar(se, n):
    """Whether an error (SE, bootstrap SE, interval) may be printed: a finite SE > 0 from at least
    verdicts.MIN_SAMPLES samples — never from fewer, whatever the input holds, and never "± 0": no spread
    is no error bar (verdicts.compare)."""
    return verdicts.unusable(0.0, se, n) is None and se > 0


def enough_samples(n):
    """Whether n samples may carry an error bar, an interval or a verdict: at least verdicts.MIN_SAMPLES."""
    return verdicts.unusable(0.0, 0.0, n) is None


def n_text(n):
    return f"{n:g}" if isinstance(n, (int, float)) and not isinstance(n, bool) and math.isfinite(n) else "?"


def censored(stat):
    """Why a statistic of a state that some runs stopped before (φ_2, no tagged bud left) has no value, or None:
    `budjam analyse` keeps such a statistic only where every run of the group reached the state."""
    c = (stat or {}).get("censored")
    if not c:
        return None
    n = stat.get("n") or 0
    return f"not measured: {n} of {n + c} runs reached this state, the others stopped first (right-censored)"


def pm(stat, key="mean"):
    """'x ± se (n)' from a {mean|median, se, n} object (no ± from fewer than 5 samples). A statistic over values
    that come in seeds (the targets of runs; `budjam analyse` counts them in "values" or "targets") has n = seeds,
    the independent samples, and says how many values they hold."""
    if censored(stat):
        return censored(stat)
    if not stat or stat.get(key) is None:
        return "not measured"
    s = fmt(stat[key])
    if error_bar(stat.get("se"), stat.get("n")):
        s += " ± " + fmt(stat["se"], 2)
    held = next((f" seeds, {stat[k]} {k}" for k in ("values", "targets") if stat.get(k) is not None), "")
    return s + f" (n={n_text(stat.get('n'))}{held})"


def isostatic_text(iso):
    """The packings at jamming counted: ΔZ_J N_nr/2 is a whole number of contacts."""
    if not iso or not iso.get("packings"):
        return "isostatic packings not counted"
    k, n, most = iso["isostatic"], iso["packings"], iso.get("most_excess_contacts", 0)
    return (f"{k} of {n} packings isostatic (ΔZ_J N_nr/2 = 0 contacts)" +
            (f", the others off by up to {abs(most)} {'contact' if abs(most) == 1 else 'contacts'} "
             f"({'more' if most > 0 else 'fewer'})" if k < n else ""))


def isostatic_verdict(iso):
    """ΔZ_J ≈ 0 claims a jamming point isostatic: the fraction of isostatic packings judged against 1 by the
    proportion rule. A z-score of the mean ΔZ_J is no test: with k packings off and the rest at 0 it is √k,
    whatever their excess."""
    if not iso or not iso.get("packings"):
        return verdicts.Verdict("inconclusive", "isostatic packings not counted")
    # the independent samples: the packings, at most one per seed (a seed's runs share their growth)
    n = min(iso["packings"], iso.get("seeds", iso["packings"]))
    return verdicts.proportion(iso["isostatic"] / iso["packings"], n, verdicts.interval(1.0, 1.0),
                               n_paper=verdicts.THEORY)


def growth_bulk(stat):
    """(statistic, text, value) of the B_grow = λ_c B_ext test: log₁₀ of the median ratio ± bootstrap SE over seeds
    (n seeds and their targets, B_grow ≤ 0 counted); an analysis.json of version ≤ 2 has the mean of
    log₁₀ B_grow/(λ_c B) instead, one of version 3 targets as n."""
    if stat.get("median") is None and stat.get("mean") is not None:
        return "⟨log₁₀ B_grow/(λ_c B)⟩", pm(stat), stat["mean"]
    s = pm(stat, "median")
    if stat.get("nonpositive_B_grow") is not None:
        s = s[:-1] + f", {stat['nonpositive_B_grow']} with B_grow ≤ 0)"
    return "log₁₀ median B_grow/(λ_c B)", s, stat.get("median")


DEPLETION_SIZE_COLUMNS = [("dphi_2", "Δφ_2, every run"), ("dphi_2_paper", "Δφ_2, paper's selection"),
                          ("dphi_2_none_left", "Δφ at none left"), ("N_div_2_over_N_J", "N_div(φ_2)/N_J (median)"),
                          ("G_2_over_Pmax", "G_2/P_max (median), every run"),
                          ("G_2_over_Pmax_paper", "G_2/P_max (median), paper's selection")]
JAMMING_SIZE_COLUMNS = [("u_J", "u_J (buds)"), ("u_J_lobes", "u_J (lobes)"), ("phi_J", "φ_J"), ("Z_J", "Z_J"),
                        ("rattler_fraction", "rattler fraction")]


def cell_pm(c):
    return pm({"mean": c.get("value"), "se": c.get("se"), "n": c.get("n"), "censored": c.get("censored")})


def limit_text(x):
    if x.get("limit") is None:
        return "— (" + x.get("why", "not fitted") + ")"
    if not error_bar(x.get("limit_se"), x.get("sizes")):
        return f"— (a fit over {n_text(x.get('sizes'))} sizes: it needs {verdicts.MIN_SAMPLES})"
    res = ", ".join(f"{r:+.1f}" for r in x.get("residuals_in_se", []))
    fit = f"χ²/dof = {fmt(x.get('chi2'), 2)}/{x.get('dof')}"
    if verdicts.fit_rejected(x.get("chi2"), x.get("dof")):
        # q_∞ of a form the data reject is no N → ∞ value, however small its (widened) error
        return (f"model rejected ({fit}; χ² > {fmt(verdicts.chi2_quantile(x['dof']))}, its 95 % quantile at "
                f"{x['dof']} dof; residuals/SE {res})")
    return f"{fmt(x['limit'])} ± {fmt(x['limit_se'], 2)} ({fit}; residuals/SE {res})"


def n_J_limit_text(J):
    """How n_J,∞ was made: the growth-only density over one period of its generation phase (or, from an
    analysis.json before that, in one box at φ_J,∞) times the fitted non-rattler fraction 1 − r_∞."""
    nl = J.get("n_J_limit") or {}
    sides = nl.get("growth_only_L")
    if isinstance(sides, list):
        return (f"n_J,∞ is the growth-only density averaged over {nl.get('growth_only_boxes')} boxes of side "
                f"{fmt(sides[0])} – {fmt(sides[1])} (one period of the phase at which a box catches a generation of "
                f"divisions) at the ⟨φ_J⟩ of the largest size, times the fitted non-rattler fraction 1 − r_∞; its error "
                f"holds the swing over that phase (± {fmt(nl.get('phase_swing'), 2)} from box to box).")
    return (f"n_J,∞ is the growth-only density in a box of side {fmt(sides)} at φ_J,∞ times the fitted non-rattler "
            "fraction 1 − r_∞ (one box: the swing of the density with the box's phase is not in its error).")


def jamming_size_rows(J, source):
    """The finite-size table of the jamming ensembles (independent seeds per size)."""
    if not J:
        return []
    head = ("| L | runs | N_J | N_J/L² | growth alone | difference/σ | n_J | " +
            " | ".join(t for _, t in JAMMING_SIZE_COLUMNS) + " |")
    rows = ["", "## Finite size at jamming", "",
            f"The jamming states of {source}. " + sizes_independence_text([J]) +
            " The cell density N_J/L² is compared with what the growth "
            "and division rules alone give at the same φ (400 growth histories per size, no mechanics): N/L² at fixed "
            "φ is not monotone in L, so it is not fitted. The other quantities are fitted by q(N) = q_∞ + c/N (weighted "
            "least squares, errors widened by √(χ²/dof) when it exceeds 1) where five sizes or more have an error bar; "
            "χ²/dof and the residuals per size (in SE, smallest L first) test that form. " + n_J_limit_text(J), "",
            head, "|" + " --- |" * (len(JAMMING_SIZE_COLUMNS) + 7)]
    for r in J["sizes"]:
        g = r.get("growth_only_cells_per_area", {})
        cells = [cell_pm(r[k]) for k, _ in JAMMING_SIZE_COLUMNS]
        rows.append(f"| {r['L']:g} | {r['runs']} | {fmt(r['N_J']['mean'])} | {cell_pm(r['cells_per_area'])} | "
                    f"{fmt(g.get('value'))}{' ± ' + fmt(g['se'], 2) if error_bar(g.get('se'), g.get('n')) else ''} | "
                    f"{fmt(r.get('cells_per_area_minus_growth_only_in_se'), 2)} | "
                    f"{cell_pm(r['n_J'])} | " + " | ".join(cells) + " |")
    nl, r = J.get("n_J_limit"), J["extrapolation"].get("rattler_fraction", {})
    if verdicts.fit_rejected(r.get("chi2"), r.get("dof")):
        n_J_inf = "— (the rattler fraction's fit is rejected: no 1 − r_∞)"
    elif nl and error_bar(nl.get("se"), r.get("sizes")):
        n_J_inf = f"{fmt(nl['value'])} ± {fmt(nl['se'], 2)}"
    else:
        n_J_inf = "—"
    rows.append("| N → ∞ | | | | | | " + n_J_inf + " | " +
                " | ".join(limit_text(J["extrapolation"][k]) for k, _ in JAMMING_SIZE_COLUMNS) + " |")
    return rows


def sizes_independence_text(entries):
    """Whether the sizes of the finite-size entries are independent samples, as analysis.json counts the seeds
    grown at more than one size (a run's random stream does not depend on L)."""
    shared = [e.get("seeds_shared") for e in entries]
    if not shared:
        return ""  # one size
    if any(not isinstance(x, int) for x in shared):
        return "Whether the sizes share seeds this analysis.json does not say (an earlier version)."
    if max(shared) == 0:
        return "Each size grows seeds of its own, so the sizes are independent samples."
    return (f"{max(shared)} seeds are grown at more than one size, and a run's random stream does not depend on L, so "
            "the sizes are not independent samples.")


def depletion_size_rows(entries):
    """Per box size and feedback strength, the depletion-point quantities of the paper's grid."""
    if not entries:
        return []
    head = "| L | runs | N_J | " + " | ".join(t for _, t in DEPLETION_SIZE_COLUMNS) + " |"
    rows = ["", "## Finite size at the depletion point", "",
            "Per box size and feedback strength. " + sizes_independence_text(entries) + " q_∞ + c/N is fitted only "
            "with five sizes or more, no seed grown at two of them (three sizes leave one degree of freedom and cannot "
            "test the form).", ""]
    for e in entries:
        rows += [f"P0 = {e['P0_label']}:", "", head, "|" + " --- |" * (len(DEPLETION_SIZE_COLUMNS) + 3)]
        for r in e["sizes"]:
            cells = [cell_pm(r[k]) for k, _ in DEPLETION_SIZE_COLUMNS]
            rows.append(f"| {r['L']:g} | {r['runs']} | {fmt(r['N_J']['mean'])} | " + " | ".join(cells) + " |")
        rows += ["| N → ∞ | | | " + " | ".join(limit_text(e["extrapolation"][k]) for k, _ in DEPLETION_SIZE_COLUMNS)
                 + " |", ""]
    return rows


def ci(stat):
    """'median ± bootstrap SE [95% CI lo, hi] (n)' (no SE or interval from fewer than 5 samples)."""
    if censored(stat):
        return censored(stat)
    if not stat or stat.get("median") is None:
        return "not measured"
    lo, hi = stat.get("ci95") or (None, None)
    n = stat.get("n")
    if not enough_samples(n):
        return f"{fmt(stat['median'])} (n={n_text(n)}, no interval below {verdicts.MIN_SAMPLES})"
    se = stat.get("se")
    s = fmt(stat["median"]) + (f" ± {fmt(se, 2)}" if error_bar(se, n) else "")
    if lo is None or hi is None:
        return f"{s} (n={n_text(n)}, no interval)"
    return f"{s} [95% CI {fmt(lo)}, {fmt(hi)}] (n={n_text(n)})"


def paper_cells_text(cells, measured, predicted):
    """The paper's figure of an identity: per (P0, Δφ) cell the means of both sides ± SE, no test. Summarised by how
    many cells' means lie more than 2 combined SE apart (about 1 in 20 by chance where the identity holds)."""
    if not cells or not cells.get("cells"):
        return "not measured"
    return (f"the paper plots per (P0, Δφ) ⟨{measured}⟩ against ⟨{predicted}⟩ ± SE over seeds, with no test: the two "
            f"means lie more than 2 combined SE apart in {cells['cells_apart_2se']} of {cells['cells_tested']} cells "
            f"with ≥ {verdicts.MIN_SAMPLES} runs (about 1 in 20 by chance where the identity holds)")


def effective_n(p, se, n, seeds):
    """The packings a fraction p of n packings is worth when they come in seeds: Kish's effective sample size
    p(1 − p)/se² from the SE by seed (at most n). Where p is 0 or 1 the SE by seed is 0 whatever the
    sample, so it says nothing: then the seeds are the independent samples. Otherwise an SE of 0 (every seed
    the same fraction) bounds nothing: n. None without an SE by seed."""
    if not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in (p, se, n, seeds)):
        return None
    if se <= 0:
        return min(n, seeds) if p in (0, 1) else n
    return min(n, p * (1 - p) / (se * se))


PAPER_P0_LABELS = {1e-1: "0.1", 1e-2: "0.01", 1e-3: "0.001", 1e-4: "0.0001", 1e-5: "1e-05"}  # the paper's grid
PAPER_SEEDS = 20  # the paper's seeds per point (docs/model.md, "Reference parameters")
PAPER_L_JAMMING = 15    # the box of the paper's u_J and n_J
PAPER_L_DIVISIONS = 20  # the box of the paper's N_div medians
PAPER_L_MAIN = 15       # the box of the paper's other numbers (h_γ, the Π(g) weights)
PAPER_SIZES = (8, 15, 20)
# The paper's Δφ targets per feedback strength (Makefile.analysis, PRESET=paper)
_PAPER_WIDE = (1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 6e-2, 0.1, 0.12)
PAPER_TARGETS = {"none": _PAPER_WIDE, "0.1": _PAPER_WIDE, "0.01": _PAPER_WIDE, "0.001": _PAPER_WIDE[:7],
                 "0.0001": _PAPER_WIDE[:7], "1e-05": _PAPER_WIDE[:6]}


def size_mismatch(have, paper_L):
    """The verdict on a number the paper gives for a box of side paper_L when budjam's value is from other
    boxes (`have`: one L or several), else None. u_J, n_J, N_div and the weight of g = 1 move with L by more than
    their errors (docs/analysis.md, "Finite size"), so a value from another box does not test the number, whatever
    z."""
    sizes = sorted(have) if isinstance(have, (list, tuple, set)) else [have]
    if paper_L in sizes:
        return None
    return verdicts.Verdict("inconclusive", f"L = {', '.join(f'{l:g}' for l in sizes)}, the paper's number is "
                                            f"for L = {paper_L:g}")


def by_seed(stat):
    """A mean over jamming states whose runs share seeds, with the seeds as its samples: SE the bootstrap
    over seeds, n the seeds (analysis.json from version 6 on says how many; before, the stat as written)."""
    if not stat or stat.get("seeds") is None:
        return stat
    return {**stat, "se": stat.get("bootstrap_se_by_seed"), "n": stat["seeds"]}


def paper_n(n, seeds):
    """The paper's number of samples for a statistic of n samples from budjam's `seeds` seeds per point:
    the paper ran the same protocol on PAPER_SEEDS seeds, so n · PAPER_SEEDS / seeds (n when seeds = 20)."""
    ok = all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and x > 0 for x in (n, seeds))
    return n * PAPER_SEEDS / seeds if ok else None


def paper_grid_departures(groups_at, label, targets_csv):
    """How a grid departs from the paper's (sizes, feedback strengths, 20 seeds per point, the Δφ targets reached
    per P0); empty when it is the paper's."""
    out = []
    if sorted(groups_at) != sorted(PAPER_SIZES):
        out.append("L = " + ", ".join(f"{x:g}" for x in sorted(groups_at)))
    for L_, g in sorted(groups_at.items()):
        missing = [l for l in PAPER_TARGETS if l not in g]
        extra = sorted(l for l in g if l not in PAPER_TARGETS)
        if missing:
            out.append(f"no runs at L = {L_:g} for P0 = " + ", ".join(missing))
        if extra:
            out.append(f"P0 = {', '.join(extra)} at L = {L_:g}, outside the paper's grid")
    if any(g_.get("runs") != PAPER_SEEDS for g in groups_at.values() for g_ in g.values()):
        out.append(f"not {PAPER_SEEDS} runs at every point")
    reached = {}
    if os.path.exists(targets_csv):
        with open(targets_csv, newline="", encoding="utf-8") as f:
            for r in csv.DictReader(f):
                if r["dphi"]:
                    p0 = label(float(r["P0"]) if r["P0"] else None)
                    reached.setdefault(p0, set()).add(float(r["dphi"]))
    if any(sorted(reached.get(l, ())) != sorted(t) for l, t in PAPER_TARGETS.items()):
        out.append("other Δφ targets")
    return out


def judged(stat, claim, key="mean", n_paper=None, seeds=None):
    """The verdict of the one rule (scripts/verdicts.py) on a {mean|median, se, n} statistic; the paper's
    sample is n_paper, or for a statistic of the grid that budjam grew with `seeds` seeds per point,
    paper_n(n, seeds)."""
    if censored(stat):
        return verdicts.Verdict("inconclusive", censored(stat))
    if not stat or stat.get(key) is None:
        return verdicts.Verdict("inconclusive", "not measured")
    if n_paper is None and seeds is not None:
        n_paper = paper_n(stat.get("n"), seeds)
    return verdicts.compare(stat[key], stat.get("se"), stat.get("n"), claim, n_paper)


def trend_of(stats, increasing, key="mean"):
    """The trend over groups: paired by seed when every group has its values by seed (analysis.json from
    version 7 on; the groups of a grid share their seeds), else each group with its SE."""
    if stats and all(s and isinstance(s.get("by_seed"), dict) for s in stats):
        return verdicts.paired_trend([s["by_seed"] for s in stats], increasing, statistic=key)
    return verdicts.trend([(s.get(key) if s else None, s.get("se") if s else None, s.get("n") if s else 0)
                           for s in stats], increasing)


def all_of(vs, noun="groups", pooled=None):
    """One verdict for a claim tested in several groups (`noun`): not confirmed if any test is, confirmed if
    all are. `pooled`: the verdict on the value pooled over the groups, tested beside them; it is named
    apart and not counted as a group."""
    words = [v.word for v in vs]
    every = words + ([pooled.word] if pooled is not None else [])
    head = f"pooled value {pooled.word}; " if pooled is not None else ""
    if "not confirmed" in every:
        return verdicts.Verdict("not confirmed", head + f"{words.count('not confirmed')} of {len(vs)} {noun} not confirmed")
    if all(w == "confirmed" for w in every):
        return verdicts.Verdict("confirmed", head + f"all {len(vs)} {noun} confirmed")
    return verdicts.Verdict("inconclusive", head + f"{words.count('inconclusive')} of {len(vs)} {noun} without a verdict")


def shear_note(bins):
    """Not a claim of the paper: why some measured G are negative (docs/moduli.md, "Shear stability")."""
    return [
        "",
        "**Negative shear moduli are physics, not a solver failure.** A packing jammed in a box of fixed shape "
        "is stable at that box (positive-definite Hessian) but can have a negative modulus for some simple shear "
        "of the box, G_min = min_φ (1/A) d²U/dγ_φ² < 0; finite Lees–Edwards strains relaxed with FIRE confirm "
        "the linear response on such packings (`budjam moduli --check`). Small packings at low P N² are often "
        "unstable in this sense (Dagois-Bohy et al., PRL 109, 095703 (2012)); the fraction falls as P N² grows. "
        "Every statistic above keeps these packings except the paper's selection (G_2 > 0); the G_2 rows are medians, "
        "as in the paper.",
        "",
        "| P N_J² | packings (targets and φ_2, all P0) | fraction with G_min < 0 |",
        "| --- | --- | --- |",
    ] + [f"| {fmt(b['PN2_lo'])} – {fmt(b['PN2_hi'])} | {b['packings']} | {fmt(b['fraction'])} |" for b in bins]


def survival_text(name, surv):
    """One P0's Kaplan–Meier summary: a_ε, ∫S and the completions and censorings behind them."""
    events, records = surv.get("events"), surv.get("records")
    if not records:  # no tagged bud's record (no survival.csv, or no run of the group depleted)
        return f"{name}: not measured (no survival records)"
    censored = records - events if events is not None and records is not None else None
    return (f"{name}: a_ε = {fmt(surv.get('a_eps'))}, ∫S = {fmt(surv.get('integral_S'))}, ε = {fmt(surv.get('epsilon'))} "
            f"({events} completions, {censored} censored)")


def p0_name(label):
    return "no feedback" if label == "none" else f"P0={label}"


def not_finished_text(entries):
    """Runs that stopped early ("runs/<preset>/L8/P0_1e-3/seed4 (step_limit)"): listed when few, else
    counted per system size, P0 and status."""
    if len(entries) <= 8:
        return "; ".join(entries)
    groups = {}
    for e in entries:
        path, _, status = e.partition(" (")
        parts = path.split("/")
        key = (parts[-3], parts[-2].removeprefix("P0_"), status.rstrip(")"))
        groups[key] = groups.get(key, 0) + 1
    return "; ".join(f"{L} P0={p0}: {n} {status}" for (L, p0, status), n in groups.items())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tables", required=True)
    ap.add_argument("--figures", required=True)
    ap.add_argument("--preset", required=True)
    ap.add_argument("--moduli", default="1")
    ap.add_argument("--dos", default="1")
    ap.add_argument("--jamming", help="tables of the jamming ensembles (`make -f Makefile.analysis PRESET=jamming analysis`); "
                                      "without them the jamming rows use the preset's own runs")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    with open(os.path.join(a.tables, "analysis.json")) as f:
        A = json.load(f)
    AJ = None
    if a.jamming:
        path = os.path.join(a.jamming, "analysis.json")
        if not os.path.isfile(path):
            sys.exit(f"report.py: --jamming {a.jamming}: no analysis.json there "
                     "(make -f Makefile.analysis -j2 PRESET=jamming analysis writes one)")
        with open(path) as f:
            AJ = json.load(f)
    # The jamming rows come from the ensemble only if its runs are of the jamming model of these runs (the keys that
    # set which jamming points a run reaches: cells, initial state, Δt, ε_U, the minimum check; `budjam analyse`
    # writes their hashes), else from these runs.
    jam_refused = None
    if AJ is not None:
        own, theirs = set(A.get("jamming_models") or []), set(AJ.get("jamming_models") or [])
        if not own or not theirs:
            jam_refused = (f"the jamming ensemble of {a.jamming} is not used: tables without jamming_model cannot show "
                           "that it is of these runs' model (cells, initial state, Δt, ε_U, minimum check)")
        elif len(own) > 1:
            jam_refused = (f"the jamming ensemble of {a.jamming} is not used: these runs are of {len(own)} jamming models "
                           "(cells, initial state, Δt, ε_U, minimum check)")
        elif own != theirs:
            jam_refused = (f"the jamming ensemble of {a.jamming} is not used: its runs are of another jamming model "
                           "(cells, initial state, Δt, ε_U or the minimum check differ)")
        if jam_refused:
            AJ = None
    U = A.get("unavailable", {})

    def lacking(*keys):
        """What the inputs of a cell need that the stored tables lack (analysis.json "unavailable"), or None."""
        for k in keys:
            if k in U:
                why = U[k]
                return "needs " + why.split("(it needs ")[1].rstrip(")") if "(it needs " in why else why
        return None

    def avail(text, *keys):
        need = lacking(*keys)
        return text if need is None else f"unavailable from the stored tables: {need}"

    L = A["main_L"]
    M = A["main"]
    C = A["constants"]

    # keyed by the label a reader expects ("none", "0.1", ..., "1e-05"), whatever budjam printed
    def label(p0):
        return "none" if p0 is None else PAPER_P0_LABELS.get(p0, repr(p0))
    groups_at = {}
    for g_ in A["groups"]:
        groups_at.setdefault(g_["L"], {})[label(g_["P0"])] = g_
    groups = groups_at.get(L, {})
    have_moduli = a.moduli == "1" and A["inputs"]["moduli_files"] > 0
    have_dos = a.dos == "1" and A["inputs"]["dos_files"] > 0
    figdir = os.path.relpath(a.figures, os.path.dirname(os.path.abspath(a.out)) or ".")

    def fig(name):
        path = os.path.join(a.figures, name + ".png")
        if os.path.exists(path):
            return f"[{name}]({figdir}/{name}.png)"
        try:  # figures.py --record-not-drawn says why
            with open(os.path.join(a.figures, name + ".not-drawn"), encoding="utf-8") as f:
                return f"{name} (not drawn: {f.read().strip()})"
        except OSError:
            return f"{name} (not drawn)"

    rows = []
    verdict_list = []

    def claim(text, paper, ours, theirs, verdict, figure):
        """A row; `verdict` is a verdicts.Verdict, or a plain text where the paper makes no claim to test."""
        if isinstance(verdict, verdicts.Verdict):
            verdict_list.append((text, verdict.word))
        rows.append(f"| {text} | {paper} | {ours} | {theirs} | {verdict} | {figure} |")

    def sel(stat, key="mean"):
        """'x ± se (n of runs)' of a statistic under the paper's selection."""
        if not stat or stat.get(key) is None:
            if not stat:
                return "not measured"
            admitted, runs = stat.get("admitted", 0), stat.get("runs", "?")
            if not admitted:
                return f"not measured ({admitted} of {runs} runs admitted)"
            if stat.get("predicted") == 0:  # the paper's φ_2 summary keeps the runs with an Eq. 14 prediction
                return f"not measured: {admitted} of {runs} runs admitted, none with an Eq. 14 prediction"
            # admitted runs without a value: for G_2, each had G_2 ≤ 0 or none (the paper keeps G_2 > 0 only)
            return f"not measured: {admitted} of {runs} runs admitted, none with a value kept (G_2 > 0 for G_2)"
        se, n = stat.get("se"), stat.get("n")
        # the φ_2 summary keeps the admitted runs with an Eq. 14 prediction
        predicted = f", {stat['predicted']} with a prediction" if stat.get("predicted") not in (None, stat.get("admitted")) else ""
        return (fmt(stat[key]) + (f" ± {fmt(se, 2)}" if error_bar(se, n) else "") +
                f" (n={n_text(n)}; {stat.get('admitted', '?')} of {stat.get('runs', '?')} runs admitted{predicted})")

    # Every group, from the weakest feedback (none, then the largest P0) to the strongest: the trends are
    # claims about feedback strength and take every group. A P0 the paper did not run has no number of
    # the paper to test, so its rows show budjam's values with no verdict of their own.
    order = sorted(groups, key=lambda l: math.inf if l == "none" else float(l), reverse=True)
    unpaired = [l for l in order if l != "none" and l not in PAPER_P0_LABELS.values()]

    def outside_grid(lab):
        return "— (P0 outside the paper's grid: no number of the paper to test)" if lab in unpaired else None
    fed = [l for l in order if l != "none"]

    # Seeds per point of this preset's grid: the paper's sample of a grid statistic is paper_n(n, seeds).
    def seeds_in(g_):
        return g_.get("runs") if g_ else None

    grid_seeds = sorted({seeds_in(groups[l]) for l in order if seeds_in(groups[l])})
    # The pooled statistics of the main box are clustered by seed over its groups (n = the distinct seeds;
    # the presets, like the paper, grow seeds 1 … S at every point), so the paper's sample of one is
    # paper_n(n, S) with S the largest group, not the mean runs per group, which unequal groups lower.
    main_seeds = max(grid_seeds) if grid_seeds else None
    # ---- jamming: the jamming ensembles at the paper's L = 15 (independent seeds), else this preset ----
    jam_L = PAPER_L_JAMMING
    jam = next((s_ for s_ in (AJ or {}).get("sizes", []) if s_["L"] == jam_L), None)
    if jam is not None:
        # a jamming-only ensemble has one state per seed; states that share seeds are judged by seed
        shared = any((jam.get(k) or {}).get("seeds") not in (None, (jam.get(k) or {}).get("n"))
                     for k in ("u_J", "u_J_lobes", "n_J", "N_J", "phi_J"))
        if shared:
            jam = {**jam, **{k: by_seed(jam.get(k)) for k in ("u_J", "u_J_lobes", "n_J", "N_J", "phi_J")}}
        jam_src = f"jamming ensemble, L = {jam_L}, " + ("errors by seed" if shared else "independent seeds")
        dzj = jam.get("dZ_J")
    else:
        # a seed's runs share their growth up to the first jamming, so its jamming states are one sample
        jam, jam_L = {**M, **{k: by_seed(M.get(k)) for k in ("u_J", "u_J_lobes", "n_J", "N_J", "phi_J", "dZ_J")}}, L
        why = jam_refused or (f"the jamming ensemble of {a.jamming} has no L = {PAPER_L_JAMMING:g}" if AJ
                              else "no jamming ensemble given")
        jam_src = f"this preset's runs at L = {L:g} ({why}; errors by seed)"
        dzj = jam.get("dZ_J")
    iso = jam.get("isostatic_J")
    # The finite-size table at jamming: the ensemble's where it is used, else this preset's own.
    fs_jamming = (AJ if AJ and AJ.get("finite_size_jamming") else A).get("finite_size_jamming")
    fs_jamming_src = ("the jamming ensemble, independent seeds" if AJ and AJ.get("finite_size_jamming") else
                      f"this preset's runs ({jam_refused or 'no jamming ensemble given'}; one state per seed)")
    claim("Unconstrained fraction at jamming u_J (L = 15 in the paper)", "≃ 0.23",
          f"{pm(jam['u_J'])}; contact-free buds / N_nr ({jam_src}); lobes, mothers included: {pm(jam['u_J_lobes'])}",
          "same: the paper's u_J counts the buds free at jamming over N_nr",
          size_mismatch(jam_L, PAPER_L_JAMMING) or
          judged(jam["u_J"], verdicts.quoted(0.23, 0.01), n_paper=PAPER_SEEDS), "—")
    uw = C["u_J_lambert_w"]
    claim("Mean-field u_J = −W₀(−2e⁻²)/2 (Eq. A10)", "≈ 0.20", fmt(uw, 4) + " (computed, exact)", "same",
          "— (computed exactly, no error bar: " + ("rounds" if round(uw, 2) == 0.20 else "does not round") + " to 0.20)",
          "—")
    claim("Nonrattler density at jamming n_J", "≃ 0.775", f"{pm(jam['n_J'])} ({jam_src})", "same",
          size_mismatch(jam_L, PAPER_L_JAMMING) or
          judged(jam["n_J"], verdicts.quoted(0.775, 0.001), n_paper=PAPER_SEEDS), "—")
    claim("Cells at jamming N_J", "—", f"{pm(jam['N_J'])} ({jam_src}); N_J/L² against the growth process alone: " +
          ("see \"Finite size at jamming\"" if fs_jamming else "not compared (no finite-size table at jamming)"),
          "same", "—", "—")
    claim("Jamming packing fraction φ_J", "—", f"{pm(jam['phi_J'])} ({jam_src})", "same", "—", "—")
    phi_J = jam["phi_J"]
    pmax = {"mean": None if phi_J.get("mean") is None else 2 / math.pi * (1 - phi_J["mean"]),
            "se": None if phi_J.get("se") is None else 2 / math.pi * phi_J["se"], "n": phi_J.get("n")}
    claim("Confluence pressure P_max = (2/π)(1 − φ_J) (Eq. D25, φ_J = 0.84)", "≈ 0.1",
          f"{fmt(C['P_max_formula_phiJ_0.84'])} (φ_J=0.84); {pm(pmax)} with the measured φ_J", "same",
          judged(pmax, verdicts.quoted(0.1, 0.1), n_paper=PAPER_SEEDS), "—")
    claim("Modified Maxwell count at jamming: ΔZ_J = Z_J − Z_iso(u_J) ≈ 0 (Eqs. 3, 5)", "marginal",
          f"{pm(dzj)} ({jam_src}); {isostatic_text(iso)}", "same", isostatic_verdict(iso), "—")
    ident = M["dZ_identity"]
    unrep = ident.get("per_P0_unrepopulated_by_run", [])
    vs = [judged(x, verdicts.quoted(0.0, 0.0), n_paper=verdicts.THEORY) for x in unrep]
    none_runs = seeds_in(groups.get("none"))
    no_test = ("no no-feedback runs at this L, whose means per target are the branch ΔZ₀(P)" if not none_runs else
               f"{none_runs} no-feedback runs, fewer than the {verdicts.MIN_SAMPLES} the branch ΔZ₀(P) is the mean of"
               if none_runs < verdicts.MIN_SAMPLES else "no feedback runs with ≤ 10 divisions after φ_J at a target"
               if fed else "no feedback runs")
    claim("ΔZ = ΔZ₀(P) + 2(u_J − u) over (P0, Δφ) (Eq. 6)", "holds within finite-size scatter",
          "residual over every target, no-feedback runs included: " + pm(ident["all_targets"]) +
          f", RMS {fmt(ident['all_targets'].get('rms'))}; the verdict's test: mean residual per run over the targets with ≤ 10 divisions after φ_J (the identity assumes no "
          "repopulation), feedback runs, per P0 (± is the SE over runs and that of the no-feedback branch ΔZ₀(P), which "
          "every run shares, in quadrature): " +
          ("; ".join(f"P0={label(x['P0'])} {pm(x)} → {v.word}" for x, v in zip(unrep, vs)) or
           f"not measured ({no_test})"),
          paper_cells_text(ident.get("paper_cells"), "ΔZ", "ΔZ₀(P) + 2(u_J − u)") +
          " (its ingredients: ΔZ₀(P) through the no-feedback targets' means, u_J the buds tagged at jamming over the "
          "target's N_nr, u the contact-free lobes; its single-pass rattler rule and contacts with rattlers in N_c "
          "are not in the tables)",
          all_of(vs, "P0 groups") if vs else verdicts.Verdict("inconclusive", f"not measured: {no_test}"), fig("fig2"))
    # A feedback strength of the paper's grid with no runs at the main L: its per-P0 claims are not
    # measured, said once per group instead of leaving its rows out.
    for lab in (l for l in PAPER_TARGETS if l not in groups):
        why = f"not measured: no runs at {p0_name(lab)}, L = {L:g} in the tables"
        claim(f"Every per-P0 claim at {p0_name(lab)} (Eq. 14; P_2/P_max and λ̄_c; G_2/P_max; G_2/P_2; N_div; h_γ; "
              "Π(g)); the trends are tested without it", "the paper's grid", why, "same",
              verdicts.Verdict("inconclusive", why), "—")
    # ---- depletion ----
    def ratio_text(pred, sim):
        p_, s_ = (pred or {}).get("mean"), (sim or {}).get("mean")
        return f"; prediction/simulation {fmt(p_ / s_)}" if p_ is not None and s_ else ""

    for lab in order:
        x = groups[lab]
        # The paper's "small systematic overestimate" gives "small" no size: the sign is what can be tested,
        # and the ratio of the means shows the size beside it.
        eq14 = judged(x["dphi_2_pred_minus_sim_paper"], verdicts.at_least(0.0), seeds=seeds_in(x))
        eq14 = verdicts.Verdict(eq14.word, eq14.why + "; the sign is tested, the paper gives \"small\" no size")
        claim(f"φ_2 − φ_J, {p0_name(lab)}: simulation vs Eq. 14", "a small systematic overestimate by the theory",
              f"{pm(x['dphi_2'])} vs {avail(pm(x['dphi_2_pred_area']), 'dphi_2_pred_area')} (a as true area); "
              f"prediction − simulation run by run {avail(pm(x.get('dphi_2_pred_minus_sim_area')), 'dphi_2_pred_area')}"
              f"{ratio_text(x.get('dphi_2_pred_area'), x['dphi_2'])}; every run",
              avail(f"{sel(x['dphi_2_paper'])} vs {pm(x['dphi_2_pred_paper'])} (a as diameter², the paper's measure; "
                    f"φ_J and φ_2 from the first jamming); prediction − simulation "
                    f"{sel(x['dphi_2_pred_minus_sim_paper'])}{ratio_text(x['dphi_2_pred_paper'], x['dphi_2_paper'])}",
                    "dphi_2_pred_paper", "dphi_2_first"),
              outside_grid(lab) or eq14, fig("fig2"))
    claim("Stronger feedback moves φ_2 closer to φ_J", "monotone",
          ", ".join(f"{p0_name(l)} {fmt(groups[l]['dphi_2']['mean'])}" for l in order),
          avail(", ".join(f"{p0_name(l)} {fmt(groups[l]['dphi_2_paper']['mean'])}" for l in order) +
                f" (the trend is tested over {len(order)} group{'s' if len(order) != 1 else ''}, from the weakest "
                "feedback to the strongest)",
                "dphi_2_pred_paper"),
          trend_of([groups[l]["dphi_2_paper"] for l in order], increasing=False), fig("fig2"))
    claim("Kaplan–Meier a_ε and ∫₀^{a_ε} S da per P0 (each P0's runs pooled, diameter²)", "—",
          "; ".join(survival_text(p0_name(l), groups[l].get("pooled_survival") or {}) for l in order),
          "per run, never pooled: each run's curve up to S ≤ 1/(its tagged buds), as runs.csv a_eps and integral_S; "
          "mean a_ε over the depleted runs: " + ", ".join(f"{p0_name(l)} {pm(groups[l].get('a_eps'))}" for l in order),
          "—", fig("figS"))
    # ---- mechanics ----
    bg_name, bg_text, bg = growth_bulk(M["B_grow_over_lambda_B_log10"])
    if have_moduli and bg is not None:
        per = {l: groups[l].get("B_grow_over_lambda_B_log10", {}) for l in order}
        pooled = judged(M["B_grow_over_lambda_B_log10"], verdicts.quoted(0.0, 0.0), key="median",
                        n_paper=verdicts.THEORY)
        vs = [judged(per[l], verdicts.quoted(0.0, 0.0), key="median", n_paper=verdicts.THEORY) for l in order]
        claim("B_grow = λ_c B_ext (Eq. 20)", "holds over (P0, Δφ)",
              f"{bg_name} = {bg_text} over the targets with λ_c B > 0, error by seed (the verdict's test); per P0: " +
              ", ".join(f"{p0_name(l)} {pm(per[l], 'median')}" for l in order),
              paper_cells_text(M["B_grow_over_lambda_B_log10"].get("paper_cells"), "B_grow", "λ_c B_ext") +
              " (its λ_c with u the contact-free lobes)",
              all_of(vs, "P0 groups", pooled=pooled), fig("fig3"))
    else:
        claim("B_grow = λ_c B_ext (Eq. 20)", "holds over (P0, Δφ)", "not measured (moduli stage off or unavailable)",
              "same", verdicts.Verdict("inconclusive", "not measured"), fig("fig3"))
    for lab in order:
        x = groups[lab]
        claim(f"P_2/P_max and λ̄_c, {p0_name(lab)}", "decrease strongly with feedback, together",
              f"{pm(x['P_2_over_Pmax'])}; λ̄_c = {avail(pm(x['lambda_bar']), 'lambda_bar')}; every run",
              f"{avail(sel(x['P_2_over_Pmax_paper']), 'dphi_2_pred_paper', 'P_2_first')}; "
              f"λ̄_c = {avail(sel(x['lambda_bar_paper']), 'lambda_bar_lobes')} (u the contact-free lobes)",
              "see trend row", fig("fig3"))
    v2 = trend_of([groups[l]["P_2_over_Pmax_paper"] for l in fed], increasing=False)
    vl = trend_of([groups[l]["lambda_bar_paper"] for l in fed], increasing=False)
    claim("P_2 and λ̄_c fall together with feedback (trend over P0)", "mirrored", "—",
          f"P_2: {v2}; λ̄_c: {vl} (over the feedback groups, paper's selection)", all_of([v2, vl], "trends"), fig("fig3"))
    if "P_dagger" in M:
        claim("P_2 ∝ exp(−P†/P0) (Eq. D19)", "P† = typical bud pressure",
              f"P† = {fmt(M['P_dagger'])}" + (f" ± {fmt(M['P_dagger_se'], 2)}" if error_bar(
                  M.get("P_dagger_se"), M.get("P_dagger_points")) else "") +
              f" (fit over {n_text(M.get('P_dagger_points'))} P0 ≤ 1e-2" +
              ("" if enough_samples(M.get("P_dagger_points")) else f"; no error bar from fewer than "
               f"{verdicts.MIN_SAMPLES}") + ")",
              "same", "—", fig("fig3"))
    for lab in order:
        x = groups[lab]
        s_ = x["G_2_over_Pmax_paper"]
        claim(f"G_2/P_max, {p0_name(lab)} (median ± bootstrap SE)", "≈ 0.2 – 1",
              pm(x["G_2_over_Pmax"], "median") + ", every run" if have_moduli else "not measured (moduli stage off)",
              avail(sel(s_, "median") + " (G_2 > 0 at φ_2 from the first jamming, Tukey fences on G_2)", "G_2_first")
              if have_moduli else "not measured",
              outside_grid(lab) or judged(s_, verdicts.interval(0.2, 1.0), key="median", seeds=seeds_in(x))
              if have_moduli else
              verdicts.Verdict("inconclusive", "not measured"), fig("fig3"))
    claim("Rigidity plateau G_2(0⁺) = n_J k ℓ_c² M₄ u_J (inputs at the strongest P0)", "finite plateau",
          (f"G_2(0⁺)/P_max = {fmt(M.get('G2_plateau_over_Pmax'))} (P0={label(M['plateau_P0'])}, "
           f"ℓ_c² = {fmt(M.get('lc2_J'))})" if M.get("plateau_P0") is not None else
           "not measured: no feedback group in this grid"),
          "same", "—", fig("fig4"))
    for lab in order:
        x = groups[lab]
        claim(f"G_2/P_2, {p0_name(lab)} (median ± bootstrap SE)", "diverges as P0 → 0",
              pm(x["G_2_over_P_2"], "median") + ", every run" if have_moduli else "not measured (moduli stage off)",
              sel(x["G_2_over_P_2_paper"], "median") if have_moduli else "not measured", "see trend row", fig("figD2"))
    claim("G_2/P_2 grows as feedback strengthens (trend over P0)", "diverges as P0 → 0", "—", "paper's selection",
          trend_of([groups[l]["G_2_over_P_2_paper"] for l in order], increasing=True, key="median")
          if have_moduli else verdicts.Verdict("inconclusive", "not measured"), fig("figD2"))
    # ---- divisions: the paper's medians are from L = 20 ----
    paper_div = {"none": (0.081, 0.001), "0.1": (0.071, 0.001), "0.01": (0.053, 0.001), "0.001": (0.013, 0.001),
                 "0.0001": None, "1e-05": None}
    g20 = groups_at.get(PAPER_L_DIVISIONS)
    for lab in order:
        pv = paper_div.get(lab)
        bound = pv is None
        cl = verdicts.at_most(3e-3) if bound else verdicts.quoted(*pv)
        paper = "—" if lab in unpaired else "≲ 3e-3 (L = 20)" if bound else f"{fmt(pv[0])} (L = 20)"
        if g20 and lab in g20:
            x = g20[lab]
            claim(f"Median N_div(φ_2)/N_J, {p0_name(lab)}, L = 20", paper,
                  ci(x["N_div_2_over_N_J"]) + "; up to φ_2 (≤ 1 tagged bud left)",
                  avail(ci(x["N_div_2_over_N_J_paper"]) + "; every division from the first jamming up to no tagged bud left",
                        "N_div_2_none_left", "N_J_first"),
                  outside_grid(lab) or judged(x["N_div_2_over_N_J_paper"], cl, key="median", seeds=seeds_in(x)),
                  fig("figD1"))
        else:
            claim(f"Median N_div(φ_2)/N_J, {p0_name(lab)}", paper, "no L = 20 runs in this preset", "—",
                  outside_grid(lab) or size_mismatch(list(groups_at), PAPER_L_DIVISIONS) or
                  verdicts.Verdict("inconclusive", f"no L = 20 runs at {p0_name(lab)}"), fig("figD1"))
    # ---- growth rates ----
    paper_h = {"0.1": (1.4e-4, 0.01e-4)}
    # h_γ and Π(g) are measured at the Δφ = 3·10⁻³ target, which a grid need not have.
    growth_missing = None
    targets_csv = os.path.join(a.tables, "targets.csv")
    if os.path.exists(targets_csv):
        with open(targets_csv, newline="", encoding="utf-8") as f:
            dphis = {float(r["dphi"]) for r in csv.DictReader(f) if r["dphi"] and float(r["L"]) == L}
        if not any(abs(d / 3e-3 - 1) < 1e-9 for d in dphis):
            growth_missing = "not measured: no target at Δφ = 3·10⁻³ at this L"
    for lab in order:
        x = groups[lab]
        ours = pm(x["h_gamma"], "median")
        if lab == "none":
            # Without feedback every cell grows at the full rate: h_γ = 0 by construction, not a measurement.
            h = (x.get("h_gamma") or {}).get("median")
            paper = "0"
            ours = (f"{fmt(h)} (n={n_text(x['h_gamma'].get('n'))})" if h is not None else "not measured")
            verdict = ("— (0 by construction without feedback: exact, no error bar, not a test)" if h == 0 else
                       "— (0 by construction without feedback: not a test; a measured value other than 0 is an "
                       "error of the analysis)" if h is not None else "— (not measured)")
        elif lab in paper_h:
            verdict = (size_mismatch(L, PAPER_L_MAIN) or
                       judged(x.get("h_gamma_paper"), verdicts.quoted(*paper_h[lab]), seeds=seeds_in(x)))
            paper = fmt(paper_h[lab][0])
        else:
            verdict, paper = "see trend row", "rises for P0 ≲ 1e-2"
        theirs = (avail(f"{pm(x.get('h_gamma_paper'))} (mean ± SE over runs, every cell, rattlers included)",
                        "h_gamma_all_cells") if lab != "none" else "same")
        if growth_missing:
            ours, theirs = growth_missing, growth_missing
            verdict = verdicts.Verdict("inconclusive", growth_missing) if lab in paper_h else "—"
        else:
            ours += " (median ± bootstrap SE)"
        claim(f"h_γ at Δφ = 3e-3, {p0_name(lab)}", paper, ours, theirs, verdict, fig("figE1"))
    strong = [l for l in fed if float(l) <= 1e-2]
    claim("h_γ rises as feedback strengthens (P0 ≲ 1e-2)", "rises", "—", "the trend of the means ± SE over runs",
          verdicts.Verdict("inconclusive", growth_missing) if growth_missing else
          trend_of([groups[l].get("h_gamma_paper") for l in strong], increasing=True), fig("figE1"))
    paper_w = {"0.1": 0.21, "0.01": 0.21, "0.0001": 0.16}
    paper_peak = {"0.1": 0.97, "0.01": 0.90, "0.001": 0.17}
    for lab in fed:
        x = groups[lab]
        w = x.get("g_peak_weight_at_1_paper") or {}
        peak = paper_peak.get(lab)
        quart = (x.get("g_compressed_q25"), x.get("g_compressed_median"), x.get("g_compressed_q75"))
        peak_text = ""
        if peak is not None and None not in quart:
            peak_text = (f"; the paper's peak ≈ {peak} lies {'inside' if quart[0] <= peak <= quart[2] else 'outside'} "
                         "the quartiles (a nearly flat density has no measurable peak: not judged)")
        paper = (f"{'≈ ' + fmt(paper_w[lab]) if lab in paper_w else '—'}; "
                 f"{'peak ≈ ' + fmt(peak) if peak is not None else ('lowest bin' if lab == '0.0001' else '—')}")
        name = f"Π(g) at Δφ = 3e-3, {p0_name(lab)}: weight at g = 1; compressed sector"
        if growth_missing:
            claim(name, paper, growth_missing, growth_missing,
                  verdicts.Verdict("inconclusive", growth_missing) if lab in paper_w else "—", fig("figE1"))
            continue
        claim(name, paper,
              avail(f"{fmt(x.get('g_peak_weight_at_1'))} (cells with g = 1 exactly)", "g_peak_weight_at_1, g_compressed_*, h_gamma_pooled"),
              avail(f"{pm(w)} (per run, the fraction of all cells, rattlers included, whose bud grows at g = 1 "
                    "exactly; mean ± SE over runs)", "g1_fraction_all_cells") + "; g < 1: " +
              avail(f"median {fmt(quart[1])}, quartiles {fmt(quart[0])} – {fmt(quart[2])}",
                    "g_peak_weight_at_1, g_compressed_*, h_gamma_pooled") + peak_text,
              (size_mismatch(L, PAPER_L_MAIN) or judged(w, verdicts.quoted(paper_w[lab], 0.01), seeds=seeds_in(x)))
              if lab in paper_w else "—", fig("figE1"))
    if "P_star_range_paper" not in M:
        claim("Crossover scale P* ~ n_J(6+2u_J) a_c/(8 ln 10) (Eq. E12)", "1.3e-3 – 4.3e-3",
              "not measured: " + ("no completion sizes a_c (no bud events, or no survival.csv in the tables)" if fed
                                  else "no feedback group in this grid (P* is a scale of the feedback runs)"), "same",
              verdicts.Verdict("inconclusive", "not measured"), fig("figE1"))
    else:
        lo, hi = M["P_star_range_paper"]
        claim("Crossover scale P* ~ n_J(6+2u_J) a_c/(8 ln 10) (Eq. E12)", "1.3e-3 – 4.3e-3",
              f"{fmt(M['P_star_range'][0])} – {fmt(M['P_star_range'][1])} (a_c = mean completion size "
              f"{fmt(M['a_c_range_area'][0])} – {fmt(M['a_c_range_area'][1])}, true area)",
              f"{fmt(lo)} – {fmt(hi)} (a_c = median of S, {fmt(M['a_c_median_range_area'][0])} – "
              f"{fmt(M['a_c_median_range_area'][1])}, true area); the ranges "
              f"{'overlap' if lo <= 4.3e-3 and hi >= 1.3e-3 else 'do not overlap'}",
              verdicts.Verdict("inconclusive", "a range over the feedback groups has no error bar"), fig("figE1"))
    # ---- spectrum ----
    D = M.get("dos") or {}
    Dp = D.get("paper") or {}
    if have_dos and D:
        diff = D.get("N_zero_minus_N_u")
        nz = Dp.get("N_zero_vs_N_u") or {}
        # slope_se is a bootstrap over seeds, null from fewer than 5 (analysis.json version 5; before it, over packings)
        nz_se = (f" ± {fmt(nz['slope_se'], 2)}" if error_bar(nz.get("slope_se"), nz.get("seeds")) else
                 " (no error bar by seed: an analysis.json before version 5)" if nz.get("seeds") is None else
                 f" (no error bar: n seeds < {verdicts.MIN_SAMPLES})" if not enough_samples(nz.get("seeds")) else
                 " (no error bar: every resample of the seeds gives this slope)" if nz.get("slope_se") == 0 else
                 " (no error bar: the bootstrap over seeds gave none)")
        slope = (f"; slope of N_zero on N_u through 0: {fmt(nz['slope_through_origin'])}{nz_se}"
                 if nz.get("slope_through_origin") is not None else "")
        claim("N_zero ≃ N_u (Eq. F4)", "tracks",
              (f"N_zero = N_u in {n_text(round(D['N_zero_equals_N_u'] * D['packings']))} of {D['packings']} "
               "distinct packings; " if D.get("N_zero_equals_N_u") is not None and D.get("packings") else "") +
              f"N_zero − N_u = {pm(diff)} (the verdict's test)",
              f"N_zero = N_u exactly in {n_text(nz.get('N_zero_equals_N_u'))} of {n_text(nz.get('packings'))} "
              f"Δφ-target packings{slope} (the paper's panel, no test)" if nz else "not measured",
              judged(diff, verdicts.quoted(0.0, 0.0), n_paper=verdicts.THEORY), fig("figF1"))
    else:
        claim("N_zero ≃ N_u (Eq. F4)", "tracks", "not measured (dos stage off or unavailable)", "same",
              verdicts.Verdict("inconclusive", "not measured"), fig("figF1"))
    if have_dos and Dp:
        od, o6 = Dp["through_origin_dZ"], Dp["through_origin_Z_minus_6"]
        n = Dp["packings"]
        p = Dp["fraction_Z_minus_6_negative"]
        half = verdicts.at_least(0.5)
        n_eff = effective_n(p, Dp.get("fraction_Z_minus_6_negative_se"), n, Dp.get("seeds"))
        if isinstance(p, (int, float)) and math.isfinite(p) and 0 <= p <= 1 and enough_samples(n_eff):
            lo, hi = verdicts.wilson(p, n_eff)
            frac_text = (f"{fmt(p)} [95% Wilson CI {fmt(lo)}, {fmt(hi)}] (n={n_text(n)} packings of "
                         f"{n_text(Dp.get('seeds'))} seeds, effective n = {n_eff:.0f}; score test at 1/2)")
        else:
            frac_text = f"{fmt(p)} (n={n_text(n)})"
        theirs = (f"through the origin on {n} Δφ-target packings: RMS residual {fmt(od['rms'])} for ΔZ, "
                  f"{fmt(o6['rms'])} for Z − 6 (no error bar: not judged); from integer contact counts ΔZ < 0 in "
                  f"{fmt(Dp['fraction_dZ_negative'])}, Z − 6 < 0 in {frac_text}")
        seeds = Dp.get("seeds")
        if n_eff is not None:
            verdict = verdicts.proportion(p, n_eff, half, n_paper=paper_n(n_eff, main_seeds))
        elif isinstance(seeds, (int, float)) and seeds < verdicts.MIN_SAMPLES:
            verdict = verdicts.inconclusive_n(seeds)  # too few seeds for an error by seed
        else:
            verdict = verdicts.Verdict("inconclusive", "no error by seed (an analysis.json before version 4)")
    else:
        theirs, verdict = "not measured (dos stage off or unavailable)", verdicts.Verdict("inconclusive", "not measured")
    claim("ω* collapses against ΔZ, not Z − 6 (Eq. F5): more than half of the packings have Z − 6 < 0",
          "collapse; > half of Z − 6 < 0",
          f"free linear fits over every packing: R² {fmt(D.get('r2_dZ'))} for ΔZ, "
          f"{fmt(D.get('r2_Z_minus_6'))} for Z − 6 (cannot tell a shift apart)" if have_dos and D else "not measured",
          theirs, verdict, fig("figF1"))

    # The size table: identities across L from the preset's own runs.
    size_rows = ["", "## System size", "",
                 "Identities over the targets of each size of this preset. " +
                 sizes_independence_text(A.get("finite_size") or []) +
                 " Errors are by seed, the targets of a seed being one sample.", "",
                 "| L | runs | ΔZ identity residual (feedback runs, all P0) | " +
                 growth_bulk(M["B_grow_over_lambda_B_log10"])[0] + " |", "| --- | --- | --- | --- |"]
    for sz in A.get("sizes", []):
        size_rows.append(f"| {sz['L']:g} | {sz['runs']} | {pm(sz['dZ_identity'].get('feedback_targets'))} | "
                         f"{growth_bulk(sz['B_grow_over_lambda_B_log10'])[1]} |")

    bins = M.get("shear_unstable_by_PN2") or []
    shear = shear_note(bins) if have_moduli and bins else []
    sizes_run = ", ".join(f"{l:g}" for l in sorted(groups_at))
    seeds_text = ("?" if not grid_seeds else f"{grid_seeds[0]:g}" if len(grid_seeds) == 1 else
                  f"{grid_seeds[0]:g}–{grid_seeds[-1]:g}")
    departures = paper_grid_departures(groups_at, label, os.path.join(a.tables, "targets.csv"))
    if a.preset == "paper" and not departures:
        scope = (f"Preset paper: the paper's grid, L = {sizes_run} with {seeds_text} seeds per point, for the targets "
                 "listed in docs/analysis.md.")
    else:
        scope = ((f"Preset paper with its grid overridden ({'; '.join(departures)}): " if a.preset == "paper" else "") +
                 f"Preset {a.preset} ran L = {sizes_run} with {seeds_text} seeds per point and its own Δφ targets, "
                 f"not the paper's grid (L = 8, 15, 20 with {PAPER_SEEDS} seeds per point, Δφ up to 0.12): its "
                 f"verdicts compare these values (main L = {L:g}) with the paper's {PAPER_SEEDS}-seed numbers (L = 15; "
                 f"L = 20 for the divisions), with s_p from the paper's {PAPER_SEEDS} seeds, so they check trends and "
                 "orders of magnitude, not the paper's values to their last digit (run `make -f Makefile.analysis -j2 "
                 "paper` for that).")
    jam_n = (jam.get("u_J") or {}).get("n") if isinstance(jam, dict) else None
    grid_np = (f"n_p = n_b (this preset ran the paper's {PAPER_SEEDS} seeds per point)" if grid_seeds == [PAPER_SEEDS]
               else f"n_p = n_b · {PAPER_SEEDS}/S for this preset's S = {seeds_text} seeds per point")
    inp = A["inputs"]
    if "tables" in inp:
        source = (f"written by `make -f Makefile.analysis PRESET={a.preset} stored-report` on "
                  f"{datetime.date.today().isoformat()}: the run directories are not stored, so `budjam analyse --tables "
                  f"{inp['tables']}` re-applied the estimators to the per-run tables their analysis wrote ({a.tables}). "
                  "A cell whose inputs those tables do not hold (steps.csv, per-cell growth factors) says what it needs")
    else:
        source = (f"written by `make -f Makefile.analysis PRESET={a.preset} report` on {datetime.date.today().isoformat()} "
                  f"from `budjam analyse` output ({a.tables})")
    tables = [n for n in ("analysis.json", "runs.csv", "targets.csv", "survival.csv", "remaining.csv", "division_curve.csv",
                          "growth_rates.csv", "trajectory.csv", "dos.csv") if os.path.exists(os.path.join(a.tables, n))]
    counts = {w: sum(1 for _, x in verdict_list if x == w) for w in ("confirmed", "not confirmed", "inconclusive")}
    tally = ", ".join(f"{n} {w}" for w, n in counts.items())
    lines = [
        "# Reproduction report",
        "",
        f"Preset **{a.preset}** (main system size L = {L:g}); {source}.",
        "",
        f"Runs: {inp['used']} of {inp['runs']} used; "
        + (f"{sum(len(d) - 1 for d in inp.get('duplicates', []))} duplicate copies of a run left out "
           f"({'; '.join(' = '.join(d) for d in inp['duplicates'])}); " if inp.get("duplicates") else "")
        + f"{len(inp['not_finished'])} stopped before their last target"
        + (" (" + not_finished_text(inp["not_finished"]) + ": their recorded states are used)" if inp["not_finished"] else "")
        + (f"; {len(inp['never_jammed'])} never jammed and contribute nothing ("
           + not_finished_text(inp["never_jammed"]) + ")" if inp.get("never_jammed") else "")
        + ". "
        f"Moduli files: {inp['moduli_files']}; spectra: {inp['dos_files']}. Bootstrap: {A['bootstrap']['resamples']} "
        f"resamples, seed {A['bootstrap']['seed']}. Jamming rows: {jam_src}"
        + (f" ({jam.get('runs')} runs)" if AJ else "") + "."
        + (" Not checked in the inputs: " + "; ".join(inp["unchecked"]) + "." if inp.get("unchecked") else "")
        + (f" Groups at L = {L:g} with a P0 outside the paper's grid (P0 = {', '.join(unpaired)}): their rows show "
           "budjam's values without a verdict of their own (the paper has no number for them), and they enter the "
           "trend rows, which order every group by feedback strength." if unpaired else ""),
        "",
        f"**Verdicts: {tally}** (docs/analysis.md, \"Verdicts\"). One rule for every row: a claim is the set of values "
        "it allows (a number quoted to its last digit, a range, a bound); z is the distance of budjam's estimate from "
        "that set in units of σ = √(s_b² + s_p²), budjam's standard error and the paper's own sampling error, estimated "
        "from budjam's spread as s_p = s_b √(n_b/n_p) for the paper's n_p samples: the paper ran "
        f"{PAPER_SEEDS} seeds per point, so n_p = {PAPER_SEEDS} for the jamming rows (one sample per seed; "
        f"budjam's n_b = {n_text(jam_n)}) and, for every other row, {grid_np}; a relation the theory predicts (ΔZ_J = 0, "
        "the ΔZ identity, B_grow = λ_c B_ext, N_zero = N_u) is no number the paper measured, so there σ = s_b. "
        "Confirmed when z ≤ z_c, not confirmed when z > z_c, with z_c the 97.5 % quantile of Student's t over the "
        "n_b − 1 degrees of freedom σ is estimated with, never below 2 (2.09 at n_b = 20; printed where above 2), "
        "inconclusive with fewer than 5 samples (no error bar is printed from fewer either). A trend is confirmed "
        "when its first-to-last change has z > z_c and no step goes against it with z > z_c, not confirmed when one "
        "does, and inconclusive otherwise.",
        "",
        "Each claim is measured twice: under budjam's definition and under the rules of the paper's own analysis "
        "(docs/analysis.md, \"Definitions\", lists both for every quantity); the verdict is for the paper's rules, "
        "except where the paper's analysis draws a figure without a test (the ΔZ identity, B_grow = λ_c B_ext, "
        "N_zero = N_u): there it is budjam's test, and the paper's figure is summarised beside it. "
        "φ_2 is the first state after jamming with at most one tagged bud left under both; the paper's selection "
        "admits a run when one of its Δφ targets reached at or beyond φ_2 had at most 10 divisions after φ_J, its Eq. 14 "
        "takes the bud size a as diameter², its G_2 statistics keep G_2 > 0 within Tukey's 1.5·IQR fences (G_2 only), "
        "and its division figure counts divisions up to the first state with no tagged bud left. Errors: ± standard "
        "error of the mean unless the cell says median (then bootstrap SE of the median) or gives a 95 % bootstrap "
        "percentile interval. " + scope,
        "",
        "| Claim of the paper | Paper | budjam's definition | Paper's definition | Verdict | Figure |",
        "| --- | --- | --- | --- | --- | --- |",
    ] + rows + jamming_size_rows(fs_jamming, fs_jamming_src) \
      + depletion_size_rows(A.get("finite_size")) + size_rows + shear + [
        "",
        "Per-group tables: " + ", ".join(f"`{n}`" for n in tables),
        "",
    ]
    write_lines(a.out, lines)
    print(f"report: {a.out}: verdicts {tally}")
    for w in ("not confirmed", "inconclusive"):
        for text, x in verdict_list:
            if x == w:
                print(f"  {w}: {text}")


if __name__ == "__main__":
    main()
