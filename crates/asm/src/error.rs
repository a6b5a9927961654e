//! Error types: [`ConfigError`] for parameters refused at construction, [`MapError`] for
//! occupancy maps that cannot be read, and [`Error`] for mapping inputs that do not fit.

use std::path::PathBuf;

/// A mapping parameter that [`crate::IasmConfig::validate`] refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// A parameter outside the range in which it means something for a robot in a room:
    /// refused when the settings are read, before any memory or time is spent on it.
    #[error("{name} = {value} is out of range: accepted {range}")]
    OutOfRange {
        /// The parameter.
        name: &'static str,
        /// Its value, as given.
        value: String,
        /// What is accepted, and why.
        range: &'static str,
    },
    /// A parameter that must be positive and finite is not.
    #[error("{name} must be positive and finite, got {value}")]
    NotPositive {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A parameter that must be finite is not.
    #[error("{name} must be finite, got {value}")]
    NotFinite {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A fraction outside `(0, 1]`.
    #[error("{name} must be in (0, 1], got {value}")]
    Fraction {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A count that must be at least one is zero.
    #[error("{0} must be at least 1")]
    Zero(&'static str),
    /// A profile name that is not known.
    #[error("unknown profile {0:?}; expected paper or robust")]
    UnknownProfile(String),
    /// A variant name that is not one of the paper's.
    #[error("unknown variant {0:?}; expected one of: ca, ws, wdp")]
    UnknownVariant(String),
}

/// An occupancy map that cannot be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MapError {
    /// The file could not be read.
    #[error("failed to read {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// The image a map YAML names could not be read.
    #[error("{yaml}: the image it names, {image}, could not be read")]
    Image {
        /// The YAML.
        yaml: PathBuf,
        /// The image, resolved against the YAML's folder.
        image: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// The YAML metadata is malformed or lacks a key.
    #[error("{path}: {message}")]
    Yaml {
        /// The YAML file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The PGM image is malformed.
    #[error("{path}: {message}")]
    Pgm {
        /// The image.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// An open region ([`crate::map::OccupancyMap::open_around`]) that cannot be built.
    #[error("an open region around the stops: {message}")]
    Open {
        /// What is wrong.
        message: String,
    },
    /// A grid whose geometry no map may have ([`crate::map::check_grid`]).
    #[error("an occupancy grid: {message}")]
    Grid {
        /// What is wrong.
        message: String,
    },
    /// A grid of more cells than a map may have ([`crate::map::MAX_CELLS`]): its cells
    /// would not fit in memory.
    #[error("an occupancy grid: {message}")]
    TooLarge {
        /// What is wrong.
        message: String,
    },
    /// A map with no known (free or occupied) cell: nowhere to put particles.
    #[error("{path}: the map has no known (free or occupied) cell")]
    NoKnownCell {
        /// The YAML file.
        path: PathBuf,
    },
}

/// Mapping inputs that do not fit together.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter was refused.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// Pose and DoA tables of different lengths.
    #[error("{poses} poses but {doas} rows of DoAs: they must match one to one")]
    LengthMismatch {
        /// Pose rows.
        poses: usize,
        /// DoA rows.
        doas: usize,
    },
    /// A row-cut flag per stop that does not match the poses.
    #[error("{poses} poses but {cut} row-cut flags: they must match one to one")]
    CutMismatch {
        /// Pose rows.
        poses: usize,
        /// Flags.
        cut: usize,
    },
    /// No pose at all.
    #[error("no observation point: the pose table is empty")]
    NoPoses,
    /// Not one stop lies in the occupancy map: the poses and the map are in other frames
    /// (or units), and no source could be found.
    #[error(
        "none of the {stops} stops lies in the occupancy map (stops x {:.1} to {:.1}, y {:.1} to {:.1} m; map x {:.1} to {:.1}, y {:.1} to {:.1} m): are the poses in the map's frame?",
        stops_box[0], stops_box[1], stops_box[2], stops_box[3],
        map_box[0], map_box[1], map_box[2], map_box[3]
    )]
    NoStopInMap {
        /// Stops.
        stops: usize,
        /// The stops' extent: x min, x max, y min, y max (m).
        stops_box: [f64; 4],
        /// The map's extent, likewise (m).
        map_box: [f64; 4],
    },
    /// A stop added to an online map lies outside the occupancy map.
    #[error(
        "stop {index} at ({x:.2}, {y:.2}) m lies outside the occupancy map (x {:.1} to {:.1}, y {:.1} to {:.1} m): are the poses in the map's frame?",
        map_box[0], map_box[1], map_box[2], map_box[3]
    )]
    StopOutsideMap {
        /// Zero-based index.
        index: usize,
        /// Its x (m).
        x: f64,
        /// Its y (m).
        y: f64,
        /// The map's extent: x min, x max, y min, y max (m).
        map_box: [f64; 4],
    },
    /// A pose with a NaN or infinite value.
    #[error("pose {index} (row {row}) has a non-finite value", row = index + 1)]
    NonFinitePose {
        /// Zero-based index.
        index: usize,
    },
    /// A DoA row with more than N azimuths.
    #[error("DoA row {row} has {got} azimuths but N = {n}", row = index + 1)]
    TooManyDoas {
        /// Zero-based row.
        index: usize,
        /// Azimuths in the row.
        got: usize,
        /// The configured N.
        n: usize,
    },
    /// A map with no known cell.
    #[error("the occupancy map has no known (free or occupied) cell")]
    EmptyMap,
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
