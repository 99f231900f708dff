//! Criterion benchmarks: nanoseconds per sample of each stage of a run on the RV-20E
//! hysteresis scenario (sampler, model, statistics), the normal generator against
//! rand_distr's, whole-run throughput, and the time per sample of every physical model on
//! rows drawn from its shipped scenario, and the random-number floor of an RV-20E row:
//! exactly the normals the sampler takes from the stream per row, drawn by the same
//! generator and normal method and used for nothing (the sampler's cost is stated as a
//! multiple of it), and a formula of the `expression` model against the same function
//! written as a built-in model.
//!
//! Run with `cargo bench -p rvtol-benches`; each figure is per sample (Throughput::Elements).

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rvtol_benches::scenario_path;
use rvtol_deviation::{SamplerScratch, Ziggurat, ZigguratScratch};
use rvtol_engine::chunk::BLOCK_ROWS;
use rvtol_engine::stats::{Moments, QuantileSketch};
use rvtol_engine::{run, RunSettings, Scenario};

const ROWS: usize = 4096;

fn rv20e() -> Scenario {
    rvtol_analysis::request::scenario::load(&scenario_path("rv20e-hysteresis.json"))
        .expect("shipped scenario loads")
}

fn normals(c: &mut Criterion) {
    let mut group = c.benchmark_group("normal");
    group.throughput(Throughput::Elements(ROWS as u64));
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut out = vec![0.0; ROWS];
    group.bench_function("ziggurat_32bit", |b| {
        let z = Ziggurat::get();
        b.iter(|| {
            for x in out.iter_mut() {
                *x = z.sample(&mut rng);
            }
        })
    });
    let mut scratch = ZigguratScratch::default();
    group.bench_function("ziggurat_32bit_fill", |b| {
        let z = Ziggurat::get();
        b.iter(|| z.fill(&mut rng, &mut out, &mut scratch))
    });
    group.bench_function("rand_distr_standard_normal", |b| {
        b.iter(|| {
            for x in out.iter_mut() {
                *x = rng.sample(rand_distr::StandardNormal);
            }
        })
    });
    group.finish();
}

fn stages(c: &mut Criterion) {
    let scenario = rv20e();
    let space = &scenario.input_space;
    let bound = &scenario.models[0];
    let n_columns = space.n_columns();
    let mut group = c.benchmark_group("rv20e_stage");
    group.throughput(Throughput::Elements(ROWS as u64));

    let mut blocks = vec![0.0; ROWS * n_columns];
    let mut counts = space.new_constraint_counts();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    // As the run draws them: column-major blocks of BLOCK_ROWS rows with reused scratch.
    let mut scratch = SamplerScratch::default();
    group.bench_function("sampler", |b| {
        b.iter(|| {
            for block in blocks.chunks_mut(BLOCK_ROWS * n_columns) {
                space
                    .sample_columns_with(&mut rng, block, &mut counts, &mut scratch)
                    .unwrap();
            }
        })
    });

    let n_out = bound.model.outputs().len();
    let inputs = model_rows(&scenario, ROWS);
    let input_slices: Vec<&[f64]> = inputs.iter().map(Vec::as_slice).collect();
    let mut outputs = vec![0.0; ROWS * n_out];
    group.bench_function("model", |b| {
        b.iter(|| bound.model.evaluate_columns(&input_slices, &mut outputs))
    });

    // The first output's column.
    let column: Vec<f64> = outputs[..ROWS].to_vec();
    let mut sketch = QuantileSketch::new(rvtol_engine::run::SKETCH_RELATIVE_ACCURACY);
    group.bench_function("moments_one_output", |b| {
        b.iter(|| Moments::from_slice(&column))
    });
    group.bench_function("sketch_one_output", |b| {
        b.iter(|| sketch.insert_slice(&column))
    });
    group.finish();
}

/// A generator that counts the 32-bit words it hands out.
struct Counting<R> {
    inner: R,
    words: u64,
}

impl<R: rand::Rng> rand::TryRng for Counting<R> {
    type Error = std::convert::Infallible;

    fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
        self.words += 1;
        Ok(self.inner.next_u32())
    }

    fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
        self.words += 2;
        Ok(self.inner.next_u64())
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
        self.words += dst.len().div_ceil(4) as u64;
        self.inner.fill_bytes(dst);
        Ok(())
    }
}

/// The floor of the RV-20E sampler: the words it takes from the stream per row (counted
/// over 64 blocks; every RV-20E draw is a ziggurat normal, one word each but for the rare
/// slow path), drawn as that many ziggurat normals in bulk and nothing else. Compare with
/// `rv20e_stage/sampler` (the same rows, drawn and placed).
fn floor(c: &mut Criterion) {
    let scenario = rv20e();
    let space = &scenario.input_space;
    let n_columns = space.n_columns();
    let mut blocks = vec![0.0; 64 * BLOCK_ROWS * n_columns];
    let mut counts = space.new_constraint_counts();
    let mut scratch = SamplerScratch::default();
    let mut counting = Counting {
        inner: ChaCha8Rng::seed_from_u64(3),
        words: 0,
    };
    for block in blocks.chunks_mut(BLOCK_ROWS * n_columns) {
        space
            .sample_columns_with(&mut counting, block, &mut counts, &mut scratch)
            .unwrap();
    }
    let per_row = counting.words as f64 / (64 * BLOCK_ROWS) as f64;
    let normals = (per_row * ROWS as f64).round() as usize;
    let mut group = c.benchmark_group("rv20e_floor");
    group.throughput(Throughput::Elements(ROWS as u64));
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut out = vec![0.0; normals];
    let mut z = ZigguratScratch::default();
    group.bench_function(format!("normals_{per_row:.2}_per_row"), |b| {
        let normal = Ziggurat::get();
        b.iter(|| normal.fill(&mut rng, &mut out, &mut z))
    });
    group.finish();
}

fn whole_run(c: &mut Criterion) {
    let scenario = rv20e();
    let mut group = c.benchmark_group("rv20e_run");
    group.sample_size(10);
    let samples = 1_000_000u64;
    group.throughput(Throughput::Elements(samples));
    let settings = RunSettings {
        samples,
        seed: 1,
        exact_percentile_limit: 0,
        sampling: Default::default(),
    };
    group.bench_function(BenchmarkId::from_parameter(samples), |b| {
        b.iter(|| run(&scenario, settings, &|_| {}).unwrap())
    });
    group.finish();
}

/// Model input columns (one per input of the scenario's first model) of `rows` rows drawn
/// from the scenario's input space.
fn model_rows(scenario: &Scenario, rows: usize) -> Vec<Vec<f64>> {
    let space = &scenario.input_space;
    let bound = &scenario.models[0];
    let n_columns = space.n_columns();
    let mut sampled = vec![0.0; rows * n_columns];
    let mut counts = space.new_constraint_counts();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    space
        .sample_rows(&mut rng, &mut sampled, &mut counts)
        .expect("shipped scenario samples");
    let model_rows: Vec<Vec<f64>> = sampled
        .chunks_exact(n_columns)
        .map(|row| bound.inputs_of_row(row, &[]))
        .collect();
    (0..bound.bindings.len())
        .map(|i| model_rows.iter().map(|row| row[i]).collect())
        .collect()
}

/// Time per sample of each physical model (targets: contact and the geometric lost motion
/// with its preload ≤ 20 µs, transmission error
/// with its curve and order amplitudes ≤ 100 µs); the torsion curve on each of its three scenarios (the
/// RV-20E's nominal is preloaded, the others are not: one more load case per row).
fn models(c: &mut Criterion) {
    let mut group = c.benchmark_group("model_per_sample");
    for (file, rows, label) in [
        ("rv20e-hysteresis.json", 4096, "geometric_hysteresis"),
        ("rv20e-lost-motion.json", 256, "rv_lost_motion"),
        ("rv20e-catalogue.json", 64, "rv_lost_motion_loaded"),
        ("rv80e-contact.json", 256, "cycloid_pin_contact"),
        ("rv40e-elastic.json", 256, "crank_elastic_error"),
        ("rv40e-transmission.json", 16, "transmission_error"),
        (
            "rv40e-transmission-002.json",
            16,
            "transmission_error_document_002",
        ),
        ("rv20e-torsion.json", 256, "torsion_curve"),
        ("rv40e-torsion.json", 256, "torsion_curve_rv40e"),
        ("rv80e-torsion.json", 256, "torsion_curve_rv80e"),
    ] {
        let scenario = rvtol_analysis::request::scenario::load(&scenario_path(file))
            .expect("shipped scenario loads");
        let inputs = model_rows(&scenario, rows);
        let input_slices: Vec<&[f64]> = inputs.iter().map(Vec::as_slice).collect();
        let bound = &scenario.models[0];
        let mut outputs = vec![0.0; rows * bound.model.outputs().len()];
        group.throughput(Throughput::Elements(rows as u64));
        group.bench_function(label, |b| {
            b.iter(|| bound.model.evaluate_columns(&input_slices, &mut outputs))
        });
    }
    group.finish();
}

/// The transmission error under load (the loaded contact solution at every point of the
/// curve, docs/models.md §12.9) per sample, one thread, at N = 4096 (the default) and
/// beyond: the RV40E of document 002 with the crank side of scenarios/reducers/rv40e.json
/// (the model's example), pin and tooth-space errors, on rows drawn from the shipped
/// transmission scenario. Target ≤ 500 µs per sample at 4096 points.
fn loaded_transmission_error(c: &mut Criterion) {
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("rv40e-transmission.json"))
            .expect("shipped scenario loads");
    let rows = 8;
    let columns = model_rows(&scenario, rows);
    let inputs: Vec<Vec<f64>> = (0..rows)
        .map(|r| columns.iter().map(|column| column[r]).collect())
        .collect();
    let entry = rvtol_models::find("transmission_error").expect("registered");
    let mut group = c.benchmark_group("transmission_error_loaded");
    group.sample_size(10);
    for points in [4096, 8192, 16384] {
        let params = (entry.example_params)()
            .with_number("pin_position_errors", 1.0)
            .with_number("tooth_profile_errors", 1.0)
            .with_number("sun_plane_offset_mm", 30.0)
            .with_number("points_per_revolution", points as f64);
        let model = (entry.build)(&params).expect("the example builds");
        assert_eq!(
            model.inputs().len(),
            inputs[0].len(),
            "the scenario's inputs"
        );
        let mut outputs = vec![0.0; model.outputs().len()];
        group.throughput(Throughput::Elements(rows as u64));
        group.bench_function(BenchmarkId::from_parameter(points), |b| {
            b.iter(|| {
                for row in &inputs {
                    model.evaluate(row, &mut outputs);
                }
            })
        });
    }
    group.finish();
}

/// The nonlinear function of ten inputs the `expression` benchmark times, as a built-in
/// model would write it.
struct TenInputs {
    inputs: Vec<rvtol_models::InputSpec>,
    outputs: Vec<rvtol_models::OutputSpec>,
}

/// Its formula, as the expression model reads it.
const TEN_INPUTS: &str = "sin(x1)*x2 + hypot(x3, x4) + exp(-x5^2) + x6*x7/(1 + x8^2) + sqrt(abs(x9))*cos(x10) + atan2(x1, x10)";

impl rvtol_models::ErrorModel for TenInputs {
    fn name(&self) -> &'static str {
        "ten_inputs"
    }
    fn inputs(&self) -> &[rvtol_models::InputSpec] {
        &self.inputs
    }
    fn outputs(&self) -> &[rvtol_models::OutputSpec] {
        &self.outputs
    }
    #[inline]
    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        out[0] = x[0].sin() * x[1]
            + x[2].hypot(x[3])
            + (-x[4].powi(2)).exp()
            + x[5] * x[6] / (1.0 + x[7].powi(2))
            + x[8].abs().sqrt() * x[9].cos()
            + x[0].atan2(x[9]);
    }
}

/// Time per sample of a ten-input nonlinear function written as a formula (the
/// `expression` model's column program) and as a built-in Rust model, on blocks of
/// BLOCK_ROWS rows as a run evaluates them (target: the formula at most 2× the built-in).
fn expression(c: &mut Criterion) {
    use rvtol_models::{ErrorModel, ParamValue};
    let names: Vec<String> = (1..=10).map(|i| format!("x{i}")).collect();
    let text = |s: &str| ParamValue::Text(s.into());
    let params = rvtol_models::ModelParams::new()
        .with(
            "inputs",
            ParamValue::Object(names.iter().map(|n| (n.clone(), text("1"))).collect()),
        )
        .with(
            "outputs",
            ParamValue::Object(vec![(
                "y".into(),
                ParamValue::Object(vec![
                    ("formula".into(), text(TEN_INPUTS)),
                    ("unit".into(), text("1")),
                ]),
            )]),
        );
    let formula = rvtol_models::Expression::from_params(&params).expect("the formula builds");
    let built_in = TenInputs {
        inputs: formula.inputs().to_vec(),
        outputs: formula.outputs().to_vec(),
    };
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let columns: Vec<Vec<f64>> = (0..10)
        .map(|_| (0..ROWS).map(|_| rng.random_range(-2.0..2.0)).collect())
        .collect();
    let mut outputs = vec![0.0; BLOCK_ROWS];
    let mut check = (vec![0.0; ROWS], vec![0.0; ROWS]);
    for (label, model, out) in [
        ("formula", &formula as &dyn ErrorModel, &mut check.0),
        ("built_in", &built_in, &mut check.1),
    ] {
        for first in (0..ROWS).step_by(BLOCK_ROWS) {
            let block: Vec<&[f64]> = columns
                .iter()
                .map(|c| &c[first..first + BLOCK_ROWS])
                .collect();
            model.evaluate_columns(&block, &mut out[first..first + BLOCK_ROWS]);
        }
        assert!(out.iter().all(|y| y.is_finite()), "{label}");
    }
    for (a, b) in check.0.iter().zip(&check.1) {
        assert!((a - b).abs() <= 1e-13 * a.abs().max(1.0), "{a} against {b}");
    }
    let mut group = c.benchmark_group("expression_per_sample");
    group.throughput(Throughput::Elements(ROWS as u64));
    for (label, model) in [
        ("formula", &formula as &dyn ErrorModel),
        ("built_in", &built_in),
    ] {
        group.bench_function(label, |b| {
            b.iter(|| {
                for first in (0..ROWS).step_by(BLOCK_ROWS) {
                    let block: Vec<&[f64]> = columns
                        .iter()
                        .map(|c| &c[first..first + BLOCK_ROWS])
                        .collect();
                    model.evaluate_columns(&block, &mut outputs);
                }
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    normals,
    stages,
    floor,
    whole_run,
    models,
    expression,
    loaded_transmission_error
);
criterion_main!(benches);
