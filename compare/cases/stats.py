"""The statistics of the verdict: two-sample tests whose power is stated.

Every ensemble metric is judged by a two-sided Welch test of the two codes' means; the level of
each test is the family level divided by the number of statistical tests in the report
(Bonferroni), so that the report as a whole fails a true agreement with probability at most
FAMILY_ALPHA. Each metric also states the smallest difference it detects: the difference at which
the same test rejects with probability POWER (validation.md: about 2.8 combined standard errors
at 95 % / 80 % for many members; more with few members, through Student's t).

Proportions (the jam fraction) use Fisher's exact test (few members per code) and Wilson score
intervals. Heavy-tailed quantities (peak ratios) are summarised by the ensemble median of each
member's windowed maximum with a percentile-bootstrap interval.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import special
from scipy import stats as sps

FAMILY_ALPHA = 0.05   # probability that a report of true agreement shows any statistical failure
POWER = 0.80          # power at which the detectable difference is stated


def mean_se(values) -> tuple[float, float, int]:
    """Mean, standard error and count of the finite values."""
    v = np.array([x for x in values if x is not None and math.isfinite(x)], float)
    if len(v) == 0:
        return float("nan"), float("nan"), 0
    se = float(np.std(v, ddof=1) / math.sqrt(len(v))) if len(v) > 1 else float("nan")
    return float(np.mean(v)), se, len(v)


def welch_df(se_a: float, n_a: int, se_b: float, n_b: int) -> float:
    """Welch-Satterthwaite degrees of freedom of the difference of two means."""
    va, vb = se_a ** 2, se_b ** 2
    den = (va ** 2 / (n_a - 1) if n_a > 1 else 0.0) + (vb ** 2 / (n_b - 1) if n_b > 1 else 0.0)
    if den <= 0:
        return float(max(n_a + n_b - 2, 1))
    return max((va + vb) ** 2 / den, 1.0)


def detectable(se_comb: float, df: float, alpha: float, power: float = POWER) -> float:
    """Smallest true difference that a two-sided t test at level alpha rejects with the given power
    (normal-shift approximation with Student's quantiles: (t_{1-alpha/2} + t_{power}) x s.e.)."""
    return float((sps.t.ppf(1 - alpha / 2, df) + sps.t.ppf(power, df)) * se_comb)


def compare_means(a: tuple, b: tuple, alpha: float) -> dict:
    """Welch test of two ensemble means. a, b: (mean, se, n). Returns the difference, the combined
    standard error, df, the p value, the critical difference (|diff| above it fails), the smallest
    detectable difference, both also relative to |mean of a|, and pass."""
    (ma, sa, na), (mb, sb, nb) = a, b
    if na < 2 or nb < 2 or not (math.isfinite(sa) and math.isfinite(sb)):
        return {"diff": mb - ma, "pass": False, "reason": f"needs at least 2 members in each code (have {na}, {nb})"}
    comb = math.hypot(sa, sb)
    df = welch_df(sa, na, sb, nb)
    diff = mb - ma
    if comb == 0:
        p = 1.0 if diff == 0 else 0.0
        crit = 0.0
    else:
        p = float(2 * sps.t.sf(abs(diff) / comb, df))
        crit = float(sps.t.ppf(1 - alpha / 2, df) * comb)
    mde = detectable(comb, df, alpha)
    scale = abs(ma) if ma else float("nan")
    return {"diff": diff, "se_comb": comb, "df": df, "p": p, "alpha": alpha, "critical": crit,
            "detectable": mde, "detectable_rel": mde / scale, "diff_rel": diff / scale,
            "pass": bool(p >= alpha)}


def wilson(k: int, n: int, conf: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a proportion k / n."""
    if n == 0:
        return float("nan"), float("nan")
    z = sps.norm.ppf(1 - (1 - conf) / 2)
    p = k / n
    den = 1 + z * z / n
    mid = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return max(0.0, mid - half), min(1.0, mid + half)


def compare_proportions(ka: int, na: int, kb: int, nb: int, alpha: float) -> dict:
    """Fisher's exact two-sided test of two proportions, with Wilson intervals and the smallest
    difference from p_a that the test detects with POWER (exact, over the binomial outcomes)."""
    if na == 0 or nb == 0:
        return {"pass": False, "reason": "no members"}
    p = float(sps.fisher_exact([[ka, na - ka], [kb, nb - kb]])[1])
    pa = ka / na
    mde = float("nan")
    for d in np.linspace(0.01, 1.0, 100):      # smallest |p_b - p_a| with power >= POWER
        pw = 0.0
        for q in (pa + d, pa - d):
            if not 0 <= q <= 1:
                continue
            pmf = sps.binom.pmf(np.arange(nb + 1), nb, q)
            rej = [sps.fisher_exact([[ka, na - ka], [j, nb - j]])[1] < alpha for j in range(nb + 1)]
            pw = max(pw, float(np.sum(pmf[rej])))
        if pw >= POWER:
            mde = float(d)
            break
    return {"a": pa, "b": kb / nb, "ci_a": wilson(ka, na), "ci_b": wilson(kb, nb), "p": p, "alpha": alpha,
            "detectable": mde, "pass": bool(p >= alpha)}


def bootstrap_median(values, conf: float = 0.95, n_boot: int = 4000, seed: int = 0) -> tuple[float, float, float]:
    """Median and its percentile-bootstrap interval (seeded: the same data give the same interval)."""
    v = np.array([x for x in values if x is not None and math.isfinite(x)], float)
    if len(v) == 0:
        return float("nan"), float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    meds = np.median(rng.choice(v, size=(n_boot, len(v)), replace=True), axis=1)
    lo, hi = np.quantile(meds, [(1 - conf) / 2, 1 - (1 - conf) / 2])
    return float(np.median(v)), float(lo), float(hi)


def members_for(rel_diff: float, cv: float, alpha: float, power: float = POWER) -> int:
    """Members per code for a two-sample test of equal size to detect a relative difference
    ``rel_diff`` when one member's coefficient of variation is ``cv``."""
    for n in range(2, 10_000):
        se = cv * math.sqrt(2.0 / n)
        if detectable(se, 2 * n - 2, alpha, power) <= rel_diff:
            return n
    return 10_000



# ------------------------------------------------------------------ equivalence (the verdict)
#
# A statistical metric agrees when the interval of the difference lies inside its margin, and
# disagrees when the interval lies entirely outside it (two one-sided tests). "Every metric
# agrees" is an intersection-union claim: each metric's (1 - 2 alpha) interval at the plain level
# bounds the false-agree rate of the whole report by alpha, with no split. "Some metric
# disagrees" is a union claim: its interval is the wider (1 - 2 alpha / m) one, m the statistical
# metrics of the report (Bonferroni), so that a report of true agreements says "disagree" with
# probability at most alpha. With sequential looks (--until-decided) both levels are split
# further over the planned looks (compare/verdict/sequential.py).

AGREE, DISAGREE, INCONCLUSIVE = "agree", "disagree", "inconclusive"


def tq(p: float, df: float) -> float:
    """Student's t quantile (scipy.special.stdtrit: sps.t.ppf without its per-call overhead, which
    the error-rate simulations would pay a hundred thousand times)."""
    return float(special.stdtrit(df, p))
NAN2 = [float("nan"), float("nan")]


@dataclasses.dataclass
class Levels:
    """The one-sided levels of a metric's two intervals: agree at alpha / looks, disagree at
    alpha / (family x looks)."""
    alpha: float = FAMILY_ALPHA
    family: int = 1             # statistical metrics of the report (the disagree split)
    looks: int = 1              # planned looks of a sequential design

    @property
    def agree(self) -> float:
        return self.alpha / max(self.looks, 1)

    @property
    def disagree(self) -> float:
        return self.alpha / (max(self.family, 1) * max(self.looks, 1))


def verdict_of(ci_agree, ci_disagree, margin: float) -> str:
    """agree: the agree interval inside [-margin, margin]; disagree: the (wider) disagree interval
    entirely outside it; inconclusive otherwise (also for an interval that is not finite)."""
    lo, hi = ci_agree
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return INCONCLUSIVE
    if -margin <= lo and hi <= margin:
        return AGREE
    dlo, dhi = ci_disagree
    if dlo > margin or dhi < -margin:
        return DISAGREE
    return INCONCLUSIVE


def _values(v) -> np.ndarray:
    return np.array([np.nan if x is None else float(x) for x in v], float)


def t_interval(est: float, se: float, df: float, alpha: float) -> list:
    """The two-sided (1 - 2 alpha) interval est +- t_{1-alpha, df} se."""
    if not (math.isfinite(est) and math.isfinite(se) and math.isfinite(df)):
        return list(NAN2)
    h = float(tq(1 - alpha, df)) * se if se > 0 else 0.0
    return [est - h, est + h]


def _unpaired(a: np.ndarray, b: np.ndarray, relative: bool) -> tuple[float, float, float]:
    """Estimate, standard error and Welch df of mean(b)/mean(a) - 1 (delta method) or of
    mean(b) - mean(a)."""
    ma, mb = a.mean(), b.mean()
    va, vb = a.var(ddof=1) / len(a), b.var(ddof=1) / len(b)
    if relative:
        rr = mb / ma
        va, vb, est = va * rr * rr / ma ** 2, vb / ma ** 2, rr - 1.0
    else:
        est = mb - ma
    den = va ** 2 / (len(a) - 1) + vb ** 2 / (len(b) - 1)
    df = (va + vb) ** 2 / den if den > 0 else float(len(a) + len(b) - 2)
    return float(est), math.sqrt(va + vb), max(float(df), 1.0)


def _paired(a: np.ndarray, b: np.ndarray, relative: bool) -> tuple[float, float, float]:
    """The same from members paired by their start: the ratio estimator's residuals b_k - R a_k
    (R = mean(b)/mean(a)) over |mean(a)|, or the differences b_k - a_k; df = n - 1."""
    ma, mb = a.mean(), b.mean()
    if relative:
        rr = mb / ma
        u, est = (b - rr * a) / abs(ma), rr - 1.0
    else:
        u, est = b - a, mb - ma
    return float(est), float(u.std(ddof=1) / math.sqrt(len(a))), float(len(a) - 1)


def difference(a, b, relative: bool = True, paired: bool = False) -> dict:
    """The statistic of code b against the reference a from their member values (None or NaN for
    a member without one): estimate, standard error, df. relative: mean(b)/mean(a) - 1; else
    mean(b) - mean(a). paired (members k of both codes start from the same state): the paired
    estimate, valid whatever the pairs' correlation (the unpaired one is not when the shared
    start correlates the members, and choosing the narrower of the two after seeing the data
    raises the false-agree rate: 0.065 against 0.045 at 4 uncorrelated members); the pairs'
    correlation is reported."""
    a, b = _values(a), _values(b)
    a_ok, b_ok = a[np.isfinite(a)], b[np.isfinite(b)]
    out = {"type": "t", "relative": relative, "n": [int(len(a_ok)), int(len(b_ok))],
           "mean": [float(a_ok.mean()) if len(a_ok) else float("nan"),
                    float(b_ok.mean()) if len(b_ok) else float("nan")]}
    if len(a_ok) < 2 or len(b_ok) < 2:
        return dict(out, reason=f"needs 2 members with a value in each code (have {len(a_ok)}, {len(b_ok)})")
    if relative and a_ok.mean() == 0:
        return dict(out, reason="the reference's mean is 0: no relative difference")
    est, se, df = _unpaired(a_ok, b_ok, relative)
    out.update(design="unpaired", correlation=float("nan"))
    both = np.isfinite(a) & np.isfinite(b) if paired and len(a) == len(b) else np.zeros(0, bool)
    if both.sum() >= 3:
        pa, pb = a[both], b[both]
        if pa.std() > 0 and pb.std() > 0:
            out["correlation"] = float(np.corrcoef(pa, pb)[0, 1])
        est, se, df = _paired(pa, pb, relative)
        out["design"] = "paired"
    return dict(out, estimate=est, se=se, df=df)


def proportions(ka: int, na: int, kb: int, nb: int) -> dict:
    """The statistic of a difference of two fractions, b - a (judged by Newcombe's interval)."""
    out = {"type": "proportion", "relative": False, "k": [ka, kb], "n": [na, nb]}
    if na == 0 or nb == 0:
        return dict(out, reason="no members")
    return dict(out, estimate=kb / nb - ka / na)


def newcombe(ka: int, na: int, kb: int, nb: int, alpha: float) -> list:
    """Newcombe's hybrid score interval (method 10) of p_b - p_a at two-sided level 1 - 2 alpha,
    built from the two Wilson intervals: it keeps its coverage with few members and at 0 or 1."""
    pa, pb = ka / na, kb / nb
    la, ua = wilson(ka, na, 1 - 2 * alpha)
    lb, ub = wilson(kb, nb, 1 - 2 * alpha)
    d = pb - pa
    return [d - math.hypot(pb - lb, ua - pa), d + math.hypot(ub - pb, pa - la)]


def judge(stat: dict, margin: float, levels: Levels) -> dict:
    """The verdict of a statistic (difference, proportions, or a profile: a list of point
    statistics, each relative to its wall's total) against its margin at these levels: the agree
    interval ``ci``, the disagree interval ``ci_disagree`` and the verdict."""
    if "reason" in stat:
        return {"ci": list(NAN2), "ci_disagree": list(NAN2), "verdict": INCONCLUSIVE}
    if stat["type"] == "proportion":
        (ka, kb), (na, nb) = stat["k"], stat["n"]
        ci, cid = newcombe(ka, na, kb, nb, levels.agree), newcombe(ka, na, kb, nb, levels.disagree)
        return {"ci": ci, "ci_disagree": cid, "verdict": verdict_of(ci, cid, margin)}
    if stat["type"] == "profile":
        return _judge_profile(stat, margin, levels)
    ci = t_interval(stat["estimate"], stat["se"], stat["df"], levels.agree)
    cid = t_interval(stat["estimate"], stat["se"], stat["df"], levels.disagree)
    return {"ci": ci, "ci_disagree": cid, "verdict": verdict_of(ci, cid, margin)}


def _judge_profile(stat: dict, margin: float, levels: Levels) -> dict:
    """A profile agrees when every point's agree interval is inside the margin (intersection-union:
    no split), disagrees when some point's disagree interval, split further over the points, is
    outside it. The reported intervals are those of the point that reaches farthest."""
    pts = stat["points"]
    per_point = Levels(levels.alpha, levels.family * max(len(pts), 1), levels.looks)
    cis = [t_interval(e, s, d, levels.agree) for e, s, d in pts]
    cids = [t_interval(e, s, d, per_point.disagree) for e, s, d in pts]
    if not pts or any(not math.isfinite(c[0]) for c in cis):
        return {"ci": list(NAN2), "ci_disagree": list(NAN2), "verdict": INCONCLUSIVE}
    if all(-margin <= c[0] and c[1] <= margin for c in cis):
        v = AGREE
    elif any(c[0] > margin or c[1] < -margin for c in cids):
        v = DISAGREE
    else:
        v = INCONCLUSIVE
    worst = max(range(len(pts)), key=lambda k: max(abs(cis[k][0]), abs(cis[k][1])))
    return {"ci": cis[worst], "ci_disagree": cids[worst], "verdict": v, "worst_point": worst}


def members_needed(stat: dict, margin: float, levels: Levels) -> int | None:
    """For an undecided statistic: the members per code that the same centre and spread would need
    to decide it (None where no number would, or where it is not a spread's matter)."""
    if "reason" in stat:
        return None
    if stat["type"] == "proportion":
        (ka, kb), (na, nb) = stat["k"], stat["n"]
        return _members_for_proportions(ka / na, kb / nb, margin, levels)
    if stat["type"] == "profile":
        pts = stat["points"]
        worst = max(pts, key=lambda p: abs(p[0]) + p[1])
        return members_to_decide(worst[0], worst[1], min(stat["n"]), margin,
                                 Levels(levels.alpha, levels.family * len(pts), levels.looks))
    return members_to_decide(stat["estimate"], stat["se"], min(stat["n"]), margin, levels,
                             stat.get("design") == "paired")


def members_to_decide(est: float, se: float, n: int, margin: float, levels: Levels,
                      paired: bool = False) -> int | None:
    """Members per code at which an interval with the same centre and per-member spread decides:
    inside the margin when the estimate is inside (agree), outside when it is outside (disagree);
    None when the estimate sits on the margin, there is no spread to scale, or more than 10^5."""
    gap = margin - abs(est)
    if gap == 0 or not (math.isfinite(se) and se > 0 and n >= 2):
        return None
    alpha = levels.agree if gap > 0 else levels.disagree
    sd = se * math.sqrt(n)

    def fits(m: int) -> bool:      # the half-width falls with m: bisect
        return tq(1 - alpha, m - 1 if paired else 2 * m - 2) * sd / math.sqrt(m) < abs(gap)
    lo, hi = 2, 100_000
    if not fits(hi):
        return None
    if fits(lo):
        return lo
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if fits(mid) else (mid, hi)
    return hi


def _members_for_proportions(pa: float, pb: float, margin: float, levels: Levels) -> int | None:
    """Members per code at which fractions pa, pb would give a Newcombe interval inside the margin."""
    if abs(pb - pa) >= margin:
        return None
    for m in (2 ** k for k in range(1, 13)):
        if all(-margin <= x <= margin for x in newcombe(round(pa * m), m, round(pb * m), m, levels.agree)):
            return m
    return None
