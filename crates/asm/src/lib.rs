//! Acoustic scene mapping with I-ASM (Fu, He, Wang, Qiao & Kong): from DoAs heard at a
//! robot's stops to a map of the sound sources around it.
//!
//! # Overview
//!
//! - [`map`]: ROS occupancy maps (YAML + PGM), with the ROS pixel-to-world convention.
//! - [`pf`]: the particle filter, its likelihood and low-variance resampling.
//! - [`dbscan`]: grid-indexed DBSCAN that is fastest where particle clouds are densest.
//! - [`assoc`]: the paper's implicit association of DoAs with a new source.
//! - [`mapper`]: I-ASM itself, the Filtering-Clustering-Implicit-Associating loop.
//! - [`online`]: the same, one stop at a time while the robot drives.
//! - [`ospa`]: the OSPA metric with its localisation and cardinality parts.
//! - [`align`]: how far a map lies from the truth once their frames agree (a diagnostic).
//! - [`diff`]: two maps of one building compared: sources kept, moved, removed, added.
//!
//! # Example
//!
//! ```
//! use iasm_asm::{IasmConfig, MapRng, Mapper, Pose, map::{Cell, OccupancyMap}, ospa::ospa};
//! use rand::SeedableRng;
//! // A free 4 x 4 m room, a robot at 8 stops, one source at (2, 3).
//! let map = OccupancyMap::new(80, 80, 0.05, [0.0, 0.0], vec![Cell::Free; 6400]);
//! let poses: Vec<Pose> = (0..8).map(|k| Pose { x: 0.5 + 0.4 * k as f64, y: 0.5, theta: 0.0 }).collect();
//! let doas: Vec<Vec<f64>> = poses.iter().map(|p| vec![(3.0 - p.y).atan2(2.0 - p.x)]).collect();
//! let result = Mapper::new(&map, &IasmConfig::default())?.run(&poses, &doas, &mut MapRng::seed_from_u64(1))?;
//! assert!(ospa(&result.positions(), &[[2.0, 3.0]], 1.0, 1.0).total < 0.2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Conventions
//!
//! SI units (m, s); angles in radians inside this crate (degrees only at the CLI's edges);
//! world frame right-handed, azimuth counter-clockwise from `x`; DoAs are in the array
//! frame, whose `x` axis is the robot's heading. All randomness comes from the caller's
//! `Rng`: the same seed gives the same map ([`MapRng`] is the generator the `iasm` CLI
//! seeds).
//!
//! Where these docs say why a default is what it is, they state the measurement that chose
//! it; `docs/decisions/` holds the decisions, `BENCHMARKS.md` today's figures and git the
//! history (the development journal: `git show 7ee1616:BENCHMARKS.md`).

pub mod align;
pub mod assoc;
pub mod dbscan;
pub mod diff;
pub mod error;
pub mod map;
pub mod mapper;
pub mod online;
pub mod ospa;
pub mod pf;

pub use error::{ConfigError, Error, MapError, Result};
pub use geom::{Pose, wrap_rad};
pub use mapper::{
    History, IasmConfig, MAX_PARTICLES, MapResult, Mapper, Profile, Refusal, Refused, Round,
    Source, SourceState, Stage, Stops, Trim, Variant,
};
pub use online::{OnlineMapper, StopUpdate};

/// The random-number generator the `iasm` pipeline seeds its maps with: xoshiro256++
/// (`rand_xoshiro`), whose output for a seed is fixed by its specification.
///
/// Why not `rand`'s `StdRng` (ChaCha12): a map draws two normal deviates per particle per
/// stop, and with ChaCha the generator took 45 % of a map's time (`perf`, arrangement II). A particle filter needs no cryptographic strength, only
/// good equidistribution, which xoshiro256++ has (it passes BigCrush and PractRand).
/// Any `Rng` can be given to [`Mapper::run`]; this one is what the CLI's seeds mean.
pub type MapRng = rand_xoshiro::Xoshiro256PlusPlus;
