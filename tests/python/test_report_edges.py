"""scripts/report.py on hand-built inputs: the stored analysis.json of the quick reference with its
sample counts, errors and values changed. No error bar, interval or verdict from fewer than 5 samples,
no traceback, and every z with the combined error of the verdict rule."""
import csv
import json
import math
import os
import re
import subprocess
import sys

import pytest

SRC = os.environ.get("BUDJAM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
REF = os.path.join(SRC, "data", "reference")
sys.path.insert(0, os.path.join(SRC, "scripts"))
import verdicts  # noqa: E402


def load(path):
    with open(path) as f:
        return json.load(f)


def report(tmp_path, A, J=None, preset="quick", targets=None):
    """Writes A (and J as the jamming tables, `targets` as targets.csv) and runs report.py; returns
    (process, report text)."""
    tables = tmp_path / "tables"
    tables.mkdir()
    (tables / "analysis.json").write_text(json.dumps(A))
    if targets is not None:
        (tables / "targets.csv").write_text(targets)
    args = [sys.executable, os.path.join(SRC, "scripts", "report.py"), "--tables", str(tables),
            "--figures", str(tmp_path / "figures"), "--preset", preset, "--out", str(tmp_path / "R.md")]
    if J is not None:
        jam = tmp_path / "jamming"
        jam.mkdir()
        (jam / "analysis.json").write_text(json.dumps(J))
        args += ["--jamming", str(jam)]
    r = subprocess.run(args, capture_output=True, text=True)
    out = (tmp_path / "R.md").read_text() if (tmp_path / "R.md").exists() else ""
    return r, out


def stats(o):
    """Every {n, se|ci95} statistic in a JSON tree."""
    if isinstance(o, dict):
        if "n" in o and ("se" in o or "ci95" in o):
            yield o
        for v in o.values():
            yield from stats(v)
    elif isinstance(o, list):
        for v in o:
            yield from stats(v)


def quick():
    """The quick reference's analysis and the committed jamming ensembles' (whose analysis.json predates the
    jamming_models list: it is taken from their runs.csv, as `analyse --tables` takes it)."""
    J = load(os.path.join(REF, "jamming", "tables", "analysis.json"))
    with open(os.path.join(REF, "jamming", "tables", "runs.csv"), newline="") as f:
        J["jamming_models"] = sorted({r["jamming_model"] for r in csv.DictReader(f)})
    return load(os.path.join(REF, "quick", "reanalysed", "analysis.json")), J


def errors_below_five(out):
    bad = [m.group(0) for m in re.finditer(r"± \S+ \(n=(\d+)", out) if int(m.group(1)) < 5]
    bad += [m.group(0) for m in re.finditer(r"CI [^(|]*\(n=(\d+)", out) if int(m.group(1)) < 5]
    return bad


def verdict_cells(out):
    return [line.split(" | ")[4] for line in out.splitlines() if line.startswith("| ") and line.count(" | ") >= 5]


@pytest.mark.parametrize("n", [0, 1, 4])
def test_no_error_bar_interval_or_verdict_from_fewer_than_five(tmp_path, n):
    A, J = quick()
    for s in list(stats(A)) + list(stats(J)):
        s["n"] = n  # the se and ci95 stay: the report must not print them
        if n == 0:
            for k in ("mean", "median", "se", "value"):
                if k in s:
                    s[k] = None
    A["main"]["dos"]["paper"]["packings"] = n  # the fraction of packings with Z − 6 < 0
    if n == 0:
        A["main"]["dos"]["paper"]["fraction_Z_minus_6_negative"] = None
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert errors_below_five(out) == []
    for cell in verdict_cells(out):
        assert not re.match(r"(not )?confirmed \(z", cell), cell


def test_nan_values_and_zero_spread_give_no_nan_verdict(tmp_path):
    A, J = quick()
    for s in list(stats(A)) + list(stats(J)):
        for k in ("mean", "median", "se"):
            if k in s:
                s[k] = math.nan
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert "z = nan" not in out and "σ = nan" not in out


def test_missing_feedback_groups_and_no_jamming_ensemble(tmp_path):
    A, _ = quick()
    A["groups"] = [g for g in A["groups"] if g["P0_label"] in ("0.001", "1e-05")]
    r, out = report(tmp_path, A)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert "| Claim of the paper |" in out


def test_without_a_jamming_ensemble_the_jamming_rows_count_seeds_not_states(tmp_path):
    # 49 jamming states from 20 seeds (unjammings make more than one per run): a seed is one sample
    A, _ = quick()
    A["main"]["u_J"] = {"mean": 0.22, "se": 0.0055, "n": 49, "runs": 120, "bootstrap_se_by_seed": 0.0088, "seeds": 20}
    r, out = report(tmp_path, A)
    assert r.returncode == 0, r.stderr
    row = next(line for line in out.splitlines() if line.startswith("| Unconstrained fraction at jamming"))
    assert "(n=20)" in row and "0.0088" in row and "n=49" not in row, row


def reanalysed_jamming():
    """The jamming ensembles as this build's `analyse --tables` computes them (the stored tables predate
    the isostatic count)."""
    return load(os.path.join(REF, "jamming", "reanalysed", "analysis.json"))


def test_jamming_numbers_take_the_papers_twenty_seeds_and_a_predicted_relation_none(tmp_path):
    A, J = quick()[0], reanalysed_jamming()
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0, r.stderr
    # n_J ≃ 0.775 is a number the paper measured on its 20 seeds: σ = s_b √(1 + n_b/20)
    nj = next(s for s in J["sizes"] if s["L"] == 15)["n_J"]
    row = next(line for line in out.splitlines() if line.startswith("| Nonrattler density at jamming"))
    sigma = float(re.search(r"σ = ([0-9.e+-]+)[,)]", row).group(1))
    assert math.isclose(sigma, nj["se"] * math.sqrt(1 + nj["n"] / 20), rel_tol=0.05), row
    # ΔZ_J = 0 (every packing isostatic) is what the theory predicts, no number of the paper's sample: σ is
    # budjam's own, that of the isostatic fraction at its boundary 1 (Wilson's half-width over 1.96)
    iso = next(s for s in J["sizes"] if s["L"] == 15)["isostatic_J"]
    row = next(line for line in out.splitlines() if line.startswith("| Modified Maxwell count"))
    sigma = float(re.search(r"σ = ([0-9.e+-]+)[,)]", row).group(1))
    lo, hi = verdicts.wilson(iso["fraction"], iso["packings"])
    assert math.isclose(sigma, (hi - lo) / (2 * 1.96), rel_tol=0.05), row


def tally_and_cells(out):
    """(the tally the report prints, the count of the verdict words in its table)."""
    tally = re.search(r"\*\*Verdicts: (\d+) confirmed, (\d+) not confirmed, (\d+) inconclusive\*\*", out)
    words = [re.match(r"(not confirmed|confirmed|inconclusive)\b", c) for c in verdict_cells(out)]
    words = [w.group(1) for w in words if w]
    return tuple(int(x) for x in tally.groups()), \
        (words.count("confirmed"), words.count("not confirmed"), words.count("inconclusive"))


def fresh(tmp_path, name):
    d = tmp_path / name
    d.mkdir()
    return d


def test_the_tally_counts_every_verdict_in_the_table(tmp_path):
    A, J = quick()
    r, out = report(tmp_path, A, J)
    printed, counted = tally_and_cells(out)
    assert printed == counted


def test_no_fit_error_from_fewer_than_five_points(tmp_path):
    A, J = quick()
    A["main"].update(P_dagger=2.8e-5, P_dagger_se=1.4e-5, P_dagger_points=4)
    A["main"]["dos"]["paper"]["packings"] = 3
    r, out = report(tmp_path, A, J)
    row = next(line for line in out.splitlines() if line.startswith("| P_2 ∝ exp"))
    assert "±" not in row
    row = next(line for line in out.splitlines() if line.startswith("| ω* collapses"))
    assert "±" not in row.split(" | ")[3] and row.split(" | ")[4].startswith("inconclusive")


def row_of(out, start):
    return next(line for line in out.splitlines() if line.startswith("| " + start))


def main_L_groups(A):
    return [g for g in A["groups"] if g["L"] == A["main_L"]]


def test_the_pooled_value_is_not_counted_as_a_group(tmp_path):
    A, J = quick()
    groups = main_L_groups(A)
    A["main"]["B_grow_over_lambda_B_log10"].update(median=1.0, se=0.01, n=100)  # pooled: far from 0
    for k, g in enumerate(groups):  # the first two groups far from 0, the others at 0
        g["B_grow_over_lambda_B_log10"].update(median=1.0 if k < 2 else 0.0, se=0.01, n=40)
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0, r.stderr
    cell = row_of(out, "B_grow = λ_c B_ext").split(" | ")[4]
    assert cell.startswith("not confirmed"), cell
    assert f"2 of {len(groups)} P0 groups not confirmed" in cell and "pooled value not confirmed" in cell, cell
    for g in groups:
        g["B_grow_over_lambda_B_log10"].update(median=0.0)
    r, out = report(fresh(tmp_path, "again"), A, J)
    cell = row_of(out, "B_grow = λ_c B_ext").split(" | ")[4]
    assert f"0 of {len(groups)} P0 groups not confirmed" in cell and "pooled value not confirmed" in cell, cell


def test_the_phi2_trend_tests_every_group_it_lists(tmp_path):
    A, J = quick()
    groups = main_L_groups(A)
    # a clean decrease over the feedback groups, but no feedback (listed first) far below all of them
    def values(mean, k):  # 20 seeds around `mean`, as analysis.json lists them by seed
        return {str(s): mean + 1e-4 * ((s * (k + 3)) % 7 - 3) for s in range(1, 21)}

    for k, g in enumerate(g for g in groups if g["P0_label"] != "none"):
        g["dphi_2_paper"].update(mean=0.05 - 0.005 * k, se=1e-4, n=20, by_seed=values(0.05 - 0.005 * k, k))
    none = next(g for g in groups if g["P0_label"] == "none")
    none["dphi_2_paper"].update(mean=0.001, se=1e-4, n=20, by_seed=values(0.001, -1))
    r, out = report(tmp_path, A, J)
    row = row_of(out, "Stronger feedback moves φ_2")
    assert "no feedback" in row.split(" | ")[3]
    assert row.split(" | ")[4].startswith("not confirmed (paired by seed, paired SE"), row
    # without the values by seed (an analysis.json before version 7) each group is judged by its SE
    for g in groups:
        g["dphi_2_paper"].pop("by_seed")
    r, out = report(fresh(tmp_path, "unpaired"), A, J)
    row = row_of(out, "Stronger feedback moves φ_2")
    assert row.split(" | ")[4].startswith("not confirmed (first to last"), row


def test_h_gamma_without_feedback_is_exact_and_not_counted(tmp_path):
    A, J = quick()
    none = next(g for g in main_L_groups(A) if g["P0_label"] == "none")
    none["h_gamma"].update(median=0.0, se=0.0, n=20)
    r, out = report(tmp_path, A, J)
    row = row_of(out, "h_γ at Δφ = 3e-3, no feedback")
    cell = row.split(" | ")[4]
    assert not re.match(r"(not )?confirmed|inconclusive", cell), cell
    assert "construction" in cell and "± 0" not in row
    assert tally_and_cells(out)[0] == tally_and_cells(out)[1]


def test_a_fraction_of_zero_or_one_is_judged_by_a_finite_error(tmp_path):
    A, J = quick()
    paper = A["main"]["dos"]["paper"]
    se = paper["fraction_Z_minus_6_negative_se"]
    for p, word in ((0.0, "not confirmed"), (1.0, "confirmed"), (0.45, None)):
        # a fraction of 0 or 1 is the same in every seed: its SE by seed is 0
        paper.update(packings=40, fraction_Z_minus_6_negative=p,
                     fraction_Z_minus_6_negative_se=0.0 if p in (0.0, 1.0) else se)
        r, out = report(fresh(tmp_path, f"p{p}"), A, J)
        row = row_of(out, "ω* collapses")
        cell = row.split(" | ")[4]
        assert "inf" not in cell and "σ = 0)" not in cell and "± 0 " not in row, row
        if word:
            assert re.match(word + r" \(z", cell), cell
            # the same in every seed: the seeds, not the packings, are the independent samples
            assert f"effective n = {paper['seeds']}" in row, row
        assert "Wilson" in row


def test_a_fraction_alike_in_every_seed_is_judged_on_its_packings(tmp_path):
    # 0 < p < 1 and an SE by seed of 0: every seed has the same fraction, which bounds nothing below the packings
    A, J = quick()
    paper = A["main"]["dos"]["paper"]
    paper.update(packings=56, fraction_Z_minus_6_negative=0.5, fraction_Z_minus_6_negative_se=0.0)
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    row = row_of(out, "ω* collapses")
    assert "effective n = 56" in row and "before version" not in row, row
    assert re.match(r"confirmed \(z = 0", row.split(" | ")[4]), row


def test_the_quick_preset_says_its_grid_and_takes_the_papers_twenty_seeds(tmp_path):
    A, J = quick()
    r, out = report(tmp_path, A, J)
    seeds = {g["runs"] for g in main_L_groups(A)}
    assert len(seeds) == 1 and seeds != {20}
    s = seeds.pop()
    assert f"L = 8 with {s} seeds per point" in out and "not the paper's grid" in out
    assert f"n_p = n_b · 20/S for this preset's S = {s} seeds per point" in out
    # the paper's h_γ is for L = 15: a value at L = 8 does not test it
    assert "inconclusive (L = 8, the paper's number is for L = 15)" in row_of(out, "h_γ at Δφ = 3e-3, P0=0.1")
    # the same grid said to be at L = 15: σ = s_b √(1 + n_b/n_p) with n_p = n_b · 20/S
    main_L = A["main_L"]
    for g in A["groups"]:
        if g["L"] == main_L:
            g["L"] = 15
    A["main_L"] = 15
    r, out = report(fresh(tmp_path, "at15"), A, J)
    x = next(g for g in main_L_groups(A) if g["P0_label"] == "0.1")["h_gamma_paper"]
    row = row_of(out, "h_γ at Δφ = 3e-3, P0=0.1")
    sigma = float(re.search(r"σ = ([0-9.e+-]+)[,)]", row).group(1))
    assert math.isclose(sigma, x["se"] * math.sqrt(1 + s / 20), rel_tol=0.05), row
    # with 20 seeds per point the paper's sample is budjam's
    for g in A["groups"]:
        g["runs"] = 20
    A["main"]["runs"] = 20 * len(main_L_groups(A))
    r, out = report(fresh(tmp_path, "twenty"), A, J)
    row = row_of(out, "h_γ at Δφ = 3e-3, P0=0.1")
    sigma = float(re.search(r"σ = ([0-9.e+-]+)[,)]", row).group(1))
    assert math.isclose(sigma, x["se"] * math.sqrt(2), rel_tol=0.05), row


def paper_tables():
    return load(os.path.join(REF, "paper", "reanalysed", "analysis.json"))


def verdict_of(out, start):
    return row_of(out, start).split(" | ")[4]


def test_a_finite_size_fit_its_chi2_rejects_prints_no_limit(tmp_path):
    A, J = quick()
    ext = J["finite_size_jamming"]["extrapolation"]
    assert ext["u_J"]["chi2"] > 12.6 and ext["rattler_fraction"]["chi2"] < 12.6 and ext["u_J"]["dof"] == 6
    # the depletion table: one rejected fit (χ² = 40 on 3 dof, above 7.81) and the others accepted
    cols = ["dphi_2", "dphi_2_paper", "dphi_2_none_left", "N_div_2_over_N_J", "G_2_over_Pmax", "G_2_over_Pmax_paper"]
    sizes = [{"L": L, "runs": 20, "N_J": {"mean": 0.77 * L * L},
              **{k: {"value": 0.01, "se": 0.001, "n": 20} for k in cols}} for L in (8, 15, 20, 30, 40)]
    fits = {k: {"sizes": 5, "limit": 0.0123, "limit_se": 4e-4, "chi2": 2.0, "dof": 3,
                "residuals_in_se": [0.5, -0.5, 0.3, -0.3, 0.1]} for k in cols}
    fits["dphi_2"].update(chi2=40.0, residuals_in_se=[3.1, -2.9, 2.5, -3.3, 1.0])
    A["finite_size"] = [{"P0": 1e-3, "P0_label": "0.001", "sizes": sizes, "extrapolation": fits}]
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    rows = [line for line in out.splitlines() if line.startswith("| N → ∞")]
    assert len(rows) == 2, rows
    jam_cells, dep_cells = ([c.strip() for c in row.strip("|").split("|")] for row in rows)
    u = jam_cells[7]  # after "N → ∞", five empty columns and n_J,∞
    assert u.startswith("model rejected (χ²/dof = 86/6") and "+5.4" in u and "±" not in u, u
    assert jam_cells[-1].startswith(f"{ext['rattler_fraction']['limit']:.3g} ± "), jam_cells[-1]
    assert jam_cells[6].startswith(f"{J['finite_size_jamming']['n_J_limit']['value']:.3g} ± ")  # n_J,∞ as before
    assert dep_cells[3].startswith("model rejected (χ²/dof = 40/3") and "+3.1" in dep_cells[3], dep_cells[3]
    assert dep_cells[4].startswith("0.0123 ± 4.0e-04 (χ²/dof = 2/3"), dep_cells[4]


def test_no_n_J_limit_from_a_rattler_fraction_its_chi2_rejects(tmp_path):
    A, J = quick()
    r_fit = J["finite_size_jamming"]["extrapolation"]["rattler_fraction"]
    r_fit.update(chi2=9.59, dof=3)  # above 7.81, the 95 % quantile at 3 dof
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    row = next(line for line in out.splitlines() if line.startswith("| N → ∞"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[-1].startswith("model rejected"), cells[-1]
    assert cells[6].startswith("— (the rattler fraction's fit is rejected"), cells[6]


@pytest.mark.parametrize("shared", [0, 8])
def test_the_report_says_whether_its_sizes_share_seeds_as_the_analysis_counted(tmp_path, shared):
    _, J = quick()
    A = load(os.path.join(REF, "paper", "reanalysed", "analysis.json"))
    assert A.get("finite_size"), "the paper reference has a finite-size table"
    for e in A["finite_size"]:
        e["seeds_shared"] = shared
    J["finite_size_jamming"]["seeds_shared"] = shared
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    for section in ("## Finite size at the depletion point", "## System size", "## Finite size at jamming"):
        text = out.split(section, 1)[1].split("\n## ", 1)[0]
        independent = "the sizes are independent samples" in text
        dependent = "the sizes are not independent samples" in text
        assert (independent, dependent) == (shared == 0, shared > 0), (section, text[:400])


def test_runs_that_never_jammed_are_not_said_to_be_used(tmp_path):
    A, J = quick()
    A["inputs"]["not_finished"] = ["runs/x/L10/P0_1e-5/seed1 (step_limit)"]
    A["inputs"]["never_jammed"] = [f"runs/x/L10/P0_1e-4/seed{k} (step_limit)" for k in range(1, 7)]
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    line = next(line for line in out.splitlines() if line.startswith("Runs:"))
    assert "1 stopped before their last target (runs/x/L10/P0_1e-5/seed1 (step_limit): their recorded states" in line
    assert "6 never jammed and contribute nothing (runs/x/L10/P0_1e-4/seed1 (step_limit)" in line, line


def test_a_value_from_another_box_than_the_papers_number_is_not_judged(tmp_path):
    # the quick preset (L = 8) without a jamming ensemble: u_J and n_J are from L = 8, the paper's from L = 15
    A, J = quick()
    assert A["main_L"] == 8
    r, out = report(tmp_path, A)
    assert r.returncode == 0, r.stderr
    for start in ("Unconstrained fraction at jamming u_J", "Nonrattler density at jamming n_J"):
        assert verdict_of(out, start) == "inconclusive (L = 8, the paper's number is for L = 15)", row_of(out, start)
    for lab in ("no feedback", "P0=0.1", "P0=1e-05"):
        assert verdict_of(out, f"Median N_div(φ_2)/N_J, {lab}") == \
            "inconclusive (L = 8, the paper's number is for L = 20)"
    assert tally_and_cells(out)[0] == tally_and_cells(out)[1]
    # with the jamming ensemble at L = 15 the jamming rows are judged
    r, out = report(fresh(tmp_path, "ensemble"), A, J)
    for start in ("Unconstrained fraction at jamming u_J", "Nonrattler density at jamming n_J"):
        assert re.match(r"(not )?confirmed \(z", verdict_of(out, start)), row_of(out, start)
    # the paper's grid (main L = 15, L = 20 runs): judged without an ensemble too
    r, out = report(fresh(tmp_path, "paper"), paper_tables())
    assert r.returncode == 0, r.stderr
    for start in ("Unconstrained fraction at jamming u_J", "Nonrattler density at jamming n_J",
                  "Median N_div(φ_2)/N_J, no feedback, L = 20"):
        assert re.match(r"(not )?confirmed \(z", verdict_of(out, start)), row_of(out, start)


def test_the_division_rows_print_the_bootstrap_se_beside_the_interval(tmp_path):
    A = paper_tables()
    g = next(g for g in A["groups"] if g["L"] == 20 and g["P0"] is None)
    r, out = report(tmp_path, A)
    assert r.returncode == 0, r.stderr
    cells = row_of(out, "Median N_div(φ_2)/N_J, no feedback, L = 20").split(" | ")
    for cell, key in ((cells[2], "N_div_2_over_N_J"), (cells[3], "N_div_2_over_N_J_paper")):
        m = re.match(r"(\S+) ± (\S+) \[95% CI (\S+), (\S+)\] \(n=(\d+)\)", cell)
        assert m, cell
        s = g[key]
        assert math.isclose(float(m.group(2)), s["se"], rel_tol=0.01) and int(m.group(5)) == s["n"], cell
    # fewer than 5 samples: neither SE nor interval
    for key in ("N_div_2_over_N_J", "N_div_2_over_N_J_paper"):
        g[key]["n"] = 4
    r, out = report(fresh(tmp_path, "few"), A)
    row = row_of(out, "Median N_div(φ_2)/N_J, no feedback, L = 20")
    assert "±" not in row and "CI" not in row, row


def test_no_plus_minus_zero_is_printed_as_an_error_bar(tmp_path):
    A, J = quick()
    g = next(g for g in A["groups"] if g["P0_label"] == "0.001")
    g["dphi_2"] = {"mean": 0.01, "se": 0.0, "n": 20}
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0, r.stderr
    assert not re.search(r"± 0 \(", out), [l for l in out.splitlines() if re.search(r"± 0 \(", l)]


def test_the_crossover_row_says_it_is_not_measured_without_completion_sizes(tmp_path):
    A, J = quick()
    for k in [k for k in A["main"] if k.startswith(("P_star_range", "a_c_"))]:
        del A["main"][k]
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0, r.stderr
    row = next(line for line in out.splitlines() if line.startswith("| Crossover scale P*"))
    assert "not measured" in row and "inconclusive" in row
    printed, counted = tally_and_cells(out)
    assert printed == counted


def test_pooled_rows_take_the_papers_twenty_seeds_when_groups_are_unequal(tmp_path):
    # Seeds 1 … S_k in group k: a statistic pooled over the groups and clustered by seed has n = max S_k
    # distinct seeds, and the paper, with seeds 1 … 20 at every point, had 20 (not 20 · n / mean S_k).
    A, J = quick()
    main = [g for g in A["groups"] if g["L"] == A["main_L"]]
    for k, g in enumerate(main):
        g["runs"] = 8 - k
    A["main"]["runs"] = sum(g["runs"] for g in main)
    # the fraction of packings with Z − 6 < 0, score test at 1/2: n_eff = p(1 − p)/SE² = 96
    A["main"]["dos"]["paper"].update(fraction_Z_minus_6_negative=0.4, fraction_Z_minus_6_negative_se=0.05,
                                     packings=200, seeds=8)
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0, r.stderr
    row = next(line for line in out.splitlines() if line.startswith("| ω* collapses"))
    sigma = float(re.search(r"σ = ([0-9.e+-]+)[,)]", row).group(1))
    assert math.isclose(sigma, math.sqrt(0.25 / 96) * math.sqrt(1 + 8 / 20), rel_tol=0.02), row
    # N_zero = N_u is a predicted relation: budjam's SE alone, whatever the groups
    A["main"]["dos"]["N_zero_minus_N_u"].update(n=8, mean=0.5, se=0.1)
    r, out = report(fresh(tmp_path, "relation"), A, J)
    row = next(line for line in out.splitlines() if line.startswith("| N_zero ≃ N_u"))
    assert "σ = 0.1, z_c = 2.36)" in row, row  # t with 7 degrees of freedom


def test_groups_outside_the_papers_grid_get_rows_without_a_verdict_and_enter_the_trends(tmp_path):
    A, J = quick()
    extra = dict(next(g for g in A["groups"] if g["P0_label"] == "0.001"), P0=3e-3, P0_label="0.003")
    A["groups"].append(extra)
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0, r.stderr
    assert "P0 = 0.003" in out.split("\n| Claim")[0]  # named in the header
    for start in ("φ_2 − φ_J, P0=0.003", "G_2/P_max, P0=0.003", "Median N_div(φ_2)/N_J, P0=0.003"):
        row = row_of(out, start)
        assert "P0 outside the paper's grid" in row, row
    # every group in the trend, ordered by feedback strength: 0.01 (weaker) before 0.003 before 0.001
    trend = row_of(out, "Stronger feedback moves φ_2 closer to φ_J")
    n = len(main_L_groups(A))
    assert f"tested over {n} groups" in trend, trend
    assert trend.index("P0=0.01 ") < trend.index("P0=0.003 ") < trend.index("P0=0.001 "), trend


def test_the_rows_say_why_a_grid_without_feedback_or_without_no_feedback_runs_measures_nothing(tmp_path):
    A, J = quick()
    main_L = A["main_L"]
    fed_only = dict(A, groups=[g for g in A["groups"] if g["P0"] is not None or g["L"] != main_L])
    fed_only["main"] = dict(A["main"], dZ_identity=dict(A["main"]["dZ_identity"], per_P0_unrepopulated_by_run=[]))
    r, out = report(fresh(tmp_path, "fed"), fed_only, J)
    assert r.returncode == 0, r.stderr
    assert "not measured (no no-feedback runs at this L" in row_of(out, "ΔZ = ΔZ₀(P) + 2(u_J − u)")
    assert "no feedback is the weakest" not in out
    A["main"].pop("P_star_range_paper", None)
    A["main"].pop("plateau_P0", None)
    none_only = dict(A, groups=[g for g in A["groups"] if g["P0"] is None or g["L"] != main_L])
    r, out = report(fresh(tmp_path, "none"), none_only, J)
    assert r.returncode == 0, r.stderr
    assert "P0=None" not in out
    assert "no feedback group in this grid" in row_of(out, "Rigidity plateau")
    assert "no feedback group in this grid" in row_of(out, "Crossover scale P*")
    assert "tested over 1 group," in row_of(out, "Stronger feedback moves φ_2 closer to φ_J")


def test_growth_rate_rows_name_the_missing_target(tmp_path):
    A, J = quick()
    with open(os.path.join(REF, "quick", "reanalysed", "targets.csv")) as f:
        lines = f.read().splitlines()
    col = lines[0].split(",").index("dphi")
    without = "\n".join([lines[0]] + [x for x in lines[1:] if float(x.split(",")[col]) != 3e-3]) + "\n"
    r, out = report(tmp_path, A, J, targets=without)
    assert r.returncode == 0, r.stderr
    for start in ("h_γ at Δφ = 3e-3, P0=0.1", "Π(g) at Δφ = 3e-3, P0=0.01"):
        assert "no target at Δφ = 3·10⁻³ at this L" in row_of(out, start), start


def test_the_n_zero_row_counts_packings_and_says_why_its_slope_has_no_error_bar(tmp_path):
    A, J = quick()
    A["main"]["dos"]["N_zero_equals_N_u"] = 1.0
    A["main"]["dos"]["packings"] = 45
    A["main"]["dos"]["paper"]["N_zero_vs_N_u"].update(seeds=5, slope_se=0, slope_through_origin=1.0)
    r, out = report(tmp_path, A, J)
    row = row_of(out, "N_zero ≃ N_u")
    assert "N_zero = N_u in 45 of 45 distinct packings" in row, row
    assert "every resample of the seeds gives this slope" in row and "n seeds < 5" not in row, row


def test_a_paper_preset_with_its_grid_overridden_does_not_claim_the_papers_grid(tmp_path):
    A, J = quick()
    r, out = report(tmp_path, A, J, preset="paper")
    assert r.returncode == 0, r.stderr
    assert "Preset paper with its grid overridden (L = 8; not 20 runs at every point" in out
    assert "Preset paper: the paper's grid" not in out
    # the committed paper tables are the paper's grid
    args = [sys.executable, os.path.join(SRC, "scripts", "report.py"), "--tables",
            os.path.join(REF, "paper", "reanalysed"), "--jamming", os.path.join(REF, "jamming", "reanalysed"),
            "--figures", str(tmp_path / "figures"), "--preset", "paper", "--out", str(tmp_path / "P.md")]
    r = subprocess.run(args, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "Preset paper: the paper's grid" in (tmp_path / "P.md").read_text()


def test_a_figure_the_tables_cannot_give_is_named_with_its_reason(tmp_path):
    A, J = quick()
    figures = tmp_path / "figures"
    figures.mkdir()
    (figures / "figE1.not-drawn").write_text("Fig. E1: no run has a target at Δφ = 3·10⁻³ (add it to TARGETS)\n")
    r, out = report(tmp_path, A, J)
    assert "figE1 (not drawn: Fig. E1: no run has a target at Δφ = 3·10⁻³" in row_of(out, "h_γ at Δφ = 3e-3, P0=0.1")


@pytest.mark.parametrize("preset", ["paper", "quick"])
def test_the_committed_survival_tables_are_what_the_estimators_write_from_their_records(budjam_exe, tmp_path, preset):
    # `analyse --tables` rebuilds every Kaplan–Meier curve from its steps: a committed table written by an
    # older estimator (a Greenwood band in the tail, say) differs. (The jamming ensemble's analysis takes a
    # minute for its growth-only baseline; its survival table is held to the band rule below.)
    tables = os.path.join(REF, preset, "tables")
    r = subprocess.run([budjam_exe, "analyse", "--tables", tables, "--out", str(tmp_path / "re")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    import csv
    with open(os.path.join(tables, "survival.csv")) as f:
        committed = list(csv.DictReader(f))
    with open(tmp_path / "re" / "survival.csv") as f:
        rebuilt = list(csv.DictReader(f))
    # the committed columns, value for value (a table may predate a column analyse adds)
    columns = list(committed[0])
    differ = [k for k, (a, b) in enumerate(zip(committed, rebuilt)) if any(a[c] != b[c] for c in columns)]
    assert len(committed) == len(rebuilt) and not differ, f"{len(differ)} rows differ, the first: line {differ[:1]}"


def test_no_committed_survival_table_has_a_band_where_fewer_than_five_buds_are_at_risk():
    import glob
    files = glob.glob(os.path.join(REF, "*", "*", "survival.csv"))
    assert len(files) >= 6, files
    import csv
    for name in files:
        with open(name) as f:
            rows = list(csv.DictReader(f))
        assert rows, name
        banded = [r for r in rows if float(r["at_risk"]) < 5 and any(r[c] for c in ("se", "lo", "hi"))]
        assert not banded, (name, banded[:3])


def test_jamming_states_that_share_seeds_take_their_error_by_seed(budjam_exe, tmp_path):
    # the quick grid's groups grow seeds 1 … 8 alike up to jamming: 20 states of 8 seeds at L = 8
    tables = os.path.join(REF, "quick", "tables")
    r = subprocess.run([budjam_exe, "analyse", "--tables", tables, "--out", str(tmp_path / "re")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    A = load(tmp_path / "re" / "analysis.json")
    shared = [k for k in ("u_J", "phi_J", "n_J", "N_J") if A["main"][k]["seeds"] < A["main"][k]["n"]]
    assert shared, "the quick grid no longer has states that share seeds: this test checks nothing"
    for k in shared:
        stat = A["main"][k]
        assert stat["se"] == stat["bootstrap_se_by_seed"] is not None, (k, stat)


def test_every_point_of_the_no_feedback_branch_carries_its_own_error(budjam_exe, tmp_path):
    # the no-feedback targets at Δφ = 1e-2 kept for only 3 runs (the others stopped before their last
    # target): that point leaves the branch, rather than taking the SE of its neighbours
    import csv
    tables = tmp_path / "tables"
    src = os.path.join(REF, "quick", "tables")
    os.mkdir(tables)
    for name in os.listdir(src):
        with open(os.path.join(src, name)) as f:
            (tables / name).write_text(f.read())
    with open(tables / "targets.csv") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    P0, dphi, run = header.index("P0"), header.index("dphi"), header.index("run")
    kept = sorted({r[run] for r in body if r[P0] in ("", "none") and float(r[dphi]) == 1e-2})[:3]
    body = [r for r in body if not (r[P0] in ("", "none") and float(r[dphi]) == 1e-2 and r[run] not in kept)]
    with open(tables / "targets.csv", "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows([header] + body)
    with open(tables / "runs.csv") as f:
        runs = list(csv.reader(f))
    R, S = runs[0].index("run"), runs[0].index("status")
    stopped = {r[run] for r in rows[1:] if r[P0] in ("", "none") and float(r[dphi]) == 1e-2} - set(kept)
    for r in runs[1:]:
        if r[R] in stopped:
            r[S] = "step_limit"
    with open(tables / "runs.csv", "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(runs)
    out = {}
    for name, t in (("all", src), ("thinned", tables)):
        r = subprocess.run([budjam_exe, "analyse", "--tables", str(t), "--out", str(tmp_path / name)],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        out[name] = load(tmp_path / name / "analysis.json")["dZ0_branch"]
    for branches in out.values():
        for b in branches:
            assert len(b["points_P_dZ"]) == len(b["points_P_se"]), b
    assert len(out["thinned"][0]["points_P_dZ"]) == len(out["all"][0]["points_P_dZ"]) - 1


def test_p_dagger_takes_its_error_from_the_seeds_not_from_the_scatter_of_groups_about_a_line(budjam_exe, tmp_path):
    # Six feedback groups of one seed list (no feedback and P0 = 0.1 relabelled 3e-3 and 3e-4), every run
    # depleted with P_2 = f(P0) c_seed: each draw of seeds shifts every ln⟨P_2⟩ by one constant, so the
    # slope, and P†, do not move (SE 0), though ln f is no line in 1/P0 (the groups scatter about it).
    import csv
    src, tables = os.path.join(REF, "quick", "tables"), tmp_path / "tables"
    os.mkdir(tables)
    relabel = {"": "0.003", "none": "0.003", "0.1": "0.0003"}
    for name in ("runs.csv", "targets.csv", "dos.csv"):
        with open(os.path.join(src, name)) as f:
            rows = list(csv.reader(f))
        c = rows[0].index("P0")
        for r in rows[1:]:
            r[c] = relabel.get(r[c], r[c])
        if name == "runs.csv":
            h = rows[0]
            for r in rows[1:]:
                inv = 1.0 / float(r[c])
                r[h.index("P_2")] = repr(math.exp(-0.3 * math.sqrt(inv)) * (1.0 + 0.1 * int(r[h.index("seed")])))
                if not r[h.index("phi_2")]:
                    r[h.index("phi_2")] = r[h.index("phi_J")]
        with open(tables / name, "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows(rows)
    r = subprocess.run([budjam_exe, "analyse", "--tables", str(tables), "--out", str(tmp_path / "out")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    M = load(tmp_path / "out" / "analysis.json")["main"]
    assert M["P_dagger_points"] == 6 and M["P_dagger_seeds"] >= 5, M
    assert M["P_dagger_se"] is not None and M["P_dagger_se"] <= 1e-9 * abs(M["P_dagger"]), M


def test_admitted_runs_without_an_eq14_prediction_are_named_as_such(tmp_path):
    """The paper's φ_2 summary keeps the admitted runs with a prediction: where none has one, the
    report says so, not that G_2 ≤ 0 left nothing."""
    A, J = quick()
    g = main_L_groups(A)[0]
    for key in ("dphi_2_paper", "P_2_over_Pmax_paper"):
        g[key].update(mean=None, se=None, n=0, admitted=7, runs=9, predicted=0)
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0, r.stderr
    lines = [line for line in out.splitlines() if "7 of 9 runs admitted" in line]
    assert len(lines) == 2  # the Eq. 14 row and the P_2/P_max row of that group
    for line in lines:
        assert "none with an Eq. 14 prediction" in line and "G_2 > 0" not in line, line


@pytest.mark.parametrize("missing", ["0.001", "none"])
def test_a_paper_p0_without_runs_gets_an_inconclusive_row_and_the_header_names_it(tmp_path, missing):
    A = paper_tables()
    A["groups"] = [g for g in A["groups"] if g["P0_label"] != missing]
    r, out = report(tmp_path, A, preset="paper")
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    name = "no feedback" if missing == "none" else f"P0={missing}"
    row = row_of(out, f"Every per-P0 claim at {name} ")
    assert row.split(" | ")[4].startswith("inconclusive (not measured: no runs at " + name), row
    for L in (8, 15, 20):
        assert f"no runs at L = {L} for P0 = {missing}" in out
    # its per-P0 rows are gone, the others stay
    assert not any(line.startswith(f"| φ_2 − φ_J, {name}:") for line in out.splitlines())
    assert sum(line.startswith("| φ_2 − φ_J, ") for line in out.splitlines()) == 5


def test_eq14_tests_the_sign_of_the_overestimate_and_prints_its_size(tmp_path):
    r, out = report(tmp_path, paper_tables(), preset="paper")
    assert r.returncode == 0, r.stderr
    rows = [line for line in out.splitlines() if line.startswith("| φ_2 − φ_J, ")]
    assert len(rows) == 6
    for row in rows:
        cells = row.split(" | ")
        assert cells[1] == "a small systematic overestimate by the theory"
        assert 'the sign is tested, the paper gives "small" no size' in cells[4], row
        assert len(re.findall(r"prediction/simulation \d", row)) == 2, row  # both definitions


def test_kaplan_meier_without_survival_records_says_not_measured(tmp_path):
    A = paper_tables()
    for g in A["groups"]:
        g["pooled_survival"] = {"events": 0, "records": 0, "epsilon": 0.005, "a_eps": None, "integral_S": None}
    r, out = report(tmp_path, A, preset="paper")
    assert r.returncode == 0, r.stderr
    row = row_of(out, "Kaplan–Meier a_ε")
    assert "not measured (no survival records)" in row and "completions" not in row.split(" | ")[2], row


def test_a_state_some_runs_stopped_before_is_not_measured_and_not_judged(tmp_path):
    # analysis.json keeps no value of φ_2 or of the none-left state where runs stopped first (right-censored)
    A = paper_tables()
    g = next(g for g in A["groups"] if g["L"] == 20 and g["P0_label"] == "0.001")
    for key in ("N_div_2_over_N_J", "N_div_2_over_N_J_paper"):
        g[key] = {**g[key], "n": 12, "median": None, "se": None, "ci95": [None, None], "censored": 8}
    r, out = report(tmp_path, A)
    assert r.returncode == 0, r.stderr
    cells = row_of(out, "Median N_div(φ_2)/N_J, P0=0.001, L = 20").split(" | ")
    for cell in cells[2:4]:
        assert "not measured: 12 of 20 runs reached this state" in cell, cell
    assert cells[4].startswith("inconclusive") and "right-censored" in cells[4], cells[4]


def test_the_isostatic_count_is_what_the_jamming_tables_hold_and_its_verdict_counts_packings(tmp_path):
    A, J = quick()[0], reanalysed_jamming()
    with open(os.path.join(REF, "jamming", "tables", "runs.csv"), newline="") as f:
        rows = [r for r in csv.DictReader(f) if float(r["L"]) == 15 and r["dZ_J"]]
    excess = [round(float(r["dZ_J"]) * float(r["N_nr_J"]) / 2) for r in rows]
    iso = next(s for s in J["sizes"] if s["L"] == 15)["isostatic_J"]
    assert (iso["packings"], iso["isostatic"]) == (len(excess), excess.count(0))
    row = lambda out: row_of(out, "Modified Maxwell count at jamming")
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0, r.stderr
    assert f"{excess.count(0)} of {len(excess)} packings isostatic" in row(out)
    # the verdict counts packings off isostatic, whatever their excess (a z of the mean would be 1 here)
    g = next(s for s in J["sizes"] if s["L"] == 15)
    for k, most, word in ((199, 1, "confirmed"), (199, 40, "confirmed"), (150, 1, "not confirmed")):
        g["isostatic_J"] = {"fraction": k / 200, "packings": 200, "isostatic": k, "seeds": 200,
                            "most_excess_contacts": most}
        r, out = report(fresh(tmp_path, f"iso{k}_{most}"), A, J)
        assert row(out).split(" | ")[4].startswith(word + " ("), row(out)


@pytest.mark.parametrize("theirs, why", [(None, None), (["0123456789abcdef"], "its runs are of another jamming model"),
                                         ([], "tables without jamming_model")])
def test_the_jamming_rows_come_from_an_ensemble_only_of_these_runs_jamming_model(tmp_path, theirs, why):
    A, J = quick()[0], reanalysed_jamming()
    assert A["jamming_models"] == J["jamming_models"] and len(A["jamming_models"]) == 1
    if theirs is not None:
        J["jamming_models"] = theirs
    r, out = report(tmp_path, A, J)
    assert r.returncode == 0, r.stderr
    u_J = row_of(out, "Unconstrained fraction at jamming u_J")
    if why is None:
        assert "(jamming ensemble, L = 15" in u_J, u_J
    else:
        assert "this preset's runs at L = 8 (the jamming ensemble of" in u_J and why in u_J, u_J
        assert "(n=200)" not in u_J, u_J


def test_without_the_ensembles_l15_or_with_it_refused_the_rows_and_the_size_table_say_whose_they_are(tmp_path):
    A, J = quick()[0], reanalysed_jamming()
    # an ensemble without L = 15: the rows are this preset's, the finite-size table still the ensemble's
    J15 = {**J, "sizes": [s for s in J["sizes"] if s["L"] != 15]}
    r, out = report(tmp_path, A, J15)
    assert r.returncode == 0, r.stderr
    u_J = row_of(out, "Unconstrained fraction at jamming u_J")
    assert "has no L = 15" in u_J and "no jamming ensemble given" not in u_J, u_J
    assert "The jamming states of the jamming ensemble" in out
    # refused: the rows and the size table are this preset's own (or absent), never the ensemble's
    A2 = {**A, "finite_size_jamming": J["finite_size_jamming"]}  # as if this preset had several sizes
    r, out = report(fresh(tmp_path, "refused"), A2, {**J, "jamming_models": ["0123456789abcdef"]})
    assert r.returncode == 0, r.stderr
    assert "The jamming states of this preset's runs (the jamming ensemble of" in out
    r, out = report(fresh(tmp_path, "refused_one_size"), A, {**J, "jamming_models": ["0123456789abcdef"]})
    assert "## Finite size at jamming" not in out and 'see "Finite size at jamming"' not in out


def test_delta_z_j_without_an_ensemble_counts_this_presets_jamming_states_also_without_no_feedback_runs(tmp_path):
    A = quick()[0]
    A["groups"] = [g for g in A["groups"] if g["P0"] is not None]
    r, out = report(tmp_path, A)
    assert r.returncode == 0, r.stderr
    iso = A["main"]["isostatic_J"]
    row = row_of(out, "Modified Maxwell count at jamming")
    assert f"{iso['isostatic']} of {iso['packings']} packings isostatic" in row, row
    assert "not counted" not in row, row
