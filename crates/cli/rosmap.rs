//! A map as the ROS 2 messages RViz and Foxglove show it: what the PNG shows, in frame
//! `map`.
//!
//! | topic | type | what |
//! |---|---|---|
//! | `/iasm/sources` | `visualization_msgs/MarkerArray` | a sphere per source (`ns` `sources`), its 2-sigma ellipse (`ellipses`, a flat cylinder), a label with its id, DoA count and, for a source silent at the end, since which stop (`labels`; a silent source's sphere is grey); led by a `DELETEALL`, so that a source gone from the map is gone from the display |
//! | `/iasm/doas` | `visualization_msgs/MarkerArray` | each stop's DoAs as rays from the robot (`ns` `doas`, one `LINE_LIST` per stop, id the stop's index) |
//! | `/iasm/path` | `nav_msgs/Path` | the stops, in order, with the robot's heading |
//! | `/iasm/source_poses` | `geometry_msgs/PoseArray` | the sources, for programs (in the map JSON's order) |
//! | `/map` | `nav_msgs/OccupancyGrid` | the occupancy map the sources were searched in |
//! | `/iasm/changes` | `visualization_msgs/MarkerArray` | with a prior map (`iasm ros2 --prior`): what changed against it (`asm::diff`), a sphere per change in the namespace of its kind (`kept`, `moved`, `removed`, `added`; id its index in the comparison), coloured by kind, a `moved` arrow from the old place to the new, and a label (`change_labels`) saying what and how sure; led by a `DELETEALL` |
//!
//! Source `k` of the map JSON (from 0) is marker id `k` in each namespace and is labelled
//! `s{k+1}`. The ellipse's axes are 4 sigma long (the 2-sigma ellipse's diameters) along the
//! eigenvectors of the source's covariance, so that its covariance can be read back as
//! `R diag((sx/4)^2, (sy/4)^2) Rᵀ`.

use asm::map::{Cell, OccupancyMap};
use asm::{MapResult, Pose};
use iasm_ros::mcap::Qos;
use iasm_ros::msg::Pose as RosPose;
use iasm_ros::msg::{
    Color, Header, Marker, MarkerArray, Message, OccupancyGrid, Path, Point, PoseArray,
    PoseStamped, Quaternion, Time,
};

/// The frame every message is in.
pub const FRAME: &str = "map";
/// The topics, as the module docs list them.
pub const SOURCES_TOPIC: &str = "/iasm/sources";
/// Each stop's DoAs as rays.
pub const DOAS_TOPIC: &str = "/iasm/doas";
/// The trajectory.
pub const PATH_TOPIC: &str = "/iasm/path";
/// The sources as poses.
pub const SOURCE_POSES_TOPIC: &str = "/iasm/source_poses";
/// The occupancy map.
pub const MAP_TOPIC: &str = "/map";
/// What changed against a prior map.
pub const CHANGES_TOPIC: &str = "/iasm/changes";
/// How far a DoA's ray is drawn from the robot (m): across a room, short of the next.
pub const RAY_LENGTH_M: f64 = 5.0;
/// A source's sphere (m across).
const SPHERE_M: f64 = 0.25;
/// Height of a source's label above it (m).
const LABEL_Z_M: f64 = 0.45;
/// Thickness of the ellipse's flat cylinder (m).
const ELLIPSE_THICKNESS_M: f64 = 0.02;

/// What a map update sends.
#[derive(Clone, Debug, PartialEq)]
pub struct MapMessages {
    /// Spheres, ellipses, labels.
    pub sources: MarkerArray,
    /// Rays per stop.
    pub doas: MarkerArray,
    /// The stops.
    pub path: Path,
    /// The sources for programs.
    pub source_poses: PoseArray,
    /// The occupancy map.
    pub grid: OccupancyGrid,
    /// What changed against a prior map, when there is one ([`change_markers`]).
    pub changes: Option<MarkerArray>,
}

/// The stops of a map: each pose, when it was heard, and its DoAs (degrees, array frame).
pub struct Stops<'a> {
    /// The robot's poses.
    pub poses: &'a [Pose],
    /// Each stop's time (ns since the epoch).
    pub stamps_ns: &'a [i64],
    /// Each stop's DoAs (degrees, array frame); fewer rows than poses leaves the rest bare.
    pub doas_deg: &'a [Vec<f64>],
}

/// The messages of `result` over `stops` (each stop's pose, time in ns and DoAs in
/// degrees), on `map`, stamped `stamp_ns`.
pub fn messages_over<'a>(
    result: &MapResult,
    stops: impl Iterator<Item = (Pose, i64, &'a [f64])>,
    map: &OccupancyMap,
    stamp_ns: i64,
) -> MapMessages {
    let (mut poses, mut stamps, mut doas) = (Vec::new(), Vec::new(), Vec::new());
    for (p, t, d) in stops {
        poses.push(p);
        stamps.push(t);
        doas.push(d.to_vec());
    }
    MapMessages::new(
        result,
        &Stops {
            poses: &poses,
            stamps_ns: &stamps,
            doas_deg: &doas,
        },
        map,
        stamp_ns,
    )
}

/// The 2-sigma ellipse of a covariance: its diameters (major, minor) and the major axis's
/// angle (rad); `None` when the covariance is not a finite positive semi-definite one.
pub fn ellipse(cov: [[f64; 2]; 2]) -> Option<(f64, f64, f64)> {
    let (a, b, d) = (cov[0][0], 0.5 * (cov[0][1] + cov[1][0]), cov[1][1]);
    if ![a, b, d].iter().all(|v| v.is_finite()) {
        return None;
    }
    let mean = 0.5 * (a + d);
    let r = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (l1, l2) = (mean + r, mean - r);
    if l2 < -1e-12 {
        return None;
    }
    let angle = 0.5 * (2.0 * b).atan2(a - d);
    Some((4.0 * l1.sqrt(), 4.0 * l2.max(0.0).sqrt(), angle))
}

/// A ROS grid from an occupancy map: rows from the origin's (the image's bottom) up,
/// free 0, occupied 100, unknown -1.
pub fn grid(map: &OccupancyMap, header: Header) -> OccupancyGrid {
    let (w, h) = (map.width(), map.height());
    let mut data = Vec::with_capacity(w * h);
    for row in 0..h {
        let j = h - 1 - row;
        data.extend((0..w).map(|i| match map.cell(i, j) {
            Cell::Free => 0,
            Cell::Occupied => 100,
            Cell::Unknown => -1,
        }));
    }
    let [ox, oy] = map.origin();
    OccupancyGrid {
        map_load_time: header.stamp,
        header,
        resolution: map.resolution() as f32,
        width: u32::try_from(w).unwrap_or(u32::MAX),
        height: u32::try_from(h).unwrap_or(u32::MAX),
        origin: RosPose::planar(ox, oy, 0.0, 0.0),
        data,
    }
}

/// A source silent at the end of the run ([`asm::SourceState::Silent`]): grey, where
/// active ones are red.
const SILENT_COLOUR: Color = Color {
    r: 0.55,
    g: 0.55,
    b: 0.55,
    a: 1.0,
};

/// Source `k`'s label: its id, DoA count and, when it fell silent, since which stop.
fn label(k: usize, s: &asm::Source) -> String {
    match s.history.silent_since() {
        Some(since) => format!(
            "s{}: {} DoAs, silent since stop {since}",
            k + 1,
            s.observations
        ),
        None => format!("s{}: {} DoAs", k + 1, s.observations),
    }
}

fn marker(header: &Header, ns: &str, id: usize, kind: i32) -> Marker {
    Marker {
        header: header.clone(),
        ns: ns.to_owned(),
        id: i32::try_from(id).unwrap_or(i32::MAX),
        kind,
        action: Marker::ADD,
        pose: RosPose::default(),
        scale: Point::new(1.0, 1.0, 1.0),
        color: Color::new(1.0, 1.0, 1.0, 1.0),
        lifetime: Time::default(),
        frame_locked: false,
        points: Vec::new(),
        colors: Vec::new(),
        text: String::new(),
    }
}

impl MapMessages {
    /// The messages of `result` over `stops`, in `map`, stamped `stamp_ns`.
    pub fn new(result: &MapResult, stops: &Stops<'_>, map: &OccupancyMap, stamp_ns: i64) -> Self {
        let header = Header::new(FRAME, stamp_ns);
        let source_colour = Color::new(0.85, 0.1, 0.1, 1.0);
        let mut markers = vec![Marker {
            action: Marker::DELETEALL,
            ..marker(&header, "", 0, Marker::SPHERE)
        }];
        for (k, s) in result.sources.iter().enumerate() {
            markers.push(Marker {
                pose: RosPose::planar(s.x, s.y, 0.0, 0.0),
                scale: Point::new(SPHERE_M, SPHERE_M, SPHERE_M),
                color: if s.history.is_active() {
                    source_colour
                } else {
                    SILENT_COLOUR
                },
                ..marker(&header, "sources", k, Marker::SPHERE)
            });
            if let Some((major, minor, angle)) = ellipse(s.covariance) {
                markers.push(Marker {
                    pose: RosPose::planar(s.x, s.y, 0.0, angle),
                    scale: Point::new(major, minor, ELLIPSE_THICKNESS_M),
                    color: Color::new(0.85, 0.1, 0.1, 0.3),
                    ..marker(&header, "ellipses", k, Marker::CYLINDER)
                });
            }
            markers.push(Marker {
                pose: RosPose::planar(s.x, s.y, LABEL_Z_M, 0.0),
                scale: Point::new(0.0, 0.0, 0.25),
                color: Color::new(0.1, 0.1, 0.1, 1.0),
                text: label(k, s),
                ..marker(&header, "labels", k, Marker::TEXT_VIEW_FACING)
            });
        }
        let doas = stops
            .poses
            .iter()
            .zip(stops.doas_deg)
            .enumerate()
            .map(|(i, (p, row))| {
                let points = row
                    .iter()
                    .filter(|a| a.is_finite())
                    .flat_map(|a| {
                        let b = p.world_bearing(a.to_radians());
                        [
                            Point::new(p.x, p.y, 0.0),
                            Point::new(
                                p.x + RAY_LENGTH_M * b.cos(),
                                p.y + RAY_LENGTH_M * b.sin(),
                                0.0,
                            ),
                        ]
                    })
                    .collect();
                Marker {
                    header: Header::new(FRAME, stamp_of(stops, i, stamp_ns)),
                    scale: Point::new(0.02, 0.0, 0.0),
                    color: Color::new(0.1, 0.4, 0.85, 0.6),
                    points,
                    ..marker(&header, "doas", i, Marker::LINE_LIST)
                }
            })
            .collect();
        let path = Path {
            header: header.clone(),
            poses: stops
                .poses
                .iter()
                .enumerate()
                .map(|(i, p)| PoseStamped {
                    header: Header::new(FRAME, stamp_of(stops, i, stamp_ns)),
                    pose: RosPose::planar(p.x, p.y, 0.0, p.theta),
                })
                .collect(),
        };
        let source_poses = PoseArray {
            header: header.clone(),
            poses: result
                .sources
                .iter()
                .map(|s| RosPose {
                    position: Point::new(s.x, s.y, 0.0),
                    orientation: Quaternion::default(),
                })
                .collect(),
        };
        Self {
            sources: MarkerArray { markers },
            doas: MarkerArray { markers: doas },
            path,
            source_poses,
            grid: grid(map, header),
            changes: None,
        }
    }

    /// Each topic's message as CDR, in the order [`MapMessages::write`] writes them.
    pub fn encoded(&self) -> [(&'static str, Qos, Vec<u8>); 5] {
        [
            (MAP_TOPIC, Qos::Latched, self.grid.to_cdr()),
            (PATH_TOPIC, Qos::Reliable, self.path.to_cdr()),
            (DOAS_TOPIC, Qos::Reliable, self.doas.to_cdr()),
            (SOURCES_TOPIC, Qos::Reliable, self.sources.to_cdr()),
            (
                SOURCE_POSES_TOPIC,
                Qos::Reliable,
                self.source_poses.to_cdr(),
            ),
        ]
    }

    /// Writes the update to an MCAP file at `log_time_ns`; the occupancy map only when
    /// `with_grid` (it is sent once, latched, unless it changes).
    ///
    /// # Errors
    /// What the writer refuses.
    pub fn write<W: std::io::Write + std::io::Seek>(
        &self,
        w: &mut iasm_ros::mcap::Writer<W>,
        log_time_ns: i64,
        with_grid: bool,
    ) -> Result<(), iasm_ros::Error> {
        let t = u64::try_from(log_time_ns).unwrap_or(0);
        if with_grid {
            w.write(MAP_TOPIC, Qos::Latched, t, &self.grid)?;
        }
        w.write(PATH_TOPIC, Qos::Reliable, t, &self.path)?;
        w.write(DOAS_TOPIC, Qos::Reliable, t, &self.doas)?;
        w.write(SOURCES_TOPIC, Qos::Reliable, t, &self.sources)?;
        if let Some(changes) = &self.changes {
            w.write(CHANGES_TOPIC, Qos::Reliable, t, changes)?;
        }
        w.write(SOURCE_POSES_TOPIC, Qos::Reliable, t, &self.source_poses)
    }
}

/// The colour of a kind of change, as `iasm diff`'s figure draws it.
fn change_colour(k: asm::diff::ChangeKind) -> Color {
    let plotters::style::RGBColor(r, g, b) = crate::figure::change_colour(k);
    Color::new(
        f32::from(r) / 255.0,
        f32::from(g) / 255.0,
        f32::from(b) / 255.0,
        1.0,
    )
}

/// What changed between `prior` and `now` (`changes`, from `asm::diff::diff` of the two),
/// as markers stamped with `header`: per change a sphere at its place now (at its old
/// place when removed) in the namespace of its kind, a label in `change_labels`, and for a
/// moved source an arrow from its old place to its new one in `change_arrows`; id the
/// change's index.
pub fn change_markers(
    prior: &[asm::diff::Placed],
    now: &[asm::diff::Placed],
    changes: &[asm::diff::Change],
    header: &Header,
) -> MarkerArray {
    use asm::diff::ChangeKind;
    let mut markers = vec![Marker {
        action: Marker::DELETEALL,
        ..marker(header, "", 0, Marker::SPHERE)
    }];
    for (k, c) in changes.iter().enumerate() {
        let old = c.before.map(|i| &prior[i]);
        let new = c.after.map(|j| &now[j]);
        let Some(at) = new.or(old) else { continue };
        let colour = change_colour(c.kind);
        markers.push(Marker {
            pose: RosPose::planar(at.x, at.y, 0.0, 0.0),
            scale: Point::new(SPHERE_M * 1.4, SPHERE_M * 1.4, SPHERE_M * 0.4),
            color: colour,
            ..marker(header, c.kind.name(), k, Marker::SPHERE)
        });
        if let (ChangeKind::Moved, Some(a), Some(b)) = (c.kind, old, new) {
            markers.push(Marker {
                scale: Point::new(0.05, 0.12, 0.15),
                color: colour,
                points: vec![Point::new(a.x, a.y, 0.0), Point::new(b.x, b.y, 0.0)],
                ..marker(header, "change_arrows", k, Marker::ARROW)
            });
        }
        let name = |i: Option<usize>| i.map_or("-".to_owned(), |i| format!("s{}", i + 1));
        let text = match c.kind {
            ChangeKind::Kept => format!("kept: prior {} is {}", name(c.before), name(c.after)),
            ChangeKind::Moved => format!(
                "moved {:.1} m: prior {} is {}",
                c.distance_m.unwrap_or(0.0),
                name(c.before),
                name(c.after)
            ),
            ChangeKind::Removed => format!("removed: prior {}", name(c.before)),
            ChangeKind::Added => format!("added: {}", name(c.after)),
        };
        markers.push(Marker {
            pose: RosPose::planar(at.x, at.y, LABEL_Z_M + 0.3, 0.0),
            scale: Point::new(0.0, 0.0, 0.2),
            color: colour,
            text: format!("{text} ({:.0} %)", 100.0 * c.confidence),
            ..marker(header, "change_labels", k, Marker::TEXT_VIEW_FACING)
        });
    }
    MarkerArray { markers }
}

/// Adds each source's kind to its label in `messages` (`iasm map --signatures`): "s1: 12
/// DoAs, speech".
pub fn label_kinds(messages: &mut MapMessages, signatures: &[Option<ssl::signature::Signature>]) {
    for m in &mut messages.sources.markers {
        if m.ns != "labels" {
            continue;
        }
        let sig = usize::try_from(m.id)
            .ok()
            .and_then(|k| signatures.get(k))
            .and_then(Option::as_ref);
        if let Some(s) = sig {
            m.text = format!("{}, {}", m.text, s.kind.name());
        }
    }
}

fn stamp_of(stops: &Stops<'_>, i: usize, fallback: i64) -> i64 {
    stops.stamps_ns.get(i).copied().unwrap_or(fallback)
}

/// A data set has no clock: its stops are placed one second apart from the epoch, which a
/// player shows as a map growing stop by stop.
pub fn stop_stamp_ns(stop: usize) -> i64 {
    i64::try_from(stop).unwrap_or(i64::MAX / 1_000_000_000) * 1_000_000_000
}

/// An MCAP file of map updates, built in memory (a map's messages are small; the grid is
/// sent once unless it changes) and written whole when finished, as every output of iasm is.
pub struct McapFile {
    path: std::path::PathBuf,
    writer: iasm_ros::mcap::Writer<std::io::Cursor<Vec<u8>>>,
    grid_sent: Option<OccupancyGrid>,
}

impl McapFile {
    /// Starts the file that [`McapFile::finish`] writes to `path`.
    ///
    /// # Errors
    /// When the MCAP header cannot be written.
    pub fn new(path: &std::path::Path) -> anyhow::Result<Self> {
        let writer = iasm_ros::mcap::Writer::new(std::io::Cursor::new(Vec::new()))
            .map_err(|e| anyhow::anyhow!("--mcap {}: {e}", path.display()))?;
        Ok(Self {
            path: path.to_owned(),
            writer,
            grid_sent: None,
        })
    }

    /// Adds an update at `log_time_ns` (the grid only when it differs from the last sent).
    ///
    /// # Errors
    /// When it cannot be written.
    pub fn add(&mut self, messages: &MapMessages, log_time_ns: i64) -> anyhow::Result<()> {
        let fresh = self
            .grid_sent
            .as_ref()
            .is_none_or(|g| g.data != messages.grid.data || g.origin != messages.grid.origin);
        messages
            .write(&mut self.writer, log_time_ns, fresh)
            .map_err(|e| anyhow::anyhow!("--mcap {}: {e}", self.path.display()))?;
        if fresh {
            self.grid_sent = Some(messages.grid.clone());
        }
        Ok(())
    }

    /// Ends the file and writes it whole to its path.
    ///
    /// # Errors
    /// When it cannot be finished or written; the message names the path.
    pub fn finish(self) -> anyhow::Result<()> {
        let bytes = self
            .writer
            .finish()
            .map_err(|e| anyhow::anyhow!("--mcap {}: {e}", self.path.display()))?
            .into_inner();
        crate::output::write_atomic(&self.path, &bytes)
    }
}

/// Writes one map update to `path`.
///
/// # Errors
/// When the file cannot be written.
pub fn write_mcap(
    path: &std::path::Path,
    messages: &MapMessages,
    log_time_ns: i64,
) -> anyhow::Result<()> {
    let mut f = McapFile::new(path)?;
    f.add(messages, log_time_ns)?;
    f.finish()
}

/// The messages of a map made from `survey`: its stops placed one second apart
/// ([`stop_stamp_ns`]), the map stamped at the last.
pub fn of_survey(survey: &crate::pipeline::Survey, result: &MapResult) -> MapMessages {
    let doas: Vec<Vec<f64>> = survey
        .doas_deg
        .iter()
        .map(|row| row.iter().flatten().copied().collect())
        .collect();
    let stamps: Vec<i64> = (0..survey.poses.len()).map(stop_stamp_ns).collect();
    let last = stamps.last().copied().unwrap_or(0);
    MapMessages::new(
        result,
        &Stops {
            poses: &survey.poses,
            stamps_ns: &stamps,
            doas_deg: &doas,
        },
        &survey.map,
        last,
    )
}

/// The messages of `result` after the stops of `session` so far, on `map`: stop `k` at
/// [`stop_stamp_ns`]`(k)`, the map stamped `stamp_ns`.
pub fn of_session(
    session: &crate::online::Session,
    result: &MapResult,
    map: &OccupancyMap,
    stamp_ns: i64,
) -> MapMessages {
    let stamps: Vec<i64> = (0..session.poses().len()).map(stop_stamp_ns).collect();
    MapMessages::new(
        result,
        &Stops {
            poses: session.poses(),
            stamps_ns: &stamps,
            doas_deg: session.doas_deg(),
        },
        map,
        stamp_ns,
    )
}
