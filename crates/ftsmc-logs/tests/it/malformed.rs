//! Every family of bad input gets one error naming the file and what is
//! wrong, never a panic: truncated, wrong magic, missing topics or columns,
//! time going back, NaN, a file over the size limit, a directory, a FIFO,
//! and format definitions that would make the parser recurse or allocate
//! without bound. The bad files are made from good synthetic ones.

use crate::common::*;
use ftsmc_logs::ulog::{read_ulog, read_ulog_flight};
use ftsmc_logs::{read_log, LogError, LogLimits};

fn good_ulog() -> Vec<u8> {
    synthetic(Options::default()).writer.bytes
}

#[test]
fn a_truncated_ulog_is_refused_with_the_byte_it_ends_at() {
    let tmp = tempfile::tempdir().unwrap();
    let s = synthetic(Options::default());
    let bytes = &s.writer.bytes;
    let ends = &s.writer.ends;
    // Inside the header, inside a format, inside a data message's body and
    // inside the 3-byte head of the last message.
    for cut in [10, ends[1] + 5, ends[ends.len() / 2] + 9, ends[ends.len() - 2] + 2, bytes.len() - 1] {
        let path = write(tmp.path(), "cut.ulg", &bytes[..cut]);
        let err = fails(read_ulog(&path, &LogLimits::default(), None));
        assert!(matches!(err, LogError::Truncated { offset, .. } if offset == cut as u64), "cut at {cut}: {err:?}");
        let text = err.to_string();
        assert!(text.starts_with(&path.display().to_string()) && text.contains("truncated"), "{text}");
    }
    // A cut between two messages leaves a shorter, valid log.
    let path = write(tmp.path(), "short.ulg", &bytes[..ends[ends.len() / 2]]);
    assert!(read_ulog(&path, &LogLimits::default(), None).is_ok());
}

#[test]
fn a_file_without_the_ulog_magic_is_refused_with_its_first_bytes() {
    let tmp = tempfile::tempdir().unwrap();
    let mut bytes = good_ulog();
    bytes[3] = b'X';
    let path = write(tmp.path(), "bad.ulg", &bytes);
    let err = fails(read_ulog(&path, &LogLimits::default(), None)).to_string();
    assert!(err.contains("not a ULog file: it starts with 55 4c 6f 58 01 12 35"), "{err}");
    // read_log then tries CSV, and says what it looked for.
    let err = fails(read_log(&path, &LogLimits::default())).to_string();
    assert!(err.contains("bad.ulg"), "{err}");
}

#[test]
fn a_ulog_without_attitude_names_the_missing_topic_and_what_it_has() {
    let tmp = tempfile::tempdir().unwrap();
    let s = synthetic(Options { attitude: false, ..Options::default() });
    let path = write(tmp.path(), "noatt.ulg", &s.writer.bytes);
    let err = fails(read_ulog_flight(&path, &LogLimits::default())).to_string();
    assert!(err.contains("missing topic vehicle_attitude"), "{err}");
    assert!(err.contains("vehicle_local_position#0"), "{err}");
}

#[test]
fn ulog_time_going_back_is_refused_naming_the_topic() {
    let tmp = tempfile::tempdir().unwrap();
    let s = synthetic(Options { attitude_step_back: Some(120), ..Options::default() });
    let path = write(tmp.path(), "back.ulg", &s.writer.bytes);
    let err = fails(read_ulog_flight(&path, &LogLimits::default()));
    assert!(
        matches!(&err, LogError::NonMonotonicTime { channel, previous, next, .. }
            if channel == "vehicle_attitude" && *previous == 3.19 && *next == 3.185),
        "{err:?}"
    );
}

#[test]
fn a_nan_the_flight_uses_is_refused_naming_the_field() {
    let tmp = tempfile::tempdir().unwrap();
    let s = synthetic(Options { nan_position: Some(40), ..Options::default() });
    let path = write(tmp.path(), "nan.ulg", &s.writer.bytes);
    // The columns keep it (a NaN is a valid float of a ULog)…
    let data = read_ulog(&path, &LogLimits::default(), None).unwrap();
    assert!(data.topic("vehicle_local_position", 0).unwrap().column("x").unwrap()[40].is_nan());
    // … the flight log does not.
    let err = fails(read_ulog_flight(&path, &LogLimits::default())).to_string();
    assert!(err.contains("vehicle_local_position.x: value NaN at sample 40 (t = 2.801 s)"), "{err}");
}

#[test]
fn a_file_over_the_limit_is_refused_with_the_limit_and_how_to_raise_it() {
    let tmp = tempfile::tempdir().unwrap();
    let bytes = good_ulog();
    let path = write(tmp.path(), "big.ulg", &bytes);
    let limits = LogLimits { max_file_bytes: 1000 };
    let err = fails(read_log(&path, &limits)).to_string();
    assert!(err.contains(&format!("{} bytes or more, over the limit of 1000 bytes", bytes.len())), "{err}");
    assert!(err.contains("raise LogLimits::max_file_bytes"), "{err}");
    let csv = write(tmp.path(), "big.csv", nanobench_csv(20).as_bytes());
    assert!(matches!(read_log(&csv, &limits), Err(LogError::TooLarge { limit: 1000, .. })));
}

#[test]
fn directories_and_fifos_are_refused_without_blocking() {
    let tmp = tempfile::tempdir().unwrap();
    let err = fails(read_log(tmp.path(), &LogLimits::default())).to_string();
    assert!(err.contains("is a directory, not a regular file"), "{err}");
    #[cfg(unix)]
    {
        let fifo = tmp.path().join("pipe.ulg");
        let name = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o600) }, 0);
        let err = fails(read_log(&fifo, &LogLimits::default())).to_string();
        assert!(err.contains("pipe.ulg is a FIFO, socket or device, not a regular file"), "{err}");
        let err = fails(read_log(std::path::Path::new("/dev/zero"), &LogLimits::default())).to_string();
        assert!(err.contains("not a regular file"), "{err}");
    }
    let err = fails(read_log(&tmp.path().join("absent.ulg"), &LogLimits::default())).to_string();
    assert!(err.contains("absent.ulg: cannot open"), "{err}");
}

/// A log whose one topic has the format `text` (after `extra` formats).
fn one_topic(extra: &[&str], text: &str) -> Vec<u8> {
    let mut w = UlogWriter::new(0);
    for f in extra {
        w.format(f);
    }
    w.format(text);
    w.subscribe(0, 0, text.split(':').next().unwrap());
    w.data(0, &Payload::default().u64(1).0);
    w.bytes
}

#[test]
fn formats_that_would_recurse_or_allocate_without_bound_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &str, &str); 5] = [
        (&[], "loop_t:uint64_t timestamp;loop_t inner;", "nested more than 16 deep"),
        (&["b_t:a_t x;", "a_t:b_t y;"], "top:uint64_t timestamp;a_t z;", "nested more than 16 deep"),
        (&[], "huge:uint64_t timestamp;uint8_t[1000000000000] x;", "longer than a message"),
        (&["empty_t:"], "holes:uint64_t timestamp;empty_t[60000] e;", "has no bytes"),
        (&[], "orphan:uint64_t timestamp;nowhere_t x;", "not defined"),
    ];
    for (extra, text, expect) in cases {
        let path = write(tmp.path(), "fmt.ulg", &one_topic(extra, text));
        let err = fails(read_ulog(&path, &LogLimits::default(), None)).to_string();
        assert!(err.contains("fmt.ulg: malformed ULog") && err.contains(expect), "{text}: {err}");
    }
}

#[test]
fn bad_csv_cells_rows_and_columns_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let good = nanobench_csv(30);
    let limits = LogLimits::default();
    let lines: Vec<&str> = good.lines().collect();

    let nan = good.replacen(",7.010000000,", ",nan,", 1);
    let err = fails(read_log(&write(tmp.path(), "nan.csv", nan.as_bytes()), &limits)).to_string();
    assert!(err.contains("nan.csv: column qw: value NaN at sample 10"), "{err}");

    let word = good.replacen(",7.010000000,", ",seven,", 1);
    let err = fails(read_log(&write(tmp.path(), "word.csv", word.as_bytes()), &limits)).to_string();
    assert!(err.contains("word.csv: line 12, column `qw`: `seven` is not a number"), "{err}");

    let mut back = lines.clone();
    back.swap(5, 6);
    let err = fails(read_log(&write(tmp.path(), "back.csv", back.join("\n").as_bytes()), &limits)).to_string();
    assert!(err.contains("back.csv: column t: time does not increase at sample 5"), "{err}");

    let short = format!("{}\n{}\n1,2,3\n", lines[0], lines[1]);
    let err = fails(read_log(&write(tmp.path(), "short.csv", short.as_bytes()), &limits)).to_string();
    assert!(err.contains("short.csv: malformed CSV") && err.contains("line 3 has 3 fields, the header 52"), "{err}");

    let no_vbat = good.replace(",pwr_pm_vbat", ",vbat");
    let table = ftsmc_logs::table::read_table(&write(tmp.path(), "nov.csv", no_vbat.as_bytes()), &limits).unwrap();
    let err = fails(ftsmc_logs::nanobench::flight_from_nanobench(&table)).to_string();
    assert!(err.contains("nov.csv: missing column(s) pwr_pm_vbat (battery)"), "{err}");

    let partial = "time_s,x_m,y_m,battery_v\n0,1,2,3\n1,1,2,3\n";
    let err = fails(read_log(&write(tmp.path(), "p.csv", partial.as_bytes()), &limits)).to_string();
    assert!(err.contains("p.csv: missing column(s) z_m (position, m, world frame)"), "{err}");

    let frame = "# frame: enu\ntime_s\n0\n1\n";
    let err = fails(read_log(&write(tmp.path(), "f.csv", frame.as_bytes()), &limits)).to_string();
    assert!(err.contains("`# frame: enu`: the frame is `ned-frd` or `zup-flu`"), "{err}");

    let one = "time_s,battery_v\n0,12\n";
    let err = fails(read_log(&write(tmp.path(), "one.csv", one.as_bytes()), &limits)).to_string();
    assert!(err.contains("one.csv: missing samples; 1 sample(s)"), "{err}");

    let unknown = "a,b\n1,2\n";
    let err = fails(read_log(&write(tmp.path(), "u.csv", unknown.as_bytes()), &limits)).to_string();
    assert!(err.contains("u.csv: missing a known format"), "{err}");

    let err = fails(read_log(&write(tmp.path(), "empty.csv", b""), &limits)).to_string();
    assert!(err.contains("empty.csv: missing a header line"), "{err}");
}
