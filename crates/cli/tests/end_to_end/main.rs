//! rvtol's end-to-end tests: the `rvtol` binary of this package (Cargo builds it for
//! this test and names it in `CARGO_BIN_EXE_rvtol`; no nested cargo) driven on the shipped
//! scenarios and on scenarios written for a test, its reports, messages and exit codes
//! checked. One test binary, one link step; `cargo test --release -p rvtol --test
//! end_to_end MODULE::` runs one file's tests. Tests that use only the library crates
//! live in tests/ (package rvtol-tests), with the precision policy of the statistical
//! tests (its `lib.rs`), which these tests share.
//!
//! What goes where:
//! - `common`: finding the binary, running it, temporary scenario files, the workspace.
//! - `cli`: the commands' reports and files, the JSON contract, thread-count
//!   independence, samples out (CSV and Parquet), init and models.
//! - `bad_input`: every bad input a user can hit: its one-line message and exit code 2.
//! - `hardening`: hostile and extreme inputs (huge, non-finite, devices, limits of
//!   memory and of files), interrupted commands, staged outputs.
//! - `mutation`: thousands of mutated shipped scenarios, validated without a panic.
//! - `scenario_format`: the scenario format's keys and units, through the binary and the
//!   engine.
//! - `readme`: README.md's examples run, their outputs as printed there.
//! - `report`: `rvtol report` and the HTML pages.
//! - `gate`: `baseline` and `check`, their bands and requirements.
//! - `allocate`: `rvtol allocate`, its proposal and verification.
//! - `conformity`: one meaning of a non-conforming sample in run, check and allocate.
//! - `fit`: `rvtol fit` against the library's fit.
//! - `shard`: `--shard` and `merge`, bit for bit the unsharded command.
//! - `kubernetes`: the Kubernetes recipe's commands (deploy/kubernetes/).
//! - `stack`: `rvtol stack`, its JSON and its refusals.
//! - `rare`: `rvtol rare`, its JSON and its refusals.

mod common;

mod allocate;
mod bad_input;
mod cli;
mod conformity;
mod fit;
mod gate;
mod hardening;
mod kubernetes;
mod mutation;
mod rare;
mod readme;
mod report;
mod scenario_format;
mod shard;
mod stack;
