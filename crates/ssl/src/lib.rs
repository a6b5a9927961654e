//! Sound source localisation for microphone arrays: angular spectra and ranked directions
//! of arrival (DoAs) from multichannel audio.
//!
//! # Overview
//!
//! A [`Localizer`] is built once per array, sample rate and [`SslConfig`]: it plans the STFT
//! ([`stft`]), the direction grid and every microphone pair's delay tables ([`grid`]).
//! [`Localizer::locate`] then transforms the audio, leaves out any channel that does not
//! hear the room (a dead or disconnected microphone: [`channels`]), computes one angular
//! spectrum per block of frames with the chosen [`Method`] (see [`method`]), pools the
//! blocks (by their mean where the recording's sound is steady and noise-like, by their
//! max elsewhere: [`steady`], [`Pooling::Auto`]), and returns the strongest peaks of the
//! pooled spectrum as [`Doa`]s, each max-pooled one placed where the mean of the blocks
//! that heard it best peaks ([`SslConfig::placement_share`]). On a compact array
//! (a ReSpeaker), each weaker DoA of a row is then refined with the stronger ones
//! projected out ([`deflate`], [`SslConfig::deflates`]). Given a recording of the robot
//! alone ([`Localizer::with_noise`]), every statistic subtracts the robot's own noise
//! ([`noise`]).
//!
//! # Example
//!
//! ```
//! use iasm_ssl::{Audio, Localizer, MicArray, Method, SslConfig};
//! // A click arriving from azimuth 90 degrees reaches mic 1 (at +y) before mic 0.
//! let array = MicArray::new("pair+", vec![[0.0, 0.0, 0.0], [0.0, 0.2, 0.0], [0.2, 0.0, 0.0]])?;
//! let fs = 16_000;
//! let noise: Vec<f32> = (0..16_000u32).map(|i| ((i.wrapping_mul(2654435761) >> 16) % 2001) as f32 / 1000.0 - 1.0).collect();
//! let lag = (0.2 / 343.0 * fs as f64).round() as usize; // 9 samples
//! let mic0 = noise[..16_000 - lag].to_vec();
//! let mic1 = noise[lag..].to_vec();
//! let mic2 = mic0.clone(); // broadside to a source at 90 degrees
//! let audio = Audio::new(fs, vec![mic0, mic1, mic2])?;
//! let config = SslConfig { method: Method::GccPhat, num_peaks: 1, ..SslConfig::default() };
//! let doas = Localizer::new(&array, fs, &config)?.locate(&audio)?;
//! assert!((doas[0].azimuth_deg - 90.0).abs() < 5.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Conventions
//!
//! - SI units: seconds, metres, hertz; angles are degrees at this crate's edges.
//! - The array frame is right-handed, `x` the robot's heading, `z` up; azimuth is
//!   counter-clockwise from `x`, wrapped to `[-180, 180)`; elevation is above the xy plane.
//! - Audio is channel-major (`channels[mic][sample]`), channel `i` is microphone `i`.
//! - The forward FFT is unnormalised; every statistic is normalised per bin, so the
//!   scale of the audio does not matter.
//!
//! Where these docs say why a default is what it is, they state the measurement that chose
//! it; `docs/decisions/` holds the decisions, `BENCHMARKS.md` today's figures and git the
//! history (the development journal: `git show 7ee1616:BENCHMARKS.md`).

pub mod array;
pub mod audio;
pub mod channels;
pub mod config;
pub mod covariance;
pub mod deflate;
pub mod error;
pub mod grid;
mod localizer;
pub mod method;
pub mod noise;
pub mod signature;
pub mod spectrum;
pub mod steady;
pub mod stft;

pub use array::{MicArray, fold_azimuth};
pub use audio::{Audio, read_wav};
pub use config::{Method, Pooling, SslConfig};
pub use covariance::SpatialCovariance;
pub use error::{ArrayError, ConfigError, Error, Result};
pub use grid::{DirectionGrid, ElevationRange};
pub use localizer::{Localizer, Located, Scratch};
pub use method::{MethodScratch, SpectrumEstimator, coherent, gcc_phat, music, mvdr, srp_phat};
pub use noise::NoiseField;
pub use spectrum::{AngularSpectrum, Doa, wrap_deg};
pub use stft::{Spectrogram, Stft};
