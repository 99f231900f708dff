#!/usr/bin/env python3
"""Time until every Sobol' interval is narrower than a width: rvtol against SALib and
OpenTURNS on the same problems, the same machine.

For each problem and tool the base sample count N (a power of two) grows from 2^12 until
every first-order and total index of every output has a 95 % interval narrower than
--width (0.01): after each run the next N is the power of two that the widest interval's
N^(-1/2) law predicts (at least twice the last). The time reported is the whole analysis
at the first N that meets the width (sampling, model evaluations, indices and their
bootstrap), wall clock, the tool's own process or calls:

- rvtol: `rvtol sensitivity SCENARIO --samples N --json FILE --quiet` (Saltelli 2010
  first order and Jansen total on both A_B and B_A designs, N(2d + 2) evaluations,
  percentile bootstrap of 500 resamples), a subprocess timed from outside;
- rvtol-rqmc: the same with `--sampling rqmc` (A and B the two halves of Owen-scrambled
  Sobol' points in 2d dimensions, 16 replicates of N/16 points, Student t intervals from
  the replicates' spread); its N doubles from 2^12 (the N^(-1/2) law would overshoot a
  design that converges faster);
- SALib 1.6: `sobol.sample(..., calc_second_order=False)` (scrambled Sobol' points,
  N(d + 2) evaluations), the model, `sobol.analyze(..., num_resamples=500)`, whose
  interval is ±S1_conf / ±ST_conf (a normal interval from the bootstrap sd);
- OpenTURNS 1.27: `SobolIndicesExperiment` (Monte Carlo, N(d + 2)), the model,
  `SaltelliSensitivityAlgorithm` with a bootstrap of 500 and its
  `get{FirstOrder,TotalOrder}IndicesInterval()`.

Models: Ishigami (a = 7, b = 0.1) and Sobol' G (a = 0, 1, 4.5, 9, 99, 99) in numpy for the
peers and as rvtol's built-in models; the RV-20E lost motion with the input shaft fixed
(nine independent variables: tolerance-band normals, a folded normal, two Rayleigh laws),
evaluated for the peers by rvtol's own model through the Python package
(`rvtol.Scenario(...).evaluate`), the inputs mapped from the unit cube by scipy's inverse
CDFs. The width criterion reads the lost motion `hysteresis_arcmin` only; the peers analyse
that output alone, while rvtol's time includes all six continuous outputs of the scenario
(it has no option to skip outputs), which counts against it.

Usage: sensitivity_peers.py [--rvtol target/release/rvtol] [--width 0.01]
       [--problems ishigami,sobol_g,rv20e] [--tools rvtol,rvtol-rqmc,salib,openturns]
       [--max-log2 21]
Needs numpy, scipy, SALib, openturns and the rvtol Python package (for the RV-20E peers).
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BOOTSTRAP = 500
RV20E_OUTPUT = "hysteresis_arcmin"


def ishigami(x):
    return np.sin(x[:, 0]) + 7.0 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])


G_COEFFICIENTS = np.array([0.0, 1.0, 4.5, 9.0, 99.0, 99.0])


def sobol_g(u):
    return np.prod((np.abs(4.0 * u - 2.0) + G_COEFFICIENTS) / (1.0 + G_COEFFICIENTS), axis=1)


def rv20e_scenario():
    """scenarios/rv20e-hysteresis.json with the input shaft fixed at zero deviation."""
    with open(os.path.join(ROOT, "scenarios", "rv20e-hysteresis.json")) as f:
        document = json.load(f)
    document["parts"] = []
    document.pop("allocation", None)
    inputs = document["models"][0]["inputs"]
    for key, value in list(inputs.items()):
        if isinstance(value, str) and value.startswith("input_shaft."):
            inputs[key] = 0.0
    document["name"] = "rv20e-input-shaft-fixed"
    return document


def rv20e_problem():
    from scipy import stats

    document = rv20e_scenario()
    marginals = []
    for variable in document["variables"]:
        (kind, p), = variable["distribution"].items()
        cp = p.get("cp", 1.0)
        if kind == "tolerance_band":
            mean = 0.5 * (p["lower"] + p["upper"]) + p.get("mean_shift", 0.0)
            marginals.append(stats.norm(loc=mean, scale=(p["upper"] - p["lower"]) / (6 * cp)))
        elif kind == "folded_normal":
            mean = 0.5 * (p["lower"] + p["upper"]) + p.get("mean_shift", 0.0)
            assert mean == 0.0
            marginals.append(stats.halfnorm(scale=(p["upper"] - p["lower"]) / (6 * cp)))
        elif kind == "rayleigh":
            marginals.append(stats.rayleigh(scale=p["upper"] / (3.635285597179897 * cp)))
        else:
            raise ValueError(kind)
    return document, marginals


class Problem:
    def __init__(self, name):
        self.name = name
        if name == "ishigami":
            self.d = 3
            self.scenario = os.path.join(ROOT, "scenarios", "ishigami.json")
            self.outputs = 1
        elif name == "sobol_g":
            self.d = 6
            self.scenario = os.path.join(ROOT, "scenarios", "sobol-g.json")
            self.outputs = 1
        elif name == "rv20e":
            self.document, self.marginals = rv20e_problem()
            self.d = len(self.marginals)
            handle = tempfile.NamedTemporaryFile("w", suffix=".json", delete=False)
            json.dump(self.document, handle)
            handle.close()
            self.scenario = handle.name
            self.rvtol_scenario = None
        else:
            raise ValueError(name)

    def from_unit_cube(self, u):
        """The model's outputs (rows × outputs) for points of the unit cube."""
        if self.name == "ishigami":
            return ishigami(-math.pi + 2.0 * math.pi * u)[:, None]
        if self.name == "sobol_g":
            return sobol_g(u)[:, None]
        import rvtol

        if self.rvtol_scenario is None:
            self.rvtol_scenario = rvtol.Scenario(self.document)
            # The lost motion (the width criterion's output).
            self.continuous = [self.rvtol_scenario.outputs.index(RV20E_OUTPUT)]
        x = np.column_stack([m.ppf(np.clip(u[:, k], 1e-16, 1 - 1e-16)) for k, m in enumerate(self.marginals)])
        # In pieces: evaluate takes at most 2·10⁷ values (inputs + outputs) per call.
        pieces = [np.asarray(self.rvtol_scenario.evaluate(x[k:k + 1_000_000]))[:, self.continuous]
                  for k in range(0, len(x), 1_000_000)]
        return np.concatenate(pieces)


def widths_rvtol(problem, n, binary, rqmc=False):
    intervals = ["--sampling", "rqmc", "--replicates", "16"] if rqmc else ["--bootstrap", str(BOOTSTRAP)]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "s.json")
        started = time.perf_counter()
        subprocess.run(
            [binary, "sensitivity", problem.scenario, "--samples", str(n), "--json", out, "--quiet"]
            + intervals,
            check=True, stdout=subprocess.DEVNULL,
        )
        elapsed = time.perf_counter() - started
        with open(out) as f:
            report = json.load(f)
    widest = 0.0
    for output in report["outputs"]:
        if problem.name == "rv20e" and output["name"] != RV20E_OUTPUT:
            continue
        for index in output["indices"]:
            for key in ("first_order_ci", "total_ci"):
                lo, hi = index[key]
                widest = max(widest, hi - lo)
    return elapsed, widest


def widths_salib(problem, n, seed=1):
    from SALib.analyze import sobol
    from SALib.sample import sobol as sobol_sample

    spec = {"num_vars": problem.d, "names": [f"x{k}" for k in range(problem.d)],
            "bounds": [[0.0, 1.0]] * problem.d}
    started = time.perf_counter()
    u = sobol_sample.sample(spec, n, calc_second_order=False, seed=seed)
    y = problem.from_unit_cube(u)
    widest = 0.0
    for j in range(y.shape[1]):
        si = sobol.analyze(spec, y[:, j], calc_second_order=False, num_resamples=BOOTSTRAP,
                           conf_level=0.95, seed=seed)
        widest = max(widest, float(np.nanmax(2 * si["S1_conf"])), float(np.nanmax(2 * si["ST_conf"])))
    return time.perf_counter() - started, widest


def widths_openturns(problem, n, seed=1):
    import openturns as ot

    ot.RandomGenerator.SetSeed(seed)
    started = time.perf_counter()
    distribution = ot.JointDistribution([ot.Uniform(0.0, 1.0)] * problem.d)
    x = ot.SobolIndicesExperiment(distribution, n, False).generate()
    y = problem.from_unit_cube(np.asarray(x))
    widest = 0.0
    for j in range(y.shape[1]):
        algorithm = ot.SaltelliSensitivityAlgorithm(x, ot.Sample(y[:, j:j + 1]), n)
        algorithm.setBootstrapSize(BOOTSTRAP)
        algorithm.setConfidenceLevel(0.95)
        for interval in (algorithm.getFirstOrderIndicesInterval(),
                         algorithm.getTotalOrderIndicesInterval()):
            lo, hi = np.asarray(interval.getLowerBound()), np.asarray(interval.getUpperBound())
            widest = max(widest, float(np.max(hi - lo)))
    return time.perf_counter() - started, widest


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rvtol", default=os.path.join(ROOT, "target", "release", "rvtol"))
    parser.add_argument("--width", type=float, default=0.01)
    parser.add_argument("--problems", default="ishigami,sobol_g,rv20e")
    parser.add_argument("--tools", default="rvtol,rvtol-rqmc,salib,openturns")
    parser.add_argument("--max-log2", type=int, default=21)
    args = parser.parse_args()
    for name in args.problems.split(","):
        problem = Problem(name)
        for tool in args.tools.split(","):
            log2 = 12
            while log2 <= args.max_log2:
                n = 2 ** log2
                if tool == "rvtol":
                    elapsed, widest = widths_rvtol(problem, n, args.rvtol)
                elif tool == "rvtol-rqmc":
                    elapsed, widest = widths_rvtol(problem, n, args.rvtol, rqmc=True)
                elif tool == "salib":
                    elapsed, widest = widths_salib(problem, n)
                else:
                    elapsed, widest = widths_openturns(problem, n)
                print(f"{name:9} {tool:10} N = 2^{log2:<2} widest interval {widest:.4f}  {elapsed:8.2f} s",
                      file=sys.stderr, flush=True)
                if widest < args.width:
                    print(json.dumps({"problem": name, "tool": tool, "n": n, "widest": widest,
                                      "seconds": round(elapsed, 3)}), flush=True)
                    break
                predicted = math.ceil(math.log2(n * (widest / args.width) ** 2))
                log2 = log2 + 1 if tool == "rvtol-rqmc" else max(log2 + 1, predicted)
            else:
                print(json.dumps({"problem": name, "tool": tool, "n": None,
                                  "widest": widest, "seconds": None}), flush=True)


if __name__ == "__main__":
    main()
