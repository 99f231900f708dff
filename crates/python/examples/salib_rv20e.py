"""Sobol' indices of the RV-20E lost motion with SALib, rvtol evaluating the model:
SALib draws the Saltelli design, rvtol.evaluate runs geometric_hysteresis on all of its rows
in parallel, SALib analyses. Run: python salib_rv20e.py [N]"""

import sys

from SALib.analyze import sobol as sobol_analyze
from SALib.sample import sobol as sobol_sample

from rv20e_problem import NAMES, VARIED, lost_motion


def indices(n=2**14, seed=1):
    """{input: (S1, S1 95 % half-width, ST, ST 95 % half-width)} from N base samples."""
    problem = {
        "num_vars": len(NAMES),
        "names": NAMES,
        "bounds": [list(VARIED[name]) for name in NAMES],  # "norm": [mean, sd]
        "dists": ["norm"] * len(NAMES),
    }
    x = sobol_sample.sample(problem, n, calc_second_order=False, seed=seed)
    y = lost_motion(x)
    si = sobol_analyze.analyze(problem, y, calc_second_order=False, seed=seed)
    return {
        name: (si["S1"][i], si["S1_conf"][i], si["ST"][i], si["ST_conf"][i])
        for i, name in enumerate(NAMES)
    }


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 2**14
    for name, (s1, s1c, st, stc) in sorted(indices(n).items(), key=lambda kv: -kv[1][2]):
        print(f"{name:36s} S1 {s1:6.3f} ± {s1c:5.3f}   ST {st:6.3f} ± {stc:5.3f}")
