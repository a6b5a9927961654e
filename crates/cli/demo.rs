//! `iasm demo`: a built-in scene, localised end to end, against its truth.
//!
//! Four far-field voiced (speech-like) sources around the paper's array, all talking at
//! once and, like loudspeakers a metre or three from a robot, 10 to 30 degrees below the
//! array; rendered with exact fractional delays (the `sim` crate) and sensor noise, then
//! localised by every method.

use anyhow::Result;
use sim::farfield::{PlaneWave, render};
use sim::signal::Signal;
use ssl::{Audio, Localizer, Method, MicArray, SslConfig, wrap_deg};

use crate::Outcome;

/// The demo scene's sources: azimuth and elevation (degrees) and signal.
pub const SOURCES: [(f64, f64, Signal); 4] = [
    (-120.0, -30.0, Signal::Harmonic(105.0)),
    (-20.0, -10.0, Signal::Harmonic(220.0)),
    (45.0, -25.0, Signal::Harmonic(140.0)),
    (150.0, -15.0, Signal::Harmonic(185.0)),
];

/// One method's result on the demo scene.
#[derive(Clone, Debug)]
pub struct DemoRow {
    /// The method.
    pub method: Method,
    /// Found azimuths (degrees), strongest first.
    pub found: Vec<f64>,
    /// For each true source, the distance (degrees) to the nearest found azimuth.
    pub errors: Vec<f64>,
}

/// Renders the scene with `seed` and localises it with every method.
///
/// # Errors
/// Only if the built-in settings were refused, which would be a bug.
pub fn run_scene(seed: u64) -> Result<Vec<DemoRow>> {
    let fs = 48_000;
    let array = MicArray::default();
    let waves: Vec<PlaneWave> = SOURCES.iter().map(|&s| s.into()).collect();
    let mics = render(
        array.positions(),
        &waves,
        fs,
        3 * fs as usize,
        343.0,
        Some(20.0),
        seed,
    );
    let audio = Audio::new(
        fs,
        mics.into_iter()
            .map(|c| c.into_iter().map(|v| (0.05 * v) as f32).collect())
            .collect(),
    )?;
    Method::ALL
        .iter()
        .map(|&method| {
            let config = SslConfig {
                method,
                num_peaks: SOURCES.len(),
                ..SslConfig::default()
            };
            let doas = Localizer::new(&array, fs, &config)?.locate(&audio)?;
            let found: Vec<f64> = doas.iter().map(|d| d.azimuth_deg).collect();
            let errors = SOURCES
                .iter()
                .map(|&(az, _, _)| {
                    found
                        .iter()
                        .map(|f| wrap_deg(f - az).abs())
                        .fold(f64::INFINITY, f64::min)
                })
                .collect();
            Ok(DemoRow {
                method,
                found,
                errors,
            })
        })
        .collect()
}

/// Runs `iasm demo` and prints the table.
///
/// # Errors
/// As [`run_scene`].
pub fn run(seed: u64) -> Result<Outcome> {
    println!(
        "iasm demo: {} sources around the paper's 6-microphone array (iasm6), 3 s at 48 kHz, 20 dB SNR, seed {seed}",
        SOURCES.len()
    );
    let truth: Vec<String> = SOURCES.iter().map(|(a, _, _)| format!("{a:7.1}")).collect();
    println!("{:<10} {}", "truth", truth.join(" "));
    for row in run_scene(seed)? {
        let found: Vec<String> = row.found.iter().map(|a| format!("{a:7.1}")).collect();
        let worst = row.errors.iter().copied().fold(0.0, f64::max);
        println!(
            "{:<10} {}   (largest error {worst:.1} deg)",
            row.method.name(),
            found.join(" ")
        );
    }
    Ok(Outcome::Success)
}
