//! A quiet source is not a loud one's copy: the source coherence of two directions
//! ([`iasm_ssl::SpatialCovariance::source_coherence`]) and the rule that reports a low peak
//! carrying a signal of its own ([`iasm_ssl::SslConfig::incoherent_relative`]), on plane waves
//! delayed exactly to the paper's array.

use iasm_ssl::{Audio, Localizer, Method, MicArray, SpatialCovariance, SslConfig, Stft, wrap_deg};
use sim::farfield::{self, PlaneWave, fractional_delay};
use sim::signal::Signal;

const SEED: u64 = 20_261_125;
const FS: u32 = 48_000;
const C: f64 = 343.0;

/// `seconds` of a white noise from `loud_deg` (elevation 0, unit gain), plus `quiet_gain`
/// times a noise from `quiet_deg`: the same noise delayed by `delay_s` (a reflection of the
/// loud source) when `copy`, else an independent one; white sensor noise `snr_db` below
/// the loud source.
fn scene(
    loud_deg: f64,
    quiet_deg: f64,
    quiet_gain: f64,
    copy: bool,
    delay_s: f64,
    snr_db: f64,
) -> Audio {
    let array = MicArray::default();
    let n = FS as usize;
    let mics = |az: f64, seed: u64| {
        let wave: PlaneWave = (az, 0.0, Signal::Noise).into();
        farfield::render(array.positions(), &[wave], FS, n, C, None, seed)
    };
    let loud = mics(loud_deg, SEED);
    let quiet: Vec<Vec<f64>> = mics(quiet_deg, if copy { SEED } else { SEED + 1 })
        .iter()
        .map(|x| fractional_delay(x, delay_s * f64::from(FS)))
        .collect();
    let noise = farfield::render(array.positions(), &[], FS, n, C, Some(0.0), SEED + 2);
    let channels = loud
        .iter()
        .zip(&quiet)
        .zip(&noise)
        .map(|((x, y), e)| {
            // Unit-power sensor noise, scaled to `snr_db` below the loud source.
            let e_gain = 10f64.powf(-snr_db / 20.0);
            (0..n)
                .map(|i| (0.1 * (x[i] + quiet_gain * y[i] + e_gain * e[i])) as f32)
                .collect()
        })
        .collect();
    Audio::new(FS, channels).unwrap()
}

fn unit(az_deg: f64) -> [f64; 3] {
    let az = az_deg.to_radians();
    [az.cos(), az.sin(), 0.0]
}

/// The source coherence of `a_deg` and `b_deg` in `audio`, through the default STFT
/// (1024-sample frames, half hop) and band (200 Hz - 8 kHz).
fn coherence(audio: &Audio, a_deg: f64, b_deg: f64) -> f64 {
    let stft = Stft::new(1024, 512).unwrap();
    let bins = (200 * 1024usize).div_ceil(FS as usize)..8000 * 1024 / FS as usize + 1;
    let spec = stft.analyze(audio, bins).unwrap();
    let cov = SpatialCovariance::of(&spec, 0..spec.num_frames());
    cov.source_coherence(
        MicArray::default().positions(),
        f64::from(FS),
        1024,
        C,
        unit(a_deg),
        unit(b_deg),
    )
    .expect("directions 100 degrees apart are resolved in most of the band")
}

/// A reflection carries its source's signal: a copy of the loud noise, 6 dB down and 3 ms
/// late (a path 1 m longer), is coherent with it (above 0.8: the delay is a seventh of a
/// 21-ms frame); an independent noise of the same level is not (below 0.2). With sensor
/// noise 10 dB below the loud source, independent of everything, the same holds: the
/// fit takes the noise out.
#[test]
fn a_reflection_is_coherent_with_its_source_and_another_source_is_not() {
    for snr_db in [40.0, 10.0] {
        let copy = coherence(&scene(40.0, -60.0, 0.5, true, 0.003, snr_db), 40.0, -60.0);
        let other = coherence(&scene(40.0, -60.0, 0.5, false, 0.003, snr_db), 40.0, -60.0);
        assert!(copy > 0.8, "SNR {snr_db} dB: a copy's coherence {copy:.3}");
        assert!(
            other < 0.2,
            "SNR {snr_db} dB: an independent source's {other:.3}"
        );
    }
}

/// A quiet source 6-9 dB below a loud one can stand between 0.15 and 0.3 of its height
/// in the pooled spectrum, under `min_relative`, beside the loud one's sidelobe (about
/// 0.2, 30 degrees from it). Whenever it does, above the sidelobe, and every rule but the
/// height lets it through (`min_relative = 0`), it is reported, because what the array
/// hears from it is a signal of its own; with the rule off it is not. (Below the
/// sidelobe it is not: the two-wave fit of the sidelobe's direction and its own leaves
/// the loud source out, both waves take some of it, and they look coherent; see
/// `iasm_ssl::covariance`.) The loud source's sidelobe is never
/// reported, nor is its reflection from the quiet source's direction at the same level:
/// they are copies. (How high a steady quiet source stands depends on the method: the
/// pairwise ones, pooling blocks that the loud source dominates, show it lower.)
#[test]
fn a_quiet_source_below_min_relative_is_reported_and_a_copy_is_not() {
    let (loud, quiet) = (40.0, -100.0);
    let near = |d: &iasm_ssl::Doa, az: f64| wrap_deg(d.azimuth_deg - az).abs() < 3.0;
    let floors = SslConfig::default().incoherent_relative..SslConfig::default().min_relative;
    let mut between = Vec::new();
    for method in Method::BLOCKWISE {
        let run = |audio: &Audio, config: SslConfig| {
            let config = SslConfig {
                method,
                num_peaks: 3,
                ..config
            };
            Localizer::new(&MicArray::default(), FS, &config)
                .unwrap()
                .locate(audio)
                .unwrap()
        };
        for db in [6.0, 7.0, 7.5, 8.0, 8.5, 9.0] {
            let gain = 10f64.powf(-db / 20.0);
            let other = scene(loud, quiet, gain, false, 0.003, 40.0);
            let copy = scene(loud, quiet, gain, true, 0.003, 40.0);
            let with = run(&other, SslConfig::default());
            assert!(near(&with[0], loud), "{method} {db} dB: {with:?}");
            let sidelobe = |doas: &[iasm_ssl::Doa]| doas.iter().any(|d| near(d, loud + 30.0));
            assert!(!sidelobe(&with), "{method} {db} dB: the sidelobe: {with:?}");
            let copied = run(&copy, SslConfig::default());
            assert!(
                !copied.iter().any(|d| near(d, quiet)) && !sidelobe(&copied),
                "{method} {db} dB: a copy of the loud source is reported: {copied:?}"
            );
            // Its height, when every other rule lets it through, and whether it stands
            // above the loud source's sidelobe (second with the sidelobe test off too).
            let heightless = SslConfig {
                min_relative: 0.0,
                ..SslConfig::default()
            };
            let height = run(&other, heightless.clone())
                .iter()
                .find(|d| near(d, quiet))
                .map_or(0.0, |d| d.relative);
            let open = SslConfig {
                sidelobe_ratio: 0.0,
                ..heightless
            };
            let second = run(&other, open).get(1).is_some_and(|d| near(d, quiet));
            if !second {
                continue;
            }
            if !floors.contains(&height) {
                continue;
            }
            between.push(format!("{method} {db} dB"));
            assert!(
                with.iter().any(|d| near(d, quiet)),
                "{method} {db} dB: the quiet source ({height:.2} high) is not reported: {with:?}"
            );
            let off = SslConfig {
                incoherent_relative: 0.0,
                ..SslConfig::default()
            };
            let without = run(&other, off);
            assert!(
                !without.iter().any(|d| near(d, quiet)),
                "{method} {db} dB, rule off: {without:?}"
            );
        }
    }
    // GCC-PHAT (7.5-9 dB with its 32-ms frame), SRP-PHAT, MUSIC and NormMUSIC at some
    // levels, measured.
    assert!(between.len() >= 6, "between the floors only: {between:?}");
    assert!(
        between.iter().filter(|c| c.starts_with("gcc-phat")).count() >= 3,
        "{between:?}"
    );
}

/// The two-wave statistic, written out in closed form, is the one-other case of the
/// general fit ([`SpatialCovariance::multiple_coherence`]), for copies and independent
/// sources alike; and fitting a third wave at a loud source's direction takes its leakage
/// out of a pair that it would otherwise make look coherent.
#[test]
fn the_pairwise_statistic_is_the_general_fit_of_two_waves() {
    let stft = Stft::new(1024, 512).unwrap();
    let bins = (200 * 1024usize).div_ceil(FS as usize)..8000 * 1024 / FS as usize + 1;
    let pos = MicArray::default().positions().to_vec();
    for copy in [true, false] {
        let audio = scene(40.0, -60.0, 0.5, copy, 0.003, 20.0);
        let spec = stft.analyze(&audio, bins.clone()).unwrap();
        let cov = SpatialCovariance::of(&spec, 0..spec.num_frames());
        let pair = cov.source_coherence(&pos, f64::from(FS), 1024, C, unit(40.0), unit(-60.0));
        let general =
            cov.multiple_coherence(&pos, f64::from(FS), 1024, C, &[unit(40.0)], unit(-60.0));
        let (pair, general) = (pair.unwrap(), general.unwrap());
        assert!(
            (pair - general).abs() < 1e-9,
            "copy {copy}: {pair} against {general}"
        );
    }
    // A quiet independent source 7 dB down at -100 degrees, and the loud source's sidelobe
    // direction (70 degrees): fitted with the sidelobe alone, the loud source leaks into
    // both waves and they look coherent; fitted with the loud source too, they do not.
    let audio = scene(40.0, -100.0, 10f64.powf(-7.0 / 20.0), false, 0.003, 40.0);
    let spec = stft.analyze(&audio, bins).unwrap();
    let cov = SpatialCovariance::of(&spec, 0..spec.num_frames());
    let quiet = unit(-100.0);
    let pair = cov
        .source_coherence(&pos, f64::from(FS), 1024, C, unit(70.0), quiet)
        .unwrap();
    let joint = cov
        .multiple_coherence(
            &pos,
            f64::from(FS),
            1024,
            C,
            &[unit(40.0), unit(70.0)],
            quiet,
        )
        .unwrap();
    assert!(
        pair > 0.6 && joint < 0.4,
        "pair {pair:.3}, joint {joint:.3}"
    );
}
