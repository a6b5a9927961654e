//! The localizer's own tests: gates, bands, channels.

use super::*;

#[test]
fn localizer_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Localizer>();
}

#[test]
fn the_decay_gate_drops_the_decay_and_keeps_a_new_onset() {
    // 16 kHz: noise for 0.5 s, then a decay at RT60 0.5 s (-60 dB in 0.5 s) for 0.5 s,
    // then noise again. Blocks are 4 hops of 256 samples (16 ms): 64 ms, and a frame
    // reaches 32 ms beyond its start.
    let fs = 16_000;
    let n = 3 * fs as usize / 2;
    let mut state = 1u64;
    let mut noise = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) as f64 / (1u64 << 31) as f64 - 1.0) as f32
    };
    let ch: Vec<Vec<f32>> = (0..6)
        .map(|_| {
            (0..n)
                .map(|i| {
                    let t = i as f64 / f64::from(fs);
                    let g = if (0.5..1.0).contains(&t) {
                        10f64.powf(-3.0 * (t - 0.5) / 0.5) // -60 dB in 0.5 s
                    } else {
                        1.0
                    };
                    (g as f32) * noise()
                })
                .collect()
        })
        .collect();
    let audio = Audio::new(fs, ch).unwrap();
    let loc = Localizer::new(&MicArray::default(), fs, &SslConfig::default()).unwrap();
    let spec = loc.stft.analyze(&audio, loc.bins.clone()).unwrap();
    let nf = spec.num_frames();
    let nb = nf / loc.config.block_frames;
    let frames = |b: usize| b * nf / nb..(b + 1) * nf / nb;
    let keep = loc.decay_gate(&spec, nb, &frames);
    let hop = loc.stft.hop();
    let block_s = |b: usize| (frames(b).start * hop) as f64 / f64::from(fs);
    for b in 0..nb {
        let (t0, t1) = (block_s(b), block_s(b) + 0.064 + 0.032);
        if t1 < 0.5 || t0 > 1.0 {
            assert!(
                keep[b],
                "block {b} at {t0:.2} s (sound) was dropped: {keep:?}"
            );
        } else if t0 > 0.65 && t1 <= 1.0 {
            // More than 0.15 s (18 dB) into the decay.
            assert!(
                !keep[b],
                "block {b} at {t0:.2} s (decay) was kept: {keep:?}"
            );
        }
    }
    // With the gate off, every block is pooled.
    let off = Localizer::new(
        &MicArray::default(),
        fs,
        &SslConfig {
            decay_gate_db: 0.0,
            ..SslConfig::default()
        },
    )
    .unwrap();
    assert!(off.decay_gate(&spec, nb, &frames).iter().all(|&k| k));
}

#[test]
fn a_band_above_nyquist_is_refused() {
    let c = SslConfig {
        fmin_hz: 8500.0,
        fmax_hz: 9000.0,
        ..SslConfig::default()
    };
    let e = Localizer::new(&MicArray::default(), 16_000, &c).unwrap_err();
    assert!(matches!(e, ConfigError::Band { .. }), "{e}");
}

#[test]
fn wrong_channel_count_is_refused() {
    let loc = Localizer::new(&MicArray::default(), 16_000, &SslConfig::default()).unwrap();
    let audio = Audio::new(16_000, vec![vec![0.0; 4000]; 4]).unwrap();
    let e = loc.locate(&audio).unwrap_err();
    assert!(
        matches!(
            e,
            Error::ChannelMismatch {
                expected: 6,
                got: 4
            }
        ),
        "{e}"
    );
}

/// An STFT computed elsewhere and handed over as frames gives the DoAs the recording gives
/// (same frames, same band), and a plane wave's direction; a wrong shape or a band the STFT
/// does not hold is refused.
#[test]
fn an_stft_given_as_frames_is_located_as_its_recording() {
    let array = MicArray::default();
    let fs = 16_000u32;
    let az = 120f64.to_radians();
    let u = [az.cos(), az.sin(), 0.0];
    let mut state = 9u64;
    let src: Vec<f32> = (0..24_000)
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as f64 / (1u64 << 31) as f64 - 1.0) as f32 * 0.3
        })
        .collect();
    // Each microphone hears the source `p . u / c` before the array's centre: whole
    // samples of delay, from 20 samples of margin.
    let channels: Vec<Vec<f32>> = array
        .positions()
        .iter()
        .map(|p| {
            let lead = (p[0] * u[0] + p[1] * u[1]) / 343.0 * f64::from(fs);
            let start = (20.0 + lead).round() as usize;
            src[start..start + 20_000].to_vec()
        })
        .collect();
    let audio = Audio::new(fs, channels).unwrap();
    let config = SslConfig {
        method: crate::Method::Mvdr,
        num_peaks: 1,
        ..SslConfig::default()
    };
    let loc = Localizer::new(&array, fs, &config).unwrap();
    let want = loc
        .locate_row_with_scratch(&audio, &mut Scratch::default())
        .unwrap();
    let n = loc.stft().frame_len() / 2 + 1;
    let full = loc.stft().analyze(&audio, 0..n).unwrap();
    let mut data = Vec::new();
    for f in 0..full.num_frames() {
        for ch in 0..full.num_channels() {
            data.extend_from_slice(full.frame(f, ch));
        }
    }
    let given = Spectrogram::from_frames(full.num_frames(), array.len(), 0..n, data).unwrap();
    let (got, spectrum) = loc
        .locate_spectrogram(&given, &mut Scratch::default())
        .unwrap();
    assert_eq!(spectrum, loc.spectrum(&audio).unwrap());
    assert_eq!(got.doas, want.doas);
    assert!(
        (got.doas[0].azimuth_deg - 120.0).abs() < 3.0,
        "{:?}",
        got.doas
    );
    assert!(matches!(
        Spectrogram::from_frames(2, 6, 0..n, vec![Complex32::default(); 5]),
        Err(Error::SpectrogramShape { got: 5, .. })
    ));
    let narrow = Spectrogram::from_frames(1, 6, 0..4, vec![Complex32::default(); 24]).unwrap();
    assert!(matches!(
        loc.locate_spectrogram(&narrow, &mut Scratch::default()),
        Err(Error::BandNotInSpectrogram { .. })
    ));
}
