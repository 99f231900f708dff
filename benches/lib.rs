//! Shared helpers of the benchmarks: the path of the shipped scenarios.

use std::path::PathBuf;

/// Path of a scenario shipped in scenarios/.
pub fn scenario_path(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios")
        .join(file)
}
