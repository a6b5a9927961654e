//! The audio on the run's clock (the module's **Time**): messages cut into continuous
//! segments where the stream's start jumps.

use super::*;

/// Cuts the audio messages (receipt time, stamp, length in bytes), whose samples lie end
/// to end, into continuous segments (module docs); a frame split across two messages is
/// joined.
pub(super) fn segments(
    msgs: &[(i64, Option<i64>, usize)],
    format: AudioFormat,
    time: &impl Fn(i64, Option<i64>) -> f64,
) -> std::result::Result<Vec<AudioSegment>, String> {
    let frame_bytes = usize::from(format.channels) * format.sample.bytes();
    let fs = f64::from(format.sample_rate);
    let not_whole = |bytes: usize| {
        format!(
            "{bytes} bytes of audio are not whole frames of {frame_bytes} bytes ({} channels of \
             {:?}): the format is not the one given",
            format.channels, format.sample
        )
    };
    let mut out: Vec<AudioSegment> = Vec::new();
    // The current segment: its first byte, its bytes so far, its start (s).
    let (mut offset, mut len, mut start) = (0usize, 0usize, f64::INFINITY);
    for &(t, stamp, n) in msgs {
        let implied = time(t, stamp) - (len + n) as f64 / frame_bytes as f64 / fs;
        if start.is_finite() && implied > start + GAP_S {
            if !len.is_multiple_of(frame_bytes) {
                return Err(not_whole(len));
            }
            out.push(AudioSegment {
                start_s: start,
                offset,
                frames: len / frame_bytes,
            });
            offset += len;
            len = 0;
            start = time(t, stamp) - n as f64 / frame_bytes as f64 / fs;
        } else {
            start = start.min(implied);
        }
        len += n;
    }
    if !len.is_multiple_of(frame_bytes) {
        return Err(not_whole(len));
    }
    if len > 0 {
        out.push(AudioSegment {
            start_s: start,
            offset,
            frames: len / frame_bytes,
        });
    }
    // The samples must last as long as the messages span: a wrong channel count, sample
    // format or rate whose frames still divide the bytes shows here.
    if let (Some(first), Some(last)) = (msgs.first(), msgs.last()) {
        let total: usize = out.iter().map(|s| s.frames).sum();
        let heard = total as f64 / fs;
        let first_len = first.2 as f64 / frame_bytes as f64 / fs;
        let span = time(last.0, last.1) - time(first.0, first.1) + first_len;
        if span > 1.0 && !(MIN_AUDIO_SHARE..=MAX_AUDIO_SHARE).contains(&(heard / span)) {
            return Err(format!(
                "its samples would last {heard:.2} s ({} channels of {:?} at {} Hz) but its \
                 messages span {span:.2} s: the format is not the one given{}",
                format.channels,
                format.sample,
                format.sample_rate,
                if heard < span {
                    ", or much of the audio was lost"
                } else {
                    ""
                }
            ));
        }
    }
    Ok(out)
}

/// The least share of the audio topic's time span its samples may fill: below, too much
/// was lost (or the format is wrong) to trust where the rest lies in time.
pub(super) const MIN_AUDIO_SHARE: f64 = 0.75;

/// The most: more samples than time (beyond a capture clock's drift and the receipt
/// times' jitter) is a wrong format.
pub(super) const MAX_AUDIO_SHARE: f64 = 1.05;
