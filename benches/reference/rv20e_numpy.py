#!/usr/bin/env python3
"""Vectorised numpy reference for the rv20e-hysteresis Monte Carlo job.

Mirrors `rvtol run scenarios/rv20e-hysteresis.json`: the scenario's distributions, the
input shaft's tolerance band (001 Eq. 9, 10, 12) with its Eq. 11 constraint imposed by
rejection, and the geometric_hysteresis model (crates/models/src/geometric_hysteresis.rs,
docs/models.md §2) in its default "physical" reading (or "document_000" when the scenario
asks for it), so that its speed can be compared with rvtol's. It is not bit-identical to
rvtol (different random streams); the statistics agree within Monte Carlo error.

Distributions (as crates/engine/src/scenario/compile/ maps the scenario file):
  tolerance_band {lower L, upper U, cp, mean_shift}  N((L+U)/2 + shift, ((U-L)/(6 cp))^2)
  normal {mean, sd}                                   N(mean, sd^2)
  folded_normal {lower, upper, cp, mean_shift}        |X|, X the tolerance-band normal above
  rayleigh {upper U, cp}                              sigma*sqrt(2E), E standard exponential
                                                      (the length of a 2-D N(0, sigma^2)
                                                      vector), sigma = U/(RAYLEIGH_QUANTILE cp)
  lognormal {median M, upper U, cp}                   exp(ln M + sigma Z), sigma = ln(U/M)/(3 cp)
  uniform {lower, upper}, triangular {lower, mode, upper}
(truncated_normal, correlations and parts other than a tolerance band are not supported.)
Random numbers: numpy's Generator on the SFC64 bit generator, standard_normal and
standard_exponential.
The input shaft, band dt over length L: du, dv ~ N(dt/2, (dt/6)^2), dalpha, dbeta ~
N(dt/L, (dt/(3L))^2), dw = dgamma = 0. Eq. 11, du + dbeta*L/2 <= dt and
dv + dalpha*L/2 <= dt, is imposed by rejection on each pair as rvtol does it: the pair is
rotated into the constrained direction z_s and the free one z_t (independent standard
normals), z_s is redrawn in vectorised batches until it holds, z_t is drawn once.

Model (docs/models.md §2.1): involute stage -(E_ws + E_wi)/(2 r1 i16 cos a') with
cos a' = a0 cos a cos b/(a0 + a1) (cos b and 1/cos b by their series below b = 1e-3 rad);
cycloid stage Eq. 16 with every term in arcmin, in the physical reading the modification
backlash 2(dr_rp - s dr_p)/(e zc) (s = sqrt(1 - K1^2)) and every term times
lambda = (zc/zp)(1 - 1/i16), Kn of Eq. 17; crank term du cos b/(a0 + a1).
Outputs: hysteresis_arcmin (Eq. 21, stages clipped at zero), involute_stage_arcmin,
cycloid_stage_arcmin, crank_bearing_arcmin, preload_arcmin (sum of max(0, -stage)) and the
one preload rule's five (crates/models/src/preload, docs/models.md §14.5): the cycloid
stage judged on its profile (the clearances at the pins' places 2πi/z_p of the modification
with its errors, the pin circle, pin radius and eccentricity errors, δJ, ΔF_r, δt and ΔF_p as
an equivalent equidistant amount), both discs alike, by the zero-torque balance of the pins
(safeguarded Newton steps on Σ max(0, l·y − g)·l, vectorised over the rows); its largest
approach (preload_overlap_um), pin force by two Palmgren line contacts
(preload_pin_force_n), no-load torque at the input (no_load_torque_nm), and the indicators
preloaded and over_preloaded (a pin force above the design's largest at rated torque,
computed once as rvtol does, or a jammed involute or crank stage). An over-preloaded
assembly counts out of the lost-motion spec; a preload within the limit conforms (no Cpk
is given while any over-preloaded sample lies within the limits, as in rvtol's report).
The reducer's parameters come from the scenario's reducer file; an input bound to
"reducer.KEY" takes its value.

Rows go in chunks of 1,000,000. Per output: mean, sd (n-1), skewness g1, excess kurtosis
g2 (merged chunk by chunk), min, max, the percentiles 0.135 / 2.275 / 15.866 / 50 /
84.134 / 97.725 / 99.865 (type 7, numpy's default "linear", read from the sorted
values) and a 40-bin histogram over [min, max].

    python3 rv20e_numpy.py --samples 10000000 --seed 20221013

Statistics go to stdout (and to --json FILE when given, after the timer stops); elapsed
wall time and ns/sample (time.perf_counter around the whole job, excluding interpreter
start-up and imports) go to stderr.
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
# 99.865 % quantile of the standard Rayleigh law, sqrt(-2 ln 0.00135) (crates/deviation/src/scalar.rs).
RAYLEIGH_QUANTILE = 3.635_285_597_179_897
# cos beta and 1/cos beta come from their series below beta^2 = 1e-6 (beta = 1e-3 rad).
TILT_SERIES_LIMIT = 1e-6
MIN_ACCEPTANCE_RATE = 0.01
# The preload rule (crates/models/src/preload/mod.rs): Palmgren's line contact, two per pin.
PALMGREN = 3.84e-5
CONTACTS_PER_PIN = 2.0
LEVER_FLOOR = 1e-12
RATED_POSITIONS = 4
# Rows of the rule's pin matrices at a time (rows × pins doubles per array).
RULE_BLOCK = 65536
DEFAULT_SCENARIO = os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenarios", "rv20e-hysteresis.json"
)

# geometric_hysteresis inputs in the model's order; x[2..12] carry Eq. 16's coefficients.
# The 19th, fit_measurement_error_mm, acts only with selective fitting, which this reference
# does not implement (Hysteresis refuses pin_classes > 1), so it is not read.
INPUTS = [
    "common_normal_upper_deviation_mm", "common_normal_lower_deviation_mm",
    "equidistant_modification_mm", "shift_modification_mm",
    "pin_circle_radius_error_mm", "pin_radius_error_mm", "pin_hole_clearance_mm",
    "cycloid_radial_runout_mm", "pin_hole_position_error_mm",
    "cycloid_cumulative_pitch_error_mm", "equidistant_modification_error_mm",
    "shift_modification_error_mm", "eccentricity_error_mm", "crank_bearing_clearance_mm",
    "input_shaft_du_mm", "input_shaft_dv_mm", "input_shaft_dalpha_rad", "input_shaft_dbeta_rad",
]
# Continuous outputs, in the model's order, then the preload rule's two indicators;
# `pin_class` exists only with selective fitting.
OUTPUTS = ["hysteresis_arcmin", "involute_stage_arcmin", "cycloid_stage_arcmin",
           "crank_bearing_arcmin", "preload_arcmin", "preload_overlap_um",
           "preload_pin_force_n", "no_load_torque_nm"]
INDICATORS = ["preloaded", "over_preloaded"]
SIX_DOF = ["du", "dv", "dw", "dalpha", "dbeta", "dgamma"]


class Hysteresis:
    """geometric_hysteresis with its checked geometry (from_params in the Rust)."""

    def __init__(self, p):
        zp, zc, z1, z2 = p["pin_count"], p["cycloid_teeth"], p["sun_teeth"], p["planet_teeth"]
        if p.get("pin_classes", 1) > 1:
            raise NotImplementedError("selective fitting (pin_classes > 1)")
        reading = p.get("reading", "physical")
        if reading not in ("physical", "document_000"):
            raise ValueError(f"reading must be physical or document_000, got {reading!r}")
        physical = reading == "physical"
        self.ratio = 1.0 + (z2 * zp) / (z1 * (zp - zc))  # 000 Eq. 4
        e, zc, rp = p["eccentricity_mm"], float(zc), p["pin_circle_radius_mm"]
        k1 = p.get("curtate_ratio", e * zp / rp)
        s = math.sqrt(1.0 - k1 * k1)
        self.a0 = p["center_distance_mm"]
        self.z_sun = p.get("sun_gear_axial_position_mm", 0.0)
        # Eq. 5/12: involute = -(E_ws + E_wi)*scale*(a0 + a1)/cos(beta)
        self.involute_scale = ARCMIN_PER_RAD / (
            2.0 * p["sun_pitch_radius_mm"] * self.ratio * self.a0
            * math.cos(math.radians(p.get("pressure_angle_deg", 20.0))))
        # Eq. 16, every term in arcmin, carried to the output by
        # lambda = (zc/zp)(1 - 1/i16) in the physical reading (1 in document_000).
        lam = zc / zp * (1.0 - 1.0 / self.ratio) if physical else 1.0
        q = ARCMIN_PER_RAD / (e * zc) * lam
        self.cycloid_coefficients = [  # for INPUTS[2:12]
            (2.0 if physical else 2.0 * s) * q,  # Δr_rp: 2(Δr_rp − s·Δr_p)/(e·zc) physical
            -2.0 * s * q,   # Δr_p
            2.0 * s * q,    # δr_p
            -2.0 * q,       # δr_rp
            q,              # δJ
            0.5 * q,        # ΔF_r
            2.0 * k1 * q,   # δt
            -k1 * q,        # ΔF_p
            2.0 * q,        # δΔr_rp
            -2.0 * s * q,   # δΔr_p
        ]
        # Eq. 17: Kn = kn_eq·Δr_rp + kn_sh·Δr_p (× λ); the term is −2·(10800/π)·Kn·δe.
        self.kn_equidistant = lam / (e * e * zc)
        self.kn_shift = -lam * (zc / (e * rp * rp * s) + s / (e * zc))
        # The preload rule, with λ of the physical reading whatever the reading; δJ, ΔF_r,
        # δt and ΔF_p enter its profile as an equidistant amount of backlash 2δ/(e·zc) at
        # the disc (geometric_hysteresis.rs `judge`).
        self.rule = PreloadRule(p, zc / zp * (1.0 - 1.0 / self.ratio), self.ratio)
        self.disc_per_arcmin = 1.0 / (ARCMIN_PER_RAD * lam)
        self.pitch_lever = e * zc

    def bind(self, binding, n_rows):
        """Prepares the column form for `binding`: input name -> float (a constant) or int
        (a row of the (n_rows, m) block of drawn columns evaluate() gets)."""
        self.binding = binding
        ids = [binding[name] for name in INPUTS]  # KeyError: an unbound input
        const = 0.0
        w = np.zeros(n_rows)
        for b, c in zip(ids[2:12], self.cycloid_coefficients):
            if isinstance(b, int):
                w[b] += c
            else:
                const += c * b
        eq, sh, de = ids[2], ids[3], ids[12]
        self.kn_rows = None
        if isinstance(eq, int) or isinstance(sh, int):
            self.kn_rows = (eq, sh, de)  # Kn·δe is not linear: evaluated row by row
        else:
            kn_term = -2.0 * ARCMIN_PER_RAD * (self.kn_equidistant * eq + self.kn_shift * sh)
            if isinstance(de, int):
                w[de] += kn_term
            else:
                const += kn_term * de
        self.cycloid_const = const
        used = np.flatnonzero(w)
        # One matrix-vector product over the rows the cycloid stage reads.
        self.cycloid_rows = slice(used[0], used[-1] + 1) if used.size else slice(0, 0)
        self.cycloid_weights = w[self.cycloid_rows]

    def evaluate(self, X, out, indicators, tmp):
        """X: (n_rows, m) block of drawn columns; out: (8, m) rows of OUTPUTS and
        indicators: (2, m) rows of INDICATORS, written in place; tmp: (3, m) scratch."""
        def x(name):
            b = self.binding[name]
            return X[b] if isinstance(b, int) else b

        hyst, invol, cyc, crank, preload = out[:5]
        t0, t1, t2 = tmp
        # Input shaft at the sun mesh, point_displacement at (0, 0, z) with dw = dgamma = 0.
        du, dv = x("input_shaft_du_mm"), x("input_shaft_dv_mm")
        da, db = x("input_shaft_dalpha_rad"), x("input_shaft_dbeta_rad")
        if self.z_sun != 0.0:
            du = du + db * self.z_sun
            dv = dv - da * self.z_sun
        a1 = np.multiply(du, du, out=t0)
        a1 += np.multiply(dv, dv, out=t1)
        np.sqrt(a1, out=a1)
        tilted = np.add(a1, self.a0, out=t0)                     # a0 + a1
        beta2 = np.multiply(da, da, out=t1)
        beta2 += np.multiply(db, db, out=t2)
        if not beta2.max() < TILT_SERIES_LIMIT:                  # beyond the series, or NaN
            big = ~(beta2 < TILT_SERIES_LIMIT)
            cos_big = np.cos(np.sqrt(beta2[big]))
        else:
            big = None
        # 1/cos beta = 1 + b/2 + 5b²/24 into invol, cos beta = 1 − b/2 + b²/24 into crank
        np.multiply(beta2, 5.0 / 24.0, out=invol)
        invol += 0.5
        invol *= beta2
        invol += 1.0
        np.multiply(beta2, 1.0 / 24.0, out=crank)
        crank -= 0.5
        crank *= beta2
        crank += 1.0
        if big is not None:
            invol[big] = 1.0 / cos_big
            crank[big] = cos_big
        # Involute stage, Eq. 5 / 12 with cos α' = a0·cos α·cos β/(a0 + a1).
        invol *= tilted
        invol *= -(x("common_normal_upper_deviation_mm") + x("common_normal_lower_deviation_mm")) \
            * self.involute_scale
        # Crank bearing clearance, Eq. 20: Δu·cos β/(a0 + a1).
        crank /= tilted
        crank *= x("crank_bearing_clearance_mm")
        crank *= ARCMIN_PER_RAD
        # Cycloid–pin stage, Eq. 16/17.
        np.dot(self.cycloid_weights, X[self.cycloid_rows], out=cyc)
        cyc += self.cycloid_const
        if self.kn_rows is not None:
            eq, sh, de = (X[b] if isinstance(b, int) else b for b in self.kn_rows)
            cyc -= 2.0 * ARCMIN_PER_RAD * (self.kn_equidistant * eq + self.kn_shift * sh) * de
        # Eq. 21 and the preload: each stage clipped at zero.
        np.maximum(invol, 0.0, out=hyst)
        hyst += np.maximum(cyc, 0.0, out=t0)
        hyst += np.maximum(crank, 0.0, out=t0)
        np.negative(cyc, out=t0)
        np.maximum(t0, 0.0, out=t0)                               # max(0, −Δφ34)
        np.negative(invol, out=preload)
        np.maximum(preload, 0.0, out=preload)
        preload += t0
        np.negative(crank, out=t0)
        np.maximum(t0, 0.0, out=t0)
        preload += t0
        self.judge(x, out, indicators)

    def judge(self, x, out, indicators):
        """The preload rule's outputs (geometric_hysteresis.rs `judge`), block by block."""
        m = out.shape[1]
        invol, cyc, crank = out[1], out[2], out[3]
        full = lambda v: np.broadcast_to(v, (m,))
        others = sum(c * x(name) for c, name in zip(self.cycloid_coefficients[4:8], INPUTS[6:10]))
        equivalent = full(0.5 * others * self.disc_per_arcmin * self.pitch_lever)
        equidistant = full(x(INPUTS[2]) + x(INPUTS[10])) + equivalent
        shift = full(x(INPUTS[3]) + x(INPUTS[11]))
        errors = [full(x(INPUTS[4])), full(x(INPUTS[5])), full(x(INPUTS[12]))]
        design = (x(INPUTS[2]), x(INPUTS[3]))
        if not all(isinstance(v, float) for v in design):
            raise NotImplementedError("a drawn design modification (the rated force per row)")
        judged = np.empty((5, min(m, RULE_BLOCK)))
        for a in range(0, m, RULE_BLOCK):
            b = min(m, a + RULE_BLOCK)
            jammed = (invol[a:b] < 0.0) | (crank[a:b] < 0.0)
            j = judged[:, :b - a]
            self.rule.judge(equidistant[a:b], shift[a:b], [v[a:b] for v in errors], jammed, design, j)
            nan = 0.0 * (invol[a:b] + cyc[a:b] + crank[a:b])
            out[5:8, a:b] = j[:3] + nan
            indicators[:, a:b] = j[3:] + nan


def illinois_root(f, lo, hi):
    """A root of f on [lo, hi] by the Illinois regula falsi (balance.rs `root`)."""
    f_lo, f_hi = f(lo), f(hi)
    if f_lo == 0.0:
        return lo
    if f_hi == 0.0:
        return hi
    if math.copysign(1.0, f_lo) == math.copysign(1.0, f_hi):
        return math.nan
    tolerance = 1e-15 * max(abs(hi - lo), abs(lo), abs(hi))
    side = 0
    for _ in range(200):
        mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        if not min(lo, hi) < mid < max(lo, hi):
            mid = 0.5 * (lo + hi)
        f_mid = f(mid)
        if f_mid == 0.0 or abs(hi - lo) <= tolerance:
            return mid
        if math.copysign(1.0, f_mid) == math.copysign(1.0, f_hi):
            hi, f_hi = mid, f_mid
            if side == -1:
                f_lo *= 0.5
            side = -1
        else:
            lo, f_lo = mid, f_mid
            if side == 1:
                f_hi *= 0.5
            side = 1
    return 0.5 * (lo + hi)


class PreloadRule:
    """The one preload rule (crates/models/src/preload/mod.rs, balance.rs `alike`)."""

    def __init__(self, p, lam, ratio):
        zp, zc = p["pin_count"], p["cycloid_teeth"]
        e, rp, rrp = p["eccentricity_mm"], p["pin_circle_radius_mm"], p["pin_radius_mm"]
        self.zp, self.zc, self.e = zp, zc, e
        self.k1 = e * zp / rp
        self.face_power = p["disc_face_width_mm"] ** 0.8
        self.friction = p.get("pin_friction_coefficient", 0.0)
        self.ratio = ratio
        self.disc_torque = 0.5 * lam * p["rated_torque_nm"] * 1000.0
        self.limit_force = p.get("preload_limit_pin_force_n")
        self.limit_overlap = p.get("preload_limit_overlap_um", math.inf)
        self.limit_torque = p.get("preload_limit_no_load_torque_nm", math.inf)
        f = self.factors(np.arange(zp) * 2.0 * math.pi / zp)
        keep = np.abs(f["lever"]) > LEVER_FLOOR * e
        self.columns = {k: v[keep] for k, v in f.items()}
        lever, cos = self.columns["lever"], self.columns["cos"]
        self.inverse = 1.0 / lever
        self.drive = lever > 0.0
        s = np.sqrt(1.0 + self.k1 ** 2 - 2.0 * self.k1 * cos)
        self.arm = np.abs((rp * (self.k1 * cos - 1.0) - e * (self.k1 - cos)) / s + rrp)
        self.rated = {}

    def factors(self, phi):
        """The pin factors at the pins' places phi (cycloid.rs `pin_factors_at`)."""
        sin, cos, k1 = np.sin(phi), np.cos(phi), self.k1
        s = np.sqrt(1.0 + k1 * k1 - 2.0 * k1 * cos)
        return {
            "lever": self.e * self.zc * sin / s,
            "equidistant": 1.0 - sin / s,
            "shift": -(1.0 - k1 * cos - math.sqrt(1.0 - k1 * k1) * sin) / s,
            "radial": (1.0 - k1 * cos) / s,
            "eccentric": (k1 - cos) / s,
            "cos": cos,
        }

    def approach(self, force):
        return CONTACTS_PER_PIN * PALMGREN * force ** 0.9 / self.face_power

    def force_at(self, approach):
        return (approach * self.face_power / (CONTACTS_PER_PIN * PALMGREN)) ** (1.0 / 0.9)

    def rated_pin_force(self, equidistant, shift):
        """F_r of the modification: the design's profile brought to zero play, one disc
        carrying λ·T_r/2, the largest over the pins' places per pitch (mod.rs)."""
        if self.limit_force is not None:
            return self.limit_force
        key = (equidistant, shift)
        if key not in self.rated:
            places = sorted({(self.zc * k % RATED_POSITIONS) / RATED_POSITIONS
                             for k in range(RATED_POSITIONS)})
            forces = []
            for f in places:
                pins = self.factors((np.arange(self.zp) + f) * 2.0 * math.pi / self.zp)
                keep = np.abs(pins["lever"]) > LEVER_FLOOR * self.e
                gaps = equidistant * pins["equidistant"][keep] + shift * pins["shift"][keep]
                forces.append(self.closed_pin_force(gaps, pins["lever"][keep]))
            self.rated[key] = max(forces)
        return self.rated[key]

    def closed_pin_force(self, gaps, levers):
        """balance.rs `closed_pin_force`: the secant stiffness iterated to its fixed point."""
        def flanks(g):
            ratio = g / levers
            return ratio[levers > 0.0].min(), (-ratio[levers < 0.0]).min()

        def play(c):
            lag, lead = flanks(gaps + c)
            return lag + lead

        def moment(y):
            d = levers * y - gaps
            return float(np.sum(np.where(d > 0.0, d * levers, 0.0)))

        scale = max(1e-6, float(np.abs(gaps).max()))
        gaps = gaps + illinois_root(play, -4.0 * scale, 4.0 * scale)
        lag, lead = flanks(gaps)
        lo = min(lag, -lead)
        force = 4.0 * self.disc_torque / (self.zp * self.e * self.zc)
        for _ in range(200):
            stiffness = force / self.approach(force)
            target = self.disc_torque / stiffness
            y = illinois_root(lambda y: target - moment(y), lo - 1.0, abs(lo) + 1.0)
            following = stiffness * float((levers * y - gaps).max())
            settled = abs(following - force) <= 1e-12 * following
            force = following
            if settled:
                break
        return force

    def judge(self, equidistant, shift, errors, jammed, design, out):
        """The rule's five outputs into out (5, m) for rows with the modification
        (equidistant, shift) and errors (pin circle, pin radius, eccentricity), each (m,)."""
        c = self.columns
        pin_circle, pin_radius, eccentric = errors
        gaps = (equidistant[:, None] * c["equidistant"] + shift[:, None] * c["shift"]
                + pin_circle[:, None] * c["radial"] - pin_radius[:, None]
                + eccentric[:, None] * c["eccentric"])
        ratio = gaps * self.inverse
        lag = np.where(self.drive, ratio, np.inf).min(axis=1)
        lead = np.where(self.drive, np.inf, -ratio).min(axis=1)
        overlapping = (lag + lead) < 0.0            # False for NaN: no overlap to balance
        overlap, force, torque = np.zeros_like(lag), np.zeros_like(lag), np.zeros_like(lag)
        rows = np.flatnonzero(overlapping)
        if rows.size:
            g = gaps[rows]
            y = self.balance(g, lag[rows], -lead[rows])
            d = self.columns["lever"] * y[:, None] - g
            largest = np.maximum(d.max(axis=1), 0.0)
            loaded = largest > 0.0
            f = np.where(loaded, self.force_at(largest), 0.0)
            stiffness = np.where(loaded, f / np.where(loaded, largest, 1.0), 0.0)
            drag = stiffness * np.where(d > 0.0, d * self.arm, 0.0).sum(axis=1)
            overlap[rows] = 1000.0 * largest
            force[rows] = f
            torque[rows] = self.friction * 2.0 * drag / self.ratio / 1000.0
        over = jammed | (overlapping & ((overlap > self.limit_overlap) | (torque > self.limit_torque)
                                        | (force > self.rated_pin_force(*design))))
        out[0], out[1], out[2] = overlap, force, torque
        out[3] = jammed | overlapping
        out[4] = over

    def balance(self, gaps, lo, hi):
        """The zero-torque balance y of each row (balance.rs `alike`): safeguarded Newton
        steps on the piecewise linear T(y) = Σ max(0, l·y − g)·l from the bracket's middle."""
        levers = self.columns["lever"]
        y = 0.5 * (lo + hi)
        active = np.arange(y.size)
        for _ in range(100):
            if active.size == 0:
                break
            ya, la, ha = y[active], lo[active], hi[active]
            d = levers * ya[:, None] - gaps[active]
            carried = d > 0.0
            dl = np.where(carried, d * levers, 0.0)
            moment = dl.sum(axis=1)
            size = np.abs(dl).sum(axis=1)
            slope = np.where(carried, levers * levers, 0.0).sum(axis=1)
            root = np.abs(moment) <= 1e-13 * size
            below = moment < 0.0
            la = np.where(below, ya, la)
            ha = np.where(below, ha, ya)
            with np.errstate(divide="ignore", invalid="ignore"):
                newton = ya - moment / slope
            following = np.where((newton > la) & (newton < ha), newton, 0.5 * (la + ha))
            settled = np.abs(following - ya) <= 1e-15 * np.maximum(np.abs(ha - la), np.abs(ya))
            y[active] = np.where(root, ya, following)
            lo[active], hi[active] = la, ha
            active = active[~(root | settled)]
        return y


def variable_sampler(dist):
    """A function (rng, out) that fills `out` with draws of a scenario variable's law."""
    (kind, d), = dist.items()
    if kind in ("tolerance_band", "folded_normal"):
        mean = 0.5 * (d["lower"] + d["upper"]) + d.get("mean_shift", 0.0)
        sd = (d["upper"] - d["lower"]) / (6.0 * d.get("cp", 1.0))
    elif kind == "normal":
        mean, sd = d["mean"], d["sd"]
    if kind in ("tolerance_band", "normal"):
        def draw(rng, out):
            rng.standard_normal(out=out)
            out *= sd
            out += mean
    elif kind == "folded_normal":
        def draw(rng, out):
            rng.standard_normal(out=out)
            out *= sd
            out += mean
            np.abs(out, out=out)
    elif kind == "rayleigh":
        sigma = d["upper"] / (RAYLEIGH_QUANTILE * d.get("cp", 1.0))

        def draw(rng, out):  # sigma·sqrt(2E): the law of sigma·sqrt(z1² + z2²)
            rng.standard_exponential(out=out)
            out *= 2.0 * sigma * sigma
            np.sqrt(out, out=out)
    elif kind == "lognormal":
        mu = math.log(d["median"])
        sigma = math.log(d["upper"] / d["median"]) / (3.0 * d.get("cp", 1.0))

        def draw(rng, out):
            rng.standard_normal(out=out)
            out *= sigma
            out += mu
            np.exp(out, out=out)
    elif kind == "uniform":
        def draw(rng, out):
            rng.random(out=out)
            out *= d["upper"] - d["lower"]
            out += d["lower"]
    elif kind == "triangular":
        def draw(rng, out):
            out[:] = rng.triangular(d["lower"], d["mode"], d["upper"], out.size)
    else:
        raise NotImplementedError(f"distribution {kind}")
    return draw


class RotatedPair:
    """a·x + b·y ≤ bound over independent x ~ N(mx, sx²), y ~ N(my, sy²), drawn as rvtol's
    RotatedPair does: z_s = (a·x + b·y − μs)/σs and an independent z_t; only z_s is
    redrawn until z_s ≤ τ."""

    def __init__(self, mx, sx, my, sy, a, b, bound):
        self.mx, self.sx, self.my, self.sy = mx, sx, my, sy
        sigma_s = math.hypot(a * sx, b * sy)
        self.c1, self.c2 = a * sx / sigma_s, b * sy / sigma_s
        self.tau = (bound - a * mx - b * my) / sigma_s
        self.acceptance = 0.5 * math.erfc(-self.tau / math.sqrt(2.0))

    def fill(self, rng, x, y, zs, zt):
        """Fills x and y (length m) with conditioned draws; zs, zt are scratch of length m.
        Returns the candidate draws of z_s up to the one that filled the last row."""
        m, p = x.size, self.acceptance
        filled = attempts = 0
        while filled < m:
            need = m - filled
            # enough candidates for `need` acceptances with near certainty: one batch
            k = int(need / p + 4.0 * math.sqrt(need * (1.0 - p)) / p) + 16
            z = rng.standard_normal(k)
            ok = np.flatnonzero(z <= self.tau)
            if ok.size >= need:
                attempts += int(ok[need - 1]) + 1
                ok = ok[:need]
            else:
                attempts += k
            np.take(z, ok, out=zs[filled:filled + ok.size])
            filled += ok.size
        rng.standard_normal(out=zt)
        # x = mx + sx·(c1·z_s − c2·z_t), y = my + sy·(c2·z_s + c1·z_t)
        np.multiply(zs, self.c1 * self.sx, out=x)
        x -= np.multiply(zt, self.c2 * self.sx, out=y)
        x += self.mx
        np.multiply(zs, self.c2 * self.sy, out=y)
        zt *= self.c1 * self.sy
        y += zt
        y += self.my
        return attempts


class Moments:
    """Count, mean and central sums M2..M4, merged chunk by chunk (Pébay 2008)."""

    def __init__(self):
        self.n, self.mean, self.m2, self.m3, self.m4 = 0, 0.0, 0.0, 0.0, 0.0
        self.lo, self.hi = math.inf, -math.inf

    def add(self, v, tmp):
        nb = v.size
        mb = float(v.mean())
        d = np.subtract(v, mb, out=tmp[0])
        d2 = np.multiply(d, d, out=tmp[1])
        m2b, m3b, m4b = float(d2.sum()), float(np.dot(d2, d)), float(np.dot(d2, d2))
        na, n = self.n, self.n + nb
        delta = mb - self.mean
        self.m4 += (m4b + delta ** 4 * na * nb * (na * na - na * nb + nb * nb) / n ** 3
                    + 6.0 * delta ** 2 * (na * na * m2b + nb * nb * self.m2) / n ** 2
                    + 4.0 * delta * (na * m3b - nb * self.m3) / n)
        self.m3 += (m3b + delta ** 3 * na * nb * (na - nb) / n ** 2
                    + 3.0 * delta * (na * m2b - nb * self.m2) / n)
        self.m2 += m2b + delta * delta * na * nb / n
        self.mean += delta * nb / n
        self.n = n


def summarise(v, mom):
    """Statistics of one output column; sorts v in place (min, max, percentiles and
    histogram are read from the sorted values)."""
    n, m2 = mom.n, mom.m2
    v.sort()
    lo, hi = float(v[0]), float(v[-1])
    h = (n - 1) * np.array(PERCENTILES) / 100.0  # type 7: between order statistics
    i = np.floor(h).astype(np.int64)
    frac = h - i
    below, above = v[i], v[np.minimum(i + 1, n - 1)]
    pct = below + frac * (above - below)
    edges = np.linspace(lo, hi, BINS + 1)
    # bins [e_k, e_k+1), the last one closed, as np.histogram
    cut = np.searchsorted(v, edges[1:-1], side="left")
    counts = np.diff(np.concatenate(([0], cut, [n])))
    return {
        "mean": mom.mean,
        "sd": math.sqrt(m2 / (n - 1)),
        "skewness": math.sqrt(n) * mom.m3 / m2 ** 1.5 if m2 > 0 else 0.0,
        "excess_kurtosis": n * mom.m4 / (m2 * m2) - 3.0 if m2 > 0 else 0.0,
        "min": lo,
        "max": hi,
        "percentiles": pct,
        "histogram": (counts, edges),
    }


def reducer_params(scenario, path):
    """The scenario's reducer: its file's parameters, then those given inline."""
    reducer = scenario.get("reducer", {})
    params = {}
    if "file" in reducer:
        with open(os.path.join(os.path.dirname(os.path.abspath(path)), reducer["file"])) as f:
            params.update(json.load(f)["params"])
    params.update(reducer.get("params", {}))
    return params


def run(scenario, n, seed, path):
    if scenario.get("correlations"):
        raise NotImplementedError("correlations")
    model_spec, = scenario["models"]
    assert model_spec["model"] == "geometric_hysteresis"
    reducer = reducer_params(scenario, path)
    model = Hysteresis({**reducer, **model_spec["params"]})

    # The block of drawn columns: the variables in scenario order, then each part's
    # drawn components; dw and dgamma of a tolerance band are exactly 0.
    names = [v["name"] for v in scenario["variables"]]
    samplers = [variable_sampler(v["distribution"]) for v in scenario["variables"]]
    row_of = {name: r for r, name in enumerate(names)}
    parts = []  # (rows [du, dv, dalpha, dbeta], pairs or None, means, sds)
    for part in scenario.get("parts", []):
        tb = part.get("tolerance_band")
        if tb is None:
            raise NotImplementedError("parts other than a tolerance band")
        dt, L = tb["delta_tau_mm"], tb["length_mm"]
        rows = {}
        for c in ("du", "dv", "dalpha", "dbeta"):
            rows[c] = len(row_of)
            row_of[f"{part['name']}.{c}"] = rows[c]
        for c in ("dw", "dgamma"):
            row_of[f"{part['name']}.{c}"] = 0.0
        # 001 Eq. 10 means and Eq. 12 sds; Eq. 11 pairs (du, dbeta) and (dv, dalpha).
        mean = {"du": dt / 2, "dv": dt / 2, "dalpha": dt / L, "dbeta": dt / L}
        sd = {"du": dt / 6, "dv": dt / 6, "dalpha": dt / (3 * L), "dbeta": dt / (3 * L)}
        pairs = None
        if tb.get("constraint_eq11", False):
            pairs = [(("du", "dbeta"), RotatedPair(mean["du"], sd["du"], mean["dbeta"], sd["dbeta"], 1.0, L / 2, dt)),
                     (("dv", "dalpha"), RotatedPair(mean["dv"], sd["dv"], mean["dalpha"], sd["dalpha"], 1.0, L / 2, dt))]
            rate = pairs[0][1].acceptance * pairs[1][1].acceptance
            if rate < MIN_ACCEPTANCE_RATE:
                raise ValueError(f"the Eq. 11 constraint accepts only {100 * rate:.3f} % of draws")
        parts.append((rows, pairs, mean, sd))
    binding = {}
    for k, b in model_spec["inputs"].items():
        if isinstance(b, str) and b.startswith("reducer."):
            binding[k] = float(reducer[b[len("reducer."):]])
        else:
            binding[k] = row_of[b] if isinstance(b, str) else float(b)
    n_rows = len(names) + 4 * len(parts)
    model.bind(binding, n_rows)

    limits = scenario.get("spec_limits", {})
    spec = {}
    for name, lim in limits.items():
        if name not in OUTPUTS:
            raise NotImplementedError(f"spec limits on {name}")
        lower = lim.get("lower")
        upper = lim.get("upper")
        # over-preloaded samples are non-conforming for hysteresis_arcmin (its condition)
        flagged = name == "hysteresis_arcmin"
        spec[OUTPUTS.index(name)] = (lower, upper, flagged)

    # SFC64, numpy's fastest bit generator (its normals cost 20 % less than PCG64's).
    rng = np.random.Generator(np.random.SFC64(seed))
    values = np.empty((len(OUTPUTS), n))       # every output value, for the percentiles
    X = np.empty((n_rows, min(CHUNK, n)))
    tmp = np.empty((3, min(CHUNK, n)))
    flags = np.empty((len(INDICATORS), min(CHUNK, n)))
    moments = [Moments() for _ in OUTPUTS]
    counts = {j: [0, 0] for j in spec}          # out of spec, flagged within the limits
    events = [0] * len(INDICATORS)
    candidates = [0] * (2 * len(parts))
    for start in range(0, n, CHUNK):
        m = min(CHUNK, n - start)
        Xm, tm = X[:, :m], tmp[:, :m]
        for r, draw in enumerate(samplers):
            draw(rng, Xm[r])
        for p, (rows, pairs, mean, sd) in enumerate(parts):
            if pairs is None:
                for c, r in rows.items():
                    rng.standard_normal(out=Xm[r])
                    Xm[r] *= sd[c]
                    Xm[r] += mean[c]
            else:
                for g, ((cx, cy), pair) in enumerate(pairs):
                    candidates[2 * p + g] += pair.fill(rng, Xm[rows[cx]], Xm[rows[cy]], tm[0], tm[1])
        out = values[:, start:start + m]
        fm = flags[:, :m]
        model.evaluate(Xm, out, fm, tm)
        for k in range(len(INDICATORS)):
            events[k] += int(np.count_nonzero(fm[k] == 1.0))
        over = fm[1] == 1.0
        for j, mom in enumerate(moments):
            mom.add(out[j], tm)
        for j, (lower, upper, flagged) in spec.items():
            v = out[j]
            within = v <= upper if upper is not None else np.isfinite(v)
            if lower is not None:
                within &= v >= lower
            n_within = int(np.count_nonzero(within))
            flagged_within = int(np.count_nonzero(within & over)) if flagged else 0
            counts[j][0] += m - n_within + flagged_within
            counts[j][1] += flagged_within

    stats = {}
    for j, name in enumerate(OUTPUTS):
        st = summarise(values[j], moments[j])
        if j in spec:
            lower, upper, _ = spec[j]
            st["spec"] = (lower, upper)
            st["out_of_spec_fraction"] = counts[j][0] / n
            st["flagged_within_spec"] = counts[j][1]
            # rvtol gives no index while non-conforming samples hide within the limits
            sides = [(upper - st["mean"]) if upper is not None else math.inf,
                     (st["mean"] - lower) if lower is not None else math.inf]
            st["cpk"] = min(sides) / (3.0 * st["sd"]) if counts[j][1] == 0 else None
        stats[name] = st
    for name, k in zip(INDICATORS, events):
        stats[name] = k / n
    draws = sum(candidates)
    stats["constraint"] = {
        "candidate_draws": draws,
        "acceptance_rate": math.prod(n / c for c in candidates) if draws else 1.0,
    }
    return stats


def report(stats, n, seed):
    print(f"rv20e_numpy | {n:,} samples | seed {seed} | numpy {np.__version__} | percentiles numpy linear")
    c = stats["constraint"]
    if c["candidate_draws"]:
        print(f"constraint 001 Eq. 11: acceptance {c['acceptance_rate'] * 100:.2f} % "
              f"({c['candidate_draws']:,} candidate draws)")
    for name in OUTPUTS:
        st = stats[name]
        print(f"\n{name}")
        print(f"  mean {st['mean']:.6g}  sd {st['sd']:.6g}  skewness {st['skewness']:.5g}  "
              f"excess_kurtosis {st['excess_kurtosis']:.5g}  min {st['min']:.6g}  max {st['max']:.6g}")
        print("  " + "  ".join(f"P{p:g} {q:.6g}" for p, q in zip(PERCENTILES, st["percentiles"])))
        if "spec" in st:
            lower, upper = st["spec"]
            limit = " and ".join(s for s in (lower is not None and f"x >= {lower:g}",
                                             upper is not None and f"x <= {upper:g}") if s)
            cpk = (f"Cpk {st['cpk']:.5g}" if st["cpk"] is not None else
                   f"Cpk n/a ({st['flagged_within_spec']:,} over-preloaded samples within the limits)")
            print(f"  ({limit}) {cpk}  out of spec {st['out_of_spec_fraction'] * 1e6:.0f} ppm "
                  f"(over-preloaded counted out of spec)")
        counts, edges = st["histogram"]
        print(f"  histogram {BINS} bins over [{edges[0]:.6g}, {edges[-1]:.6g}]: "
              + " ".join(str(c) for c in counts))
    for name in INDICATORS:
        print(f"\n{name} {stats[name] * 100:.4f} % of samples")


def to_json(stats, n, seed):
    doc = {"samples": n, "seed": seed, "numpy": np.__version__,
           **{name: stats[name] for name in INDICATORS},
           "constraint": stats["constraint"], "outputs": {}}
    for name in OUTPUTS:
        st = dict(stats[name])
        st["percentiles"] = {f"{p:g}": float(q) for p, q in zip(PERCENTILES, st["percentiles"])}
        counts, edges = st.pop("histogram")
        st["histogram"] = {"lower_edge": float(edges[0]), "bin_width": float(edges[1] - edges[0]),
                           "counts": [int(c) for c in counts]}
        doc["outputs"][name] = st
    return doc


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--seed", type=int, default=20221013)
    ap.add_argument("--scenario", default=DEFAULT_SCENARIO)
    ap.add_argument("--json", metavar="FILE", help="also write the statistics as JSON")
    args = ap.parse_args()
    t0 = time.perf_counter()
    with open(args.scenario) as f:
        scenario = json.load(f)
    stats = run(scenario, args.samples, args.seed, args.scenario)
    report(stats, args.samples, args.seed)
    sys.stdout.flush()
    elapsed = time.perf_counter() - t0
    print(f"elapsed {elapsed:.3f} s, {elapsed * 1e9 / args.samples:.1f} ns/sample", file=sys.stderr)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(to_json(stats, args.samples, args.seed), f, indent=1)


if __name__ == "__main__":
    main()
