//! What the analytic DoA tests share: plane waves delayed exactly (a fractional delay
//! applied as a phase ramp in the frequency domain) to the microphones of an array, from
//! known directions, and the localizer run on them. Each module uses some of it.

use iasm_ssl::{Audio, Localizer, Method, MicArray, SslConfig, wrap_deg};
use sim::farfield::{self, PlaneWave};
use sim::signal::Signal;

pub const SEED: u64 = 20_241_122;
pub const FS: u32 = 48_000;
pub const C: f64 = 343.0;

/// What each microphone hears of far-field sources at (azimuth, elevation) degrees, each
/// of unit power, plus white sensor noise at `snr_db`.
pub fn render(
    array: &MicArray,
    sources: &[(f64, f64, Signal)],
    seconds: f64,
    snr_db: f64,
    seed: u64,
) -> Audio {
    let waves: Vec<PlaneWave> = sources.iter().map(|&s| s.into()).collect();
    let n = (seconds * f64::from(FS)) as usize;
    let mics = farfield::render(array.positions(), &waves, FS, n, C, Some(snr_db), seed);
    let channels = mics
        .into_iter()
        .map(|ch| ch.into_iter().map(|v| (0.1 * v) as f32).collect())
        .collect();
    Audio::new(FS, channels).unwrap()
}

/// Runs every method on `audio` and returns one line per expected azimuth not found
/// within `tol` degrees among the first `expected.len()` DoAs.
pub fn misses(
    label: &str,
    array: &MicArray,
    audio: &Audio,
    expected: &[f64],
    tol: f64,
) -> Vec<String> {
    let mut out = Vec::new();
    for method in Method::BLOCKWISE {
        let config = SslConfig {
            method,
            num_peaks: expected.len(),
            ..SslConfig::default()
        };
        let doas = Localizer::new(array, FS, &config)
            .unwrap()
            .locate(audio)
            .unwrap();
        for &want in expected {
            let best = doas
                .iter()
                .map(|d| wrap_deg(d.azimuth_deg - want).abs())
                .fold(f64::INFINITY, f64::min);
            if best > tol {
                let got: Vec<String> = doas
                    .iter()
                    .map(|d| format!("{:.1}", d.azimuth_deg))
                    .collect();
                out.push(format!(
                    "{method}/{label}: want {want:.1}, got [{}] (off {best:.1})",
                    got.join(", ")
                ));
            }
        }
    }
    out
}

pub fn assert_none(failures: Vec<String>) {
    assert!(failures.is_empty(), "seed {SEED}:\n{}", failures.join("\n"));
}

/// One second of two white-noise plane waves on the default array, from azimuths `az_a`
/// and `az_b` (elevation 0, no sensor noise), scaled at each sample `i` by `gains(i)`.
pub fn two_noises(az_a: f64, az_b: f64, gains: impl Fn(usize) -> (f64, f64)) -> Audio {
    two_waves(
        &MicArray::default(),
        FS,
        Signal::Noise,
        None,
        (az_a, az_b),
        gains,
    )
}

/// What each microphone of `array` hears in `seconds` at `fs` of plane waves `(azimuth,
/// signal)` in the plane, summed: wave `k` of unit power (with white sensor noise `snr_db`
/// under it, none for `None`), rendered with seed `SEED + k` and scaled at sample `i` by
/// `gain(k, i)`.
pub fn mixed_waves(
    array: &MicArray,
    fs: u32,
    waves: &[(f64, Signal)],
    seconds: f64,
    snr_db: Option<f64>,
    gain: impl Fn(usize, usize) -> f64,
) -> Vec<Vec<f64>> {
    let n = (seconds * f64::from(fs)) as usize;
    let mut mix = vec![vec![0.0f64; n]; array.len()];
    for (k, &(az, signal)) in waves.iter().enumerate() {
        let wave: PlaneWave = (az, 0.0, signal).into();
        let mics = farfield::render(
            array.positions(),
            &[wave],
            fs,
            n,
            C,
            snr_db,
            SEED + k as u64,
        );
        for (m, ch) in mix.iter_mut().zip(mics) {
            for (i, (o, v)) in m.iter_mut().zip(ch).enumerate() {
                *o += gain(k, i) * v;
            }
        }
    }
    mix
}

/// One second at `fs` of two plane waves of `signal` heard by `array` from azimuths
/// `az.0` and `az.1` (elevation 0), scaled at each sample `i` by `gains(i)`, with white
/// sensor noise `snr_db` under a unit-power wave (none for `None`).
pub fn two_waves(
    array: &MicArray,
    fs: u32,
    signal: Signal,
    snr_db: Option<f64>,
    az: (f64, f64),
    gains: impl Fn(usize) -> (f64, f64),
) -> Audio {
    let waves = [(az.0, signal), (az.1, signal)];
    let mix = mixed_waves(array, fs, &waves, 1.0, snr_db, |k, i| {
        let (ga, gb) = gains(i);
        if k == 0 { ga } else { gb }
    });
    let channels = mix
        .iter()
        .map(|m| m.iter().map(|&v| (0.1 * v) as f32).collect())
        .collect();
    Audio::new(fs, channels).unwrap()
}

/// The DoAs the default array's localizer with `config` finds in `audio`.
pub fn locate(audio: &Audio, config: &SslConfig) -> Vec<iasm_ssl::Doa> {
    Localizer::new(&MicArray::default(), FS, config)
        .unwrap()
        .locate(audio)
        .unwrap()
}

/// Independent Gaussian noise on every channel (a stop where nothing sounds): a seeded
/// xorshift generator and the Box-Muller transform.
pub fn independent_noise(channels: usize, seconds: f64, seed: u64) -> Audio {
    let mut state = seed | 1;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let n = (seconds * f64::from(FS)) as usize;
    let channels = (0..channels)
        .map(|_| {
            (0..n)
                .map(|_| {
                    let (u, v) = (uniform(), uniform());
                    (0.01 * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()) as f32
                })
                .collect()
        })
        .collect();
    Audio::new(FS, channels).unwrap()
}

/// Two steady speech-shaped plane waves heard by `array` at 16 kHz for one second, from
/// azimuths `az_a` and `az_b` (the second at amplitude `gain_b`), with sensor noise 30 dB
/// under the first.
pub fn two_talkers(array: &MicArray, az_a: f64, az_b: f64, gain_b: f64) -> (u32, Audio) {
    let fs = 16_000;
    let audio = two_waves(
        array,
        fs,
        Signal::SpeechShaped,
        Some(30.0),
        (az_a, az_b),
        |_| (1.0, gain_b),
    );
    (fs, audio)
}

/// `audio` with channel `c` replaced by `with(i)` at sample `i`.
pub fn replaced(audio: &Audio, c: usize, with: impl Fn(usize) -> f32) -> Audio {
    let mut channels = audio.channels().to_vec();
    channels[c] = (0..audio.num_samples()).map(with).collect();
    Audio::new(audio.sample_rate(), channels).unwrap()
}
