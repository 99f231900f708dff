"""Sobol' indices of the RV-20E lost motion with OpenTURNS, rvtol evaluating the model:
an OpenTURNS PythonFunction whose sample evaluation hands the whole design to
rvtol.evaluate (parallel Rust), a SobolIndicesExperiment and Saltelli's estimator.
Run: python openturns_rv20e.py [N]"""

import sys

import numpy as np
import openturns as ot

from rv20e_problem import NAMES, VARIED, lost_motion


def indices(n=2**14, seed=1):
    """{input: (S1, ST, ST's 95 % bootstrap interval)} from N base samples."""
    ot.RandomGenerator.SetSeed(seed)
    function = ot.PythonFunction(
        len(NAMES), 1, func_sample=lambda x: lost_motion(np.asarray(x)).reshape(-1, 1)
    )
    marginals = [ot.Normal(*VARIED[name]) for name in NAMES]
    joint = getattr(ot, "JointDistribution", None) or ot.ComposedDistribution
    experiment = ot.SobolIndicesExperiment(joint(marginals), n)
    x = experiment.generate()
    y = function(x)
    algorithm = ot.SaltelliSensitivityAlgorithm(x, y, n)
    algorithm.setBootstrapSize(200)
    first, total = algorithm.getFirstOrderIndices(), algorithm.getTotalOrderIndices()
    interval = algorithm.getTotalOrderIndicesInterval()
    low, high = interval.getLowerBound(), interval.getUpperBound()
    return {name: (first[i], total[i], (low[i], high[i])) for i, name in enumerate(NAMES)}


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 2**14
    for name, (s1, st, (low, high)) in sorted(indices(n).items(), key=lambda kv: -kv[1][1]):
        print(f"{name:36s} S1 {s1:6.3f}   ST {st:6.3f} ({low:6.3f} .. {high:6.3f})")
