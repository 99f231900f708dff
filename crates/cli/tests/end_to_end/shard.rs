//! Sharded runs (`run --shard K/N --partial`, `merge`): the merge of the shards is the run,
//! byte for byte, for every shipped scenario, both percentile paths, any shard count
//! (including shards with no chunk) and several orders of the partials; and every file a merge
//! must refuse is refused with one line and exit 2.

use crate::common;

use std::ops::Range;
use std::path::{Path, PathBuf};

use common::{run_rvtol, scenario};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rvtol_analysis::sensitivity::{merge_sobol, sobol_chunks, sobol_indices, SensitivitySettings};
use rvtol_analysis::shapley::{
    merge_shapley, shapley_effects, shapley_partial, shapley_permutations, ShapleySettings,
};
use rvtol_analysis::shard::{
    decode, encode, ShapleyShard, ShardCommand, ShardContent, ShardHeader,
};
use rvtol_deviation::SamplingMethod;
use rvtol_engine::chunk::shard_range;
use rvtol_engine::chunk::CHUNK_SIZE;
use rvtol_engine::report::RunReport;
use rvtol_engine::{merge, run, run_chunks, RunSettings, Sampling, Scenario};
use rvtol_tests::scenario_path;

/// Shard counts of the acceptance: one, a few, more than the chunks (empty shards).
const SHARD_COUNTS: [u64; 5] = [1, 2, 3, 7, 64];

/// Every shipped scenario.
fn shipped() -> Vec<String> {
    let mut files: Vec<String> = std::fs::read_dir(scenario_path(""))
        .unwrap()
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".json"))
        .collect();
    files.sort();
    assert!(files.len() >= 14, "{files:?}");
    files
}

fn report(scenario: &Scenario, result: rvtol_engine::RunResult) -> String {
    RunReport::new(scenario, result).to_json()
}

/// Orders in which each set of partials is merged (shuffles of its own seed).
const MERGE_ORDERS: u64 = 3;

/// The reports merged from `shards` shards, each partial written to bytes and read back
/// (the file format is part of the path), merged in [`MERGE_ORDERS`] shuffled orders.
fn sharded_reports(scenario: &Scenario, settings: RunSettings, shards: u64) -> Vec<String> {
    // The shards side by side, as on a cluster (each evaluates the pilot chunk alone).
    let partials: Vec<_> = (0..shards)
        .into_par_iter()
        .map(|k| {
            let chunks = shard_range(settings.chunk_count(), k, shards);
            let partial = run_chunks(scenario, settings, chunks.clone(), &|_| {}).unwrap();
            let header = test_header(
                ShardCommand::Run {
                    samples: settings.samples,
                    seed: settings.seed,
                    exact_percentile_limit: settings.exact_percentile_limit,
                    sampling: settings.sampling.method.name().to_string(),
                    replicates: settings.sampling.replicates,
                },
                k,
                shards,
                chunks.clone(),
            );
            match round_trip(&header, ShardContent::Run(partial)) {
                ShardContent::Run(partial) => partial,
                ShardContent::Sensitivity { .. } => unreachable!(),
            }
        })
        .collect();
    (0..MERGE_ORDERS)
        .map(|order| {
            let mut shuffled = partials.clone();
            shuffled.shuffle(&mut ChaCha8Rng::seed_from_u64(
                shards * MERGE_ORDERS + order,
            ));
            report(scenario, merge(scenario, settings, shuffled).unwrap())
        })
        .collect()
}

/// A header for in-process partials (the CLI's build and scenario checks are tested
/// through the binary below).
fn test_header(command: ShardCommand, shard: u64, shards: u64, chunks: Range<u64>) -> ShardHeader {
    ShardHeader {
        rvtol_version: "test".into(),
        build: "test".into(),
        scenario_fallback_name: "test".into(),
        scenario_file: String::new(),
        command,
        shard,
        shards,
        chunks: [chunks.start, chunks.end],
    }
}

/// The content as a shard file carries it: written to bytes and read back.
fn round_trip(header: &ShardHeader, content: ShardContent) -> ShardContent {
    let file = decode(&encode(header, &content)).unwrap();
    assert_eq!(&file.header, header);
    file.content
}

#[test]
fn every_shipped_scenario_merges_to_the_run_bit_for_bit() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    // Three full chunks and a partial one: 64 shards leave most of them empty.
    let samples = 3 * CHUNK_SIZE as u64 + 1234;
    for file in shipped() {
        // The transmission error in its rigid first contact here (its structure, every
        // shard count): under load (the shipped default, some 40 times the cost) the 64
        // shards' pilot chunks alone would take a CPU-hour. The loaded reading merges in
        // `the_loaded_transmission_error_merges_to_the_run_bit_for_bit`.
        let scenario = if file == "rv40e-transmission.json" {
            rigid_transmission_scenario()
        } else {
            rvtol_analysis::request::scenario::load(&scenario_path(&file)).unwrap()
        };
        // Exact percentiles, then the sketch (a limit of 0 values forces it).
        for exact_percentile_limit in [u64::MAX, 0] {
            let settings = RunSettings {
                samples,
                seed: 7,
                exact_percentile_limit,
                sampling: Default::default(),
            };
            let single =
                pool.install(|| report(&scenario, run(&scenario, settings, &|_| {}).unwrap()));
            for shards in SHARD_COUNTS {
                for merged in pool.install(|| sharded_reports(&scenario, settings, shards)) {
                    assert!(
                        merged == single,
                        "{file}: {shards} shards, exact limit {exact_percentile_limit}: the merged report differs from the run's"
                    );
                }
            }
        }
    }
}

/// The shipped transmission-error scenario in the rigid first contact.
fn rigid_transmission_scenario() -> Scenario {
    let file = "rv40e-transmission.json";
    let text = rvtol_tests::shipped_text(scenario_path(file)).replace(
        "\"disc_contact\": \"loaded\"",
        "\"disc_contact\": \"first_contact\"",
    );
    assert!(text.contains("\"disc_contact\": \"first_contact\""));
    Scenario::from_json(&text, file).unwrap()
}

#[test]
fn the_loaded_transmission_error_merges_to_the_run_bit_for_bit() {
    // The shipped transmission error under load (each row warm starts its points from
    // per-thread work state): two chunks, the first a full one, in three shards (the last
    // holds no chunk but evaluates the pilot), with exact percentiles and the sketch.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let file = "rv40e-transmission.json";
    let scenario = rvtol_analysis::request::scenario::load(&scenario_path(file)).unwrap();
    let samples = CHUNK_SIZE as u64 + 300;
    for exact_percentile_limit in [u64::MAX, 0] {
        let settings = RunSettings {
            samples,
            seed: 11,
            exact_percentile_limit,
            sampling: Default::default(),
        };
        let single = pool.install(|| report(&scenario, run(&scenario, settings, &|_| {}).unwrap()));
        for merged in pool.install(|| sharded_reports(&scenario, settings, 3)) {
            assert!(
                merged == single,
                "{file}: 3 shards, exact limit {exact_percentile_limit}: the merged report differs from the run's"
            );
        }
    }
}

/// Sobol' indices (row and block bootstrap, replicated Latin hypercube and scrambled
/// Sobol' designs) and Shapley effects merged from 1, 2, 3, 7 and 64 shards in shuffled
/// order are those of one process, bit for bit.
#[test]
fn sensitivity_merges_to_the_analysis_bit_for_bit() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    // Two full chunks and a partial one.
    let samples = 2 * CHUNK_SIZE as u64 + 1808;
    for file in [
        "ishigami.json",
        "sobol-g.json",
        "rv20e-hysteresis.json",
        "linear-stack-correlated.json",
        "shapley-linear-gaussian.json",
    ] {
        let scenario = rvtol_analysis::request::scenario::load(&scenario_path(file)).unwrap();
        // The row bootstrap, then the block bootstrap (a limit of 0 values forces it); a
        // scrambled Sobol' design of 2 replicates (two chunks each, the second part-filled)
        // and a Latin hypercube of 4 (one part-filled chunk each).
        let rqmc = Sampling {
            method: SamplingMethod::Rqmc,
            replicates: 2,
        };
        let lhs = Sampling {
            method: SamplingMethod::LatinHypercube,
            replicates: 4,
        };
        for (row_bootstrap_limit, sampling) in [
            (u64::MAX, Sampling::MONTE_CARLO),
            (0, Sampling::MONTE_CARLO),
            (u64::MAX, rqmc),
            (u64::MAX, lhs),
        ] {
            let settings = SensitivitySettings {
                base_samples: samples,
                seed: 11,
                bootstrap: 200,
                confidence: 0.95,
                row_bootstrap_limit,
                sampling,
            };
            let single = pool
                .install(|| format!("{:?}", sobol_indices(&scenario, settings, &|_| {}).unwrap()));
            for shards in SHARD_COUNTS {
                let mut partials: Vec<_> = pool.install(|| {
                    (0..shards)
                        .into_par_iter()
                        .map(|k| {
                            let chunks = shard_range(settings.chunk_count(), k, shards);
                            let sobol =
                                sobol_chunks(&scenario, settings, chunks.clone(), &|_| {}).unwrap();
                            let header = test_header(
                                ShardCommand::Sensitivity {
                                    samples,
                                    seed: 11,
                                    bootstrap: 200,
                                    row_bootstrap_limit,
                                    sampling: sampling.method.name().to_string(),
                                    replicates: sampling.replicates,
                                    shapley: None,
                                },
                                k,
                                shards,
                                chunks,
                            );
                            match round_trip(
                                &header,
                                ShardContent::Sensitivity {
                                    sobol,
                                    shapley: None,
                                },
                            ) {
                                ShardContent::Sensitivity { sobol, .. } => sobol,
                                ShardContent::Run(_) => unreachable!(),
                            }
                        })
                        .collect()
                });
                partials.shuffle(&mut ChaCha8Rng::seed_from_u64(shards));
                let merged = pool.install(|| {
                    format!("{:?}", merge_sobol(&scenario, settings, partials).unwrap())
                });
                assert!(
                    merged == single,
                    "{file}: {shards} shards, row limit {row_bootstrap_limit}, {sampling:?}: the merged indices differ"
                );
            }
        }
    }
    // Shapley effects: 120 permutations of the five-player Gaussian scenario.
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("shapley-linear-gaussian.json"))
            .unwrap();
    let settings = ShapleySettings {
        permutations: 120,
        outer: 64,
        inner: 3,
        seed: 5,
    };
    let single = pool.install(|| format!("{:?}", shapley_effects(&scenario, settings).unwrap()));
    let total = shapley_permutations(&scenario, settings).unwrap();
    for shards in SHARD_COUNTS.into_iter().chain([total + 3]) {
        let mut partials: Vec<_> = pool.install(|| {
            (0..shards)
                .into_par_iter()
                .map(|k| {
                    let range = shard_range(total, k, shards);
                    let partial = shapley_partial(&scenario, settings, range.clone()).unwrap();
                    let header = test_header(
                        ShardCommand::Sensitivity {
                            samples: 2,
                            seed: 5,
                            bootstrap: 2,
                            row_bootstrap_limit: 0,
                            sampling: "mc".into(),
                            replicates: 1,
                            shapley: Some(ShapleyShard {
                                budget: 120,
                                outer: 64,
                                permutations: total,
                                range: [range.start, range.end],
                            }),
                        },
                        k,
                        shards,
                        0..0,
                    );
                    let sobol = rvtol_analysis::sensitivity::SobolPartial {
                        chunks: 0..0,
                        values: rvtol_analysis::sensitivity::SobolChunks::Rows(Vec::new()),
                    };
                    match round_trip(
                        &header,
                        ShardContent::Sensitivity {
                            sobol,
                            shapley: Some(partial),
                        },
                    ) {
                        ShardContent::Sensitivity { shapley, .. } => shapley.unwrap(),
                        ShardContent::Run(_) => unreachable!(),
                    }
                })
                .collect()
        });
        partials.shuffle(&mut ChaCha8Rng::seed_from_u64(shards));
        let merged = pool.install(|| {
            format!(
                "{:?}",
                merge_shapley(&scenario, settings, partials).unwrap()
            )
        });
        assert!(
            merged == single,
            "{shards} shards: the merged Shapley effects differ"
        );
    }
}

/// A merge of partials that do not cover the run, or overlap, is an error (the engine's own
/// check, under the CLI's file checks).
#[test]
fn merge_refuses_gaps_and_overlaps() {
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("rv20e-hysteresis.json")).unwrap();
    let settings = RunSettings {
        samples: 5 * CHUNK_SIZE as u64,
        seed: 3,
        exact_percentile_limit: u64::MAX,
        sampling: Default::default(),
    };
    let part = |a: u64, b: u64| run_chunks(&scenario, settings, a..b, &|_| {}).unwrap();
    let gap = merge(&scenario, settings, vec![part(0, 2), part(3, 5)]).unwrap_err();
    assert!(gap.to_string().contains("chunks 2..3 are missing"), "{gap}");
    let overlap = merge(&scenario, settings, vec![part(0, 3), part(2, 5)]).unwrap_err();
    assert!(overlap.to_string().contains("overlap"), "{overlap}");
    let short = merge(&scenario, settings, vec![part(0, 4)]).unwrap_err();
    assert!(
        short.to_string().contains("chunks 4..5 are missing"),
        "{short}"
    );
    assert!(run_chunks(&scenario, settings, 4..6, &|_| {}).is_err());
}

/// A directory of its own for one test's files, removed when dropped.
struct Dir(PathBuf);

impl Dir {
    fn new(label: &str) -> Dir {
        let dir = std::env::temp_dir().join(format!("rvtol-shard-{label}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Dir(dir)
    }
    fn file(&self, name: &str) -> String {
        self.0.join(name).display().to_string()
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn ok(args: &[&str]) -> String {
    let out = run_rvtol(args);
    assert!(
        out.status.success(),
        "rvtol {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Runs `rvtol args`, expects exit 2 with one line on stderr containing `needle`.
fn refused(args: &[&str], needle: &str) {
    let out = run_rvtol(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "rvtol {args:?}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains(needle), "expected {needle:?} in: {stderr}");
}

/// Writes shard `k` of `n` of `file` to `out`, with extra arguments.
fn shard(file: &str, k: u64, n: u64, out: &str, extra: &[&str]) {
    let shard = format!("{k}/{n}");
    let mut args = vec!["run", file, "--shard", &shard, "--partial", out, "-q"];
    args.extend_from_slice(extra);
    ok(&args);
}

#[test]
fn cli_merge_is_the_run_and_the_baseline() {
    let dir = Dir::new("cli");
    let file = scenario("rv20e-hysteresis.json");
    for (label, extra) in [
        ("exact", vec!["--samples", "30000"]),
        (
            "sketch",
            vec!["--samples", "30000", "--exact-percentile-limit", "1000"],
        ),
        // Replicates that do not fill their last chunk, drawn from scrambled Sobol' points.
        (
            "rqmc",
            vec![
                "--samples",
                "30000",
                "--sampling",
                "rqmc",
                "--replicates",
                "6",
            ],
        ),
    ] {
        let full = dir.file(&format!("{label}-full.json"));
        let mut args = vec!["run", &file, "--json", &full, "-q"];
        args.extend_from_slice(&extra);
        ok(&args);
        let parts: Vec<String> = (0..3)
            .map(|k| dir.file(&format!("{label}-{k}.part")))
            .collect();
        for (k, part) in parts.iter().enumerate() {
            shard(&file, k as u64, 3, part, &extra);
        }
        let merged = dir.file(&format!("{label}-merged.json"));
        ok(&["merge", &parts[2], &parts[0], &parts[1], "--json", &merged]);
        assert_eq!(
            std::fs::read(&full).unwrap(),
            std::fs::read(&merged).unwrap(),
            "{label}"
        );
        // A rerun shard given twice is accepted.
        let again = dir.file(&format!("{label}-again.json"));
        ok(&[
            "merge", &parts[0], &parts[1], &parts[1], &parts[2], "--json", &again,
        ]);
        assert_eq!(
            std::fs::read(&full).unwrap(),
            std::fs::read(&again).unwrap()
        );
    }
    // The baseline from the shards is the baseline of the run; a check of the shards
    // against it passes.
    let parts: Vec<String> = (0..3)
        .map(|k| dir.file(&format!("exact-{k}.part")))
        .collect();
    let direct = dir.file("baseline-direct.json");
    ok(&["baseline", &file, "--samples", "30000", "-o", &direct, "-q"]);
    let merged = dir.file("baseline-merged.json");
    ok(&[
        "merge",
        &parts[0],
        &parts[1],
        &parts[2],
        "--baseline",
        &merged,
    ]);
    assert_eq!(
        std::fs::read(&direct).unwrap(),
        std::fs::read(&merged).unwrap()
    );
    let report = ok(&["merge", &parts[0], &parts[1], &parts[2], "--check", &direct]);
    assert!(report.contains("within their baseline bands"), "{report}");
}

/// Rewrites a shard file with `change` applied to its decoded header and partial (the
/// checksum recomputed: a file another build or another run could have written).
fn rewritten(from: &str, to: &str, change: impl FnOnce(&mut ShardHeader, &mut ShardContent)) {
    let mut file = decode(&std::fs::read(from).unwrap()).unwrap();
    change(&mut file.header, &mut file.content);
    std::fs::write(to, encode(&file.header, &file.content)).unwrap();
}

#[test]
fn cli_merge_refuses_what_is_not_one_whole_run() {
    let dir = Dir::new("refusals");
    let file = scenario("rv20e-hysteresis.json");
    let samples = ["--samples", "20000"];
    let p: Vec<String> = (0..4).map(|k| dir.file(&format!("{k}.part"))).collect();
    for (k, part) in p.iter().enumerate() {
        shard(&file, k as u64, 4, part, &samples);
    }
    // A gap, and --missing listing it in job-array form.
    refused(&["merge", &p[0], &p[3]], "shards 1,2 of 4 have no file");
    assert_eq!(ok(&["merge", "--missing", &p[0], &p[3]]), "1,2\n");
    assert_eq!(ok(&["merge", "--missing", &p[0], &p[1], &p[2], &p[3]]), "");
    // A conflicting duplicate.
    let conflict = dir.file("conflict.part");
    rewritten(&p[1], &conflict, |_, content| {
        if let ShardContent::Run(partial) = content {
            partial.replicates[0].1[0].below_lower += 1;
        }
    });
    refused(
        &["merge", &p[0], &p[1], &conflict, &p[2], &p[3]],
        "shard 1/4 is also in",
    );
    // Another scenario, other settings, another shard count, another build.
    let foreign = dir.file("foreign.part");
    shard(&scenario("rv20e-torsion.json"), 1, 4, &foreign, &samples);
    refused(&["merge", &p[0], &foreign], "the scenario differs from");
    // Another text of this scenario (its description edited, the data files written in
    // so that it loads from the temporary folder): its shard is refused, and so is its
    // baseline beside these shards' merge, unless --scenario-changed says the design
    // changed on purpose.
    let mut edited: serde_json::Value = serde_json::from_str(&rvtol_tests::shipped_text(
        scenario_path("rv20e-hysteresis.json"),
    ))
    .unwrap();
    edited["description"] = "edited after the shards ran".into();
    let edited_file = dir.file("edited.json");
    std::fs::write(&edited_file, edited.to_string()).unwrap();
    let edited_part = dir.file("edited.part");
    shard(&edited_file, 1, 4, &edited_part, &samples);
    refused(&["merge", &p[0], &edited_part], "the scenario differs from");
    let edited_baseline = dir.file("edited-baseline.json");
    ok(&[
        "baseline",
        &edited_file,
        "--samples",
        "20000",
        "-o",
        &edited_baseline,
        "-q",
    ]);
    refused(
        &[
            "merge",
            &p[0],
            &p[1],
            &p[2],
            &p[3],
            "--check",
            &edited_baseline,
        ],
        "scenario_sha256: recorded from another text",
    );
    let checked = ok(&[
        "merge",
        &p[0],
        &p[1],
        &p[2],
        &p[3],
        "--check",
        &edited_baseline,
        "--scenario-changed",
    ]);
    assert!(checked.contains("within their baseline bands"), "{checked}");
    let seed = dir.file("seed.part");
    shard(&file, 1, 4, &seed, &["--samples", "20000", "--seed", "99"]);
    refused(&["merge", &p[0], &seed], "the settings differ from");
    let sampling = dir.file("sampling.part");
    shard(
        &file,
        1,
        4,
        &sampling,
        &[
            "--samples",
            "20000",
            "--sampling",
            "lhs",
            "--replicates",
            "4",
        ],
    );
    refused(&["merge", &p[0], &sampling], "the settings differ from");
    // Samples that do not split into the replicates, and replicates without a method
    // that has them: one line each, before anything runs, naming the option that gave
    // the value.
    refused(
        &["run", &file, "--sampling", "rqmc", "--samples", "1001"],
        "error: --samples: 1001 samples do not split into 16 replicates",
    );
    refused(
        &["run", &file, "--replicates", "4", "--samples", "1000"],
        "error: --replicates: Monte Carlo rows are independent",
    );
    let count = dir.file("count.part");
    shard(&file, 1, 3, &count, &samples);
    refused(&["merge", &p[0], &count], "the shard count differs from");
    let build = dir.file("build.part");
    rewritten(&p[1], &build, |header, _| {
        header.build = "rvtol 0.0.1 sha256:0".into()
    });
    refused(
        &["merge", &p[0], &build, &p[2], &p[3]],
        "computed by another build of rvtol",
    );
    // A sampling method this rvtol does not know.
    let unknown = dir.file("unknown.part");
    rewritten(&p[1], &unknown, |header, _| {
        if let ShardCommand::Run { sampling, .. } = &mut header.command {
            *sampling = "qmc".into();
        }
    });
    refused(&["merge", &p[0], &unknown], "damaged: sampling \"qmc\"");
    // A chunk range that is not the shard's.
    let range = dir.file("range.part");
    rewritten(&p[1], &range, |header, _| header.shard = 2);
    refused(
        &["merge", &p[0], &range],
        "does not cover what that shard computes",
    );
    // Damaged files: truncated, a flipped byte, not a shard file at all, unreadable.
    let bytes = std::fs::read(&p[1]).unwrap();
    let truncated = dir.file("truncated.part");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    refused(&["merge", &p[0], &truncated], "damaged");
    let flipped = dir.file("flipped.part");
    let mut altered = bytes.clone();
    let middle = altered.len() / 2;
    altered[middle] ^= 1;
    std::fs::write(&flipped, &altered).unwrap();
    refused(
        &["merge", &p[0], &flipped],
        "damaged: its checksum does not match",
    );
    refused(
        &["merge", &scenario("rv20e-hysteresis.json")],
        "not a shard file of rvtol",
    );
    refused(&["merge", &dir.file("absent.part")], "cannot read");
    // The whole set still merges.
    ok(&[
        "merge",
        &p[3],
        &p[2],
        &p[1],
        &p[0],
        "--json",
        &dir.file("whole.json"),
    ]);
    // Usage: --shard needs --partial and excludes the reports; K < N.
    refused(&["run", &file, "--shard", "1/4"], "--partial");
    refused(
        &[
            "run",
            &file,
            "--shard",
            "4/4",
            "--partial",
            &dir.file("x.part"),
        ],
        "0 <= K < N",
    );
    refused(
        &[
            "run",
            &file,
            "--shard",
            "0/4",
            "--partial",
            &dir.file("x.part"),
            "--json",
            "-",
        ],
        "cannot be used with",
    );
    assert!(!Path::new(&dir.file("x.part")).exists());
}

/// Writes the `n` shards of `rvtol sensitivity file options…` to K.part in `dir`; returns
/// their paths in shard order.
fn sensitivity_shards(dir: &Dir, file: &str, n: u64, options: &[&str]) -> Vec<String> {
    (0..n)
        .map(|k| {
            let part = dir.file(&format!("{k}.part"));
            let shard = format!("{k}/{n}");
            let mut args = vec![
                "sensitivity",
                file,
                "--shard",
                &shard,
                "--partial",
                &part,
                "-q",
            ];
            args.extend_from_slice(options);
            ok(&args);
            part
        })
        .collect()
}

#[test]
fn cli_sensitivity_merge_is_the_analysis() {
    let dir = Dir::new("sensitivity");
    let file = scenario("shapley-linear-gaussian.json");
    let options = [
        "--samples",
        "12000",
        "--bootstrap",
        "100",
        "--shapley",
        "--permutations",
        "120",
        "--outer",
        "64",
    ];
    let full = dir.file("full.json");
    let mut args = vec!["sensitivity", &file, "--json", &full, "-q"];
    args.extend_from_slice(&options);
    ok(&args);
    let parts = sensitivity_shards(&dir, &file, 4, &options);
    let merged = dir.file("merged.json");
    ok(&[
        "merge", &parts[3], &parts[1], &parts[0], &parts[2], "--json", &merged,
    ]);
    assert_eq!(
        std::fs::read(&full).unwrap(),
        std::fs::read(&merged).unwrap()
    );
    // A run's shard does not belong with them; a baseline needs a run's shards.
    let run_part = dir.file("run.part");
    shard(&file, 1, 4, &run_part, &["--samples", "12000"]);
    refused(&["merge", &parts[0], &run_part], "the command differs from");
    refused(
        &[
            "merge",
            &parts[0],
            &parts[1],
            &parts[2],
            &parts[3],
            "--baseline",
            &dir.file("b.json"),
        ],
        "take the shards of a run",
    );
    // Other Shapley settings are another analysis.
    let other = dir.file("other.part");
    let mut args = vec![
        "sensitivity",
        &file,
        "--shard",
        "1/4",
        "--partial",
        &other,
        "-q",
    ];
    args.extend_from_slice(&options[..7]);
    args.extend_from_slice(&["--outer", "32"]);
    ok(&args);
    refused(
        &["merge", &parts[0], &other],
        "Shapley permutations 120 outer 32 against",
    );
    refused(
        &["merge", &parts[0], &parts[2], &parts[3]],
        "shard 1 of 4 has no file: run them (rvtol sensitivity",
    );
}

#[test]
fn cli_replicated_sensitivity_merge_is_the_analysis() {
    // 4 replicates of 3000 points of a scrambled Sobol' design: shards cut inside the
    // replicates, and the merge gives the analysis' bytes.
    let dir = Dir::new("sensitivity-rqmc");
    let file = scenario("rv20e-hysteresis.json");
    let options = [
        "--samples",
        "12000",
        "--sampling",
        "rqmc",
        "--replicates",
        "4",
    ];
    let full = dir.file("full.json");
    let mut args = vec!["sensitivity", &file, "--json", &full, "-q"];
    args.extend_from_slice(&options);
    ok(&args);
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&full).unwrap()).unwrap();
    assert_eq!(report["sampling"]["method"], "rqmc");
    assert_eq!(report["sampling"]["points_per_replicate"], 3000);
    assert!(report.get("bootstrap").is_none(), "{report}");
    let parts = sensitivity_shards(&dir, &file, 3, &options);
    let merged = dir.file("merged.json");
    ok(&["merge", &parts[2], &parts[0], &parts[1], "--json", &merged]);
    assert_eq!(
        std::fs::read(&full).unwrap(),
        std::fs::read(&merged).unwrap()
    );
    // A Latin hypercube shard is another analysis.
    let other = dir.file("lhs.part");
    let mut args = vec![
        "sensitivity",
        &file,
        "--shard",
        "1/3",
        "--partial",
        &other,
        "-q",
    ];
    args.extend_from_slice(&options[..2]);
    args.extend_from_slice(&["--sampling", "lhs", "--replicates", "4"]);
    ok(&args);
    refused(
        &["merge", &parts[0], &other],
        "(samples 12000, seed 20221013, sampling lhs × 4, no Shapley against",
    );
    // A replicated design has no bootstrap; its samples must split into the replicates.
    refused(
        &[
            "sensitivity",
            &file,
            "--sampling",
            "rqmc",
            "--bootstrap",
            "100",
        ],
        "--bootstrap: the intervals of a replicated rqmc design come from its replicates",
    );
    refused(
        &[
            "sensitivity",
            &file,
            "--sampling",
            "lhs",
            "--samples",
            "1000",
            "--replicates",
            "16",
        ],
        "error: --samples: 1000 base samples do not split into 16 replicates",
    );
}
