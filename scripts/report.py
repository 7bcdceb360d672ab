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


def pm(stat, key="mean"):
    """'x ± se (n)' from a {mean|median, se, n} object."""
    if not stat or stat.get(key) is None:
        return "not measured"
    s = fmt(stat[key])
    if stat.get("se") is not None:
        s += " ± " + fmt(stat["se"], 2)
    return s + f" (n={stat.get('n', '?')})"


def growth_bulk(stat):
    """(statistic, text, value) of the B_grow = λ_c B_ext test: log₁₀ of the median ratio ± bootstrap SE (n,
    B_grow ≤ 0 counted); an analysis.json of version ≤ 2 has the mean of log₁₀ B_grow/(λ_c B) instead."""
    if stat.get("median") is None and stat.get("mean") is not None:
        return "⟨log₁₀ B_grow/(λ_c B)⟩", pm(stat), stat["mean"]
    s = pm(stat, "median")
    if stat.get("nonpositive_B_grow") is not None:
        s = s[:-1] + f", {stat['nonpositive_B_grow']} with B_grow ≤ 0)"
    return "log₁₀ median B_grow/(λ_c B)", s, stat.get("median")


FINITE_SIZE_COLUMNS = [("u_J", "u_J (buds)"), ("u_J_lobes", "u_J (lobes)"), ("n_J", "n_J"), ("phi_J", "φ_J"),
                       ("dphi_2", "Δφ_2 (≤ 1 left)"), ("dphi_2_paper", "Δφ_2 (none left, paper's selection)"),
                       ("dphi_2_paper_all", "Δφ_2 (none left, every run)"),
                       ("N_div_2_over_N_J", "N_div(φ_2)/N_J (median)"), ("G_2_over_Pmax", "G_2/P_max (median)"),
                       ("G_2_over_Pmax_at_paper_phi2", "G_2/P_max at none left (median)")]


def finite_size_rows(entries):
    """The finite-size table of every P0 run at several sizes, with its N → ∞ extrapolation."""
    if not entries:
        return []
    head = "| L | runs | N_J | " + " | ".join(t for _, t in FINITE_SIZE_COLUMNS) + " |"
    rows = ["", "## Finite size", "",
            "Per box size and feedback strength, and the extrapolation q(N_J) = q_∞ + c/N_J (weighted least squares on "
            "the per-size values with their standard errors, errors widened by √(χ²/dof) when it exceeds 1); "
            "χ²/dof ≫ 1 says the 1/N form does not describe the data.", ""]
    for e in entries:
        rows += [f"P0 = {e['P0_label']}:", "", head, "|" + " --- |" * (len(FINITE_SIZE_COLUMNS) + 3)]
        for r in e["sizes"]:
            cells = [pm({"mean": r[k]["value"], "se": r[k]["se"], "n": r[k]["n"]}) for k, _ in FINITE_SIZE_COLUMNS]
            rows.append(f"| {r['L']:g} | {r['runs']} | {fmt(r['N_J']['mean'])} | " + " | ".join(cells) + " |")
        limits = []
        for k, _ in FINITE_SIZE_COLUMNS:
            x = e["extrapolation"][k]
            if x.get("limit") is None:
                limits.append("—")
            else:
                limits.append(f"{fmt(x['limit'])} ± {fmt(x['limit_se'], 2)} (χ² {fmt(x['chi2'], 2)}, {x['dof']} dof)")
        rows += [f"| N → ∞ | | | " + " | ".join(limits) + " |", ""]
    return rows


def ci(stat):
    if not stat or stat.get("median") is None:
        return "not measured"
    lo, hi = stat["ci95"]
    return f"{fmt(stat['median'])} [95% CI {fmt(lo)}, {fmt(hi)}] (n={stat['n']})"


def near(stat, paper, half_digit, key="mean", se_key="se"):
    """Verdict on a '≃ paper' claim: confirmed when |x − paper| ≤ 2 SE + half the paper's last digit."""
    if not stat or stat.get(key) is None:
        return "awaits data"
    tol = 2 * (stat.get(se_key) or 0) + half_digit
    return "confirmed" if abs(stat[key] - paper) <= tol else "not confirmed"


def monotone(values, increasing=False):
    """Verdict on a trend claim over the feedback groups (weak → strong)."""
    v = [x for x in values if x is not None]
    if len(v) < 3:
        return "awaits data"
    ok = all((b >= a) if increasing else (b <= a) for a, b in zip(v, v[1:]))
    return "confirmed" if ok else "not confirmed"


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
    ap.add_argument("--survival", help="`budjam survival` JSON of the main L (default: TABLES/survival_main_L.json)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    with open(os.path.join(a.tables, "analysis.json")) as f:
        A = json.load(f)
    with open(a.survival or os.path.join(a.tables, "survival_main_L.json")) as f:
        surv = json.load(f)
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

    def rerun(verdict, *keys):
        return verdict if lacking(*keys) is None else "awaits a re-run"

    def untestable(stat, verdict):
        """The verdict, unless the paper's selection admitted no run: then why the claim cannot be tested."""
        if verdict == "awaits data" and stat and stat.get("runs") and stat.get("admitted") == 0:
            return (f"not testable: the paper's selection admits none of {stat['runs']} runs "
                    "(each has more than 10 divisions after φ_J by its end)")
        return verdict
    L = A["main_L"]
    M = A["main"]
    C = A["constants"]
    # keyed by the label a reader expects ("none", "0.1", ..., "1e-05"), whatever budjam printed
    def label(p0):
        return "none" if p0 is None else {1e-1: "0.1", 1e-2: "0.01", 1e-3: "0.001", 1e-4: "0.0001", 1e-5: "1e-05"}.get(p0, repr(p0))
    groups = {label(g["P0"]): g for g in A["groups"] if g["L"] == L}
    have_moduli = a.moduli == "1" and A["inputs"]["moduli_files"] > 0
    have_dos = a.dos == "1" and A["inputs"]["dos_files"] > 0
    figdir = os.path.relpath(a.figures, os.path.dirname(os.path.abspath(a.out)) or ".")

    def fig(name):
        path = os.path.join(a.figures, name + ".png")
        return f"[{name}]({figdir}/{name}.png)" if os.path.exists(path) else f"{name} (not drawn)"

    def g(label, key, kind="mean"):
        x = groups.get(label)
        if x is None:
            return "no runs"
        return ci(x[key]) if kind == "ci" else pm(x[key], kind)

    def needs(flag, text, what):
        return text if flag else f"not measured ({what} stage off or unavailable)"

    rows = []

    def claim(text, paper, ours, theirs, verdict, figure):
        rows.append(f"| {text} | {paper} | {ours} | {theirs} | {verdict} | {figure} |")

    def sel(stat, key="mean"):
        """'x ± se (n of runs)' of a statistic under the paper's selection."""
        if not stat or stat.get(key) is None:
            return "not measured"
        se = stat.get("se" if key == "mean" else "median_se")
        return (fmt(stat[key]) + (f" ± {fmt(se, 2)}" if se is not None else "") +
                f" (n={stat['n']} of {stat['runs']} runs; {stat['admitted']} admitted)")

    def states(stat):
        if not stat or stat.get("mean") is None:
            return "not measured"
        return (f"{fmt(stat['mean'])} ± {fmt(stat['se'], 2)} (n={stat['n']} jamming states of {stat['runs']} runs; "
                f"bootstrap by seed ± {fmt(stat['bootstrap_se_by_seed'], 2)})")

    order = [l for l in ("none", "0.1", "0.01", "0.001", "0.0001", "1e-05") if l in groups]
    fed = [l for l in order if l != "none"]
    paper_P0 = M.get("paper_P0")
    strong = f"P0={label(paper_P0)}" if paper_P0 is not None else "strongest P0"

    # ---- jamming ----
    claim("Unconstrained fraction at jamming u_J (L = 15 in the paper)", "≃ 0.23",
          states(M["u_J"]) + "; contact-free buds / N_nr, every run",
          states(M.get("u_J_paper")) + f"; contact-free lobes (mothers included) / N_nr, {strong}",
          near(M.get("u_J_paper"), 0.23, 0.005), "—")
    claim("Mean-field u_J = −W₀(−2e⁻²)/2 (Eq. A10)", "≈ 0.20", fmt(C["u_J_lambert_w"], 4) + " (computed)", "same",
          "confirmed" if round(C["u_J_lambert_w"], 2) == 0.20 else "not confirmed", "—")
    claim("Nonrattler density at jamming n_J", "≃ 0.775", states(M["n_J"]) + "; every run",
          states(M.get("n_J_paper")) + f"; {strong}", near(M.get("n_J_paper"), 0.775, 0.0005), "—")
    claim("Jamming packing fraction φ_J", "—", states(M["phi_J"]), "same", "—", "—")
    claim("Confluence pressure P_max = (2/π)(1 − φ_J) (Eq. D25, φ_J = 0.84)", "≈ 0.1",
          f"{fmt(C['P_max_formula_phiJ_0.84'])} (φ_J=0.84); {fmt(M['P_max_formula_measured_phiJ'])} with the measured φ_J",
          "same", "confirmed" if round(M["P_max_formula_measured_phiJ"], 1) == 0.1 else "not confirmed", "—")
    dzj = groups.get("none", {}).get("dZ_J")
    claim("Modified Maxwell count at jamming: ΔZ_J = Z_J − Z_iso(u_J) ≈ 0 (Eqs. 3, 5)", "marginal",
          pm(dzj) + " (no feedback)", "same",
          "confirmed" if dzj and dzj.get("mean") is not None and abs(dzj["mean"]) < 1e-9 else "not confirmed", "—")
    ident = M["dZ_identity"]
    per = ident["per_P0_feedback"]
    worst = max((abs(x["mean"]) for x in per if x["mean"] is not None), default=None)
    claim("ΔZ = ΔZ₀(P) + 2(u_J − u) over (P0, Δφ) (Eq. 6)", "holds within finite-size scatter",
          "residual over every target, no-feedback runs included: " + pm(ident["all_targets"]) +
          f", RMS {fmt(ident['all_targets'].get('rms'))}",
          "residual per P0, feedback runs only: " +
          "; ".join(f"P0={label(x['P0'])} {fmt(x['mean'])} ± {fmt(x['se'], 2)} (n={x['n']}, RMS {fmt(x['rms'])})" for x in per),
          "awaits data" if worst is None else ("confirmed" if worst < 0.1 else "not confirmed") +
          " (|mean residual| < 0.1 at every P0)", fig("fig2"))
    # ---- depletion ----
    for lab in order:
        x = groups[lab]
        sim = x["dphi_2_paper"]
        pred = x["dphi_2_pred_area"]
        verdict = "awaits data"
        if sim.get("mean") is not None and pred.get("mean") is not None:
            ratio = pred["mean"] / sim["mean"]
            verdict = ("confirmed" if 1.0 <= ratio <= 1.5 else "not confirmed") + f" (theory/simulation = {fmt(ratio)})"
        claim(f"φ_2 − φ_J, {p0_name(lab)}: simulation vs Eq. 14 (a as true area)", "theory slightly overestimates",
              f"{pm(x['dphi_2'])} vs {avail(pm(pred), 'dphi_2_pred_area')}; φ_2 at ≤ 1 tagged bud left, every run",
              avail(f"{sel(sim)} vs {pm(pred)}; φ_2 at no tagged bud left, paper's selection", "dphi_2_paper", "N_div_end"),
              rerun(untestable(sim, verdict), "dphi_2_paper", "N_div_end"), fig("fig2"))
    claim("Stronger feedback moves φ_2 closer to φ_J", "monotone",
          ", ".join(f"{p0_name(l)} {fmt(groups[l]['dphi_2']['mean'])}" for l in order),
          avail(", ".join(f"{p0_name(l)} {fmt(groups[l]['dphi_2_paper']['mean'])}" for l in order), "dphi_2_paper", "N_div_end"),
          rerun(monotone([groups[l]["dphi_2_paper"]["mean"] for l in fed]), "dphi_2_paper", "N_div_end"), fig("fig2"))
    claim("Kaplan–Meier a_ε and ∫₀^{a_ε} S da (pooled, diameter²)", "—",
          f"a_ε = {fmt(surv.get('a_eps'))}, ∫S = {fmt(surv.get('integral_S'))}, ε = {fmt(surv.get('epsilon'))} "
          f"({surv.get('events')} completions, {surv.get('censored')} censored)", "same", "—", fig("figS"))
    # ---- mechanics ----
    bg_name, bg_text, bg = growth_bulk(M["B_grow_over_lambda_B_log10"])
    per_p0, worst = "", bg
    if bg is not None and all("B_grow_over_lambda_B_log10" in groups[l] for l in order):  # analysis.json v ≥ 3
        medians = {l: groups[l]["B_grow_over_lambda_B_log10"]["median"] for l in order}
        per_p0 = "; per P0: " + ", ".join(f"{p0_name(l)} {fmt(m)}" for l, m in medians.items())
        worst = max([bg] + [m for m in medians.values() if m is not None], key=abs)
    claim("B_grow = λ_c B_ext (Eq. 20)", "holds over (P0, Δφ)",
          needs(have_moduli, f"{bg_name} = {bg_text} over the targets with λ_c B > 0{per_p0}", "moduli"), "same",
          "awaits data" if not have_moduli or bg is None else
          ("confirmed" if abs(worst) < 0.1 else "not confirmed") +
          (" (within 10^±0.1 pooled and at every P0)" if per_p0 else " (within 10^±0.1)"), fig("fig3"))
    for lab in order:
        x = groups[lab]
        claim(f"P_2/P_max and λ̄_c, {p0_name(lab)}", "decrease strongly with feedback, together",
              f"{pm(x['P_2_over_Pmax'])}; λ̄_c = {avail(pm(x['lambda_bar']) + ' (plain mean over [φ_J, φ_2])', 'lambda_bar')}; "
              "every run",
              avail(f"{sel(x['P_2_over_Pmax_paper'])}; λ̄_c = {sel(x['lambda_bar_paper'])}", "P_2_paper", "lambda_bar_paper",
                    "N_div_end"), "see trend row", fig("fig3"))
    p2 = [groups[l]["P_2_over_Pmax_paper"]["mean"] for l in fed]
    lb = [groups[l]["lambda_bar_paper"]["mean"] for l in fed]
    v2, vl = monotone(p2), monotone(lb)
    claim("P_2 and λ̄_c fall together with feedback (trend over P0)", "mirrored",
          "—", avail("P_2: " + v2 + "; λ̄_c: " + vl + " (monotone over the feedback groups)", "P_2_paper",
                     "lambda_bar_paper", "N_div_end"),
          rerun("confirmed" if v2 == vl == "confirmed" else ("awaits data" if "awaits data" in (v2, vl) else "not confirmed"),
                "P_2_paper", "lambda_bar_paper", "N_div_end"),
          fig("fig3"))
    if "P_dagger" in M:
        claim("P_2 ∝ exp(−P†/P0) (Eq. D19)", "P† = typical bud pressure",
              f"P† = {fmt(M['P_dagger'])} ± {fmt(M['P_dagger_se'], 2)} (fit over {M['P_dagger_points']} P0 ≤ 1e-2)",
              "same", "—", fig("fig3"))
    for lab in order:
        x = groups[lab]
        s_ = x["G_2_over_Pmax_paper"]
        verdict = "awaits data"
        if have_moduli and s_.get("median") is not None:
            verdict = "confirmed" if 0.2 <= s_["median"] <= 1.0 else "not confirmed"
        claim(f"G_2/P_max, {p0_name(lab)} (median ± bootstrap SE)", "≈ 0.2 – 1",
              needs(have_moduli, pm(x["G_2_over_Pmax"], "median") + ", every run", "moduli"),
              avail(needs(have_moduli, sel(s_, "median"), "moduli"), "N_div_end"),
              rerun(untestable(s_, verdict) if have_moduli else verdict, "N_div_end"), fig("fig3"))
    claim("Rigidity plateau G_2(0⁺) = n_J k ℓ_c² M₄ u_J (inputs at the strongest P0)", "finite plateau",
          f"G_2(0⁺)/P_max = {fmt(M.get('G2_plateau_over_Pmax'))} (P0={M.get('plateau_P0')}, ℓ_c² = {fmt(M.get('lc2_J'))})",
          "same", "—", fig("fig4"))
    gp = [groups[l]["G_2_over_P_2_paper"]["median"] for l in order]
    for lab in order:
        x = groups[lab]
        claim(f"G_2/P_2, {p0_name(lab)} (median ± bootstrap SE)", "diverges as P0 → 0",
              needs(have_moduli, pm(x["G_2_over_P_2"], "median") + ", every run", "moduli"),
              avail(needs(have_moduli, sel(x["G_2_over_P_2_paper"], "median"), "moduli"), "N_div_end"),
              rerun("see trend: " + (monotone(gp, increasing=True) if have_moduli else "awaits data"), "N_div_end"),
              fig("figD2"))
    # ---- divisions: the paper's medians are from L = 20 ----
    paper_div = {"none": 0.081, "0.1": 0.071, "0.01": 0.053, "0.001": 0.013, "0.0001": 3e-3, "1e-05": 3e-3}
    for lab in order:
        x = groups[lab]["N_div_2_over_N_J_paper"]
        pv = paper_div.get(lab)
        verdict = "awaits L = 20 runs"
        if x.get("median") is not None and pv is not None and L != 20:
            lo, hi = x["ci95"]
            inside = x["median"] <= pv if pv == 3e-3 else lo <= pv <= hi
            verdict += f" (at L = {L:g} the paper's value is {'inside' if inside else 'outside'} the 95 % CI)"
        claim(f"Median N_div(φ_2)/N_J, {p0_name(lab)}", ("≲ 3e-3" if pv == 3e-3 else fmt(pv)) + " (L = 20)",
              g(lab, "N_div_2_over_N_J", "ci") + "; φ_2 at ≤ 1 tagged bud left",
              avail(g(lab, "N_div_2_over_N_J_paper", "ci") + "; every division after φ_J up to no tagged bud left",
                    "N_div_2_paper"), verdict, fig("figD1"))
    # ---- growth rates ----
    paper_h = {"none": (0.0, 0.0), "0.1": (1.4e-4, 0.05e-4)}
    hs = [groups[l]["h_gamma"]["median"] for l in fed]
    for lab in order:
        x = groups[lab]
        if lab in paper_h:
            pv, half = paper_h[lab]
            verdict = near(x["h_gamma"], pv, half, key="median")
            paper = fmt(pv)
        else:
            verdict = "see trend: " + monotone([v for l, v in zip(fed, hs) if float(l) <= 1e-2], increasing=True)
            paper = "rises for P0 ≲ 1e-2"
        claim(f"h_γ at Δφ = 3e-3, {p0_name(lab)} (median ± bootstrap SE)", paper, pm(x["h_gamma"], "median"), "same",
              verdict, fig("figE1"))
    paper_w = {"0.1": 0.21, "0.01": 0.21, "0.0001": 0.16}
    paper_peak = {"0.1": 0.97, "0.01": 0.90, "0.001": 0.17}
    for lab in fed:
        x = groups[lab]
        w = x.get("g_peak_weight_at_1_paper") or {}
        verdict = near(w, paper_w[lab], 0.005) if lab in paper_w else "—"
        peak = paper_peak.get(lab)
        quart = (x.get("g_compressed_q25"), x.get("g_compressed_median"), x.get("g_compressed_q75"))
        if peak is not None and None not in quart:
            verdict += (f"; peak ≈ {peak} {'inside' if quart[0] <= peak <= quart[2] else 'outside'} the quartiles "
                        "(a nearly flat density has no measurable peak)")
        claim(f"Π(g) at Δφ = 3e-3, {p0_name(lab)}: weight at g = 1; compressed sector",
              f"{'≈ ' + fmt(paper_w[lab]) if lab in paper_w else '—'}; "
              f"{'peak ≈ ' + fmt(peak) if peak is not None else ('lowest bin' if lab == '0.0001' else '—')}",
              avail(f"{fmt(x.get('g_peak_weight_at_1'))} (cells with g = 1 exactly)", "g_peak_weight_at_1, g_compressed_*, h_gamma_pooled"),
              f"{pm(w)} (u at Δφ = 3e-3); g < 1: " +
              avail(f"median {fmt(quart[1])}, quartiles {fmt(quart[0])} – {fmt(quart[2])}",
                    "g_peak_weight_at_1, g_compressed_*, h_gamma_pooled"),
              verdict, fig("figE1"))
    if "P_star_range_paper" in M:
        lo, hi = M["P_star_range_paper"]
        overlap = lo <= 4.3e-3 and hi >= 1.3e-3
        claim("Crossover scale P* ~ n_J(6+2u_J) a_c/(8 ln 10) (Eq. E12)", "1.3e-3 – 4.3e-3",
              f"{fmt(M['P_star_range'][0])} – {fmt(M['P_star_range'][1])} (a_c = mean completion size "
              f"{fmt(M['a_c_range_area'][0])} – {fmt(M['a_c_range_area'][1])}, true area)",
              f"{fmt(lo)} – {fmt(hi)} (a_c = median of S, {fmt(M['a_c_median_range_area'][0])} – "
              f"{fmt(M['a_c_median_range_area'][1])}, true area)",
              ("confirmed" if overlap else "not confirmed") + " (ranges overlap)", fig("figE1"))
    # ---- spectrum ----
    D = M.get("dos") or {}
    Dp = D.get("paper") or {}
    claim("N_zero ≃ N_u (Eq. F4)", "tracks",
          needs(have_dos and D, f"N_zero = N_u in {fmt(D.get('N_zero_equals_N_u'))} of {D.get('packings')} distinct packings; "
                                f"mean abs(N_zero − N_u) = {fmt(D.get('N_zero_minus_N_u_abs'))}", "dos"), "same",
          "awaits data" if not (have_dos and D) else
          ("confirmed" if D["N_zero_equals_N_u"] >= 0.9 else "not confirmed") + " (equal in ≥ 90 %)", fig("figF1"))
    if have_dos and Dp:
        od, o6 = Dp["through_origin_dZ"], Dp["through_origin_Z_minus_6"]
        ok = Dp["fraction_Z_minus_6_negative"] > 0.5 and od["rms"] < o6["rms"]
        theirs = (f"through the origin on {Dp['packings']} Δφ-target packings: RMS residual {fmt(od['rms'])} for ΔZ, "
                  f"{fmt(o6['rms'])} for Z − 6; from integer contact counts ΔZ < 0 in {fmt(Dp['fraction_dZ_negative'])}, "
                  f"Z − 6 < 0 in {fmt(Dp['fraction_Z_minus_6_negative'])}")
        verdict = "confirmed" if ok else "not confirmed"
    else:
        theirs, verdict = "not measured (dos stage off or unavailable)", "awaits data"
    claim("ω* collapses against ΔZ, not Z − 6 (Eq. F5)", "collapse; > half of Z − 6 < 0",
          needs(have_dos and D, f"free linear fits over every packing: R² {fmt(D.get('r2_dZ'))} for ΔZ, "
                                f"{fmt(D.get('r2_Z_minus_6'))} for Z − 6 (cannot tell a shift apart)", "dos"),
          theirs, verdict, fig("figF1"))

    # The size table: the numbers the size-effects figure compares across L.
    size_rows = ["", "## System size", "",
                 "Quantities fixed at jamming over distinct jamming states; identities over the targets of each size.", "",
                 "| L | runs | jamming states | u_J (buds) | u_J (lobes) | n_J | φ_J | ΔZ identity residual (feedback runs, all P0) "
                 "| " + growth_bulk(M["B_grow_over_lambda_B_log10"])[0] + " |",
                 "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for sz in A.get("sizes", []):
        fed_res = sz["dZ_identity"].get("feedback_targets")
        allfed = pm(fed_res) if fed_res else "per P0 (an analysis.json without the pooled value): " + "; ".join(
            f"{label(x['P0'])} {fmt(x['mean'])} (n={x['n']})" for x in sz["dZ_identity"]["per_P0_feedback"])
        size_rows.append(f"| {sz['L']:g} | {sz['runs']} | {sz['jamming_states']} | {pm(sz['u_J'])} | {pm(sz['u_J_lobes'])} | "
                         f"{pm(sz['n_J'])} | {pm(sz['phi_J'])} | {allfed} | {growth_bulk(sz['B_grow_over_lambda_B_log10'])[1]} |")
    for Lp in (8, 15, 20):
        if not any(sz["L"] == Lp for sz in A.get("sizes", [])):
            size_rows.append(f"| {Lp} | not run | | | | | | | |")

    bins = M.get("shear_unstable_by_PN2") or []
    shear = shear_note(bins) if have_moduli and bins else []
    scope = ("The quick preset uses L = 8 and few seeds: it checks trends and orders of magnitude, not the paper's "
             "L = 15 values to their last digit (run `make -f Makefile.analysis -j2 paper` for that)."
             if a.preset == "quick" else
             f"Preset {a.preset}: the paper's grid for the sizes and targets listed in docs/analysis.md.")
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
    lines = [
        "# Reproduction report",
        "",
        f"Preset **{a.preset}** (main system size L = {L:g}); {source}.",
        "",
        f"Runs: {inp['used']} of {inp['runs']} reached jamming and are used; "
        + (f"{sum(len(d) - 1 for d in inp.get('duplicates', []))} duplicate copies of a run left out "
           f"({'; '.join(' = '.join(d) for d in inp['duplicates'])}); " if inp.get("duplicates") else "")
        + 
        f"{len(inp['not_finished'])} stopped before their last target"
        + (" (" + not_finished_text(inp["not_finished"]) + ": their recorded states are used)" if inp["not_finished"] else "")
        + ". "
        f"Moduli files: {inp['moduli_files']}; spectra: {inp['dos_files']}. Bootstrap: {A['bootstrap']['resamples']} "
        f"resamples, seed {A['bootstrap']['seed']}.",
        "",
        "Each claim is measured twice: under budjam's own definition and under the one the paper's analysis "
        "used (docs/analysis.md, \"Definitions\"); the verdict is for the paper's definition. Errors: ± standard "
        "error of the mean unless the cell says median (then bootstrap SE of the median) or gives a 95 % bootstrap "
        "percentile interval. Quantities fixed at jamming count each distinct jamming state once (runs of one seed "
        "share their growth up to jamming in every P0 group), with a bootstrap that resamples seeds beside it; "
        "per-P0 statistics have one run per seed. The paper's selection keeps runs with ≤ 10 divisions after φ_J at "
        "their end and G_2 > 0, then Tukey's 1.5·IQR fences per P0. A run ends at the φ_2 of its own definition "
        "(jamming.phi2_tagged_left: at most one tagged bud left by default, none in the paper) once its targets are "
        "done and saves that packing; the other definition's φ_2 is read from its log, so only runs whose targets "
        "lie beyond budjam's φ_2 reach the paper's (n says how many), and G_2 under the paper's definition is at the "
        "paper's φ_2 only in runs that saved it there (analysis.json G_2_at_paper_phi2), else at budjam's. "
        "A '≃ x' claim is confirmed when the measured "
        "value lies within 2 SE plus half the paper's last digit. " + scope,
        "",
        "| Claim of the paper | Paper | budjam's definition | Paper's definition | Verdict | Figure |",
        "| --- | --- | --- | --- | --- | --- |",
    ] + rows + size_rows + finite_size_rows(A.get("finite_size")) + shear + [
        "",
        "Per-group tables: " + ", ".join(f"`{n}`" for n in tables),
        "",
    ]
    write_lines(a.out, lines)


if __name__ == "__main__":
    main()
