//! What a request needs in memory, worked out before anything is allocated, so that a
//! request that cannot fit is refused with one line naming the figure and the way out,
//! instead of aborting halfway through on a failed allocation.
//!
//! The estimates count the large, sample-dependent buffers: values kept for exact
//! percentiles or the row bootstrap, and the per-thread blocks (sampled columns, model
//! outputs, sample matrices of the analyses). Constant overheads (sketches, model tables,
//! the program itself) are covered by [`BASE_BYTES`]. The ways out name the command
//! line's options; [`MemoryNeed::check`] spells them for the caller.

use rvtol_deviation::human_bytes;
use rvtol_engine::chunk::{BLOCK_ROWS, CHUNK_SIZE, WAVE_CHUNKS};
use rvtol_engine::format::group_thousands;
use rvtol_engine::run::RunSettings;
use rvtol_engine::scenario::{Binding, Scenario};

use super::Caller;
use crate::sensitivity::{independent_groups, IntervalMethod, SensitivitySettings};

/// Bytes of one kept value.
const VALUE: f64 = 8.0;
/// Allowance for everything that does not grow with the request (program, model tables,
/// sketches).
pub const BASE_BYTES: f64 = 64e6;

/// The memory a request needs, with what it is for and how to need less.
#[derive(Debug, Clone, PartialEq)]
pub struct MemoryNeed {
    /// Bytes.
    pub bytes: f64,
    /// What takes most of it, in words.
    pub what: String,
    /// How a user needs less.
    pub way_out: &'static str,
}

/// How a user needs less worker memory: fewer threads while there are several.
fn fewer_workers(threads: usize) -> &'static str {
    if threads > 1 {
        "use fewer threads (--threads) or fewer input columns"
    } else {
        "use fewer input columns"
    }
}

impl MemoryNeed {
    /// `Err(one line)` when the need exceeds `budget` bytes (`budget_source` says where the
    /// budget comes from), the options it names spelt for `caller`.
    pub fn check(&self, budget: f64, budget_source: &str, caller: Caller) -> Result<(), String> {
        if self.bytes <= budget {
            return Ok(());
        }
        // Below the fixed allowance no request fits: say so rather than advise less.
        let way_out = if budget < BASE_BYTES {
            format!("allow at least {} (--max-memory)", human_bytes(self.bytes))
        } else {
            self.way_out.to_string()
        };
        Err(caller.respell(&format!(
            "needs about {} of memory ({}, and {} for the program and its tables), more than the {} available ({budget_source}): {way_out}",
            human_bytes(self.bytes),
            self.what,
            human_bytes(BASE_BYTES),
            human_bytes(budget),
        )))
    }
}

/// The buffers each worker thread of a run keeps: a block of sampled columns and the
/// sampler's scratch, the chunk's output columns, one model's outputs and its constant
/// input columns.
fn run_scratch_per_thread(scenario: &Scenario) -> f64 {
    let constants: usize = scenario
        .models
        .iter()
        .map(|bound| {
            bound
                .bindings
                .iter()
                .filter(|b| matches!(b, Binding::Constant(_)))
                .count()
        })
        .sum();
    let columns = scenario.input_space.n_columns() as f64;
    let outputs = scenario.outputs.len() as f64;
    VALUE
        * (3.0 * BLOCK_ROWS as f64 * columns
            + CHUNK_SIZE as f64 * (2.0 * outputs + constants as f64))
}

/// A Monte Carlo run (`run`, `baseline`, `check`): the kept values when the percentiles are
/// exact (all of them plus one wave in flight), and the per-thread buffers.
pub fn run(scenario: &Scenario, settings: &RunSettings, threads: usize) -> MemoryNeed {
    let continuous = scenario.continuous_outputs().len() as f64;
    let samples = settings.samples as f64;
    let exact = settings.samples.saturating_mul(continuous.max(1.0) as u64)
        <= settings.exact_percentile_limit;
    let kept = if exact {
        let in_flight = samples.min((WAVE_CHUNKS as usize * CHUNK_SIZE) as f64);
        VALUE * continuous * (samples + in_flight)
    } else {
        0.0
    };
    // Partials: about four splits per thread, each with its scratch.
    let scratch = 4.0 * threads as f64 * run_scratch_per_thread(scenario);
    MemoryNeed {
        bytes: BASE_BYTES + kept + scratch,
        what: if exact {
            format!(
                "{} kept values for exact percentiles of {continuous} output{}",
                group_thousands((samples * continuous) as u64),
                if continuous == 1.0 { "" } else { "s" }
            )
        } else {
            format!(
                "the worker buffers of {} input columns",
                scenario.input_space.n_columns()
            )
        },
        way_out: if exact {
            "lower --exact-percentile-limit (the percentiles then come from the bounded-memory sketch) or ask for fewer --samples"
        } else {
            fewer_workers(threads)
        },
    }
}

/// `rvtol stack`: the most rows it evaluates at once (the box's corners or the linearity
/// rows, whichever is more) with their outputs, twice (rows and their column-major copy),
/// and the run's per-thread buffers; or its Monte Carlo run's need
/// ([`run`]), when it has one and that is more (the two are not held at once).
pub fn stack(
    scenario: &Scenario,
    run_settings: Option<&RunSettings>,
    threads: usize,
) -> MemoryNeed {
    let own = stack_rows(scenario, threads);
    match run_settings.map(|settings| run(scenario, settings, threads)) {
        Some(run_need) if run_need.bytes > own.bytes => run_need,
        _ => own,
    }
}

/// `rvtol rare`: a level of subset simulation keeps its points and their candidates
/// (2·N·dims values and N scores); every worker holds a task's rows.
pub fn rare(scenario: &Scenario, level_samples: usize, threads: usize) -> MemoryNeed {
    let dims = scenario.input_space.quasi_dimensions().unwrap_or(0).max(1) as f64;
    let rows = level_samples as f64;
    MemoryNeed {
        bytes: BASE_BYTES
            + VALUE * rows * (2.0 * dims + 1.0)
            + threads as f64 * run_scratch_per_thread(scenario),
        what: format!(
            "{} points of {} normal scores per level",
            group_thousands(level_samples as u64),
            dims as u64
        ),
        way_out: fewer_workers(threads),
    }
}

fn stack_rows(scenario: &Scenario, threads: usize) -> MemoryNeed {
    let rows = (crate::stack::MOST_VERTICES as f64).max(crate::stack::LINEARITY_ROWS as f64);
    let width = (scenario.input_space.n_columns() + scenario.outputs.len()) as f64;
    MemoryNeed {
        bytes: BASE_BYTES
            + 2.0 * VALUE * rows * width
            + threads as f64 * run_scratch_per_thread(scenario),
        what: format!(
            "{} rows of {} input columns",
            group_thousands(rows as u64),
            scenario.input_space.n_columns()
        ),
        way_out: fewer_workers(threads),
    }
}

/// `rvtol sensitivity`: the row bootstrap keeps N·(2G + 2) values per continuous output
/// (twice, while one output's are concatenated); every worker holds a chunk's sample
/// matrices A, B and a mixed one with their column-major copy, and the chunk's values.
pub fn sensitivity(
    scenario: &Scenario,
    settings: &SensitivitySettings,
    threads: usize,
) -> MemoryNeed {
    let variants = (2 * independent_groups(scenario).len() + 2) as f64;
    let continuous = scenario.continuous_outputs().len() as f64;
    let n = settings.base_samples as f64;
    let method = settings.interval_method(scenario);
    let rows = method == IntervalMethod::Rows;
    let kept = match method {
        IntervalMethod::Rows => VALUE * n * variants * (continuous + 1.0),
        // Block sums: 2G + 3 numbers per block and output.
        IntervalMethod::Blocks { rows } => {
            VALUE * (n / rows as f64).ceil() * (variants + 1.0) * continuous
        }
        // One block per chunk.
        IntervalMethod::Replicates => {
            VALUE * settings.chunk_count() as f64 * (variants + 1.0) * continuous
        }
    };
    let columns = scenario.input_space.n_columns() as f64;
    let per_thread = VALUE * CHUNK_SIZE as f64 * (4.0 * columns + variants * continuous);
    let workers = threads as f64 * per_thread;
    let (what, way_out) = if rows {
        (
            format!(
                "{} model values for the row bootstrap",
                group_thousands((n * variants * continuous) as u64)
            ),
            "lower --row-bootstrap-limit (the intervals then come from the bounded-memory block bootstrap) or ask for fewer --samples",
        )
    } else if kept > workers {
        (
            format!(
                "the sums of {} blocks of rows for the intervals",
                group_thousands((kept / (VALUE * (variants + 1.0) * continuous.max(1.0))) as u64)
            ),
            "ask for fewer --samples",
        )
    } else {
        (
            format!("the sample matrices of {columns} input columns per worker thread"),
            fewer_workers(threads),
        )
    };
    MemoryNeed {
        bytes: BASE_BYTES + kept + workers,
        what,
        way_out,
    }
}

/// `rvtol allocate`: each Monte Carlo run keeps the targeted output's values (one run at a
/// time) besides the run's per-thread buffers; with `--rare`, each importance-sampling
/// estimate keeps a value, a score and a weight per point of its sample.
pub fn allocation(
    scenario: &Scenario,
    settings: &crate::allocation::AllocationSettings,
    threads: usize,
) -> MemoryNeed {
    let scratch = 4.0 * threads as f64 * run_scratch_per_thread(scenario);
    if let Some(rare) = settings.rare {
        let points = rare.max_evaluations;
        return MemoryNeed {
            bytes: BASE_BYTES + 3.0 * VALUE * points as f64 + scratch,
            what: format!(
                "up to {} weighted points per importance-sampling estimate",
                group_thousands(points)
            ),
            way_out: "ask for fewer --max-evaluations",
        };
    }
    let samples = settings.samples;
    let kept = 2.0 * VALUE * samples as f64;
    MemoryNeed {
        bytes: BASE_BYTES + kept + scratch,
        what: format!(
            "{} kept values of the targeted output per Monte Carlo run",
            group_thousands(samples)
        ),
        way_out: "ask for fewer --samples",
    }
}

/// Rows given in memory (the Python module's `evaluate`): their inputs copied, the
/// outputs of each block and of all rows, and the array handed back, and per worker
/// thread a block's input and output columns.
pub fn rows_evaluation(scenario: &Scenario, rows: u64, threads: usize) -> MemoryNeed {
    let inputs = scenario.input_space.n_columns() as f64;
    let outputs = scenario.outputs.len() as f64;
    MemoryNeed {
        bytes: BASE_BYTES
            + VALUE * rows as f64 * (inputs + 3.0 * outputs)
            + threads as f64 * VALUE * CHUNK_SIZE as f64 * (inputs + 2.0 * outputs),
        what: format!(
            "the inputs and outputs of {} rows, {} + {} values each",
            group_thousands(rows),
            inputs,
            outputs
        ),
        way_out: "evaluate fewer rows at a time",
    }
}

/// Bytes `rvtol evaluate` takes per byte of its rows' CSV: the text, its parsed records,
/// the input values, the evaluated table of inputs and outputs and its CSV (about 4.2 per
/// byte measured for 1,000,000 rows of 10 inputs and 1 output).
pub fn table_evaluation_factor(scenario: &Scenario) -> f64 {
    let inputs = scenario.columns.len().max(1) as f64;
    let outputs = scenario.outputs.len() as f64;
    3.0 + 2.0 * (inputs + outputs) / inputs
}

/// `rvtol evaluate` of a CSV of `file_bytes` bytes of rows.
pub fn table_evaluation(scenario: &Scenario, file_bytes: u64, file: &str) -> MemoryNeed {
    MemoryNeed {
        bytes: BASE_BYTES + table_evaluation_factor(scenario) * file_bytes as f64,
        what: format!(
            "the {} of rows of {file} read, evaluated and written out",
            human_bytes(file_bytes as f64)
        ),
        way_out: "split the rows into smaller files",
    }
}
