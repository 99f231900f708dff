//! Tests of the loaded contact solution: the one-disc limit against `cycloid_pin_contact`'s
//! load sharing (document 003's 683.76 N case and a modified profile), the equilibrium and
//! compatibility of two discs, preload, the light-load limit and the bounded failures.

use super::*;
use crate::cycloid_pin_contact::{CycloidPinContact, ENTRY};
use crate::ModelParams;

/// Document 003's RV-80E (validation.md: 40 pins, 39 teeth, e 1.5, r_p 76.5 mm, face width
/// 12 mm as cycloid_pin_contact's example) with 003's T_c = share·T.
fn rv80e(share: f64) -> CycloidPinContact {
    let params: ModelParams = (ENTRY.example_params)()
        .with_number("disc_load_share", share)
        .with_number("disc_torque_balance", 0.0);
    CycloidPinContact::from_params(&params).unwrap()
}

fn contact(model: &CycloidPinContact) -> PinContact {
    PinContact::new(model.face_width(), 0.0, 121.0)
}

/// One disc without crank compliance: its pins' forces at the turn y.
fn forces(contact: &PinContact, disc: &LoadedDisc, y: f64) -> Vec<f64> {
    let largest = disc
        .gaps
        .iter()
        .zip(disc.levers)
        .map(|(g, l)| l * y - g)
        .fold(0.0_f64, f64::max);
    let stiffness = contact.force_at(largest) / largest;
    disc.gaps
        .iter()
        .zip(disc.levers)
        .map(|(g, l)| stiffness * (l * y - g).max(0.0))
        .collect()
}

#[test]
fn one_disc_without_cranks_is_the_load_sharing_of_003() {
    // 003's RV-80E, unmodified, T_c = 400 N·m: cycloid_pin_contact's load sharing gives
    // F_max = T_c·max l/Σ l² = 0.99912 × 683.76 N (validation.md 003; that model's test
    // `unmodified_profile_gives_the_closed_form`). The per-pin solution on the same pins
    // must give the same turn and forces: the same contact law, the same equations.
    let model = rv80e(0.5);
    let sharing = model.solve(&[800.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let law = contact(&model);
    let gaps = vec![0.0; sharing.levers.len()];
    let disc = LoadedDisc {
        gaps: &gaps,
        levers: &sharing.levers,
        arms: &sharing.levers,
        offset: 0.0,
        slack: 0.0,
    };
    let y = one_disc(&law, &disc, 400_000.0).unwrap();
    assert!(
        (y / sharing.rotation - 1.0).abs() < 1e-12,
        "{y} vs {}",
        sharing.rotation
    );
    let ours = forces(&law, &disc, y);
    for (a, b) in ours.iter().zip(&sharing.forces) {
        assert!((a - b).abs() <= 1e-9 * b.max(1.0), "{a} vs {b}");
    }
    let f_max = ours.iter().cloned().fold(0.0, f64::max);
    assert!((f_max / 683.76 - 0.99912).abs() < 1e-4, "{f_max}");
    // A modified profile (003's 0.004/−0.008 mm, share 0.55: 8–11 pins loaded) too.
    let model = rv80e(0.55);
    let sharing = model.solve(&[800.0, 0.004, -0.008, 0.0, 0.0, 0.0, 0.0]);
    let disc = LoadedDisc {
        gaps: &sharing.clearances,
        levers: &sharing.levers,
        arms: &sharing.levers,
        offset: 0.0,
        slack: 0.0,
    };
    let y = one_disc(&law, &disc, 440_000.0).unwrap();
    assert!((y / sharing.rotation - 1.0).abs() < 1e-12);
    for (a, b) in forces(&law, &disc, y).iter().zip(&sharing.forces) {
        assert!((a - b).abs() <= 1e-9 * b.max(1.0), "{a} vs {b}");
    }
    // And the reverse flank under a negative moment: the mirror image (l → −l).
    let mirrored: Vec<f64> = sharing.levers.iter().map(|l| -l).collect();
    let disc = LoadedDisc {
        gaps: &sharing.clearances,
        levers: &mirrored,
        arms: &mirrored,
        offset: 0.0,
        slack: 0.0,
    };
    let y_mirror = one_disc(&law, &disc, -440_000.0).unwrap();
    assert!((y_mirror + y).abs() < 1e-12 * y.abs());
}

/// Levers of 003's RV-80E pins at φ_i = 2π·i/40 + `phase`, and gaps from a clearance per pin.
fn levers(phase: f64) -> Vec<f64> {
    let (k1, lever): (f64, f64) = (1.5 * 40.0 / 76.5, 1.5 * 39.0);
    (0..40)
        .map(|i| {
            let phi = 2.0 * std::f64::consts::PI * i as f64 / 40.0 + phase;
            let s = (1.0 + k1 * k1 - 2.0 * k1 * phi.cos()).sqrt();
            lever * phi.sin() / s
        })
        .collect()
}

fn law() -> PinContact {
    PinContact::new(12.0, 0.0, 121.0)
}

#[test]
fn the_secant_law_is_the_contact_laws() {
    // K(δ) = F(δ)/δ of PinContact (δ(F) = 2·3.84e-5·F^0.9/L^0.8) to a few ulps, and its
    // derivative K/(9δ) against a central difference.
    let contact = law();
    let secant = contact.secant_law();
    for approach in [1e-5, 3.3e-4, 2e-3, 0.02] {
        let (k, dk) = secant.stiffness(approach);
        let exact = contact.force_at(approach) / approach;
        assert!((k / exact - 1.0).abs() < 1e-14, "{k} {exact}");
        assert!((contact.approach(k * approach) / approach - 1.0).abs() < 1e-13);
        let h = 1e-6 * approach;
        let difference =
            (secant.stiffness(approach + h).0 - secant.stiffness(approach - h).0) / (2.0 * h);
        assert!((dk / difference - 1.0).abs() < 1e-6, "{dk} {difference}");
    }
}

#[test]
fn two_discs_balance_the_torque_and_share_one_carrier_angle() {
    // Two discs with different clearances and offsets, a crank compliance c: the solution
    // must satisfy M_1 + M_2 = M* and x = C_d + y_d + c·M_d for both discs to rounding.
    let levers = levers(0.013);
    let gaps_1: Vec<f64> = levers.iter().map(|l| 0.004 + 0.00002 * l.abs()).collect();
    let gaps_2: Vec<f64> = levers.iter().map(|l| 0.002 - 0.00001 * l).collect();
    let discs = [
        LoadedDisc {
            gaps: &gaps_1,
            levers: &levers,
            arms: &levers,
            offset: 1e-5,
            slack: 0.0,
        },
        LoadedDisc {
            gaps: &gaps_2,
            levers: &levers,
            arms: &levers,
            offset: -2e-5,
            slack: 0.0,
        },
    ];
    let solver = TwoDiscs::new(&law(), 2e-9);
    for target in [-50_000.0, -1_000.0, 3_000.0] {
        let s = solver.solve(&discs, target, &Solution::COLD).unwrap();
        let sum = s.moments[0] + s.moments[1];
        assert!(
            (sum - target).abs() <= 1e-9 * target.abs(),
            "{sum} vs {target}"
        );
        for (d, disc) in discs.iter().enumerate() {
            let (m, _) = disc.moment(&solver.law, s.turns[d]);
            assert!((m - s.moments[d]).abs() <= 1e-12 * target.abs());
            let x = disc.offset + s.turns[d] + solver.compliance * m;
            assert!((x - s.carrier).abs() < 1e-12, "{x} vs {}", s.carrier);
        }
        // Warm started from its own solution it stays there; from a point 1e-6 rad off
        // (the fast path: both turns by Newton's iteration) it reaches the safeguarded
        // iteration's solution to their tolerance.
        let again = solver.solve(&discs, target, &s).unwrap();
        assert!((again.carrier - s.carrier).abs() < 1e-12);
        assert_eq!(again.iterations, 1);
        let off = Solution {
            turns: [s.turns[0] + 1e-6, s.turns[1] - 2e-6],
            ..s
        };
        let fast = solver.solve(&discs, target, &off).unwrap();
        assert!(fast.iterations <= FAST_STEPS, "{}", fast.iterations);
        assert!(
            (fast.carrier - s.carrier).abs() < 1e-12,
            "{} {}",
            fast.carrier,
            s.carrier
        );
    }
}

#[test]
fn alike_discs_carry_half_each() {
    // Identical discs: each carries M*/2, at the one-disc turn for M*/2 (c = 0 there, and
    // the carrier c·M*/2 further).
    let levers = levers(0.05);
    let gaps: Vec<f64> = levers.iter().map(|l| 0.003 + 0.00003 * l.abs()).collect();
    let disc = LoadedDisc {
        gaps: &gaps,
        levers: &levers,
        arms: &levers,
        offset: 3e-5,
        slack: 0.0,
    };
    let solver = TwoDiscs::new(&law(), 5e-9);
    let target = -20_000.0;
    let s = solver
        .solve(&[disc, disc], target, &Solution::COLD)
        .unwrap();
    let alone = one_disc(&law(), &disc, 0.5 * target).unwrap();
    for d in 0..2 {
        assert!((s.moments[d] / (0.5 * target) - 1.0).abs() < 1e-9);
        assert!((s.turns[d] - alone).abs() < 1e-13);
    }
    let expected = disc.offset + alone + solver.compliance * 0.5 * target;
    assert!((s.carrier - expected).abs() < 1e-12);
}

#[test]
fn a_light_load_tends_to_the_first_contact() {
    // Free play on both discs, disc 2 further from contact: as M* → 0⁻ the carrier tends to
    // the rigid first contact on the drive flank, max_d (C_d + max over l < 0 of g/l), and
    // the second disc carries nothing once its window is out of reach. The elastic part
    // shrinks like |M*|^0.9 (pins; the crank side linearly).
    let levers = levers(0.02);
    let gaps: Vec<f64> = levers.iter().map(|l| 0.002 + 0.00001 * l.abs()).collect();
    let discs = [
        LoadedDisc {
            gaps: &gaps,
            levers: &levers,
            arms: &levers,
            offset: 0.0,
            slack: 0.0,
        },
        LoadedDisc {
            gaps: &gaps,
            levers: &levers,
            arms: &levers,
            // Its play is about ±(0.002/58.5 + 1e-5) = ±4.4e-5 rad: 3e-5 apart the windows
            // overlap, disc 1's drive end 3e-5 ahead of disc 2's.
            offset: -3e-5,
            slack: 0.0,
        },
    ];
    let first = discs
        .iter()
        .map(|d| d.offset + d.first_touch(-1.0))
        .fold(f64::NEG_INFINITY, f64::max);
    let solver = TwoDiscs::new(&law(), 2e-9);
    let gap = |target: f64| {
        let s = solver.solve(&discs, target, &Solution::COLD).unwrap();
        assert_eq!(s.moments[1], 0.0);
        first - s.carrier
    };
    let (coarse, fine) = (gap(-1_000.0), gap(-10.0));
    assert!(coarse > 0.0 && fine > 0.0);
    // 100 times less load: at least 100^0.9 / 2 = 31.6 times less elastic angle.
    assert!(coarse / fine > 31.0, "{coarse} {fine}");
    assert!(gap(-1e-6) < 1e-11);
}

#[test]
fn an_overlapping_pair_is_solved_on_both_flanks() {
    // 8 µm of overlap on every pin of both discs (far beyond any preload limit): both
    // flanks loaded at zero and at small torque, a finite solution in equilibrium.
    let levers = levers(0.031);
    let gaps = vec![-0.008; levers.len()];
    let disc = LoadedDisc {
        gaps: &gaps,
        levers: &levers,
        arms: &levers,
        offset: 0.0,
        slack: 0.0,
    };
    let twisted = LoadedDisc {
        offset: 2e-4,
        slack: 0.0,
        ..disc
    };
    let solver = TwoDiscs::new(&law(), 2e-9);
    for target in [-1e-3, -5_000.0] {
        let s = solver
            .solve(&[disc, twisted], target, &Solution::COLD)
            .unwrap();
        assert!(s.carrier.is_finite());
        assert!((s.moments[0] + s.moments[1] - target).abs() < 1e-6 * target.abs().max(1.0));
        // Both discs loaded on both flanks: a pin with l > 0 and one with l < 0 approach.
        for (d, y) in [disc, twisted].iter().zip(s.turns) {
            let approach = |sign: f64| {
                d.gaps
                    .iter()
                    .zip(d.levers)
                    .filter(|(_, l)| **l * sign > 0.0)
                    .map(|(g, l)| l * y - g)
                    .fold(f64::NEG_INFINITY, f64::max)
            };
            assert!(approach(1.0) > 0.0 && approach(-1.0) > 0.0);
        }
    }
}

#[test]
fn a_point_without_a_solution_fails_with_its_cause() {
    // No pin on the loaded flank (every lever positive under a negative moment), a
    // non-finite gap: bounded failures that name their cause, no hang.
    let levers: Vec<f64> = levers(0.0).iter().map(|l| l.abs() + 1.0).collect();
    let gaps = vec![0.001; levers.len()];
    let disc = LoadedDisc {
        gaps: &gaps,
        levers: &levers,
        arms: &levers,
        offset: 0.0,
        slack: 0.0,
    };
    let solver = TwoDiscs::new(&law(), 1e-9);
    let failed = solver.solve(&[disc, disc], -100.0, &Solution::COLD);
    assert_eq!(failed, Err(Unconverged::NoBracket));
    assert!(failed
        .unwrap_err()
        .to_string()
        .contains("no pin on the loaded flank"));
    let mut bad = gaps.clone();
    bad[3] = f64::NAN;
    let nan = LoadedDisc {
        gaps: &bad,
        levers: &levers,
        arms: &levers,
        offset: 0.0,
        slack: 0.0,
    };
    assert_eq!(
        solver.solve(&[disc, nan], 100.0, &Solution::COLD),
        Err(Unconverged::NoBracket)
    );
    assert_eq!(one_disc(&law(), &nan, 100.0), Err(Unconverged::NoBracket));
    assert!(Unconverged::Iterations
        .to_string()
        .contains("did not settle"));
    // Gaps that put the first contact 0.02 rad (twice MAX_TURN) away: refused at once,
    // cold and from a warm start, rather than bracketed by doubling.
    let far: Vec<f64> = levers.iter().map(|l| 0.02 * l.abs()).collect();
    let far_disc = LoadedDisc {
        gaps: &far,
        levers: &levers,
        arms: &levers,
        offset: 0.0,
        slack: 0.0,
    };
    assert_eq!(
        solver.solve(&[far_disc, far_disc], 100.0, &Solution::COLD),
        Err(Unconverged::BeyondSmallTurns)
    );
    let near: Vec<f64> = levers.iter().map(|l| 1e-4 * l.abs()).collect();
    let near_disc = LoadedDisc {
        gaps: &near,
        levers: &levers,
        arms: &levers,
        offset: 0.0,
        slack: 0.0,
    };
    let warm = solver
        .solve(&[near_disc, near_disc], 100.0, &Solution::COLD)
        .unwrap();
    assert!(warm.turns.iter().all(|t| t.abs() < MAX_TURN));
    assert_eq!(
        solver.solve(&[far_disc, far_disc], 100.0, &warm),
        Err(Unconverged::BeyondSmallTurns)
    );
}

#[test]
fn the_ninth_root_is_the_two_cube_roots_within_a_few_ulps() {
    use crate::preload::{ninth_root, ROOT_CELLS};
    // ninth_root against x.cbrt().cbrt() (SecantLaw::stiffness's, within an ulp or two of
    // the true root) over 1e-12..1e3 mm, every cell of the mantissa and every exponent
    // class mod 9: at most 4 ulps apart (the table's roots, the series' rounding and the
    // two cube roots' own error; the series' truncation is below 2·10⁻¹⁹).
    let mut worst = 0.0_f64;
    for i in 0..200_000 {
        // Exponents −40..10 in steps that fall on every mantissa cell (a step of
        // 2.5·10⁻⁴ in the exponent is 1/40 of a cell at most).
        let x = (-40.0 + 50.0 * (i as f64 / 200_000.0)).exp2();
        let (fast, reference) = (ninth_root(x), x.cbrt().cbrt());
        let ulps = (fast - reference).abs() / (reference * f64::EPSILON);
        worst = worst.max(ulps);
    }
    assert!(worst <= 4.0, "{worst} ulps");
    // The cells' edges and the exponent classes' edges.
    for e in -20..20 {
        for cell in 0..=ROOT_CELLS {
            let x = (1.0 + cell as f64 / ROOT_CELLS as f64) * f64::from(e).exp2();
            let x = if cell == ROOT_CELLS {
                f64::from(e + 1).exp2() * (1.0 - f64::EPSILON)
            } else {
                x
            };
            let (fast, reference) = (ninth_root(x), x.cbrt().cbrt());
            assert!(
                (fast - reference).abs() <= 4.0 * reference * f64::EPSILON,
                "{x}"
            );
        }
    }
    // Outside the normal range: the two cube roots themselves.
    for x in [0.0, 1e-310, f64::INFINITY] {
        assert_eq!(ninth_root(x).to_bits(), x.cbrt().cbrt().to_bits());
    }
}

#[test]
fn the_slack_is_taken_up_toward_each_disc_s_moment() {
    // A disc with needle slack s turns against the carrier by ±s without moment: under a
    // moment of one sign the solution is the slack-free one with the carrier s further
    // that way, each disc at the same turn; and a self-overlapping pair of discs (both
    // flanks carrying at rest, 2 µm of overlap) holds its own balance at zero torque
    // wherever the carrier stands within ±s of it (zero moment on each disc).
    let levers = levers(0.05);
    let gaps: Vec<f64> = levers.iter().map(|l| 0.003 + 0.00003 * l.abs()).collect();
    let tight = LoadedDisc {
        gaps: &gaps,
        levers: &levers,
        arms: &levers,
        offset: 3e-5,
        slack: 0.0,
    };
    let slack = 4e-5;
    let loose = LoadedDisc { slack, ..tight };
    let solver = TwoDiscs::new(&law(), 5e-9);
    for target in [-20_000.0, 15_000.0] {
        let a = solver
            .solve(&[tight, tight], target, &Solution::COLD)
            .unwrap();
        let warm = solver.at_rest(&[loose, loose]).unwrap();
        let b = solver.solve(&[loose, loose], target, &warm).unwrap();
        let shift = slack.copysign(target);
        assert!((b.carrier - a.carrier - shift).abs() < 1e-12, "{target}");
        for d in 0..2 {
            assert!((b.turns[d] - a.turns[d]).abs() < 1e-12);
            assert!((b.moments[d] / a.moments[d] - 1.0).abs() < 1e-9);
        }
    }
    let pressed: Vec<f64> = levers.iter().map(|_| -0.002).collect();
    let held = LoadedDisc {
        gaps: &pressed,
        slack,
        ..tight
    };
    let rest = solver.at_rest(&[held, held]).unwrap();
    let s = solver.solve(&[held, held], 0.0, &rest).unwrap();
    assert_eq!(s.moments, [0.0, 0.0]);
    assert!((s.turns[0] - rest.turns[0]).abs() < 1e-15);
}
