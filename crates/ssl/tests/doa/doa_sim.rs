//! Analytic DoA tests: plane waves delayed exactly (a fractional delay applied as a phase
//! ramp in the frequency domain) to the microphones of an array, from known directions.
//! Every case runs with every method and reports all failures in one table.

use crate::common::*;
use iasm_ssl::{ElevationRange, Localizer, Method, MicArray, SslConfig, wrap_deg};
use proptest::prelude::*;
use sim::signal::Signal;

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
