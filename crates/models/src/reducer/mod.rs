//! `rv_lost_motion`: the lost motion and the preload of an RV reducer from its geometry,
//! pin by pin and disc by disc (docs/models.md §14). The reducer is one definition
//! (`geometry.rs`); the deviations act through it at the two discs' pins over one output
//! revolution (`windows.rs`); an assembly whose flanks overlap is judged by the forces and
//! the drag its preload makes (`preload.rs`).
//!
//! ```text
//! lost motion at Θ_k   LM_k = max(0, W_k) + max(0, Δφ12')
//!   W_k = min_d upper_d(Θ_k) − max_d lower_d(Θ_k)  the two discs' common window (windows.rs)
//!   Δφ12' = −(E_ws + E_wi)/(2·r1·i·cos α')·10800/π, cos α' = a0·cos α·cos β/(a0 + a1)
//!                                                    (000 Eq. 5, 12; β, a1 from 001 Eq. 5–8)
//! outputs              worst = max_k LM_k, mean = Σ_k LM_k/M over Θ_k = 2π·k/M, M = q·z_p
//! least                min_k LM_k
//! preload              at the Θ_k of the narrowest window, when it is negative: the
//!                      zero-torque balance of both discs (preload.rs): the largest approach
//!                      of a pin contact (the overlap a flank takes up), the largest pin
//!                      force F_max(0), the no-load torque T_0 at the input
//! preload class        free: min_k W_k ≥ 0 and Δφ12' ≥ 0
//!                      over-preloaded: F_max(0) > limit, overlap > limit, T_0 > limit, or
//!                      Δφ12' < 0 (a jammed gear mesh has no allowance)
//!                      preloaded within the limit otherwise
//! default limit        the largest pin force at rated torque of the design (preload.rs)
//! ```
//! `lost_motion_arcmin` and its mean are non-conforming when the assembly is
//! over-preloaded; a preload within the limit is a design state and conforms.
//!
//! q (`positions_per_pin`, default 4) is the number of points per turn of the cranks
//! against the carrier, in which the pins advance one pitch against the eccentric. The mean
//! over the revolution is settled at q = 4; the worst of M angles converges as 1/q (a pin
//! limits a window in a narrow peak), 4 % low at P99.865 on the RV-20E scenario against
//! q = 16 (docs/models.md §14.4; test: the worst grows and the mean settles with q).

mod folds;
mod geometry;
mod layout;
#[cfg(test)]
pub(crate) mod test_streams;
mod torsion;
mod windows;

use rvtol_deviation::point_displacement;

use crate::preload::{self, DiscPins, Preload, PreloadRule};
use crate::stiffness::build;
use crate::{
    concat_params, ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputSpec,
    ParamSpec, ARCMIN_PER_RAD,
};
use geometry::{Grid, Reducer};
use layout::Layout;
use torsion::{Figures, Pins, Torsion};
use windows::{direct_pins, disc_window, row_terms, RowTable};

/// The model's own keys (`PARAMS` adds the crank side's).
const OWN_PARAMS: &[ParamSpec] = &[
    ParamSpec { name: "sun_teeth", unit: "1", description: "z1, sun teeth", default: None },
    ParamSpec { name: "planet_teeth", unit: "1", description: "z2, planet teeth", default: None },
    ParamSpec { name: "cycloid_teeth", unit: "1", description: "z_c, disc teeth (z_p − 1)", default: None },
    ParamSpec { name: "pin_count", unit: "1", description: "z_p, pins", default: None },
    ParamSpec { name: "pin_circle_radius_mm", unit: "mm", description: "r_p, pin centre circle radius", default: None },
    ParamSpec { name: "pin_radius_mm", unit: "mm", description: "r_rp, pin radius", default: None },
    ParamSpec { name: "eccentricity_mm", unit: "mm", description: "e, eccentricity (K1 = e·z_p/r_p is derived)", default: None },
    ParamSpec { name: "equidistant_modification_mm", unit: "mm", description: "Δr_rp, the design's equidistant amount (generating pin radius minus r_rp; positive: clearance)", default: None },
    ParamSpec { name: "shift_modification_mm", unit: "mm", description: "Δr_p, the design's shift amount (generating pin circle minus r_p; positive: less clearance)", default: None },
    ParamSpec { name: "pressure_angle_deg", unit: "deg", description: "α of the involute stage", default: Some(20.0) },
    ParamSpec { name: "center_distance_mm", unit: "mm", description: "a0, sun–planet centre distance = the crank circle radius", default: None },
    ParamSpec { name: "sun_pitch_radius_mm", unit: "mm", description: "r1, sun pitch radius (000 Eq. 5)", default: None },
    ParamSpec { name: "sun_gear_axial_position_mm", unit: "mm", description: "z of the sun mesh from the input shaft's deviation reference point", default: Some(0.0) },
    ParamSpec { name: "crank_count", unit: "1", description: "m, cranks (2 or 3) on the crank circle, evenly spaced", default: Some(2.0) },
    ParamSpec { name: "crank_eccentric_spacing_mm", unit: "mm", description: "s, axial distance between the two eccentrics' (discs') mid-planes: a crank's tilt acts at ±s/2", default: None },
    ParamSpec { name: "disc_face_width_mm", unit: "mm", description: "L, the disc's face width (the pin contacts' length)", default: None },
    preload::FRICTION,
    preload::PARAMS[0],
    ParamSpec { name: "pitch_measuring_radius_mm", unit: "mm", description: "r_m, the circle on which the cumulative pitch deviation is measured (default r_p − r_rp)", default: None },
    ParamSpec { name: "positions_per_pin", unit: "1", description: "q, output angles per pin pitch (M = q·z_p over a revolution)", default: Some(4.0) },
    preload::PARAMS[1],
    preload::PARAMS[2],
    preload::PARAMS[3],
    ParamSpec { name: "loaded_figures", unit: "1", description: "1: also the catalogue's figures from the loaded contact solution at the widest window's output angle (lost motion at ±3 % of rated torque, hysteresis loss, torsional rigidity, angle at rated torque, largest pin force at rated; docs/models.md §14.9), which read the crank side's keys; 0: free play and preload only", default: Some(0.0) },
    ParamSpec { name: "crank_bearing_friction_coefficient", unit: "1", description: "μ_b, friction coefficient of a needle row on its journal radius, in [0, 0.5) (loaded figures)", default: None },
];

/// The crank side's keys (`stiffness::build`) but the eccentrics' spacing, which is the
/// model's own.
const CRANK_SIDE: (&[ParamSpec], &[ParamSpec]) = build::PARAMS.as_slice().split_at(7);

const PARAMS: [ParamSpec; OWN_PARAMS.len() + build::PARAMS.len() - 1] =
    concat_params(&[OWN_PARAMS, CRANK_SIDE.0, CRANK_SIDE.1.split_at(1).1]);

/// Most points per pin pitch.
const MAX_PER_PIN: u32 = 64;

/// Registry entry.
pub const ENTRY: ModelEntry = ModelEntry {
    name: "rv_lost_motion",
    summary: "lost motion and preload of an RV reducer from its geometry: two discs, pin by pin, over one output revolution, with the preload's pin forces and no-load torque (000 Eq. 5, 12; 003; docs/models.md §14)",
    params: &PARAMS,
    build: |params| Ok(Box::new(RvLostMotion::from_params(params)?)),
    example_params: RvLostMotion::rv20e_params,
    example_inputs: &[
        ("common_normal_upper_deviation_mm", 0.0035),
        ("common_normal_lower_deviation_mm", -0.0309),
    ],
};

thread_local! {
    /// Each thread's row table (the model allocates nothing per sample once it has grown).
    static TABLE: std::cell::RefCell<RowTable> = std::cell::RefCell::new(RowTable::default());
    /// Each thread's pins of the two discs for the zero-torque balance.
    static PINS: std::cell::RefCell<[DiscPins; 2]> =
        std::cell::RefCell::new([DiscPins::new(0.0, 0.0), DiscPins::new(0.0, 0.0)]);
    /// Each thread's pins of the two discs for the loaded figures.
    static LOADED: std::cell::RefCell<[Pins; 2]> =
        const { std::cell::RefCell::new([Pins::new(), Pins::new()]) };
}

/// One revolution of a row's windows.
struct Revolution {
    /// The widest common window W and its grid point, rad at the output.
    widest: (f64, usize),
    /// The mean of max(0, W) over the M points.
    mean: f64,
    /// The narrowest W.
    narrowest: f64,
    /// The narrowest rigid W (every overlap, the discs' own included) and its grid point,
    /// where the preload is judged.
    deepest: (f64, usize),
}

/// Windows this close to the widest (rad at the output, 3·10⁻⁹ arcmin) count as as wide
/// where the loaded figures choose their point: far above the rounding of the windows'
/// ends (some 10⁻¹⁹ rad), far below any width a deviation makes.
const WIDEST_TIE: f64 = 1e-12;

/// The model with its reducer and grid.
#[derive(Debug, Clone)]
pub struct RvLostMotion {
    reducer: Reducer,
    grid: Grid,
    layout: Layout,
    rule: PreloadRule,
    /// The loaded figures (`loaded_figures`), when asked for.
    torsion: Option<Torsion>,
    /// 10800/π / (2·r1·i·a0·cos α).
    involute_scale: f64,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

impl RvLostMotion {
    /// The RV-20E of document 000 (Table 8, Table 9's design modification; K1 derived),
    /// with the pins, face width and rated torque of the shipped torsion scenario.
    pub fn rv20e_params() -> ModelParams {
        ModelParams::new()
            .with_number("sun_teeth", 12.0)
            .with_number("planet_teeth", 42.0)
            .with_number("cycloid_teeth", 39.0)
            .with_number("pin_count", 40.0)
            .with_number("pin_circle_radius_mm", 52.0)
            .with_number("pin_radius_mm", 2.0)
            .with_number("eccentricity_mm", 0.9)
            .with_number("equidistant_modification_mm", -0.010)
            .with_number("shift_modification_mm", -0.012)
            .with_number("center_distance_mm", 27.5)
            .with_number("sun_pitch_radius_mm", 13.5)
            .with_number("disc_face_width_mm", 8.0)
            .with_number("crank_eccentric_spacing_mm", 9.0)
            .with_number("pin_friction_coefficient", 0.02)
            .with_number("rated_torque_nm", 167.0)
    }

    /// Builds the model, checking every parameter once.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let reducer = Reducer::from_params(params)?;
        let per_pin = params.count("positions_per_pin", Some(4.0))?;
        if per_pin > MAX_PER_PIN {
            return Err(ModelError::new(
                "positions_per_pin",
                format!("must be at most {MAX_PER_PIN}, got {per_pin}"),
            ));
        }
        let grid = Grid::new(&reducer, per_pin as usize);
        let rule = PreloadRule::from_params(
            params,
            &reducer.stage,
            reducer.pin_radius,
            reducer.face_width,
            (reducer.ratio, reducer.lambda),
        )?;
        let torsion = match params.flag("loaded_figures", false)? {
            true => Some(Torsion::from_params(
                params,
                &reducer,
                rule.contact(),
                &grid,
            )?),
            false => {
                // Not read without the loaded figures, but the model's numbers all the same.
                for spec in CRANK_SIDE.0.iter().chain(&CRANK_SIDE.1[1..]) {
                    params.number(spec.name, Some(0.0))?;
                }
                params.number("crank_bearing_friction_coefficient", Some(0.0))?;
                None
            }
        };
        params.reject_unknown(&PARAMS.iter().map(|p| p.name).collect::<Vec<_>>())?;
        let involute_scale = ARCMIN_PER_RAD
            / (2.0
                * reducer.sun_pitch_radius
                * reducer.ratio
                * reducer.center_distance
                * reducer.pressure_angle.cos());
        let layout = Layout::new(reducer.cranks);
        Ok(RvLostMotion {
            inputs: layout::inputs(reducer.cranks, reducer.stage.pins),
            outputs: layout::outputs(torsion.is_some()),
            layout,
            grid,
            rule,
            torsion,
            involute_scale,
            reducer,
        })
    }

    /// The largest pin force at rated torque of the design, N (the default limit).
    pub fn rated_pin_force(&self) -> f64 {
        self.rule
            .rated_pin_force(self.reducer.equidistant, self.reducer.shift)
    }

    /// M = q·z_p, the output angles over a revolution.
    pub fn points(&self) -> usize {
        self.grid.points
    }

    /// The index of the input named `name`.
    pub fn input_index(&self, name: &str) -> Option<usize> {
        self.inputs.iter().position(|i| i.name == name)
    }

    /// λ.
    pub fn lambda(&self) -> f64 {
        self.reducer.lambda
    }

    /// Both discs' rigid windows at grid point k, output angles (rad): [(lower, upper); 2]
    /// (negative width where a disc's own flanks overlap).
    pub fn disc_windows(&self, x: &[f64], k: usize) -> [(f64, f64); 2] {
        let terms = row_terms(&self.reducer, &self.grid, &self.layout, x);
        [0, 1].map(|d| {
            disc_window(&self.reducer, &self.grid, &self.layout, &terms, x, k, d)
                .ends(self.reducer.lambda)
        })
    }

    /// Both discs' windows at rest at grid point k, computed pin by pin in full
    /// (`DiscWindow::at_rest`: a disc whose own flanks overlap rests at its own balance,
    /// its slack about it), output angles (rad).
    pub fn disc_windows_at_rest(&self, x: &[f64], k: usize) -> [(f64, f64); 2] {
        let (reducer, grid, layout) = (&self.reducer, &self.grid, &self.layout);
        let terms = row_terms(reducer, grid, layout, x);
        [0, 1].map(|d| {
            let pins = direct_pins(reducer, grid, layout, &terms, x, (k, d));
            disc_window(reducer, grid, layout, &terms, x, k, d).at_rest(reducer.lambda, &pins)
        })
    }

    /// The common window's width W_k (rad at the output) at every grid point.
    pub fn window_widths(&self, x: &[f64]) -> Vec<f64> {
        let terms = row_terms(&self.reducer, &self.grid, &self.layout, x);
        let mut table = RowTable::default();
        table.fill(&self.reducer, &self.grid, &self.layout, &terms, x);
        (0..self.grid.points)
            .map(|k| self.width(&table, k))
            .collect()
    }

    /// W_k from the row's table.
    #[inline(always)]
    fn width(&self, table: &RowTable, k: usize) -> f64 {
        let ends = |d| table.ends(&self.grid, k, d);
        let ((lo0, up0), (lo1, up1)) = (ends(0), ends(1));
        up0.min(up1) - lo0.max(lo1)
    }

    /// The rigid W_k (`RowTable::rigid_ends`): every overlap, the discs' own included.
    #[inline(always)]
    fn rigid_width(&self, table: &RowTable, k: usize) -> f64 {
        let ends = |d| table.rigid(&self.grid, k, d);
        let ((lo0, up0), (lo1, up1)) = (ends(0), ends(1));
        up0.min(up1) - lo0.max(lo1)
    }

    /// The revolution (`Revolution`).
    fn scan_revolution(&self, table: &RowTable) -> Revolution {
        let mut scan = Revolution {
            widest: (f64::NEG_INFINITY, 0),
            mean: 0.0,
            narrowest: f64::INFINITY,
            deepest: (f64::INFINITY, 0),
        };
        for k in 0..self.grid.points {
            let w = self.width(table, k);
            if w > scan.widest.0 {
                scan.widest = (w, k);
            }
            scan.mean += w.max(0.0);
            scan.narrowest = scan.narrowest.min(w);
            let rigid = self.rigid_width(table, k);
            if rigid < scan.deepest.0 {
                scan.deepest = (rigid, k);
            }
        }
        scan.mean /= self.grid.points as f64;
        scan
    }

    /// Δφ12', arcmin (000 Eq. 5, 12).
    fn involute(&self, x: &[f64]) -> f64 {
        let s = self.layout.shaft;
        let shaft = [x[s], x[s + 1], 0.0, x[s + 2], x[s + 3], 0.0];
        let at_sun = point_displacement(&shaft, [0.0, 0.0, self.reducer.sun_position]);
        let a1 = at_sun[0].hypot(at_sun[1]);
        let cos_beta = x[s + 2].hypot(x[s + 3]).cos();
        let (ws, wi) = self.layout.common_normal;
        -(x[ws] + x[wi]) * self.involute_scale * (self.reducer.center_distance + a1) / cos_beta
    }

    /// Both discs' pins at grid point k, every pin, for the preload's balance: each gap
    /// (the pitch's turn folded in) the row table's run value plus the pin's own terms,
    /// t_m + δr_i·f_r + δt_i·f_t − ρ_i, as the windows read it.
    fn pins_at(&self, table: &RowTable, x: &[f64], k: usize, discs: &mut [DiscPins; 2]) {
        let columns = &self.grid.columns;
        for (d, disc) in discs.iter_mut().enumerate() {
            let (_, offset, slack) = table.heads[2 * (k % self.grid.per_pin) + d];
            disc.reset(offset, slack);
            self.each_pin(table, x, (k, d), |gap, j, _| {
                disc.push(gap, columns.lever[j], columns.slip_arm[j])
            });
        }
    }

    /// Disc d's pins at grid point k, in pin order: `visit(gap, j, m)` with the pin's gap
    /// (the pitch's turn folded in: the row table's run value plus the pin's own terms,
    /// t_m + δr_i·f_r + δt_i·f_t − ρ_i, as the windows read it), its column entry j and
    /// its entry m in the run. Returns the disc's crank offset C_d and slack s_d.
    fn each_pin(
        &self,
        table: &RowTable,
        x: &[f64],
        (k, d): (usize, usize),
        mut visit: impl FnMut(f64, usize, usize),
    ) -> (f64, f64) {
        let (grid, pins) = (&self.grid, self.reducer.stage.pins);
        let columns = &grid.columns;
        let kq = k % grid.per_pin;
        let (radial, rest) = x[self.layout.pins..].split_at(pins);
        let (tangential, rest) = rest.split_at(pins);
        let radius = &rest[..pins];
        let (base, offset, slack) = table.heads[2 * kq + d];
        let run = &table.runs[(2 * kq + d) * pins..(2 * kq + d + 1) * pins];
        let (_, start) = grid.placement(k, d);
        // Pin i meets entry start + i, less z_p past the end of the run.
        let entries = (start..pins).chain(0..start);
        for (i, m) in entries.enumerate() {
            let j = base + m;
            let gap =
                run[m] + radial[i] * columns.radial[j] + tangential[i] * columns.tangential[j]
                    - radius[i];
            visit(gap, j, m);
        }
        (offset, slack)
    }

    /// The loaded figures of a row at the grid point of its widest window `(W, k)` (rad
    /// at the output), the involute stage's free play `involute` in arcmin.
    fn loaded_figures(
        &self,
        torsion: &Torsion,
        table: &RowTable,
        x: &[f64],
        (window, k): (f64, usize),
        involute: f64,
    ) -> Figures {
        let columns = &self.grid.columns;
        let pins = self.reducer.stage.pins;
        LOADED.with(|discs| {
            let mut discs = discs.borrow_mut();
            for (d, disc) in discs.iter_mut().enumerate() {
                let (base, offset, slack) = table.heads[2 * (k % self.grid.per_pin) + d];
                disc.reset(offset, slack);
                self.each_pin(table, x, (k, d), |gap, j, m| {
                    // A pin at φ = 0 or π holds no turn (the windows leave it out too).
                    if columns.inverse_lever[j] == 0.0 {
                        return;
                    }
                    disc.gaps.push(gap);
                    disc.levers.push(columns.lever[j]);
                    disc.slip.push(columns.slip_arm[j]);
                    disc.along.push(columns.eccentric[j]);
                    disc.place.push(torsion.place(base / pins, m));
                });
            }
            torsion.figures(&mut discs, window, involute / ARCMIN_PER_RAD)
        })
    }

    /// The first grid point (in output angle) whose window is as wide as the widest to
    /// [`WIDEST_TIE`], and its width: where the loaded figures are read. Several points
    /// are often equally wide (a window that is one disc's slack about its own balance),
    /// and the strict widest among them would be chosen by rounding alone.
    fn first_widest(&self, table: &RowTable, widest: f64) -> (f64, usize) {
        (0..self.grid.points)
            .map(|k| (self.width(table, k), k))
            .find(|(w, _)| *w >= widest - WIDEST_TIE)
            .unwrap_or((widest, 0))
    }

    /// The preload of a row whose narrowest window (at grid point `at`) is negative.
    fn preload(&self, table: &RowTable, x: &[f64], at: usize) -> Preload {
        PINS.with(|discs| {
            let mut discs = discs.borrow_mut();
            self.pins_at(table, x, at, &mut discs);
            preload::zero_torque(self.rule.contact(), &mut discs)
        })
    }
}

impl ErrorModel for RvLostMotion {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn inputs(&self) -> &[InputSpec] {
        &self.inputs
    }

    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }

    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        if x.iter().any(|v| !v.is_finite()) {
            out.iter_mut().for_each(|o| *o = f64::NAN);
            return;
        }
        let terms = row_terms(&self.reducer, &self.grid, &self.layout, x);
        let involute = self.involute(x) + 0.0;
        let free_involute = involute.max(0.0);
        let (scan, overlapping, preload, figures) = TABLE.with(|table| {
            let mut table = table.borrow_mut();
            table.fill(&self.reducer, &self.grid, &self.layout, &terms, x);
            let scan = self.scan_revolution(&table);
            // Pins carry at rest where the pair's windows miss each other or a disc's own
            // flanks overlap; the balance is taken where the overlap is deepest.
            let overlapping = scan.narrowest < 0.0 || table.own_overlap;
            let preload = if overlapping {
                self.preload(&table, x, scan.deepest.1)
            } else {
                Preload::NONE
            };
            let figures = self.torsion.as_ref().map(|torsion| {
                let at = self.first_widest(&table, scan.widest.0);
                self.loaded_figures(torsion, &table, x, at, free_involute)
            });
            (scan, overlapping, preload, figures)
        });
        let (widest, sum, least) = (scan.widest.0, scan.mean, scan.narrowest);
        let class = self.rule.classify(
            &preload,
            (overlapping, involute < 0.0),
            (self.reducer.equidistant, self.reducer.shift),
        );
        out[0] = widest.max(0.0) * ARCMIN_PER_RAD + free_involute;
        out[1] = sum * ARCMIN_PER_RAD + free_involute;
        out[2] = least.max(0.0) * ARCMIN_PER_RAD + free_involute;
        out[3] = involute;
        out[4] = preload.overlap_um;
        out[5] = preload.pin_force;
        out[6] = preload.no_load_torque;
        out[7] = class.preloaded();
        out[8] = class.over();
        if let Some(figures) = figures {
            out[9] = figures.lost_motion;
            out[10] = figures.hysteresis_loss;
            out[11] = figures.rigidity;
            out[12] = figures.angle_at_rated;
            out[13] = figures.pin_force;
        }
    }
}

#[cfg(test)]
mod tests;
