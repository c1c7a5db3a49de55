//! Reading a file ftsmc did not write — a shard's `summary.json`,
//! `scenario.toml` or `runs.csv` given to `ftsmc merge`, a result folder's
//! manifest — only when it is a regular file of at most a stated size.
//!
//! The file is opened without blocking (`O_NONBLOCK` on Unix: opening a
//! FIFO for reading then returns at once instead of waiting for a writer),
//! its type and size are checked on the open file (`fstat`, so it cannot
//! be swapped between the check and the read), and at most `limit + 1`
//! bytes are read, so a FIFO, a device such as `/dev/zero`, a directory, a
//! file over the limit or one that grows while being read is refused
//! without reading more than the limit.

use std::io::Read as _;
use std::path::Path;

use anyhow::{bail, Context, Result};

/// Largest `runs.csv` of one shard `ftsmc merge` reads: 1 GiB (about
/// 700,000 rows of ~1.5 KB; split the campaign into more shards to stay
/// below it).
pub const MAX_RUNS_CSV_BYTES: u64 = 1 << 30;

/// Largest `summary.json` or `scenario.toml` of a shard `ftsmc merge`
/// reads: 16 MiB (a shard's are a few KiB).
pub const MAX_SHARD_TEXT_BYTES: u64 = 16 << 20;

/// Largest result-folder manifest (`.ftsmc-<command>.manifest`) read: 16
/// MiB (about 130,000 files).
pub const MAX_MANIFEST_BYTES: u64 = 16 << 20;

/// The bytes of `path`, which must be a regular file of at most `limit`
/// bytes; `what` names it in errors (`shard `s1`: runs.csv`).
pub fn read_limited(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt as _;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).with_context(|| format!("{what}: cannot open {}", path.display()))?;
    let meta = file.metadata().with_context(|| format!("{what}: cannot read the metadata of {}", path.display()))?;
    if !meta.is_file() {
        let kind = if meta.is_dir() { "a directory" } else { "a device, FIFO or socket" };
        bail!("{what}: {} is {kind}, not a regular file", path.display());
    }
    let too_big = |len: u64| {
        anyhow::anyhow!("{what}: {} is larger than the limit of {limit} bytes ({len} bytes or more)", path.display())
    };
    if meta.len() > limit {
        return Err(too_big(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .with_context(|| format!("{what}: cannot read {}", path.display()))?;
    if bytes.len() as u64 > limit {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_within_the_limit_are_read() {
        let tmp = tempfile::tempdir().unwrap();
        let file = tmp.path().join("a.csv");
        std::fs::write(&file, "0123456789").unwrap();
        assert_eq!(read_limited(&file, 10, "a").unwrap(), b"0123456789");
        let err = read_limited(&file, 9, "shard `s`: runs.csv").unwrap_err().to_string();
        assert!(err.starts_with("shard `s`: runs.csv: ") && err.contains("limit of 9 bytes"), "{err}");
        let err = read_limited(tmp.path(), 10, "x").unwrap_err().to_string();
        assert!(err.contains("a directory"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_and_a_device_are_refused_without_blocking() {
        let tmp = tempfile::tempdir().unwrap();
        let fifo = tmp.path().join("fifo");
        let c_path = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo only creates a file.
        assert_eq!(unsafe { libc::mkfifo(c_path.as_ptr(), 0o600) }, 0);
        let err = read_limited(&fifo, 10, "m").unwrap_err().to_string();
        assert!(err.contains("not a regular file"), "{err}");
        let err = read_limited(Path::new("/dev/zero"), 10, "m").unwrap_err().to_string();
        assert!(err.contains("not a regular file"), "{err}");
    }
}
