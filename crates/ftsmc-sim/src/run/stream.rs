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
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};

use super::recording::{write_header, CsvRows};

/// Recorded rows per chunk handed to the formatter thread (about 0.5 MB
/// of numbers for the widest recording; a 100 Hz recording hands one over
/// every ~10 s of flight).
pub const STREAM_CHUNK_ROWS: usize = 1024;

/// Chunks that may wait for the formatter: beyond them the flight waits
/// (memory stays bounded should the writer be slow).
const QUEUED_CHUNKS: usize = 4;

/// What a recorder hands to the formatter thread, in order: the header,
/// rows, and the end once every row was handed over.
pub(super) enum Message {
    /// The column names (none when the flight does not record).
    Header(Vec<String>),
    /// The next rows of the recording, column by column.
    Rows(Vec<Vec<f64>>),
    /// The flight ended and every row was handed over.
    End,
}

/// The formatter thread's end of a recording streamed as CSV: put it in
/// [`RunOptions::stream`](super::RunOptions::stream) of the one flight
/// whose recording it writes ([`stream_csv`]).
#[derive(Clone, Debug)]
pub struct RowStream {
    tx: SyncSender<Message>,
    rows: usize,
}

impl RowStream {
    /// Rows per chunk.
    pub(super) fn chunk_rows(&self) -> usize {
        self.rows
    }

    /// Hand `message` over (waiting while [`QUEUED_CHUNKS`] wait). False
    /// when the formatter thread stopped (its writer failed): nothing
    /// more need be sent.
    pub(super) fn send(&self, message: Message) -> bool {
        self.tx.send(message).is_ok()
    }
}

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
        let stream = RowStream { tx, rows: chunk_rows };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::{RunOptions, RunOutput};
    use crate::scenario::Scenario;

    /// Paper scenario 2 for `duration` s, recorded at 100 Hz.
    fn scenario(duration: f64) -> Scenario {
        let mut s = Scenario::paper_scenarios().remove(1);
        s.duration = duration;
        s.simulation.record_rate = 100.0;
        s
    }

    /// Fly FTAFTSMC with its CSV streamed into `out` by chunks of `rows`.
    fn streamed<W: Write + Send + ?Sized>(
        s: &Scenario,
        record: bool,
        rows: usize,
        out: &mut W,
    ) -> (RunOutput, std::io::Result<()>) {
        stream_csv(out, rows, |stream| {
            let options = RunOptions { record, stream: Some(stream), ..Default::default() };
            crate::registry::run_as("ftaftsmc", "ftaftsmc", s, options).unwrap()
        })
    }

    /// The streamed CSV is the recording's `write_csv`, byte for byte,
    /// whatever the chunk: one row, a chunk that divides the rows exactly
    /// (300 = 4 × 75), one that does not (43), exactly the rows, more rows than
    /// the flight has; and a flight that does not record streams what
    /// `write_csv` writes of its empty recording.
    #[test]
    fn streamed_csv_is_write_csv_byte_for_byte() {
        let s = scenario(3.0);
        let mut whole = None;
        for rows in [1, 43, 75, 300, STREAM_CHUNK_ROWS, 1 << 20] {
            let mut out = Vec::new();
            let (run, written) = streamed(&s, true, rows, &mut out);
            written.unwrap();
            assert_eq!(run.recording.len(), 300);
            let csv = run.recording.to_csv();
            assert!(out == csv, "chunks of {rows} rows: the streamed CSV differs");
            // The recording itself does not depend on the streaming.
            let whole = whole.get_or_insert_with(|| csv.clone());
            assert!(*whole == csv, "chunks of {rows} rows changed the recording");
        }
        let plain = crate::registry::run_as("ftaftsmc", "ftaftsmc", &s, RunOptions::default()).unwrap();
        assert!(
            plain.recording.to_csv() == *whole.as_ref().unwrap(),
            "a streamed flight records what a plain one does"
        );

        let mut out = Vec::new();
        let (run, written) = streamed(&s, false, 7, &mut out);
        written.unwrap();
        assert!(run.recording.is_empty());
        assert_eq!(out, run.recording.to_csv());
        assert_eq!(out, b"\n");
    }

    /// A writer that fails once it was given `room` bytes.
    struct Failing {
        room: usize,
    }

    impl Write for Failing {
        fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
            if self.room == 0 {
                return Err(std::io::Error::other("disk full"));
            }
            let n = bytes.len().min(self.room);
            self.room -= n;
            Ok(n)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// A failing writer's error is returned (at the header, in the rows,
    /// at the last chunk), and the flight still completes.
    #[test]
    fn a_writer_error_is_returned() {
        let s = scenario(3.0);
        let size = streamed(&s, true, 43, &mut Vec::new()).0.recording.to_csv().len();
        for room in [0, 10, size / 2, size - 1] {
            let (run, written) = streamed(&s, true, 43, &mut Failing { room });
            let err = written.expect_err("the writer's error");
            assert_eq!(err.to_string(), "disk full", "room {room}");
            assert!(run.exit.is_completed() && run.recording.len() == 300, "room {room}");
        }
        streamed(&s, true, 43, &mut Failing { room: size }).1.unwrap();
    }

    /// A stream no flight used, or one two flights used, is an error, not
    /// a CSV that looks whole.
    #[test]
    fn a_stream_without_one_whole_flight_is_an_error() {
        let s = scenario(0.5);
        let (_, written) = stream_csv(&mut Vec::new(), 8, |_| ());
        assert_eq!(written.unwrap_err().kind(), std::io::ErrorKind::InvalidData);
        let (_, written) = stream_csv(&mut Vec::new(), 8, |stream| {
            for _ in 0..2 {
                let options = RunOptions { stream: Some(stream), ..Default::default() };
                crate::registry::run_as("ftaftsmc", "ftaftsmc", &s, options).unwrap();
            }
        });
        assert_eq!(written.unwrap_err().kind(), std::io::ErrorKind::InvalidData);
    }
}
