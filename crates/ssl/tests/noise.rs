//! The robot's own noise subtracted (`iasm_ssl::noise`): a talker 10 dB below a fan that moves
//! with the array is found once a recording of the fan alone is given, by every method.
//! Plane waves delayed exactly to the paper's array, so the bearings are known.

use iasm_ssl::{Audio, Error, Localizer, Method, MicArray, SslConfig, wrap_deg};
use sim::farfield::{self, PlaneWave};
use sim::signal::Signal;

const FS: u32 = 16_000;
const C: f64 = 343.0;
const TALKER_AZ: f64 = 60.0;
/// The fan: behind the array and below it, in the robot's body.
const FAN: (f64, f64) = (180.0, -40.0);

/// `seconds` of plane waves `(azimuth, elevation, gain)` of white noise heard by `array`,
/// the signals drawn with `seed`.
fn heard(array: &MicArray, waves: &[(f64, f64, f64)], seconds: f64, seed: u64) -> Audio {
    let n = (seconds * f64::from(FS)) as usize;
    let mut mix = vec![vec![0.0f64; n]; array.len()];
    for (k, &(az, el, gain)) in waves.iter().enumerate() {
        let wave: PlaneWave = (az, el, Signal::Noise).into();
        let mics = farfield::render(array.positions(), &[wave], FS, n, C, None, seed + k as u64);
        for (m, ch) in mix.iter_mut().zip(mics) {
            for (o, v) in m.iter_mut().zip(ch) {
                *o += gain * v;
            }
        }
    }
    let channels = mix
        .iter()
        .map(|m| m.iter().map(|&v| (0.05 * v) as f32).collect())
        .collect();
    Audio::new(FS, channels).unwrap()
}

/// The fan 10 dB above the talker, as a stop hears them; and the fan alone, another
/// stretch of its noise, as the user records it.
fn stop_and_fan_alone(array: &MicArray) -> (Audio, Audio) {
    let fan_gain = 10f64.powf(10.0 / 20.0);
    let stop = heard(
        array,
        &[(TALKER_AZ, 0.0, 1.0), (FAN.0, FAN.1, fan_gain)],
        1.0,
        11,
    );
    let alone = heard(array, &[(FAN.0, FAN.1, fan_gain)], 3.0, 901);
    (stop, alone)
}

fn first_azimuth(loc: &Localizer, audio: &Audio) -> f64 {
    loc.locate(audio).unwrap()[0].azimuth_deg
}

#[test]
fn a_talker_under_the_robots_fan_is_found_once_the_fan_alone_is_given() {
    let array = MicArray::default();
    let (stop, alone) = stop_and_fan_alone(&array);
    let mut failures = Vec::new();
    for method in Method::BLOCKWISE {
        let config = SslConfig {
            method,
            num_peaks: 2,
            ..SslConfig::default()
        };
        let plain = Localizer::new(&array, FS, &config).unwrap();
        // Without the recording, the fan is the strongest direction.
        let without = first_azimuth(&plain, &stop);
        if wrap_deg(without - FAN.0).abs() > 5.0 {
            failures.push(format!(
                "{method}: without the noise, first DoA {without:.1}, not the fan"
            ));
        }
        let less = plain.with_noise(&alone).unwrap();
        assert!(less.noise().is_some());
        // The method's response to an ideal plane wave (the sidelobe rule's) is the
        // method's, not the recording's: the robot's noise is no part of it.
        let mut scratch = iasm_ssl::Scratch::default();
        let profile = |l: &Localizer, s: &mut iasm_ssl::Scratch| {
            l.plane_wave_profile(TALKER_AZ, 0.0, s).unwrap()
        };
        let plain = Localizer::new(&array, FS, &config).unwrap();
        if profile(&plain, &mut scratch) != profile(&less, &mut scratch) {
            failures.push(format!(
                "{method}: the plane wave's profile moved with the noise"
            ));
        }
        let with = first_azimuth(&less, &stop);
        if wrap_deg(with - TALKER_AZ).abs() > 2.0 {
            failures.push(format!(
                "{method}: with the noise, first DoA {with:.1}, not the talker at {TALKER_AZ}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_noise_field_is_the_mean_cross_spectrum_of_the_recording() {
    // One plane wave: every bin's field is rank one, N_ij = P e^{i w (lead_i - lead_j)},
    // with the same power at every microphone: |N_ij| = N_ii = N_jj.
    let array = MicArray::default();
    let alone = heard(&array, &[(FAN.0, FAN.1, 1.0)], 2.0, 5);
    let loc = Localizer::new(&array, FS, &SslConfig::default())
        .unwrap()
        .with_noise(&alone)
        .unwrap();
    let field = loc.noise().unwrap();
    assert_eq!(field.num_channels(), array.len());
    assert!(field.frames() >= iasm_ssl::noise::MIN_NOISE_FRAMES);
    let mut worst = 0.0f64;
    for b in field.bins().step_by(7) {
        let p0 = f64::from(field.power(b, 0));
        for i in 0..array.len() {
            for j in 0..array.len() {
                let n = field.cross(b, i, j);
                let (pi, pj) = (f64::from(field.power(b, i)), f64::from(field.power(b, j)));
                // Hermitian, and coherent: |N_ij|^2 = N_ii N_jj.
                assert_eq!(n, field.cross(b, j, i).conj());
                worst = worst.max((f64::from(n.norm()) / (pi * pj).sqrt() - 1.0).abs());
                worst = worst.max((pi / p0 - 1.0).abs());
            }
        }
    }
    assert!(
        worst < 0.02,
        "a plane wave's field is rank one: off by {worst:.4}"
    );
    // The field of three of the microphones is theirs.
    let sub = field.subset(&[4, 0, 2]);
    let b = field.bins().start + 10;
    assert_eq!(sub.cross(b, 0, 2), field.cross(b, 4, 2));
    assert_eq!(sub.cross(b, 1, 1), field.cross(b, 0, 0));
}

#[test]
fn a_noise_recording_that_does_not_fit_is_refused() {
    let array = MicArray::default();
    let loc = || Localizer::new(&array, FS, &SslConfig::default()).unwrap();
    // Too short to estimate a covariance from (a tenth of a second).
    let short = heard(&array, &[(FAN.0, FAN.1, 1.0)], 0.1, 5);
    match loc().with_noise(&short) {
        Err(Error::NoiseTooShort { frames, min }) => assert!(frames < min),
        other => panic!("a 0.1-s noise recording: {other:?}"),
    }
    // Another array's channels, another rate.
    let three = MicArray::new("three", array.positions()[..3].to_vec()).unwrap();
    let other = heard(&three, &[(FAN.0, FAN.1, 1.0)], 1.0, 5);
    assert!(matches!(
        loc().with_noise(&other),
        Err(Error::ChannelMismatch {
            expected: 6,
            got: 3
        })
    ));
    let resampled = Audio::new(
        48_000,
        heard(&array, &[(0.0, 0.0, 1.0)], 1.0, 5)
            .channels()
            .to_vec(),
    )
    .unwrap();
    assert!(matches!(
        loc().with_noise(&resampled),
        Err(Error::SampleRateMismatch { .. })
    ));
}
