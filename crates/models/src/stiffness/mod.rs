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
//! - `bodies`: the plates around the rows' bores (Michell's harmonics, Kelvin's force);
//! - `tapered`: a support bearing's tapered row with its axial preload;
//! - `shaft`: the crank shaft on its supports, in the two load modes of the discs;
//! - `carrier`: the pillars on their roots in the plates;
//! - `involute`: the first stage reflected to the output;
//! - `chain`: the crank side in series for one load state.
//!
//! Units: lengths mm, forces N, torques N·mm, stiffnesses N/mm (translation) and N·mm/rad
//! (rotation), angles rad. Steel: E and ν are parameters of the models. Sign convention:
//! every compliance and deflection is a positive magnitude along the load; the models give
//! them their signs.
//!
//! Left out, and why (docs/models.md §13 gives their sizes): radial clearance of the rows
//! (their free play is `geometric_hysteresis`'s Δu; at 2 µm it changes the 50–100 % slope
//! of an RV-20E needle row by under 1 %, checked in the tests), preload of the support
//! bearings (it stiffens them: the unpreloaded secant is the softer bound), edge loading of
//! a row whose journal tilts with the shaft's bending, the bending of the disc's lobes, the
//! plates' bores around the support bearings and their in-plane paths to the pillars, the
//! housing and the main bearings (they carry no torque about the axis), the planet gear's
//! force on the crank shaft (about 3 % of the eccentric loads).

mod bodies;
mod carrier;
mod chain;
mod contact;
mod involute;
mod lundberg;
mod shaft;
mod tapered;

pub use carrier::Carrier;
pub use chain::{ChainTerms, CrankSide};
pub use contact::{line_contact_approach, RollerRow, PALMGREN_LINE, STRIBECK_LINE};
pub use involute::InvoluteStage;
pub use lundberg::{
    hertz_half_width, iso_16281_roller_approach, lundberg_body_approach, lundberg_needle_approach,
    ISO_16281_ROLLER, LUNDBERG_CONSTANT,
};
pub use shaft::{CrankShaft, ShaftModes};
pub use tapered::TaperedRow;
