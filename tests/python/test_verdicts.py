"""The verdict rule of the reproduction reports (scripts/verdicts.py): each branch on its edge."""
import math
import os
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
    # same number of samples: σ = √2 s_b; z just below and above 2
    s = 0.01
    c = v.quoted(0.5, 0.0)
    assert v.compare(0.5 + 2 * math.sqrt(2) * s * 0.999, s, 20, c).word == "confirmed"
    assert v.compare(0.5 + 2 * math.sqrt(2) * s * 1.001, s, 20, c).word == "not confirmed"
    # the paper's 20 samples against budjam's 200: σ = s_b √(1 + 10)
    assert v.compare(0.5 + 2 * math.sqrt(11) * s * 0.999, s, 200, c, n_paper=20).word == "confirmed"
    assert v.compare(0.5 + 2 * math.sqrt(11) * s * 1.001, s, 200, c, n_paper=20).word == "not confirmed"


def test_a_fraction_within_noise_of_a_bound_is_consistent_with_it():
    # 48.6 % of 940 packings against "more than half": 1 SE below, not a refutation
    p, n = 0.486, 940
    se = math.sqrt(p * (1 - p) / n)
    assert v.compare(p, se, n, v.at_least(0.5)).word == "confirmed"
    assert v.compare(0.40, math.sqrt(0.4 * 0.6 / n), n, v.at_least(0.5)).word == "not confirmed"


def test_ranges_and_bounds():
    assert v.compare(0.15, 0.01, 20, v.interval(0.2, 1.0)).word == "not confirmed"
    assert v.compare(0.19, 0.01, 20, v.interval(0.2, 1.0)).word == "confirmed"
    assert v.compare(0.0, 0.0, 20, v.at_most(3e-3)).word == "confirmed"
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
                        os.path.join(ref, "reanalysed"), "--survival", os.path.join(ref, "tables", "survival_main_L.json"),
                        "--figures", os.path.join(ref, "figures"), "--preset", "paper", "--jamming", str(tmp_path / "none"),
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
    # σ = 0 (every sample equal, n ≥ 5): inside the set z = 0, outside it z = ∞ — no 0/0, no NaN
    assert str(v.compare(0.0, 0.0, 8, v.quoted(0.0, 0.0))) == "confirmed (z = 0, σ = 0)"
    r = v.compare(1e-9, 0.0, 8, v.quoted(0.0, 0.0))
    assert r.word == "not confirmed" and "z = inf" in r.why
    assert v.compare(-0.5, 0.0, 8, v.at_least(0.0)).word == "not confirmed"
    assert v.compare(-0.5, 0.0, 8, v.at_most(0.0)).word == "confirmed"
    # a negative estimate against an interval: the distance to its near end
    assert v.compare(-0.1, 0.1, 20, v.interval(0.2, 1.0)).word == "not confirmed"
    assert v.compare(-0.1, 0.2, 20, v.interval(0.2, 1.0)).word == "confirmed"
    flat = [(1.0, 0.0, 8), (1.0, 0.0, 8)]
    assert v.trend(flat, increasing=True).word == "inconclusive"
    assert v.trend([(1.0, 0.0, 8), (2.0, 0.0, 8)], increasing=True).word == "confirmed"
    assert v.trend([(1.0, 0.0, 8), (2.0, 0.0, 8)], increasing=False).word == "not confirmed"


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
