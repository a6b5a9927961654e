//! Faulty microphones: a dead or disconnected channel is left out, but only where the
//! others can localise by themselves.

use crate::common::*;
use iasm_ssl::{Audio, Localizer, Method, MicArray, Scratch, SslConfig, wrap_deg};

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
