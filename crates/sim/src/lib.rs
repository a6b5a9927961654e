//! Synthetic multichannel audio with known truth, for tests and benchmarks.
//!
//! # Overview
//!
//! - [`signal`]: source signals (white noise, a voiced harmonic series), seeded.
//! - [`farfield`]: plane waves from known directions, delayed exactly (fractional delays
//!   applied as a phase ramp) to each microphone: the analytic reference for DoA tests.
//!
//! - [`room`], [`ism`]: shoebox rooms and their impulse responses by the image-source
//!   method (Allen & Berkley, 1979), with fractional-delay arrivals and Schroeder's
//!   reverberation-time estimate.
//!
//! - [`plan`]: rooms whose floor plan is any simple polygon (an L, a corridor with
//!   alcoves), extruded: image sources checked for visibility per microphone for the
//!   early reflections, a diffuse late field after them.
//!
//! - [`render`]: what each microphone hears of sources in a room (FFT convolution with the
//!   image-source responses).
//!
//! - [`draw`]: whole scenes drawn at random from a seed (plans of six families, sources,
//!   arrays, paths): the benchmark no rule was written for.
//!
//! - [`scene`]: a robot carrying an array through a room with sources, from a TOML file,
//!   rendered stop by stop.
//!
//! # Example
//!
//! ```
//! use iasm_sim::{farfield::{PlaneWave, render}, signal::Signal};
//! let mics = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]];
//! let waves = [PlaneWave { azimuth_deg: 0.0, elevation_deg: 0.0, signal: Signal::Noise }];
//! let audio = render(&mics, &waves, 16_000, 1600, 343.0, None, 1);
//! assert_eq!((audio.len(), audio[0].len()), (2, 1600));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Conventions
//!
//! SI units; azimuth counter-clockwise from `x`, elevation above the `xy` plane, degrees at
//! the API; audio channel-major (`audio[mic][sample]`).

pub mod draw;
pub mod error;
pub mod farfield;
pub mod ism;
pub mod plan;
pub mod render;
pub mod room;
pub mod scene;
pub mod signal;

pub use error::SimError;
pub use plan::PlanRoom;
pub use room::{Room, Space};
