//! A recording's CSV written while the flight flies ([`stream_csv`]): the
//! flight's recorder hands its rows over in chunks of
//! [`STREAM_CHUNK_ROWS`] to a formatter thread, which formats them into
//! the writer as [`Recording::write_csv`] would (the same bytes, whatever
//! the threads' timing: chunks go in order and each number is formatted
//! alone). A flight runs on one core; this puts the formatting, and the
//! writing and hashing behind the writer, on another.
//!
//! [`Recording::write_csv`]: super::Recording::write_csv

use std::io::Write;
use std::sync::mpsc::{sync_channel, Receiver};

use super::recording::{write_header, CsvRows, Message, RowStream};

/// Recorded rows per chunk handed to the formatter thread (about 0.5 MB
/// of numbers for the widest recording; a 100 Hz recording hands one over
/// every ~10 s of flight).
pub const STREAM_CHUNK_ROWS: usize = 1024;

/// Chunks that may wait for the formatter: beyond them the flight waits
/// (memory stays bounded should the writer be slow).
const QUEUED_CHUNKS: usize = 4;

/// Fly with the recording's CSV streamed into `out`: `fly` gets the
/// [`RowStream`] to put in the [`RunOptions`](super::RunOptions) of one
/// flight, which hands its rows over every `chunk_rows` recorded rows while
/// a formatter thread writes them to `out`. Returns what `fly` returned and
/// whether the CSV was written whole: `out` then holds exactly the bytes
/// [`Recording::write_csv`](super::Recording::write_csv) writes of that
/// flight's recording.
///
/// # Errors
/// The first error of `out` (the flight still flies to its end), or
/// [`std::io::ErrorKind::InvalidData`] when the stream did not carry one
/// whole flight (no flight used it, two did, or the flight was dropped
/// before its end). Either way `out` holds an incomplete CSV.
///
/// # Panics
/// If `chunk_rows` is 0; a panic of the formatter thread is resumed here.
pub fn stream_csv<W, T>(out: &mut W, chunk_rows: usize, fly: impl FnOnce(&RowStream) -> T) -> (T, std::io::Result<()>)
where
    W: Write + Send + ?Sized,
{
    assert!(chunk_rows > 0, "a chunk holds at least one row");
    let (tx, rx) = sync_channel(QUEUED_CHUNKS);
    std::thread::scope(|scope| {
        let formatter = scope.spawn(move || format_stream(rx, out));
        let stream = RowStream::new(tx, chunk_rows);
        let flown = fly(&stream);
        // The formatter ends once every sender (this one, the recorder's) is gone.
        drop(stream);
        let written = formatter.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (flown, written)
    })
}

/// The formatter thread: each message into `out` until the stream's end.
fn format_stream<W: Write + ?Sized>(rx: Receiver<Message>, out: &mut W) -> std::io::Result<()> {
    let broken = |why: &str| Err(std::io::Error::new(std::io::ErrorKind::InvalidData, why.to_string()));
    let mut rows: Option<CsvRows> = None;
    let mut ended = false;
    for message in rx {
        match (message, &mut rows, ended) {
            (Message::Header(names), None, false) => {
                write_header(&names, out)?;
                rows = Some(CsvRows::new(names.len()));
            }
            (Message::Rows(columns), Some(formatter), false) => formatter.write(&columns, out)?,
            (Message::End, Some(formatter), false) => {
                formatter.flush(out)?;
                ended = true;
            }
            _ => return broken("a streamed recording must be one flight's header, rows and end"),
        }
    }
    if ended {
        Ok(())
    } else {
        broken("the streamed flight ended without handing over all of its rows")
    }
}
