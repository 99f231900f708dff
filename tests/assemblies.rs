//! Tests of the assemblies a page draws beside the nominal one (rvtol_analysis::assemblies):
//! the row chosen is the run's own row nearest the target (checked against every row of
//! the sample table), the model's curves there are those of that row's inputs (not the
//! nominal's), and the output a torsion model is chosen by is its lost motion, the first
//! output with spec limits.

use rvtol_analysis::assemblies::{chosen_assemblies, curve_output, ASSEMBLY_ROWS};
use rvtol_engine::run::{model_inputs_of_row, sample_table};
use rvtol_engine::Scenario;
use rvtol_tests::{run_settings, scenario_path, shipped_text};

fn load(file: &str) -> Scenario {
    Scenario::from_json(&shipped_text(scenario_path(file)), file).unwrap()
}

#[test]
fn the_chosen_row_is_the_nearest_of_the_run_rows_and_its_curves_are_its_own() {
    let scenario = load("rv20e-torsion.json");
    let lost_motion = (scenario.outputs.iter())
        .position(|o| o.name == "lost_motion_arcmin")
        .unwrap();
    assert_eq!(curve_output(&scenario, 0), Some(lost_motion));
    // 1,500 rows: fewer than ASSEMBLY_ROWS, so every row of a run of that size is searched.
    let (samples, seed) = (1500, 11);
    assert!(samples < ASSEMBLY_ROWS);
    let targets = |name: &str| -> Vec<(String, f64)> {
        assert_eq!(name, "lost_motion_arcmin");
        vec![("P50".into(), 0.6), ("P99.865".into(), 1.9)]
    };
    let chosen = chosen_assemblies(&scenario, seed, samples, &targets).unwrap();
    assert_eq!(chosen.len(), 2);
    let table = sample_table(&scenario, run_settings(samples, seed)).unwrap();
    // The nominal inputs: every deviation at its mean (model 0 reads no other model).
    let mean_row = scenario.input_space.mean_row();
    let nominal = model_inputs_of_row(&scenario, &mean_row, &vec![0.0; scenario.outputs.len()]);
    for (assembly, target) in chosen.iter().zip([0.6, 1.9]) {
        assert_eq!(assembly.rows, samples);
        assert_eq!(assembly.output, "lost_motion_arcmin");
        // Brute force: no row with a value lies nearer the target.
        let r = assembly.sample as usize;
        let value = table.output_row(r)[lost_motion];
        assert_eq!(assembly.value, value);
        let distance = (value - target).abs();
        for other in 0..table.rows {
            let v = table.output_row(other)[lost_motion];
            assert!(
                !(v.is_finite() && (v - target).abs() < distance),
                "row {other}"
            );
        }
        // Its curves are the model's at that row's inputs, which are not the nominal's.
        let inputs = model_inputs_of_row(&scenario, table.input_row(r), table.output_row(r));
        assert_ne!(inputs[0], nominal[0]);
        assert!(assembly.left_out.is_empty());
        assert_eq!(assembly.curves, scenario.models[0].model.curves(&inputs[0]));
    }
    // The tail's assembly has more lost motion than the median one.
    assert!(chosen[1].value > chosen[0].value);
}

#[test]
fn a_scenario_whose_models_draw_no_curves_chooses_nothing() {
    let scenario = load("rv20e-hysteresis.json");
    let chosen = chosen_assemblies(&scenario, 1, 1000, &|_| vec![("P50".into(), 0.5)]).unwrap();
    assert!(chosen.is_empty());
}
