"""The equivalence verdict's error rates on synthetic normal data (compare/cases/stats.py, sequential.py).

Members are drawn from normal distributions with a known relative difference between the codes.
The false-agree rate (true difference on the margin) and the false-disagree rate (true difference
0, and on the margin: the worst case) must be at or below their nominal levels over 2,000
verdicts, with one look and with the sequential looks of --until-decided. A wrong variant (every
look at the plain level) must break the bound: the test can fail."""
import math

import numpy as np
import pytest

from dem.compare.verdict import sequential
from dem.compare.cases import stats

ALPHA = stats.FAMILY_ALPHA
TRIALS = 2000
MARGIN, CV, RHO = 0.10, 0.08, 0.5
MC = 3 * math.sqrt(ALPHA * (1 - ALPHA) / TRIALS)   # three Monte Carlo standard errors of a rate of alpha


def _members(rng, n, shift):
    """n paired members: native ~ N(100, (100 CV)^2), the other code its shift, correlation RHO."""
    z = rng.normal(size=(2, n))
    a = 100 * (1 + CV * z[0])
    b = 100 * (1 + shift) * (1 + CV * (RHO * z[0] + math.sqrt(1 - RHO ** 2) * z[1]))
    return a, b


def _verdict(a, b, levels):
    return stats.judge(stats.difference(a, b, relative=True, paired=True), MARGIN, levels)["verdict"]


def _sequential(rng, shift, first=4, max_members=16, looks=None):
    """One --until-decided run on synthetic members: looks at 4, 8, 12, 16 members until decided."""
    k = looks or sequential.planned_looks(first, first, max_members)
    a, b = _members(rng, max_members, shift)
    n = first
    while True:
        v = _verdict(a[:n], b[:n], stats.Levels(ALPHA, 1, k))
        if v != stats.INCONCLUSIVE or n >= max_members:
            return v
        n = min(n + first, max_members)


def _rate(fn, want):
    return sum(fn() == want for _ in range(TRIALS)) / TRIALS


def test_false_agree_at_the_margin_is_at_most_alpha_with_one_look():
    rng = np.random.default_rng(11)
    for shift in (MARGIN, -MARGIN):
        r = _rate(lambda: _verdict(*_members(rng, 8, shift), stats.Levels(ALPHA)), stats.AGREE)
        print(f"one look, 8 members, true difference {shift:+.0%}: false agree {r:.4f}")
        assert r <= ALPHA + MC, (shift, r)


def test_false_disagree_is_at_most_its_level():
    """A true agreement (difference 0, or on the margin: its worst case) says disagree with
    probability at most the disagree level; for a report of m metrics that level is alpha / m,
    so that the report's false-disagree rate is at most alpha (Bonferroni). Here m = 1, and a
    report of 10 metrics at difference 0."""
    rng = np.random.default_rng(12)
    for shift in (0.0, MARGIN, -MARGIN):
        r = _rate(lambda: _verdict(*_members(rng, 8, shift), stats.Levels(ALPHA)), stats.DISAGREE)
        print(f"one look, 8 members, true difference {shift:+.0%}: false disagree {r:.4f}")
        assert r <= ALPHA + MC, (shift, r)
    lv = stats.Levels(ALPHA, family=10)
    r = _rate(lambda: stats.DISAGREE if any(_verdict(*_members(rng, 8, 0.0), lv) == stats.DISAGREE
                                              for _ in range(10)) else stats.AGREE, stats.DISAGREE)
    print(f"10-metric reports at difference 0: any false disagree {r:.4f}")
    assert r <= ALPHA + MC, r


def test_sequential_looks_keep_both_rates():
    rng = np.random.default_rng(13)
    fa = _rate(lambda: _sequential(rng, MARGIN), stats.AGREE)
    fd = _rate(lambda: _sequential(rng, 0.0), stats.DISAGREE)
    fd_m = _rate(lambda: _sequential(rng, MARGIN), stats.DISAGREE)
    decided = _rate(lambda: _sequential(rng, 0.0), stats.AGREE)
    print(f"sequential, looks at 4/8/12/16: false agree {fa:.4f}, false disagree {fd:.4f} (at 0), "
          f"{fd_m:.4f} (on the margin); agree at 0: {decided:.3f}")
    assert fa <= ALPHA + MC and fd <= ALPHA + MC and fd_m <= ALPHA + MC
    assert decided > 0.8        # and they decide: a true difference of 0 agrees in most runs by 16 members


def test_looks_without_the_split_break_the_false_agree_bound():
    """The wrong variant: every look at the plain level (looks=1) inflates the false-agree rate."""
    rng = np.random.default_rng(14)
    wrong = _rate(lambda: _sequential(rng, MARGIN, first=3, max_members=24, looks=1), stats.AGREE)
    right = _rate(lambda: _sequential(rng, MARGIN, first=3, max_members=24), stats.AGREE)
    print(f"false agree, 8 looks of 3 members: {right:.4f} with the split, {wrong:.4f} without")
    assert wrong > ALPHA + MC and right <= ALPHA + MC, (wrong, right)


def test_intervals_and_verdicts_against_hand_values():
    a = np.array([100.0, 102.0, 98.0, 101.0, 99.0])
    b = a * 1.02
    st = stats.difference(a, b, relative=True, paired=False)
    assert st["estimate"] == pytest.approx(0.02, abs=1e-12)
    # unpaired relative se by the delta method: sqrt(se_b^2 + R^2 se_a^2) / mean(a)
    se_a = np.std(a, ddof=1) / math.sqrt(5)
    assert st["se"] == pytest.approx(math.hypot(1.02 * se_a, 1.02 * se_a) / 100.0, rel=1e-12)
    # paired: b = 1.02 a exactly, so the ratio residuals vanish and the interval is the point
    sp = stats.difference(a, b, relative=True, paired=True)
    assert sp["design"] == "paired" and sp["se"] == pytest.approx(0.0, abs=1e-15)
    assert sp["correlation"] == pytest.approx(1.0)
    assert stats.verdict_of([-0.05, 0.05], [-0.08, 0.08], 0.1) == stats.AGREE
    assert stats.verdict_of([0.11, 0.2], [0.105, 0.3], 0.1) == stats.DISAGREE
    assert stats.verdict_of([0.05, 0.15], [0.0, 0.2], 0.1) == stats.INCONCLUSIVE
    assert stats.verdict_of([0.11, 0.2], [0.09, 0.3], 0.1) == stats.INCONCLUSIVE   # the wider one reaches in
    # a t interval at one-sided alpha: est +- t_{1-alpha, df} se
    lo, hi = stats.t_interval(0.01, 0.02, 7, 0.05)
    assert hi - 0.01 == pytest.approx(1.894578605 * 0.02, rel=1e-8)


def test_members_to_decide_is_the_first_count_whose_interval_fits():
    lv = stats.Levels(ALPHA)
    n, se, est = 4, 0.04, 0.02
    need = stats.members_to_decide(est, se, n, MARGIN, lv)
    sd = se * math.sqrt(n)
    half = lambda m: stats.tq(1 - ALPHA, 2 * m - 2) * sd / math.sqrt(m)  # noqa: E731
    assert half(need) < MARGIN - est <= half(need - 1)
    assert stats.members_to_decide(MARGIN, se, n, MARGIN, lv) is None


def test_proportions_newcombe_interval():
    """Newcombe's hybrid interval from the two Wilson intervals (hand formula), and 0/8 vs 0/8 is
    inconclusive at the 0.2 margin (the Wilson upper bound of 0/8 at 90 % is z^2 / (8 + z^2))."""
    z = stats.sps.norm.ppf(0.95)
    lo, hi = stats.newcombe(0, 8, 0, 8, ALPHA)
    assert hi == pytest.approx(z * z / (8 + z * z), rel=1e-12) and lo == pytest.approx(-hi)
    st = stats.proportions(0, 8, 0, 8)
    assert stats.judge(st, 0.2, stats.Levels(ALPHA))["verdict"] == stats.INCONCLUSIVE
    assert stats.members_needed(st, 0.2, stats.Levels(ALPHA)) == 16
    assert stats.judge(stats.proportions(0, 64, 0, 64), 0.2, stats.Levels(ALPHA))["verdict"] == stats.AGREE
    assert stats.judge(stats.proportions(0, 16, 16, 16), 0.2, stats.Levels(ALPHA, 10))["verdict"] == stats.DISAGREE


def test_a_profile_agrees_only_when_every_point_does():
    lv = stats.Levels(ALPHA)
    ok = {"type": "profile", "n": [8, 8], "points": [[0.0, 0.01, 14], [0.02, 0.01, 14]]}
    assert stats.judge(ok, MARGIN, lv)["verdict"] == stats.AGREE
    one_wide = dict(ok, points=ok["points"] + [[0.05, 0.05, 14]])
    assert stats.judge(one_wide, MARGIN, lv)["verdict"] == stats.INCONCLUSIVE
    one_off = dict(ok, points=ok["points"] + [[0.5, 0.01, 14]])
    assert stats.judge(one_off, MARGIN, lv)["verdict"] == stats.DISAGREE
