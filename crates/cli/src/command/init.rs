//! `rvtol init`: a complete, valid scenario for a model to start from.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::{outputs_ok, target};
use crate::output::{print, write_report, Format};
use crate::BadInput;

/// The arguments of `rvtol init`.
#[derive(Debug, Args)]
pub struct InitArgs {
    /// Model name (`rvtol models`).
    pub model: String,
    /// A parameter of the design, KEY=VALUE (a number or a text), in place of the
    /// example's; the inputs follow (e.g. `--param pin_position_errors=1` gives the
    /// transmission error an input per pin). Repeatable.
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Write the scenario to PATH instead of standard output.
    #[arg(short = 'o', long = "output", value_name = "PATH")]
    pub output: Option<PathBuf>,
}

/// `rvtol init`: the model's skeleton scenario with the given parameters.
pub fn init(args: InitArgs) -> Result<()> {
    let (model, params, output) = (args.model.as_str(), &args.params, args.output.as_deref());
    let mut given = serde_json::Map::new();
    for param in params {
        let Some((key, value)) = param.split_once('=') else {
            return Err(BadInput(format!("--param {param}: expected KEY=VALUE")).into());
        };
        let value = match value.trim().parse::<f64>() {
            Ok(x) if x.is_finite() => serde_json::json!(x),
            _ => serde_json::json!(value),
        };
        given.insert(key.trim().to_string(), value);
    }
    outputs_ok(&[target("-o", output, Format::Json)], &[])?;
    // The engine names a parameter by its scenario path; here it came from --param.
    let text = rvtol_engine::scenario::skeleton::skeleton_with(model, &given).map_err(|m| {
        BadInput(match m.strip_prefix("params.") {
            Some(rest) => format!("--param {rest}"),
            None => m,
        })
    })?;
    match output {
        Some(path) => write_report(path, &text),
        None => print(&text),
    }
}
