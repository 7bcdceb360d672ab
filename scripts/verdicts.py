"""The one verdict rule of the reproduction reports (docs/analysis.md, "Verdicts").

A claim of the paper is a set C of values: a number quoted to its last digit ("≃ 0.23": every value
that rounds to it, [0.225, 0.235]), a range ("0.2 – 1"), or a bound ("≲ 3e-3", "> 1/2"). budjam's
estimate x has its standard error s_b from n_b samples. The paper's number has a sampling error of its
own that the paper does not quote; with the same protocol the spread per sample is the same, so it is
s_p = s_b √(n_b / n_p) for the paper's n_p samples (its 20 seeds per point: n_p = n_b · 20/S for a grid
budjam grew with S seeds per point, n_p = n_b when S = 20). The
combined error is σ = √(s_b² + s_p²), and z = distance(x, C) / σ (0 inside C). A relation the theory
predicts (ΔZ_J = 0, an identity between measured quantities, N_zero = N_u) is no number the paper
measured: it has no sampling error of its own, n_p = THEORY and σ = s_b.

    inconclusive   n_b < 5: no error bar and no verdict (the n is stated); likewise with no finite
                   estimate, no error bar, an SE of 0 (no spread among n_b ≥ 5 values is no error bar
                   either: z would be 0 or ∞ by the tie alone), or a paper's n_p that is not a positive
                   number (the reason is stated);
    confirmed      z ≤ z_c: x lies within z_c σ of C, consistent with the claim at 95 %;
    not confirmed  z > z_c.

z_c is the 97.5 % quantile of Student's t with n_b − 1 degrees of freedom (σ is estimated from the
n_b samples: 2.78 at n_b = 5, 2.09 at 20), and never below 2 (the normal 1.96, rounded up). Tests whose
σ is not estimated from the sample (the score test of a proportion, the sign test) use z_c = 2.

z is printed to 3 significant digits, more where rounding would carry a z above z_c onto it, so that
the printed z is on the same side of z_c as its verdict.

A proportion p̂ = k/n (a fraction of packings) is judged by the score test: its SE is that of the claim's
boundary p0 nearest to p̂, √(p0(1 − p0)/n), not the Wald √(p̂(1 − p̂)/n), which is 0 at p̂ = 0 or 1 and would make
z 0 or ∞ whatever n; its interval is Wilson's (the score test inverted), never of zero width. At a boundary
p0 = 0 or 1 the score SE is 0 too, so there the SE is the half-width of p̂'s Wilson interval over 1.96.

A fit rejected by its χ² (above the 95 % quantile of χ² with its degrees of freedom) gives no value.

A trend over the feedback groups ("decreases with feedback") is budjam's own data tested for
direction, each group with its SE: not confirmed when a step between neighbouring groups goes against
the claimed direction by more than z_c σ of that step, confirmed when the change from the first group
to the last goes the claimed way by more than z_c σ and no step goes against it by more than z_c σ
(z_c of the smaller group's n, or of the seeds a paired step has), and
inconclusive otherwise (the data do not resolve the trend) or when a group has no error bar by the rule
for one claim (fewer than 5 samples, none, or an SE of 0). Groups grown from the same seeds (every P0
of a grid) are compared seed by seed where the values by seed are known: a step's σ is then the paired
SE of the per-seed differences over the seeds both groups have (a mean), or the step is a sign test on
those differences, z = (n₊ − n₋)/√(n₊ + n₋) (a median); fewer than 5 such seeds carry no verdict.

Nothing here measures: the estimates and their errors come from `budjam analyse`.
"""
import math
from dataclasses import dataclass

MIN_SAMPLES = 5  # no error bar and no verdict from fewer (as `budjam analyse` writes no SE then)
THEORY = "theory"  # n_p of a relation the theory predicts: no paper sample, so s_p = 0
Z_MAX = 2.0      # ≈ 95 % two-sided, for a normal z; the least z_c of every test


def t_quantile(dof):
    """The 97.5 % quantile of Student's t with dof degrees of freedom, by the Cornish–Fisher expansion
    about the normal quantile in powers of 1/dof (Abramowitz & Stegun 26.7.5, four terms): within 10⁻³ of
    the exact value for dof ≥ 4, which is every dof a verdict has (n ≥ 5); exact as dof → ∞."""
    x = 1.959963984540054  # the normal 97.5 % quantile
    g = ((x ** 3 + x) / 4,
         (5 * x ** 5 + 16 * x ** 3 + 3 * x) / 96,
         (3 * x ** 7 + 19 * x ** 5 + 17 * x ** 3 - 15 * x) / 384,
         (79 * x ** 9 + 776 * x ** 7 + 1482 * x ** 5 - 1920 * x ** 3 - 945 * x) / 92160)
    return x + sum(gk / dof ** (k + 1) for k, gk in enumerate(g))


def z_critical(n):
    """z_c of a test whose σ is estimated from n samples: Student's t with n − 1 degrees of freedom at
    97.5 %, and never below Z_MAX."""
    return max(Z_MAX, t_quantile(n - 1))


@dataclass(frozen=True)
class Claim:
    """The set of values a claim allows: the closed interval [lo, hi] (±inf for a bound)."""
    lo: float
    hi: float

    def distance(self, x):
        return max(self.lo - x, 0.0, x - self.hi)


def quoted(value, last_digit):
    """'≃ value' quoted to `last_digit` (0.23 → 0.01): the values that round to it."""
    return Claim(value - last_digit / 2, value + last_digit / 2)


def interval(lo, hi):
    return Claim(lo, hi)


def at_most(bound):
    return Claim(-math.inf, bound)


def at_least(bound):
    return Claim(bound, math.inf)


@dataclass(frozen=True)
class Verdict:
    word: str            # confirmed | not confirmed | inconclusive
    why: str             # z and σ, or the reason there is no verdict

    def __str__(self):
        return f"{self.word} ({self.why})"


def _fmt(v, digits=2):
    if v == 0 or not math.isfinite(v):
        return f"{v:g}"
    a = abs(v)
    return f"{v:.{digits}g}" if 1e-3 <= a < 1e4 else f"{v:.{digits - 1}e}"


def _fmt_z(z, z_c=Z_MAX):
    """z to 3 significant digits, or as many more as it takes to keep z on its side of z_c: rounding
    2.004 to "2" would print a not-confirmed verdict with the z of a confirmed one."""
    digits = 3
    while True:
        s = _fmt(z, digits)
        if (abs(z) > z_c) == (abs(float(s)) > z_c) or digits >= 17:
            return s
        digits += 1


def inconclusive_n(n):
    return Verdict("inconclusive", f"n = {n:g} < {MIN_SAMPLES}")


def _finite(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def unusable(estimate, se, n):
    """Why (estimate, se, n) can carry no verdict, or None when it can: fewer than 5 samples (or no
    count), no finite estimate, or no error bar (missing, not finite or negative)."""
    if not _finite(n) or n < MIN_SAMPLES:
        return inconclusive_n(n if _finite(n) else 0)
    if not _finite(estimate):
        return Verdict("inconclusive", f"no finite estimate (n = {n:g})")
    if not _finite(se) or se < 0:
        return Verdict("inconclusive", f"no error bar (n = {n:g})")
    return None


def compare(estimate, se, n, claim, n_paper=None, z_c=None):
    """The verdict on one claim from budjam's estimate ± se over n samples; n_paper = the paper's
    number of samples (None: the same as budjam's; THEORY: a predicted relation, no paper sample);
    z_c the critical z (None: z_critical(n), se being estimated from the n samples)."""
    why_not = unusable(estimate, se, n)
    if why_not is not None:
        return why_not
    if n_paper is None:
        n_paper = n
    elif n_paper is not THEORY and (not _finite(n_paper) or n_paper <= 0):
        shown = f"{n_paper:g}" if isinstance(n_paper, (int, float)) and not isinstance(n_paper, bool) else repr(n_paper)
        return Verdict("inconclusive", f"n_p = {shown}: the paper's sample size must be a positive number")
    if se == 0:
        return Verdict("inconclusive", f"SE = 0 from n = {n:g} samples: no spread, no error bar to judge by")
    z_c = z_critical(n) if z_c is None else z_c
    s_p = 0.0 if n_paper is THEORY else se * math.sqrt(n / n_paper)
    return _judged(estimate, math.hypot(se, s_p), claim, z_c)


def _judged(estimate, sigma, claim, z_c):
    z = claim.distance(estimate) / sigma
    word = "confirmed" if z <= z_c else "not confirmed"
    limit = "" if z_c == Z_MAX else f", z_c = {z_c:.3g}"
    return Verdict(word, f"z = {_fmt_z(z, z_c)}, σ = {_fmt(sigma)}{limit}")


def paired(differences):
    """The verdict on "no difference" between two of budjam's own protocols run on the same seeds, from the
    per-seed differences: the same rule with the paired standard error as σ (both sides are budjam's, on
    the same samples, so there is no second sampling error). Differences that are all exactly 0 are the
    same results: confirmed without a z."""
    d = [x for x in differences if _finite(x)]
    if len(d) != len(differences):
        return Verdict("inconclusive", f"{len(differences) - len(d)} of {len(differences)} differences not finite")
    n = len(d)
    if n >= MIN_SAMPLES and all(x == 0 for x in d):
        return Verdict("confirmed", f"identical in all n = {n}")
    mean = math.fsum(d) / n if n else math.nan
    se = math.sqrt(math.fsum((x - mean) ** 2 for x in d) / (n - 1) / n) if n > 1 else math.nan
    why_not = unusable(mean, se, n)
    if why_not is not None:
        return why_not
    if se == 0:
        return Verdict("inconclusive", f"SE = 0 from n = {n:g} samples: no spread, no error bar to judge by")
    return _judged(mean, se, Claim(0.0, 0.0), z_critical(n))


def _clamp01(x):
    return min(max(x, 0.0), 1.0)


def proportion(p, n, claim, n_paper=None):
    """The verdict on a claim about a proportion p = k/n by the score test: the SE is that of p0, the
    claim's boundary nearest to p, √(p0(1 − p0)/n) — not 0 at p = 0 or 1. When p0 itself is 0 or 1 the score
    SE is 0 (no k other than 0 or n is possible there), which would turn any p ≠ p0 into z = ∞: the SE is
    then the half-width of p's Wilson interval over 1.96, never 0. n_paper as in compare()."""
    why_not = unusable(p, 0.0, n)
    if why_not is not None:
        return why_not
    if not 0.0 <= p <= 1.0:
        return Verdict("inconclusive", f"not a proportion: {_fmt(p)} (n = {n:g})")
    ends = [e for e in (claim.lo, claim.hi) if math.isfinite(e)]
    p0 = _clamp01(min(ends, key=lambda e: abs(e - p)) if ends else p)  # the boundary nearest to p
    se0 = math.sqrt(p0 * (1.0 - p0) / n)
    if se0 == 0:
        lo, hi = wilson(p, n)
        se0 = (hi - lo) / (2 * 1.96)
    return compare(p, se0, n, claim, n_paper, z_c=Z_MAX)  # se0 is the null's, not estimated


def wilson(p, n, z=1.96):
    """Wilson's score interval (95 % by default) of a proportion p = k/n, n ≥ 1: never of zero width."""
    d = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / d
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / d
    return _clamp01(centre - half), _clamp01(centre + half)


def trend(points, increasing):
    """The verdict on a monotone trend over groups in order: points = [(estimate, se, n), …]."""
    if len(points) < 2:
        return Verdict("inconclusive", f"{len(points)} group(s)")
    for est, se, n in points:
        why_not = unusable(est, se, n)
        if why_not is not None:
            return why_not
        if se == 0:  # as in compare(): a step between two such groups would be z = 0 or ∞ by the tie alone
            return Verdict("inconclusive", f"SE = 0 from n = {n:g} samples: no spread, no error bar to judge by")
    sign = 1.0 if increasing else -1.0

    def z(a, b):  # in units of the step's critical z
        return sign * (b[0] - a[0]) / math.hypot(a[1], b[1]) / z_critical(min(a[2], b[2]))

    steps = [z(a, b) for a, b in zip(points, points[1:])]
    worst = min(range(len(steps)), key=lambda k: steps[k])
    overall = z(points[0], points[-1])
    c_worst = z_critical(min(points[worst][2], points[worst + 1][2]))
    c_overall = z_critical(min(points[0][2], points[-1][2]))
    why = (f"first to last z = {_fmt_z(overall * c_overall, c_overall)}, "
           f"worst step z = {_fmt_z(steps[worst] * c_worst, c_worst)}")
    if steps[worst] < -1:
        return Verdict("not confirmed", why)
    if overall > 1:
        return Verdict("confirmed", why)
    return Verdict("inconclusive", why + ": not resolved")


def _paired_step(a, b, sign, statistic):
    """(z, n, why not, z_c) of the change from group a to group b (dicts seed → value) in the claimed
    direction, paired by seed over the n seeds both have (the sign test: those with a difference); z is
    None, with the reason, when they cannot carry a verdict."""
    d = [sign * (b[s] - a[s]) for s in a if s in b and _finite(a[s]) and _finite(b[s])]
    if statistic == "median":
        up, down = sum(x > 0 for x in d), sum(x < 0 for x in d)
        m = up + down
        if m < MIN_SAMPLES:
            return None, m, f"{m} seeds with a difference, fewer than {MIN_SAMPLES}", Z_MAX
        return (up - down) / math.sqrt(m), m, None, Z_MAX
    n = len(d)
    if n < MIN_SAMPLES:
        return None, n, f"{n} seeds in both groups, fewer than {MIN_SAMPLES}", Z_MAX
    mean = math.fsum(d) / n
    se = math.sqrt(math.fsum((x - mean) ** 2 for x in d) / (n - 1) / n)
    if se == 0:
        return None, n, f"SE = 0 from n = {n} differences: no spread, no error bar to judge by", Z_MAX
    return mean / se, n, None, z_critical(n)


def paired_trend(groups, increasing, statistic="mean"):
    """trend() for groups grown from the same seeds: groups = [{seed: value}, …] in order; a step is the
    paired test of the per-seed differences over the seeds both groups have (statistic "mean": the paired
    SE; "median": the sign test)."""
    if len(groups) < 2:
        return Verdict("inconclusive", f"{len(groups)} group(s)")
    sign = 1.0 if increasing else -1.0
    steps = [_paired_step(a, b, sign, statistic) for a, b in zip(groups, groups[1:])]
    overall = _paired_step(groups[0], groups[-1], sign, statistic)
    for z, _, why_not, _ in steps + [overall]:
        if z is None:
            return Verdict("inconclusive", "paired by seed: " + why_not)
    worst = min(steps, key=lambda s: s[0] / s[3])  # the step furthest against the claim, in its z_c
    counts = [n for _, n, _, _ in steps]
    test = "sign test" if statistic == "median" else "paired SE"
    seeds = f"{min(counts)}" if min(counts) == max(counts) else f"{min(counts)}–{max(counts)}"
    why = (f"paired by seed, {test}: first to last z = {_fmt_z(overall[0], overall[3])}, worst step z = "
           f"{_fmt_z(worst[0], worst[3])}, {seeds} seeds per step")
    if worst[0] < -worst[3]:
        return Verdict("not confirmed", why)
    if overall[0] > overall[3]:
        return Verdict("confirmed", why)
    return Verdict("inconclusive", why + ": not resolved")


def _lower_gamma_regularised(a, x):
    """P(a, x) = γ(a, x)/Γ(a) by its power series, which converges for every x ≥ 0 (in about x terms)."""
    if x <= 0:
        return 0.0
    term = total = 1.0 / a
    k = 0
    while term > total * 1e-17 and k < 100000:
        k += 1
        term *= x / (a + k)
        total += term
    return min(1.0, total * math.exp(a * math.log(x) - x - math.lgamma(a)))


def chi2_quantile(dof, level=0.95):
    """The `level` quantile of the χ² distribution with dof > 0 degrees of freedom, by bisection on its
    CDF P(dof/2, x/2): exact to rounding, and without scipy, which Debian's python3 lacks by default."""
    lo, hi = 0.0, dof + 10.0 * math.sqrt(2.0 * dof) + 10.0
    while _lower_gamma_regularised(dof / 2.0, hi / 2.0) < level:
        lo, hi = hi, 2.0 * hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if _lower_gamma_regularised(dof / 2.0, mid / 2.0) < level:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-12 * hi:
            break
    return 0.5 * (lo + hi)


def fit_rejected(chi2, dof, level=0.95):
    """Whether a fit's χ² exceeds the `level` quantile of χ² with dof degrees of freedom (its model then
    does not describe the data, and its parameters are not estimates of anything); None when there is no
    test (no finite χ², or no degree of freedom left)."""
    if not _finite(chi2) or not _finite(dof) or dof <= 0:
        return None
    return chi2 > chi2_quantile(dof, level)
