//! A recording's CSV written while its flight flies (`run::stream_csv`)
//! is `Recording::write_csv`'s, byte for byte, and its writer's errors are
//! returned.

use std::io::Write;

use ftsmc_sim::registry::run_as;
use ftsmc_sim::run::{stream_csv, RunOptions, RunOutput, STREAM_CHUNK_ROWS};
use ftsmc_sim::scenario::Scenario;

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
        run_as("ftaftsmc", "ftaftsmc", s, options).unwrap()
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
    let plain = run_as("ftaftsmc", "ftaftsmc", &s, RunOptions::default()).unwrap();
    assert!(plain.recording.to_csv() == *whole.as_ref().unwrap(), "a streamed flight records what a plain one does");

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
            run_as("ftaftsmc", "ftaftsmc", &s, options).unwrap();
        }
    });
    assert_eq!(written.unwrap_err().kind(), std::io::ErrorKind::InvalidData);
}
