//! The records of a ROS 1 bag, format 2.0 (<http://wiki.ros.org/Bags/Format/2.0>).
//!
//! A bag is the line `#ROSBAG V2.0`, then records: a header (fields `name=value`, each
//! with its length) and data, each with its length. The header's `op` says what the record
//! is: the bag header, a chunk (compressed records: connections and messages), a
//! connection (a topic and its type), a message, and index records that only help a reader
//! seek. [`scan`] reads the records in the order they were written, once, from any
//! [`Read`]: a bag of camera images many times the size of memory is read through without
//! keeping what is not asked for. It does not use the index at all, so a bag whose
//! recorder was stopped before it wrote one (`rosbag record` killed: a `.bag.active` file,
//! whose index position is zero) is read up to its last whole chunk, and
//! [`Summary::truncated`] says where it ended.

use std::collections::HashMap;
use std::io::{ErrorKind, Read};

use crate::error::{Error, Result};
use crate::msg::Encoding;

const MAGIC: &[u8] = b"#ROSBAG V2.0\n";
const OP_MESSAGE: u8 = 0x02;
const OP_BAG_HEADER: u8 = 0x03;
const OP_INDEX: u8 = 0x04;
const OP_CHUNK: u8 = 0x05;
const OP_CHUNK_INFO: u8 = 0x06;
const OP_CONNECTION: u8 = 0x07;

/// The largest record header read (bytes): a connection's header holds its message
/// definition, a few kilobytes to a few hundred; a length beyond this is a corrupt file,
/// not a header to allocate for.
const MAX_HEADER_BYTES: u32 = 64 << 20;

/// A topic as the bag records it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Connection {
    /// The connection's number, which its messages give.
    pub id: u32,
    /// The topic (`/audio`).
    pub topic: String,
    /// The message type (`audio_common_msgs/AudioData`).
    pub msg_type: String,
    /// How its messages are serialised.
    pub encoding: Encoding,
}

/// One message as [`scan`] hands it on.
#[derive(Clone, Copy, Debug)]
pub struct Message<'a> {
    /// Its connection.
    pub connection: &'a Connection,
    /// The time the recorder received it (ns since the epoch).
    pub time_ns: i64,
    /// Its serialised bytes (ROS 1 serialisation, little-endian).
    pub data: &'a [u8],
}

/// What [`scan`] saw beside the messages.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    /// Every connection, in the order they appeared.
    pub connections: Vec<Connection>,
    /// Messages per connection id.
    pub counts: HashMap<u32, usize>,
    /// The first and last message time per connection id (ns).
    pub spans: HashMap<u32, (i64, i64)>,
    /// `Some(offset)` when the file ends inside a record (a recording that was cut off):
    /// the byte at which the last whole record ended; every message before it was read.
    pub truncated: Option<u64>,
    /// The chunks' compressions seen (`none`, `bz2`, `lz4`).
    pub compressions: Vec<String>,
}

impl Summary {
    /// Counts a message of connection `id` at `time_ns` into its count and span.
    pub fn count(&mut self, id: u32, time_ns: i64) {
        *self.counts.entry(id).or_default() += 1;
        let span = self.spans.entry(id).or_insert((time_ns, time_ns));
        span.0 = span.0.min(time_ns);
        span.1 = span.1.max(time_ns);
    }
}

/// Reads every record of the bag `r` in order and hands each message to `visit`.
///
/// # Errors
/// A file that is not a ROS 1 bag of format 2.0, a record that does not parse, a chunk
/// that does not decompress, what `visit` returns, or the reader's I/O errors. A file cut
/// off inside a record is not an error ([`Summary::truncated`]).
pub fn scan<R: Read>(r: R, mut visit: impl FnMut(Message<'_>) -> Result<()>) -> Result<Summary> {
    let mut summary = Summary::default();
    scan_into(r, 0, &mut summary, &mut visit)?;
    Ok(summary)
}

/// [`scan`] of one file of a bag split into several (`rosbag record --split`), numbered
/// `file` (connection numbers are per file: a connection's [`Connection::id`] is `file`
/// in its upper 16 bits), into the `summary` of the whole bag.
///
/// # Errors
/// As [`scan`].
pub fn scan_into<R: Read>(
    mut r: R,
    file: u32,
    summary: &mut Summary,
    mut visit: impl FnMut(Message<'_>) -> Result<()>,
) -> Result<()> {
    let mut magic = [0u8; 13];
    let got = read_up_to(&mut r, &mut magic)?;
    if got < MAGIC.len() || magic != MAGIC {
        return Err(not_a_bag(&magic[..got]));
    }
    let mut by_id: HashMap<u32, Connection> = HashMap::new();
    let mut offset = MAGIC.len() as u64;
    loop {
        let record = match read_record(&mut r, offset)? {
            Next::Record(rec) => rec,
            Next::End => break,
            Next::Truncated => {
                summary.truncated = Some(offset);
                break;
            }
        };
        let start = offset;
        offset += record.len;
        match record.op {
            OP_CHUNK => {
                let compression = record.field_str("compression", start)?;
                let size = record.field_u32("size", start)? as usize;
                let data = decompress(&compression, record.data, size, start)?;
                if !summary.compressions.contains(&compression) {
                    summary.compressions.push(compression);
                }
                let mut inner: &[u8] = &data;
                let mut at = 0u64;
                loop {
                    let rec = match read_record(&mut inner, at)? {
                        Next::Record(rec) => rec,
                        Next::End => break,
                        Next::Truncated => {
                            return Err(Error::Corrupt {
                                offset: start,
                                what: format!(
                                    "the chunk's records end inside a record at its byte {at}"
                                ),
                            });
                        }
                    };
                    let rec_at = at;
                    at += rec.len;
                    handle(rec, start + rec_at, file, &mut by_id, summary, &mut visit)?;
                }
            }
            _ => handle(record, start, file, &mut by_id, summary, &mut visit)?,
        }
    }
    Ok(())
}

/// Handles one record outside a chunk's framing: a connection is kept, a message is
/// counted and handed on, the bag header and index records are passed over.
fn handle(
    rec: Record,
    offset: u64,
    file: u32,
    by_id: &mut HashMap<u32, Connection>,
    summary: &mut Summary,
    visit: &mut impl FnMut(Message<'_>) -> Result<()>,
) -> Result<()> {
    match rec.op {
        OP_CONNECTION => {
            let id = rec.field_u32("conn", offset)?;
            let topic = rec.field_str("topic", offset)?;
            let fields = parse_fields(&rec.data, offset)?;
            let msg_type = fields
                .iter()
                .find(|(k, _)| k == "type")
                .map(|(_, v)| String::from_utf8_lossy(v).into_owned())
                .ok_or_else(|| Error::Corrupt {
                    offset,
                    what: format!("connection {id} ({topic}) names no message type"),
                })?;
            if let std::collections::hash_map::Entry::Vacant(e) = by_id.entry(id) {
                let c = Connection {
                    id: (file << 16) | (id & 0xffff),
                    topic,
                    msg_type,
                    encoding: Encoding::Ros1,
                };
                summary.connections.push(c.clone());
                e.insert(c);
            }
        }
        OP_MESSAGE => {
            let id = rec.field_u32("conn", offset)?;
            let time = rec.field("time", offset)?;
            if time.len() != 8 {
                return Err(Error::Corrupt {
                    offset,
                    what: format!("a message's time has {} bytes, not 8", time.len()),
                });
            }
            let sec = u32::from_le_bytes(time[..4].try_into().expect("4 bytes"));
            let nsec = u32::from_le_bytes(time[4..].try_into().expect("4 bytes"));
            let time_ns = i64::from(sec) * 1_000_000_000 + i64::from(nsec);
            let connection = by_id.get(&id).ok_or_else(|| Error::Corrupt {
                offset,
                what: format!("a message on connection {id}, which no record before it defines"),
            })?;
            summary.count(connection.id, time_ns);
            visit(Message {
                connection,
                time_ns,
                data: &rec.data,
            })?;
        }
        OP_BAG_HEADER | OP_INDEX | OP_CHUNK_INFO => {}
        OP_CHUNK => {
            return Err(Error::Corrupt {
                offset,
                what: "a chunk inside a chunk".into(),
            });
        }
        op => {
            return Err(Error::Corrupt {
                offset,
                what: format!("unknown record op 0x{op:02x}"),
            });
        }
    }
    Ok(())
}

/// What a file that is not a ROS 1 bag of format 2.0 looks like, from its first bytes.
fn not_a_bag(head: &[u8]) -> Error {
    let what = if head.starts_with(b"#ROSBAG V") {
        let version = String::from_utf8_lossy(&head[9..]).trim().to_string();
        format!(
            "a ROS bag of format {version}, which only ROS's own tools still read (rosbag reindex/fix)"
        )
    } else if head.starts_with(b"\x89MCAP") {
        "an MCAP file (a ROS 2 bag): read it with iasm_bag::read_file, which tells the two apart"
            .into()
    } else if head.starts_with(b"SQLite format") {
        "an SQLite database (a ROS 2 bag's .db3): read it with iasm_bag::read_file, which tells them apart"
            .into()
    } else if head.is_empty() {
        "the file is empty".into()
    } else {
        "its first line is not #ROSBAG V2.0".into()
    };
    Error::NotABag { what }
}

/// One record: its op, its header's fields and its data.
struct Record {
    op: u8,
    fields: Vec<(String, Vec<u8>)>,
    data: Vec<u8>,
    /// Its length in the file, lengths included (bytes).
    len: u64,
}

enum Next {
    Record(Record),
    End,
    Truncated,
}

impl Record {
    fn field(&self, name: &str, offset: u64) -> Result<&[u8]> {
        self.fields
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_slice())
            .ok_or_else(|| Error::Corrupt {
                offset,
                what: format!("a record of op 0x{:02x} without its field {name}", self.op),
            })
    }

    fn field_u32(&self, name: &str, offset: u64) -> Result<u32> {
        let v = self.field(name, offset)?;
        let bytes: [u8; 4] = v.try_into().map_err(|_| Error::Corrupt {
            offset,
            what: format!("field {name} has {} bytes, not 4", v.len()),
        })?;
        Ok(u32::from_le_bytes(bytes))
    }

    fn field_str(&self, name: &str, offset: u64) -> Result<String> {
        Ok(String::from_utf8_lossy(self.field(name, offset)?).into_owned())
    }
}

/// Reads one record at `offset` (for messages only); [`Next::End`] at a clean end of
/// input, [`Next::Truncated`] when the input ends inside the record.
fn read_record<R: Read>(r: &mut R, offset: u64) -> Result<Next> {
    let mut len = [0u8; 4];
    match read_up_to(r, &mut len)? {
        0 => return Ok(Next::End),
        4 => {}
        _ => return Ok(Next::Truncated),
    }
    let header_len = u32::from_le_bytes(len);
    if header_len > MAX_HEADER_BYTES {
        return Err(Error::Corrupt {
            offset,
            what: format!("a record header of {header_len} bytes"),
        });
    }
    let Some(header) = read_exact_or_short(r, header_len)? else {
        return Ok(Next::Truncated);
    };
    if read_up_to(r, &mut len)? < 4 {
        return Ok(Next::Truncated);
    }
    let data_len = u32::from_le_bytes(len);
    let Some(data) = read_exact_or_short(r, data_len)? else {
        return Ok(Next::Truncated);
    };
    let fields = parse_fields(&header, offset)?;
    let op = match fields.iter().find(|(k, _)| k == "op") {
        Some((_, v)) if v.len() == 1 => v[0],
        Some(_) => {
            return Err(Error::Corrupt {
                offset,
                what: "an op field not one byte long".into(),
            });
        }
        None => {
            return Err(Error::Corrupt {
                offset,
                what: "a record without an op".into(),
            });
        }
    };
    Ok(Next::Record(Record {
        op,
        fields,
        data,
        len: 8 + u64::from(header_len) + u64::from(data_len),
    }))
}

/// A header's (or a connection record's data's) fields: each a length, then `name=value`.
fn parse_fields(mut bytes: &[u8], offset: u64) -> Result<Vec<(String, Vec<u8>)>> {
    let corrupt = |what: String| Error::Corrupt { offset, what };
    let mut fields = Vec::new();
    while !bytes.is_empty() {
        if bytes.len() < 4 {
            return Err(corrupt("a header field's length is cut off".into()));
        }
        let n = u32::from_le_bytes(bytes[..4].try_into().expect("4 bytes")) as usize;
        bytes = &bytes[4..];
        if n > bytes.len() {
            return Err(corrupt(format!(
                "a header field of {n} bytes where {} remain",
                bytes.len()
            )));
        }
        let (field, rest) = bytes.split_at(n);
        bytes = rest;
        let eq = field
            .iter()
            .position(|&b| b == b'=')
            .ok_or_else(|| corrupt("a header field without '='".into()))?;
        fields.push((
            String::from_utf8_lossy(&field[..eq]).into_owned(),
            field[eq + 1..].to_vec(),
        ));
    }
    Ok(fields)
}

/// A chunk's records, decompressed; `size` is their length as the chunk's header gives it
/// (no more than one byte beyond it is decompressed, so a corrupt chunk cannot fill the
/// memory).
fn decompress(compression: &str, data: Vec<u8>, size: usize, offset: u64) -> Result<Vec<u8>> {
    let corrupt = |what: String| Error::Corrupt { offset, what };
    let out = match compression {
        "none" => data,
        "bz2" => read_bounded(bzip2::read::BzDecoder::new(data.as_slice()), size as u64)
            .map_err(|e| corrupt(format!("a bz2 chunk that does not decompress: {e}")))?,
        "lz4" => read_bounded(
            lz4_flex::frame::FrameDecoder::new(data.as_slice()),
            size as u64,
        )
        .map_err(|e| corrupt(format!("an lz4 chunk that does not decompress: {e}")))?,
        other => {
            return Err(corrupt(format!(
                "a chunk compressed with {other:?}, which is not none, bz2 or lz4"
            )));
        }
    };
    if out.len() != size {
        return Err(corrupt(format!(
            "a {compression} chunk of {} bytes where its header says {size}",
            out.len()
        )));
    }
    Ok(out)
}

/// What the decoder `r` gives, but no more than a byte beyond `size` (a chunk's
/// decompressed length as its header gives it), so that a corrupt chunk cannot fill the
/// memory; the caller compares the length with `size`.
pub(crate) fn read_bounded(r: impl Read, size: u64) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    r.take(size + 1).read_to_end(&mut out)?;
    Ok(out)
}

/// Reads into `buf` until it is full or the input ends; the number of bytes read.
pub(crate) fn read_up_to<R: Read>(r: &mut R, buf: &mut [u8]) -> Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(e.into()),
        }
    }
    Ok(got)
}

/// `n` bytes, or `None` when the input ends first. Reads through `take`, so that a corrupt
/// length allocates only as much as the input holds.
fn read_exact_or_short<R: Read>(r: &mut R, n: u32) -> Result<Option<Vec<u8>>> {
    let mut out = Vec::new();
    r.by_ref().take(u64::from(n)).read_to_end(&mut out)?;
    Ok((out.len() == n as usize).then_some(out))
}
