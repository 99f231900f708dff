//! What `TransmissionError::from_params` builds once, section by section: the reading the
//! parameters ask for ([`Reading`]), the physical reading's geometry beyond the stage
//! (crank circle, the discs' spacing, the sun's plane), the one preload rule, and the
//! curve's points grouped by the pin slots they see. Each reading builds its own tables
//! (`literal::Literal::new`, `two_discs::build`, `loaded::build`).

use rvtol_deviation::Shown;
use std::f64::consts::PI;

use super::common::{Group, Point};
use super::two_discs::{CrankClosure, DiscContact};
use crate::cycloid::CycloidStage;
use crate::preload::{self, PreloadRule};
use crate::{ModelError, ModelParams};

/// The reading the parameters ask for (docs/models.md §12): `reading`, `disc_contact` and
/// `crank_closure`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Reading {
    /// Document 002 read literally (one disc, the cranks averaged).
    pub literal: bool,
    /// How the two discs' rigid contacts make the output's.
    pub contact: DiscContact,
    /// The loaded contact solution (`disc_contact` "loaded", the physical reading's
    /// default); it keeps the rigid first contact's tables for its interference flag and
    /// preload judgement.
    pub under_load: bool,
    /// How a disc sits on its crank pins.
    pub closure: CrankClosure,
}

impl Reading {
    /// The reading of `params`.
    pub fn from_params(params: &ModelParams) -> Result<Reading, ModelError> {
        let literal = match params.text("reading", "physical")?.as_str() {
            "physical" => false,
            "document_002" => true,
            other => {
                return Err(ModelError::new(
                    "reading",
                    format!("must be \"physical\" or \"document_002\", got \"{other}\""),
                ))
            }
        };
        let (contact, under_load) = match params.text("disc_contact", "loaded")?.as_str() {
            "loaded" => (DiscContact::FirstContact, !literal),
            "first_contact" => (DiscContact::FirstContact, false),
            "load_shared" => (DiscContact::LoadShared, false),
            other => {
                return Err(ModelError::new(
                    "disc_contact",
                    format!(
                        "must be \"loaded\", \"first_contact\" or \"load_shared\", got \"{other}\""
                    ),
                ))
            }
        };
        let closure = match params.text("crank_closure", "four_bar")?.as_str() {
            "four_bar" => CrankClosure::FourBar,
            "averaged" => CrankClosure::Averaged,
            other => {
                return Err(ModelError::new(
                    "crank_closure",
                    format!("must be \"four_bar\" or \"averaged\", got \"{other}\""),
                ))
            }
        };
        Ok(Reading {
            literal,
            contact,
            under_load,
            closure,
        })
    }
}

/// The physical reading's geometry beyond the stage: the crank circle radius a_w, the
/// discs' spacing s and the sun plane's offset L_s, mm.
pub(super) fn physical_geometry(
    params: &ModelParams,
    stage: &CycloidStage,
) -> Result<(f64, f64, f64), ModelError> {
    let (eccentricity, pin_circle) = (stage.eccentricity, stage.pin_circle_radius);
    let crank_radius = params.positive("crank_circle_radius_mm", None)?;
    if crank_radius <= eccentricity || crank_radius >= pin_circle {
        return Err(ModelError::new(
            "crank_circle_radius_mm",
            format!(
                "must lie between the eccentricity {} mm and the pin circle radius {} mm, got {}",
                Shown(eccentricity),
                Shown(pin_circle),
                Shown(crank_radius)
            ),
        ));
    }
    // Geometry that can be: the two discs' mid-planes (each on its eccentric: one
    // dimension of the reducer, the crank side's too) within a pin-circle radius of each
    // other, the sun plane within ten of the input shaft's reference.
    let spacing = params.positive("crank_eccentric_spacing_mm", None)?;
    if spacing > pin_circle {
        return Err(ModelError::new(
            "crank_eccentric_spacing_mm",
            format!(
                "must be a length up to the pin circle radius {} mm, got {}",
                Shown(pin_circle),
                Shown(spacing)
            ),
        ));
    }
    let sun_offset = params.number("sun_plane_offset_mm", Some(0.0))?;
    if sun_offset.abs() > 10.0 * pin_circle {
        return Err(ModelError::new(
            "sun_plane_offset_mm",
            format!(
                "must lie within ±10 pin circle radii ({} mm), got {}",
                Shown(10.0 * pin_circle),
                Shown(sun_offset)
            ),
        ));
    }
    Ok((crank_radius, spacing, sun_offset))
}

/// The preload rule that judges where the discs do not fit (physical reading only; 002's
/// literal reading reads the keys a reducer file gives it and leaves them); `ratio_lambda`
/// is (i, λ).
pub(super) fn preload_rule(
    params: &ModelParams,
    stage: &CycloidStage,
    literal: bool,
    ratio_lambda: (f64, f64),
) -> Result<Option<PreloadRule>, ModelError> {
    if literal {
        for key in ["pin_radius_mm", "disc_face_width_mm", "rated_torque_nm"] {
            params.number(key, Some(0.0))?;
        }
        for spec in &preload::PARAMS[1..] {
            params.number(spec.name, Some(0.0))?;
        }
        params.number(preload::FRICTION.name, Some(0.0))?;
        return Ok(None);
    }
    let pin_radius = params.positive("pin_radius_mm", None)?;
    stage.check_pin_radius("pin_radius_mm", pin_radius)?;
    let face_width = params.positive("disc_face_width_mm", None)?;
    Ok(Some(PreloadRule::from_params(
        params,
        stage,
        pin_radius,
        face_width,
        ratio_lambda,
    )?))
}

/// The curve's N = `points` points, sorted into [`Group`]s of the points that see the same
/// pin slots (phase of the fractional pin pitch, g = gcd(z_c·z_p, N)), the same crank angle
/// and the same tooth shift; `ratio` is i.
pub(super) fn curve_points(
    stage: &CycloidStage,
    points: usize,
    g: usize,
    ratio: f64,
) -> (Vec<Point>, Vec<Group>) {
    let (pins, cycloid_teeth) = (stage.pins, stage.teeth);
    let cycloid_mesh = cycloid_teeth * pins;
    let angle = |step: usize| (2.0 * PI * (step % points) as f64 / points as f64).sin_cos();
    let mut keyed: Vec<((usize, usize, usize), Point)> = (0..points)
        .map(|j| {
            let theta = 2.0 * PI * j as f64 / points as f64;
            let turns = cycloid_mesh * j;
            let point = Point {
                output: angle(j),
                crank: angle(pins * j),
                sun: ((ratio - 1.0) * theta).sin_cos(),
                pin_shift: ((turns / points) % pins) as u32,
                tooth_shift: ((turns / points) % cycloid_teeth) as u32,
                index: j as u32,
            };
            let phase = (turns % points) / g;
            let key = (phase, (pins * j) % points, point.tooth_shift as usize);
            (key, point)
        })
        .collect();
    keyed.sort_by_key(|(key, point)| (*key, point.index));
    let mut groups: Vec<Group> = Vec::new();
    for (k, (key, _)) in keyed.iter().enumerate() {
        match groups.last_mut() {
            Some(group) if keyed[group.start as usize].0 == *key => group.end += 1,
            _ => groups.push(Group {
                phase: key.0 as u32,
                start: k as u32,
                end: k as u32 + 1,
            }),
        }
    }
    let curve_points = keyed.into_iter().map(|(_, point)| point).collect();
    (curve_points, groups)
}
