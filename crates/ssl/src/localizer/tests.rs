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
