//! Which peaks of a spectrum are sources, on plane waves and noise whose answer is known:
//! nothing where nothing sounds, the significance of a weak wave, an array pattern's
//! sidelobes, a third source an octave hears beyond N, and a linear array's two sides.

use crate::common::*;
use iasm_ssl::{Audio, ElevationRange, Localizer, Method, MicArray, SslConfig, wrap_deg};
use sim::signal::Signal;

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
