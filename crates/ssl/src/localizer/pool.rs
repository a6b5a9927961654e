//! Pooling: the blocks of a recording's STFT, which of them are kept (the decay gate),
//! how they are pooled (max, the mean of the top few, or the mean of a steady recording),
//! and the dominance votes cast with them.

use super::*;

impl Localizer {
    /// The pooled spectrum of the STFT in `scratch.spec` ([`Localizer::analyse`]), the
    /// block spectra taken from `blocks`.
    pub(super) fn pooled(&self, scratch: &mut Scratch, blocks: Blocks<'_>) -> AngularSpectrum {
        let spec = std::mem::take(&mut scratch.spec);
        let pooling = self.pooling_of(&spec);
        let pooled = self.pool(&spec, scratch, blocks, pooling);
        scratch.spec = spec;
        pooled
    }

    /// How the blocks of `spec` are pooled: as set, or for [`Pooling::Auto`], the mean
    /// where the recording is steady and noise-like in each octave of the band
    /// ([`crate::steady`]), else max; always the mean for MUSIC.
    ///
    /// Why the mean for MUSIC: its pseudo-spectrum is no power. A block's peak height is
    /// how nearly the noise subspace misses a steering vector, which spans orders of
    /// magnitude from block to block, so the maximum over blocks is the maximum of
    /// outliers; MUSIC as Schmidt defines it uses every snapshot, and the mean of the
    /// blocks' pseudo-spectra uses them all. Measured on arrangement II (first 4 DoAs
    /// within 5 degrees, in the poses' frame): max 0.194, mean 0.381 with the bins grouped
    /// as NormMUSIC groups them, 0.606 with each bin apart
    /// ([`crate::SslConfig::music_freq_smoothing`]), 0.662 with noise-only groups flat
    /// ([`crate::SslConfig::music_sources`]), 0.688 with no block's peak sharper than its
    /// snapshots resolve (`Music::resolution`); pyroomacoustics' MUSIC 0.388.
    pub(super) fn pooling_of(&self, spec: &Spectrogram) -> Pooling {
        if self.config.pooling != Pooling::Auto {
            return self.config.pooling;
        }
        if self.config.method == crate::Method::Music {
            return Pooling::Mean;
        }
        let (n_blocks, frames) = self.blocks(spec.num_frames());
        if crate::steady::Octaves::of(spec, n_blocks, &frames).is_steady() {
            Pooling::Mean
        } else {
            Pooling::Max
        }
    }

    /// The pooled spectrum of the blocks of `spec` (this localizer's band, or a wider one
    /// of the same STFT: see [`Spectrogram::band_into`]), its dominance votes with it;
    /// the block spectra from `source`. Stored spectra pool only the blocks they hold.
    pub(super) fn pool(
        &self,
        spec: &Spectrogram,
        scratch: &mut Scratch,
        source: Blocks<'_>,
        pooling: Pooling,
    ) -> AngularSpectrum {
        let nf = spec.num_frames();
        let (n_blocks, frames) = self.blocks(nf);
        let dominance = self.config.dominance_blocks > 0;
        let energy = if dominance || self.config.decay_gate_db > 0.0 {
            block_energies(spec, n_blocks, &frames)
        } else {
            Vec::new()
        };
        let mut keep = self.gate(&energy, n_blocks, nf);
        if let Blocks::Stored { blocks, .. } = source {
            for (b, k) in keep.iter_mut().enumerate() {
                *k = *k && blocks.binary_search(&b).is_ok();
            }
        }
        let kept_blocks: Vec<usize> = (0..n_blocks).filter(|&b| keep[b]).collect();
        let ranges: Vec<Range<usize>> = kept_blocks.iter().map(|&b| frames(b)).collect();
        // A block holding half the energy of the one before or less is the room's decay,
        // and one more than `VOTE_QUIET_DB` below the recording's loudest is a pause or
        // silence: neither votes (see `SslConfig::dominance_blocks`).
        let loudest = energy.iter().copied().fold(0.0, f64::max);
        let quiet = loudest * 10f64.powf(-VOTE_QUIET_DB / 10.0);
        let votes_in = |b: usize| {
            dominance && energy[b] >= quiet && (b == 0 || energy[b] >= 0.5 * energy[b - 1])
        };
        let mut pooler = Pooler::new(self, kept_blocks.len(), pooling, dominance);
        let mut block = std::mem::take(&mut scratch.block);
        block.resize(self.grid.len(), 0.0);
        let mut sink = |i: usize, block: &[f32]| pooler.take(block, votes_in(kept_blocks[i]));
        match source {
            Blocks::Estimate => self.estimator.estimate_blocks(
                spec,
                &ranges,
                &mut block,
                &mut scratch.method,
                &mut sink,
            ),
            Blocks::EstimateWithOctaves => {
                let mut parts = std::mem::take(&mut scratch.parts);
                let octaves: Vec<Range<usize>> = self
                    .subbands
                    .iter()
                    .map(|s| s.bins.start - self.bins.start..s.bins.end - self.bins.start)
                    .collect();
                parts.valid = self.estimator.estimate_blocks_parts(
                    spec,
                    &ranges,
                    &octaves,
                    &mut block,
                    &mut scratch.method,
                    &mut sink,
                );
                parts.blocks.clone_from(&kept_blocks);
                scratch.parts = parts;
            }
            Blocks::Stored { spectra, blocks } => {
                let nd = self.grid.len();
                for (i, b) in kept_blocks.iter().enumerate() {
                    let at = blocks
                        .binary_search(b)
                        .expect("only stored blocks are kept");
                    sink(i, &spectra[at * nd..(at + 1) * nd]);
                }
            }
        }
        scratch.block = block;
        pooler
            .finish(self.grid.clone())
            .with_mirror_axis(self.mirror_axis_deg)
    }

    /// How `nf` frames split into blocks: their number, and each block's frames. Blocks
    /// split the frames as evenly as possible and cover all of them.
    pub(super) fn blocks(&self, nf: usize) -> (usize, impl Fn(usize) -> Range<usize> + Copy) {
        let n_blocks = if self.estimator.whole_recording() {
            1
        } else {
            (nf / self.config.block_frames).max(1)
        };
        (n_blocks, move |b: usize| {
            b * nf / n_blocks..(b + 1) * nf / n_blocks
        })
    }

    /// The frames of the blocks of `spec` that the pooling keeps ([`Localizer::gate`]).
    pub(super) fn kept_frames(&self, spec: &Spectrogram) -> Vec<Range<usize>> {
        let nf = spec.num_frames();
        let (n_blocks, frames) = self.blocks(nf);
        let energy = if self.config.decay_gate_db > 0.0 {
            block_energies(spec, n_blocks, &frames)
        } else {
            Vec::new()
        };
        let keep = self.gate(&energy, n_blocks, nf);
        (0..n_blocks).filter(|&b| keep[b]).map(frames).collect()
    }

    /// [`Localizer::gate`] on the blocks of `spec` (the tests' entry).
    #[cfg(test)]
    pub(super) fn decay_gate(
        &self,
        spec: &Spectrogram,
        n_blocks: usize,
        frames: &dyn Fn(usize) -> Range<usize>,
    ) -> Vec<bool> {
        let energy = block_energies(spec, n_blocks, frames);
        self.gate(&energy, n_blocks, spec.num_frames())
    }

    /// Which of `n_blocks` blocks (of `nf` frames in all) the pooling keeps, given their
    /// energies ([`block_energies`]): all when the gate is off; else those whose energy is
    /// within `decay_gate_db` of the loudest block of the preceding `decay_window_s` (see
    /// [`SslConfig::decay_gate_db`]). The loudest block of a recording is always kept.
    pub(super) fn gate(&self, energy: &[f64], n_blocks: usize, nf: usize) -> Vec<bool> {
        let gate = self.config.decay_gate_db;
        if gate <= 0.0 || n_blocks < 2 {
            return vec![true; n_blocks];
        }
        // Blocks per window: the window's length over one block's hop in time.
        let frames_per_block = nf as f64 / n_blocks as f64;
        let block_s = self.stft.hop() as f64 * frames_per_block / f64::from(self.sample_rate);
        let window = ((self.config.decay_window_s / block_s).round() as usize).max(1);
        let floor = 10f64.powf(-gate / 10.0);
        (0..n_blocks)
            .map(|b| {
                let recent = energy[b.saturating_sub(window)..b]
                    .iter()
                    .copied()
                    .fold(0.0, f64::max);
                energy[b] >= floor * recent
            })
            .collect()
    }
}

/// Each block's energy: all channels, the band's bins.
pub(super) fn block_energies(
    spec: &Spectrogram,
    n_blocks: usize,
    frames: &dyn Fn(usize) -> Range<usize>,
) -> Vec<f64> {
    // Less the robot's own noise ([`crate::noise`]), kept at least a share of what was
    // heard: the gates compare the sources' levels.
    let noise = spec.noise().map_or(0.0, |n| n.frame_energy(spec.bins()));
    (0..n_blocks)
        .map(|b| {
            let heard: f64 = frames(b)
                .flat_map(|f| (0..spec.num_channels()).map(move |c| (f, c)))
                .map(|(f, c)| {
                    spec.frame(f, c)
                        .iter()
                        .map(|x| f64::from(x.norm_sqr()))
                        .sum::<f64>()
                })
                .sum();
            let floor = f64::from(crate::noise::RESIDUAL_FLOOR) * heard;
            (heard - noise * frames(b).len() as f64).max(floor)
        })
        .collect()
}

/// The blocks' spectra pooled as they come ([`Localizer::pool`]): the maximum, the mean of
/// the top few or the mean, per direction; with the dominance votes and each block's
/// azimuth profile.
struct Pooler {
    /// Azimuth cells of the grid (a block's row of directions at one elevation).
    n_az: usize,
    /// Per azimuth cell, the blocks whose strongest direction lies there (empty when the
    /// votes are off; `SslConfig::dominance_blocks`).
    votes: Vec<u32>,
    /// Whether each block's azimuth profile is kept, for placing the DoAs
    /// (`SslConfig::placement_share`; the octaves' localizers have it off: their DoAs are
    /// block maxima), and the profiles, block after block.
    place: bool,
    profiles: Vec<f32>,
    /// Max pooling (else the mean), and each direction's `k` largest block values,
    /// largest first (k = 1: the plain maximum), whose mean it pools.
    max: bool,
    k: usize,
    top: Vec<f32>,
    /// The mean so far (mean pooling), or the pooled spectrum once finished.
    pooled: Vec<f32>,
    /// How many blocks are pooled.
    kept: usize,
}

impl Pooler {
    fn new(l: &Localizer, kept: usize, pooling: Pooling, dominance: bool) -> Self {
        let (n_az, len) = (l.grid.num_azimuths(), l.grid.len());
        let k = l.config.pool_top.min(kept).max(1);
        let max = pooling != Pooling::Mean;
        let place = max && l.config.placement_share > 0.0;
        Pooler {
            n_az,
            votes: vec![0u32; if dominance { n_az } else { 0 }],
            place,
            profiles: Vec::with_capacity(if place { kept * n_az } else { 0 }),
            max,
            k,
            top: if max {
                vec![f32::NEG_INFINITY; len * k]
            } else {
                Vec::new()
            },
            pooled: vec![0.0f32; len],
            kept,
        }
    }

    /// One block's spectrum, and whether it votes.
    fn take(&mut self, block: &[f32], votes: bool) {
        if votes {
            let (mut best, mut at) = (f32::NEG_INFINITY, 0);
            for (d, &v) in block.iter().enumerate() {
                if v > best {
                    (best, at) = (v, d);
                }
            }
            self.votes[at % self.n_az] += 1;
        }
        if self.place {
            let n_az = self.n_az;
            let at = self.profiles.len();
            self.profiles.extend_from_slice(&block[..n_az]);
            for row in block.chunks_exact(n_az).skip(1) {
                self.profiles[at..]
                    .iter_mut()
                    .zip(row)
                    .for_each(|(p, &v)| *p = p.max(v));
            }
        }
        let k = self.k;
        match (self.max, k) {
            // The plain maximum as one vectorisable pass.
            (true, 1) => (self.top.iter_mut())
                .zip(block)
                .for_each(|(t, &v)| *t = t.max(v)),
            (true, _) => {
                for (t, &v) in self.top.chunks_exact_mut(k).zip(block) {
                    if v > t[k - 1] {
                        let mut i = k - 1;
                        while i > 0 && t[i - 1] < v {
                            t[i] = t[i - 1];
                            i -= 1;
                        }
                        t[i] = v;
                    }
                }
            }
            (false, _) => {
                let kept = self.kept as f32;
                (self.pooled.iter_mut())
                    .zip(block)
                    .for_each(|(p, &v)| *p += v / kept)
            }
        }
    }

    /// The pooled spectrum on `grid`, with its votes and profiles.
    fn finish(mut self, grid: DirectionGrid) -> AngularSpectrum {
        if self.max {
            for (p, t) in self.pooled.iter_mut().zip(self.top.chunks_exact(self.k)) {
                *p = t.iter().sum::<f32>() / self.k as f32;
            }
        }
        AngularSpectrum::new(grid, self.pooled)
            .with_pooling(if self.max {
                Pooling::Max
            } else {
                Pooling::Mean
            })
            .with_votes(self.votes)
            .with_block_profiles(self.profiles)
    }
}
