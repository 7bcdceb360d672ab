"""The verdict rule of the reproduction reports (scripts/verdicts.py): each branch on its edge."""
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.environ.get("BUDJAM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", "..")),
                                "scripts"))
import verdicts as v  # noqa: E402


def test_no_verdict_below_five_samples_whatever_the_agreement():
    assert v.compare(0.23, 0.0, 4, v.quoted(0.23, 0.01)).word == "inconclusive"
    assert v.compare(0.23, 0.01, 5, v.quoted(0.23, 0.01)).word == "confirmed"
    assert v.compare(0.23, None, 20, v.quoted(0.23, 0.01)).word == "inconclusive"


def test_a_quoted_number_allows_what_rounds_to_it():
    c = v.quoted(0.23, 0.01)
    assert c.distance(0.2349) == 0 and c.distance(0.2251) == 0
    assert math.isclose(c.distance(0.24), 0.005)


def test_the_combined_error_adds_the_papers_sampling_error():
    # same number of samples: σ = √2 s_b; z just below and above 2 (z_c = 2 from 62 samples on)
    s = 0.01
    c = v.quoted(0.5, 0.0)
    assert v.compare(0.5 + 2 * math.sqrt(2) * s * 0.999, s, 100, c).word == "confirmed"
    assert v.compare(0.5 + 2 * math.sqrt(2) * s * 1.001, s, 100, c).word == "not confirmed"
    # the paper's 20 samples against budjam's 200: σ = s_b √(1 + 10)
    assert v.compare(0.5 + 2 * math.sqrt(11) * s * 0.999, s, 200, c, n_paper=20).word == "confirmed"
    assert v.compare(0.5 + 2 * math.sqrt(11) * s * 1.001, s, 200, c, n_paper=20).word == "not confirmed"


def test_a_relation_the_theory_predicts_is_judged_on_budjams_error_alone():
    # no paper sample behind a predicted relation: σ = s_b, whatever budjam's n
    s = 0.01
    c = v.quoted(0.0, 0.0)
    for n in (5, 20, 200):
        z_c = v.z_critical(n)
        assert v.compare(z_c * s * 0.999, s, n, c, n_paper=v.THEORY).word == "confirmed"
        assert v.compare(z_c * s * 1.001, s, n, c, n_paper=v.THEORY).word == "not confirmed"
    # the same estimate is confirmed once a paper sample's error is added: the two rules differ
    assert v.compare(2 * s * 1.001, s, 200, c).word == "confirmed"
    assert v.compare(0.0, s, 4, c, n_paper=v.THEORY).word == "inconclusive"


def test_a_fraction_within_noise_of_a_bound_is_consistent_with_it():
    # 48.6 % of 940 packings against "more than half": 1 SE below, not a refutation
    p, n = 0.486, 940
    se = math.sqrt(p * (1 - p) / n)
    assert v.compare(p, se, n, v.at_least(0.5)).word == "confirmed"
    assert v.compare(0.40, math.sqrt(0.4 * 0.6 / n), n, v.at_least(0.5)).word == "not confirmed"


def test_ranges_and_bounds():
    assert v.compare(0.15, 0.01, 20, v.interval(0.2, 1.0)).word == "not confirmed"
    assert v.compare(0.19, 0.01, 20, v.interval(0.2, 1.0)).word == "confirmed"
    assert v.compare(0.0, 0.001, 20, v.at_most(3e-3)).word == "confirmed"
    assert v.compare(0.02, 0.001, 20, v.at_most(3e-3)).word == "not confirmed"


def test_trend_confirmed_refuted_or_unresolved():
    down = [(0.04, 0.002, 20), (0.03, 0.002, 20), (0.01, 0.001, 20)]
    assert v.trend(down, increasing=False).word == "confirmed"
    assert v.trend(down, increasing=True).word == "not confirmed"
    flat = [(0.04, 0.01, 20), (0.039, 0.01, 20), (0.041, 0.01, 20)]
    assert v.trend(flat, increasing=False).word == "inconclusive"
    # a step against the trend by more than 2σ refutes it even when the ends agree with it
    bump = [(0.04, 0.001, 20), (0.05, 0.001, 20), (0.01, 0.001, 20)]
    assert v.trend(bump, increasing=False).word == "not confirmed"
    assert v.trend([(0.04, 0.001, 4), (0.01, 0.001, 20)], increasing=False).word == "inconclusive"


def test_report_refuses_jamming_tables_that_are_not_there(tmp_path):
    import subprocess
    src = os.environ.get("BUDJAM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
    ref = os.path.join(src, "data", "reference", "paper")
    out = tmp_path / "R.md"
    r = subprocess.run([sys.executable, os.path.join(src, "scripts", "report.py"), "--tables",
                        os.path.join(ref, "reanalysed"), "--figures", os.path.join(ref, "figures"), "--preset", "paper", "--jamming", str(tmp_path / "none"),
                        "--out", str(out)], capture_output=True, text=True)
    assert r.returncode != 0
    assert r.stderr.count("\n") == 1 and "--jamming" in r.stderr
    assert not out.exists()


def test_no_verdict_without_a_finite_estimate_or_error_bar_and_the_reason_is_true():
    c = v.quoted(0.23, 0.01)
    for est, se, n in ((math.nan, 0.01, 20), (math.inf, 0.01, 20), (None, 0.01, 20),
                       (0.23, math.nan, 20), (0.23, None, 20), (0.23, -0.01, 20), (0.23, 0.01, math.nan),
                       (0.23, 0.01, None)):
        r = v.compare(est, se, n, c)
        assert r.word == "inconclusive", (est, se, n, r)
        assert "nan" not in r.why and "z =" not in r.why
    # n = 20 is not "< 5": the reason names what is missing
    assert "error bar" in v.compare(0.23, None, 20, c).why and "< 5" not in v.compare(0.23, None, 20, c).why
    assert "estimate" in v.compare(math.nan, 0.01, 20, c).why
    for n in (0, 1, 4):
        assert v.compare(0.23, 0.01, n, c).why == f"n = {n} < 5"
    pts = [(0.04, 0.002, 20), (math.nan, 0.002, 20), (0.01, 0.001, 20)]
    assert v.trend(pts, increasing=False).word == "inconclusive"
    assert v.trend([(0.04, None, 20), (0.01, 0.001, 20)], increasing=False).word == "inconclusive"


def test_zero_spread_is_never_a_division_into_a_verdict_of_chance():
    # a negative estimate against an interval: the distance to its near end
    assert v.compare(-0.1, 0.1, 20, v.interval(0.2, 1.0)).word == "not confirmed"
    assert v.compare(-0.1, 0.2, 20, v.interval(0.2, 1.0)).word == "confirmed"
    # a trend is judged by the same rule as one claim: a group with an SE of 0 has no error bar, so a
    # step to or from it would be z = 0 or ±∞ by the tie alone, whichever way it goes
    for points in ([(1.0, 0.0, 8), (1.0, 0.0, 8)], [(1.0, 0.0, 8), (2.0, 0.0, 8)], [(1.0, 0.1, 8), (0.5, 0.0, 10)]):
        for increasing in (True, False):
            r = v.trend(points, increasing=increasing)
            assert r.word == "inconclusive" and "SE = 0" in r.why, (points, r)


def test_a_proportion_at_zero_or_one_keeps_a_finite_error():
    # the score test: the SE is the one of the claim's boundary p0 = 1/2, √(p0(1 − p0)/n), not the
    # Wald SE √(p̂(1 − p̂)/n), which is 0 at p̂ = 0 or 1
    half = v.at_least(0.5)
    n = 40
    s = math.sqrt(0.25 / n)
    r = v.proportion(0.0, n, half)
    assert r.word == "not confirmed" and "inf" not in r.why
    assert math.isclose(float(r.why.split("z = ")[1].split(",")[0]), 0.5 / (math.sqrt(2) * s), rel_tol=0.02)
    r = v.proportion(1.0, n, half)
    assert r.word == "confirmed" and "σ = 0)" not in r.why
    # a few below one half out of 40 is within noise of it; far below is not
    assert v.proportion(0.45, n, half).word == "confirmed"
    assert v.proportion(0.2, n, half).word == "not confirmed"
    r = v.proportion(0.45, n, half)
    assert math.isclose(float(r.why.split("z = ")[1].split(",")[0]), 0.05 / (math.sqrt(2) * s), rel_tol=0.02)
    # against a bound of 1/2 from above, p̂ = 1 is a finite distance in finite units
    r = v.proportion(1.0, n, v.at_most(0.5))
    assert r.word == "not confirmed" and "inf" not in r.why
    # the paper's sample enters as for every other row; fewer than 5: no verdict
    assert v.proportion(0.45, n, half, n_paper=20).why != v.proportion(0.45, n, half).why
    assert v.proportion(0.0, 4, half).word == "inconclusive"
    assert v.proportion(math.nan, n, half).word == "inconclusive"


def test_the_wilson_interval_never_has_zero_width():
    for p in (0.0, 1.0, 0.3):
        lo, hi = v.wilson(p, 20)
        assert 0.0 <= lo <= p <= hi <= 1.0 and hi - lo > 0.05
    lo, hi = v.wilson(0.0, 20)
    assert lo == 0.0 and math.isclose(hi, 0.161, abs_tol=1e-3)  # 1.96²/(20 + 1.96²)


def z_of(r):
    return float(r.why.split("z = ")[1].split(",")[0])


def test_a_printed_z_is_on_the_same_side_of_its_critical_value_as_its_verdict():
    s = 0.01
    sigma = math.sqrt(2) * s  # same n as the paper
    c = v.quoted(0.5, 0.0)
    for n in (100, 20, 5):
        z_c = v.z_critical(n)
        for dz in (-1.5, -0.01, -0.001, -0.0001, 0.0, 0.00001, 0.0001, 0.001, 0.004, 0.04, 0.05, 0.4, 84.0):
            r = v.compare(0.5 + (z_c + dz) * sigma, s, n, c)
            if r.word == "confirmed":
                assert z_of(r) <= z_c, r
            else:
                assert r.word == "not confirmed" and z_of(r) > z_c, r
    assert str(v.compare(0.5 + 2.04 * sigma, s, 100, c)) == "not confirmed (z = 2.04, σ = 0.014)"
    assert str(v.compare(0.5 + 2.04 * sigma, s, 20, c)) == "confirmed (z = 2.04, σ = 0.014, z_c = 2.09)"
    # a trend: its first-to-last z decides "confirmed" (> z_c), its worst step "not confirmed" (< −z_c)
    up = v.trend([(0.0, 0.01, 100), (2.004 * math.sqrt(2) * 0.01, 0.01, 100)], increasing=True)
    assert up.word == "confirmed" and float(up.why.split("first to last z = ")[1].split(",")[0]) > 2, up
    down = v.trend([(0.0, 0.01, 100), (2.004 * math.sqrt(2) * 0.01, 0.01, 100)], increasing=False)
    assert down.word == "not confirmed" and float(down.why.split("worst step z = ")[1]) < -2, down
    # from 20 samples per group the same step resolves nothing (z_c = 2.09)
    assert v.trend([(0.0, 0.01, 20), (2.004 * math.sqrt(2) * 0.01, 0.01, 20)], increasing=True).word == "inconclusive"


def test_the_critical_z_is_students_t_at_97_5_percent_never_below_two():
    for dof, t in ((4, 2.7764), (9, 2.2622), (19, 2.0930), (29, 2.0452), (120, 1.9799)):
        assert abs(v.t_quantile(dof) - t) < 1e-3, dof
    assert abs(v.t_quantile(1e12) - 1.959964) < 1e-6
    assert abs(v.z_critical(5) - 2.7764) < 1e-3 and v.z_critical(200) == 2.0
    # five paired differences at z = 2.05 are consistent with none (two-sided p ≈ 0.11)
    assert v.paired([0.9, 1.1, 0.2, 1.3, -0.35]).word == "confirmed"
    ups = [{s: 0.0 for s in range(5)}, {0: 0.9, 1: 1.1, 2: 0.2, 3: 1.3, 4: -0.35}]
    assert v.paired_trend(ups, increasing=True).word == "inconclusive"


def test_a_zero_standard_error_from_five_or_more_samples_gives_no_verdict():
    # every value tied: SE 0 is no error bar, and z would be 0 or ∞ by the tie alone
    for est, claim in ((0.0, v.quoted(0.0, 0.0)), (1e-9, v.quoted(0.0, 0.0)), (-0.5, v.at_least(0.0)),
                       (-0.5, v.at_most(0.0)), (0.23, v.quoted(0.23, 0.01))):
        r = v.compare(est, 0.0, 8, claim)
        assert r.word == "inconclusive" and "SE = 0" in r.why and "n = 8" in r.why, r
        assert "z =" not in r.why and "inf" not in r.why
        assert v.compare(est, 0.0, 8, claim, n_paper=20).word == "inconclusive"
    # fewer than 5 samples: the reason stays the count
    assert v.compare(0.0, 0.0, 4, v.quoted(0.0, 0.0)).why == "n = 4 < 5"


def test_a_proportion_at_a_claim_boundary_of_zero_or_one_keeps_a_finite_error():
    # p0 = 0 or 1: the score SE √(p0(1 − p0)/n) is 0 there, so the SE is that of Wilson's interval at p̂
    n = 40
    for p, claim in ((0.0, v.at_most(0.0)), (0.025, v.at_most(0.0)), (0.5, v.at_most(0.0)),
                     (1.0, v.at_least(1.0)), (0.9, v.at_least(1.0)), (0.0, v.quoted(0.0, 0.0)),
                     (1.0, v.quoted(1.0, 0.0))):
        r = v.proportion(p, n, claim)
        assert r.word in ("confirmed", "not confirmed"), (p, r)
        assert "inf" not in r.why and "σ = 0)" not in r.why and math.isfinite(z_of(r)), (p, r)
        lo, hi = v.wilson(p, n)
        se = (hi - lo) / (2 * 1.96)
        assert math.isclose(z_of(r), claim.distance(p) / (math.sqrt(2) * se), rel_tol=0.01, abs_tol=1e-12), (p, r)
    assert v.proportion(0.0, n, v.at_most(0.0)).word == "confirmed"
    assert v.proportion(0.5, n, v.at_most(0.0)).word == "not confirmed"
    # the boundary nearest to p̂ is inside (0, 1): the score SE as before
    r = v.proportion(0.0, n, v.interval(0.5, 1.0))
    assert math.isclose(z_of(r), 0.5 / (math.sqrt(2) * math.sqrt(0.25 / n)), rel_tol=0.01)


def test_a_paper_sample_size_that_is_not_a_positive_number_gives_no_verdict():
    c = v.quoted(0.5, 0.01)
    for n_p in (0, 0.0, -5, -0.5, math.nan, math.inf, -math.inf):
        for r in (v.compare(0.51, 0.01, 20, c, n_paper=n_p), v.proportion(0.4, 40, v.at_least(0.5), n_paper=n_p)):
            assert r.word == "inconclusive" and "n_p" in r.why and "z =" not in r.why, (n_p, r)
    # None is "the same as budjam's n"
    assert v.compare(0.53, 0.01, 20, c, n_paper=None).why == v.compare(0.53, 0.01, 20, c, n_paper=20).why
    assert v.compare(0.53, 0.01, 20, c, n_paper=None).word in ("confirmed", "not confirmed")


def test_the_chi2_quantile_is_the_tabulated_one_and_decides_rejection():
    # 95 % points of χ² (any statistics table)
    for dof, q in ((1, 3.841), (2, 5.991), (3, 7.815), (6, 12.592), (10, 18.307), (30, 43.773), (100, 124.342)):
        assert math.isclose(v.chi2_quantile(dof), q, abs_tol=1.5e-3), dof
    assert math.isclose(v.chi2_quantile(6, 0.99), 16.812, abs_tol=1.5e-3)
    assert v.fit_rejected(86, 6) is True and v.fit_rejected(12.5, 6) is False and v.fit_rejected(8.4, 6) is False
    assert v.fit_rejected(5.0, 0) is None and v.fit_rejected(math.nan, 6) is None and v.fit_rejected(None, 6) is None


def test_two_protocols_on_the_same_seeds_are_judged_by_their_paired_differences():
    # the same results: confirmed; one seed that differs is judged by the spread of the differences
    assert v.paired([0.0] * 5).word == "confirmed"
    assert v.paired([0.0] * 4).word == "inconclusive"  # n < 5, even when identical
    r = v.paired([0.1, 0.12, 0.09, 0.11, 0.1])
    assert r.word == "not confirmed" and "z =" in r.why  # a consistent shift: z ≫ 2
    assert v.paired([0.1, -0.12, 0.09, -0.11, 0.02]).word == "confirmed"
    # z is |mean| over the paired SE, no second sampling error
    d = [1.0, 2.0, 3.0, 4.0, 5.0]
    se = math.sqrt(sum((x - 3.0) ** 2 for x in d) / 4 / 5)
    assert f"σ = {v._fmt(se)}" in v.paired(d).why
    assert v.paired([0.3] * 6).word == "inconclusive"  # SE = 0 without identity: no error bar
    assert v.paired([0.1, math.nan, 0.2, 0.1, 0.0]).word == "inconclusive"


def adaptive_study(root, seeds, shift=0.0):
    """A hand-built OUT tree of scripts/adaptive_dt_study.sh: one target, P and G per seed, the adaptive
    runs' P moved by `shift` times the seed's own scatter."""
    import json
    import pathlib
    for protocol in ("nominal", "adaptive"):
        for s in seeds:
            d = pathlib.Path(root) / protocol / "P0_1e-3" / f"seed{s}"
            (d / "packings").mkdir(parents=True)
            P = 1e-3 * (1 + 0.1 * math.sin(s)) + (shift * 1e-5 * (1 + 0.2 * math.cos(3 * s)) if protocol == "adaptive" else 0)
            target = {"index": 1, "dphi": 1e-3, "P": P, "Z": 6.0, "u": 0.2, "N_div": 0}
            (d / "summary.json").write_text(json.dumps({"status": "finished", "targets": [target], "accepted_steps": 10,
                                                        "rejected_steps": 0, "step_J": 5}))
            (d / "packings" / "target_1.moduli.json").write_text(json.dumps({"G": 0.01, "energy_minimum": True}))


def adaptive_row(tmp_path, seeds, shift=0.0):
    import subprocess
    import sys
    root = tmp_path / f"study{len(seeds)}_{shift}"
    adaptive_study(root, seeds, shift)
    out = subprocess.run([sys.executable, str(pathlib_src() / "scripts" / "adaptive_dt_table.py"), str(root)],
                         capture_output=True, text=True, check=True).stdout
    return next(line for line in out.splitlines() if line.startswith("| 1e-3 |"))


def pathlib_src():
    import pathlib
    return pathlib.Path(__file__).resolve().parents[2]


def test_the_adaptive_step_table_judges_agreement_by_the_one_rule(tmp_path):
    # the same results in every seed: confirmed; a shift of the adaptive runs' P: not confirmed, naming P
    assert adaptive_row(tmp_path, range(1, 7)).endswith("| confirmed |")
    row = adaptive_row(tmp_path, range(1, 7), shift=1.0)
    assert "not confirmed: P (z =" in row, row
    # fewer than 5 paired seeds: no verdict and no ± (the old table said "yes" from 2 seeds)
    row = adaptive_row(tmp_path, range(1, 3), shift=1.0)
    assert "inconclusive" in row and "(n = 2 < 5)" in row and "±" not in row, row


def test_a_trend_over_groups_of_the_same_seeds_is_paired_by_seed():
    # Each seed's value falls by 0.001 from group to group, while the seeds spread by 0.01: groups
    # of the same seeds resolve the fall that independent groups' SEs (0.01/√20 each) cannot.
    base = {str(s): 0.05 + 0.01 * math.sin(s) for s in range(1, 21)}
    groups = [{s: x - 0.001 * k + 1e-5 * math.cos(7 * int(s) + k) for s, x in base.items()} for k in range(3)]
    unpaired = [(statistics.mean(g.values()), statistics.stdev(g.values()) / math.sqrt(20), 20) for g in groups]
    assert v.trend(unpaired, increasing=False).word == "inconclusive"
    paired = v.paired_trend(groups, increasing=False)
    assert paired.word == "confirmed" and "paired by seed" in paired.why
    assert v.paired_trend(groups, increasing=True).word == "not confirmed"
    # the sign test: 20 of 20 seeds fall at every step, z = 20/√20
    median = v.paired_trend(groups, increasing=False, statistic="median")
    assert median.word == "confirmed" and "sign test" in median.why and "4.47" in median.why
    # only the seeds both groups have are paired: four of them carry no verdict
    few = [{s: x for s, x in g.items() if int(s) <= 4} for g in groups]
    assert v.paired_trend(few, increasing=False).word == "inconclusive"
    assert "4 seeds in both groups" in v.paired_trend(few, increasing=False).why
    # the same values in every group: no spread, no verdict
    same = [dict(base), dict(base)]
    assert v.paired_trend(same, increasing=False).word == "inconclusive"
