//! rvtol's library tests that span crates: scenarios run through the engine and the
//! analyses, statistical and golden-value tests, the physical models against their
//! documents, the code's shape. One module per concern, built as one test binary (one
//! link step; `cargo test --release -p rvtol-tests --test integration <module>::` runs
//! one file's tests). The tests that drive the `rvtol` binary are the CLI package's
//! (crates/cli/tests/end_to_end/).

mod common;

mod assemblies;
mod capability_intervals;
mod conformity;
mod copula;
mod engine;
mod expression;
mod lost_motion;
mod msrv;
mod percentile_intervals;
mod rare;
mod rare_allocation;
mod sampler;
mod sampling;
mod sensitivity;
mod stack;
mod stiffness;
mod structure;
mod sweep;
mod transmission_error;
