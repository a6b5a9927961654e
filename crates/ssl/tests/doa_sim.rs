//! Analytic DoA tests: plane waves delayed exactly (a fractional delay applied as a phase
//! ramp in the frequency domain) to the microphones of an array, from known directions.
//! Every case runs with every method and reports all failures in one table.

use iasm_ssl::{
    Audio, ElevationRange, Localizer, Method, MicArray, Pooling, Scratch, SslConfig, wrap_deg,
};
use proptest::prelude::*;
use sim::farfield::{self, PlaneWave};
use sim::signal::Signal;

const SEED: u64 = 20_241_122;
const FS: u32 = 48_000;
const C: f64 = 343.0;

/// What each microphone hears of far-field sources at (azimuth, elevation) degrees, each
/// of unit power, plus white sensor noise at `snr_db`.
fn render(
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
fn misses(label: &str, array: &MicArray, audio: &Audio, expected: &[f64], tol: f64) -> Vec<String> {
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

fn assert_none(failures: Vec<String>) {
    assert!(failures.is_empty(), "seed {SEED}:\n{}", failures.join("\n"));
}

#[test]
fn one_noise_source_is_found_within_2_degrees_all_around() {
    let array = MicArray::default();
    let mut failures = Vec::new();
    for k in 0..24 {
        let az = wrap_deg(-180.0 + 15.0 * k as f64 + 3.7);
        let audio = render(&array, &[(az, 0.0, Signal::Noise)], 0.4, 30.0, SEED + k);
        failures.extend(misses(
            &format!("noise@{az:.1}"),
            &array,
            &audio,
            &[az],
            2.0,
        ));
    }
    assert_none(failures);
}

#[test]
fn one_harmonic_source_is_found_within_2_degrees_all_around() {
    let array = MicArray::default();
    let mut failures = Vec::new();
    for k in 0..12 {
        let az = wrap_deg(-175.0 + 30.0 * k as f64 + 1.3);
        let f0 = 110.0 + 10.0 * k as f64;
        let audio = render(
            &array,
            &[(az, 0.0, Signal::Harmonic(f0))],
            0.4,
            30.0,
            SEED + k,
        );
        failures.extend(misses(
            &format!("harmonic{f0}@{az:.1}"),
            &array,
            &audio,
            &[az],
            2.0,
        ));
    }
    assert_none(failures);
}

#[test]
fn an_elevated_source_needs_the_elevation_search_on_a_3d_array() {
    // iasm6 has microphones at two heights, so a source 20 degrees above the plane adds a
    // vertical delay that a horizontal-only search mistakes for azimuth; searching
    // elevation recovers both angles. (The subspace methods find a lone source's azimuth
    // even in the plane: the steering vector nearest its subspace keeps the azimuth. Their
    // elevation search is checked below all the same.)
    let array = MicArray::default();
    let audio = render(&array, &[(63.0, 20.0, Signal::Noise)], 0.4, 30.0, SEED);
    let mut failures = Vec::new();
    for method in Method::PAPER {
        let flat = SslConfig {
            method,
            num_peaks: 1,
            elevation: Some(ElevationRange::PLANE),
            ..SslConfig::default()
        };
        let d = Localizer::new(&array, FS, &flat)
            .unwrap()
            .locate(&audio)
            .unwrap()[0];
        if wrap_deg(d.azimuth_deg - 63.0).abs() < 5.0 {
            failures.push(format!(
                "{method}: horizontal search unexpectedly unbiased: {d:?}"
            ));
        }
    }
    for method in Method::BLOCKWISE {
        // The default for a 3-D array searches elevation.
        let search = SslConfig {
            method,
            num_peaks: 1,
            ..SslConfig::default()
        };
        let d = Localizer::new(&array, FS, &search)
            .unwrap()
            .locate(&audio)
            .unwrap()[0];
        if wrap_deg(d.azimuth_deg - 63.0).abs() > 2.0 || (d.elevation_deg - 20.0).abs() > 10.0 {
            failures.push(format!(
                "{method}: elevation search: want (63, 20), got {d:?}"
            ));
        }
    }
    assert_none(failures);
}

#[test]
fn a_planar_array_needs_no_elevation_search() {
    // On a planar array elevation scales every delay by cos(el) alike: azimuth is unbiased.
    let array = MicArray::preset("respeaker6").unwrap();
    let audio = render(&array, &[(-120.0, 25.0, Signal::Noise)], 0.4, 30.0, SEED);
    assert_none(misses("planar-el25", &array, &audio, &[-120.0], 2.0));
}

#[test]
fn two_and_three_simultaneous_sources_are_all_found() {
    let array = MicArray::default();
    let mut failures = Vec::new();
    // Each scene is either all noise or all voiced: a voiced source's energy sits in a
    // quarter of the bins, and a broadband noise source beside it takes the rest (see the
    // `ssl` crate docs), which is a different test.
    let cases: [(&[f64], bool); 6] = [
        (&[-100.0, 40.0], false),
        (&[10.0, 50.0], false),
        (&[10.0, 50.0], true),
        (&[-150.0, -30.0, 90.0], false),
        (&[0.0, 45.0, 170.0], false),
        (&[0.0, 45.0, 170.0], true),
    ];
    for (k, &(azs, voiced)) in cases.iter().enumerate() {
        let sources: Vec<(f64, f64, Signal)> = azs
            .iter()
            .enumerate()
            .map(|(i, &a)| {
                (
                    a,
                    0.0,
                    if voiced {
                        Signal::Harmonic(110.0 + 47.0 * i as f64)
                    } else {
                        Signal::Noise
                    },
                )
            })
            .collect();
        let audio = render(&array, &sources, 0.6, 30.0, SEED + 100 + k as u64);
        failures.extend(misses(&format!("{azs:?}"), &array, &audio, azs, 3.0));
    }
    assert_none(failures);
}

#[test]
fn every_preset_localises_a_source() {
    // Small arrays at a robot's usual 16 kHz: the grid and band adapt to the geometry.
    let mut failures = Vec::new();
    for name in iasm_ssl::array::PRESETS {
        let array = MicArray::preset(name).unwrap();
        let audio = render(&array, &[(-37.0, 0.0, Signal::Noise)], 0.4, 30.0, SEED);
        failures.extend(misses(name, &array, &audio, &[-37.0], 3.0));
    }
    assert_none(failures);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    #[test]
    fn any_azimuth_is_found_within_2_degrees(az in -180.0f64..180.0, seed in 0u64..1000) {
        let array = MicArray::default();
        let audio = render(&array, &[(az, 0.0, Signal::Noise)], 0.3, 30.0, seed);
        let failures = misses("prop", &array, &audio, &[az], 2.0);
        prop_assert!(failures.is_empty(), "{}", failures.join("\n"));
    }

    #[test]
    fn rotating_array_and_source_together_keeps_the_doa(rot in -180.0f64..180.0, az in -180.0f64..180.0) {
        // The array turned by `rot` hears a source at `az + rot` (world) at `az` (array frame).
        let base = MicArray::default();
        let (s, c) = rot.to_radians().sin_cos();
        let turned: Vec<[f64; 3]> = base.positions().iter().map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]]).collect();
        let turned = MicArray::new("turned", turned).unwrap();
        let audio = render(&turned, &[(wrap_deg(az + rot), 0.0, Signal::Noise)], 0.3, 30.0, SEED);
        // Localise with the unrotated geometry: the array frame turned with the array.
        let failures = misses("rot", &base, &audio, &[az], 2.0);
        prop_assert!(failures.is_empty(), "{}", failures.join("\n"));
    }
}

/// N is an upper bound: one source in free field gives one DoA by default, and the
/// spectrum's ripples only when `min_relative` and `min_significance` are 0 (MBSS Locate's
/// behaviour).
#[test]
fn one_source_gives_one_doa_when_n_is_set_high() {
    let array = MicArray::default();
    for method in Method::BLOCKWISE {
        for (k, az) in [-150.0, -20.0, 75.0].into_iter().enumerate() {
            let audio = render(
                &array,
                &[(az, 0.0, Signal::Noise)],
                0.4,
                30.0,
                SEED + k as u64,
            );
            let locate = |min_relative| {
                let config = SslConfig {
                    method,
                    num_peaks: 4,
                    min_relative,
                    min_significance: if min_relative > 0.0 {
                        SslConfig::default().min_significance
                    } else {
                        0.0
                    },
                    sidelobe_ratio: if min_relative > 0.0 {
                        SslConfig::default().sidelobe_ratio
                    } else {
                        0.0
                    },
                    ..SslConfig::default()
                };
                Localizer::new(&array, FS, &config)
                    .unwrap()
                    .locate(&audio)
                    .unwrap()
            };
            let d = locate(SslConfig::default().min_relative);
            assert_eq!(d.len(), 1, "{method} {az}: {d:?}");
            assert!(
                wrap_deg(d[0].azimuth_deg - az).abs() < 2.0,
                "{method} {az}: {d:?}"
            );
            assert_eq!(locate(0.0).len(), 4, "{method} {az}");
        }
    }
}

#[test]
fn a_row_is_cut_only_when_a_further_peak_passes_the_thresholds() {
    // Three noise sources of equal power: N = 2 reports two of three (cut), N = 3 all
    // three (not cut: nothing else stands out), N = 5 the same three. A row's DoAs are
    // those of `locate`.
    let array = MicArray::default();
    let azs = [-150.0, -30.0, 90.0];
    let sources: Vec<(f64, f64, Signal)> = azs.iter().map(|&a| (a, 0.0, Signal::Noise)).collect();
    let audio = render(&array, &sources, 0.6, 30.0, SEED + 7);
    for method in Method::BLOCKWISE {
        let row = |num_peaks| {
            let config = SslConfig {
                method,
                num_peaks,
                ..SslConfig::default()
            };
            let loc = Localizer::new(&array, FS, &config).unwrap();
            let located = loc
                .locate_row_with_scratch(&audio, &mut iasm_ssl::Scratch::default())
                .unwrap();
            assert_eq!(located.doas, loc.locate(&audio).unwrap(), "{method}");
            located
        };
        let (two, three, five) = (row(2), row(3), row(5));
        assert_eq!((two.doas.len(), two.cut), (2, true), "{method}: {two:?}");
        assert_eq!(
            (three.doas.len(), three.cut),
            (3, false),
            "{method}: {three:?}"
        );
        assert_eq!(
            (five.doas.len(), five.cut),
            (3, false),
            "{method}: {five:?}"
        );
        // (MUSIC's subspace dimension is capped at N, so its spectrum depends on N.)
        if !matches!(method, Method::Music | Method::NormMusic) {
            assert_eq!(two.doas[..], three.doas[..2], "{method}");
        }
        for az in azs {
            assert!(
                three
                    .doas
                    .iter()
                    .any(|d| wrap_deg(d.azimuth_deg - az).abs() < 3.0),
                "{method}: {az} not in {three:?}"
            );
        }
    }
}

/// One second of two white-noise plane waves on the default array, from azimuths `az_a`
/// and `az_b` (elevation 0, no sensor noise), scaled at each sample `i` by `gains(i)`.
fn two_noises(az_a: f64, az_b: f64, gains: impl Fn(usize) -> (f64, f64)) -> Audio {
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
fn mixed_waves(
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
fn two_waves(
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
fn locate(audio: &Audio, config: &SslConfig) -> Vec<iasm_ssl::Doa> {
    Localizer::new(&MicArray::default(), FS, config)
        .unwrap()
        .locate(audio)
        .unwrap()
}

/// `block_frames` beyond the recording's length pools one spectrum of the whole recording
/// (pyroomacoustics' default use): every method finds two steady noise sources 100 degrees
/// apart within 2 degrees, and the sidelobe test's synthetic wave stays one short block.
#[test]
fn a_block_longer_than_the_recording_is_one_spectrum_of_it() {
    let audio = two_noises(30.0, 130.0, |_| (1.0, 1.0));
    for method in Method::BLOCKWISE {
        let config = SslConfig {
            method,
            elevation: Some(ElevationRange::PLANE),
            block_frames: 1_000_000,
            num_peaks: 2,
            ..SslConfig::default()
        };
        let doas = locate(&audio, &config);
        for want in [30.0, 130.0] {
            assert!(
                doas.iter()
                    .any(|d| wrap_deg(d.azimuth_deg - want).abs() <= 2.0),
                "{method:?}: no DoA near {want} in {doas:?}"
            );
        }
    }
}

/// A source heard for one block's span (80 ms with the default frame), 6 dB louder,
/// beside one heard throughout: max pooling keeps the burst's block high; averaging each
/// direction's 4 best blocks (`pool_top = 4`) keeps the steady source first and the burst
/// under 0.6 of that height.
#[test]
fn averaging_the_best_blocks_lets_a_one_block_burst_fade() {
    let n = FS as usize; // 1 s
    let (steady, burst) = (40.0, -100.0);
    // A block: 4 frames, each half a frame after the one before.
    let frame = SslConfig::default().frame_len_at(FS);
    let on = (n / 2)..(n / 2 + frame + 3 * frame / 2);
    let audio = two_noises(steady, burst, |i| {
        (1.0, if on.contains(&i) { 2.0 } else { 0.0 })
    });
    for method in Method::PAPER {
        let burst_height = |pool_top: usize| {
            let config = SslConfig {
                method,
                num_peaks: 4,
                min_relative: 0.0,
                pool_top,
                ..SslConfig::default()
            };
            let doas = locate(&audio, &config);
            assert!(
                wrap_deg(doas[0].azimuth_deg - steady).abs() < 2.0,
                "{method}, pool_top {pool_top}: the steady source is not first: {doas:?}"
            );
            doas.iter()
                .find(|d| wrap_deg(d.azimuth_deg - burst).abs() < 3.0)
                .map_or(0.0, |d| d.relative)
        };
        let (max, top4) = (burst_height(1), burst_height(4));
        assert!(
            max > 0.45,
            "{method}: max pooling keeps the burst at {max:.2}"
        );
        // The burst's frames fall in at most two blocks: averaged over four, about half.
        assert!(
            top4 < 0.6 * max,
            "{method}: 4 best blocks keep the burst at {top4:.2} (max pooling {max:.2})"
        );
    }
}

/// A steady source at 40 degrees, and a second at -100 degrees that sounds only from 0.4 to
/// 0.6 s while the first drops by 6 dB: for those blocks the second is the strongest thing
/// the array hears. Its DoA reports the blocks it dominated, and with `min_relative = 1`
/// (only the strongest peak passes by height) it is reported because of them, and only
/// because of them, with the decay gate on or off.
#[test]
fn a_source_that_dominates_blocks_is_reported_below_min_relative() {
    let n = FS as usize; // 1 s: blocks of 4 hops of half the default frame
    let (steady, second) = (40.0, -100.0);
    // Gains of the two sources inside the window `on` (samples).
    let mix = |on: std::ops::Range<usize>, ga: f64, gb: f64| {
        two_noises(steady, second, |i| {
            if on.contains(&i) {
                (ga, gb)
            } else {
                (1.0, 0.0)
            }
        })
    };
    let audio = mix(2 * n / 5..3 * n / 5, 0.5, 1.0);
    // The same 14 dB below the rest of the recording (beyond the vote's 10-dB floor) from 0.3 s
    // to the end: a pause, where nothing votes, not even once the decay gate's 0.5-s
    // memory has let its last blocks back into the pooling.
    let pause = mix(3 * n / 10..n, 0.1, 0.2);
    // Blocks wholly inside the 0.2-s window (of 4 hops of half a frame each); a block it
    // only partly covers may go either way.
    let frame = SslConfig::default().frame_len_at(FS);
    let block_s = 4.0 * (frame / 2) as f64 / f64::from(FS);
    let blocks = ((n - frame) / (frame / 2) + 1) as u32 / 4;
    let inside = (0.2 / block_s).floor() as u32 - 1;
    for method in Method::PAPER {
        let run_gated = |audio: &Audio, dominance_blocks: usize, decay_gate_db: f64| {
            // Height alone (`min_relative`) and the block count decide: the rule for low
            // peaks with a signal of their own (`incoherent_relative`) is off, as the
            // second source's signal is its own.
            let config = SslConfig {
                method,
                num_peaks: 4,
                min_relative: 1.0,
                incoherent_relative: 0.0,
                dominance_blocks,
                decay_gate_db,
                ..SslConfig::default()
            };
            locate(audio, &config)
        };
        let run_on = |audio: &Audio, dominance_blocks: usize| {
            run_gated(audio, dominance_blocks, SslConfig::default().decay_gate_db)
        };
        let run = |dominance_blocks: usize| run_on(&audio, dominance_blocks);
        let near = |d: &iasm_ssl::Doa, az: f64| wrap_deg(d.azimuth_deg - az).abs() < 2.0;
        let with = run(2);
        assert!(near(&with[0], steady), "{method}: {with:?}");
        let doa = with.iter().find(|d| near(d, second));
        let Some(doa) = doa else {
            panic!("{method}: the second source is not reported: {with:?}");
        };
        assert!(
            (inside..=inside + 2).contains(&doa.dominant_blocks),
            "{method}: the second source dominated {} blocks, {inside} to {} expected",
            doa.dominant_blocks,
            inside + 2
        );
        assert!(doa.relative < 1.0, "{method}: {doa:?}");
        // The steady source dominated every other block.
        assert!(
            with[0].dominant_blocks >= blocks - inside - 2,
            "{method}: {with:?}"
        );
        // Without the count, height alone decides: only the strongest peak.
        let without = run(0);
        assert_eq!(without.len(), 1, "{method}: {without:?}");
        assert!(near(&without[0], steady), "{method}: {without:?}");
        let quiet = run_on(&pause, 2);
        assert_eq!(quiet.len(), 1, "{method}: {quiet:?}");
        assert!(near(&quiet[0], steady), "{method}: {quiet:?}");
        // With the decay gate off (every block pooled, as MBSS Locate does) the vote
        // keeps its own floor: the second source is still reported, and the pause still
        // gives nothing.
        let ungated = run_gated(&audio, 2, 0.0);
        assert!(
            ungated.iter().any(|d| near(d, second)),
            "{method}, decay gate off: the second source is not reported: {ungated:?}"
        );
        let quiet = run_gated(&pause, 2, 0.0);
        assert_eq!(quiet.len(), 1, "{method}, decay gate off: {quiet:?}");
    }
}

/// A source at 40 degrees stops at 0.5 s; from then on a "reflection" from -100 degrees
/// decays as in a room of RT60 0.6 s (-60 dB in 0.6 s, 4.3 dB per 43-ms block). The decay
/// gate keeps its first blocks (within 10 dB of what preceded them), where the reflection
/// is the strongest direction; but each holds less than half the energy of the block
/// before, so none votes, and the reflection is not reported. (Counting them, it is: the
/// test fails with the falling-energy rule removed.)
#[test]
fn blocks_of_a_decay_give_no_dominance() {
    let n = FS as usize;
    let (source, reflection) = (40.0, -100.0);
    let stop = n / 2;
    // Amplitude falls 60 dB (a factor 1000) in 0.6 s.
    let decay = |i: usize| 1000f64.powf(-((i - stop) as f64) / (0.6 * f64::from(FS)));
    let audio = two_noises(source, reflection, |i| {
        if i < stop {
            (1.0, 0.0)
        } else {
            (0.0, decay(i))
        }
    });
    for method in Method::PAPER {
        // The "reflection" is an independent noise, not a copy of the source: the rule for
        // low peaks with a signal of their own (`incoherent_relative`) would report it.
        let config = SslConfig {
            method,
            num_peaks: 4,
            min_relative: 1.0,
            incoherent_relative: 0.0,
            ..SslConfig::default()
        };
        let doas = locate(&audio, &config);
        assert!(
            wrap_deg(doas[0].azimuth_deg - source).abs() < 2.0,
            "{method}: {doas:?}"
        );
        assert_eq!(doas.len(), 1, "{method}: the decay is reported: {doas:?}");
    }
}

/// Independent Gaussian noise on every channel (a stop where nothing sounds): a seeded
/// xorshift generator and the Box-Muller transform.
fn independent_noise(channels: usize, seconds: f64, seed: u64) -> Audio {
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

/// Where nothing sounds, nothing is reported: every peak of a spectrum of independent
/// sensor noise lies below the significance floor, with every method; with the floor off
/// the same recording gives its N random peaks (so the floor is what removes them).
#[test]
fn independent_noise_on_every_channel_gives_no_doa() {
    for (name, array) in [
        ("iasm6", MicArray::default()),
        ("respeaker4", MicArray::preset("respeaker4").unwrap()),
    ] {
        for k in 0..3 {
            let audio = independent_noise(array.len(), 0.5, SEED + k);
            for method in Method::BLOCKWISE {
                let config = SslConfig {
                    method,
                    ..SslConfig::default()
                };
                let doas = Localizer::new(&array, FS, &config)
                    .unwrap()
                    .locate(&audio)
                    .unwrap();
                assert!(doas.is_empty(), "{method}/{name}/{k}: {doas:?}");
                let off = SslConfig {
                    min_significance: 0.0,
                    ..config
                };
                let doas = Localizer::new(&array, FS, &off)
                    .unwrap()
                    .locate(&audio)
                    .unwrap();
                assert!(
                    !doas.is_empty(),
                    "{method}/{name}/{k}: nothing even without the floor"
                );
                assert!(
                    doas.iter().all(|d| d.significance.abs() < 6.0),
                    "{method}/{name}/{k}: noise stands out: {doas:?}"
                );
            }
        }
    }
}

/// The significance of a plane wave follows its expected value. With per-microphone SNR
/// `s` (linear), two microphones' bins at the true delay are complex Gaussians of
/// correlation `rho = s / (1 + s)`, and the mean of the product of their unit phasors is
/// `(pi / 4) rho 2F1(1/2, 1/2; 2; rho^2)`, about `(pi / 4) rho` for a weak source; the
/// statistic is that mean times `sqrt(2 F B P)`. A source 10 dB below the sensor noise,
/// 0.4 s long, stands far above the floor, and is reported.
#[test]
fn a_plane_wave_below_the_sensor_noise_is_significant() {
    let array = MicArray::default();
    let az = 37.0;
    let audio = render(&array, &[(az, 0.0, Signal::Noise)], 0.4, -10.0, SEED);
    let config = SslConfig {
        method: Method::GccPhat,
        num_peaks: 1,
        ..SslConfig::default()
    };
    let loc = Localizer::new(&array, FS, &config).unwrap();
    let doas = loc.locate(&audio).unwrap();
    assert_eq!(doas.len(), 1, "{doas:?}");
    assert!(wrap_deg(doas[0].azimuth_deg - az).abs() < 3.0, "{doas:?}");
    // F frames (the default frame, half of it the hop, over 0.4 s at 48 kHz), B bins of
    // the 200-8000 Hz band at 48000 / frame Hz, P = 15 pairs.
    let frame = config.frame_len_at(FS) as f64;
    let frames = (0.4 * f64::from(FS) - frame) / (frame / 2.0) + 1.0;
    let spacing = f64::from(FS) / frame;
    let bins = (8000.0 / spacing).floor() - (200.0 / spacing).ceil() + 1.0;
    let rho = 0.1f64 / 1.1;
    let hyp = 1.0 + rho * rho / 8.0; // 2F1(1/2, 1/2; 2; rho^2) to second order
    let mean = std::f64::consts::FRAC_PI_4 * rho * hyp;
    let want = mean * (2.0 * frames.floor() * bins * 15.0).sqrt();
    let got = doas[0].significance;
    assert!(
        (got / want - 1.0).abs() < 0.1,
        "significance {got:.1}, expected about {want:.1}"
    );
    assert!(got > 3.0 * config.min_significance, "{got}");
}

/// The directions (degrees) of a profile's local maxima of at least `floor`, beyond 15
/// degrees of its top: the sidelobes.
fn sidelobes(profile: &[f32], azimuths: &[f64], floor: f32) -> Vec<f64> {
    let n = profile.len();
    let top = (0..n)
        .max_by(|&a, &b| profile[a].total_cmp(&profile[b]))
        .unwrap();
    (0..n)
        .filter(|&i| {
            let (l, c, r) = (profile[(i + n - 1) % n], profile[i], profile[(i + 1) % n]);
            c >= l && c > r && c >= floor && wrap_deg(azimuths[i] - azimuths[top]).abs() > 15.0
        })
        .map(|i| azimuths[i])
        .collect()
}

#[test]
fn a_plane_waves_profile_has_the_sidelobes_of_the_arrays_pattern() {
    // GCC-PHAT's response to one plane wave is, pair by pair, the band's bins summed at
    // the difference of the pair's delays: sum_p sum_b cos(w_b (tau_p(u) - tau_p(u0))).
    // Computed here independently on the horizontal plane, its sidelobes stand where the
    // localizer's synthetic profile has them, within 2 degrees.
    let array = MicArray::default();
    let config = SslConfig {
        method: Method::GccPhat,
        elevation: Some(ElevationRange::PLANE),
        ..SslConfig::default()
    };
    let loc = Localizer::new(&array, FS, &config).unwrap();
    let azimuths = loc.grid().azimuths().to_vec();
    let frame = config.frame_len_at(FS) as f64;
    let bins: Vec<f64> = (1..=(frame as usize / 2))
        .map(|b| b as f64 * f64::from(FS) / frame)
        .filter(|f| (config.fmin_hz..=config.fmax_hz).contains(f))
        .collect();
    let p = array.positions();
    for az0 in [0.0, 40.0, -100.0] {
        let delays = |az: f64| -> Vec<f64> {
            let u = [az.to_radians().cos(), az.to_radians().sin()];
            (0..p.len())
                .flat_map(|i| (i + 1..p.len()).map(move |j| (i, j)))
                .map(|(i, j)| ((p[i][0] - p[j][0]) * u[0] + (p[i][1] - p[j][1]) * u[1]) / C)
                .collect()
        };
        let d0 = delays(az0);
        let analytic: Vec<f32> = azimuths
            .iter()
            .map(|&az| {
                delays(az)
                    .iter()
                    .zip(&d0)
                    .map(|(t, t0)| {
                        bins.iter()
                            .map(|f| (std::f64::consts::TAU * f * (t - t0)).cos())
                            .sum::<f64>()
                    })
                    .sum::<f64>() as f32
            })
            .collect();
        let mut sorted = analytic.clone();
        sorted.sort_by(f32::total_cmp);
        let (median, top) = (sorted[sorted.len() / 2], sorted[sorted.len() - 1]);
        let analytic: Vec<f32> = analytic
            .iter()
            .map(|v| (v - median) / (top - median))
            .collect();
        let ours = loc
            .plane_wave_profile(az0, 0.0, &mut iasm_ssl::Scratch::default())
            .unwrap();
        let want = sidelobes(&analytic, &azimuths, 0.1);
        let got = sidelobes(&ours, &azimuths, 0.1);
        assert!(!want.is_empty(), "{az0}: the pattern has sidelobes");
        for w in &want {
            assert!(
                got.iter().any(|g| wrap_deg(g - w).abs() <= 2.0),
                "{az0}: sidelobe at {w} not in {got:?}"
            );
        }
        let at = |az: f64| {
            azimuths
                .iter()
                .position(|&a| wrap_deg(a - az).abs() < 0.5)
                .unwrap()
        };
        assert!(
            (ours[at(az0)] - 1.0).abs() < 1e-3,
            "{az0}: the top is the wave's direction"
        );
    }
}

#[test]
fn a_sources_sidelobes_are_not_reported_as_sources() {
    // One noise source in free field with every threshold but the sidelobe test off, so
    // that every local maximum of the spectrum is a candidate: the peaks at the sidelobes
    // of the source's own pattern are reported without the test and not with it, and the
    // source is still found.
    let array = MicArray::default();
    let mut seen = 0;
    for method in [Method::GccPhat, Method::SrpPhat, Method::Mvdr] {
        for (k, az) in [25.0, -120.0, 100.0].into_iter().enumerate() {
            let audio = render(
                &array,
                &[(az, 0.0, Signal::Noise)],
                0.5,
                40.0,
                SEED + 30 + k as u64,
            );
            let open = SslConfig {
                method,
                num_peaks: 8,
                min_relative: 0.0,
                min_prominence: 0.0,
                min_significance: 0.0,
                dominance_blocks: 0,
                sidelobe_ratio: 0.0,
                ..SslConfig::default()
            };
            let loc = Localizer::new(&array, FS, &open).unwrap();
            let without = loc.locate(&audio).unwrap();
            let top = without[0];
            assert!(
                wrap_deg(top.azimuth_deg - az).abs() < 2.0,
                "{method} {az}: {top:?}"
            );
            let profile = loc
                .plane_wave_profile(
                    top.azimuth_deg,
                    top.elevation_deg,
                    &mut iasm_ssl::Scratch::default(),
                )
                .unwrap();
            let lobes = sidelobes(&profile, loc.grid().azimuths(), 0.1);
            let near_lobe = |d: &iasm_ssl::Doa| {
                lobes
                    .iter()
                    .any(|l| wrap_deg(d.azimuth_deg - l).abs() <= 3.0)
            };
            seen += usize::from(without.iter().any(near_lobe));
            let tested = SslConfig {
                sidelobe_ratio: SslConfig::default().sidelobe_ratio,
                ..open
            };
            let with = Localizer::new(&array, FS, &tested)
                .unwrap()
                .locate(&audio)
                .unwrap();
            assert_eq!(with[0], top, "{method} {az}");
            assert!(
                !with.iter().any(near_lobe),
                "{method} {az}: lobes {lobes:?}, {with:?}"
            );
        }
    }
    // Without the test, sidelobes are among the candidates in most cases.
    assert!(
        seen >= 5,
        "sidelobes reported in only {seen} of 9 cases without the test"
    );
}

/// Three sources of equal power: two white noises and a voiced one (harmonics of 150 Hz,
/// falling 6 dB per octave). Over the band the noises stand highest; from 700 Hz up the
/// voiced source wins the octaves' blocks, where its harmonics stand far above the noises'
/// share of each bin. With N = 2 the row holds the two noises and is cut, and the voiced
/// source is reported beyond N within 1.5 degrees, with its octaves' votes; with the votes
/// off, or with N = 3 (the row then holds all three and is not cut), nothing is reported
/// beyond N. A lone source gives nothing beyond N = 1 either: every octave's maxima fall on
/// it. The same for the pairwise methods and for NormMUSIC (its subspace set to three
/// sources, so that the third is in it at N = 2), whose octaves' spectra come from the
/// band's own pass.
#[test]
fn a_source_an_octave_hears_is_reported_beyond_n_in_a_cut_row() {
    let array = MicArray::default();
    let sources = [
        (-150.0, 0.0, Signal::Noise),
        (-30.0, 0.0, Signal::Noise),
        (90.0, 0.0, Signal::Harmonic(150.0)),
    ];
    let audio = render(&array, &sources, 0.6, 30.0, SEED + 11);
    let lone = render(&array, &[(40.0, 0.0, Signal::Noise)], 0.6, 30.0, SEED + 12);
    for method in [
        Method::GccPhat,
        Method::Mvdr,
        Method::SrpPhat,
        Method::NormMusic,
    ] {
        let row = |audio: &Audio, num_peaks, subband_votes| {
            let config = SslConfig {
                method,
                num_peaks,
                subband_votes,
                // MUSIC's subspace holds all three sources whatever N.
                music_sources: Some(3),
                ..SslConfig::default()
            };
            Localizer::new(&array, FS, &config)
                .unwrap()
                .locate_row_with_scratch(audio, &mut iasm_ssl::Scratch::default())
                .unwrap()
        };
        let (two, off, three) = (row(&audio, 2, 4), row(&audio, 2, 0), row(&audio, 3, 4));
        let near = |d: &iasm_ssl::Doa, az: f64, tol: f64| wrap_deg(d.azimuth_deg - az).abs() <= tol;
        assert!(two.cut, "{method}: {two:?}");
        for az in [-150.0, -30.0] {
            assert!(
                two.doas.iter().any(|d| near(d, az, 2.0)),
                "{method}: {two:?}"
            );
        }
        assert_eq!(two.extra.len(), 1, "{method}: {two:?}");
        assert!(near(&two.extra[0], 90.0, 1.5), "{method}: {two:?}");
        assert!(two.extra[0].dominant_blocks >= 4, "{method}: {two:?}");
        assert_eq!(two.all().count(), 3);
        // The same row without the extras (to rounding: with the votes on, the band's
        // spectrum is the sum of its octaves' and the rest's, summed apart).
        assert!(off.extra.is_empty(), "{method}: {off:?}");
        assert_eq!(off.doas.len(), two.doas.len(), "{method}");
        for (a, b) in off.doas.iter().zip(&two.doas) {
            assert!(near(a, b.azimuth_deg, 1e-3), "{method}: {a:?} {b:?}");
        }
        assert!(!three.cut && three.extra.is_empty(), "{method}: {three:?}");
        // Every peak reported, as MBSS Locate does, so that the lone source's row is cut
        // at N = 1 by its ripples.
        let bare = SslConfig {
            method,
            num_peaks: 1,
            min_relative: 0.0,
            min_prominence: 0.0,
            sidelobe_ratio: 0.0,
            min_significance: 0.0,
            ..SslConfig::default()
        };
        let one = Localizer::new(&array, FS, &bare)
            .unwrap()
            .locate_row_with_scratch(&lone, &mut iasm_ssl::Scratch::default())
            .unwrap();
        assert!(
            one.cut && near(&one.doas[0], 40.0, 2.0),
            "{method}: {one:?}"
        );
        assert!(one.extra.is_empty(), "{method}: {one:?}");
    }
}

#[test]
fn a_linear_array_reports_each_source_once_on_its_own_side_of_the_line() {
    // A Kinect's four microphones on a line along the heading (x = -11.3, 3.6, 7.6 and
    // 11.3 cm). It hears the angle to its line only: a source at -60 degrees sounds as one
    // at +60, and is reported there, once, never as two DoAs.
    let kinect = MicArray::new(
        "kinect",
        vec![
            [-0.113, 0.0, 0.0],
            [0.036, 0.0, 0.0],
            [0.076, 0.0, 0.0],
            [0.113, 0.0, 0.0],
        ],
    )
    .unwrap();
    assert_eq!(kinect.mirror_axis_deg(), Some(0.0));
    let mut failures = Vec::new();
    let cases: [(&[f64], &[f64]); 3] = [
        (&[-60.0], &[60.0]),
        (&[-60.0, 120.0], &[60.0, 120.0]),
        (&[30.0, -110.0], &[30.0, 110.0]),
    ];
    for (k, &(azs, folded)) in cases.iter().enumerate() {
        let sources: Vec<(f64, f64, Signal)> =
            azs.iter().map(|&a| (a, 0.0, Signal::Noise)).collect();
        let audio = render(&kinect, &sources, 0.6, 30.0, SEED + 300 + k as u64);
        for method in Method::BLOCKWISE {
            let config = SslConfig {
                method,
                num_peaks: 3,
                ..SslConfig::default()
            };
            let loc = Localizer::new(&kinect, FS, &config).unwrap();
            assert_eq!(loc.mirror_axis_deg(), Some(0.0));
            let got: Vec<f64> = loc
                .locate(&audio)
                .unwrap()
                .iter()
                .map(|d| d.azimuth_deg)
                .collect();
            let found = folded
                .iter()
                .all(|&f| got.iter().any(|&g| wrap_deg(g - f).abs() <= 3.0));
            if !found
                || got.len() != folded.len()
                || got.iter().any(|&g| !(0.0..=180.0).contains(&g))
            {
                failures.push(format!("{method}/{azs:?}: want {folded:?}, got {got:.1?}"));
            }
        }
    }
    assert_none(failures);
}

/// Two steady speech-shaped plane waves heard by `array` at 16 kHz for one second, from
/// azimuths `az_a` and `az_b` (the second at amplitude `gain_b`), with sensor noise 30 dB
/// under the first.
fn two_talkers(array: &MicArray, az_a: f64, az_b: f64, gain_b: f64) -> (u32, Audio) {
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

/// The row (N = 2, GCC-PHAT) that `array` gives for `audio` of two talkers, deflated or
/// not (`None`: as the array's default), with the deflation gate `gate`
/// ([`SslConfig::deflate_max_residual`]); the row must hold both and nothing more (not
/// cut).
fn two_talker_row(
    array: &MicArray,
    audio: &Audio,
    deflate: Option<bool>,
    gate: f64,
) -> Vec<iasm_ssl::Doa> {
    let config = SslConfig {
        method: Method::GccPhat,
        num_peaks: 2,
        deflate,
        deflate_max_residual: gate,
        ..SslConfig::default()
    };
    let located = Localizer::new(array, audio.sample_rate(), &config)
        .unwrap()
        .locate_row_with_scratch(audio, &mut Default::default())
        .unwrap();
    assert!(!located.cut, "the row holds both talkers and nothing more");
    located.doas
}

/// On the ReSpeaker 4-mic (6.4 cm across) the weaker of two talkers 60-120 degrees apart
/// peaks on the stronger one's wide lobe, 3-10 degrees off its plane wave (GCC-PHAT);
/// deflation (`SslConfig::deflate`: the stronger DoA projected out) puts it back within
/// 2.5 degrees and a third of that error, and leaves the stronger DoA where it was. It is
/// the default for so compact an array (`SslConfig::deflates`).
#[test]
fn deflation_moves_a_weak_talker_off_a_strong_ones_lobe() {
    let array = MicArray::preset("respeaker4").unwrap();
    // (strong, weak azimuth, weak amplitude)
    let cases = [
        (90.0, 30.0, 0.7),
        (90.0, -30.0, 0.6),
        (90.0, -20.0, 0.7),
        (0.0, -60.0, 0.6),
        (45.0, -30.0, 0.7),
        (90.0, 20.0, 0.8),
    ];
    for (strong, weak, gain) in cases {
        let (_, audio) = two_talkers(&array, strong, weak, gain);
        let row = |deflate: Option<bool>| two_talker_row(&array, &audio, deflate, 0.65);
        let (plain, deflated) = (row(Some(false)), row(Some(true)));
        assert_eq!(row(None), deflated, "{strong}/{weak}: the default deflates");
        assert_eq!(plain.len(), 2, "{strong}/{weak}: {plain:?}");
        let off = |d: &iasm_ssl::Doa| wrap_deg(d.azimuth_deg - weak).abs();
        let (before, after) = (off(&plain[1]), off(&deflated[1]));
        assert!(
            before >= 2.5,
            "{strong}/{weak}: the pooled peak lies only {before:.1} degrees off"
        );
        assert!(
            after <= 2.5 && after <= before / 3.0,
            "{strong}/{weak}: {before:.1} degrees off, deflated {after:.1}"
        );
        assert_eq!(deflated[0], plain[0]);
    }
}

/// The paper's array (0.211 m across: its far-field distance at 8 kHz is 2.08 m, beyond
/// most sources a robot maps) is not deflated by default: its row is the spectrum's, as
/// with deflation off, where deflation would have moved the weaker DoA.
#[test]
fn the_papers_array_keeps_its_peaks_by_default() {
    let array = MicArray::default();
    let (_, audio) = two_talkers(&array, 90.0, 20.0, 0.6);
    let row = |deflate: Option<bool>| two_talker_row(&array, &audio, deflate, 0.65);
    let plain = row(Some(false));
    assert_eq!(plain.len(), 2, "{plain:?}");
    assert_ne!(row(Some(true)), plain, "deflation moves the weaker DoA");
    assert_eq!(row(None), plain);
}

/// Deflation refines a row only when the row's DoAs explain what the array hears
/// (`SslConfig::deflate_max_residual`): two talkers in 30-dB sensor noise leave, once
/// both are projected out, a few percent of the power per dimension, so the default gate
/// (0.65) lets the weaker DoA be refined, as the gate off (0) does; a gate below that
/// share (0.01) leaves the row as the spectrum gave it.
#[test]
fn deflation_refines_a_row_only_when_its_doas_explain_the_field() {
    let array = MicArray::preset("respeaker4").unwrap();
    let (strong, weak) = (90.0, 30.0);
    let (_, audio) = two_talkers(&array, strong, weak, 0.7);
    let row = |deflate: bool, gate: f64| two_talker_row(&array, &audio, Some(deflate), gate);
    let plain = row(false, 0.65);
    assert_eq!(plain.len(), 2, "{plain:?}");
    let refined = row(true, 0.65);
    let off = |d: &iasm_ssl::Doa| wrap_deg(d.azimuth_deg - weak).abs();
    assert!(
        off(&refined[1]) < off(&plain[1]),
        "{plain:?} -> {refined:?}"
    );
    assert_eq!(row(true, 0.0), refined, "the gate off");
    assert_eq!(row(true, 0.01), plain, "a gate below the row's residual");
}

/// A steady noise source 12 dB under the sensor noise (per microphone), heard from 24
/// azimuths all around, pooled with max: the pooled peak lies where one block's noise put
/// the maximum; placed at the peak of the mean of its best quarter of the blocks
/// (`placement_share`, the default), the DoA lies nearer the bearing, for every method the
/// paper used (measured: mean |error| GCC-PHAT 0.91 -> 0.64 degrees, MVDR 0.62 -> 0.50).
/// The default pooling, [`Pooling::Auto`], pools such a steady recording by the mean of
/// all its blocks, nearer still (0.32 and 0.27 degrees; see
/// `a_steady_recording_is_pooled_by_its_mean_and_one_that_pauses_by_its_max`).
#[test]
fn a_doa_placed_from_its_best_blocks_lies_nearer_the_source_than_the_pooled_peak() {
    let array = MicArray::default();
    for method in Method::PAPER {
        let (mut pooled, mut placed, mut averaged) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..24 {
            let az = wrap_deg(-180.0 + 15.0 * k as f64 + 3.7);
            let audio = render(&array, &[(az, 0.0, Signal::Noise)], 0.5, -12.0, SEED + k);
            let error = |pooling: Pooling, share: f64| {
                let config = SslConfig {
                    method,
                    num_peaks: 1,
                    pooling,
                    placement_share: share,
                    ..SslConfig::default()
                };
                let doas = locate(&audio, &config);
                assert!(
                    !doas.is_empty(),
                    "{method}: no DoA for the source at {az:.1}"
                );
                wrap_deg(doas[0].azimuth_deg - az).abs()
            };
            pooled.push(error(Pooling::Max, 0.0));
            placed.push(error(Pooling::Max, SslConfig::default().placement_share));
            averaged.push(error(
                Pooling::default(),
                SslConfig::default().placement_share,
            ));
        }
        let mean = |e: &[f64]| e.iter().sum::<f64>() / e.len() as f64;
        let (pooled, placed, averaged) = (mean(&pooled), mean(&placed), mean(&averaged));
        assert!(
            placed < 0.85 * pooled && placed < 1.0,
            "{method}: mean |error| pooled peak {pooled:.2}, placed {placed:.2} degrees"
        );
        assert!(
            averaged < placed,
            "{method}: mean |error| placed {placed:.2}, mean pooling {averaged:.2} degrees"
        );
    }
}

/// What each microphone of `array` hears of plane waves `(azimuth, signal)` in the plane,
/// each of unit power and scaled at sample `i` by `gain(k, i)` (`k` the wave's index),
/// plus white sensor noise 30 dB under a unit-power wave; `seconds` long at 48 kHz.
fn gated_waves(
    array: &MicArray,
    waves: &[(f64, Signal)],
    seconds: f64,
    gain: impl Fn(usize, usize) -> f64,
) -> Audio {
    let mix = mixed_waves(array, FS, waves, seconds, None, gain);
    let noise = independent_noise(array.len(), seconds, SEED + 99);
    let channels = mix
        .iter()
        .zip(noise.channels())
        .map(|(m, e)| {
            // `independent_noise` is 0.01 RMS: 30 dB under the waves' 0.316.
            m.iter()
                .zip(e)
                .map(|(v, &w)| (0.316 * v) as f32 + w)
                .collect()
        })
        .collect();
    Audio::new(FS, channels).unwrap()
}

/// A case of the pooling test: its name, its waves, each wave's gain at each sample, and
/// the pooling the default should choose.
type PoolingCase = (
    &'static str,
    Vec<(f64, Signal)>,
    Box<dyn Fn(usize, usize) -> f64>,
    Pooling,
);

/// [`Pooling::Auto`] (the default) pools a recording by the mean of its blocks when its
/// blocks' levels are steady in every octave of the band and its spectrum is noise-like,
/// and by their max otherwise (`iasm_ssl::steady`). Steady: one or two noise sources sounding
/// throughout (white, pink or speech-shaped), or two of the same spectrum taking turns.
/// Not: a source that pauses (on for 0.2 s, off for 0.1 s, as syllables and words are),
/// two sources of different spectra taking turns every 0.2 s (whose summed level is
/// steady while each octave's is not), and a steady hum (a harmonic series at 180 Hz: lines,
/// not noise).
#[test]
fn a_steady_recording_is_pooled_by_its_mean_and_one_that_pauses_by_its_max() {
    let array = MicArray::default();
    let pooling_of = |audio: &Audio, method: Method| {
        let config = SslConfig {
            method,
            num_peaks: 2,
            ..SslConfig::default()
        };
        let loc = Localizer::new(&array, FS, &config).unwrap();
        loc.locate_row_with_scratch(audio, &mut Scratch::default())
            .unwrap()
            .pooling
    };
    let steady = |_: usize, _: usize| 1.0;
    let every_200_ms = |i: usize| (i / (FS as usize / 5)) % 2;
    let cases: [PoolingCase; 6] = [
        (
            "white noise",
            vec![(40.0, Signal::Noise)],
            Box::new(steady),
            Pooling::Mean,
        ),
        (
            "pink and speech-shaped noise",
            vec![(40.0, Signal::PinkNoise), (-100.0, Signal::SpeechShaped)],
            Box::new(steady),
            Pooling::Mean,
        ),
        (
            "a source that pauses",
            vec![(40.0, Signal::SpeechShaped)],
            Box::new(|_, i| {
                if (i % (FS as usize * 3 / 10)) < FS as usize / 5 {
                    1.0
                } else {
                    0.0
                }
            }),
            Pooling::Max,
        ),
        (
            "two spectra taking turns",
            vec![(40.0, Signal::Noise), (-100.0, Signal::SpeechShaped)],
            Box::new(move |k, i| if every_200_ms(i) == k { 1.0 } else { 0.0 }),
            Pooling::Max,
        ),
        (
            "a hum",
            vec![(40.0, Signal::Harmonic(180.0))],
            Box::new(steady),
            Pooling::Max,
        ),
        (
            "the same spectrum taking turns",
            vec![(40.0, Signal::Noise), (-100.0, Signal::Noise)],
            Box::new(move |k, i| if every_200_ms(i) == k { 1.0 } else { 0.0 }),
            Pooling::Mean,
        ),
    ];
    for (name, waves, gain, want) in &cases {
        let audio = gated_waves(&array, waves, 1.2, gain);
        for method in Method::PAPER {
            assert_eq!(pooling_of(&audio, method), *want, "{method}: {name}");
        }
    }
    // A pooling that is set is used as set.
    let audio = gated_waves(&array, &cases[0].1, 1.2, steady);
    let config = SslConfig {
        pooling: Pooling::Max,
        ..SslConfig::default()
    };
    let loc = Localizer::new(&array, FS, &config).unwrap();
    let row = loc
        .locate_row_with_scratch(&audio, &mut Scratch::default())
        .unwrap();
    assert_eq!(row.pooling, Pooling::Max);
}

/// `audio` with channel `c` replaced by `with(i)` at sample `i`.
fn replaced(audio: &Audio, c: usize, with: impl Fn(usize) -> f32) -> Audio {
    let mut channels = audio.channels().to_vec();
    channels[c] = (0..audio.num_samples()).map(with).collect();
    Audio::new(audio.sample_rate(), channels).unwrap()
}

/// A dead microphone (a channel of zeros) or a disconnected one (its own noise at the
/// others' level) is left out of the recording (`SslConfig::screen_channels`,
/// `iasm_ssl::channels`): the row is exactly the one the array of the other five microphones
/// gives for their channels, both talkers within 2 degrees, and it names the channel and
/// why. Working microphones are all kept.
#[test]
fn a_dead_or_disconnected_microphone_is_left_out() {
    let array = MicArray::default();
    let (fs, audio) = two_talkers(&array, 40.0, -100.0, 0.8);
    let config = SslConfig {
        method: Method::GccPhat,
        num_peaks: 3,
        ..SslConfig::default()
    };
    let row = |array: &MicArray, audio: &Audio, config: &SslConfig| {
        Localizer::new(array, fs, config)
            .unwrap()
            .locate_row_with_scratch(audio, &mut Scratch::default())
            .unwrap()
    };
    let healthy = row(&array, &audio, &config);
    assert_eq!(healthy.faulty_channels, vec![]);
    assert_eq!(healthy.microphones, 6);
    let level = (audio.channels()[3].iter().map(|v| v * v).sum::<f32>()
        / audio.num_samples() as f32)
        .sqrt();
    // Independent noise at the channel's level (48 000 samples; the first are used).
    let own = independent_noise(1, 1.0, 77).channels()[0].clone();
    let own_rms = (own.iter().map(|v| v * v).sum::<f32>() / own.len() as f32).sqrt();
    let keep = [0usize, 1, 2, 4, 5];
    let five = MicArray::new(
        "iasm6 without 3",
        keep.iter().map(|&i| array.positions()[i]).collect(),
    )
    .unwrap();
    let five_config = SslConfig {
        screen_channels: false,
        ..config.clone()
    };
    for (what, broken) in [
        ("zeros", replaced(&audio, 3, |_| 0.0)),
        (
            "its own noise",
            replaced(&audio, 3, |i| own[i] * level / own_rms),
        ),
    ] {
        let got = row(&array, &broken, &config);
        let others = Audio::new(
            fs,
            keep.iter().map(|&i| broken.channels()[i].clone()).collect(),
        )
        .unwrap();
        let want = row(&five, &others, &five_config);
        assert_eq!(
            got.faulty_channels.len(),
            1,
            "{what}: {:?}",
            got.faulty_channels
        );
        assert_eq!(got.faulty_channels[0].0, 3, "{what}");
        assert_eq!(got.microphones, 5, "{what}");
        assert_eq!(got.doas, want.doas, "{what}");
        for az in [40.0, -100.0] {
            assert!(
                got.doas
                    .iter()
                    .any(|d| wrap_deg(d.azimuth_deg - az).abs() < 2.0),
                "{what}: {az} not in {:?}",
                got.doas
            );
        }
    }
}

/// Faulty channels are left out only where the others can localise by themselves: on a
/// triangle of microphones, one dead leaves a line (whose DoAs would be folded onto one
/// side of it, the rest of the data set's not), so the row keeps every channel and still
/// names the dead one; two dead leave one microphone, which hears no direction, and the
/// row is empty.
#[test]
fn faulty_channels_are_kept_where_the_others_cannot_localise_alone() {
    let triangle = MicArray::new(
        "triangle",
        vec![[0.1, 0.0, 0.0], [-0.05, 0.0866, 0.0], [-0.05, -0.0866, 0.0]],
    )
    .unwrap();
    let (fs, audio) = two_talkers(&triangle, 40.0, -100.0, 0.5);
    let config = SslConfig {
        method: Method::GccPhat,
        num_peaks: 2,
        ..SslConfig::default()
    };
    let loc = Localizer::new(&triangle, fs, &config).unwrap();
    let row = |audio: &Audio| {
        loc.locate_row_with_scratch(audio, &mut Scratch::default())
            .unwrap()
    };
    let one_dead = replaced(&audio, 2, |_| 0.0);
    let got = row(&one_dead);
    assert_eq!(got.microphones, 3);
    assert_eq!(got.faulty_channels.len(), 1);
    assert_eq!(got.faulty_channels[0].0, 2);
    assert!(!got.doas.is_empty());
    let two_dead = replaced(&one_dead, 1, |_| 0.0);
    let got = row(&two_dead);
    assert_eq!(got.microphones, 1);
    let dead: Vec<usize> = got.faulty_channels.iter().map(|f| f.0).collect();
    assert_eq!(dead, vec![1, 2]);
    assert!(got.doas.is_empty(), "{:?}", got.doas);
}
