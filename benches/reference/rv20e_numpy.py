#!/usr/bin/env python3
"""Vectorised numpy reference for the rv20e-hysteresis Monte Carlo job.

Mirrors scenarios/rv20e-hysteresis.json evaluated with the geometric_hysteresis model
(crates/models/src/geometric_hysteresis.rs) so its speed can be compared with rvtol's.
It is not bit-identical to rvtol (different random streams); the statistics agree within
Monte Carlo error.

    python3 rv20e_numpy.py --samples 10000000 --seed 20221013

Statistics go to stdout; elapsed wall time and ns/sample (time.perf_counter around the
whole job, excluding interpreter start-up and imports) go to stderr.
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

CHUNK = 1_000_000
ARCMIN_PER_RAD = 180.0 * 60.0 / math.pi
PERCENTILES = [0.135, 2.275, 15.866, 50.0, 84.134, 97.725, 99.865]
BINS = 40
DEFAULT_SCENARIO = os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenarios", "rv20e-hysteresis.json"
)


def band_mean_sd(dist):
    """tolerance_band {lower, upper, cp, mean_shift}: mean = centre + shift, sd = (U-L)/(6 cp)."""
    b = dist["tolerance_band"]
    lower, upper, cp = b["lower"], b["upper"], b.get("cp", 1.0)
    return 0.5 * (lower + upper) + b.get("mean_shift", 0.0), (upper - lower) / (6.0 * cp)


def draw_constrained_pair(rng, m, mean_a, sd_a, mean_b, sd_b, coef_b, bound):
    """m draws of independent normals (a, b) conditioned on a + coef_b*b <= bound (rejection)."""
    a = mean_a + sd_a * rng.standard_normal(m)
    b = mean_b + sd_b * rng.standard_normal(m)
    bad = np.flatnonzero(a + coef_b * b > bound)
    while bad.size:
        k = bad.size
        a[bad] = mean_a + sd_a * rng.standard_normal(k)
        b[bad] = mean_b + sd_b * rng.standard_normal(k)
        bad = bad[a[bad] + coef_b * b[bad] > bound]
    return a, b


class Hysteresis:
    """geometric_hysteresis with its checked geometry (from_params in the Rust)."""

    def __init__(self, p):
        zp, zc, z1, z2 = p["pin_count"], p["cycloid_teeth"], p["sun_teeth"], p["planet_teeth"]
        self.ratio = 1.0 + (z2 * zp) / (z1 * (zp - zc))  # 000 Eq. 4
        self.e = p["eccentricity_mm"]
        self.zc = float(zc)
        self.rp = p["pin_circle_radius_mm"]
        self.k1 = p.get("curtate_ratio", self.e * zp / self.rp)
        self.cos_alpha = math.cos(math.radians(p.get("pressure_angle_deg", 20.0)))
        self.a0 = p["center_distance_mm"]
        self.r1 = p["sun_pitch_radius_mm"]
        self.z_sun = p.get("sun_gear_axial_position_mm", 0.0)

    def evaluate(self, x):
        """x: dict of input name -> scalar or array. Returns (hyst, invol, cyc, crank, interf)."""
        du, dv = x["input_shaft_du_mm"], x["input_shaft_dv_mm"]
        da, db = x["input_shaft_dalpha_rad"], x["input_shaft_dbeta_rad"]
        # point_displacement at (0, 0, z) with dw = dgamma = 0
        ux = du + db * self.z_sun
        uy = dv - da * self.z_sun
        a1 = np.sqrt(ux * ux + uy * uy)
        beta2 = da * da + db * db
        cos_beta = 1.0 - 0.5 * beta2 + beta2 * beta2 / 24.0  # series below beta = 1e-3 rad
        big = beta2 >= 1e-6
        if big.any():
            cos_beta[big] = np.cos(np.sqrt(beta2[big]))
        tilted = self.a0 + a1

        cos_op = self.a0 * self.cos_alpha * cos_beta / tilted
        involute = -(x["common_normal_upper_deviation_mm"] + x["common_normal_lower_deviation_mm"]) \
            * ARCMIN_PER_RAD / (2.0 * self.r1 * self.ratio * cos_op)

        e, zc, k1 = self.e, self.zc, self.k1
        s = math.sqrt(1.0 - k1 * k1)
        per_ezc = 1.0 / (e * zc)
        mod_eq, mod_sh = x["equidistant_modification_mm"], x["shift_modification_mm"]
        k_n = mod_eq / (e * e * zc) - (zc / (e * self.rp * self.rp * s) + s * per_ezc) * mod_sh
        cycloid = ((2.0 * mod_eq - 2.0 * mod_sh) * s * per_ezc
                   + 2.0 * x["pin_circle_radius_error_mm"] * s * per_ezc
                   - 2.0 * x["pin_radius_error_mm"] * per_ezc
                   + x["pin_hole_clearance_mm"] * per_ezc
                   + 0.5 * x["cycloid_radial_runout_mm"] * per_ezc
                   + 2.0 * x["pin_hole_position_error_mm"] * k1 * per_ezc
                   - x["cycloid_cumulative_pitch_error_mm"] * k1 * per_ezc
                   + 2.0 * x["equidistant_modification_error_mm"] * per_ezc
                   - 2.0 * x["shift_modification_error_mm"] * s * per_ezc
                   - 2.0 * k_n * x["eccentricity_error_mm"]) * ARCMIN_PER_RAD

        crank = x["crank_bearing_clearance_mm"] * cos_beta / tilted * ARCMIN_PER_RAD

        hyst = np.maximum(involute, 0.0) + np.maximum(cycloid, 0.0) + np.maximum(crank, 0.0)
        interference = (involute < 0.0) | (cycloid < 0.0) | (crank < 0.0)
        return hyst, involute, cycloid, crank, interference


def summarise(v):
    n = v.size
    mean = v.mean()
    d = v - mean
    d2 = d * d
    m2 = d2.sum()
    m3 = (d2 * d).sum()
    m4 = (d2 * d2).sum()
    del d, d2
    lo, hi = v.min(), v.max()
    counts, edges = np.histogram(v, bins=BINS, range=(lo, hi))
    return {
        "mean": mean,
        "sd": math.sqrt(m2 / (n - 1)),
        "skewness": math.sqrt(n) * m3 / m2 ** 1.5 if m2 > 0 else 0.0,
        "excess_kurtosis": n * m4 / (m2 * m2) - 3.0 if m2 > 0 else 0.0,
        "min": lo,
        "max": hi,
        "percentiles": np.percentile(v, PERCENTILES),
        "histogram": (counts, edges),
    }


def run(scenario, n, seed):
    model_spec = scenario["models"][0]
    assert model_spec["model"] == "geometric_hysteresis"
    model = Hysteresis(model_spec["params"])
    variables = [(v["name"],) + band_mean_sd(v["distribution"]) for v in scenario["variables"]]
    var_mean = np.array([m for _, m, _ in variables])[:, None]
    var_sd = np.array([s for _, _, s in variables])[:, None]
    part = scenario["parts"][0]
    tb = part["tolerance_band"]
    dt, L = tb["delta_tau_mm"], tb["length_mm"]
    constrained = tb.get("constraint_eq11", False)
    bound = dt if constrained else math.inf

    rng = np.random.default_rng(seed)
    names = ["hysteresis_arcmin", "involute_stage_arcmin", "cycloid_stage_arcmin",
             "crank_bearing_arcmin"]
    columns = [[] for _ in names]
    n_interf = 0
    for start in range(0, n, CHUNK):
        m = min(CHUNK, n - start)
        z = var_mean + var_sd * rng.standard_normal((len(variables), m))
        values = {name: z[i] for i, (name, _, _) in enumerate(variables)}
        # 001 Eq. 10/12 means and sds; Eq. 11 pairs (du, dbeta) and (dv, dalpha)
        du, dbeta = draw_constrained_pair(rng, m, dt / 2, dt / 6, dt / L, dt / (3 * L), L / 2, bound)
        dv, dalpha = draw_constrained_pair(rng, m, dt / 2, dt / 6, dt / L, dt / (3 * L), L / 2, bound)
        values[part["name"] + ".du"], values[part["name"] + ".dv"] = du, dv
        values[part["name"] + ".dalpha"], values[part["name"] + ".dbeta"] = dalpha, dbeta
        x = {k: (values[b] if isinstance(b, str) else b) for k, b in model_spec["inputs"].items()}
        *outs, interf = model.evaluate(x)
        for col, o in zip(columns, outs):
            col.append(o)
        n_interf += int(np.count_nonzero(interf))

    stats = {}
    for name, col in zip(names, columns):
        v = np.concatenate(col)
        col.clear()
        stats[name] = summarise(v)
        if name == "hysteresis_arcmin":
            upper = scenario["spec_limits"]["hysteresis_arcmin"]["upper"]
            st = stats[name]
            st["cpk"] = (upper - st["mean"]) / (3.0 * st["sd"])
            st["out_of_spec_fraction"] = np.count_nonzero(v > upper) / n
        del v
    stats["interference_fraction"] = n_interf / n
    return stats


def report(stats, n, seed):
    print(f"rv20e_numpy | {n:,} samples | seed {seed} | numpy {np.__version__} | percentiles numpy linear")
    for name, st in stats.items():
        if name == "interference_fraction":
            continue
        print(f"\n{name}")
        print(f"  mean {st['mean']:.6g}  sd {st['sd']:.6g}  skewness {st['skewness']:.5g}  "
              f"excess_kurtosis {st['excess_kurtosis']:.5g}  min {st['min']:.6g}  max {st['max']:.6g}")
        print("  " + "  ".join(f"P{p:g} {q:.6g}" for p, q in zip(PERCENTILES, st["percentiles"])))
        if "cpk" in st:
            print(f"  Cpk (x <= 1) {st['cpk']:.5g}  out of spec {st['out_of_spec_fraction'] * 1e6:.0f} ppm")
        counts, edges = st["histogram"]
        print(f"  histogram {BINS} bins over [{edges[0]:.6g}, {edges[-1]:.6g}]: "
              + " ".join(str(c) for c in counts))
    print(f"\ninterference {stats['interference_fraction'] * 100:.4f} % of samples")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--seed", type=int, default=20221013)
    ap.add_argument("--scenario", default=DEFAULT_SCENARIO)
    args = ap.parse_args()
    t0 = time.perf_counter()
    with open(args.scenario) as f:
        scenario = json.load(f)
    stats = run(scenario, args.samples, args.seed)
    report(stats, args.samples, args.seed)
    sys.stdout.flush()
    elapsed = time.perf_counter() - t0
    print(f"elapsed {elapsed:.3f} s, {elapsed * 1e9 / args.samples:.1f} ns/sample", file=sys.stderr)


if __name__ == "__main__":
    main()
