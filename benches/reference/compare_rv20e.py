#!/usr/bin/env python3
"""Compares the numpy reference's statistics with rvtol's for the same job, in standard
errors of the difference (the two programs draw different random streams, so they should
differ by Monte Carlo error only).

    python3 benches/reference/rv20e_numpy.py --samples 1000000 --seed 1 --json np.json
    rvtol run scenarios/rv20e-hysteresis.json --samples 1000000 --seed 2 --json rv.json
    python3 benches/reference/compare_rv20e.py np.json rv.json

Standard errors, combined over both runs as √(SE₁² + SE₂²), each run's from rvtol's figures:
means sd/√n; sds sd·√((g2 + 2)/(4n)) (g2 the excess kurtosis); percentiles from rvtol's
distribution-free 95 % interval (order-statistic ranks), SE = half-width/1.96; fractions
(the indicators, out of spec) binomial √(p(1 − p)/n). A percentile whose interval has no
width (0 .. 0 where the output has an atom at zero) is compared for equality; the
percentiles of an output with flagged samples (hysteresis_arcmin: rvtol places the
over-preloaded beyond the limit, numpy reports the values) are left out. Prints one
line per figure, z = (numpy − rvtol)/SE, and the largest |z|; exits 1 when a |z| exceeds
the limit (--limit, default 4: with about 80 figures, a larger |z| has a chance below
0.5 % under agreement).
"""
import argparse
import json
import math
import sys

PERCENTILES = ["0.135", "2.275", "15.866", "50", "84.134", "97.725", "99.865"]


def rows(numpy, rvtol):
    """(figure, numpy value, rvtol value, combined SE) for every figure both report."""
    n_np, n_rv = numpy["samples"], rvtol["samples"]
    outputs = {o["name"]: o for o in rvtol["outputs"]}
    for name, st in numpy["outputs"].items():
        r = outputs[name]
        sd, g2 = r["sd"], r["excess_kurtosis"]
        both = lambda se: se * math.sqrt(1.0 + n_rv / n_np)  # se of rvtol's run, scaled
        yield f"{name} mean", st["mean"], r["mean"], both(sd / math.sqrt(n_rv))
        yield f"{name} sd", st["sd"], r["sd"], both(sd * math.sqrt((g2 + 2.0) / (4.0 * n_rv)))
        for p in PERCENTILES:
            if "value_percentiles" in r:
                # rvtol places the flagged samples beyond the limit there, numpy does not:
                # its values' percentiles have no interval to compare them with.
                continue
            lo, hi = r["percentile_ci95"][p]
            yield f"{name} P{p}", st["percentiles"][p], r["percentiles"][p], both((hi - lo) / 2 / 1.96)
        if "out_of_spec_fraction" in st:
            p = r["ppm_out"] / 1e6
            se = math.sqrt(p * (1.0 - p) * (1.0 / n_rv + 1.0 / n_np))
            yield f"{name} out of spec", st["out_of_spec_fraction"], p, se
    for name in ("preloaded", "over_preloaded"):
        if name in numpy:
            p = outputs[name]["fraction"]
            se = math.sqrt(p * (1.0 - p) * (1.0 / n_rv + 1.0 / n_np))
            yield f"{name} fraction", numpy[name], p, se


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("numpy_json")
    ap.add_argument("rvtol_json")
    ap.add_argument("--limit", type=float, default=4.0)
    args = ap.parse_args()
    with open(args.numpy_json) as f:
        numpy = json.load(f)
    with open(args.rvtol_json) as f:
        rvtol = json.load(f)
    print("| quantity | rvtol | numpy | numpy − rvtol | combined SE | z |")
    print("|---|---|---|---|---|---|")
    worst, unequal = 0.0, []
    for figure, a, b, se in rows(numpy, rvtol):
        if not (math.isfinite(a) and math.isfinite(b)):
            continue
        if se == 0.0:
            z = 0.0 if a == b else math.inf
            if a != b:
                unequal.append(figure)
        else:
            z = (a - b) / se
        worst = max(worst, abs(z))
        print(f"| {figure} | {b:.7g} | {a:.7g} | {a - b:.3g} | {se:.3g} | {z:+.2f} |")
    print(f"\nlargest |z| {worst:.2f}" + (f"; unequal atoms: {unequal}" if unequal else ""))
    return 0 if worst <= args.limit else 1


if __name__ == "__main__":
    sys.exit(main())
