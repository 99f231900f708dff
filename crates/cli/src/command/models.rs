//! `rvtol models`: the registry's models with their parameters, inputs and outputs.

use anyhow::Result;

use crate::output::print;

/// `rvtol models`: the list, on standard output.
pub fn models() -> Result<()> {
    let mut out = String::new();
    for entry in rvtol_models::all() {
        out.push_str(&format!("{}\n  {}\n", entry.name, entry.summary));
        out.push_str("  parameters:\n");
        for p in entry.params {
            let default = p
                .default
                .map(|d| format!(" (default {})", rvtol_deviation::Shown(d)))
                .unwrap_or_default();
            out.push_str(&format!(
                "    {:<36} {:<6} {}{default}\n",
                p.name, p.unit, p.description
            ));
        }
        let model = (entry.build)(&(entry.example_params)())
            .map_err(|err| anyhow::anyhow!("example of {} does not build: {err}", entry.name))?;
        out.push_str("  inputs:\n");
        for i in model.inputs() {
            out.push_str(&format!(
                "    {:<36} {:<6} {}\n",
                i.name, i.unit, i.description
            ));
        }
        out.push_str("  outputs:\n");
        for o in model.outputs() {
            out.push_str(&format!(
                "    {:<36} {:<8} {}\n",
                o.name, o.unit, o.description
            ));
        }
        out.push('\n');
    }
    print(&out)
}
