//! The recorded time series: [`Recording`] and its columns.

use std::sync::mpsc::SyncSender;

use ftsmc_core::cascade::Controller;
use ftsmc_core::law::MAX_ESTIMATES;

use crate::scenario::Scenario;

use super::observer::{Observer, Tick};

pub use crate::limits::MAX_RECORDING_COLUMNS;

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

/// The recorder's end of a recording streamed as CSV: put it in
/// [`RunOptions::stream`](super::RunOptions::stream) of the one flight
/// whose recording it writes ([`stream_csv`](super::stream_csv)); the
/// recorder hands its rows over through it (`run/stream.rs` formats them).
#[derive(Clone, Debug)]
pub struct RowStream {
    tx: SyncSender<Message>,
    rows: usize,
}

impl RowStream {
    /// The sending end of a stream of `rows`-row chunks ([`stream_csv`](super::stream_csv)).
    pub(super) fn new(tx: SyncSender<Message>, rows: usize) -> Self {
        Self { tx, rows }
    }

    /// Rows per chunk.
    pub(super) fn chunk_rows(&self) -> usize {
        self.rows
    }

    /// Hand `message` over (waiting while the channel is full). False
    /// when the formatter thread stopped (its writer failed): nothing
    /// more need be sent.
    pub(super) fn send(&self, message: Message) -> bool {
        self.tx.send(message).is_ok()
    }
}

/// Column names of a [`Recording`], in order (docs/outputs.md explains each):
/// `t`, the state, the references, the commanded and applied inputs, rotor
/// speeds, the sliding variables `s_<axis>` (only for a controller whose
/// telemetry has a sliding-mode part, `sliding`: the paper's cascade; PID
/// and SE(3) have none), the named estimates `<name>_<axis>` of each
/// channel law (`estimate_names`, e.g. `["delta_hat", "", ""]`; `""` slots
/// are not written), `alpha_hat` and `mass_estimate` (only with mass
/// adaptation, `adapts_mass`), true mass and inertia, disturbances.
pub fn recording_columns(estimate_names: &[&str; MAX_ESTIMATES], sliding: bool, adapts_mass: bool) -> Vec<String> {
    let mut names: Vec<String> = [
        "t",
        "x",
        "y",
        "z",
        "phi",
        "theta",
        "psi",
        "vx",
        "vy",
        "vz",
        "phi_rate",
        "theta_rate",
        "psi_rate",
        "x_ref",
        "y_ref",
        "z_ref",
        "phi_ref",
        "theta_ref",
        "psi_ref",
        "phi_demand",
        "theta_demand",
        "thrust",
        "roll_torque",
        "pitch_torque",
        "yaw_torque",
        "thrust_cmd",
        "roll_torque_cmd",
        "pitch_torque_cmd",
        "yaw_torque_cmd",
        "omega_1",
        "omega_2",
        "omega_3",
        "omega_4",
        "omega_bar",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if sliding {
        for axis in ftsmc_core::cascade::channel::NAMES {
            names.push(format!("s_{axis}"));
        }
    }
    for axis in ftsmc_core::cascade::channel::NAMES {
        for name in estimate_names.iter().filter(|n| !n.is_empty()) {
            names.push(format!("{name}_{axis}"));
        }
    }
    if adapts_mass {
        names.push("alpha_hat".into());
        names.push("mass_estimate".into());
    }
    for n in ["mass_true", "inertia_1", "inertia_2", "inertia_3"] {
        names.push(n.to_string());
    }
    for axis in ftsmc_core::cascade::channel::NAMES {
        names.push(format!("d_{axis}"));
    }
    names
}

/// Time series of a run, column-major.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recording {
    /// Column names ([`recording_columns`]).
    pub names: Vec<String>,
    /// One vector per column, all the same length.
    pub columns: Vec<Vec<f64>>,
}

impl Recording {
    /// An empty recording with these columns.
    pub fn with_columns(names: Vec<String>) -> Self {
        let columns = vec![Vec::new(); names.len()];
        Self { names, columns }
    }

    /// Append one row (`row.len()` must equal the number of columns).
    #[inline]
    pub fn push_row(&mut self, row: &[f64]) {
        debug_assert_eq!(row.len(), self.columns.len());
        for (col, &v) in self.columns.iter_mut().zip(row) {
            col.push(v);
        }
    }

    /// Append one row given in two parts, `first` then `rest` (together one
    /// value per column).
    pub fn push_row_parts(&mut self, first: &[f64], rest: &[f64]) {
        debug_assert_eq!(first.len() + rest.len(), self.columns.len());
        for (col, &v) in self.columns.iter_mut().zip(first.iter().chain(rest)) {
            col.push(v);
        }
    }

    /// The column called `name` (empty slice if unknown).
    pub fn column(&self, name: &str) -> &[f64] {
        self.names.iter().position(|n| n == name).map(|i| self.columns[i].as_slice()).unwrap_or(&[])
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// True when no row was recorded.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Write the time series as CSV to `out`: a header of the column
    /// names, then one line per row, `,`-separated, `\n`-terminated, each
    /// number in its shortest round-trip form ([`push_number`]). Rows are
    /// formatted into one reused chunk of about [`CSV_CHUNK_BYTES`] and
    /// handed to `out` chunk by chunk: a 20 MB file never sits in memory
    /// whole (on a virtual machine the page faults of a fresh 20 MB
    /// buffer cost more than formatting it). No allocation per number or
    /// row (the `csv` crate with a `String` per number cost
    /// ~9,600 instructions per simulated step); each number's text is
    /// copied in by `put` (no `memcpy` call), and a number with the bits
    /// of the one above it in its column reuses that text instead of being
    /// formatted again.
    ///
    /// # Errors
    /// The first error of `out`.
    pub fn write_csv<W: std::io::Write + ?Sized>(&self, out: &mut W) -> std::io::Result<()> {
        write_header(&self.names, out)?;
        let mut rows = CsvRows::new(self.columns.len());
        rows.write(&self.columns, out)?;
        rows.flush(out)
    }

    /// [`Recording::write_csv`] into a new buffer.
    pub fn to_csv(&self) -> Vec<u8> {
        // ~20 bytes per number (sign, 17 digits, point, separator).
        let mut out = Vec::with_capacity(
            self.names.iter().map(|n| n.len() + 1).sum::<usize>() + self.len() * self.columns.len() * 20,
        );
        // Writing to a Vec cannot fail.
        let _ = self.write_csv(&mut out);
        out
    }
}

/// Bytes of CSV [`Recording::write_csv`] formats before handing them on.
pub const CSV_CHUNK_BYTES: usize = 1 << 16;

/// The CSV header line of [`Recording::write_csv`]: the column names,
/// `,`-separated, `\n`-terminated (an empty line for no columns).
pub(super) fn write_header<W: std::io::Write + ?Sized>(names: &[String], out: &mut W) -> std::io::Result<()> {
    out.write_all(names.join(",").as_bytes())?;
    out.write_all(b"\n")
}

/// The rows of [`Recording::write_csv`], formatted into one reused chunk
/// of about [`CSV_CHUNK_BYTES`] that is handed on whenever it is full:
/// rows may come in several batches ([`CsvRows::write`]; a recording
/// streamed while it is flown, `run/stream.rs`), and the bytes are the same
/// however they are split, each number being formatted alone.
pub(super) struct CsvRows {
    chunk: Vec<u8>,
    end: usize,
    buffer: zmij::Buffer,
    /// Per column, where its text of the previous row starts in `chunk`
    /// and its length (none at the first row of a batch and after a
    /// flush): a number with the bits of the one above it (constant
    /// columns, held values: about a sixth of a flight's numbers) is that text.
    above: Vec<Option<(usize, usize)>>,
}

impl CsvRows {
    /// A formatter of rows of `width` numbers.
    pub(super) fn new(width: usize) -> Self {
        // A row is at most 25 bytes per number (24 for the longest, one
        // separator): one more row always fits after CSV_CHUNK_BYTES, and
        // 24 bytes can be copied from anywhere in a row.
        Self {
            chunk: vec![0u8; CSV_CHUNK_BYTES + 25 * width + 24],
            end: 0,
            buffer: zmij::Buffer::new(),
            above: vec![None; width],
        }
    }

    /// Format every row of `columns` (all the same length, `width` of
    /// them), handing each full chunk to `out`; the last, partly filled
    /// chunk stays for the next batch or [`CsvRows::flush`].
    pub(super) fn write<W: std::io::Write + ?Sized>(
        &mut self,
        columns: &[Vec<f64>],
        out: &mut W,
    ) -> std::io::Result<()> {
        debug_assert_eq!(columns.len(), self.above.len());
        let Self { chunk, end, buffer, above } = self;
        // The row above is in another batch: nothing to reuse yet.
        above.fill(None);
        let rows = columns.first().map_or(0, Vec::len);
        for i in 0..rows {
            for (j, column) in columns.iter().enumerate() {
                if j > 0 {
                    chunk[*end] = b',';
                    *end += 1;
                }
                let v = column[i];
                let start = *end;
                *end = match above[j] {
                    Some((from, n)) if v.to_bits() == column[i - 1].to_bits() => {
                        chunk.copy_within(from..from + 24, *end);
                        *end + n
                    }
                    _ => put(chunk, *end, number_text(buffer, v)),
                };
                above[j] = Some((start, *end - start));
            }
            chunk[*end] = b'\n';
            *end += 1;
            if *end >= CSV_CHUNK_BYTES {
                out.write_all(&chunk[..*end])?;
                *end = 0;
                above.fill(None);
            }
        }
        Ok(())
    }

    /// Hand the rest of the chunk to `out`.
    pub(super) fn flush<W: std::io::Write + ?Sized>(&mut self, out: &mut W) -> std::io::Result<()> {
        out.write_all(&self.chunk[..self.end])?;
        self.end = 0;
        self.above.fill(None);
        Ok(())
    }
}

/// Append `v` to `out` in its shortest round-trip decimal form, parsing
/// back to the same bits (`0.3`, `1.0`, `-2.5e-7`, `1.2e+16`: positional for
/// decimal exponents −5…15, else scientific), or `NaN`, `inf`, `-inf` when
/// not finite (spelled as pandas and MATLAB read them).
///
/// The digits come from `zmij` (Schubfach/yy; dtolnay's successor to `ryu`,
/// the formatter serde_json uses, so summary.json prints numbers the same
/// way): on a scenario-2 flight it needs ~220 instructions per number
/// against ~360 for `ryu` and ~1,500 for `format!("{v}")` into a `String`.
pub fn push_number(out: &mut Vec<u8>, v: f64) {
    out.extend_from_slice(number_text(&mut zmij::Buffer::new(), v));
}

/// The text of [`push_number`], in `buffer` (at most 24 bytes).
#[inline]
fn number_text(buffer: &mut zmij::Buffer, v: f64) -> &[u8] {
    if v.is_finite() {
        buffer.format_finite(v).as_bytes()
    } else if v.is_nan() {
        b"NaN"
    } else if v > 0.0 {
        b"inf"
    } else {
        b"-inf"
    }
}

/// Copy `text` (at most 24 bytes: a number of [`number_text`]) into
/// `out` at `at` and return where it ends, by two fixed-size copies that
/// overlap (16, 8, 4 bytes, or single bytes under 4): the compiler inlines
/// them, where a copy of `text.len()` bytes calls `memcpy` (3.4 % of the
/// CPU time of a recorded 200 s `ftsmc run`). `out` must have room for
/// the text at `at` (it panics otherwise).
#[inline(always)]
fn put(out: &mut [u8], at: usize, text: &[u8]) -> usize {
    let n = text.len();
    let end = at + n;
    if n >= 16 {
        out[at..at + 16].copy_from_slice(&text[..16]);
        out[end - 16..end].copy_from_slice(&text[n - 16..]);
    } else if n >= 8 {
        out[at..at + 8].copy_from_slice(&text[..8]);
        out[end - 8..end].copy_from_slice(&text[n - 8..]);
    } else if n >= 4 {
        out[at..at + 4].copy_from_slice(&text[..4]);
        out[end - 4..end].copy_from_slice(&text[n - 4..]);
    } else if n > 0 {
        out[at] = text[0];
        out[at + n / 2] = text[n / 2];
        out[end - 1] = text[n - 1];
    }
    end
}

/// The time series of one flight as it is flown (an [`Observer`] of the
/// run loop): a [`Recording`] with its controller's columns,
/// a row every `every` ticks (none with 0), assembled on the stack; with
/// a [`RowStream`], the rows are also handed over in chunks as they come
/// (`run/stream.rs`).
pub(super) struct Recorder {
    /// The rows recorded so far.
    pub recording: Recording,
    every: u64,
    /// Where completed chunks of rows go, until the formatter stops.
    stream: Option<RowStream>,
    /// Rows handed to `stream` so far.
    sent: usize,
    /// The estimate slots written (those with a name).
    named_slots: [usize; MAX_ESTIMATES],
    n_named: usize,
    /// The controller reports sliding variables (`Telemetry::sliding_mode`).
    sliding: bool,
    adapts_mass: bool,
}

impl Recorder {
    /// Columns for `controller` flying `scenario` for `steps` control ticks:
    /// a row every `control_rate / record_rate` ticks when `record` is on and
    /// `record_rate > 0`, none otherwise (room for all of them is reserved
    /// up front). With a `stream`, the header goes there now and the rows
    /// in chunks as they are recorded.
    pub(super) fn new<R: ftsmc_core::lanes::Real, C: Controller<R> + ?Sized>(
        scenario: &Scenario,
        record: bool,
        steps: u64,
        controller: &C,
        stream: Option<RowStream>,
    ) -> Self {
        let sim = &scenario.simulation;
        let every = if record && sim.record_rate > 0.0 {
            ((sim.control_rate / sim.record_rate).round() as u64).max(1)
        } else {
            0
        };
        let estimate_names = controller.estimate_names();
        let adapts_mass = controller.adapts_mass();
        let sliding = controller.telemetry().sliding_mode.is_some();
        let mut recording = if every > 0 {
            let mut names = recording_columns(&estimate_names, sliding, adapts_mass);
            if let Some(s) = scenario.sensors.filter(crate::sensors::pipeline::requested) {
                names.extend(crate::sensors::pipeline::column_names(&s).iter().map(|n| n.to_string()));
            }
            Recording::with_columns(names)
        } else {
            Recording::default()
        };
        if let Some(per_row) = steps.checked_div(every) {
            // Reserved up front up to the default `max_samples`; beyond it
            // (a raised or `inf` limit) the columns grow as rows come, so
            // no request overflows the reservation.
            let rows = per_row.saturating_add(1).min(crate::limits::DEFAULT_MAX_SAMPLES as u64) as usize;
            for c in &mut recording.columns {
                c.reserve(rows);
            }
        }
        let mut named_slots = [0; MAX_ESTIMATES];
        let mut n_named = 0;
        for (slot, name) in estimate_names.iter().enumerate() {
            if !name.is_empty() {
                named_slots[n_named] = slot;
                n_named += 1;
            }
        }
        let stream = stream.filter(|s| s.send(Message::Header(recording.names.clone())));
        Self { recording, every, stream, sent: 0, named_slots, n_named, sliding, adapts_mass }
    }

    /// Hand the rows recorded since the last chunk to the stream (if any).
    fn send_rows(&mut self) {
        let Some(stream) = &self.stream else { return };
        let rows: Vec<Vec<f64>> = self.recording.columns.iter().map(|c| c[self.sent..].to_vec()).collect();
        self.sent = self.recording.len();
        if !stream.send(Message::Rows(rows)) {
            // The formatter stopped (its writer failed): it reports why.
            self.stream = None;
        }
    }

    /// The recording, its last rows and end handed to the stream (if any).
    pub(super) fn finish(mut self) -> Recording {
        if self.recording.len() > self.sent {
            self.send_rows();
        }
        if let Some(stream) = self.stream.take() {
            stream.send(Message::End);
        }
        self.recording
    }

    /// True when tick `k` is recorded.
    #[inline]
    pub(super) fn due(&self, k: u64) -> bool {
        self.every > 0 && k % self.every == 0
    }

    /// Append the row of `tick`.
    fn push(&mut self, tick: &Tick<'_>) {
        let telemetry = tick.telemetry;
        let command = tick.command;
        let mut row = Row::new();
        row.push(tick.t);
        row.extend(&tick.state);
        row.extend(&tick.reference.position);
        row.extend(&telemetry.attitude_reference);
        row.extend(&telemetry.attitude_demand);
        row.extend(&tick.applied);
        row.extend(&[command.thrust, command.torque[0], command.torque[1], command.torque[2]]);
        row.extend(&tick.omega);
        row.push(tick.omega_bar);
        let sliding_mode = telemetry.sliding_mode.unwrap_or_default();
        if self.sliding {
            row.extend(&sliding_mode.sliding);
        }
        for est in &telemetry.estimates {
            for &slot in &self.named_slots[..self.n_named] {
                row.push(est[slot]);
            }
        }
        if self.adapts_mass {
            row.push(sliding_mode.alpha_hat);
            row.push(sliding_mode.alpha_hat * tick.nominal_mass);
        }
        row.push(tick.mass);
        row.extend(&tick.inertia);
        row.extend(&tick.disturbance);
        self.recording.push_row_parts(row.as_slice(), tick.pipeline);
        if self.stream.as_ref().is_some_and(|s| self.recording.len() - self.sent >= s.chunk_rows()) {
            self.send_rows();
        }
    }
}

impl Observer for Recorder {
    /// Record the tick when it is due (every `control_rate / record_rate` ticks).
    #[inline]
    fn tick(&mut self, tick: &Tick<'_>) {
        if self.due(tick.k) {
            self.push(tick);
        }
    }
    /// Only the recorded ticks.
    #[inline]
    fn reads_telemetry(&self, k: u64) -> bool {
        self.due(k)
    }
}

/// One row of a [`Recording`] being assembled on the stack.
pub(super) struct Row {
    values: [f64; MAX_RECORDING_COLUMNS],
    len: usize,
}

impl Row {
    #[inline]
    pub(super) fn new() -> Self {
        Self { values: [0.0; MAX_RECORDING_COLUMNS], len: 0 }
    }

    #[inline]
    pub(super) fn push(&mut self, v: f64) {
        self.values[self.len] = v;
        self.len += 1;
    }

    #[inline]
    pub(super) fn extend(&mut self, vs: &[f64]) {
        self.values[self.len..self.len + vs.len()].copy_from_slice(vs);
        self.len += vs.len();
    }

    pub(super) fn as_slice(&self) -> &[f64] {
        &self.values[..self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `put` writes exactly the text, whatever its length, and nothing
    /// around it.
    #[test]
    fn put_copies_every_length_exactly() {
        let text: Vec<u8> = (b'a'..=b'x').collect();
        for n in 0..=24 {
            for at in [0, 1, 7, 30] {
                let mut out = [b'.'; 64];
                assert_eq!(put(&mut out, at, &text[..n]), at + n);
                assert_eq!(&out[at..at + n], &text[..n], "n {n} at {at}");
                assert!(out[..at].iter().chain(&out[at + n..]).all(|&b| b == b'.'), "n {n} at {at}");
            }
        }
    }

    /// The CSV of `recording` spelled number by number with [`push_number`].
    fn plain_csv(names: &[String], recording: &Recording) -> Vec<u8> {
        let mut plain = names.join(",").into_bytes();
        plain.push(b'\n');
        for i in 0..recording.len() {
            for (j, column) in recording.columns.iter().enumerate() {
                if j > 0 {
                    plain.push(b',');
                }
                push_number(&mut plain, column[i]);
            }
            plain.push(b'\n');
        }
        plain
    }

    proptest::proptest! {
        /// Any numbers (every bit pattern, and repeats of a few values so
        /// that texts are reused from the row above) give their plain spelling.
        #[test]
        fn csv_of_any_numbers_is_their_plain_spelling(
            rows in proptest::collection::vec(
                proptest::collection::vec(
                    proptest::prop_oneof![
                        proptest::num::f64::ANY,
                        proptest::strategy::Just(-0.0),
                        proptest::strategy::Just(1e16),
                        proptest::strategy::Just(-2.2250738585072014e-308),
                    ],
                    3,
                ),
                0..300,
            )
        ) {
            let names: Vec<String> = ["a", "b", "c"].iter().map(|n| n.to_string()).collect();
            let mut recording = Recording::with_columns(names.clone());
            for row in &rows {
                recording.push_row(row);
            }
            proptest::prop_assert!(recording.to_csv() == plain_csv(&names, &recording));
        }
    }

    /// The CSV is the header and each row's numbers in [`push_number`]'s
    /// form, `,`-separated, `\n`-terminated: checked against that plain
    /// spelling on edge cases, random bit patterns, a constant column and
    /// held values, over several chunks.
    #[test]
    fn csv_is_each_number_in_push_number_form() {
        let edge = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            0.3,
            1e-5,
            9.999e-6,
            1e15,
            1e16,
            1.2e16,
            123456789012345680.0,
            5e-324,
            -5e-324,
            2.2250738585072014e-308,
            -2.2250738585072014e-308,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            f64::NAN,
            -f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.1 + 0.2,
            -1.5e-7,
            1e100,
            12.5,
            100.0,
        ];
        let names: Vec<String> = (0..9).map(|j| format!("c{j}")).collect();
        let mut recording = Recording::with_columns(names.clone());
        let mut state = 0x2545f4914f6cdd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for r in 0..30_000usize {
            let row: Vec<f64> = (0..names.len())
                .map(|j| {
                    let bits = next();
                    if j == 7 {
                        // A constant column: every text but the first copied from the row above.
                        return -2.2250738585072014e-308;
                    }
                    if j == 8 {
                        // Held values of every length, a few rows each.
                        return edge[(r / 3) % edge.len()];
                    }
                    match bits % 5 {
                        0 => edge[(bits >> 8) as usize % edge.len()],
                        1 => f64::from_bits(bits),
                        2 => (bits >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0,
                        3 => ((bits >> 20) % 200_000) as f64 * 0.001 - 100.0,
                        _ => r as f64 * 0.01,
                    }
                })
                .collect();
            recording.push_row(&row);
        }
        let plain = plain_csv(&names, &recording);
        assert!(plain.len() > 3 * CSV_CHUNK_BYTES);
        assert!(recording.to_csv() == plain, "the CSV differs from its numbers' plain spelling");
        // The same bytes when the rows come in batches (a streamed
        // recording), whatever their size: one row, a divisor of the
        // rows, a size that leaves a remainder, more than the rows.
        for batch in [1, 3_000, 7_001, 50_000] {
            let mut out = Vec::new();
            write_header(&recording.names, &mut out).unwrap();
            let mut rows = CsvRows::new(recording.columns.len());
            for first in (0..recording.len()).step_by(batch) {
                let last = (first + batch).min(recording.len());
                let part: Vec<Vec<f64>> = recording.columns.iter().map(|c| c[first..last].to_vec()).collect();
                rows.write(&part, &mut out).unwrap();
            }
            rows.flush(&mut out).unwrap();
            assert!(out == plain, "batches of {batch} rows: the CSV differs");
        }
        // An empty recording is its header alone; no columns, an empty line.
        assert_eq!(Recording::with_columns(names).to_csv(), b"c0,c1,c2,c3,c4,c5,c6,c7,c8\n");
        assert_eq!(Recording::default().to_csv(), b"\n");
    }
}
