//! The message types a robot run's audio and poses come in, decoded from their ROS 1
//! serialisation (little-endian; a string or a variable array is a `u32` length and its
//! elements; a fixed array is its elements; a time is `u32` seconds and `u32` nanoseconds).
//!
//! Audio: `audio_common_msgs/AudioData` (`uint8[] data`: interleaved frames, as ROS's
//! `audio_capture` publishes them), `audio_common_msgs/AudioDataStamped` (a header and
//! one), and `audio_common_msgs/AudioInfo`, which says their channels, rate and sample
//! format; and `audio_common_msgs/AudioStamped` of the ROS 2 `audio_common` of
//! `audio_capturer_node`, a package of the same name whose messages carry their own format
//! and their samples in typed arrays. Poses: `nav_msgs/Odometry`, `geometry_msgs/PoseStamped`,
//! `geometry_msgs/PoseWithCovarianceStamped` (AMCL's `/amcl_pose`) and
//! `geometry_msgs/Pose2D`. The robot's own map: `nav_msgs/OccupancyGrid`. Each message
//! must decode to its last byte, so that a type of the same name but another definition is
//! an error, not numbers read from the wrong place.

use geom::Pose;

/// A message type this crate reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `audio_common_msgs/AudioData`.
    AudioData,
    /// `audio_common_msgs/AudioDataStamped`.
    AudioDataStamped,
    /// `audio_common_msgs/AudioStamped` (the ROS 2 `audio_common` of `audio_capturer_node`):
    /// a header, the format, and the samples in a typed array.
    AudioStamped,
    /// `audio_common_msgs/AudioInfo`.
    AudioInfo,
    /// `nav_msgs/Odometry`.
    Odometry,
    /// `geometry_msgs/PoseStamped`.
    PoseStamped,
    /// `geometry_msgs/PoseWithCovarianceStamped`.
    PoseWithCovarianceStamped,
    /// `geometry_msgs/Pose2D`.
    Pose2D,
    /// `nav_msgs/OccupancyGrid`.
    OccupancyGrid,
    /// `tf2_msgs/TFMessage` (`/tf`, `/tf_static`).
    Tf,
}

impl Kind {
    /// The kind of a type name as a bag gives it (`nav_msgs/Odometry`; ROS 2's
    /// `nav_msgs/msg/Odometry` is taken too); `None` for a type this crate does not read.
    pub fn of(msg_type: &str) -> Option<Self> {
        let name = msg_type.replacen("/msg/", "/", 1);
        Some(match name.as_str() {
            "audio_common_msgs/AudioData" => Self::AudioData,
            "audio_common_msgs/AudioDataStamped" => Self::AudioDataStamped,
            "audio_common_msgs/AudioStamped" => Self::AudioStamped,
            "audio_common_msgs/AudioInfo" => Self::AudioInfo,
            "nav_msgs/Odometry" => Self::Odometry,
            "geometry_msgs/PoseStamped" => Self::PoseStamped,
            "geometry_msgs/PoseWithCovarianceStamped" => Self::PoseWithCovarianceStamped,
            "geometry_msgs/Pose2D" => Self::Pose2D,
            "nav_msgs/OccupancyGrid" => Self::OccupancyGrid,
            "tf2_msgs/TFMessage" => Self::Tf,
            _ => return None,
        })
    }

    /// Whether its messages are audio samples.
    pub fn is_audio(self) -> bool {
        matches!(
            self,
            Self::AudioData | Self::AudioDataStamped | Self::AudioStamped
        )
    }

    /// Whether its messages are poses.
    pub fn is_pose(self) -> bool {
        matches!(
            self,
            Self::Odometry | Self::PoseStamped | Self::PoseWithCovarianceStamped | Self::Pose2D
        )
    }
}

/// The format an `AudioStamped` message gives its own samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Embedded {
    /// Channels per frame.
    pub channels: i32,
    /// Frames per second.
    pub rate: i32,
    /// The sample format, by the array that holds the samples: `F32LE`, `S32LE`, `S16LE`,
    /// `S8` or `U8`.
    pub sample: &'static str,
}

/// An audio message: its stamp, its samples' bytes (interleaved frames), and for
/// `AudioStamped` their format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AudioChunk<'a> {
    /// The header's stamp (ns); `None` for `AudioData` or a stamp of zero.
    pub stamp_ns: Option<i64>,
    /// The samples, little-endian.
    pub data: &'a [u8],
    /// The format the message gives (only `AudioStamped` does).
    pub format: Option<Embedded>,
}

/// `audio_common_msgs/AudioInfo`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AudioInfo {
    /// Channels per frame.
    pub channels: u8,
    /// Frames per second.
    pub sample_rate: u32,
    /// The sample format (GStreamer's names: `S16LE`, `S24LE`, `S32LE`, `F32LE`, ...).
    pub sample_format: String,
    /// Bits per second.
    pub bitrate: u32,
    /// `wave` for raw PCM, or a compressed coding (`mp3`).
    pub coding_format: String,
}

/// A pose message: the robot's pose and the time and frame its header gives.
#[derive(Clone, Debug, PartialEq)]
pub struct StampedPose {
    /// The header's stamp (ns since the epoch); `None` for a type without a header or a
    /// stamp of zero (a publisher that does not stamp).
    pub stamp_ns: Option<i64>,
    /// The header's frame (`map`, `odom`); `None` for a type without a header.
    pub frame_id: Option<String>,
    /// The pose in the plane: position, and heading as the yaw of the orientation.
    pub pose: Pose,
}

/// One transform of a `tf2_msgs/TFMessage`: the child frame's pose in the parent's.
#[derive(Clone, Debug, PartialEq)]
pub struct Transform {
    /// Its stamp (ns since the epoch); `None` when zero.
    pub stamp_ns: Option<i64>,
    /// The parent frame.
    pub parent: String,
    /// The child frame.
    pub child: String,
    /// The child's pose in the parent, in the plane.
    pub pose: Pose,
}

/// `nav_msgs/OccupancyGrid`: a robot's map of its surroundings.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// The frame it is given in (`map`).
    pub frame_id: String,
    /// The side of a cell (m), as the message gives it (`float32`).
    pub resolution: f32,
    /// Cells per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The pose of cell (0, 0)'s outer corner in the frame.
    pub origin: Pose,
    /// Row-major from the origin's row: -1 unknown, else the occupancy in percent.
    pub data: Vec<i8>,
}

/// How a message's fields are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// ROS 1: little-endian, packed; a header has a sequence number.
    Ros1,
    /// ROS 2's CDR (little-endian): a 4-byte encapsulation header, then each primitive
    /// aligned to its size from the header's end; a string's length counts its terminating
    /// NUL; a header has no sequence number.
    Cdr,
}

/// Reads serialised fields from a message's bytes.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
    encoding: Encoding,
}

impl<'a> Cursor<'a> {
    /// A cursor at the first field; for CDR, after the encapsulation header, which must say
    /// little-endian CDR.
    fn new(bytes: &'a [u8], encoding: Encoding) -> Result<Self, String> {
        match encoding {
            Encoding::Ros1 => Ok(Self {
                bytes,
                at: 0,
                encoding,
            }),
            Encoding::Cdr => match bytes {
                [0, 1, _, _, ..] => Ok(Self {
                    bytes: &bytes[4..],
                    at: 0,
                    encoding,
                }),
                [0, 0, _, _, ..] => Err("big-endian CDR, which ROS 2 does not write".into()),
                [a, b, ..] => Err(format!(
                    "a CDR encapsulation of 0x{a:02x}{b:02x}, not little-endian CDR"
                )),
                _ => Err("too short for a CDR message".into()),
            },
        }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let rest = self.bytes.len() - self.at;
        if n > rest {
            return Err(format!(
                "ends at byte {} where {n} more bytes were to follow",
                self.bytes.len()
            ));
        }
        let out = &self.bytes[self.at..self.at + n];
        self.at += n;
        Ok(out)
    }

    /// In CDR, moves to the next multiple of `n` (a primitive's size).
    fn align(&mut self, n: usize) -> Result<(), String> {
        if self.encoding == Encoding::Cdr {
            let pad = (n - self.at % n) % n;
            self.take(pad)?;
        }
        Ok(())
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        self.align(N)?;
        Ok(self.take(N)?.try_into().expect("N bytes"))
    }

    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array()?))
    }

    fn f32(&mut self) -> Result<f32, String> {
        Ok(f32::from_le_bytes(self.array()?))
    }

    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.array()?))
    }

    /// A `uint8[]` or `int8[]`: a count and the bytes.
    fn bytes(&mut self) -> Result<&'a [u8], String> {
        let n = self.u32()? as usize;
        self.take(n)
    }

    /// A sequence of `width`-byte numbers, as its bytes: a count, then (in CDR aligned to
    /// `width`) the elements.
    fn numbers(&mut self, width: usize) -> Result<&'a [u8], String> {
        let n = self.u32()? as usize;
        if n == 0 {
            return Ok(&[]);
        }
        self.align(width)?;
        let len = n
            .checked_mul(width)
            .ok_or_else(|| format!("{n} elements of {width} bytes"))?;
        self.take(len)
    }

    fn string(&mut self) -> Result<String, String> {
        let mut b = self.bytes()?;
        if self.encoding == Encoding::Cdr {
            // CDR counts the terminating NUL.
            match b.split_last() {
                Some((0, rest)) => b = rest,
                _ => return Err("a CDR string without its terminating NUL".into()),
            }
        }
        Ok(String::from_utf8_lossy(b).into_owned())
    }

    /// A `std_msgs/Header`'s stamp (`None` when zero) and frame (ROS 1's seq passed over).
    fn header(&mut self) -> Result<(Option<i64>, String), String> {
        if self.encoding == Encoding::Ros1 {
            self.u32()?;
        }
        // ROS 1: u32 seconds; ROS 2: i32 seconds (times before 1970 are not a robot's).
        let sec = self.u32()?;
        let nsec = self.u32()?;
        let frame = self.string()?;
        let ns = i64::from(sec) * 1_000_000_000 + i64::from(nsec);
        Ok(((ns != 0).then_some(ns), frame))
    }

    /// A `geometry_msgs/Pose` in the plane: x, y and the orientation's yaw.
    fn pose(&mut self) -> Result<Pose, String> {
        let x = self.f64()?;
        let y = self.f64()?;
        self.f64()?;
        let [qx, qy, qz, qw] = [self.f64()?, self.f64()?, self.f64()?, self.f64()?];
        let norm = (qx * qx + qy * qy + qz * qz + qw * qw).sqrt();
        if !(norm > 0.5 && norm < 1.5) {
            return Err(format!(
                "an orientation quaternion of norm {norm:.3} (x {qx}, y {qy}, z {qz}, w {qw}), not a rotation"
            ));
        }
        let yaw = (2.0 * (qw * qz + qx * qy)).atan2(1.0 - 2.0 * (qy * qy + qz * qz));
        Ok(Pose::new(x, y, yaw))
    }

    fn skip_f64s(&mut self, n: usize) -> Result<(), String> {
        self.align(8)?;
        self.take(8 * n).map(|_| ())
    }

    /// Every byte read (CDR may pad the end to a multiple of 4).
    fn done(self) -> Result<(), String> {
        match self.bytes.len() - self.at {
            0 => Ok(()),
            n if self.encoding == Encoding::Cdr
                && n < 4
                && self.bytes[self.at..].iter().all(|&b| b == 0) =>
            {
                Ok(())
            }
            n => Err(format!(
                "{n} bytes left over after its last field: not the message definition this \
                 type has in ROS"
            )),
        }
    }
}

/// An audio message's stamp (`None` for `AudioData`, which has none, or a zero stamp) and
/// its sample bytes.
///
/// # Errors
/// Bytes that are not a message of `kind` (a text saying why).
pub fn audio(kind: Kind, encoding: Encoding, bytes: &[u8]) -> Result<AudioChunk<'_>, String> {
    let mut c = Cursor::new(bytes, encoding)?;
    let stamp_ns = match kind {
        Kind::AudioData => None,
        Kind::AudioDataStamped | Kind::AudioStamped => c.header()?.0,
        other => return Err(format!("{other:?} is not an audio message")),
    };
    if kind != Kind::AudioStamped {
        let data = c.bytes()?;
        c.done()?;
        return Ok(AudioChunk {
            stamp_ns,
            data,
            format: None,
        });
    }
    // AudioInfo { int32 format, channels, rate, chunk }, then AudioData { float32[],
    // int32[], int16[], int8[], uint8[] }, one of them filled.
    let _format = c.u32()?;
    let channels = c.u32()? as i32;
    let rate = c.u32()? as i32;
    let _chunk = c.u32()?;
    let arrays = [
        ("F32LE", c.numbers(4)?),
        ("S32LE", c.numbers(4)?),
        ("S16LE", c.numbers(2)?),
        ("S8", c.numbers(1)?),
        ("U8", c.numbers(1)?),
    ];
    c.done()?;
    let filled: Vec<&(&str, &[u8])> = arrays.iter().filter(|a| !a.1.is_empty()).collect();
    let (sample, data) = match filled.as_slice() {
        [] => ("S16LE", &[][..]),
        [(name, data)] => (*name, *data),
        _ => return Err("samples in more than one of its arrays".into()),
    };
    Ok(AudioChunk {
        stamp_ns,
        data,
        format: Some(Embedded {
            channels,
            rate,
            sample,
        }),
    })
}

/// An `AudioInfo` message.
///
/// # Errors
/// Bytes that are not one.
pub fn audio_info(encoding: Encoding, bytes: &[u8]) -> Result<AudioInfo, String> {
    let mut c = Cursor::new(bytes, encoding)?;
    let info = AudioInfo {
        channels: c.u8()?,
        sample_rate: c.u32()?,
        sample_format: c.string()?,
        bitrate: c.u32()?,
        coding_format: c.string()?,
    };
    c.done()?;
    Ok(info)
}

/// A pose message of `kind`.
///
/// # Errors
/// Bytes that are not a message of `kind`, or an orientation that is not a rotation.
pub fn pose(kind: Kind, encoding: Encoding, bytes: &[u8]) -> Result<StampedPose, String> {
    let mut c = Cursor::new(bytes, encoding)?;
    let ((stamp_ns, frame_id), pose) = match kind {
        Kind::Odometry => {
            let (stamp, frame) = c.header()?;
            c.bytes()?; // child_frame_id
            let pose = c.pose()?;
            c.skip_f64s(36 + 6 + 36)?; // covariance, twist, its covariance
            ((stamp, Some(frame)), pose)
        }
        Kind::PoseStamped => {
            let (stamp, frame) = c.header()?;
            ((stamp, Some(frame)), c.pose()?)
        }
        Kind::PoseWithCovarianceStamped => {
            let (stamp, frame) = c.header()?;
            let pose = c.pose()?;
            c.skip_f64s(36)?;
            ((stamp, Some(frame)), pose)
        }
        Kind::Pose2D => {
            let (x, y, theta) = (c.f64()?, c.f64()?, c.f64()?);
            ((None, None), Pose::new(x, y, theta))
        }
        other => return Err(format!("{other:?} is not a pose message")),
    };
    c.done()?;
    if !stamp_pose_finite(&pose) {
        return Err(format!(
            "a pose that is not finite ({}, {}, {})",
            pose.x, pose.y, pose.theta
        ));
    }
    Ok(StampedPose {
        stamp_ns,
        frame_id,
        pose,
    })
}

/// An `OccupancyGrid` message.
///
/// # Errors
/// Bytes that are not one, a grid whose cells are not `width * height`, or a cell size
/// that is not positive.
pub fn grid(encoding: Encoding, bytes: &[u8]) -> Result<Grid, String> {
    let mut c = Cursor::new(bytes, encoding)?;
    let (_, frame_id) = c.header()?;
    c.u32()?; // map_load_time
    c.u32()?;
    let resolution = c.f32()?;
    let width = c.u32()? as usize;
    let height = c.u32()? as usize;
    let origin = c.pose()?;
    let data: Vec<i8> = c.bytes()?.iter().map(|&b| b as i8).collect();
    c.done()?;
    if width.checked_mul(height) != Some(data.len()) {
        return Err(format!(
            "{} cells for a grid of {width} x {height}",
            data.len()
        ));
    }
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(format!("a cell size of {resolution} m"));
    }
    Ok(Grid {
        frame_id,
        resolution,
        width,
        height,
        origin,
        data,
    })
}

fn stamp_pose_finite(p: &Pose) -> bool {
    p.x.is_finite() && p.y.is_finite() && p.theta.is_finite()
}

/// A `TFMessage`'s transforms.
///
/// # Errors
/// Bytes that are not one, or a rotation that is not one.
pub fn transforms(encoding: Encoding, bytes: &[u8]) -> Result<Vec<Transform>, String> {
    let mut c = Cursor::new(bytes, encoding)?;
    let n = c.u32()? as usize;
    // Each transform takes at least 60 bytes: a count beyond that is not a count.
    if n > bytes.len() / 60 {
        return Err(format!("{n} transforms in {} bytes", bytes.len()));
    }
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let (stamp_ns, parent) = c.header()?;
        let child = c.string()?;
        let pose = c.pose()?;
        out.push(Transform {
            stamp_ns,
            parent,
            child,
            pose,
        });
    }
    c.done()?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(sec: u32, nsec: u32, frame: &str) -> Vec<u8> {
        let mut b = 7u32.to_le_bytes().to_vec();
        b.extend(sec.to_le_bytes());
        b.extend(nsec.to_le_bytes());
        b.extend((frame.len() as u32).to_le_bytes());
        b.extend(frame.as_bytes());
        b
    }

    fn pose_bytes(x: f64, y: f64, yaw: f64) -> Vec<u8> {
        let q = [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
        [x, y, 0.5]
            .iter()
            .chain(&q)
            .flat_map(|v| v.to_le_bytes())
            .collect()
    }

    #[test]
    fn a_pose_stamped_gives_its_yaw_and_stamp() {
        let mut b = header(12, 500_000_000, "map");
        b.extend(pose_bytes(1.5, -2.0, 2.5));
        let p = pose(Kind::PoseStamped, Encoding::Ros1, &b).unwrap();
        assert_eq!(p.stamp_ns, Some(12_500_000_000));
        assert_eq!((p.pose.x, p.pose.y), (1.5, -2.0));
        approx::assert_abs_diff_eq!(p.pose.theta, 2.5, epsilon = 1e-12);
    }

    #[test]
    fn a_yaw_beyond_pi_comes_back_wrapped() {
        let mut b = header(1, 0, "map");
        b.extend(pose_bytes(0.0, 0.0, 3.5));
        let p = pose(Kind::PoseStamped, Encoding::Ros1, &b).unwrap();
        approx::assert_abs_diff_eq!(
            p.pose.theta,
            3.5 - 2.0 * std::f64::consts::PI,
            epsilon = 1e-12
        );
    }

    #[test]
    fn a_message_of_another_definition_is_refused() {
        let mut b = header(1, 0, "map");
        b.extend(pose_bytes(0.0, 0.0, 0.0));
        // A PoseStamped read as a PoseWithCovarianceStamped runs out of bytes.
        let e = pose(Kind::PoseWithCovarianceStamped, Encoding::Ros1, &b).unwrap_err();
        assert!(e.contains("more bytes"), "{e}");
        // Extra bytes after the last field are refused too.
        b.extend([0u8; 3]);
        let e = pose(Kind::PoseStamped, Encoding::Ros1, &b).unwrap_err();
        assert!(e.contains("3 bytes left over"), "{e}");
    }

    #[test]
    fn an_orientation_of_zeros_is_not_a_heading() {
        let mut b = header(1, 0, "map");
        b.extend([0.0f64; 7].iter().flat_map(|v| v.to_le_bytes()));
        assert!(
            pose(Kind::PoseStamped, Encoding::Ros1, &b)
                .unwrap_err()
                .contains("not a rotation")
        );
    }

    #[test]
    fn audio_data_and_info_decode() {
        let mut b = 5u32.to_le_bytes().to_vec();
        b.extend([1, 2, 3, 4, 5]);
        assert_eq!(
            audio(Kind::AudioData, Encoding::Ros1, &b).unwrap().data,
            &[1u8, 2, 3, 4, 5][..]
        );
        let mut s = header(0, 0, "");
        s.extend(&b);
        assert_eq!(
            audio(Kind::AudioDataStamped, Encoding::Ros1, &s)
                .unwrap()
                .stamp_ns,
            None,
            "a zero stamp is none"
        );
        let mut i = vec![6u8];
        i.extend(16000u32.to_le_bytes());
        i.extend(5u32.to_le_bytes());
        i.extend(b"S16LE");
        i.extend(1_536_000u32.to_le_bytes());
        i.extend(4u32.to_le_bytes());
        i.extend(b"wave");
        let info = audio_info(Encoding::Ros1, &i).unwrap();
        assert_eq!((info.channels, info.sample_rate), (6, 16000));
        assert_eq!(
            (info.sample_format.as_str(), info.coding_format.as_str()),
            ("S16LE", "wave")
        );
    }

    #[test]
    fn type_names_of_ros_1_and_ros_2_are_both_known() {
        assert_eq!(Kind::of("nav_msgs/Odometry"), Some(Kind::Odometry));
        assert_eq!(Kind::of("nav_msgs/msg/Odometry"), Some(Kind::Odometry));
        assert_eq!(Kind::of("sensor_msgs/Image"), None);
    }
}
