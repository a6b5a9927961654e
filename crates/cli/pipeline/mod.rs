//! The one place where recordings become DoAs and DoAs become a map.
//!
//! Every command that goes from recordings to a map goes through here, so that a setting
//! means the same thing in `map`, `eval`, `regress` and `demo`:
//!
//! ```text
//!  SurveyInputs ──► Survey::load ──► Survey { map, poses, doas_deg, truth } ──► Survey::map
//!  (files)          (localise_files                                              evaluate
//!                    when no DoA table)
//!  Simulated (a rendered scene) ──► Simulated::survey ──► the same Survey
//! ```
//!
//! A [`Survey`] is what one robot run gives the mapper: the occupancy map, a pose per stop,
//! the DoAs heard at each stop (a table in degrees, array frame, strongest first, as the
//! published tables and `iasm ssl` write it), and the true sources when known. The DoA
//! source (a table or the SSL) does not matter past this point.

use crate::dataset::read_timed_poses;
use crate::dataset::{Dataset, Table, first_with_ext, list_files, load_map, read_poses};
use crate::dataset::{read_recording, read_sources, read_table};
use crate::explain::MissedTally;
use crate::score::{DoaScore, score_doas};
use crate::settings::Settings;
use anyhow::{Context, Result, bail, ensure};
use asm::map::OccupancyMap;
use asm::ospa::{Ospa, ospa};
use asm::{IasmConfig, MapResult, Mapper, Pose, Variant};
use rayon::prelude::*;
use serde::Serialize;
use sim::scene::PreparedScene;
use ssl::{Audio, Doa, Localizer, Located, MicArray, Scratch, SslConfig};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

mod evaluate;
mod localise;
mod runs;
mod scene;
mod signatures;
mod survey;

pub use crate::robot_noise::RobotNoise;
pub use evaluate::*;
pub use localise::*;
pub use runs::*;
pub use scene::*;
pub use signatures::*;
pub use survey::*;
