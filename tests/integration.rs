//! rvtol's end-to-end, scenario, statistical and golden-value tests, one module per
//! concern, built as one test binary (one link step; `cargo test --release --test
//! integration <module>::` runs one file's tests).

mod common;

mod allocate;
mod bad_input;
mod capability_intervals;
mod cli;
mod engine;
mod fit;
mod gate;
mod hardening;
mod kubernetes;
mod lost_motion;
mod msrv;
mod mutation;
mod percentile_intervals;
mod readme;
mod report;
mod sampler;
mod sampling;
mod scenario_format;
mod sensitivity;
mod shard;
mod stiffness;
mod structure;
mod transmission_error;
