//! The elastic elements between an RV reducer's output flange and its pins, other than the
//! pin contacts themselves (those are `cycloid_pin_contact`'s load sharing): the needle row
//! on each crank eccentric and the disc body around its bore, the crank shaft between its
//! support bearings, the support bearings, the carrier's wind-up (pillars and their roots
//! in the plates) and the involute first stage. `torsion_curve` chains them
//! in series with the pins (docs/models.md §13); `crank_elastic_error` uses the needle row.
//! One file per element, each opening with its equations and sources:
//!
//! - `contact`: Palmgren's line contact and the Stribeck–Palmgren roller row;
//! - `lundberg`: Lundberg's and ISO/TS 16281's laws beside Palmgren's, for the choice;
//! - `bodies`: the plates around the rows' bores (Michell's harmonics, Kelvin's force),
//!   the seats' paths to the pillars and the disc web around the pillars' holes;
//! - `tapered`: a support bearing's tapered row with its axial preload;
//! - `shaft`: the crank shaft on its supports, in the two load modes of the discs;
//! - `carrier`: the pillars on their roots in the plates;
//! - `joint`: the end plate's bolted joint on each pillar (VDI 2230's preload, Ito's
//!   joint-surface stiffness);
//! - `plate`: the end plate's bending around each pillar's root;
//! - `housing`: the housing's bore around the pins, under the pin forces;
//! - `involute`: the first stage reflected to the output;
//! - `chain`: the crank side in series for one load state;
//! - `build`: the crank side from a model's parameters, with the estimation rules.
//!
//! Units: lengths mm, forces N, torques N·mm, stiffnesses N/mm (translation) and N·mm/rad
//! (rotation), angles rad. Steel: E and ν are parameters of the models. Sign convention:
//! every compliance and deflection is a positive magnitude along the load; the models give
//! them their signs.
//!
//! Left out, and why (docs/models.md §13 gives their sizes): radial clearance of the rows
//! (their free play is `geometric_hysteresis`'s Δu; at 2 µm it changes the 50–100 % slope
//! of an RV-20E needle row by under 1 %, checked in the tests), edge loading of a row whose
//! journal tilts with the shaft's bending, the bending of the disc's lobes, the main
//! bearings (they carry no torque about the axis), the planet gear's force on the crank
//! shaft (about 3 % of the eccentric loads).

mod bodies;
pub(crate) mod build;
mod carrier;
mod chain;
mod contact;
mod housing;
mod involute;
mod joint;
mod lundberg;
mod plate;
mod shaft;
mod tapered;

pub use bodies::{disc_web_compliance, hole_energy, kelvin_stress, net_force_compliance};
pub use carrier::{guided_beam_compliance, Carrier};
pub use chain::{ChainTerms, CrankSide};
pub use contact::{line_contact_approach, RollerRow, PALMGREN_LINE, STRIBECK_LINE};
pub use housing::{michell_response, Housing};
pub use involute::InvoluteStage;
pub use joint::{assembly_preload, bolt_for_pillar, BoltedJoint, EndCompliance};
pub use lundberg::{
    hertz_half_width, iso_16281_roller_approach, lundberg_body_approach, lundberg_needle_approach,
    ISO_16281_ROLLER, LUNDBERG_CONSTANT,
};
pub use plate::{hub_deflection_coefficients, hub_tilt_stiffness};
pub use shaft::{CrankShaft, ShaftModes};
pub use tapered::TaperedRow;
