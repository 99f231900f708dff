//! Requests as the front-ends make them, in one place so that the command line and the
//! Python module cannot drift: where a scenario comes from and how its text is read
//! ([`scenario`], with the data files it refers to, [`data`]); the settings of each command
//! with their defaults resolved against the scenario's and their limits checked ([`run`],
//! [`sensitivity`], [`allocation`], [`gate`], [`shard`], [`stack`], [`rare`]); the columns of the tables
//! `evaluate` and `fit` read ([`evaluate`], [`fit`]); what a request needs in memory
//! ([`memory`]) against what the machine gives ([`machine`]); every file read whole within
//! a bound ([`input_file`], [`table`]) and the rows written out ([`samples`]). A refused
//! request is a [`Refusal`], which names an option as the [`Caller`] spells it. The front
//! ends parse arguments, show progress, write files and map errors to exit codes.

pub mod allocation;
pub mod data;
pub mod evaluate;
pub mod fit;
pub mod gate;
pub mod input_file;
pub mod machine;
pub mod memory;
pub mod rare;
pub mod run;
pub mod samples;
pub mod scenario;
pub mod sensitivity;
pub mod shard;
pub mod stack;
pub mod table;

use rvtol_engine::ScenarioError;

/// Who makes a request: how its messages spell an option.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Caller {
    /// The `rvtol` command line: `--samples-out`, `--sampling mc`.
    CommandLine,
    /// The Python module: `samples_out`, `sampling="mc"`.
    Python,
}

impl Caller {
    /// The option `name` (written with underscores) as the caller spells it.
    pub fn option(self, name: &str) -> String {
        match self {
            Caller::CommandLine => format!("--{}", name.replace('_', "-")),
            Caller::Python => name.to_string(),
        }
    }

    /// A message written with the command line's options (`--row-bootstrap-limit`) with
    /// each spelt for the caller.
    pub fn respell(self, text: &str) -> String {
        match self {
            Caller::CommandLine => text.to_string(),
            Caller::Python => {
                let mut out = String::with_capacity(text.len());
                let mut rest = text;
                while let Some(at) = rest.find("--") {
                    out.push_str(&rest[..at]);
                    let name: String = rest[at + 2..]
                        .chars()
                        .take_while(|c| c.is_ascii_lowercase() || *c == '-')
                        .collect();
                    out.push_str(&name.replace('-', "_"));
                    rest = &rest[at + 2 + name.len()..];
                }
                out.push_str(rest);
                out
            }
        }
    }

    /// The option `name` set to `value`, as the caller writes it.
    pub fn setting(self, name: &str, value: &str) -> String {
        match self {
            Caller::CommandLine => format!("{} {value}", self.option(name)),
            Caller::Python => format!("{name}=\"{value}\""),
        }
    }
}

/// Why a request is refused before any work.
#[derive(Debug, Clone, PartialEq)]
pub enum Refusal {
    /// A value the request gave: `{option}: {message}` (the option as the caller spells
    /// it).
    Option {
        /// The option (or options, `--permutations × --outer`).
        option: String,
        /// What is wrong with it.
        message: String,
    },
    /// The scenario's value (or anything the scenario file must change).
    Scenario(ScenarioError),
    /// A file the request reads (a table of rows or measurements): one line naming it.
    Input(String),
}

impl Refusal {
    /// A refusal of the value of `option` (`name` as the caller spells it).
    pub fn option(caller: Caller, name: &str, message: impl Into<String>) -> Refusal {
        Refusal::Option {
            option: caller.option(name),
            message: message.into(),
        }
    }

    /// The error about a request value that a check reports at the scenario key of the
    /// same name (`samples`, `sampling`, `replicates`): the option's when the request gave
    /// it (`given`), else the scenario's.
    pub fn at_option_or_scenario(
        err: ScenarioError,
        caller: Caller,
        given: &[(&str, bool)],
    ) -> Refusal {
        match given.iter().find(|(key, given)| *given && err.path == *key) {
            Some((key, _)) => Refusal::option(caller, key, err.message),
            None => Refusal::Scenario(err),
        }
    }
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::Option { option, message } => write!(f, "{option}: {message}"),
            Refusal::Scenario(err) => write!(f, "{err}"),
            Refusal::Input(message) => write!(f, "{message}"),
        }
    }
}

impl std::error::Error for Refusal {}
