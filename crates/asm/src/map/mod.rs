//! Occupancy grid maps in the ROS `map_server` format.
//!
//! A map is a YAML file of metadata (image, resolution, origin, negate, thresholds, mode)
//! and a PGM image. The ROS convention places the image's **lower-left** pixel at
//! `origin`: pixel column `i`, row `j` (row 0 at the top of the image) has its centre at
//! `x = origin_x + (i + 0.5) r`, `y = origin_y + (h - 1 - j + 0.5) r`.
//! (The authors' MATLAB code crops and flips the image, which shifts its map by about
//! 0.25 m in y against the poses; we follow ROS.)

mod format;
mod occupancy;

pub use occupancy::{
    Cell, MAX_CELLS, MAX_EXTENT_M, MAX_RESOLUTION_M, MIN_RESOLUTION_M, OccupancyMap, check_grid,
};
