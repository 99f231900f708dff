#!/usr/bin/env python3
"""Reference ranks of the distribution-free percentile intervals, computed in 40-digit
arithmetic, independently of rvtol's binomial module (crates/stats/src/binomial.rs).

For B ~ Binomial(n, p), p = percent / 100 as an IEEE double (the value rvtol uses) and
q = 1 - p exactly, the interval [X_(l), X_(u)] at 95 % has
  l = the largest m with P(B <= m) <= 0.025 (blank when P(B <= 0) > 0.025),
  u = the smallest m with P(B <= m) >= 0.975 (blank when that m is n).
Masses come from mpmath's log-gamma at 40 significant digits (at n = 1e12 ln n! is about
2.7e13, so its absolute error is about 1e-26); tails are their plain sums, run outwards
until a term is below 1e-30 of the sum. The rank is found by stepping from the normal
guess; 'margin' is the smallest relative distance of the two decisive tail sums from
0.025, so a rank computed in double precision is exact when margin >> 1e-13.

Writes tests/data/binomial_ranks.csv in about 7 CPU-minutes (n = 10¹² dominates).
Usage: python3 scripts/binomial-reference.py [output.csv]
"""
import sys
import mpmath
from mpmath import mp, mpf

mp.dps = 40
TAIL = mpf("0.025")
PERCENTS = ["0.135", "2.275", "15.866", "50", "84.134", "97.725", "99.865"]
SIZES = [10**3, 12_345, 10**4, 10**5, 10**6, 10**7, 4 * 10**7, 10**8,
         999_999_937, 10**9, 10**10, 10**11, 10**12]


def log_mass(n, k, log_p, log_q, log_n_factorial):
    return (log_n_factorial - mpmath.loggamma(k + 1) - mpmath.loggamma(n - k + 1)
            + k * log_p + (n - k) * log_q)


class Law:
    def __init__(self, n, p):
        self.n, self.p, self.q = n, mpf(p), 1 - mpf(p)
        self.log_p, self.log_q = mpmath.log(self.p), mpmath.log(self.q)
        self.log_n_factorial = mpmath.loggamma(n + 1)

    def mass(self, k):
        if k < 0 or k > self.n:
            return mpf(0)
        return mpmath.exp(log_mass(self.n, k, self.log_p, self.log_q, self.log_n_factorial))

    def lower_tail(self, k):
        """P(B <= k)."""
        if k >= self.n:
            return mpf(1)
        if k < 0:
            return mpf(0)
        term = self.mass(k)
        total = term
        j = k
        while j > 0:
            ratio = j * self.q / ((self.n - j + 1) * self.p)
            if ratio < 1 and term < total * mpf("1e-30"):
                break
            term *= ratio
            total += term
            j -= 1
        return total

    def upper_tail(self, k):
        """P(B >= k)."""
        if k <= 0:
            return mpf(1)
        if k > self.n:
            return mpf(0)
        term = self.mass(k)
        total = term
        j = k
        while j < self.n:
            ratio = (self.n - j) * self.p / ((j + 1) * self.q)
            if ratio < 1 and term < total * mpf("1e-30"):
                break
            term *= ratio
            total += term
            j += 1
        return total

    def guess(self, z):
        n, p = self.n, float(self.p)
        value = n * p + z * (n * p * (1 - p)) ** 0.5
        return min(max(int(round(value)), 0), n)


def lower_rank(law):
    """(l, margin): the largest m with P(B <= m) <= TAIL."""
    m = law.guess(-1.959963984540054)
    below = law.lower_tail(m)
    if below <= TAIL:
        while m < law.n and below + law.mass(m + 1) <= TAIL:
            m += 1
            below += law.mass(m)
    else:
        while below > TAIL and m >= 0:
            below -= law.mass(m)
            m -= 1
    if m < 0:
        return None, abs(law.mass(0) / TAIL - 1)
    # Decisive sums: P(B <= m) <= TAIL < P(B <= m + 1).
    above = below + law.mass(m + 1)
    return m, min(abs(below / TAIL - 1), abs(above / TAIL - 1))


def upper_rank(law):
    """(u, margin): the smallest m with P(B >= m + 1) <= TAIL."""
    m = law.guess(1.959963984540054)
    above = law.upper_tail(m + 1)
    if above <= TAIL:
        while m > 0 and above + law.mass(m) <= TAIL:
            above += law.mass(m)
            m -= 1
    else:
        while above > TAIL and m < law.n:
            m += 1
            above -= law.mass(m)
    previous = above + law.mass(m)
    margin = min(abs(above / TAIL - 1), abs(previous / TAIL - 1))
    return (None if m >= law.n else m), margin


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "tests/data/binomial_ranks.csv"
    rows = ["n,percent,lower,upper,margin"]
    for n in SIZES:
        for percent in PERCENTS:
            p = float(percent) / 100.0
            law = Law(n, p)
            low, margin_low = lower_rank(law)
            high, margin_high = upper_rank(law)
            fmt = lambda r: "" if r is None else str(r)
            margin = min(margin_low, margin_high)
            rows.append(f"{n},{percent},{fmt(low)},{fmt(high)},{mpmath.nstr(margin, 3)}")
            print(rows[-1], file=sys.stderr, flush=True)
    with open(out, "w") as handle:
        handle.write("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
