//! `read_ulog` against pyulog (PX4/pyulog, the reference ULog parser), field
//! by field on every ULog sample of data/: the same topics and instances,
//! the same field names and every value equal (NaN equal to NaN), `time_s`
//! equal to pyulog's `timestamp / 1e6`. Needs the samples (data/fetch.sh)
//! and a Python with pyulog:
//!
//! ```sh
//! python3 -m venv target/venv && target/venv/bin/pip install pyulog
//! FTSMC_PYULOG_PYTHON=target/venv/bin/python cargo test -p ftsmc-logs --test pyulog_agreement -- --include-ignored
//! ```

use std::collections::BTreeMap;
use std::process::Command;

use crate::common::data_dir;
use ftsmc_logs::ulog::read_ulog;
use ftsmc_logs::LogLimits;

/// Prints, for every data set of the log, a line `name#multi_id<TAB>field<TAB>v,v,…`
/// (values as Python's shortest round-trip repr of the float64).
const DUMP: &str = r#"
import sys
from pyulog import ULog
for d in ULog(sys.argv[1]).data_list:
    for name, values in d.data.items():
        if "_padding" in name:
            continue
        print(f"{d.name}#{d.multi_id}\t{name}\t" + ",".join(repr(float(v)) for v in values))
"#;

#[test]
#[ignore = "needs data/fetch.sh and FTSMC_PYULOG_PYTHON (a Python with pyulog)"]
fn read_ulog_agrees_with_pyulog_on_every_value() {
    let python = std::env::var("FTSMC_PYULOG_PYTHON").expect("set FTSMC_PYULOG_PYTHON to a Python with pyulog");
    let dir = data_dir().join("ulog");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e} (run data/fetch.sh)", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ulg"))
        .collect();
    files.sort();
    assert!(!files.is_empty());
    for file in files {
        let out = Command::new(&python).arg("-c").arg(DUMP).arg(&file).output().unwrap();
        assert!(out.status.success(), "pyulog on {}: {}", file.display(), String::from_utf8_lossy(&out.stderr));
        let mut reference: BTreeMap<String, Vec<(String, Vec<f64>)>> = BTreeMap::new();
        for line in String::from_utf8(out.stdout).unwrap().lines() {
            let mut cells = line.split('\t');
            let (topic, field, values) = (cells.next().unwrap(), cells.next().unwrap(), cells.next().unwrap_or(""));
            let values = values.split(',').filter(|v| !v.is_empty()).map(|v| v.parse::<f64>().unwrap()).collect();
            reference.entry(topic.to_string()).or_default().push((field.to_string(), values));
        }
        let ours = read_ulog(&file, &LogLimits::default(), None).unwrap();
        let name = file.display();
        let topics: Vec<String> =
            ours.topics.iter().map(|t| format!("{}#{}", t.topic.name, t.topic.multi_id)).collect();
        assert_eq!(topics, reference.keys().cloned().collect::<Vec<_>>(), "{name}: topics");
        let mut compared = 0usize;
        for t in &ours.topics {
            let key = format!("{}#{}", t.topic.name, t.topic.multi_id);
            let fields = &reference[&key];
            let names: Vec<&str> = fields.iter().map(|(f, _)| f.as_str()).collect();
            assert_eq!(t.topic.fields, names, "{name}: {key}: field names");
            for (column, (field, values)) in t.columns.iter().zip(fields) {
                assert_eq!(column.len(), values.len(), "{name}: {key}.{field}: count");
                for (i, (a, b)) in column.iter().zip(values).enumerate() {
                    assert!(
                        a == b || (a.is_nan() && b.is_nan()),
                        "{name}: {key}.{field}[{i}]: {a} here, {b} in pyulog"
                    );
                }
                compared += values.len();
            }
            let stamps = &fields.iter().find(|(f, _)| f == "timestamp").unwrap().1;
            let expected: Vec<f64> = stamps.iter().map(|s| s / 1e6).collect();
            assert_eq!(t.time_s, expected, "{name}: {key}: time_s");
        }
        eprintln!("{name}: {compared} values equal to pyulog's");
    }
}
