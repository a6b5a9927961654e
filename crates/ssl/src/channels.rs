//! Microphones that do not hear the room: found in each recording and left out of it
//! ([`crate::SslConfig::screen_channels`]).
//!
//! A microphone fails in two ways that a robot's recordings show. It goes **silent**: a
//! connector works loose, a channel is muted, a driver writes zeros. Or it is
//! **disconnected** but its preamplifier is not: the channel then holds its own
//! electronic hiss, at a level like the others', and nothing of the room. Either way the
//! file still has the array's channel count, so nothing refuses it, and the localizer's
//! every statistic assumes that each channel holds the room's sound plus a little noise of
//! its own. The pairs with the failed channel add nothing to an angular spectrum's peaks,
//! but they lower its background and its every peak's relative height alike, and the
//! rules that tell a quiet source from a reflection (the source coherence's noise term,
//! the significance) read the failed channel as a source of independent signal. Measured
//! (`two_talkers`, first rendering, N = 3, the paper's
//! 6-microphone array): with one channel zeroed, or replaced by white noise at its level,
//! low peaks of nothing pass the thresholds at a third of the stops and the map's OSPA goes
//! from 0.017 / 0.015 m (GCC-PHAT / MVDR) to 0.066-0.070; localised without that channel
//! (the array of the other five), 0.024 / 0.025 m, what an array of five gives. Over seven
//! data sets (our simulator's, pyroomacoustics', the authors' recordings; a dead and a
//! hissing channel, both methods) the mean goes from 0.139 to 0.126 m, 13 of 28 cases
//! better and 9 worse: kept, a faulty channel's pairs add a near-constant or random term to
//! every direction, which moves which low peaks pass the thresholds, by chance either way
//! (`reverberant_low_snr` MVDR 0.066 -> 0.307 m with a hissing channel, arrangement II
//! MVDR 0.205 -> 0.154); left out, the recording is localised exactly as the array without
//! that microphone localises it, which a user can reproduce and reason about. And the run
//! says which microphone failed, which it did not before.
//!
//! **Silent.** A channel's power in the band (summed over the frames) is zero, or lies
//! more than [`SILENT_DB`] below the reference channel's, the upper median of the
//! channels' powers (so that up to half of them may have failed without moving it). The microphones of an array lie within
//! a few tens of centimetres of each other: a source 0.5 m from the paper's 0.24-m array
//! is 4 dB louder at the nearest microphone than at the furthest, and microphone
//! capsules' sensitivities differ by a few dB; 30 dB is no working channel's.
//!
//! **Incoherent.** A channel's best magnitude-squared coherence with any other channel
//! (per bin, over the recording's frames, averaged over the band's bins) stands no higher
//! than independent noise puts it, while the others' stand well above. Two independent
//! signals averaged over `K` frames have a coherence of about `1 / K` per bin
//! (the estimator's bias: measured, 0.029-0.031 at `K = 36`), so a channel is incoherent
//! when its best lies below `1/K + INCOHERENT_SHARE (r - 1/K)`, where `r` is the upper
//! median of the channels' best values, and the test is made only when `r` is at least
//! [`COHERENT_BIAS_MULTIPLE`] times the bias (in silence, or with sensor noise only, no
//! channel is coherent with any other, and none is singled out). Measured on every
//! recording we have (the 78 renderings of the suite's and
//! held-out scenes, five arrays among them; the pyroomacoustics surveys, speech and steady
//! noise, RT60 0.3-0.8 s; the authors' 40 recordings at 48 kHz): a working channel's best
//! lies at 0.73-1.0 of `r` (0.57 on a Kinect's line, whose end microphone is 0.15 m
//! from the nearest), `r` 4.7-46 times the bias wherever a source sounds, and the channels'
//! levels within 2.4 dB of the reference; no channel of any of them is faulty. Why the
//! coherence and not a level: a disconnected channel's hiss can be as loud as the room.
//!
//! Each is judged per recording (a connector can work loose mid-survey), on the STFT the
//! localizer computes anyway: every fourth bin of the band ([`BIN_STRIDE`]), all channel
//! pairs, about 0.2 ms for the paper's 3-s recordings at 48 kHz. A recording with fewer
//! than [`MIN_FRAMES`] frames is judged only by level.

use crate::stft::Spectrogram;

/// A channel whose power in the band lies this many dB or more below the reference
/// channel's (the upper median of the channels') is silent.
pub const SILENT_DB: f64 = 30.0;

/// Where between independent noise's coherence (0) and the channels' typical best (1) a
/// channel's best coherence must reach not to be incoherent.
pub const INCOHERENT_SHARE: f64 = 0.25;

/// The coherence test is made only when the channels' typical best coherence stands at
/// least this many times above independent noise's.
pub const COHERENT_BIAS_MULTIPLE: f64 = 3.0;

/// Recordings of fewer frames are judged by level only: a coherence over so few frames
/// is near 1 for anything.
pub const MIN_FRAMES: usize = 8;

/// The coherence and the levels are computed on every this-many-th bin of the band.
pub const BIN_STRIDE: usize = 4;

/// Why a channel was found not to hear the room.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case", tag = "fault")]
pub enum Fault {
    /// Its power in the band lies `below_db` dB under the reference channel's (at most
    /// 300: a channel of zeros).
    Silent {
        /// dB under the reference channel's power.
        below_db: f64,
    },
    /// Its best coherence with any other channel is `coherence`, where the channels'
    /// typical best is `typical` and independent noise gives `noise`.
    Incoherent {
        /// Its best magnitude-squared coherence with another channel, band average.
        coherence: f64,
        /// The upper median of the channels' best coherences.
        typical: f64,
        /// What independent signals give over this many frames: `1 / K`.
        noise: f64,
    },
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Fault::Silent { below_db } if below_db >= MAX_BELOW_DB => {
                write!(f, "silent (no signal at all)")
            }
            Fault::Silent { below_db } => {
                write!(f, "silent ({below_db:.0} dB below the other microphones)")
            }
            Fault::Incoherent {
                coherence,
                typical,
                noise,
            } => write!(
                f,
                "incoherent with every other microphone, as a channel of its own noise is \
                 (coherence {coherence:.3}; independent noise gives {noise:.3}, the others \
                 {typical:.3})"
            ),
        }
    }
}

/// The largest [`Fault::Silent::below_db`] reported.
const MAX_BELOW_DB: f64 = 300.0;

/// The per-channel statistics of one recording's STFT that [`faults`] judges.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelStats {
    /// Each channel's power in the band's sampled bins, summed over the frames.
    pub power: Vec<f64>,
    /// Magnitude-squared coherence of each pair of channels, averaged over the sampled
    /// bins where both hold power (row-major, `M x M`, 1 on the diagonal).
    pub coherence: Vec<f64>,
    /// The frames they were summed over.
    pub frames: usize,
}

impl ChannelStats {
    /// The statistics of `spec` (every channel, every frame, every [`BIN_STRIDE`]-th bin).
    pub fn of(spec: &Spectrogram) -> Self {
        let (m, nf) = (spec.num_channels(), spec.num_frames());
        let bins: Vec<usize> = (0..spec.bins().len()).step_by(BIN_STRIDE).collect();
        let nb = bins.len();
        // Per bin: each channel's power and each pair's cross-spectrum, summed over frames.
        let mut power = vec![0.0f64; m * nb];
        let mut cross = vec![(0.0f64, 0.0f64); m * m * nb];
        for f in 0..nf {
            for i in 0..m {
                let xi = spec.frame(f, i);
                for (k, &b) in bins.iter().enumerate() {
                    power[i * nb + k] += f64::from(xi[b].norm_sqr());
                }
                for j in i + 1..m {
                    let xj = spec.frame(f, j);
                    let row = &mut cross[(i * m + j) * nb..][..nb];
                    for (c, &b) in row.iter_mut().zip(&bins) {
                        // x_i x_j^*
                        let (a, z) = (xi[b], xj[b]);
                        c.0 += f64::from(a.re * z.re + a.im * z.im);
                        c.1 += f64::from(a.im * z.re - a.re * z.im);
                    }
                }
            }
        }
        let mut coherence = vec![1.0f64; m * m];
        for i in 0..m {
            for j in i + 1..m {
                let (mut sum, mut n) = (0.0, 0usize);
                for k in 0..nb {
                    let (pi, pj) = (power[i * nb + k], power[j * nb + k]);
                    if pi > 0.0 && pj > 0.0 {
                        let c = cross[(i * m + j) * nb + k];
                        sum += (c.0 * c.0 + c.1 * c.1) / (pi * pj);
                        n += 1;
                    }
                }
                let c = if n > 0 {
                    (sum / n as f64).min(1.0)
                } else {
                    0.0
                };
                coherence[i * m + j] = c;
                coherence[j * m + i] = c;
            }
        }
        let power = (0..m)
            .map(|i| power[i * nb..(i + 1) * nb].iter().sum())
            .collect();
        Self {
            power,
            coherence,
            frames: nf,
        }
    }

    /// Number of channels.
    pub fn num_channels(&self) -> usize {
        self.power.len()
    }

    /// The coherence of channels `i` and `j`.
    pub fn coherence(&self, i: usize, j: usize) -> f64 {
        self.coherence[i * self.num_channels() + j]
    }
}

/// The upper median of `v` (not empty): the `ceil(n / 2)`-th largest.
fn upper_median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| b.total_cmp(a));
    v[(v.len() - 1) / 2]
}

/// The channels of `stats` that do not hear the room, ascending, each with its
/// [`Fault`]: the silent ones, then among the rest the incoherent ones (see the module
/// docs). None when no channel holds any power (silence says nothing of the microphones).
pub fn faults(stats: &ChannelStats) -> Vec<(usize, Fault)> {
    let m = stats.num_channels();
    if m < 2 || stats.power.iter().all(|&p| p <= 0.0) {
        return Vec::new();
    }
    let reference = upper_median(stats.power.clone());
    let floor = reference * 10f64.powf(-SILENT_DB / 10.0);
    let mut out: Vec<(usize, Fault)> = (0..m)
        .filter(|&i| stats.power[i] < floor || stats.power[i] == 0.0)
        .map(|i| {
            let below_db = if stats.power[i] > 0.0 {
                (10.0 * (reference / stats.power[i]).log10()).min(MAX_BELOW_DB)
            } else {
                MAX_BELOW_DB
            };
            (i, Fault::Silent { below_db })
        })
        .collect();
    let live: Vec<usize> = (0..m)
        .filter(|&i| out.iter().all(|&(j, _)| j != i))
        .collect();
    if live.len() >= 3 && stats.frames >= MIN_FRAMES {
        let best: Vec<f64> = live
            .iter()
            .map(|&i| {
                live.iter()
                    .filter(|&&j| j != i)
                    .map(|&j| stats.coherence(i, j))
                    .fold(0.0, f64::max)
            })
            .collect();
        let noise = 1.0 / stats.frames as f64;
        let typical = upper_median(best.clone());
        if typical >= COHERENT_BIAS_MULTIPLE * noise {
            let bar = noise + INCOHERENT_SHARE * (typical - noise);
            out.extend(
                live.iter()
                    .zip(&best)
                    .filter(|&(_, &b)| b < bar)
                    .map(|(&i, &b)| {
                        (
                            i,
                            Fault::Incoherent {
                                coherence: b,
                                typical,
                                noise,
                            },
                        )
                    }),
            );
        }
    }
    out.sort_by_key(|&(i, _)| i);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Audio, Stft};

    /// `m` channels of one white noise delayed by `k` samples on channel `k` (a wave
    /// crossing a line of microphones), 1 s at 16 kHz, with a little independent noise each.
    fn wave(m: usize, seed: u64) -> Vec<Vec<f32>> {
        let mut s = seed;
        let mut next = move || {
            // xorshift64*, uniform in [-1, 1)
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f32 / (1u64 << 52) as f32 - 1.0
        };
        let n = 16_000;
        let src: Vec<f32> = (0..n + m).map(|_| next()).collect();
        (0..m)
            .map(|k| (0..n).map(|t| src[t + m - k] + 0.05 * next()).collect())
            .collect()
    }

    fn stats(channels: Vec<Vec<f32>>) -> ChannelStats {
        let audio = Audio::new(16_000, channels).unwrap();
        let spec = Stft::new(512, 256)
            .unwrap()
            .analyze(&audio, 7..257)
            .unwrap();
        ChannelStats::of(&spec)
    }

    #[test]
    fn working_channels_have_no_fault() {
        for m in [2, 4, 6] {
            assert_eq!(faults(&stats(wave(m, 7))), vec![], "{m} channels");
        }
    }

    #[test]
    fn a_channel_of_zeros_or_40_db_down_is_silent_and_10_db_down_is_not() {
        let mut ch = wave(6, 3);
        ch[2].iter_mut().for_each(|v| *v = 0.0);
        ch[4].iter_mut().for_each(|v| *v *= 0.01); // -40 dB
        ch[5].iter_mut().for_each(|v| *v *= 0.316); // -10 dB
        let f = faults(&stats(ch));
        assert_eq!(f.len(), 2, "{f:?}");
        assert_eq!(
            f[0],
            (
                2,
                Fault::Silent {
                    below_db: MAX_BELOW_DB
                }
            )
        );
        let (i, Fault::Silent { below_db }) = f[1] else {
            panic!("{f:?}")
        };
        assert_eq!(i, 4);
        // The reference is the upper median, a channel at full level.
        assert!((below_db - 40.0).abs() < 0.5, "{below_db}");
    }

    #[test]
    fn a_channel_of_its_own_noise_at_the_rooms_level_is_incoherent() {
        let mut ch = wave(6, 11);
        let own = wave(1, 99).remove(0);
        ch[1] = own;
        let s = stats(ch);
        let f = faults(&s);
        assert_eq!(f.len(), 1, "{f:?}");
        let (
            1,
            Fault::Incoherent {
                coherence,
                noise,
                typical,
            },
        ) = f[0]
        else {
            panic!("{f:?}")
        };
        // 1 s at hop 256: 61 frames; independent noise's coherence is about 1 / 61.
        assert_eq!(s.frames, 61);
        assert!((noise - 1.0 / 61.0).abs() < 1e-12);
        assert!(coherence < 2.0 * noise, "{coherence} {noise}");
        assert!(typical > 0.9, "{typical}");
    }

    #[test]
    fn silence_and_sensor_noise_single_out_no_channel() {
        let silence = vec![vec![0.0f32; 16_000]; 4];
        assert_eq!(faults(&stats(silence)), vec![]);
        // Every channel its own noise: none is coherent with any other, so none is odd.
        let noise: Vec<Vec<f32>> = (0..4).map(|k| wave(1, 100 + k).remove(0)).collect();
        assert_eq!(faults(&stats(noise)), vec![]);
    }

    #[test]
    fn a_pair_cannot_say_which_of_its_two_is_incoherent_but_can_which_is_silent() {
        let ch = vec![wave(1, 5).remove(0), wave(1, 6).remove(0)];
        assert_eq!(faults(&stats(ch)), vec![]);
        let mut ch = wave(2, 5);
        ch[0].iter_mut().for_each(|v| *v = 0.0);
        assert_eq!(
            faults(&stats(ch)),
            vec![(
                0,
                Fault::Silent {
                    below_db: MAX_BELOW_DB
                }
            )]
        );
    }
}
