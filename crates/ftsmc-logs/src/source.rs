//! Opening a log: only a regular file of at most a stated size, read as a
//! stream through a counting reader (so errors can name the byte offset).
//! The size limit is checked on the file's metadata and again on the bytes
//! read, in case the file grows.
//!
//! The file is opened without blocking (`O_NONBLOCK` on Unix: opening a FIFO
//! for reading returns at once instead of waiting for a writer), its type and
//! size are checked on the open file (`fstat`, so it cannot be swapped
//! between the check and the read), and at most `limit + 1` bytes are ever
//! read, so a file that grows while being read is refused too.

use std::cell::Cell;
use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::Path;
use std::rc::Rc;

use crate::error::LogError;

/// Limits of every reader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogLimits {
    /// Largest file read, bytes. Default 256 MiB: a PX4 log of an hour at
    /// the default logging profile is about 100–200 MB; a NanoBench flight
    /// is about 3 MB. The decoded columns of one topic take at most 8 bytes
    /// per byte of the file (a `uint8` field becomes an `f64`).
    pub max_file_bytes: u64,
}

impl Default for LogLimits {
    fn default() -> Self {
        Self { max_file_bytes: 256 << 20 }
    }
}

/// The number of bytes read so far, shared with the reader that counts them.
#[derive(Clone, Debug, Default)]
pub(crate) struct Offset(Rc<Cell<u64>>);

impl Offset {
    /// Bytes read so far.
    pub(crate) fn get(&self) -> u64 {
        self.0.get()
    }
}

/// A reader that counts its bytes and refuses to pass `limit`.
#[derive(Debug)]
pub(crate) struct Counted<R> {
    inner: R,
    read: Offset,
    limit: u64,
}

impl<R: std::io::BufRead> std::io::BufRead for Counted<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        self.inner.fill_buf()
    }

    fn consume(&mut self, amount: usize) {
        self.inner.consume(amount);
        let total = self.read.get() + amount as u64;
        self.read.0.set(total);
    }
}

impl<R: Read> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        let total = self.read.get() + n as u64;
        self.read.0.set(total);
        if total > self.limit {
            return Err(io::Error::other(GrewPastLimit));
        }
        Ok(n)
    }
}

/// The marker of the error a [`Counted`] reader returns past its limit.
#[derive(Debug)]
pub(crate) struct GrewPastLimit;

impl std::fmt::Display for GrewPastLimit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("the file grew past the size limit while being read")
    }
}

impl std::error::Error for GrewPastLimit {}

/// An open log: the buffered, counting reader and what it was opened with.
#[derive(Debug)]
pub(crate) struct Opened {
    /// The path as given, for error messages.
    pub(crate) file: String,
    /// The file's bytes, buffered, counted as they are consumed.
    pub(crate) reader: Counted<BufReader<File>>,
    /// Bytes read so far.
    pub(crate) offset: Offset,
    /// The size limit it was opened with, bytes.
    pub(crate) limit: u64,
}

impl Opened {
    /// The error of a failed read: the size limit, the end of the file
    /// inside a record (`Truncated`), or another I/O error.
    pub(crate) fn io_error(&self, err: io::Error) -> LogError {
        let file = self.file.clone();
        if err.get_ref().is_some_and(|e| e.is::<GrewPastLimit>()) {
            return LogError::TooLarge { file, size: self.offset.get(), limit: self.limit };
        }
        if err.kind() == io::ErrorKind::UnexpectedEof {
            return LogError::Truncated { file, offset: self.offset.get() };
        }
        LogError::Read { file, source: err }
    }
}

/// Opens `path` for reading if it is a regular file of at most
/// `limits.max_file_bytes` bytes.
pub(crate) fn open(path: &Path, limits: &LogLimits) -> Result<Opened, LogError> {
    let file = path.display().to_string();
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt as _;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let handle = options.open(path).map_err(|source| LogError::Open { file: file.clone(), source })?;
    let meta = handle.metadata().map_err(|source| LogError::Open { file: file.clone(), source })?;
    if !meta.is_file() {
        let kind = if meta.is_dir() { "a directory" } else { "a FIFO, socket or device" };
        return Err(LogError::NotRegularFile { file, kind });
    }
    let limit = limits.max_file_bytes;
    if meta.len() > limit {
        return Err(LogError::TooLarge { file, size: meta.len(), limit });
    }
    let offset = Offset::default();
    // The limit is enforced on the bytes consumed; the buffer reads at most
    // its capacity past it.
    let reader = Counted { inner: BufReader::with_capacity(64 << 10, handle), read: offset.clone(), limit };
    Ok(Opened { file, reader, offset, limit })
}
