//! ROS 2 bags in MCAP (`ros2 bag record`'s storage since ROS 2 Iron, and Jazzy's default).
//!
//! An MCAP file is a stream of records: schemas (a message type and its definition),
//! channels (a topic, its schema and how its messages are encoded) and messages (a channel,
//! a log time, the bytes), most of them inside chunks compressed with zstd or lz4. The
//! `mcap` crate (Foxglove's, which maintains the format) reads the records through its
//! sans-IO linear reader: front to back, from any [`Read`], one chunk in memory at a time.
//! The chunks are decompressed here, in pure Rust (ruzstd, lz4_flex), with their sizes
//! bounded: the reader's own zstd path spins forever on a chunk whose compressed size is
//! corrupt (mcap 0.24), and a robot's bag may end in any state.
//! Messages of channels encoded as `cdr` (ROS 2) or `ros1` are handed on as
//! [`crate::format`] hands on a ROS 1 bag's, the receipt time being the log time; other
//! encodings (JSON, Protobuf) are listed but not decoded. A file that ends inside a record
//! (a recorder that was killed) is read up to there, and [`Summary::truncated`] says so.
//!
//! A ROS 2 bag is a folder: `metadata.yaml` and one or more `.mcap` files (split by size or
//! duration), read in their order as one run ([`scan_files`]). Through Humble and Iron,
//! rosbag2 stored them in SQLite instead (`.db3`: a `topics` table and a `messages` table
//! of topic, time stamp and CDR bytes), read through SQLite itself ([`scan_sqlite`]:
//! rusqlite, SQLite built in), in time order.
//!
//! `ros2 bag record --compression-format zstd` compresses a bag in one of two ways, both
//! read here: `--compression-mode file` compresses each finished file whole
//! (`run_0.db3.zstd`, `run_0.mcap.zstd`), and `--compression-mode message` each message's
//! bytes as a zstd frame of their own. Compressed files are told by their first bytes (the
//! zstd frame's magic number) and read through a streaming decoder: an MCAP file front to
//! back as it decompresses; a SQLite file, which SQLite can only open as a file, first
//! decompressed into a temporary file that is removed after it is read ([`scan_files`]).
//! Compressed messages are told the same way, since a CDR message never begins with
//! that number (its first two bytes are its encapsulation, `00 00` or `00 01`).

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

use mcap::records::Record;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};

use crate::error::{Error, Result};
use crate::format::{Connection, Message, Summary, read_bounded, read_up_to};
use crate::msg::Encoding;

/// The longest record read (bytes): a camera image is a few megabytes; a length beyond this
/// is a corrupt file, not a record to allocate for.
const MAX_RECORD_BYTES: usize = 1 << 30;

/// Reads every record of the MCAP stream `r` and hands each message of a ROS channel to
/// `visit`; `file` numbers the file within its bag (channel ids are per file), and
/// `summary` gathers what is seen across the bag's files.
///
/// # Errors
/// A stream that is not MCAP, a record that does not parse or decompress, what `visit`
/// returns, or the reader's I/O errors; a stream cut off inside a record is not an error.
pub fn scan<R: Read>(
    mut r: R,
    file: u32,
    summary: &mut Summary,
    mut visit: impl FnMut(Message<'_>) -> Result<()>,
) -> Result<()> {
    // Chunks are decompressed here, not by the reader (mcap 0.24's zstd loop spins forever on
    // a chunk whose compressed size is corrupt).
    let options = LinearReaderOptions::default()
        .with_record_length_limit(MAX_RECORD_BYTES)
        .with_emit_chunks(true);
    let mut reader = LinearReader::new_with_options(options);
    let mut state = State::default();
    let mut read = 0u64;
    let mut at_eof = false;
    while let Some(event) = reader.next_event() {
        let event = match event {
            Ok(e) => e,
            Err(_) if at_eof => {
                // Cut off: everything before was read.
                summary.truncated = Some(read);
                break;
            }
            Err(e) if read == 0 || matches!(e, mcap::McapError::BadMagic) => {
                return Err(Error::NotABag {
                    what: format!("not an MCAP file ({e})"),
                });
            }
            Err(e) => {
                return Err(Error::Corrupt {
                    offset: read,
                    what: e.to_string(),
                });
            }
        };
        match event {
            LinearReadEvent::ReadRequest(_) if at_eof => {
                // It asks for more after the end: the file ends inside a record.
                summary.truncated = Some(read);
                break;
            }
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need);
                let n = loop {
                    match r.read(buf) {
                        Ok(n) => break n,
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                        Err(e) => return Err(e.into()),
                    }
                };
                read += n as u64;
                at_eof = n == 0;
                reader.notify_read(n);
            }
            LinearReadEvent::Record { data, opcode } => {
                let corrupt = |what: String| Error::Corrupt { offset: read, what };
                let record =
                    mcap::parse_record(opcode, data).map_err(|e| corrupt(e.to_string()))?;
                if let Record::Chunk { header, data } = record {
                    let records = decompress(&header, &data).map_err(corrupt)?;
                    for (op, body) in inner_records(&records).map_err(corrupt)? {
                        let record =
                            mcap::parse_record(op, body).map_err(|e| corrupt(e.to_string()))?;
                        state.take(record, file, summary, read, &mut visit)?;
                    }
                } else {
                    state.take(record, file, summary, read, &mut visit)?;
                }
            }
        }
    }
    Ok(())
}

/// The schemas and channels seen so far in one file.
#[derive(Default)]
struct State {
    schemas: HashMap<u16, String>,
    by_id: HashMap<u32, Connection>,
}

impl State {
    /// Keeps a schema or a channel, hands a message on.
    fn take(
        &mut self,
        record: Record<'_>,
        file: u32,
        summary: &mut Summary,
        offset: u64,
        visit: &mut impl FnMut(Message<'_>) -> Result<()>,
    ) -> Result<()> {
        match record {
            Record::Schema { header, .. } => {
                self.schemas.insert(header.id, header.name);
            }
            Record::Channel(ch) => {
                let id = (file << 16) | u32::from(ch.id);
                let schema = self.schemas.get(&ch.schema_id).cloned().unwrap_or_default();
                let (msg_type, encoding) = match ch.message_encoding.as_str() {
                    "cdr" => (schema, Encoding::Cdr),
                    "ros1" => (schema, Encoding::Ros1),
                    // Listed, but its messages are not handed on (no known kind).
                    other => (format!("{schema} ({other})"), Encoding::Cdr),
                };
                let c = Connection {
                    id,
                    topic: ch.topic,
                    msg_type,
                    encoding,
                };
                if !summary.connections.iter().any(|k| k.id == id) {
                    summary.connections.push(c.clone());
                }
                self.by_id.insert(id, c);
            }
            Record::Message { header, data } => {
                let id = (file << 16) | u32::from(header.channel_id);
                let connection = self.by_id.get(&id).ok_or_else(|| Error::Corrupt {
                    offset,
                    what: format!(
                        "a message on channel {}, which no record before it defines",
                        header.channel_id
                    ),
                })?;
                let time_ns = i64::try_from(header.log_time).unwrap_or(i64::MAX);
                summary.count(id, time_ns);
                let data = message_bytes(&data, connection, summary)?;
                visit(Message {
                    connection,
                    time_ns,
                    data: &data,
                })?;
            }
            _ => {}
        }
        Ok(())
    }
}

/// A chunk's records, decompressed: zstd (ruzstd) or lz4 frames (lz4_flex), no more than
/// the size its header gives plus a byte.
fn decompress(
    header: &mcap::records::ChunkHeader,
    data: &[u8],
) -> std::result::Result<Vec<u8>, String> {
    let size = header.uncompressed_size;
    if size > MAX_RECORD_BYTES as u64 {
        return Err(format!("a chunk of {size} bytes"));
    }
    let got = match header.compression.as_str() {
        "" => Ok(data.to_vec()),
        "zstd" => ruzstd::decoding::StreamingDecoder::new(data)
            .map_err(|e| std::io::Error::other(e.to_string()))
            .and_then(|d| read_bounded(d, size)),
        "lz4" => read_bounded(lz4_flex::frame::FrameDecoder::new(data), size),
        other => {
            return Err(format!(
                "a chunk compressed with {other:?}, which is not zstd or lz4"
            ));
        }
    };
    let out = got.map_err(|e| {
        format!(
            "a {} chunk that does not decompress: {e}",
            header.compression
        )
    })?;
    if out.len() as u64 != size {
        return Err(format!(
            "a chunk of {} bytes where its header says {size}",
            out.len()
        ));
    }
    // The writer's CRC-32 of the records (0: not computed).
    let crc = crc32fast::hash(&out);
    if header.uncompressed_crc != 0 && crc != header.uncompressed_crc {
        return Err(format!(
            "a chunk whose records' checksum is {crc:08x} where its header says {:08x}",
            header.uncompressed_crc
        ));
    }
    Ok(out)
}

/// The records of a chunk: each an opcode, a `u64` length and that many bytes.
fn inner_records(mut bytes: &[u8]) -> std::result::Result<Vec<(u8, &[u8])>, String> {
    let mut out = Vec::new();
    while !bytes.is_empty() {
        if bytes.len() < 9 {
            return Err("a chunk's last record is cut off".into());
        }
        let op = bytes[0];
        let len = u64::from_le_bytes(bytes[1..9].try_into().expect("8 bytes"));
        let rest = &bytes[9..];
        let len = usize::try_from(len)
            .ok()
            .filter(|&n| n <= rest.len())
            .ok_or_else(|| {
                format!(
                    "a record of {len} bytes in a chunk where {} remain",
                    rest.len()
                )
            })?;
        out.push((op, &rest[..len]));
        bytes = &rest[len..];
    }
    Ok(out)
}

/// How a ROS 2 bag's files store its messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// MCAP files.
    Mcap,
    /// SQLite databases (`.db3`).
    Sqlite,
    /// Not ROS 2: a ROS 1 bag, or the ROS 1 bags of a run that `rosbag record --split` cut
    /// into files.
    Ros1,
}

/// The files of a ROS 2 bag (a folder of `.mcap` or `.db3` files, split by size or
/// duration, in their order: `_0`, `_1`, ...; or of the same compressed file by file,
/// `.mcap.zstd` or `.db3.zstd`), or of a ROS 1 bag split by `rosbag record --split` (a
/// folder of `.bag` files), or a lone file told by its first bytes (decompressed, if it is
/// a zstd frame).
///
/// # Errors
/// A folder with none of these files; a file that cannot be read, or a compressed one
/// whose first bytes do not decompress.
pub fn bag_files(path: &Path) -> Result<(Storage, Vec<std::path::PathBuf>)> {
    if !path.is_dir() {
        let head = decompressed_head(path)?;
        let storage = if head.starts_with(b"\x89MCAP") {
            Storage::Mcap
        } else if head.starts_with(b"SQLite format 3") {
            Storage::Sqlite
        } else {
            // A ROS 1 bag, or what its reader will name as not one.
            Storage::Ros1
        };
        return Ok((storage, vec![path.to_path_buf()]));
    }
    // A ROS 2 bag's folder says which files are the bag: another run's file left beside
    // them is not read into this one.
    if let Some(listed) = listed_files(path)? {
        let name = |p: &std::path::PathBuf| {
            let n = p
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            n.strip_suffix(".zstd").map(str::to_owned).unwrap_or(n)
        };
        let storage = if listed.iter().all(|p| name(p).ends_with(".mcap")) {
            Storage::Mcap
        } else if listed.iter().all(|p| name(p).ends_with(".db3")) {
            Storage::Sqlite
        } else {
            return Err(Error::NotABag {
                what: format!(
                    "{}: its files are neither all MCAP nor all SQLite",
                    path.join("metadata.yaml").display()
                ),
            });
        };
        return Ok((storage, listed));
    }
    let (mut mcaps, mut db3s, mut bags) = (Vec::new(), Vec::new(), Vec::new());
    for entry in std::fs::read_dir(path)? {
        let p = entry?.path();
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let name = name.strip_suffix(".zstd").unwrap_or(&name);
        if name.ends_with(".mcap") {
            mcaps.push(p);
        } else if name.ends_with(".db3") {
            db3s.push(p);
        } else if name.ends_with(".bag") {
            bags.push(p);
        }
    }
    // A file decompressed beside its compressed original (`zstd -d` keeps it) is read once.
    for files in [&mut mcaps, &mut db3s, &mut bags] {
        let plain: Vec<std::path::PathBuf> = files
            .iter()
            .filter(|p| p.extension().is_none_or(|e| e != "zstd"))
            .cloned()
            .collect();
        files.retain(|p| {
            !plain.contains(&p.with_extension("")) || p.extension().is_none_or(|e| e != "zstd")
        });
    }
    let (storage, mut files) = match (mcaps.is_empty(), db3s.is_empty(), bags.is_empty()) {
        (false, _, _) => (Storage::Mcap, mcaps),
        (true, false, _) => (Storage::Sqlite, db3s),
        (true, true, false) => (Storage::Ros1, bags),
        (true, true, true) => {
            return Err(Error::NotABag {
                what: "a folder without .mcap, .db3 or .bag files (nor .mcap.zstd or .db3.zstd)"
                    .into(),
            });
        }
    };
    // Natural order: run_0, run_1, ..., run_10 (of the name without its extensions).
    files.sort_by_key(|p| {
        let name = p
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let name = name.strip_suffix(".zstd").unwrap_or(&name);
        let name = name.rsplit_once('.').map_or(name, |(stem, _)| stem);
        let digits: String = name
            .chars()
            .rev()
            .take_while(char::is_ascii_digit)
            .collect();
        let n: u64 = digits
            .chars()
            .rev()
            .collect::<String>()
            .parse()
            .unwrap_or(0);
        (
            name.len() - digits.len(),
            name[..name.len() - digits.len()].to_string(),
            n,
        )
    });
    Ok((storage, files))
}

/// The files `dir/metadata.yaml` names (rosbag2's `relative_file_paths`, in order), or
/// `None` without one (or one that names none).
///
/// # Errors
/// A metadata file that cannot be read, or that names a file the folder does not hold.
fn listed_files(dir: &Path) -> Result<Option<Vec<std::path::PathBuf>>> {
    let meta = dir.join("metadata.yaml");
    if !meta.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&meta)?;
    let mut lines = text
        .lines()
        .skip_while(|l| l.trim() != "relative_file_paths:");
    if lines.next().is_none() {
        return Ok(None);
    }
    let mut files = Vec::new();
    for line in lines {
        let Some(item) = line.trim().strip_prefix("- ") else {
            break;
        };
        let file = dir.join(item.trim().trim_matches(|c| c == '"' || c == '\''));
        if !file.is_file() {
            return Err(Error::NotABag {
                what: format!(
                    "{} names {}, which is not in the folder",
                    meta.display(),
                    file.display()
                ),
            });
        }
        files.push(file);
    }
    Ok((!files.is_empty()).then_some(files))
}

/// The first bytes of a zstd frame (RFC 8878), little-endian `0xFD2FB528`.
const ZSTD_MAGIC: [u8; 4] = [0x28, 0xB5, 0x2F, 0xFD];

/// Whether the file at `path` is zstd-compressed (begins with a zstd frame).
fn is_zstd(path: &Path) -> Result<bool> {
    let mut head = [0u8; 4];
    let n = read_up_to(&mut std::fs::File::open(path)?, &mut head)?;
    Ok(head[..n] == ZSTD_MAGIC)
}

/// The first 16 bytes of the file at `path`, decompressed if it is zstd-compressed (fewer
/// if it is shorter).
fn decompressed_head(path: &Path) -> Result<Vec<u8>> {
    let mut head = [0u8; 16];
    let n = if is_zstd(path)? {
        let f = BufReader::new(std::fs::File::open(path)?);
        read_up_to(&mut zstd_reader(f, path)?, &mut head).map_err(|e| decompress_error(e, path))?
    } else {
        read_up_to(&mut std::fs::File::open(path)?, &mut head)?
    };
    Ok(head[..n].to_vec())
}

/// The decompressed stream of a zstd-compressed file: its frames one after another (a
/// compressor may write a large file as several).
struct ZstdFrames<R: BufRead> {
    frame: Option<ruzstd::decoding::StreamingDecoder<R, ruzstd::decoding::FrameDecoder>>,
}

/// A reader of the zstd-compressed `r` (the file at `path`, for its error).
fn zstd_reader<R: BufRead>(r: R, path: &Path) -> Result<ZstdFrames<R>> {
    let frame = ruzstd::decoding::StreamingDecoder::new(r).map_err(|e| Error::Decompress {
        path: path.to_path_buf(),
        what: e.to_string(),
    })?;
    Ok(ZstdFrames { frame: Some(frame) })
}

/// A decoder's error inside [`ZstdFrames`]' I/O errors, told from the file's own I/O
/// errors by [`decompress_error`].
#[derive(Debug)]
struct Undecodable(String);

impl std::fmt::Display for Undecodable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Undecodable {}

/// `e`, or [`Error::Decompress`] naming `path` when `e` is a decoder's error.
fn decompress_error(e: impl Into<Error>, path: &Path) -> Error {
    match e.into() {
        Error::Io(io) if io.get_ref().is_some_and(|i| i.is::<Undecodable>()) => Error::Decompress {
            path: path.to_path_buf(),
            what: io.to_string(),
        },
        e => e,
    }
}

impl<R: BufRead> Read for ZstdFrames<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        loop {
            let Some(frame) = self.frame.as_mut() else {
                return Ok(0);
            };
            let n = frame
                .read(buf)
                .map_err(|e| std::io::Error::other(Undecodable(e.to_string())))?;
            if n > 0 || buf.is_empty() {
                return Ok(n);
            }
            // The frame ended: another may follow.
            let mut rest = self.frame.take().expect("a frame").into_inner();
            if rest.fill_buf()?.is_empty() {
                return Ok(0);
            }
            self.frame = Some(
                ruzstd::decoding::StreamingDecoder::new(rest)
                    .map_err(|e| std::io::Error::other(Undecodable(e.to_string())))?,
            );
        }
    }
}

/// A message's bytes as its type serialises them: those of a bag compressed message by
/// message (`ros2 bag record --compression-mode message`) are each a zstd frame,
/// decompressed here (to at most [`MAX_RECORD_BYTES`]); others are handed on as they are.
/// `summary` has counted the message already (its number on the topic, for the error).
///
/// # Errors
/// A frame that does not decompress, or decompresses to more than the bound.
fn message_bytes<'a>(
    data: &'a [u8],
    connection: &Connection,
    summary: &Summary,
) -> Result<Cow<'a, [u8]>> {
    // rosbag2 compresses CDR messages; a ROS 1 message in MCAP begins with its own fields.
    if connection.encoding != Encoding::Cdr || !data.starts_with(&ZSTD_MAGIC) {
        return Ok(Cow::Borrowed(data));
    }
    let error = |what: String| Error::Message {
        topic: connection.topic.clone(),
        msg_type: connection.msg_type.clone(),
        index: summary.counts.get(&connection.id).copied().unwrap_or(0),
        what,
    };
    let out = ZstdFrames {
        frame: Some(ruzstd::decoding::StreamingDecoder::new(data).map_err(|e| {
            error(format!(
                "a zstd-compressed message that does not decompress ({e})"
            ))
        })?),
    };
    let out = read_bounded(out, MAX_RECORD_BYTES as u64).map_err(|e| {
        error(format!(
            "a zstd-compressed message that does not decompress ({e})"
        ))
    })?;
    if out.len() > MAX_RECORD_BYTES {
        return Err(error(format!(
            "a zstd-compressed message of more than {MAX_RECORD_BYTES} bytes"
        )));
    }
    Ok(Cow::Owned(out))
}

/// Scans the files of a bag ([`bag_files`]: a ROS 1 bag, or a folder or file of a ROS 2
/// bag or of a split ROS 1 run) as one run; files compressed whole with zstd are
/// decompressed as they are read (a SQLite file into a temporary file first).
///
/// # Errors
/// As [`bag_files`], [`scan`] and [`scan_sqlite`]; a file that cannot be opened; a
/// compressed file that does not decompress, or a SQLite one that cannot be written out
/// to the temporary folder.
pub fn scan_files(
    path: &Path,
    mut visit: impl FnMut(Message<'_>) -> Result<()>,
) -> Result<Summary> {
    let mut summary = Summary::default();
    let (storage, files) = bag_files(path)?;
    for (k, file) in files.iter().enumerate() {
        let k = u32::try_from(k).map_err(|_| Error::Config("more than 2^16 files".into()))?;
        // The file's bytes, decompressed if they are compressed; the caller buffers them.
        let compressed = is_zstd(file)?;
        let open = || -> Result<Box<dyn Read>> {
            let f = std::fs::File::open(file)?;
            Ok(if compressed {
                Box::new(zstd_reader(BufReader::new(f), file)?)
            } else {
                Box::new(f)
            })
        };
        let read = match storage {
            Storage::Mcap => scan(
                BufReader::with_capacity(1 << 20, open()?),
                k,
                &mut summary,
                &mut visit,
            ),
            Storage::Sqlite if compressed => {
                let tmp = decompressed_copy(open()?, file)?;
                scan_sqlite(tmp.path(), k, &mut summary, &mut visit)
            }
            Storage::Sqlite => scan_sqlite(file, k, &mut summary, &mut visit),
            Storage::Ros1 => crate::format::scan_into(
                BufReader::with_capacity(1 << 20, open()?),
                k,
                &mut summary,
                &mut visit,
            ),
        };
        read.map_err(|e| decompress_error(e, file))?;
        if summary.truncated.is_some() {
            break;
        }
    }
    Ok(summary)
}

/// The decompressed stream `from` (of the file `file`) in a temporary file, removed when
/// it is dropped: SQLite opens files only.
///
/// # Errors
/// A stream that does not decompress ([`Error::Decompress`]); the temporary file cannot be
/// made or written (the temporary folder full), named.
fn decompressed_copy(mut from: impl Read, file: &Path) -> Result<tempfile::NamedTempFile> {
    let mut tmp = tempfile::Builder::new()
        .prefix("iasm-bag-")
        .suffix(".db3")
        .tempfile()?;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = match from.read(&mut buf) {
            Ok(0) => return Ok(tmp),
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(decompress_error(e, file)),
        };
        tmp.as_file_mut().write_all(&buf[..n]).map_err(|e| {
            std::io::Error::new(
                e.kind(),
                format!(
                    "writing {} decompressed to {}: {e}",
                    file.display(),
                    tmp.path().display()
                ),
            )
        })?;
    }
}

/// Reads the messages of one rosbag2 SQLite file (`topics`: id, name, type,
/// serialization format; `messages`: topic id, time stamp, data), in time order, and hands
/// each on; `file` numbers it within its bag, as for [`scan`].
///
/// # Errors
/// A database that SQLite cannot open or read (not rosbag2's tables, a corrupt page),
/// or what `visit` returns.
pub fn scan_sqlite(
    path: &Path,
    file: u32,
    summary: &mut Summary,
    visit: &mut impl FnMut(Message<'_>) -> Result<()>,
) -> Result<()> {
    use rusqlite::{Connection as Db, OpenFlags};
    let sql = |e: rusqlite::Error| Error::Database(e.to_string());
    let db = Db::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(sql)?;
    let mut by_id: HashMap<i64, Connection> = HashMap::new();
    let mut topics = db
        .prepare("SELECT id, name, type, serialization_format FROM topics")
        .map_err(sql)?;
    let mut rows = topics.query([]).map_err(sql)?;
    while let Some(row) = rows.next().map_err(sql)? {
        let tid: i64 = row.get(0).map_err(sql)?;
        let name: String = row.get(1).map_err(sql)?;
        let ty: String = row.get(2).map_err(sql)?;
        let format: String = row.get(3).map_err(sql)?;
        let id = (file << 16) | (tid as u32 & 0xffff);
        let (msg_type, encoding) = match format.as_str() {
            "cdr" => (ty, Encoding::Cdr),
            other => (format!("{ty} ({other})"), Encoding::Cdr),
        };
        let c = Connection {
            id,
            topic: name,
            msg_type,
            encoding,
        };
        if !summary.connections.iter().any(|k| k.id == id) {
            summary.connections.push(c.clone());
        }
        by_id.insert(tid, c);
    }
    let mut messages = db
        .prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id")
        .map_err(sql)?;
    let mut rows = messages.query([]).map_err(sql)?;
    while let Some(row) = rows.next().map_err(sql)? {
        let tid: i64 = row.get(0).map_err(sql)?;
        let time_ns: i64 = row.get(1).map_err(sql)?;
        let data = row
            .get_ref(2)
            .map_err(sql)?
            .as_blob()
            .map_err(|e| Error::Database(e.to_string()))?;
        let connection = by_id.get(&tid).ok_or_else(|| {
            Error::Database(format!(
                "a message of topic {tid}, which the topics table does not list"
            ))
        })?;
        summary.count(connection.id, time_ns);
        let data = message_bytes(data, connection, summary)?;
        visit(Message {
            connection,
            time_ns,
            data: &data,
        })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn connection(encoding: Encoding) -> Connection {
        Connection {
            id: 1,
            topic: "/audio".into(),
            msg_type: "audio_common_msgs/msg/AudioData".into(),
            encoding,
        }
    }

    #[test]
    fn a_compressed_cdr_message_is_decompressed_and_a_ros1_one_left_as_it_is() {
        // A CDR message (encapsulation 00 01 00 00, then its fields), as rosbag2's
        // message mode stores it: one zstd frame.
        let cdr: Vec<u8> = [0u8, 1, 0, 0].into_iter().chain(0..=200).collect();
        let frame = ruzstd::encoding::compress_to_vec(
            &cdr[..],
            ruzstd::encoding::CompressionLevel::Fastest,
        );
        assert!(frame.starts_with(&ZSTD_MAGIC));
        let summary = Summary::default();
        let got = message_bytes(&frame, &connection(Encoding::Cdr), &summary).unwrap();
        assert_eq!(&got[..], &cdr[..]);
        // Uncompressed CDR passes through untouched.
        let got = message_bytes(&cdr, &connection(Encoding::Cdr), &summary).unwrap();
        assert!(matches!(got, Cow::Borrowed(_)));
        // A ROS 1 message whose first field happens to hold the magic is its own bytes.
        let got = message_bytes(&frame, &connection(Encoding::Ros1), &summary).unwrap();
        assert_eq!(&got[..], &frame[..]);
        // A frame cut short is an error naming the topic.
        let e = message_bytes(
            &frame[..frame.len() / 2],
            &connection(Encoding::Cdr),
            &summary,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("/audio") && e.contains("zstd"), "{e}");
    }
}
