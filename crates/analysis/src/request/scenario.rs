//! Where a scenario comes from and how its text is read: a file (relative data paths start
//! from its folder), standard input, or a text the caller holds (the Python module's dict,
//! data paths relative to a folder it names). The text read is the file's with the numbers
//! of the data files it refers to written in ([`super::data`]): the scenario from then on
//! (a shard carries it, `allocate` scales it). The command line and the Python module read
//! every scenario here; the engine reads no file.

use std::path::{Path, PathBuf};

use rvtol_engine::{Scenario, ScenarioError};

use super::data::{data_files, inline_data_files};
use super::input_file::{read_standard_input, read_text, ReadLimit};

/// Where a scenario comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum ScenarioSource {
    /// A file.
    File(PathBuf),
    /// Standard input (a path `-` on the command line).
    StandardInput,
    /// A text the caller holds, its data paths relative to `folder`.
    Text {
        /// The scenario's JSON text.
        text: String,
        /// The folder relative data paths start from.
        folder: PathBuf,
    },
}

/// A scenario's text as read, with the name it takes when it gives none.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioText {
    /// The text, data files written in.
    pub text: String,
    /// The file's stem, or `scenario`.
    pub fallback_name: String,
}

/// Why a scenario cannot be read or used.
#[derive(Debug, Clone, PartialEq)]
pub enum SourceError {
    /// Its text (or a data file's) cannot be read: one line naming the file.
    Read(String),
    /// The scenario (or a data file it refers to) is not valid.
    Scenario(ScenarioError),
}

impl std::fmt::Display for SourceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SourceError::Read(message) => write!(f, "(file): {message}"),
            SourceError::Scenario(err) => write!(f, "{err}"),
        }
    }
}

impl std::error::Error for SourceError {}

impl ScenarioSource {
    /// The source a command line names: standard input for `-`, else the file.
    pub fn of_path(path: &Path) -> ScenarioSource {
        if path.as_os_str() == "-" {
            ScenarioSource::StandardInput
        } else {
            ScenarioSource::File(path.to_path_buf())
        }
    }

    /// The folder its relative data paths start from.
    pub fn folder(&self) -> PathBuf {
        match self {
            ScenarioSource::File(path) => scenario_folder(path),
            ScenarioSource::StandardInput => PathBuf::from("."),
            ScenarioSource::Text { folder, .. } => folder.clone(),
        }
    }

    /// The name a scenario without `name` takes: the file's stem, else `scenario`.
    pub fn fallback_name(&self) -> String {
        match self {
            ScenarioSource::File(path) => path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scenario".to_string()),
            _ => "scenario".to_string(),
        }
    }

    /// The text (each file within `limit`), data files written in.
    pub fn read(&self, limit: &ReadLimit) -> Result<ScenarioText, SourceError> {
        let text = match self {
            ScenarioSource::File(path) => read_text(path, limit).map_err(SourceError::Read)?,
            ScenarioSource::StandardInput => {
                read_standard_input(limit).map_err(SourceError::Read)?
            }
            ScenarioSource::Text { text, .. } => text.clone(),
        };
        let text = inline_data_files(&text, &self.folder(), limit)
            .map_err(SourceError::Scenario)?
            .into_owned();
        Ok(ScenarioText {
            text,
            fallback_name: self.fallback_name(),
        })
    }

    /// The validated scenario (its first problem the error) and its text.
    pub fn load(&self, limit: &ReadLimit) -> Result<(Scenario, ScenarioText), SourceError> {
        let text = self.read(limit)?;
        let scenario =
            Scenario::from_json(&text.text, &text.fallback_name).map_err(SourceError::Scenario)?;
        Ok((scenario, text))
    }

    /// The files a command on this scenario reads: the scenario's and the data files it
    /// refers to (none for standard input, which cannot be read twice, nor for a text).
    pub fn files(&self, limit: &ReadLimit) -> Vec<(&'static str, PathBuf)> {
        let ScenarioSource::File(path) = self else {
            return Vec::new();
        };
        let mut inputs = vec![("the scenario file", path.clone())];
        if let Ok(text) = read_text(path, limit) {
            inputs.extend(
                data_files(&text, &self.folder())
                    .into_iter()
                    .map(|file| ("a data file of the scenario", file)),
            );
        }
        inputs
    }
}

/// Reads and validates the scenario file at `path`, each file within
/// [`ReadLimit::library`] (the library's callers: tests, benches, scripts).
pub fn load(path: &Path) -> Result<Scenario, SourceError> {
    read(path).map(|(scenario, _)| scenario)
}

/// [`load`], with the scenario's text (data files written in).
pub fn read(path: &Path) -> Result<(Scenario, String), SourceError> {
    let source = ScenarioSource::File(path.to_path_buf());
    source
        .load(&ReadLimit::library())
        .map(|(scenario, text)| (scenario, text.text))
}

/// The folder a scenario file's relative data paths start from.
pub fn scenario_folder(path: &Path) -> PathBuf {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    }
}
