//! Where results go: report files and standard output.
//!
//! A report file is written as a user expects of the path they named:
//! - a regular file (new or existing) is replaced atomically: the text goes to a temporary
//!   file in the same directory, is synced, and is renamed over the path, so an interrupted
//!   run never leaves a half-written report; an existing file keeps its permission bits;
//! - a symbolic link is followed: its final target is written (replaced atomically when
//!   it is a regular file), the link itself stays;
//! - a character or block device or a FIFO (`/dev/null`, `/dev/stdout`, a named pipe) is
//!   written through, never replaced: renaming a file over a device would turn it into a
//!   regular file and break every program that uses it;
//! - a directory or a socket is an error naming the path;
//! - `-` is standard output.
//!
//! Before any work, [`check_targets`] refuses what could not be written or would destroy
//! something: a missing folder, a directory, a folder the process may not write in, an
//! output that is one of the command's inputs (the scenario, its data files, a baseline),
//! two outputs on one file, two on standard output, a name whose extension says another
//! format than the one written.
//!
//! A command with several outputs (`run --json --html --samples-out`, `merge`, `check`,
//! `allocate`, `curve`) stages them ([`StagedOutputs`]) and replaces them together only
//! once everything has succeeded: a command that fails replaces none of its outputs.
//!
//! Temporary files are named `.NAME.rvtol-tmp-PID`; one left by a killed run is removed by
//! the next write to the same path once its process is gone (checked through /proc where
//! there is one).
//!
//! Standard output: a closed pipe (`rvtol … | head`) ends the output quietly, as Unix tools
//! do; any other write error (a full disk) is an error of one line.

use std::ffi::OsString;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// Most symbolic links followed from a report path (as the kernel's own limit).
const MAX_LINKS: usize = 40;

/// Writes `contents` to `path` as the module documentation describes.
pub fn write_report(path: &Path, contents: &str) -> Result<()> {
    write_bytes(path, contents.as_bytes())
}

/// Writes `contents` to `path` as [`write_report`] does (a binary file: a shard's partial).
pub fn write_bytes(path: &Path, contents: &[u8]) -> Result<()> {
    let mut staged = StagedOutputs::new();
    staged.add_bytes(path, contents)?;
    staged.commit()
}

/// The outputs of one command, written together when it has succeeded: each file's text
/// goes to a temporary file beside it as soon as it is made ([`StagedOutputs::add`]), and
/// only [`StagedOutputs::commit`] renames them over their paths, one after the other with
/// nothing left that can fail for want of space, writes through to devices and FIFOs and
/// prints what goes to standard output. A command that fails before it commits (an error
/// returned with `?`, the staged outputs dropped) leaves every file it was pointed at as
/// it was: dropping removes the temporaries.
///
/// A command whose report explains its own failure (samples lost to non-finite values
/// beyond `--max-non-finite`) ends with [`StagedOutputs::print_only`]: standard output,
/// which replaces nothing, still shows the report; the files stay as they were.
#[derive(Default)]
pub struct StagedOutputs {
    pending: Vec<Pending>,
}

/// One output of a [`StagedOutputs`], waiting for the commit.
enum Pending {
    /// A regular file's new text, in `temporary` beside `target` (the path the user named
    /// with its links followed).
    Replace { temporary: PathBuf, target: PathBuf },
    /// A device or a FIFO, written through (it cannot be replaced, nor its writing staged).
    Through {
        path: PathBuf,
        shown: PathBuf,
        contents: Vec<u8>,
    },
    /// Standard output.
    Stdout(Vec<u8>),
}

impl StagedOutputs {
    /// Nothing staged yet.
    pub fn new() -> StagedOutputs {
        StagedOutputs::default()
    }

    /// Stages `contents` for `path` (`-`: standard output).
    pub fn add(&mut self, path: &Path, contents: &str) -> Result<()> {
        self.add_bytes(path, contents.as_bytes())
    }

    /// Stages text for standard output (a command's table).
    pub fn add_stdout(&mut self, text: &str) {
        self.pending.push(Pending::Stdout(text.as_bytes().to_vec()));
    }

    /// [`StagedOutputs::add`] for bytes: a regular file's temporary is written and synced
    /// now, so that a full disk or a folder that refuses it fails the command before any
    /// output is replaced.
    pub fn add_bytes(&mut self, path: &Path, contents: &[u8]) -> Result<()> {
        if is_stdout(path) {
            self.pending.push(Pending::Stdout(contents.to_vec()));
            return Ok(());
        }
        let through = |target: &Path| Pending::Through {
            path: target.to_path_buf(),
            shown: path.to_path_buf(),
            contents: contents.to_vec(),
        };
        // A path that ends on a device or FIFO through the kernel's own link resolution is
        // written through as it stands: `/dev/stdout` when standard output is a pipe links
        // to `/proc/self/fd/1`, whose link text (`pipe:[…]`) names no path to follow by
        // hand.
        if let Ok(metadata) = fs::metadata(path) {
            let kind = metadata.file_type();
            if !kind.is_file() && !kind.is_dir() && !is_socket(&kind) {
                self.pending.push(through(path));
                return Ok(());
            }
        }
        let target = resolve_links(path)?;
        let permissions = match fs::metadata(&target) {
            Ok(metadata) => {
                let kind = metadata.file_type();
                if kind.is_file() {
                    Some(metadata.permissions())
                } else if kind.is_dir() {
                    bail!("cannot write {}: it is a directory", path.display())
                } else if is_socket(&kind) {
                    bail!("cannot write {}: it is a socket", path.display())
                } else {
                    self.pending.push(through(&target));
                    return Ok(());
                }
            }
            Err(err) if err.kind() == io::ErrorKind::NotFound => None,
            Err(err) => {
                return Err(err).with_context(|| format!("cannot write {}", path.display()))
            }
        };
        let temporary = stage_file(&target, contents, permissions)?;
        // The same file staged twice (two spellings of one path): the last text wins, and
        // its temporary, of the same name, already holds it.
        self.pending.retain(
            |p| !matches!(p, Pending::Replace { temporary: other, .. } if *other == temporary),
        );
        self.pending.push(Pending::Replace { temporary, target });
        Ok(())
    }

    /// Replaces every staged file, writes to the devices and FIFOs, then prints what goes
    /// to standard output.
    pub fn commit(mut self) -> Result<()> {
        let pending = std::mem::take(&mut self.pending);
        let mut stdout = Vec::new();
        let mut through = Vec::new();
        let mut renames = Vec::new();
        for entry in pending {
            match entry {
                Pending::Replace { temporary, target } => renames.push((temporary, target)),
                Pending::Through {
                    path,
                    shown,
                    contents,
                } => through.push((path, shown, contents)),
                Pending::Stdout(contents) => stdout.push(contents),
            }
        }
        let mut failed = None;
        for (temporary, target) in &renames {
            if failed.is_some() {
                let _ = fs::remove_file(temporary);
                continue;
            }
            if let Err(err) = rename_into_place(temporary, target) {
                let _ = fs::remove_file(temporary);
                failed = Some(err);
            }
        }
        if let Some(err) = failed {
            return Err(err);
        }
        for (path, shown, contents) in through {
            write_through(&path, &contents)
                .with_context(|| format!("cannot write {}", shown.display()))?;
        }
        for contents in stdout {
            print_bytes(&contents)?;
        }
        Ok(())
    }

    /// The end of a command whose report explains its failure: what goes to standard
    /// output is printed, every file stays as it was (its temporary removed).
    pub fn print_only(mut self) -> Result<()> {
        let pending = std::mem::take(&mut self.pending);
        for entry in pending {
            match entry {
                Pending::Replace { temporary, .. } => {
                    let _ = fs::remove_file(temporary);
                }
                Pending::Through { .. } => {}
                Pending::Stdout(contents) => print_bytes(&contents)?,
            }
        }
        Ok(())
    }
}

impl Drop for StagedOutputs {
    /// A command that did not commit replaces nothing: its temporaries go.
    fn drop(&mut self) {
        for entry in &self.pending {
            if let Pending::Replace { temporary, .. } = entry {
                let _ = fs::remove_file(temporary);
            }
        }
    }
}

/// Whether `path` names standard output (`-`).
pub fn is_stdout(path: &Path) -> bool {
    path == Path::new("-")
}

/// Refuses, before any work, a report path that cannot be written: a directory, a path
/// whose folder does not exist, or a folder in which this process cannot create the
/// report's temporary file (tried, then removed). `-`, standard output, and an existing
/// device or FIFO (written through) always can be.
pub fn check_destination(path: &Path) -> Result<()> {
    if is_stdout(path) {
        return Ok(());
    }
    if let Ok(metadata) = fs::metadata(path) {
        if metadata.is_dir() {
            bail!("cannot write {}: it is a directory", path.display());
        }
        if !metadata.is_file() {
            return Ok(());
        }
    }
    let target = resolve_links(path)?;
    let (directory, name) = split(&target)?;
    match fs::metadata(&directory) {
        Ok(metadata) if metadata.is_dir() => {}
        Ok(_) => bail!(
            "cannot write {}: {} is not a folder",
            path.display(),
            directory.display()
        ),
        Err(err) => bail!(
            "cannot write {}: its folder {}: {err}",
            path.display(),
            directory.display()
        ),
    }
    // The report replaces the file through a temporary one beside it: the folder must
    // take a new file (permissions, a read-only or full file system, an immutable folder).
    let temporary = directory.join(format!("{}{}", temporary_prefix(&name), std::process::id()));
    match OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(&temporary)
    {
        Ok(file) => {
            drop(file);
            let _ = fs::remove_file(&temporary);
            Ok(())
        }
        Err(err) => bail!(
            "cannot write {}: its folder {} takes no new file: {err}",
            path.display(),
            directory.display()
        ),
    }
}

/// A file a command is asked to write, with the option that names it (for messages).
#[derive(Debug, Clone, Copy)]
pub struct OutputFile<'a> {
    /// The option, as typed: `--json`, `-o`.
    pub option: &'static str,
    pub path: &'a Path,
    /// What is written, which decides the names and whether `-` may take it.
    pub format: Format,
}

/// What an [`OutputFile`] receives, as far as its name is concerned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Format {
    /// JSON (a report, a scenario, a baseline, a fragment): any name but one of another
    /// format rvtol writes (`.html`, `.csv`, `.parquet`, `.xml`); `-` allowed.
    Json,
    /// JUnit XML: any name but `.json`, `.html`, `.csv`, `.parquet`; `-` allowed.
    Xml,
    /// An HTML page: `.html` or `.htm`; `-` allowed.
    Html,
    /// A sample table, CSV or Parquet as the name says: `.csv` or `.parquet`; `-` is CSV.
    Table,
    /// Binary (a shard's partial result): any name, not standard output.
    Binary,
}

impl Format {
    /// Why the name matters, for the message refusing another.
    fn what(self) -> &'static str {
        match self {
            Format::Html => "an HTML page is written there",
            Format::Table => "the extension chooses the format",
            Format::Json => "JSON is written there",
            Format::Xml => "JUnit XML is written there",
            Format::Binary => "",
        }
    }

    /// The extensions a name must end in (empty: any but [`Format::refused`]).
    fn extensions(self) -> &'static [&'static str] {
        match self {
            Format::Html => &["html", "htm"],
            Format::Table => &["csv", "parquet"],
            Format::Json | Format::Xml | Format::Binary => &[],
        }
    }

    /// The extensions of the other formats rvtol writes, which a name of this one may not
    /// end in.
    fn refused(self) -> &'static [&'static str] {
        match self {
            Format::Json => &["html", "htm", "csv", "parquet", "xml"],
            Format::Xml => &["json", "html", "htm", "csv", "parquet"],
            Format::Html | Format::Table | Format::Binary => &[],
        }
    }
}

/// A file a command reads, with what it is (for messages): "the scenario file".
pub type Input<'a> = (&'a str, &'a Path);

/// Refuses, before any work, outputs that cannot be written ([`check_destination`]) or
/// would destroy something: one of the command's inputs, another output's file, a second
/// claim on standard output, a name whose extension says another format. One line each,
/// naming the option.
pub fn check_targets(targets: &[OutputFile<'_>], inputs: &[Input<'_>]) -> Result<()> {
    let mut stdout_taken: Option<&str> = None;
    for (i, target) in targets.iter().enumerate() {
        let OutputFile {
            option,
            path,
            format,
        } = *target;
        if is_stdout(path) {
            if format == Format::Binary {
                bail!("{option}: '-' (standard output) cannot take a binary file: name a file");
            }
            if let Some(first) = stdout_taken {
                bail!(
                    "{option}: standard output ('-') already takes {first}: one output at most goes there"
                );
            }
            stdout_taken = Some(option);
            continue;
        }
        check_destination(path).map_err(|err| anyhow::anyhow!("{option}: {err}"))?;
        let regular = fs::metadata(path).map_or(true, |m| m.is_file());
        let extensions = format.extensions();
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        if regular && format.refused().contains(&extension.as_str()) {
            bail!(
                "{option}: {}: .{extension} names another format ({}): choose another name",
                path.display(),
                format.what()
            );
        }
        if regular && !extensions.is_empty() && !extensions.contains(&extension.as_str()) {
            bail!(
                "{option}: {}: name it {} ({})",
                path.display(),
                extensions
                    .iter()
                    .map(|e| format!(".{e}"))
                    .collect::<Vec<_>>()
                    .join(" or "),
                format.what()
            );
        }
        let Some(key) = file_key(path) else {
            continue;
        };
        if let Some((what, _)) = inputs
            .iter()
            .find(|(_, input)| file_key(input).as_ref() == Some(&key))
        {
            bail!(
                "{option}: {} is {what}, which this command reads: writing there would destroy it; name another file",
                path.display()
            );
        }
        if let Some(other) = targets[..i]
            .iter()
            .find(|other| !is_stdout(other.path) && file_key(other.path).as_ref() == Some(&key))
        {
            bail!(
                "{option}: {} is also the file of {}: give each output its own file",
                path.display(),
                other.option
            );
        }
    }
    Ok(())
}

/// What makes two paths one file, for the checks of [`check_targets`]: an existing
/// regular file's device and inode (links and other spellings included; elsewhere its
/// canonical path), a new file's folder (resolved) and name. Devices and FIFOs have none:
/// they are written through, and several outputs may share `/dev/null`.
#[derive(Debug, PartialEq)]
enum FileKey {
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

fn file_key(path: &Path) -> Option<FileKey> {
    match fs::metadata(path) {
        Ok(metadata) if metadata.is_file() => Some(inode_key(path, &metadata)),
        Ok(_) => None,
        Err(_) => {
            let target = resolve_links(path).ok()?;
            let (directory, name) = split(&target).ok()?;
            let directory = fs::canonicalize(directory).ok()?;
            Some(FileKey::Path(directory.join(name)))
        }
    }
}

#[cfg(unix)]
fn inode_key(_path: &Path, metadata: &fs::Metadata) -> FileKey {
    use std::os::unix::fs::MetadataExt;
    FileKey::Inode(metadata.dev(), metadata.ino())
}

#[cfg(not(unix))]
fn inode_key(path: &Path, _metadata: &fs::Metadata) -> FileKey {
    FileKey::Path(fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()))
}

#[cfg(unix)]
fn is_socket(kind: &fs::FileType) -> bool {
    use std::os::unix::fs::FileTypeExt;
    kind.is_socket()
}

#[cfg(not(unix))]
fn is_socket(_kind: &fs::FileType) -> bool {
    false
}

/// The path a report named `path` lands on: `path` itself, or the final target of the
/// symbolic links it names (a dangling link's target is created).
fn resolve_links(path: &Path) -> Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match fs::symlink_metadata(&current) {
            Ok(metadata) if metadata.file_type().is_symlink() => {
                let link = fs::read_link(&current)
                    .with_context(|| format!("cannot read the link {}", current.display()))?;
                current = match current.parent() {
                    Some(parent) if link.is_relative() => parent.join(link),
                    _ => link,
                };
            }
            _ => return Ok(current),
        }
    }
    bail!(
        "cannot write {}: more than {MAX_LINKS} symbolic links",
        path.display()
    )
}

/// Writes into an existing device or FIFO without creating, replacing or syncing it.
fn write_through(path: &Path, contents: &[u8]) -> io::Result<()> {
    let mut file = OpenOptions::new().write(true).open(path)?;
    file.write_all(contents)?;
    file.flush()
}

/// The directory and file name of `path`.
fn split(path: &Path) -> Result<(PathBuf, OsString)> {
    let directory = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?
        .to_os_string();
    Ok((directory, name))
}

/// The prefix of the temporary files of reports named `name`.
fn temporary_prefix(name: &OsString) -> String {
    format!(".{}.rvtol-tmp-", name.to_string_lossy())
}

/// Writes `contents` into the temporary file that will replace (or create) the regular
/// file `path` ([`rename_into_place`]), synced; it gets `permissions` when given (those of
/// the file it replaces). Its path, or the error (nothing left behind).
fn stage_file(
    path: &Path,
    contents: &[u8],
    permissions: Option<fs::Permissions>,
) -> Result<PathBuf> {
    let (directory, name) = split(path)?;
    remove_stale_temporaries(&directory, &name);
    let temporary = directory.join(format!("{}{}", temporary_prefix(&name), std::process::id()));
    let result = (|| -> io::Result<()> {
        let mut file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(&temporary)?;
        if let Some(permissions) = permissions {
            file.set_permissions(permissions)?;
        }
        file.write_all(contents)?;
        file.sync_all()
    })();
    match result {
        Ok(()) => Ok(temporary),
        Err(err) => {
            let _ = fs::remove_file(&temporary);
            Err(err).with_context(|| format!("cannot write {}", path.display()))
        }
    }
}

/// Renames the staged `temporary` over `path`, and makes the rename durable (a directory
/// that cannot be synced is no error).
fn rename_into_place(temporary: &Path, path: &Path) -> Result<()> {
    fs::rename(temporary, path).with_context(|| format!("cannot write {}", path.display()))?;
    if let Ok(dir) = File::open(split(path)?.0) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// Removes temporary files of earlier writes to `name` in `directory` whose process is
/// gone (a run killed between creating and renaming). Only where /proc tells which
/// processes live; elsewhere they stay (and a later write of the same process id reuses
/// the name).
fn remove_stale_temporaries(directory: &Path, name: &OsString) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let prefix = temporary_prefix(name);
    let Ok(entries) = fs::read_dir(directory) else {
        return;
    };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pid) = file_name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .and_then(|pid| pid.parse::<u32>().ok())
        else {
            continue;
        };
        let alive = Path::new(&format!("/proc/{pid}")).exists();
        if !alive && entry.file_type().is_ok_and(|t| t.is_file()) {
            let _ = fs::remove_file(entry.path());
        }
    }
}

/// Writes `text` to standard output: a closed pipe ends the output quietly (the reader has
/// what it wanted), any other failure is an error.
pub fn print(text: &str) -> Result<()> {
    print_bytes(text.as_bytes())
}

/// [`print`] for bytes.
fn print_bytes(contents: &[u8]) -> Result<()> {
    let mut stdout = io::stdout().lock();
    match stdout.write_all(contents).and_then(|()| stdout.flush()) {
        Err(err) if err.kind() == io::ErrorKind::BrokenPipe => Ok(()),
        other => other.context("cannot write to standard output"),
    }
}

/// Writes a line to standard error, ignoring failure (there is nowhere left to report it).
pub fn note(line: &str) {
    let _ = writeln!(io::stderr().lock(), "{line}");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("rvtol-output-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_stale_temporary_of_a_dead_process_is_removed() {
        let dir = scratch("stale");
        let target = dir.join("report.json");
        // No process has id 0 in /proc; a temporary "left" by it is stale.
        let stale = dir.join(".report.json.rvtol-tmp-0");
        fs::write(&stale, "half").unwrap();
        let other = dir.join(".other.json.rvtol-tmp-0");
        fs::write(&other, "not ours").unwrap();
        write_report(&target, "{}\n").unwrap();
        assert_eq!(fs::read_to_string(&target).unwrap(), "{}\n");
        assert_eq!(stale.exists(), !Path::new("/proc/self").exists());
        assert!(
            other.exists(),
            "a temporary of another report is left alone"
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn staged_outputs_replace_all_their_files_on_commit_and_none_when_dropped() {
        let dir = scratch("staged");
        let (a, b) = (dir.join("a.json"), dir.join("b.html"));
        fs::write(&a, "old a").unwrap();
        fs::write(&b, "old b").unwrap();
        let mut staged = StagedOutputs::new();
        staged.add(&a, "new a").unwrap();
        staged.add(&b, "new b").unwrap();
        assert_eq!(
            fs::read_to_string(&a).unwrap(),
            "old a",
            "nothing before the commit"
        );
        drop(staged);
        assert_eq!(fs::read_to_string(&a).unwrap(), "old a");
        assert_eq!(fs::read_to_string(&b).unwrap(), "old b");
        let names = |dir: &Path| -> Vec<String> {
            let mut names: Vec<String> = fs::read_dir(dir)
                .unwrap()
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect();
            names.sort();
            names
        };
        assert_eq!(names(&dir), ["a.json", "b.html"], "no temporary left");
        let mut staged = StagedOutputs::new();
        staged.add(&a, "new a").unwrap();
        staged.add(&b, "new b").unwrap();
        staged.commit().unwrap();
        assert_eq!(fs::read_to_string(&a).unwrap(), "new a");
        assert_eq!(fs::read_to_string(&b).unwrap(), "new b");
        assert_eq!(names(&dir), ["a.json", "b.html"]);
        let mut staged = StagedOutputs::new();
        staged.add(&a, "newer a").unwrap();
        staged.print_only().unwrap();
        assert_eq!(fs::read_to_string(&a).unwrap(), "new a");
        assert_eq!(names(&dir), ["a.json", "b.html"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_directory_is_an_error() {
        let dir = scratch("dir");
        let err = write_report(&dir, "x").unwrap_err();
        assert_eq!(
            err.to_string(),
            format!("cannot write {}: it is a directory", dir.display())
        );
        fs::remove_dir_all(&dir).unwrap();
    }
}
