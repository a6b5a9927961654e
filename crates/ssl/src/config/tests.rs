//! The settings' defaults, names and checks.

use super::*;
use crate::MicArray;

/// 32 ms at every rate, rounded up to a length of 2s, 3s and 5s (the same bins, 31.25
/// Hz apart, at 16 and 48 kHz); the power of two at or above 20 ms for the subspace
/// methods; a set length stands.
#[test]
fn default_frame_is_32_ms_at_every_rate() {
    let c = SslConfig::default();
    for (rate, len) in [
        (8_000, 256),
        (16_000, 512),
        (22_050, 720),
        (44_100, 1440),
        (48_000, 1536),
        (96_000, 3072),
    ] {
        assert_eq!(c.frame_len_at(rate), len, "{rate} Hz");
        let ms = 1e3 * len as f64 / f64::from(rate);
        assert!((32.0..32.7).contains(&ms), "{rate} Hz: {ms} ms");
    }
    assert_eq!(smooth_at_or_above(1411), 1440);
    assert_eq!(smooth_at_or_above(7), 8);
    assert_eq!(smooth_at_or_above(1), 1);
    for method in [Method::Music, Method::NormMusic]
        .into_iter()
        .chain(Method::COHERENT)
    {
        let c = SslConfig {
            method,
            ..SslConfig::default()
        };
        assert_eq!(c.frame_len_at(48_000), 1024);
        assert_eq!(c.frame_len_at(44_100), 1024);
        assert_eq!(c.frame_len_at(16_000), 512);
    }
    let set = SslConfig {
        frame_len: Some(1000),
        ..SslConfig::default()
    };
    assert_eq!(set.frame_len_at(48_000), 1000);
}

#[test]
fn elevation_is_searched_for_3d_arrays_only() {
    let a3 = crate::MicArray::preset("iasm6").unwrap();
    let a2 = crate::MicArray::preset("respeaker6").unwrap();
    assert_eq!(ElevationRange::auto(&a3), ElevationRange::ROBOT);
    assert_eq!(ElevationRange::auto(&a2), ElevationRange::PLANE);
}

/// The default deflates where every source a robot maps is a plane wave to the array:
/// its far-field distance `2 D² f / c` at the band's top under a metre. The paper's
/// array (aperture 0.211 m: 2.08 m at 8 kHz) is not deflated unless the band stops
/// below 3.84 kHz; a ReSpeaker (64 mm: 0.19 m) always is; a setting decides for both.
#[test]
fn the_default_deflates_compact_arrays_only() {
    let iasm6 = MicArray::preset("iasm6").unwrap();
    let respeaker = MicArray::preset("respeaker4").unwrap();
    let d = SslConfig::default();
    let far = |a: &MicArray, f: f64| 2.0 * a.aperture().powi(2) * f / d.speed_of_sound;
    assert!(
        (far(&iasm6, 8000.0) - 2.08).abs() < 0.01,
        "{}",
        far(&iasm6, 8000.0)
    );
    assert!((far(&respeaker, 8000.0) - 0.19).abs() < 0.01);
    for rate in [16_000, 44_100, 48_000] {
        assert!(!d.deflates(&iasm6, rate));
        assert!(d.deflates(&respeaker, rate));
    }
    // The band's top, not the sample rate, sets it: capped at Nyquist (8 kHz at 16 kHz).
    let low = |fmax_hz: f64| SslConfig {
        fmax_hz,
        ..SslConfig::default()
    };
    assert!(!low(3900.0).deflates(&iasm6, 16_000));
    assert!(low(3700.0).deflates(&iasm6, 16_000));
    assert!(low(20_000.0).deflates(&iasm6, 7_200));
    for (set, want) in [(Some(true), true), (Some(false), false)] {
        let c = SslConfig {
            deflate: set,
            ..SslConfig::default()
        };
        assert_eq!(c.deflates(&iasm6, 16_000), want);
        assert_eq!(c.deflates(&respeaker, 16_000), want);
    }
}

#[test]
fn methods_round_trip_through_their_names() {
    for m in Method::ALL {
        assert_eq!(m.name().parse::<Method>().unwrap(), m);
    }
    assert!("musik".parse::<Method>().is_err());
}

#[test]
fn the_default_is_valid_and_bad_values_are_named() {
    SslConfig::default().validate().unwrap();
    let c = SslConfig {
        az_step_deg: 0.0,
        ..SslConfig::default()
    };
    assert!(
        matches!(
            c.validate(),
            Err(ConfigError::OutOfRange {
                name: "az_step_deg",
                ..
            })
        ),
        "{:?}",
        c.validate()
    );
    let c = SslConfig {
        num_peaks: 0,
        ..SslConfig::default()
    };
    assert!(matches!(
        c.validate(),
        Err(ConfigError::OutOfRange {
            name: "num_peaks",
            ..
        })
    ));
    let c = SslConfig {
        pool_top: 0,
        ..SslConfig::default()
    };
    assert_eq!(c.validate(), Err(ConfigError::PoolTop(0)));
    let c = SslConfig {
        speed_of_sound: -1.0,
        ..SslConfig::default()
    };
    assert!(matches!(
        c.validate(),
        Err(ConfigError::OutOfRange {
            name: "speed_of_sound",
            ..
        })
    ));
    let c = SslConfig {
        min_prominence: 1.5,
        ..SslConfig::default()
    };
    assert_eq!(c.validate(), Err(ConfigError::MinProminence(1.5)));
}

#[test]
fn unknown_keys_are_refused() {
    let e = toml::from_str::<SslConfig>("metod = \"mvdr\"").unwrap_err();
    assert!(e.to_string().contains("metod"), "{e}");
}
