//! Every file rvtol reads whole goes through here, within a bound: scenarios and the data
//! columns they refer to, CSV tables, reports, baselines and shard files. A file that is
//! no regular file and no pipe (a character device such as a copy of /dev/zero, a block
//! device, a socket, a folder) is refused before it is read, a regular file larger than
//! the bound before it is read, and a pipe or standard input once it gives more than the
//! bound; each refusal is one line naming the file. Nothing else reads a file whole.

use std::io::Read;
use std::path::Path;

use rvtol_deviation::human_bytes;

/// The bound of a library caller that has no memory allowance of its own (the engine's
/// [`super::scenario`]'s sources, the Python module): 1 GiB.
pub const LIBRARY_READ_LIMIT: u64 = 1 << 30;

/// The most bytes a file read whole may have, and what sets that bound (for the message
/// that refuses a larger file, with the way around it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReadLimit {
    /// Bytes.
    pub bytes: u64,
    /// What the bound is, in words ("a quarter of the 1.0 GB of memory available
    /// (--max-memory)").
    pub source: String,
}

impl ReadLimit {
    /// The bound of a library caller ([`LIBRARY_READ_LIMIT`]).
    pub fn library() -> ReadLimit {
        ReadLimit {
            bytes: LIBRARY_READ_LIMIT,
            source: "the bound of a file read whole".to_string(),
        }
    }

    /// The part of this bound left after `used` bytes.
    pub fn less(&self, used: u64) -> ReadLimit {
        ReadLimit {
            bytes: self.bytes.saturating_sub(used),
            source: self.source.clone(),
        }
    }

    /// The one line refusing `path`, of `size` bytes (at least, for a pipe).
    fn refusal(&self, path: &Path, size: u64, at_least: bool) -> String {
        format!(
            "{}: {}{}, more than the {} a file may have here ({})",
            path.display(),
            if at_least { "more than " } else { "" },
            human_bytes(size as f64),
            human_bytes(self.bytes as f64),
            self.source
        )
    }
}

/// What a file that cannot be read whole is, in words, or `None` for a regular file or a
/// pipe.
fn unreadable_kind(file_type: std::fs::FileType) -> Option<&'static str> {
    if file_type.is_file() {
        return None;
    }
    if file_type.is_dir() {
        return Some("a folder");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if file_type.is_fifo() {
            return None;
        }
        if file_type.is_char_device() {
            return Some("a character device");
        }
        if file_type.is_block_device() {
            return Some("a block device");
        }
        if file_type.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

/// Reads at most `limit` bytes of `reader` (`expected` bytes, when known, reserved at
/// once); `Err(read)` with the bytes read so far when it gives more.
fn read_within(
    reader: impl Read,
    limit: u64,
    expected: Option<u64>,
) -> std::io::Result<Result<Vec<u8>, u64>> {
    let mut bytes = Vec::with_capacity(expected.unwrap_or(0).min(limit) as usize);
    reader
        .take(limit.saturating_add(1))
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        Ok(Err(bytes.len() as u64 - 1))
    } else {
        Ok(Ok(bytes))
    }
}

/// The bytes of the file at `path` (symbolic links followed), at most `limit.bytes`; one
/// line naming the file when it cannot be read, is no regular file nor a pipe, or is
/// larger.
pub fn read_bytes(path: &Path, limit: &ReadLimit) -> Result<Vec<u8>, String> {
    let cannot = |err: std::io::Error| format!("{}: cannot read: {err}", path.display());
    let metadata = std::fs::metadata(path).map_err(cannot)?;
    if let Some(kind) = unreadable_kind(metadata.file_type()) {
        return Err(format!(
            "{}: cannot read: {kind}, not a regular file (rvtol reads its inputs whole from regular files, or from a pipe)",
            path.display()
        ));
    }
    let regular = metadata.is_file();
    if regular && metadata.len() > limit.bytes {
        return Err(limit.refusal(path, metadata.len(), false));
    }
    let file = std::fs::File::open(path).map_err(cannot)?;
    let expected = regular.then_some(metadata.len());
    match read_within(file, limit.bytes, expected).map_err(cannot)? {
        Ok(bytes) => Ok(bytes),
        Err(read) => Err(limit.refusal(path, read, true)),
    }
}

/// UTF-8 text, or one line naming `shown` and the first byte that is not.
fn text_of(bytes: Vec<u8>, shown: &str) -> Result<String, String> {
    String::from_utf8(bytes).map_err(|err| {
        format!(
            "{shown}: cannot read: not UTF-8 text (byte {} is not)",
            err.utf8_error().valid_up_to()
        )
    })
}

/// The text of the file at `path`, as [`read_bytes`]; it must be UTF-8.
pub fn read_text(path: &Path, limit: &ReadLimit) -> Result<String, String> {
    text_of(read_bytes(path, limit)?, &path.display().to_string())
}

/// The text of standard input, at most `limit.bytes`; one line naming standard input
/// otherwise.
pub fn read_standard_input(limit: &ReadLimit) -> Result<String, String> {
    text_of(read_standard_input_bytes(limit)?, "standard input")
}

/// The bytes of standard input, at most `limit.bytes`; one line naming standard input
/// otherwise.
pub fn read_standard_input_bytes(limit: &ReadLimit) -> Result<Vec<u8>, String> {
    let shown = Path::new("standard input");
    let stdin = std::io::stdin().lock();
    match read_within(stdin, limit.bytes, None)
        .map_err(|err| format!("standard input: cannot read: {err}"))?
    {
        Ok(bytes) => Ok(bytes),
        Err(read) => Err(limit.refusal(shown, read, true)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("rvtol-input-file-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch folder");
        dir
    }

    fn limit(bytes: u64) -> ReadLimit {
        ReadLimit {
            bytes,
            source: "the test's bound".to_string(),
        }
    }

    #[test]
    fn a_regular_file_is_read_up_to_the_bound() {
        let dir = scratch("regular");
        let path = dir.join("a.json");
        std::fs::write(&path, "{\"a\": 1}").expect("write");
        assert_eq!(read_text(&path, &limit(8)).as_deref(), Ok("{\"a\": 1}"));
        let err = read_text(&path, &limit(7)).unwrap_err();
        assert_eq!(
            err,
            format!(
                "{}: 8 B, more than the 7 B a file may have here (the test's bound)",
                path.display()
            )
        );
        std::fs::write(&path, [b'a', 0xff, b'b']).expect("write");
        assert!(read_text(&path, &limit(8))
            .unwrap_err()
            .ends_with(": cannot read: not UTF-8 text (byte 1 is not)"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_device_or_a_folder_is_refused_before_it_is_read() {
        // /dev/zero never ends: read whole, it takes all memory.
        let err = read_bytes(Path::new("/dev/zero"), &limit(u64::MAX)).unwrap_err();
        assert_eq!(
            err,
            "/dev/zero: cannot read: a character device, not a regular file (rvtol reads its inputs whole from regular files, or from a pipe)"
        );
        let dir = scratch("folder");
        let err = read_bytes(&dir, &limit(u64::MAX)).unwrap_err();
        assert!(
            err.contains(": cannot read: a folder, not a regular file"),
            "{err}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_stream_is_cut_at_the_bound() {
        let endless = std::io::repeat(b'x');
        assert_eq!(read_within(endless, 1000, None).unwrap(), Err(1000));
        assert_eq!(
            read_within(&b"abc"[..], 3, Some(3)).unwrap(),
            Ok(b"abc".to_vec())
        );
        assert_eq!(limit(10).less(4).bytes, 6);
        assert_eq!(limit(10).less(40).bytes, 0);
    }
}
