//! IMU samples from ROS 1 bags (`.bag`, through the `rosbag` crate) and ROS 2 MCAP files
//! (`.mcap`, through the `mcap` crate): the `sensor_msgs/Imu` messages of one topic, timed by
//! their `header.stamp` (when the sensor measured, not when the message was recorded).
//!
//! Message layouts (fixed, so decoded by hand):
//! - ROS 1 serialisation (wiki.ros.org/msg, "Serialization"): little-endian; `header` = seq u32,
//!   stamp secs u32 + nsecs u32, frame_id (u32 length + bytes); then orientation 4 f64,
//!   orientation_covariance 9 f64 (fixed arrays carry no length), angular_velocity 3 f64, its
//!   covariance 9 f64, linear_acceleration 3 f64, its covariance 9 f64.
//! - ROS 2 CDR (OMG XCDR1 as rmw_fastrtps writes it): a 4-byte encapsulation header (0x00 0x01
//!   little-endian, 0x00 0x00 big-endian); `header` = stamp sec i32 + nanosec u32, frame_id (u32
//!   length including the NUL, bytes, NUL); every f64 aligned to 8 bytes counted from the end of
//!   the encapsulation header; then the same fields as ROS 1.

use crate::error::{LogError, Problem, Result};
use std::path::Path;

/// The file formats recognised by their first bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// ROS 1 bag v2.0 (wiki.ros.org/Bags/Format/2.0: the file starts with `#ROSBAG V2.0\n`).
    RosBag,
    /// MCAP (mcap.dev/spec: the file starts with the magic `\x89MCAP0\r\n`).
    Mcap,
}

/// The format of a file from its first bytes, if it is a bag or MCAP file.
pub fn format_of(first_bytes: &[u8]) -> Option<Format> {
    if first_bytes.starts_with(b"#ROSBAG V2.0\n") {
        Some(Format::RosBag)
    } else if first_bytes.starts_with(b"\x89MCAP0\r\n") {
        Some(Format::Mcap)
    } else {
        None
    }
}

/// The MCAP file of a ROS 2 bag directory (as `ros2 bag record -s mcap` writes it).
pub fn bag_directory_file(dir: &Path) -> Result<std::path::PathBuf> {
    let source = dir.display().to_string();
    let mut mcap = Vec::new();
    let mut db3 = false;
    let unreadable =
        |e: std::io::Error| LogError::new(&source, Problem::UnreadableDirectory).caused_by(e);
    for entry in std::fs::read_dir(dir).map_err(unreadable)? {
        let p = entry.map_err(unreadable)?.path();
        match p.extension().and_then(|e| e.to_str()) {
            Some("mcap") => mcap.push(p),
            Some("db3") => db3 = true,
            _ => {}
        }
    }
    mcap.sort();
    let problem = match mcap.len() {
        1 => return Ok(mcap.remove(0)),
        0 if db3 => "a ROS 2 bag in sqlite3 storage (.db3); imudrift reads MCAP: convert it with `ros2 bag convert` (storage_id: mcap) or record with `-s mcap`".to_string(),
        0 => "a directory without a .mcap file; give a log file, a ROS 1 bag or a ROS 2 MCAP file".to_string(),
        _ => format!(
            "a bag split into {} files ({}); give one of them (each is analysed on its own)",
            mcap.len(),
            mcap.iter().map(|p| p.file_name().unwrap_or_default().to_string_lossy().into_owned()).collect::<Vec<_>>().join(", ")
        ),
    };
    Err(LogError::content(&source, problem))
}

/// IMU samples of one topic, SI (rad/s, m/s^2), in stamp order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImuSeries {
    pub topic: String,
    /// header.stamp, ns.
    pub t_ns: Vec<i64>,
    pub gyro: [Vec<f64>; 3],
    pub accel: [Vec<f64>; 3],
}

impl ImuSeries {
    /// Times in s from the first stamp (exact differences of the integer stamps).
    pub fn t_s(&self) -> Vec<f64> {
        let t0 = self.t_ns.first().copied().unwrap_or(0);
        self.t_ns.iter().map(|&t| (t - t0) as f64 * 1e-9).collect()
    }

    fn push(&mut self, m: ImuSample) {
        self.t_ns.push(m.t_ns);
        for a in 0..3 {
            self.gyro[a].push(m.gyro[a]);
            self.accel[a].push(m.accel[a]);
        }
    }
}

/// One decoded message.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuSample {
    /// header.stamp, ns.
    pub t_ns: i64,
    pub gyro: [f64; 3],
    pub accel: [f64; 3],
}

const ROS1_TYPE: &str = "sensor_msgs/Imu";
const ROS2_TYPE: &str = "sensor_msgs/msg/Imu";

/// Read the IMU messages of `topic` (or of the only IMU topic) from a bag or MCAP file.
pub fn read_imu(path: &Path, format: Format, topic: Option<&str>) -> Result<ImuSeries> {
    let source = path.display().to_string();
    // The readers are third-party code on untrusted bytes: a panic in them (rosbag indexes
    // past the end of a truncated file) is an error here, and its message is not printed.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = std::panic::catch_unwind(|| match format {
        Format::RosBag => read_rosbag(path, &source, topic),
        Format::Mcap => read_mcap(path, &source, topic),
    });
    std::panic::set_hook(hook);
    let mut series = match result {
        Ok(r) => r?,
        Err(_) => {
            return Err(LogError::content(
                &source,
                "the file is damaged (its reader stopped); re-record or repair it",
            ))
        }
    };
    if series.t_ns.len() < 2 {
        let problem = format!(
            "topic {} has {} sensor_msgs/Imu message(s); at least 2 are needed",
            series.topic,
            series.t_ns.len()
        );
        return Err(LogError::content(&source, problem));
    }
    check_values(&series, &source)?;
    sort_by_stamp(&mut series, &source)?;
    Ok(series)
}

/// Every gyro and accelerometer value finite and of a magnitude a log may hold
/// ([`crate::limits::valid_value`]), as the CSV reader requires: else an error naming the message (in
/// file order) and the field.
fn check_values(s: &ImuSeries, source: &str) -> Result<()> {
    let fields = [
        ("angular_velocity", &s.gyro),
        ("linear_acceleration", &s.accel),
    ];
    for (field, axes) in fields {
        for (axis, values) in axes.iter().enumerate() {
            let Some(k) = values.iter().position(|&v| !crate::limits::valid_value(v)) else {
                continue;
            };
            let v = values[k];
            let problem = if v.is_finite() {
                format!(
                    "{} is beyond the largest magnitude a log may hold ({:e}: squares of larger values overflow)",
                    crate::error::sig(v, 3),
                    crate::limits::MAX_ABS_VALUE
                )
            } else {
                format!("{v} is not a number a sensor measures")
            };
            let at = crate::error::At::Message {
                topic: s.topic.clone(),
                index: k + 1,
            };
            let column = format!("{field}.{}", noise::AXIS_NAMES[axis]);
            return Err(LogError::content(source, problem).at(at).in_column(&column));
        }
    }
    Ok(())
}

/// Messages in stamp order (bags are in receive order); two messages with one stamp are refused.
fn sort_by_stamp(s: &mut ImuSeries, source: &str) -> Result<()> {
    if s.t_ns.windows(2).all(|w| w[0] < w[1]) {
        return Ok(());
    }
    let mut idx: Vec<usize> = (0..s.t_ns.len()).collect();
    idx.sort_by_key(|&i| s.t_ns[i]);
    for w in idx.windows(2) {
        if s.t_ns[w[0]] == s.t_ns[w[1]] {
            return Err(LogError::content(source, format!(
                "topic {}: messages {} and {} have the same header.stamp ({} ns); expected one sample per stamp",
                s.topic,
                w[0].min(w[1]) + 1,
                w[0].max(w[1]) + 1,
                s.t_ns[w[0]]
            )));
        }
    }
    let take = |v: &Vec<f64>| idx.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    s.t_ns = idx.iter().map(|&i| s.t_ns[i]).collect();
    for a in 0..3 {
        s.gyro[a] = take(&s.gyro[a]);
        s.accel[a] = take(&s.accel[a]);
    }
    Ok(())
}

/// The topic to read among (topic, type) pairs: the one asked for, or the only IMU topic.
fn choose_topic(
    source: &str,
    topics: &[(String, String)],
    asked: Option<&str>,
    imu_type: &'static str,
) -> Result<String> {
    let imu: Vec<&String> = topics
        .iter()
        .filter(|(_, t)| t == imu_type)
        .map(|(n, _)| n)
        .collect();
    let listing = || {
        topics
            .iter()
            .map(|(n, t)| format!("{n} ({t})"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let problem = match asked {
        Some(t) if imu.iter().any(|n| *n == t) => return Ok(t.to_string()),
        Some(t) => Problem::NoSuchTopic {
            topic: t.to_string(),
            imu_type,
            topics: listing(),
        },
        None => match imu.as_slice() {
            [one] => return Ok(one.to_string()),
            [] if topics.is_empty() => Problem::Content(format!(
                "no {imu_type} topic: the file defines no topic at all (empty, or its chunks are damaged)"
            )),
            [] => Problem::Content(format!("no {imu_type} topic (topics: {})", listing())),
            many => Problem::SeveralTopics {
                imu_type,
                topics: many.iter().map(|s| s.to_string()).collect(),
            },
        },
    };
    Err(LogError::new(source, problem))
}

fn read_rosbag(path: &Path, source: &str, topic: Option<&str>) -> Result<ImuSeries> {
    use rosbag::{ChunkRecord, IndexRecord, MessageRecord, RosBag};
    let bad =
        |what: &str, e: &dyn std::fmt::Display| LogError::content(source, format!("{what}: {e}"));
    let bag = RosBag::new(path).map_err(|e| bad("not a readable ROS 1 bag", &e))?;
    // Connections (topic, type) from the index section.
    let mut conns: Vec<(u32, String, String)> = Vec::new();
    for r in bag.index_records() {
        if let IndexRecord::Connection(c) = r.map_err(|e| bad("bad index record", &e))? {
            conns.push((c.id, c.topic.to_string(), c.tp.to_string()));
        }
    }
    let topics: Vec<(String, String)> = conns
        .iter()
        .map(|(_, n, t)| (n.clone(), t.clone()))
        .collect();
    let chosen = choose_topic(source, &topics, topic, ROS1_TYPE)?;
    let ids: Vec<u32> = conns
        .iter()
        .filter(|(_, n, t)| *n == chosen && t == ROS1_TYPE)
        .map(|(id, _, _)| *id)
        .collect();
    let mut out = ImuSeries {
        topic: chosen,
        ..ImuSeries::default()
    };
    let mut k = 0usize;
    for r in bag.chunk_records() {
        let r = r.map_err(|e| bad("bad chunk record", &e))?;
        let ChunkRecord::Chunk(chunk) = r else {
            continue;
        };
        for m in chunk.messages() {
            let m = m.map_err(|e| bad("bad record in a chunk", &e))?;
            let MessageRecord::MessageData(d) = m else {
                continue;
            };
            if !ids.contains(&d.conn_id) {
                continue;
            }
            k += 1;
            let s = decode_ros1(d.data).ok_or_else(|| {
                let problem = format!(
                    "topic {}: message {k} is not a valid {ROS1_TYPE}",
                    out.topic
                );
                LogError::content(source, problem)
            })?;
            out.push(s);
        }
    }
    Ok(out)
}

fn read_mcap(path: &Path, source: &str, topic: Option<&str>) -> Result<ImuSeries> {
    use mcap::records::Record;
    use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
    use std::collections::BTreeMap;
    let file = std::fs::File::open(path)
        .map_err(|e| LogError::new(source, Problem::Unreadable).caused_by(e))?;
    // SAFETY: a read-only private mapping of a regular file this process holds open; the bytes
    // are only read (the hazard of a concurrent truncation is the one every mmap reader accepts).
    let map = unsafe { memmap2::Mmap::map(&file) }
        .map_err(|e| LogError::new(source, Problem::Unmappable).caused_by(e))?;
    // The crate's sans-io reader with a bound on record lengths: a damaged length field is an
    // error, not an attempt to allocate it (its MessageStream sets no bound). Chunk CRCs are
    // checked. Records in file order (mcap.dev/spec: schemas and channels before their use).
    let opts = LinearReaderOptions::default()
        .with_validate_chunk_crcs(true)
        .with_record_length_limit(map.len().max(1 << 30));
    let mut reader = LinearReader::new_with_options(opts);
    let mut bytes: &[u8] = &map;
    let mut schemas: BTreeMap<u16, String> = BTreeMap::new();
    // channel id -> (topic, schema name, message encoding)
    let mut channels: BTreeMap<u16, (String, String, String)> = BTreeMap::new();
    let mut samples: BTreeMap<u16, Vec<ImuSample>> = BTreeMap::new();
    let mut past_data_end = false;
    let bad = |e: &dyn std::fmt::Display| {
        LogError::content(source, format!("not a readable MCAP file: {e}"))
    };
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| bad(&e))? {
            LinearReadEvent::ReadRequest(n) => {
                let k = n.min(bytes.len());
                reader.insert(k).copy_from_slice(&bytes[..k]);
                reader.notify_read(k);
                bytes = &bytes[k..];
            }
            LinearReadEvent::Record { opcode, data } => {
                // 0x03 schema, 0x04 channel, 0x05 message, 0x0F data end (the summary after
                // it repeats schemas and channels).
                if past_data_end || !matches!(opcode, 0x03 | 0x04 | 0x05 | 0x0F) {
                    continue;
                }
                if !prefixes_fit(opcode, data) {
                    return Err(bad(
                        &"a length in a schema or channel record runs past the record",
                    ));
                }
                match mcap::parse_record(opcode, data).map_err(|e| bad(&e))? {
                    Record::DataEnd(_) => past_data_end = true,
                    Record::Schema { header, .. } => {
                        schemas.insert(header.id, header.name.clone());
                    }
                    Record::Channel(c) => {
                        let schema = schemas.get(&c.schema_id).cloned().unwrap_or_default();
                        channels
                            .insert(c.id, (c.topic.clone(), schema, c.message_encoding.clone()));
                    }
                    Record::Message { header, data } => {
                        let Some((topic, schema, encoding)) = channels.get(&header.channel_id)
                        else {
                            let problem = format!(
                                "a message refers to channel {}, never defined",
                                header.channel_id
                            );
                            return Err(LogError::content(source, problem));
                        };
                        if schema != ROS2_TYPE {
                            continue;
                        }
                        let v = samples.entry(header.channel_id).or_default();
                        if encoding != "cdr" {
                            let problem = format!("topic {topic}: message encoding {encoding:?}; expected \"cdr\" (ROS 2)");
                            return Err(LogError::content(source, problem));
                        }
                        let s = decode_cdr(&data).ok_or_else(|| {
                            let problem = format!(
                                "topic {topic}: message {} is not a valid {ROS2_TYPE}",
                                v.len() + 1
                            );
                            LogError::content(source, problem)
                        })?;
                        v.push(s);
                    }
                    _ => {}
                }
            }
        }
    }
    let mut topics: Vec<(String, String)> = Vec::new();
    for (t, schema, _) in channels.values() {
        let pair = (t.clone(), schema.clone());
        if !topics.contains(&pair) {
            topics.push(pair);
        }
    }
    let chosen = choose_topic(source, &topics, topic, ROS2_TYPE)?;
    let mut out = ImuSeries {
        topic: chosen,
        ..ImuSeries::default()
    };
    for (id, v) in samples {
        if channels[&id].0 == out.topic {
            for s in v {
                out.push(s);
            }
        }
    }
    Ok(out)
}

/// Little-endian reads with bounds checks.
struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
    /// Where alignment is counted from.
    origin: usize,
    big_endian: bool,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let s = self.b.get(self.pos..self.pos.checked_add(N)?)?;
        self.pos += N;
        s.try_into().ok()
    }
    fn u32(&mut self) -> Option<u32> {
        let b = self.take::<4>()?;
        Some(if self.big_endian {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        })
    }
    fn f64(&mut self) -> Option<f64> {
        let b = self.take::<8>()?;
        Some(if self.big_endian {
            f64::from_be_bytes(b)
        } else {
            f64::from_le_bytes(b)
        })
    }
    fn skip(&mut self, n: usize) -> Option<()> {
        self.pos = self.pos.checked_add(n)?;
        (self.pos <= self.b.len()).then_some(())
    }
    fn align(&mut self, n: usize) {
        let rel = self.pos - self.origin;
        self.pos += (n - rel % n) % n;
    }
    /// orientation, covariances, angular velocity and linear acceleration after the header.
    fn body(&mut self, t_ns: i64, align: bool) -> Option<ImuSample> {
        if align {
            self.align(8);
        }
        self.skip(8 * (4 + 9))?;
        let gyro = [self.f64()?, self.f64()?, self.f64()?];
        self.skip(8 * 9)?;
        let accel = [self.f64()?, self.f64()?, self.f64()?];
        self.skip(8 * 9)?;
        Some(ImuSample { t_ns, gyro, accel })
    }
}

/// Whether the length prefixes of an MCAP schema (0x03) or channel (0x04) record fit in the
/// record (mcap.dev/spec: strings and byte arrays are prefixed by their u32 length, the
/// channel's metadata map by its u32 byte length). The `mcap` crate reserves a prefix's length
/// before it reads: a damaged length of 4 GiB was a 4 GiB allocation (found by the `bag_reader`
/// fuzz target). Other records are read without such prefixes, or not at all.
fn prefixes_fit(opcode: u8, data: &[u8]) -> bool {
    fn field(r: &mut Reader) -> Option<()> {
        let n = r.u32()? as usize;
        r.skip(n)
    }
    let mut r = Reader {
        b: data,
        pos: 0,
        origin: 0,
        big_endian: false,
    };
    let fits = match opcode {
        // id; name, encoding, data
        0x03 => r
            .skip(2)
            .and_then(|_| field(&mut r))
            .and_then(|_| field(&mut r))
            .and_then(|_| field(&mut r)),
        // id, schema id; topic, message encoding; metadata: byte length, then key-value strings
        0x04 => (|| {
            r.skip(4)?;
            field(&mut r)?;
            field(&mut r)?;
            let end = (r.u32()? as usize).checked_add(r.pos)?;
            (end <= data.len()).then_some(())?;
            while r.pos < end {
                field(&mut r)?;
                field(&mut r)?;
            }
            Some(())
        })(),
        _ => Some(()),
    };
    fits.is_some()
}

/// A ROS 1 serialised sensor_msgs/Imu.
pub fn decode_ros1(b: &[u8]) -> Option<ImuSample> {
    let mut r = Reader {
        b,
        pos: 0,
        origin: 0,
        big_endian: false,
    };
    let _seq = r.u32()?;
    let secs = r.u32()?;
    let nsecs = r.u32()?;
    let len = r.u32()? as usize;
    r.skip(len)?;
    r.body(secs as i64 * 1_000_000_000 + nsecs as i64, false)
}

/// A CDR serialised sensor_msgs/msg/Imu (ROS 2).
pub fn decode_cdr(b: &[u8]) -> Option<ImuSample> {
    let big_endian = match b.get(..2)? {
        [0x00, 0x01] => false,
        [0x00, 0x00] => true,
        _ => return None,
    };
    let mut r = Reader {
        b,
        pos: 4,
        origin: 4,
        big_endian,
    };
    let sec = r.u32()? as i32;
    let nanosec = r.u32()?;
    let len = r.u32()? as usize;
    r.skip(len)?;
    r.body(sec as i64 * 1_000_000_000 + nanosec as i64, true)
}

/// The bytes of a ROS 1 sensor_msgs/Imu (for writers in tests and benchmarks).
pub fn encode_ros1(seq: u32, s: &ImuSample, frame_id: &str) -> Vec<u8> {
    let (secs, nsecs) = split_stamp(s.t_ns);
    let mut b = Vec::with_capacity(16 + frame_id.len() + 8 * 40);
    b.extend_from_slice(&seq.to_le_bytes());
    b.extend_from_slice(&(secs as u32).to_le_bytes());
    b.extend_from_slice(&nsecs.to_le_bytes());
    b.extend_from_slice(&(frame_id.len() as u32).to_le_bytes());
    b.extend_from_slice(frame_id.as_bytes());
    push_body(&mut b, s);
    b
}

/// The bytes of a ROS 2 sensor_msgs/msg/Imu in little-endian CDR.
pub fn encode_cdr(s: &ImuSample, frame_id: &str) -> Vec<u8> {
    let (secs, nsecs) = split_stamp(s.t_ns);
    let mut b = vec![0x00, 0x01, 0x00, 0x00];
    b.extend_from_slice(&(secs as i32).to_le_bytes());
    b.extend_from_slice(&nsecs.to_le_bytes());
    b.extend_from_slice(&(frame_id.len() as u32 + 1).to_le_bytes());
    b.extend_from_slice(frame_id.as_bytes());
    b.push(0);
    while (b.len() - 4) % 8 != 0 {
        b.push(0);
    }
    push_body(&mut b, s);
    b
}

fn split_stamp(t_ns: i64) -> (i64, u32) {
    (
        t_ns.div_euclid(1_000_000_000),
        t_ns.rem_euclid(1_000_000_000) as u32,
    )
}

fn push_body(b: &mut Vec<u8>, s: &ImuSample) {
    let mut f = |v: f64| b.extend_from_slice(&v.to_le_bytes());
    for v in [0.0, 0.0, 0.0, 1.0] {
        f(v);
    }
    for _ in 0..9 {
        f(0.0);
    }
    for v in s.gyro {
        f(v);
    }
    for _ in 0..9 {
        f(0.0);
    }
    for v in s.accel {
        f(v);
    }
    for _ in 0..9 {
        f(0.0);
    }
}

/// Write samples as a ROS 1 bag v2.0 (wiki.ros.org/Bags/Format/2.0): one uncompressed chunk
/// holding the connection and the messages, its index data, then the index section (connection
/// and chunk info records). For tests and benchmarks; `rosbag record` writes the same records.
pub fn write_rosbag(path: &Path, topic: &str, samples: &[ImuSample]) -> std::io::Result<()> {
    fn field(h: &mut Vec<u8>, name: &str, value: &[u8]) {
        h.extend_from_slice(&((name.len() + 1 + value.len()) as u32).to_le_bytes());
        h.extend_from_slice(name.as_bytes());
        h.push(b'=');
        h.extend_from_slice(value);
    }
    fn record(out: &mut Vec<u8>, header: &[u8], data: &[u8]) {
        out.extend_from_slice(&(header.len() as u32).to_le_bytes());
        out.extend_from_slice(header);
        out.extend_from_slice(&(data.len() as u32).to_le_bytes());
        out.extend_from_slice(data);
    }
    fn time(t_ns: i64) -> [u8; 8] {
        let (s, n) = split_stamp(t_ns);
        let mut b = [0u8; 8];
        b[..4].copy_from_slice(&(s as u32).to_le_bytes());
        b[4..].copy_from_slice(&n.to_le_bytes());
        b
    }
    let conn = 0u32.to_le_bytes();
    let connection = |out: &mut Vec<u8>| {
        let mut h = Vec::new();
        field(&mut h, "op", &[0x07]);
        field(&mut h, "conn", &conn);
        field(&mut h, "topic", topic.as_bytes());
        let mut d = Vec::new();
        field(&mut d, "topic", topic.as_bytes());
        field(&mut d, "type", ROS1_TYPE.as_bytes());
        field(&mut d, "md5sum", b"6a62c6daae103f4ff57a132d6f95cec2");
        field(&mut d, "message_definition", b"std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n");
        record(out, &h, &d);
    };
    // The chunk's content: the connection, then the messages (offsets kept for the index).
    let mut chunk = Vec::new();
    connection(&mut chunk);
    let mut offsets = Vec::with_capacity(samples.len());
    for (i, s) in samples.iter().enumerate() {
        offsets.push(chunk.len() as u32);
        let mut h = Vec::new();
        field(&mut h, "op", &[0x02]);
        field(&mut h, "conn", &conn);
        field(&mut h, "time", &time(s.t_ns));
        record(&mut chunk, &h, &encode_ros1(i as u32, s, "imu"));
    }
    let start = samples.iter().map(|s| s.t_ns).min().unwrap_or(0);
    let end = samples.iter().map(|s| s.t_ns).max().unwrap_or(0);
    let mut out = b"#ROSBAG V2.0\n".to_vec();
    // Bag header, padded to 4096 bytes; index_pos patched below.
    let header_at = out.len();
    let bag_header = |index_pos: u64| {
        let mut h = Vec::new();
        field(&mut h, "op", &[0x03]);
        field(&mut h, "index_pos", &index_pos.to_le_bytes());
        field(&mut h, "conn_count", &1u32.to_le_bytes());
        field(&mut h, "chunk_count", &1u32.to_le_bytes());
        let mut r = Vec::new();
        let pad = 4096 - 4 - h.len() - 4;
        record(&mut r, &h, &vec![b' '; pad]);
        r
    };
    out.extend_from_slice(&bag_header(0));
    let chunk_pos = out.len() as u64;
    let mut h = Vec::new();
    field(&mut h, "op", &[0x05]);
    field(&mut h, "compression", b"none");
    field(&mut h, "size", &(chunk.len() as u32).to_le_bytes());
    record(&mut out, &h, &chunk);
    // Index data of the chunk.
    let mut h = Vec::new();
    field(&mut h, "op", &[0x04]);
    field(&mut h, "ver", &1u32.to_le_bytes());
    field(&mut h, "conn", &conn);
    field(&mut h, "count", &(samples.len() as u32).to_le_bytes());
    let mut d = Vec::with_capacity(samples.len() * 12);
    for (s, off) in samples.iter().zip(&offsets) {
        d.extend_from_slice(&time(s.t_ns));
        d.extend_from_slice(&off.to_le_bytes());
    }
    record(&mut out, &h, &d);
    // Index section: the connection and the chunk info.
    let index_pos = out.len() as u64;
    connection(&mut out);
    let mut h = Vec::new();
    field(&mut h, "op", &[0x06]);
    field(&mut h, "ver", &1u32.to_le_bytes());
    field(&mut h, "chunk_pos", &chunk_pos.to_le_bytes());
    field(&mut h, "start_time", &time(start));
    field(&mut h, "end_time", &time(end));
    field(&mut h, "count", &1u32.to_le_bytes());
    let mut d = Vec::new();
    d.extend_from_slice(&conn);
    d.extend_from_slice(&(samples.len() as u32).to_le_bytes());
    record(&mut out, &h, &d);
    let patched = bag_header(index_pos);
    out[header_at..header_at + patched.len()].copy_from_slice(&patched);
    std::fs::write(path, out)
}

/// Write samples as a ROS 2 MCAP file (`mcap` crate; schema `sensor_msgs/msg/Imu` in `ros2msg`,
/// messages in `cdr`), as `ros2 bag record -s mcap` does, one channel per topic. For tests and
/// benchmarks.
pub fn write_mcap(
    path: &Path,
    topics: &[(&str, &[ImuSample])],
) -> std::result::Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut w = mcap::Writer::new(file)?;
    let schema = w.add_schema(
        ROS2_TYPE,
        "ros2msg",
        b"std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n",
    )?;
    for (topic, samples) in topics {
        let channel = w.add_channel(schema, topic, "cdr", &std::collections::BTreeMap::new())?;
        for (i, s) in samples.iter().enumerate() {
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: channel,
                    sequence: i as u32,
                    log_time: s.t_ns as u64,
                    publish_time: s.t_ns as u64,
                },
                &encode_cdr(s, "imu"),
            )?;
        }
    }
    w.finish()?;
    Ok(())
}
