//! A run's topics, clock and segments from messages made here.

use super::*;

fn topic(name: &str, ty: &str, n: usize) -> TopicInfo {
    TopicInfo {
        topic: name.into(),
        msg_type: ty.into(),
        messages: n,
        span_s: (0.0, 1.0),
    }
}

#[test]
fn a_stream_published_stamped_and_unstamped_is_taken_stamped() {
    let both = [
        topic("/audio/audio", "audio_common_msgs/AudioData", 300),
        topic(
            "/audio/audio_stamped",
            "audio_common_msgs/AudioDataStamped",
            300,
        ),
        topic("/odom", "nav_msgs/Odometry", 900),
    ];
    assert_eq!(
        same_stream_twice(&both).unwrap().topic,
        "/audio/audio_stamped"
    );
    // Two microphones' streams, or counts that differ, are two streams: the user names one.
    let other_ns = [
        both[0].clone(),
        topic(
            "/mic2/audio_stamped",
            "audio_common_msgs/AudioDataStamped",
            300,
        ),
    ];
    assert!(same_stream_twice(&other_ns).is_none());
    let other_count = [
        both[0].clone(),
        topic(
            "/audio/audio_stamped",
            "audio_common_msgs/AudioDataStamped",
            299,
        ),
    ];
    assert!(same_stream_twice(&other_count).is_none());
    let e = choose(&other_ns, None, "audio", "--audio-topic", Kind::is_audio)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("2 audio topics") && e.contains("--audio-topic"),
        "{e}"
    );
}
