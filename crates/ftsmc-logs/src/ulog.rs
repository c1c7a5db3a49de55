//! PX4 ULog files (PX4 User Guide, "ULog File Format"): a stream of named
//! topics whose fields come out as `f64` columns, and the [`FlightLog`] of a
//! PX4 multicopter flight.
//!
//! # Which parser
//!
//! The bytes are parsed by the [`yule_log`] crate (MIT, streamed: one
//! message in memory at a time). Three crates on crates.io were run on five
//! of pyulog's sample logs (PX4/pyulog `test/*.ulg`) and compared with
//! pyulog 1.3 topic by topic (message counts per topic and instance, and
//! the first, middle and last value of every field):
//!
//! | crate | result |
//! | --- | --- |
//! | `yule_log` 0.4.0 | every count and value equal to pyulog's on all five |
//! | `px4-ulog` 0.1.1 | merges a topic's instances (`multi_id`), counts a prefix-matched topic under another's name; needs a `File` |
//! | `ulog-rs` 0.0.4 | refuses two of the five (appended-data flag; `int16_t[8]`); reads the whole file into memory |
//!
//! Two faults of `yule_log` 0.4.0 are worked around here rather than
//! written around by hand: its array and nested-type allocation trusts the
//! format text (an array of 10¹⁸ elements, a type that contains itself), so
//! every format a subscription uses is checked first (nesting, array and
//! message sizes; see [`MAX_NESTING`]);
//! and it reports every fault of the 16-byte file header as "Invalid
//! Header", so the header is read and checked here. One is not: it prints
//! a line to standard output when a format's name contains `heartbeat`.
//!
//! # Time
//!
//! A ULog time stamp is microseconds since boot (`uint64_t timestamp`, the
//! first field of every topic); `time_s` is that over 10⁶. Integer fields
//! become `f64` exactly up to 2⁵³.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufReader, Cursor, Read};
use std::path::Path;
use std::rc::Rc;

use yule_log::builder::ULogParserBuilder;
use yule_log::errors::ULogError;
use yule_log::model::def::{self, BaseType};
use yule_log::model::inst::{self, FieldValue};
use yule_log::model::msg::UlogMessage;
use yule_log::parser::ULogParser;

use crate::error::LogError;
use crate::flight_log::{FlightLog, Frame, MotorUnit, Motors};
use crate::source::{self, Counted, LogLimits, Offset};

/// The 7 magic bytes a ULog file starts with: `ULog` 01 12 35.
pub const MAGIC: [u8; 7] = [b'U', b'L', b'o', b'g', 0x01, 0x12, 0x35];

/// Deepest nesting of types in a format: PX4's go 3 deep; a format that
/// contains itself would recurse without end.
pub const MAX_NESTING: usize = 16;

/// Largest ULog message body, bytes (the message size is a `uint16_t`).
pub const MAX_MESSAGE_BYTES: usize = u16::MAX as usize;

type Reader = Framing<std::io::Chain<Cursor<[u8; 16]>, Counted<BufReader<File>>>>;

/// Where the bytes read so far end in ULog's framing: the 16-byte header,
/// then messages of `uint16_t size`, `uint8_t type` and `size` bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum At {
    /// Inside the file header, this many bytes to go.
    Header(usize),
    /// Between two messages: the next byte is a size's low byte.
    Boundary,
    /// The size's low byte read.
    SizeHigh(u8),
    /// The size read; the type byte next.
    Type(usize),
    /// Inside a message body, this many bytes to go.
    Body(usize),
}

/// Follows the framing of the bytes `yule_log` reads, so that the end of
/// the file inside a message is an error: `yule_log` 0.4.0 takes every end
/// of file a read meets as the end of the log, and decodes the message it
/// was reading from zeros.
struct Framing<R> {
    inner: R,
    at: At,
}

/// The marker of the error [`Framing`] returns at an end of file inside a
/// message.
#[derive(Debug)]
struct EndInsideMessage;

impl std::fmt::Display for EndInsideMessage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("the file ends inside a message")
    }
}

impl std::error::Error for EndInsideMessage {}

impl<R: Read> Read for Framing<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        if n == 0 && !buf.is_empty() && self.at != At::Boundary {
            return Err(std::io::Error::other(EndInsideMessage));
        }
        let mut i = 0;
        while i < n {
            self.at = match self.at {
                At::Header(left) | At::Body(left) => {
                    let take = left.min(n - i);
                    i += take;
                    match (self.at, left - take) {
                        (_, 0) => At::Boundary,
                        (At::Header(_), rest) => At::Header(rest),
                        (_, rest) => At::Body(rest),
                    }
                }
                At::Boundary => {
                    i += 1;
                    At::SizeHigh(buf[i - 1])
                }
                At::SizeHigh(low) => {
                    i += 1;
                    At::Type(usize::from(u16::from_le_bytes([low, buf[i - 1]])))
                }
                At::Type(0) => {
                    i += 1;
                    At::Boundary
                }
                At::Type(size) => {
                    i += 1;
                    At::Body(size)
                }
            };
        }
        Ok(n)
    }
}

/// One instance of a topic: its name, `multi_id` and flattened field names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Topic {
    /// uORB topic name (`vehicle_attitude`).
    pub name: String,
    /// Instance (0 for the first; `sensor_accel` 0, 1, 2 …).
    pub multi_id: u8,
    /// Field names as pyulog spells them: arrays `q[0]`, nested types
    /// `current.lat`, padding left out. Includes `timestamp` (µs).
    pub fields: Vec<String>,
}

/// One logged message of a topic.
#[derive(Clone, Debug, PartialEq)]
pub struct UlogRecord {
    /// The topic instance (shared by all its records).
    pub topic: Rc<Topic>,
    /// Its time stamp, s since boot.
    pub time_s: f64,
    /// One value per name of `topic.fields`, in their unit in the uORB
    /// message definition (PX4 `msg/*.msg`).
    pub values: Vec<f64>,
}

/// The logged messages of a ULog file, one at a time, in file order.
pub struct UlogStream {
    file: String,
    offset: Offset,
    limit: u64,
    parser: ULogParser<Reader>,
    formats: HashMap<String, def::Format>,
    topics: HashMap<u16, Rc<Topic>>,
    parameters: BTreeMap<String, f64>,
    finished: bool,
}

impl std::fmt::Debug for UlogStream {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("UlogStream").field("file", &self.file).field("offset", &self.offset.get()).finish()
    }
}

impl UlogStream {
    /// Opens `path` (a regular file within `limits`) and checks its header.
    /// `only` limits the records to these topic names (every topic if
    /// `None`); the others are skipped without being decoded.
    pub fn open(path: &Path, limits: &LogLimits, only: Option<&[&str]>) -> Result<Self, LogError> {
        let mut opened = source::open(path, limits)?;
        let mut head = [0u8; 16];
        if let Err(err) = opened.reader.read_exact(&mut head) {
            return Err(opened.io_error(err));
        }
        if head[..7] != MAGIC {
            let found = head[..7].iter().map(|b| format!("{b:02x}")).collect::<Vec<_>>().join(" ");
            return Err(LogError::BadMagic { file: opened.file, found });
        }
        let (file, offset, limit) = (opened.file.clone(), opened.offset.clone(), opened.limit);
        let reader: Reader = Framing { inner: Cursor::new(head).chain(opened.reader), at: At::Header(16) };
        let mut builder = ULogParserBuilder::new(reader).include_timestamp(true);
        if let Some(names) = only {
            builder = builder.set_subscription_allow_list(names.iter().copied());
        }
        let parser = builder.build().map_err(|e| LogError::Malformed {
            file: file.clone(),
            format: "ULog",
            offset: 0,
            detail: e.to_string(),
        })?;
        Ok(Self {
            file,
            offset,
            limit,
            parser,
            formats: HashMap::new(),
            topics: HashMap::new(),
            parameters: BTreeMap::new(),
            finished: false,
        })
    }

    /// The path as given.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// Parameters seen so far (`PARAM` messages: initial values, then
    /// changes), by name; `int32` values as `f64`.
    pub fn parameters(&self) -> &BTreeMap<String, f64> {
        &self.parameters
    }

    fn error(&self, err: ULogError) -> LogError {
        let file = self.file.clone();
        let offset = self.offset.get();
        match err {
            ULogError::Io(io) => {
                if io.get_ref().is_some_and(|e| e.is::<EndInsideMessage>()) {
                    LogError::Truncated { file, offset }
                } else if io.get_ref().is_some_and(|e| e.is::<source::GrewPastLimit>()) {
                    LogError::TooLarge { file, size: offset, limit: self.limit }
                } else if io.kind() == std::io::ErrorKind::UnexpectedEof {
                    LogError::Truncated { file, offset }
                } else {
                    LogError::Read { file, source: io }
                }
            }
            ULogError::UnexpectedEndOfFile => LogError::Truncated { file, offset },
            other => LogError::Malformed { file, format: "ULog", offset, detail: other.to_string() },
        }
    }

    fn malformed(&self, detail: String) -> LogError {
        LogError::Malformed { file: self.file.clone(), format: "ULog", offset: self.offset.get(), detail }
    }

    fn subscribe(&mut self, msg_id: u16, name: &str, multi_id: u8) -> Result<(), LogError> {
        let format = check_format(&self.formats, name).map_err(|d| self.malformed(d))?;
        let mut fields = Vec::new();
        flatten_names(&self.formats, format, "", &mut fields);
        let topic = Topic { name: name.to_string(), multi_id, fields };
        self.topics.insert(msg_id, Rc::new(topic));
        Ok(())
    }
}

impl Iterator for UlogStream {
    type Item = Result<UlogRecord, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        while !self.finished {
            let message = match self.parser.next() {
                None => {
                    self.finished = true;
                    return None;
                }
                Some(Err(err)) => {
                    self.finished = true;
                    return Some(Err(self.error(err)));
                }
                Some(Ok(m)) => m,
            };
            match message {
                UlogMessage::FormatDefinition(format) => {
                    self.formats.insert(format.name.to_string(), format);
                }
                UlogMessage::AddSubscription(sub) => {
                    if let Err(err) = self.subscribe(sub.msg_id, &sub.message_name, sub.multi_id) {
                        self.finished = true;
                        return Some(Err(err));
                    }
                }
                UlogMessage::Parameter(p) => {
                    let value = match p.value {
                        inst::ParameterValue::INT32(v) => f64::from(v),
                        inst::ParameterValue::FLOAT(v) => f64::from(v),
                    };
                    self.parameters.insert(p.key, value);
                }
                UlogMessage::LoggedData(data) => {
                    let Some(topic) = self.topics.get(&data.msg_id).cloned() else {
                        self.finished = true;
                        return Some(Err(
                            self.malformed(format!("data of msg_id {} before its subscription", data.msg_id))
                        ));
                    };
                    let mut values = Vec::with_capacity(topic.fields.len());
                    flatten_values(&data.data, &mut values);
                    if values.len() != topic.fields.len() {
                        self.finished = true;
                        let detail = format!(
                            "{}: {} values decoded, its format has {} fields",
                            topic.name,
                            values.len(),
                            topic.fields.len()
                        );
                        return Some(Err(self.malformed(detail)));
                    }
                    return Some(Ok(UlogRecord { topic, time_s: data.timestamp as f64 / 1e6, values }));
                }
                _ => {}
            }
        }
        None
    }
}

/// Bytes of one value of a base type.
fn base_size(base: &BaseType) -> Option<usize> {
    Some(match base {
        BaseType::UINT8 | BaseType::INT8 | BaseType::BOOL | BaseType::CHAR => 1,
        BaseType::UINT16 | BaseType::INT16 => 2,
        BaseType::UINT32 | BaseType::INT32 | BaseType::FLOAT => 4,
        BaseType::UINT64 | BaseType::INT64 | BaseType::DOUBLE => 8,
        BaseType::OTHER(_) => return None,
    })
}

/// Checks the format `name` and every type nested in it before a message of
/// it is decoded: defined, nested at most [`MAX_NESTING`] deep (so never in
/// itself), every array and the whole at most [`MAX_MESSAGE_BYTES`] long,
/// and no nested type of zero bytes (whose arrays would cost memory without
/// bytes in the file). Returns the format, or what is wrong with it.
fn check_format<'a>(formats: &'a HashMap<String, def::Format>, name: &str) -> Result<&'a def::Format, String> {
    fn size(formats: &HashMap<String, def::Format>, name: &str, depth: usize) -> Result<usize, String> {
        if depth > MAX_NESTING {
            return Err(format!("type `{name}` is nested more than {MAX_NESTING} deep (does it contain itself?)"));
        }
        let format = formats.get(name).ok_or_else(|| format!("type `{name}` is used but not defined"))?;
        let mut total = 0usize;
        for field in &format.fields {
            let count = field.r#type.array_size.unwrap_or(1);
            if count > MAX_MESSAGE_BYTES {
                return Err(format!("`{name}.{}`: array of {count} elements, longer than a message", field.name));
            }
            let one = match &field.r#type.base_type {
                BaseType::OTHER(inner) => {
                    let s = size(formats, inner, depth + 1)?;
                    if s == 0 {
                        return Err(format!("`{name}.{}`: type `{inner}` has no bytes", field.name));
                    }
                    s
                }
                base => base_size(base).unwrap_or(1),
            };
            total = total.saturating_add(one.saturating_mul(count));
            if total > MAX_MESSAGE_BYTES {
                return Err(format!("type `{name}` is longer than a message ({MAX_MESSAGE_BYTES} bytes)"));
            }
        }
        Ok(total)
    }
    size(formats, name, 0)?;
    Ok(&formats[name])
}

fn is_padding(name: &str) -> bool {
    name.starts_with("_padding")
}

fn flatten_names(formats: &HashMap<String, def::Format>, format: &def::Format, prefix: &str, out: &mut Vec<String>) {
    for field in &format.fields {
        if is_padding(&field.name) {
            continue;
        }
        let name = format!("{prefix}{}", field.name);
        let element = |out: &mut Vec<String>, name: String| match &field.r#type.base_type {
            BaseType::OTHER(inner) => flatten_names(formats, &formats[inner], &format!("{name}."), out),
            _ => out.push(name),
        };
        match field.r#type.array_size {
            None => element(out, name),
            Some(n) => (0..n).for_each(|i| element(out, format!("{name}[{i}]"))),
        }
    }
}

fn flatten_values(format: &inst::Format, out: &mut Vec<f64>) {
    for field in &format.fields {
        if is_padding(&field.name) {
            continue;
        }
        push_value(&field.value, out);
    }
}

fn push_value(value: &FieldValue, out: &mut Vec<f64>) {
    use FieldValue::*;
    match value {
        ScalarU8(x) => out.push(f64::from(*x)),
        ScalarU16(x) => out.push(f64::from(*x)),
        ScalarU32(x) => out.push(f64::from(*x)),
        ScalarU64(x) => out.push(*x as f64),
        ScalarI8(x) => out.push(f64::from(*x)),
        ScalarI16(x) => out.push(f64::from(*x)),
        ScalarI32(x) => out.push(f64::from(*x)),
        ScalarI64(x) => out.push(*x as f64),
        ScalarF32(x) => out.push(f64::from(*x)),
        ScalarF64(x) => out.push(*x),
        ScalarBool(x) => out.push(f64::from(u8::from(*x))),
        ScalarChar(x) => out.push(f64::from(x.as_u8())),
        ScalarOther(f) => flatten_values(f, out),
        ArrayU8(a) => out.extend(a.iter().map(|&x| f64::from(x))),
        ArrayU16(a) => out.extend(a.iter().map(|&x| f64::from(x))),
        ArrayU32(a) => out.extend(a.iter().map(|&x| f64::from(x))),
        ArrayU64(a) => out.extend(a.iter().map(|&x| x as f64)),
        ArrayI8(a) => out.extend(a.iter().map(|&x| f64::from(x))),
        ArrayI16(a) => out.extend(a.iter().map(|&x| f64::from(x))),
        ArrayI32(a) => out.extend(a.iter().map(|&x| f64::from(x))),
        ArrayI64(a) => out.extend(a.iter().map(|&x| x as f64)),
        ArrayF32(a) => out.extend(a.iter().map(|&x| f64::from(x))),
        ArrayF64(a) => out.extend_from_slice(a),
        ArrayBool(a) => out.extend(a.iter().map(|&x| f64::from(u8::from(x)))),
        ArrayChar(a) => out.extend(a.iter().map(|x| f64::from(x.as_u8()))),
        ArrayOther(a) => a.iter().for_each(|f| flatten_values(f, out)),
    }
}

/// The records of one topic instance as columns.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicColumns {
    /// The topic instance.
    pub topic: Rc<Topic>,
    /// Time of each record, s since boot, in file order.
    pub time_s: Vec<f64>,
    /// One column per name of `topic.fields`, as long as `time_s`.
    pub columns: Vec<Vec<f64>>,
}

impl TopicColumns {
    /// The column of field `name` (pyulog's spelling: `q[0]`, `xyz[2]`).
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.topic.fields.iter().position(|f| f == name).map(|i| &self.columns[i][..])
    }
}

/// A ULog file read into columns.
#[derive(Clone, Debug, PartialEq)]
pub struct UlogData {
    /// The path as given.
    pub file: String,
    /// Every topic instance that logged at least one message, by name then
    /// `multi_id`.
    pub topics: Vec<TopicColumns>,
    /// Last value of every parameter.
    pub parameters: BTreeMap<String, f64>,
}

impl UlogData {
    /// Topic `name`, instance `multi_id`.
    pub fn topic(&self, name: &str, multi_id: u8) -> Option<&TopicColumns> {
        self.topics.iter().find(|t| t.topic.name == name && t.topic.multi_id == multi_id)
    }
}

/// Reads the topics of a ULog file into columns (`only`: these topic names,
/// or every topic). Memory: the columns of the topics kept, 8 bytes a value.
pub fn read_ulog(path: &Path, limits: &LogLimits, only: Option<&[&str]>) -> Result<UlogData, LogError> {
    let mut stream = UlogStream::open(path, limits, only)?;
    let mut topics: BTreeMap<(String, u8), TopicColumns> = BTreeMap::new();
    for record in stream.by_ref() {
        let record = record?;
        let key = (record.topic.name.clone(), record.topic.multi_id);
        let entry = topics.entry(key).or_insert_with(|| TopicColumns {
            topic: record.topic.clone(),
            time_s: Vec::new(),
            columns: vec![Vec::new(); record.topic.fields.len()],
        });
        if entry.topic.fields != record.topic.fields {
            let detail = format!(
                "topic {} instance {} subscribed twice with different formats",
                record.topic.name, record.topic.multi_id
            );
            return Err(LogError::Malformed {
                file: stream.file.clone(),
                format: "ULog",
                offset: stream.offset.get(),
                detail,
            });
        }
        entry.time_s.push(record.time_s);
        for (column, value) in entry.columns.iter_mut().zip(record.values) {
            column.push(value);
        }
    }
    Ok(UlogData {
        file: stream.file.clone(),
        topics: topics.into_values().collect(),
        parameters: stream.parameters.clone(),
    })
}

/// The PX4 topics a [`FlightLog`] is made of, in the order looked for
/// (uORB message definitions, PX4-Autopilot `msg/`): attitude is required
/// and gives the time base; every other channel is held at its latest
/// sample at each attitude time stamp.
pub const FLIGHT_TOPICS: [&str; 7] = [
    "vehicle_attitude",         // q[0..3]: w, x, y, z, body FRD to world NED
    "vehicle_local_position",   // x, y, z (m, NED); vx, vy, vz (m/s, NED)
    "vehicle_angular_velocity", // xyz[0..2] (rad/s, body FRD), bias-corrected
    "sensor_combined",          // gyro_rad[0..2] (rad/s), accelerometer_m_s2[0..2] (m/s²), body FRD
    "actuator_motors",          // control[0..3], normalised 0..1 (PX4 v1.14 and later)
    "actuator_outputs",         // output[0..3], PWM µs (earlier PX4)
    "battery_status",           // voltage_v (V)
];

/// One channel picked from a topic: its time and its columns.
struct Channel<'a> {
    what: String,
    names: Vec<String>,
    time: &'a [f64],
    columns: Vec<&'a [f64]>,
}

fn channel<'a>(data: &'a UlogData, topic: &str, fields: &[&str]) -> Option<Channel<'a>> {
    let t = data.topic(topic, 0)?;
    let columns = fields.iter().map(|f| t.column(f)).collect::<Option<Vec<_>>>()?;
    let names = fields.iter().map(|f| format!("{topic}.{f}")).collect();
    Some(Channel { what: topic.to_string(), names, time: &t.time_s, columns })
}

/// The [`FlightLog`] of a PX4 ULog file (frame [`Frame::NedFrd`]).
///
/// Time base: `vehicle_attitude` instance 0, from the first time stamp at
/// which every channel found has a sample (an attitude sample with the
/// time stamp of the one before it is left out, so that time strictly
/// increases). Body rates come from
/// `vehicle_angular_velocity` if logged, else `sensor_combined.gyro_rad`;
/// motors from `actuator_motors` (normalised) if logged, else
/// `actuator_outputs` instance 0 (PWM µs). Errors: no `vehicle_attitude`
/// (`Missing`), a channel whose time goes back (`NonMonotonicTime`), a
/// non-finite value used (`NotFinite`, naming the topic and field).
pub fn read_ulog_flight(path: &Path, limits: &LogLimits) -> Result<FlightLog, LogError> {
    let data = read_ulog(path, limits, Some(&FLIGHT_TOPICS))?;
    flight_from_ulog(&data)
}

/// The [`FlightLog`] of ULog columns already read (see [`read_ulog_flight`]).
pub fn flight_from_ulog(data: &UlogData) -> Result<FlightLog, LogError> {
    let file = || data.file.clone();
    let attitude = channel(data, "vehicle_attitude", &["q[0]", "q[1]", "q[2]", "q[3]"]).ok_or_else(|| {
        let names: Vec<String> = data.topics.iter().map(|t| format!("{}#{}", t.topic.name, t.topic.multi_id)).collect();
        LogError::Missing {
            file: file(),
            what: "topic vehicle_attitude (instance 0, fields q[0]..q[3])".into(),
            found: if names.is_empty() {
                "no topic of a flight log was logged".into()
            } else {
                format!("it has {}", names.join(", "))
            },
        }
    })?;
    let position = channel(data, "vehicle_local_position", &["x", "y", "z"]);
    let velocity = channel(data, "vehicle_local_position", &["vx", "vy", "vz"]);
    let rates = channel(data, "vehicle_angular_velocity", &["xyz[0]", "xyz[1]", "xyz[2]"])
        .or_else(|| channel(data, "sensor_combined", &["gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]"]));
    let accel =
        channel(data, "sensor_combined", &["accelerometer_m_s2[0]", "accelerometer_m_s2[1]", "accelerometer_m_s2[2]"]);
    let motor_fields = |name: &str| [0, 1, 2, 3].map(|i| format!("{name}[{i}]"));
    let [a, b, c, d] = motor_fields("control");
    let [e, f, g, h] = motor_fields("output");
    let motors = channel(data, "actuator_motors", &[&a, &b, &c, &d])
        .map(|ch| (MotorUnit::Normalised, ch))
        .or_else(|| channel(data, "actuator_outputs", &[&e, &f, &g, &h]).map(|ch| (MotorUnit::PwmMicroseconds, ch)));
    let battery = channel(data, "battery_status", &["voltage_v"]);

    let mut all: Vec<&Channel> = vec![&attitude];
    all.extend(position.iter().chain(&velocity).chain(&rates).chain(&accel).chain(&battery));
    if let Some((_, m)) = &motors {
        all.push(m);
    }
    for ch in &all {
        if let Some(i) = (1..ch.time.len()).find(|&i| ch.time[i] < ch.time[i - 1]) {
            return Err(LogError::NonMonotonicTime {
                file: file(),
                channel: ch.what.clone(),
                index: i,
                previous: ch.time[i - 1],
                next: ch.time[i],
            });
        }
    }
    // The base: attitude time stamps from when every channel has a sample,
    // each strictly after the one kept before it.
    let start = all.iter().filter_map(|ch| ch.time.first().copied()).fold(f64::NEG_INFINITY, f64::max);
    let mut base: Vec<usize> = Vec::new();
    for (i, &t) in attitude.time.iter().enumerate() {
        if t >= start && base.last().is_none_or(|&j| t > attitude.time[j]) {
            base.push(i);
        }
    }
    let times: Vec<f64> = base.iter().map(|&i| attitude.time[i]).collect();
    let origin = times.first().copied().unwrap_or(0.0);
    let hold = |ch: &Channel| -> Result<Vec<Vec<f64>>, LogError> {
        let mut out = Vec::with_capacity(times.len());
        let mut j = 0;
        for &t in &times {
            while j + 1 < ch.time.len() && ch.time[j + 1] <= t {
                j += 1;
            }
            let row: Vec<f64> = ch.columns.iter().map(|c| c[j]).collect();
            if let Some(k) = row.iter().position(|v| !v.is_finite()) {
                let field = ch.names[k].clone();
                return Err(LogError::NotFinite { file: file(), field, index: j, time: ch.time[j], value: row[k] });
            }
            out.push(row);
        }
        Ok(out)
    };
    let vec3 = |ch: &Option<Channel>| -> Result<Option<Vec<[f64; 3]>>, LogError> {
        ch.as_ref().map(|c| Ok(hold(c)?.into_iter().map(|r| [r[0], r[1], r[2]]).collect())).transpose()
    };
    let log = FlightLog {
        source: file(),
        frame: Frame::NedFrd,
        time_origin_s: origin,
        time_s: times.iter().map(|t| t - origin).collect(),
        position_m: vec3(&position)?,
        velocity_m_s: vec3(&velocity)?,
        attitude_wxyz: Some(hold(&attitude)?.into_iter().map(|r| [r[0], r[1], r[2], r[3]]).collect()),
        body_rates_rad_s: vec3(&rates)?,
        accel_m_s2: vec3(&accel)?,
        motors: motors
            .as_ref()
            .map(|(unit, ch)| {
                Ok::<_, LogError>(Motors {
                    unit: *unit,
                    values: hold(ch)?.into_iter().map(|r| [r[0], r[1], r[2], r[3]]).collect(),
                })
            })
            .transpose()?,
        battery_v: battery
            .as_ref()
            .map(|ch| Ok::<_, LogError>(hold(ch)?.into_iter().map(|r| r[0]).collect()))
            .transpose()?,
        setpoint: None,
    };
    log.validate()?;
    Ok(log)
}
