#!/usr/bin/env python3
"""Samples and wall time to a stated interval half-width: Monte Carlo against Latin
hypercube against randomized QMC, for one output of one scenario.

Protocol (README, "Fewer samples for the same interval"):

- For each method and each N of a ladder of powers of two, `rvtol run SCENARIO --samples N
  --sampling METHOD --json - --exact-percentile-limit 1e9` is run with SEEDS seeds; the 95 % half-width of each figure
  (mean, sd, P50, P99.865 of OUTPUT) is read from the report and averaged over the seeds,
  and the whole process's wall time is measured around the call.
  - lhs and rqmc: their replicate intervals (16 replicates of N/16 points, Student t).
  - mc: the report's own intervals: the mean's 1.96·s/√N, the sd's 1.96·s·√((κ+2)/(4N))
    (κ the excess kurtosis; the delta method the capability intervals use), the
    percentiles' distribution-free order-statistic intervals.
- The convergence rate is the least-squares slope b of log half-width against log N over
  the ladder (Monte Carlo: −1/2).
- The target half-width of each figure is Monte Carlo's at N = TARGET_N (the fit's value
  there). The samples each method needs are N* = exp((log target − a)/b) from its fit,
  rounded up to the method's next power of two (16 × a power of two for lhs and rqmc); its
  wall time is the measured time of that N when on the ladder, else the largest rung's
  time per sample × N* (marked ~).

Usage: sampling_convergence.py RVTOL SCENARIO OUTPUT --ladder 14 22 [--seeds 3]
       [--target-n 1048576]
"""

import argparse
import json
import math
import subprocess
import time

FIGURES = ["mean", "sd", "P50", "P99.865"]
METHODS = ["mc", "lhs", "rqmc"]
Z95 = 1.959963984540054


def half_widths(report, output, method):
    o = next(x for x in report["outputs"] if x["name"] == output)
    if method == "mc":
        n = o["n"]
        s = o["sd"]
        kappa = o["excess_kurtosis"]
        pct = o["percentile_ci95"]
        return {
            "mean": Z95 * s / math.sqrt(n),
            "sd": Z95 * s * math.sqrt((kappa + 2.0) / (4.0 * n)),
            "P50": 0.5 * (pct["50"][1] - pct["50"][0]),
            "P99.865": 0.5 * (pct["99.865"][1] - pct["99.865"][0]),
        }
    r = o["replicate_ci95"]

    def half(interval):
        # No replicate interval (a percentile beyond a replicate's outermost ranks): NaN,
        # which leaves the rung out of that figure's fit.
        return math.nan if None in interval else 0.5 * (interval[1] - interval[0])

    return {
        "mean": half(r["mean"]),
        "sd": half(r["sd"]),
        "P50": half(r["percentiles"]["50"]),
        "P99.865": half(r["percentiles"]["99.865"]),
    }


def run(rvtol, scenario, samples, method, seed):
    start = time.perf_counter()
    out = subprocess.run(
        [rvtol, "run", scenario, "--samples", str(samples), "--sampling", method,
         "--seed", str(seed), "--json", "-", "--quiet",
         # Exact percentiles at every N: the sketch's error bound would widen Monte
         # Carlo's percentile intervals beyond the exact-percentile limit.
         "--exact-percentile-limit", "1000000000"],
        check=True, capture_output=True, text=True,
    ).stdout
    return json.loads(out), time.perf_counter() - start


def fit(points):
    xs = [math.log(n) for n, _ in points]
    ys = [math.log(h) for _, h in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    return my - b * mx, b


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rvtol")
    ap.add_argument("scenario")
    ap.add_argument("output")
    ap.add_argument("--ladder", nargs=2, type=int, default=[14, 22])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--target-n", type=int, default=1 << 20)
    args = ap.parse_args()
    ladder = [1 << k for k in range(args.ladder[0], args.ladder[1] + 1)]
    measured = {}  # (method, N) -> (half-widths averaged, seconds averaged)
    # Methods alternate within each rung so that a busy moment of the host hits all three.
    for n in ladder:
        for method in METHODS:
            sums = {f: 0.0 for f in FIGURES}
            seconds = 0.0
            for seed in range(1, args.seeds + 1):
                report, t = run(args.rvtol, args.scenario, n, method, seed)
                for f, h in half_widths(report, args.output, method).items():
                    sums[f] += h / args.seeds
                seconds += t / args.seeds
            measured[(method, n)] = (sums, seconds)
            print(f"# {method:4} N = {n:>9}: {seconds:7.3f} s  "
                  + "  ".join(f"{f} {sums[f]:.3e}" for f in FIGURES), flush=True)
    fits = {(m, f): fit([(n, measured[(m, n)][0][f]) for n in ladder if measured[(m, n)][0][f] > 0])
            for m in METHODS for f in FIGURES}
    print(f"\n{args.scenario} {args.output}: target = Monte Carlo's half-width at N = {args.target_n}")
    print("| figure | target half-width | " + " | ".join(
        f"{m}: slope, N, wall" for m in METHODS) + " |")
    largest = ladder[-1]
    for f in FIGURES:
        a_mc, b_mc = fits[("mc", f)]
        target = math.exp(a_mc + b_mc * math.log(args.target_n))
        cells = []
        for m in METHODS:
            a, b = fits[(m, f)]
            need = math.exp((math.log(target) - a) / b)
            n = max(16 if m != "mc" else 1, 1 << math.ceil(math.log2(max(need, 1.0))))
            if (m, n) in measured:
                wall = f"{measured[(m, n)][1]:.3f} s"
            else:
                per = measured[(m, largest)][1] / largest
                wall = f"~{per * n:.3f} s"
            cells.append(f"{b:.2f}, 2^{int(math.log2(n))}, {wall}")
        print(f"| {f} | {target:.3g} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
