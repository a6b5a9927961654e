//! The audio on the run's clock (the module's **Time**): stamps that lie set right by
//! when their messages were recorded, and messages cut into continuous segments where the
//! stream's start jumps.

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

/// The median of the lags `t - stamp` (ns) of messages, `None` with fewer than three:
/// two messages cannot say which of them lies.
pub(crate) fn median_lag<'a, T: 'a>(
    msgs: impl IntoIterator<Item = &'a (i64, Option<i64>, T)>,
) -> Option<i64> {
    let mut lags: Vec<i64> = msgs
        .into_iter()
        .filter_map(|m| m.1.map(|s| m.0 - s))
        .collect();
    if lags.len() < 3 {
        return None;
    }
    lags.sort_unstable();
    Some(lags[lags.len() / 2])
}

/// A run of messages of one topic whose stamps strayed from the clock the run began on
/// ([`STAMP_JUMP_S`]) and were set right by when they were recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct StampJump {
    /// The topic.
    pub topic: String,
    /// When the first and the last of them were recorded (ns since the epoch).
    pub recorded_ns: (i64, i64),
    /// How far their stamps lay from the clock (s): positive when they lay early.
    pub jump_s: f64,
    /// How many.
    pub messages: usize,
}

impl StampJump {
    /// The jump in words, times in seconds from `start_ns`.
    pub fn describe(&self, start_ns: i64) -> String {
        let n = self.messages;
        let rel = |ns: i64| (ns - start_ns) as f64 * 1e-9;
        format!(
            "{}: {n} message{} recorded from {:.1} to {:.1} s {} stamped {:.1} s {} than {} \
             recorded (a clock step or a wrong stamp): timed by when {} recorded",
            self.topic,
            if n == 1 { "" } else { "s" },
            rel(self.recorded_ns.0),
            rel(self.recorded_ns.1),
            if n == 1 { "was" } else { "were" },
            self.jump_s.abs(),
            if self.jump_s > 0.0 {
                "earlier"
            } else {
                "later"
            },
            if n == 1 { "it was" } else { "they were" },
            if n == 1 { "it was" } else { "they were" },
        )
    }
}

/// Sets right the stamps of one topic that lie: where a message's stamp differs from the
/// time it was recorded (`t - stamp`) by more than [`STAMP_JUMP_S`] beyond the usual lag
/// `lag` (ns: that of the clock the run began on, over its topics' first messages), the
/// stamp stepped (an NTP correction, a clock set by hand) or is wrong (a driver's bug), and
/// the message is timed by when it was recorded, less the usual lag. Returns each run of
/// such messages (the topic, when, how far and which way the stamps jumped), so that no
/// stop is built from audio and poses on two clocks and no stop is lost without a word.
///
/// The time a message was recorded (a bag's log time, a live node's arrival time) is
/// taken on one machine's steady clock: it does not step, and it lags the stamp by what
/// the transport takes, which varies by far less than a second.
pub(crate) fn rectify_stamps<T>(
    topic: &str,
    msgs: &mut [(i64, Option<i64>, T)],
    lag: i64,
) -> Vec<StampJump> {
    let tolerance = (STAMP_JUMP_S * 1e9) as i64;
    let mut out: Vec<StampJump> = Vec::new();
    // Whether the last message lied too: a run goes on while they do, at the same jump.
    let mut open = false;
    for m in msgs.iter_mut() {
        match m.1 {
            Some(s) if (m.0 - s - lag).abs() > tolerance => {
                let jump_s = (m.0 - s - lag) as f64 * 1e-9;
                match out.last_mut() {
                    Some(j) if open && (j.jump_s - jump_s).abs() * 1e9 <= tolerance as f64 => {
                        j.recorded_ns.1 = m.0;
                        j.messages += 1;
                    }
                    _ => out.push(StampJump {
                        topic: topic.to_owned(),
                        recorded_ns: (m.0, m.0),
                        jump_s,
                        messages: 1,
                    }),
                }
                m.1 = Some(m.0 - lag);
                open = true;
            }
            _ => open = false,
        }
    }
    out
}

/// How many of a run's first stamped messages (all topics, in receipt order) give the lag
/// of the clock it began on: a second or two of a robot's topics, enough that one wrong
/// stamp among them does not move the median.
pub(crate) const FIRST_MESSAGES: usize = 25;

/// How far a stamp may stray from its topic's usual lag behind the time its message was
/// recorded (s) before it is taken for a lie: a second, above a loaded recorder's jitter
/// (tens of milliseconds) and an audio driver's buffering, and below the shortest stop
/// that a stamp wrong by as much would pair with the wrong audio.
pub const STAMP_JUMP_S: f64 = 1.0;
