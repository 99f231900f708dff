//! rvtol-models: the physical error models of RV reducers behind one small trait.
//!
//! A model is a pure function from one row of named inputs to named outputs
//! ([`ErrorModel::evaluate`]); it owns no randomness and no I/O. Its fixed parameters
//! (geometry) are checked once, when the engine builds it from the scenario through the
//! registry ([`all`], [`find`]); `evaluate` never re-checks them.
//!
//! Adding a model touches three places: its file here, one line in [`all`], one scenario.

mod chains;
mod crank_elastic_error;
mod cycloid;
mod cycloid_pin_contact;
pub mod declared;
mod expression;
mod geometric_hysteresis;
mod linear_stack;
mod loaded;
mod params;
mod preload;
mod reducer;
mod spectrum;
mod stiffness;
mod test_functions;
mod torsion_curve;
mod transmission_error;

pub use crank_elastic_error::{CrankElasticError, CrankForces, DiscForces, DiscLoad};
pub use cycloid_pin_contact::{ContactSolution, CycloidPinContact};
pub use expression::Expression;
pub use geometric_hysteresis::{tilt_from_deflection, GeometricHysteresis};
pub use linear_stack::LinearStack;
pub use params::{ModelError, ModelParams, ParamValue};
pub use reducer::RvLostMotion;
pub use spectrum::{OrderDft, RealFft};
pub use stiffness::{
    assembly_preload, bolt_for_pillar, disc_web_compliance, guided_beam_compliance,
    hertz_half_width, hole_energy, hub_deflection_coefficients, hub_tilt_stiffness,
    iso_16281_roller_approach, kelvin_stress, line_contact_approach, lundberg_body_approach,
    lundberg_needle_approach, michell_response, net_force_compliance, BoltedJoint, Carrier,
    ChainTerms, CrankShaft, CrankSide, EndCompliance, Housing, InvoluteStage, RollerRow,
    ShaftModes, TaperedRow, ISO_16281_ROLLER, LUNDBERG_CONSTANT, PALMGREN_LINE, STRIBECK_LINE,
};
pub use test_functions::{Ishigami, SobolG};
pub use torsion_curve::{TorsionCurve, TorsionTerms};
pub use transmission_error::TransmissionError;

/// Arcminutes per radian, 180·60/π (000 Eq. 5, 13, 18 carry this factor).
pub const ARCMIN_PER_RAD: f64 = 180.0 * 60.0 / std::f64::consts::PI;

/// Arcseconds per radian, 180·3600/π.
pub const ARCSEC_PER_RAD: f64 = 180.0 * 3600.0 / std::f64::consts::PI;

/// Inputs plus outputs of one row that [`ErrorModel::evaluate_columns`]'s default gathers
/// on the stack (larger models use one heap buffer per block).
pub const ROW_BUFFER: usize = 512;

/// A named model input with its unit.
#[derive(Debug, Clone, PartialEq)]
pub struct InputSpec {
    /// Name, with the unit as suffix (`pin_radius_error_mm`).
    pub name: String,
    /// Unit (`mm`, `rad`, …; `any` when the model does not care).
    pub unit: String,
    /// One line saying what it is and where it comes from.
    pub description: &'static str,
}

/// Whether an output is a continuous quantity or a 0/1 event indicator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputKind {
    /// A continuous quantity: moments, percentiles, histogram, capability.
    Continuous,
    /// 1 when an event happened in the sample, else 0: the report gives its fraction with
    /// a confidence interval.
    Indicator,
}

/// A named model output with its unit.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputSpec {
    /// Name, with the unit as suffix (`hysteresis_arcmin`).
    pub name: String,
    /// Unit (`arcmin`, `fraction`, …).
    pub unit: String,
    /// One line saying what it is.
    pub description: &'static str,
    /// Continuous or indicator.
    pub kind: OutputKind,
    /// An indicator output of the same model that governs this output sample by sample,
    /// when there is one (see [`OutputCondition`]).
    pub condition: Option<OutputCondition>,
}

/// A continuous output whose samples an indicator output of the same model qualifies: an
/// interfering profile has no transmission error, a preloaded stage does not conform
/// whatever its lost motion. The engine counts the flagged samples per output and reports
/// them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutputCondition {
    /// Name of the indicator output (of the same model).
    pub indicator: &'static str,
    /// What a sample with the indicator set means for this output.
    pub effect: ConditionEffect,
}

/// What an indicator set on a sample means for the output it qualifies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConditionEffect {
    /// The sample has no value of this output (the model writes NaN): it is kept out of
    /// the output's statistics and counted as excluded; against spec limits it does not
    /// conform.
    Excluded,
    /// The value stands and enters the statistics, but the sample does not conform to the
    /// output's spec limits (unless the scenario's spec says flagged samples conform).
    NonConforming,
}

/// A fixed parameter a model reads from the scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Key in the scenario's `params` object.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// What it is.
    pub description: &'static str,
    /// Default value when the scenario omits it; `None` means required.
    pub default: Option<f64>,
}

/// The parameter lists `parts` one after the other, N in all (checked when it is
/// evaluated, at compile time for a `const`): a model's `params` made of its own keys and
/// the shared lists of `preload` and `stiffness::build`, in the order `rvtol models`
/// shows them.
pub(crate) const fn concat_params<const N: usize>(parts: &[&[ParamSpec]]) -> [ParamSpec; N] {
    const EMPTY: ParamSpec = ParamSpec {
        name: "",
        unit: "",
        description: "",
        default: None,
    };
    let mut out = [EMPTY; N];
    let (mut k, mut part) = (0, 0);
    while part < parts.len() {
        let mut i = 0;
        while i < parts[part].len() {
            out[k] = parts[part][i];
            (k, i) = (k + 1, i + 1);
        }
        part += 1;
    }
    assert!(k == N, "the parts hold another number of parameters than N");
    out
}

/// A physical error model: a pure function from inputs to outputs.
pub trait ErrorModel: Send + Sync {
    /// Registry name (`geometric_hysteresis`).
    fn name(&self) -> &'static str;
    /// Inputs it reads, in the order of the `inputs` row.
    fn inputs(&self) -> &[InputSpec];
    /// Outputs it writes, in the order of the `outputs` row.
    fn outputs(&self) -> &[OutputSpec];
    /// Evaluates one sample. `inputs.len() == self.inputs().len()`,
    /// `outputs.len() == self.outputs().len()`. No allocation, no panic on finite input.
    fn evaluate(&self, inputs: &[f64], outputs: &mut [f64]);
    /// Evaluates a block of samples held column by column: `inputs[i]` holds input i of
    /// each of the block's n rows (every slice n long), and output j of row r goes to
    /// `outputs[j·n + r]` (`outputs.len() == n·self.outputs().len()`). The engine calls it
    /// once per block, so the per-sample call is static, not dynamic, dispatch. The default
    /// gathers each row and calls [`Self::evaluate`]; models whose arithmetic vectorises
    /// override it with a column-wise loop that gives the same bits.
    fn evaluate_columns(&self, inputs: &[&[f64]], outputs: &mut [f64]) {
        let (n_in, n_out) = (inputs.len(), self.outputs().len());
        if n_out == 0 {
            return;
        }
        let n = outputs.len() / n_out;
        let mut stack = [0.0; ROW_BUFFER];
        let mut heap = Vec::new();
        let buffer = if n_in + n_out <= ROW_BUFFER {
            &mut stack[..n_in + n_out]
        } else {
            heap.resize(n_in + n_out, 0.0);
            &mut heap[..]
        };
        let (row, out) = buffer.split_at_mut(n_in);
        for r in 0..n {
            for (x, column) in row.iter_mut().zip(inputs) {
                *x = column[r];
            }
            self.evaluate(row, out);
            for (j, &y) in out.iter().enumerate() {
                outputs[j * n + r] = y;
            }
        }
    }

    /// Checks input `input` where the scenario binds it to the constant `value` (the
    /// engine calls it once per constant binding): `Err(reason)` for a value the model
    /// cannot work with, such as a torque that engages no pin. Inputs bound to variables
    /// are not checked here: a sample outside the model's domain gives NaN outputs, which
    /// the engine counts and reports.
    fn check_constant(&self, _input: usize, _value: f64) -> Result<(), String> {
        Ok(())
    }

    /// The curves this model draws for one input row (`rvtol curve`); none by default.
    fn curves(&self, _inputs: &[f64]) -> Vec<Curve> {
        Vec::new()
    }
}

/// How a curve is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CurveStyle {
    /// Points joined by lines.
    Lines,
    /// A vertical stem per point (a spectrum), on a logarithmic x axis.
    LogStems,
}

/// One named series of (x, y) points of a [`Curve`].
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// The points in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// A curve a model draws for one input row (`rvtol curve`): a transmission-error trace,
/// its order spectrum, a torsion curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// File stem of its CSV and SVG (`transmission_error_curve`).
    pub name: String,
    /// Plot title.
    pub title: String,
    /// x axis label with unit.
    pub x_label: String,
    /// y axis label with unit.
    pub y_label: String,
    /// Lines or stems.
    pub style: CurveStyle,
    /// Its series; the CSV has one x column and one y column per series when every
    /// series shares the x values, else x,y pairs per series.
    pub series: Vec<Series>,
}

impl Curve {
    /// The first point of the curve that is not finite, with its series' label: where the
    /// model cannot draw it.
    pub fn first_non_finite(&self) -> Option<(&str, (f64, f64))> {
        self.series.iter().find_map(|series| {
            let &point = (series.points.iter()).find(|(x, y)| !(x.is_finite() && y.is_finite()))?;
            Some((series.label.as_str(), point))
        })
    }
}

/// How a model is built from its scenario parameters, and how it is described.
pub struct ModelEntry {
    /// Registry name.
    pub name: &'static str,
    /// One line: what it computes and its source document.
    pub summary: &'static str,
    /// Its fixed parameters.
    pub params: &'static [ParamSpec],
    /// Builds it from checked parameters.
    pub build: fn(&ModelParams) -> Result<Box<dyn ErrorModel>, ModelError>,
    /// Parameters of a representative instance, for `rvtol models`.
    pub example_params: fn() -> ModelParams,
    /// The inputs of that instance whose design value is not zero (a load torque, a
    /// design modification), for the skeleton `rvtol init` writes.
    pub example_inputs: &'static [(&'static str, f64)],
}

/// Every model rvtol knows, in the order `rvtol models` lists them.
pub fn all() -> &'static [ModelEntry] {
    &[
        geometric_hysteresis::ENTRY,
        reducer::ENTRY,
        cycloid_pin_contact::ENTRY,
        crank_elastic_error::ENTRY,
        torsion_curve::ENTRY,
        transmission_error::ENTRY,
        linear_stack::ENTRY,
        expression::ENTRY,
        test_functions::ISHIGAMI_ENTRY,
        test_functions::SOBOL_G_ENTRY,
    ]
}

/// Models registered while the program runs, after the built-in ones: the Python
/// package's `python` model, whose outputs a Python function computes.
static REGISTERED: std::sync::RwLock<Vec<&'static ModelEntry>> = std::sync::RwLock::new(Vec::new());

/// Registers a model that is not built in (a front-end's own, such as the Python
/// package's functions); a second entry of a name known already is ignored.
pub fn register(entry: &'static ModelEntry) {
    let mut registered = REGISTERED.write().unwrap_or_else(|e| e.into_inner());
    let known = all().iter().chain(registered.iter().copied());
    if !known.into_iter().any(|known| known.name == entry.name) {
        registered.push(entry);
    }
}

/// The registry entry of a model by name: a built-in one, or one [`register`]ed.
pub fn find(name: &str) -> Option<&'static ModelEntry> {
    all().iter().find(|entry| entry.name == name).or_else(|| {
        let registered = REGISTERED.read().unwrap_or_else(|e| e.into_inner());
        registered.iter().copied().find(|entry| entry.name == name)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_registered_model_is_found_once() {
        static EXTRA: ModelEntry = ModelEntry {
            name: "registered_for_a_test",
            ..test_functions::ISHIGAMI_ENTRY
        };
        register(&EXTRA);
        register(&EXTRA);
        assert_eq!(find(EXTRA.name).map(|e| e.name), Some(EXTRA.name));
        let registered = REGISTERED.read().unwrap();
        assert_eq!(
            registered.iter().filter(|e| e.name == EXTRA.name).count(),
            1
        );
        drop(registered);
        // A built-in name stays the built-in model's.
        static SHADOW: ModelEntry = ModelEntry {
            name: "ishigami",
            ..linear_stack::ENTRY
        };
        register(&SHADOW);
        let found = find("ishigami").unwrap();
        assert_eq!(found.summary, test_functions::ISHIGAMI_ENTRY.summary);
    }

    /// A model with `n` inputs and three outputs: Σx, Σ(i + 1)·x_i and the first input
    /// (7 without inputs), to see where the default column form puts each value.
    struct Probe {
        inputs: Vec<InputSpec>,
        outputs: Vec<OutputSpec>,
    }

    impl Probe {
        fn new(n: usize) -> Probe {
            let spec = |name: String| InputSpec {
                name,
                unit: "any".into(),
                description: "probe",
            };
            Probe {
                inputs: (0..n).map(|i| spec(format!("x{i}"))).collect(),
                outputs: ["sum", "weighted", "first"]
                    .iter()
                    .map(|name| OutputSpec {
                        name: (*name).into(),
                        unit: "any".into(),
                        description: "probe",
                        kind: OutputKind::Continuous,
                        condition: None,
                    })
                    .collect(),
            }
        }
    }

    impl ErrorModel for Probe {
        fn name(&self) -> &'static str {
            "probe"
        }
        fn inputs(&self) -> &[InputSpec] {
            &self.inputs
        }
        fn outputs(&self) -> &[OutputSpec] {
            &self.outputs
        }
        fn evaluate(&self, x: &[f64], out: &mut [f64]) {
            out[0] = x.iter().sum();
            out[1] = x.iter().enumerate().map(|(i, v)| (i + 1) as f64 * v).sum();
            out[2] = x.first().copied().unwrap_or(7.0);
        }
    }

    #[test]
    fn default_column_form_lays_out_rows_and_outputs() {
        // Output j of row r at j·n + r, equal to the row form: with no inputs, a few, and
        // more than the stack buffer holds (the heap path).
        let n = 5;
        for n_in in [0, 3, ROW_BUFFER] {
            let model = Probe::new(n_in);
            let columns: Vec<Vec<f64>> = (0..n_in)
                .map(|i| (0..n).map(|r| (10 * r + i) as f64 * 0.5).collect())
                .collect();
            let inputs: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
            let mut outputs = vec![f64::NAN; 3 * n];
            model.evaluate_columns(&inputs, &mut outputs);
            for r in 0..n {
                let row: Vec<f64> = columns.iter().map(|column| column[r]).collect();
                let mut expected = [0.0; 3];
                model.evaluate(&row, &mut expected);
                for (j, value) in expected.iter().enumerate() {
                    assert_eq!(
                        outputs[j * n + r].to_bits(),
                        value.to_bits(),
                        "{n_in} inputs"
                    );
                }
            }
        }
    }
}
