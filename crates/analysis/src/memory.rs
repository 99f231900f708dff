//! What an analysis needs in memory, worked out before anything is allocated (the run's
//! and the row evaluation's are rvtol-engine's `memory`, whose [`MemoryNeed`] these
//! return too): the sensitivity analysis' kept model values or block sums and its
//! per-thread sample matrices, the allocation's kept values of the targeted output.

use rvtol_engine::chunk::CHUNK_SIZE;
use rvtol_engine::format::group_thousands;
use rvtol_engine::memory::{fewer_workers, run_scratch_per_thread, MemoryNeed, BASE_BYTES, VALUE};
use rvtol_engine::Scenario;

use crate::sensitivity::{independent_groups, IntervalMethod, SensitivitySettings};

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
/// time) besides the run's per-thread buffers.
pub fn allocation(scenario: &Scenario, samples: u64, threads: usize) -> MemoryNeed {
    let scratch = 4.0 * threads as f64 * run_scratch_per_thread(scenario);
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
