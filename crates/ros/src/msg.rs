//! The ROS 2 messages a map is shown with, as Humble and Jazzy define them (the two agree on
//! every field here): each encodes to CDR ([`Message::to_cdr`]), decodes from it
//! ([`Message::from_cdr`]), and gives its `ros2msg` schema ([`Message::schema`]) as an MCAP
//! file and Foxglove want it: the type's fields, then each type it uses, once, after a line
//! of `=` and `MSG: package/Type`.
//!
//! `visualization_msgs/msg/Marker` carries fields for textures and meshes that a map never
//! fills; they are written empty and skipped on reading, and the struct leaves them out.

use crate::Error;
use crate::cdr::{Reader, Writer};

/// A message type: its name, its schema, and its CDR form.
pub trait Message: Sized {
    /// The type's full name (`visualization_msgs/msg/MarkerArray`).
    const NAME: &'static str;
    /// Writes the fields (no header).
    fn encode(&self, w: &mut Writer);
    /// Reads the fields (no header).
    ///
    /// # Errors
    /// [`Error::Decode`] where the bytes end early or hold a corrupt length.
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error>;
    /// The message as CDR, header included, as DDS and MCAP carry it.
    fn to_cdr(&self) -> Vec<u8> {
        let mut w = Writer::new();
        self.encode(&mut w);
        w.finish()
    }
    /// A message from its CDR bytes (header included).
    ///
    /// # Errors
    /// As [`Message::decode`], and a header that is not little-endian CDR.
    fn from_cdr(bytes: &[u8]) -> Result<Self, Error> {
        Self::decode(&mut Reader::new(bytes)?)
    }
    /// The `ros2msg` schema: this type's definition and every type it uses.
    fn schema() -> String {
        schema(Self::NAME)
    }
}

/// The definitions (fields only), by the short name the fields use, and the types each uses.
const DEFINITIONS: &[(&str, &str, &[&str])] = &[
    (
        "builtin_interfaces/Time",
        "int32 sec\nuint32 nanosec\n",
        &[],
    ),
    (
        "builtin_interfaces/Duration",
        "int32 sec\nuint32 nanosec\n",
        &[],
    ),
    (
        "std_msgs/Header",
        "builtin_interfaces/Time stamp\nstring frame_id\n",
        &["builtin_interfaces/Time"],
    ),
    (
        "std_msgs/ColorRGBA",
        "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n",
        &[],
    ),
    (
        "geometry_msgs/Point",
        "float64 x\nfloat64 y\nfloat64 z\n",
        &[],
    ),
    (
        "geometry_msgs/Vector3",
        "float64 x\nfloat64 y\nfloat64 z\n",
        &[],
    ),
    (
        "geometry_msgs/Quaternion",
        "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
        &[],
    ),
    (
        "geometry_msgs/Pose",
        "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
        &["geometry_msgs/Point", "geometry_msgs/Quaternion"],
    ),
    (
        "geometry_msgs/PoseStamped",
        "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
        &["std_msgs/Header", "geometry_msgs/Pose"],
    ),
    (
        "geometry_msgs/PoseArray",
        "std_msgs/Header header\ngeometry_msgs/Pose[] poses\n",
        &["std_msgs/Header", "geometry_msgs/Pose"],
    ),
    (
        "nav_msgs/Path",
        "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n",
        &["std_msgs/Header", "geometry_msgs/PoseStamped"],
    ),
    (
        "nav_msgs/MapMetaData",
        "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\ngeometry_msgs/Pose origin\n",
        &["builtin_interfaces/Time", "geometry_msgs/Pose"],
    ),
    (
        "nav_msgs/OccupancyGrid",
        "std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n",
        &["std_msgs/Header", "nav_msgs/MapMetaData"],
    ),
    (
        "sensor_msgs/CompressedImage",
        "std_msgs/Header header\nstring format\nuint8[] data\n",
        &["std_msgs/Header"],
    ),
    (
        "visualization_msgs/UVCoordinate",
        "float32 u\nfloat32 v\n",
        &[],
    ),
    (
        "visualization_msgs/MeshFile",
        "string filename\nuint8[] data\n",
        &[],
    ),
    (
        "visualization_msgs/Marker",
        "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\n\
         int32 LINE_LIST=5\nint32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\n\
         int32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\nint32 TRIANGLE_LIST=11\n\
         int32 ARROW_STRIP=12\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\n\
         std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\n\
         geometry_msgs/Pose pose\ngeometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\n\
         builtin_interfaces/Duration lifetime\nbool frame_locked\ngeometry_msgs/Point[] points\n\
         std_msgs/ColorRGBA[] colors\nstring texture_resource\n\
         sensor_msgs/CompressedImage texture\n\
         visualization_msgs/UVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\n\
         visualization_msgs/MeshFile mesh_file\nbool mesh_use_embedded_materials\n",
        &[
            "std_msgs/Header",
            "geometry_msgs/Pose",
            "geometry_msgs/Vector3",
            "std_msgs/ColorRGBA",
            "builtin_interfaces/Duration",
            "geometry_msgs/Point",
            "sensor_msgs/CompressedImage",
            "visualization_msgs/UVCoordinate",
            "visualization_msgs/MeshFile",
        ],
    ),
    (
        "visualization_msgs/MarkerArray",
        "visualization_msgs/Marker[] markers\n",
        &["visualization_msgs/Marker"],
    ),
    (
        "geometry_msgs/Pose2D",
        "float64 x\nfloat64 y\nfloat64 theta\n",
        &[],
    ),
    (
        "iasm_msgs/Stop",
        "std_msgs/Header header\nstring run\nuint32 index\ngeometry_msgs/Pose2D pose\n\
         float64[] doas_deg\nbool cut\nstring method\n",
        &["std_msgs/Header", "geometry_msgs/Pose2D"],
    ),
];

/// The `ros2msg` schema of `name` (`pkg/msg/Type` or `pkg/Type`).
///
/// # Panics
/// For a type this module does not define.
pub fn schema(name: &str) -> String {
    let short = name.replace("/msg/", "/");
    let find = |n: &str| {
        DEFINITIONS
            .iter()
            .find(|d| d.0 == n)
            .unwrap_or_else(|| panic!("no definition of {n}"))
    };
    let top = find(&short);
    let mut text = top.1.to_owned();
    // Each dependency once, in the order first met, depth first.
    let mut seen: Vec<&str> = Vec::new();
    let mut stack: Vec<&str> = top.2.iter().rev().copied().collect();
    while let Some(n) = stack.pop() {
        if seen.contains(&n) {
            continue;
        }
        seen.push(n);
        let d = find(n);
        text.push_str(&"=".repeat(80));
        text.push_str(&format!("\nMSG: {n}\n{}", d.1));
        stack.extend(d.2.iter().rev().copied().filter(|x| !seen.contains(x)));
    }
    text
}

/// `builtin_interfaces/msg/Time` (and `Duration`, the same fields).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, below 10^9.
    pub nanosec: u32,
}

impl Time {
    /// The time `ns` nanoseconds after the epoch (clamped to what `sec: i32` holds).
    pub fn from_ns(ns: i64) -> Self {
        let sec = ns.div_euclid(1_000_000_000);
        let nanosec = ns.rem_euclid(1_000_000_000) as u32;
        match i32::try_from(sec) {
            Ok(sec) => Self { sec, nanosec },
            Err(_) if sec < 0 => Self {
                sec: i32::MIN,
                nanosec: 0,
            },
            Err(_) => Self {
                sec: i32::MAX,
                nanosec: 999_999_999,
            },
        }
    }
    /// Nanoseconds since the epoch.
    pub fn ns(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }
    fn encode(self, w: &mut Writer) {
        w.i32(self.sec);
        w.u32(self.nanosec);
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        Ok(Self {
            sec: r.i32()?,
            nanosec: r.u32()?,
        })
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Header {
    /// When.
    pub stamp: Time,
    /// The frame the message's coordinates are in (`map`).
    pub frame_id: String,
}

impl Header {
    /// A header in `frame` at `stamp_ns`.
    pub fn new(frame: &str, stamp_ns: i64) -> Self {
        Self {
            stamp: Time::from_ns(stamp_ns),
            frame_id: frame.to_owned(),
        }
    }
    fn encode(&self, w: &mut Writer) {
        self.stamp.encode(w);
        w.string(&self.frame_id);
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        Ok(Self {
            stamp: Time::decode(r)?,
            frame_id: r.string()?,
        })
    }
}

/// `geometry_msgs/msg/Point` (and `Vector3`, the same fields).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Point {
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// z (m).
    pub z: f64,
}

impl Point {
    /// A point.
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }
    fn encode(self, w: &mut Writer) {
        w.f64(self.x);
        w.f64(self.y);
        w.f64(self.z);
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        Ok(Self {
            x: r.f64()?,
            y: r.f64()?,
            z: r.f64()?,
        })
    }
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self::yaw(0.0)
    }
}

impl Quaternion {
    /// A turn of `yaw` (rad) about z.
    pub fn yaw(yaw: f64) -> Self {
        let (s, c) = (yaw / 2.0).sin_cos();
        Self {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }
    /// The turn about z this quaternion makes (its yaw, rad).
    pub fn to_yaw(self) -> f64 {
        (2.0 * (self.w * self.z + self.x * self.y))
            .atan2(1.0 - 2.0 * (self.y * self.y + self.z * self.z))
    }
    fn encode(self, w: &mut Writer) {
        w.f64(self.x);
        w.f64(self.y);
        w.f64(self.z);
        w.f64(self.w);
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        Ok(Self {
            x: r.f64()?,
            y: r.f64()?,
            z: r.f64()?,
            w: r.f64()?,
        })
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    /// Where.
    pub position: Point,
    /// Which way.
    pub orientation: Quaternion,
}

impl Pose {
    /// A pose in the plane: at (x, y, z) heading `yaw` (rad).
    pub fn planar(x: f64, y: f64, z: f64, yaw: f64) -> Self {
        Self {
            position: Point::new(x, y, z),
            orientation: Quaternion::yaw(yaw),
        }
    }
    fn encode(&self, w: &mut Writer) {
        self.position.encode(w);
        self.orientation.encode(w);
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        Ok(Self {
            position: Point::decode(r)?,
            orientation: Quaternion::decode(r)?,
        })
    }
}

/// `std_msgs/msg/ColorRGBA`, each part in [0, 1].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Color {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Opacity.
    pub a: f32,
}

impl Color {
    /// A colour.
    pub const fn new(r: f32, g: f32, b: f32, a: f32) -> Self {
        Self { r, g, b, a }
    }
    fn encode(self, w: &mut Writer) {
        for v in [self.r, self.g, self.b, self.a] {
            w.f32(v);
        }
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        Ok(Self {
            r: r.f32()?,
            g: r.f32()?,
            b: r.f32()?,
            a: r.f32()?,
        })
    }
}

/// `geometry_msgs/msg/PoseArray`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseArray {
    /// Frame and time.
    pub header: Header,
    /// The poses.
    pub poses: Vec<Pose>,
}

impl Message for PoseArray {
    const NAME: &'static str = "geometry_msgs/msg/PoseArray";
    fn encode(&self, w: &mut Writer) {
        self.header.encode(w);
        w.len(self.poses.len());
        for p in &self.poses {
            p.encode(w);
        }
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        let header = Header::decode(r)?;
        let n = r.len(56)?;
        let poses = (0..n).map(|_| Pose::decode(r)).collect::<Result<_, _>>()?;
        Ok(Self { header, poses })
    }
}

/// `geometry_msgs/msg/PoseStamped`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseStamped {
    /// Frame and time.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}

impl Message for PoseStamped {
    const NAME: &'static str = "geometry_msgs/msg/PoseStamped";
    fn encode(&self, w: &mut Writer) {
        self.header.encode(w);
        self.pose.encode(w);
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        Ok(Self {
            header: Header::decode(r)?,
            pose: Pose::decode(r)?,
        })
    }
}

/// `nav_msgs/msg/Path`: a trajectory.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Path {
    /// Frame and time.
    pub header: Header,
    /// The poses, in order.
    pub poses: Vec<PoseStamped>,
}

impl Message for Path {
    const NAME: &'static str = "nav_msgs/msg/Path";
    fn encode(&self, w: &mut Writer) {
        self.header.encode(w);
        w.len(self.poses.len());
        for p in &self.poses {
            p.encode(w);
        }
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        let header = Header::decode(r)?;
        let n = r.len(64)?;
        let poses = (0..n)
            .map(|_| PoseStamped::decode(r))
            .collect::<Result<_, _>>()?;
        Ok(Self { header, poses })
    }
}

/// `nav_msgs/msg/OccupancyGrid`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OccupancyGrid {
    /// Frame and time.
    pub header: Header,
    /// When the map was loaded.
    pub map_load_time: Time,
    /// The side of a cell (m).
    pub resolution: f32,
    /// Cells per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// The pose of cell (0, 0)'s outer corner.
    pub origin: Pose,
    /// Row-major from the origin's row: -1 unknown, else occupancy in percent.
    pub data: Vec<i8>,
}

impl Message for OccupancyGrid {
    const NAME: &'static str = "nav_msgs/msg/OccupancyGrid";
    fn encode(&self, w: &mut Writer) {
        self.header.encode(w);
        self.map_load_time.encode(w);
        w.f32(self.resolution);
        w.u32(self.width);
        w.u32(self.height);
        self.origin.encode(w);
        w.len(self.data.len());
        for &v in &self.data {
            w.i8(v);
        }
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        let header = Header::decode(r)?;
        let map_load_time = Time::decode(r)?;
        let resolution = r.f32()?;
        let width = r.u32()?;
        let height = r.u32()?;
        let origin = Pose::decode(r)?;
        let data = r.bytes()?.iter().map(|&b| b as i8).collect();
        Ok(Self {
            header,
            map_load_time,
            resolution,
            width,
            height,
            origin,
            data,
        })
    }
}

/// `visualization_msgs/msg/Marker`, without the texture and mesh fields (written empty).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Marker {
    /// Frame and time.
    pub header: Header,
    /// Namespace: with `id`, names the marker.
    pub ns: String,
    /// Its id within the namespace.
    pub id: i32,
    /// Its shape ([`Marker::SPHERE`], ...).
    pub kind: i32,
    /// [`Marker::ADD`], [`Marker::DELETE`] or [`Marker::DELETEALL`].
    pub action: i32,
    /// Where, and which way.
    pub pose: Pose,
    /// Size (m) along its axes.
    pub scale: Point,
    /// Colour.
    pub color: Color,
    /// How long it lasts; zero for ever.
    pub lifetime: Time,
    /// Whether it is moved with its frame.
    pub frame_locked: bool,
    /// Points, for lines and lists.
    pub points: Vec<Point>,
    /// A colour per point, or none.
    pub colors: Vec<Color>,
    /// Text, for [`Marker::TEXT_VIEW_FACING`].
    pub text: String,
}

impl Marker {
    /// A sphere.
    pub const SPHERE: i32 = 2;
    /// An arrow from `points[0]` to `points[1]` (`scale`: shaft and head diameters, head
    /// length).
    pub const ARROW: i32 = 0;
    /// A cylinder (a flat one draws an ellipse).
    pub const CYLINDER: i32 = 3;
    /// A line through `points`.
    pub const LINE_STRIP: i32 = 4;
    /// Segments between pairs of `points`.
    pub const LINE_LIST: i32 = 5;
    /// Text facing the viewer.
    pub const TEXT_VIEW_FACING: i32 = 9;
    /// Add or replace.
    pub const ADD: i32 = 0;
    /// Delete the marker of this `ns` and `id`.
    pub const DELETE: i32 = 2;
    /// Delete every marker (of `ns`, when given).
    pub const DELETEALL: i32 = 3;
}

impl Message for Marker {
    const NAME: &'static str = "visualization_msgs/msg/Marker";
    fn encode(&self, w: &mut Writer) {
        self.header.encode(w);
        w.string(&self.ns);
        w.i32(self.id);
        w.i32(self.kind);
        w.i32(self.action);
        self.pose.encode(w);
        self.scale.encode(w);
        self.color.encode(w);
        self.lifetime.encode(w);
        w.bool(self.frame_locked);
        w.len(self.points.len());
        for p in &self.points {
            p.encode(w);
        }
        w.len(self.colors.len());
        for c in &self.colors {
            c.encode(w);
        }
        w.string(""); // texture_resource
        Header::default().encode(w); // texture: header, format, data
        w.string("");
        w.bytes(&[]);
        w.len(0); // uv_coordinates
        w.string(&self.text);
        w.string(""); // mesh_resource
        w.string(""); // mesh_file: filename, data
        w.bytes(&[]);
        w.bool(false); // mesh_use_embedded_materials
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        let header = Header::decode(r)?;
        let ns = r.string()?;
        let id = r.i32()?;
        let kind = r.i32()?;
        let action = r.i32()?;
        let pose = Pose::decode(r)?;
        let scale = Point::decode(r)?;
        let color = Color::decode(r)?;
        let lifetime = Time::decode(r)?;
        let frame_locked = r.bool()?;
        let n = r.len(24)?;
        let points = (0..n).map(|_| Point::decode(r)).collect::<Result<_, _>>()?;
        let n = r.len(16)?;
        let colors = (0..n).map(|_| Color::decode(r)).collect::<Result<_, _>>()?;
        r.string()?;
        Header::decode(r)?;
        r.string()?;
        r.bytes()?;
        let n = r.len(8)?;
        for _ in 0..n {
            r.f32()?;
            r.f32()?;
        }
        let text = r.string()?;
        r.string()?;
        r.string()?;
        r.bytes()?;
        r.bool()?;
        Ok(Self {
            header,
            ns,
            id,
            kind,
            action,
            pose,
            scale,
            color,
            lifetime,
            frame_locked,
            points,
            colors,
            text,
        })
    }
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MarkerArray {
    /// The markers, applied in order.
    pub markers: Vec<Marker>,
}

impl Message for MarkerArray {
    const NAME: &'static str = "visualization_msgs/msg/MarkerArray";
    fn encode(&self, w: &mut Writer) {
        w.len(self.markers.len());
        for m in &self.markers {
            m.encode(w);
        }
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        let n = r.len(100)?;
        let markers = (0..n)
            .map(|_| Marker::decode(r))
            .collect::<Result<_, _>>()?;
        Ok(Self { markers })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_schema_lists_each_type_it_uses_once() {
        let s = schema(MarkerArray::NAME);
        assert!(s.starts_with("visualization_msgs/Marker[] markers\n"));
        for t in [
            "visualization_msgs/Marker",
            "std_msgs/Header",
            "builtin_interfaces/Time",
            "builtin_interfaces/Duration",
            "geometry_msgs/Pose",
            "geometry_msgs/Point",
            "geometry_msgs/Quaternion",
            "geometry_msgs/Vector3",
            "std_msgs/ColorRGBA",
            "sensor_msgs/CompressedImage",
            "visualization_msgs/UVCoordinate",
            "visualization_msgs/MeshFile",
        ] {
            assert_eq!(s.matches(&format!("\nMSG: {t}\n")).count(), 1, "{t}");
        }
        assert_eq!(s.matches("MSG: ").count(), 12);
        assert!(schema(Path::NAME).contains("MSG: geometry_msgs/PoseStamped\n"));
    }

    #[test]
    fn a_stop_is_laid_out_as_cdr_aligns_it_and_reads_back() {
        let stop = Stop {
            header: Header::new("map", 1_000_000_002),
            run: "/r".into(),
            index: 3,
            pose: [1.0, 2.0, 0.5],
            doas_deg: vec![10.0],
            cut: true,
            method: "mvdr".into(),
        };
        let b = stop.to_cdr();
        let body = &b[4..];
        // Header: stamp (8), frame "map" (4 + 4); run "/r" (4 + 3) ends at 23, so the
        // index is aligned to 24, the pose's float64s to 32, the DoA after its count (56)
        // to 64, the bool at 72, the method's length aligned to 76; 85 bytes.
        let f64_at = |at: usize| f64::from_le_bytes(body[at..at + 8].try_into().unwrap());
        assert_eq!(body.len(), 85);
        assert_eq!(u32::from_le_bytes(body[24..28].try_into().unwrap()), 3);
        assert_eq!([f64_at(32), f64_at(40), f64_at(48)], [1.0, 2.0, 0.5]);
        assert_eq!(u32::from_le_bytes(body[56..60].try_into().unwrap()), 1);
        assert_eq!(f64_at(64), 10.0);
        assert_eq!(body[72], 1);
        assert_eq!(&body[80..85], b"mvdr\0");
        assert_eq!(Stop::from_cdr(&b).unwrap(), stop);
        for n in 0..b.len() {
            assert!(Stop::from_cdr(&b[..n]).is_err());
        }
        assert!(Stop::schema().contains("MSG: geometry_msgs/Pose2D\n"));
    }

    /// The interface package for the ROS tools (`docs/ros/iasm_msgs`) defines the fields
    /// this module writes.
    #[test]
    fn the_stop_msg_file_defines_the_fields_written() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../docs/ros/iasm_msgs/msg/Stop.msg"
        );
        let text = std::fs::read_to_string(path).unwrap();
        let fields: String = text
            .lines()
            .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
            .map(|l| format!("{l}\n"))
            .collect();
        assert_eq!(schema(Stop::NAME).split("=====").next().unwrap(), fields);
    }

    #[test]
    fn a_marker_reads_back_as_written() {
        let m = Marker {
            header: Header::new("map", 1_500_000_001),
            ns: "sources".into(),
            id: 3,
            kind: Marker::LINE_LIST,
            action: Marker::ADD,
            pose: Pose::planar(1.0, -2.0, 0.5, 0.3),
            scale: Point::new(0.1, 0.2, 0.3),
            color: Color::new(1.0, 0.5, 0.0, 0.8),
            lifetime: Time::default(),
            frame_locked: true,
            points: vec![Point::new(1.0, 2.0, 3.0), Point::new(-1.0, 0.0, 7.5)],
            colors: vec![Color::new(0.1, 0.2, 0.3, 0.4)],
            text: "s3".into(),
        };
        let a = MarkerArray {
            markers: vec![m.clone(), Marker::default()],
        };
        let back = MarkerArray::from_cdr(&a.to_cdr()).unwrap();
        assert_eq!(back, a);
        assert_eq!(
            back.markers[0].header.stamp,
            Time {
                sec: 1,
                nanosec: 500_000_001
            }
        );
        assert!((back.markers[0].pose.orientation.to_yaw() - 0.3).abs() < 1e-12);
        // Every prefix is an error, never a panic.
        let bytes = a.to_cdr();
        for n in 0..bytes.len() {
            assert!(MarkerArray::from_cdr(&bytes[..n]).is_err());
        }
    }

    #[test]
    fn times_split_into_seconds_and_nanoseconds() {
        assert_eq!(
            Time::from_ns(-1),
            Time {
                sec: -1,
                nanosec: 999_999_999
            }
        );
        assert_eq!(Time::from_ns(2_000_000_003).ns(), 2_000_000_003);
        assert_eq!(Time::from_ns(i64::MAX).sec, i32::MAX);
    }
}

/// `iasm_msgs/msg/Stop`: what a robot's node heard at one stop, all a merging node needs to
/// map it (`docs/ros/iasm_msgs/msg/Stop.msg`): no audio crosses the network.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stop {
    /// When the robot arrived; the frame of the pose (`map`).
    pub header: Header,
    /// The run: the publishing node's fully qualified name.
    pub run: String,
    /// The stop's place in its run, from 0.
    pub index: u32,
    /// Where the robot stood: x, y (m), heading (rad).
    pub pose: [f64; 3],
    /// The DoAs: azimuths (degrees, the array's frame), strongest first.
    pub doas_deg: Vec<f64>,
    /// Whether N cut the row (a further peak passed the thresholds).
    pub cut: bool,
    /// The SSL method that heard them.
    pub method: String,
}

impl Message for Stop {
    const NAME: &'static str = "iasm_msgs/msg/Stop";
    fn encode(&self, w: &mut Writer) {
        self.header.encode(w);
        w.string(&self.run);
        w.u32(self.index);
        for v in self.pose {
            w.f64(v);
        }
        w.len(self.doas_deg.len());
        for &d in &self.doas_deg {
            w.f64(d);
        }
        w.bool(self.cut);
        w.string(&self.method);
    }
    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        let header = Header::decode(r)?;
        let run = r.string()?;
        let index = r.u32()?;
        let pose = [r.f64()?, r.f64()?, r.f64()?];
        let n = r.len(8)?;
        let doas_deg = (0..n).map(|_| r.f64()).collect::<Result<_, _>>()?;
        Ok(Self {
            header,
            run,
            index,
            pose,
            doas_deg,
            cut: r.bool()?,
            method: r.string()?,
        })
    }
}
