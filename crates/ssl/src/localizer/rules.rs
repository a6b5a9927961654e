//! The SSL's rules: which peaks of the pooled spectrum are DoAs (deflation, the octaves'
//! votes, sidelobes, coherence and significance).

use super::*;

impl Localizer {
    /// The row of the recording whose STFT is in `scratch.spec` ([`Localizer::analyse`]),
    /// localised with every channel.
    pub(super) fn located(&self, scratch: &mut Scratch) -> Result<Located> {
        Ok(self.located_with_spectrum(scratch)?.0)
    }

    /// [`Localizer::located`], and the pooled spectrum whose peaks the row's DoAs are.
    pub(super) fn located_with_spectrum(
        &self,
        scratch: &mut Scratch,
    ) -> Result<(Located, AngularSpectrum)> {
        let n = self.config.num_peaks;
        // The N strongest resolved peaks, and the next one: the row is cut when that one
        // passes the thresholds too (the peaks are taken strongest first, so the first N
        // are those of a search for N).
        let source = if self.shared_octaves() {
            Blocks::EstimateWithOctaves
        } else {
            Blocks::Estimate
        };
        let spectrum = self.pooled(scratch, source);
        let mut peaks =
            spectrum.resolved_peaks(n + 1, self.config.min_sep_deg, self.config.min_prominence);
        let next = (peaks.len() > n).then(|| peaks.remove(n));
        let stands_out = |d: &Doa| {
            let dominant = self.config.dominance_blocks;
            d.relative >= self.config.min_relative
                || (dominant > 0 && d.dominant_blocks as usize >= dominant)
        };
        let (mut doas, mut next) = if self.config.incoherent_relative > 0.0 {
            self.by_coherence(peaks, next, &scratch.spec, stands_out)
        } else {
            (
                peaks.into_iter().filter(stands_out).collect(),
                next.filter(stands_out),
            )
        };
        if self.config.sidelobe_ratio > 0.0 && doas.len() + usize::from(next.is_some()) > 1 {
            (doas, next) = self.drop_sidelobes(doas, next.take())?;
        }
        let checked = doas.len();
        doas.extend(next);
        // Every DoA's significance (cheap beside the spectrum: one pass over the frames,
        // then a few thousand terms per DoA); those below the floor are noise. The pass
        // over the frames is made once, for the row and its extra DoAs alike.
        let mut coherence = None;
        let mut significant = |doas: Vec<Doa>, spec: &Spectrogram| {
            let z = if doas.is_empty() {
                Vec::new()
            } else {
                let g = coherence.get_or_insert_with(|| self.coherence(spec));
                self.significance(g, &doas)
            };
            let floor = self.config.min_significance;
            doas.into_iter()
                .zip(z)
                .map(|(d, significance)| Doa { significance, ..d })
                .map(move |d| (floor <= 0.0 || d.significance >= floor).then_some(d))
                .collect::<Vec<_>>()
        };
        let mut row = significant(doas, &scratch.spec).into_iter();
        let doas: Vec<Doa> = row.by_ref().take(checked).flatten().collect();
        let cut = row.next().flatten().is_some();
        let extra = if cut && !self.subbands.is_empty() {
            let extra = self.octave_doas(&spectrum, &doas, scratch);
            significant(extra, &scratch.spec)
                .into_iter()
                .flatten()
                .collect()
        } else {
            Vec::new()
        };
        // Where each DoA lies: from its own best blocks (`SslConfig::placement_share`).
        let sep = self.config.min_sep_deg;
        let doas = spectrum.placed(doas, self.config.placement_share, 0.5 * sep, sep);
        let pooling = spectrum.pooling();
        let doas = if self.deflate && !cut && doas.len() >= 2 {
            self.deflated(doas, &scratch.spec, pooling)
        } else {
            doas
        };
        Ok((
            Located {
                doas,
                cut,
                extra,
                pooling,
                faulty_channels: Vec::new(),
                microphones: self.array.len(),
            },
            spectrum,
        ))
    }

    /// `doas` (a row, strongest first) with each DoA but the first refined with the
    /// stronger ones projected out ([`SslConfig::deflate`], [`crate::deflate`]), on the
    /// blocks of `spec` that the pooling keeps.
    pub(super) fn deflated(
        &self,
        doas: Vec<Doa>,
        spec: &Spectrogram,
        pooling: Pooling,
    ) -> Vec<Doa> {
        if spec.num_channels() < 3 {
            // One stronger DoA projected out leaves too few dimensions to search in.
            return doas;
        }
        let gate = self.config.deflate_max_residual;
        if gate > 0.0 && !crate::deflate::testable(doas.len(), spec.num_channels()) {
            // The gate cannot test the row: leave it before computing its covariances.
            return doas;
        }
        let blocks = self.kept_frames(spec);
        let cov = crate::deflate::BlockCovariances::of(spec, &blocks);
        let setup = crate::deflate::Setup {
            positions: self.array.positions(),
            fs: f64::from(self.sample_rate),
            frame_len: self.stft.frame_len(),
            c: self.config.speed_of_sound,
            pooling,
            pool_top: self.config.pool_top,
        };
        let at = |d: &Doa| (d.azimuth_deg, d.elevation_deg);
        let strong: Vec<(f64, f64)> = doas.iter().map(at).collect();
        if gate > 0.0
            && !crate::deflate::residual_share(&setup, spec, &cov, &strong)
                .is_some_and(|r| r < gate)
        {
            return doas;
        }
        doas.iter()
            .enumerate()
            .map(|(k, d)| Doa {
                azimuth_deg: crate::deflate::deflated_azimuth(
                    &setup,
                    spec,
                    &cov,
                    &strong[..k],
                    at(d),
                ),
                ..*d
            })
            .collect()
    }

    /// The extra DoAs of a cut row ([`Located::extra`]) before the significance floor:
    /// each octave of the band pooled on its own (the STFT in `scratch`), its resolved
    /// peaks with their block votes, merged across octaves within
    /// [`SUBBAND_MERGE_DEG`]; those with [`SslConfig::subband_votes`] votes or more and no
    /// DoA of `row` within [`SslConfig::min_sep_deg`], at most `N` of them, most votes
    /// first, read off the full band's pooled `spectrum`.
    pub(super) fn octave_doas(
        &self,
        spectrum: &AngularSpectrum,
        row: &[Doa],
        scratch: &mut Scratch,
    ) -> Vec<Doa> {
        let c = &self.config;
        let spec = std::mem::take(&mut scratch.spec);
        let mut octave = std::mem::take(&mut scratch.octave);
        let parts = std::mem::take(&mut scratch.parts);
        let mut spectra = std::mem::take(&mut scratch.part_spectra);
        // (azimuth, votes) of every octave's peaks that dominated a block.
        let mut peaks: Vec<(f64, u32)> = Vec::new();
        for (o, sub) in self.subbands.iter().enumerate() {
            spec.band_into(sub.bins.clone(), &mut octave);
            let source = if self.shared_octaves() && parts.valid {
                self.estimator.part_spectra(
                    o,
                    &self.octave_dirs,
                    &mut scratch.method,
                    &mut spectra,
                );
                Blocks::Stored {
                    spectra: &spectra,
                    blocks: &parts.blocks,
                }
            } else {
                Blocks::Estimate
            };
            let pooled = sub.pool(&octave, scratch, source, spectrum.pooling());
            peaks.extend(
                pooled
                    .resolved_peaks(2 * c.num_peaks, c.min_sep_deg, c.min_prominence)
                    .into_iter()
                    .filter(|p| p.dominant_blocks > 0)
                    .map(|p| (p.azimuth_deg, p.dominant_blocks)),
            );
        }
        scratch.spec = spec;
        scratch.octave = octave;
        scratch.parts = parts;
        scratch.part_spectra = spectra;
        // Greedily, the peak with the most votes takes every peak within the merge
        // distance: their votes summed, their azimuths averaged by votes.
        peaks.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.total_cmp(&b.0)));
        let mut merged: Vec<(f64, u32)> = Vec::new();
        while let Some(&(at, _)) = peaks.first() {
            let (near, rest): (Vec<_>, Vec<_>) = peaks
                .into_iter()
                .partition(|p| wrap_deg(p.0 - at).abs() <= SUBBAND_MERGE_DEG);
            let votes: u32 = near.iter().map(|p| p.1).sum();
            let offset: f64 = near
                .iter()
                .map(|p| wrap_deg(p.0 - at) * f64::from(p.1))
                .sum::<f64>()
                / f64::from(votes);
            merged.push((wrap_deg(at + offset), votes));
            peaks = rest;
        }
        merged.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.total_cmp(&b.0)));
        // Each direction is read off the full band's spectrum: at its strongest local
        // maximum within the merge distance (the octaves' coarser grid and their scatter
        // place it a few degrees off), else at its own cell.
        let maxima = spectrum.peaks(self.grid.num_azimuths(), 0.0);
        let (profile, el_at) = spectrum.azimuth_profile();
        let median = f64::from(crate::spectrum::median(&profile));
        let span = maxima.first().map_or(0.0, |d| d.strength - median);
        let mut extra: Vec<Doa> = Vec::new();
        for (azimuth_deg, votes) in merged {
            if (votes as usize) < c.subband_votes || extra.len() == c.num_peaks {
                break;
            }
            let near = |d: &&Doa| wrap_deg(d.azimuth_deg - azimuth_deg).abs() <= SUBBAND_MERGE_DEG;
            let doa = match maxima.iter().find(near) {
                Some(d) => Doa {
                    dominant_blocks: votes,
                    ..*d
                },
                None => {
                    let cell = self.grid.azimuth_cell(azimuth_deg);
                    let strength = f64::from(profile[cell]);
                    Doa {
                        azimuth_deg,
                        elevation_deg: self.grid.elevations()[el_at[cell]],
                        strength,
                        relative: if span > 0.0 {
                            (strength - median) / span
                        } else {
                            0.0
                        },
                        dominant_blocks: votes,
                        prominence: 0.0,
                        significance: 0.0,
                    }
                }
            };
            let apart = |d: &Doa| wrap_deg(d.azimuth_deg - doa.azimuth_deg).abs() > c.min_sep_deg;
            if row.iter().all(apart) && extra.iter().all(apart) {
                extra.push(doa);
            }
        }
        extra
    }

    /// The peaks (strongest first, and the next one beyond `N`) that [`SslConfig`]'s
    /// height rules (`stands_out`) keep, and those they do not that stand at least
    /// [`SslConfig::incoherent_relative`] high and are incoherent with every stronger peak
    /// ([`SslConfig::max_incoherence`]). Stronger peaks are all of them, reported or not:
    /// a peak that copies a reflection the height rules left out copies its source too.
    /// The recording's covariance (`spec`, the blocks the pooling kept) is computed once,
    /// when a peak first needs it.
    pub(super) fn by_coherence(
        &self,
        peaks: Vec<Doa>,
        next: Option<Doa>,
        spec: &Spectrogram,
        stands_out: impl Fn(&Doa) -> bool,
    ) -> (Vec<Doa>, Option<Doa>) {
        let c = &self.config;
        let has_next = next.is_some();
        let all: Vec<Doa> = peaks.into_iter().chain(next).collect();
        let n = all.len() - usize::from(has_next);
        let mut cov = None;
        let mut kept: Vec<Doa> = Vec::new();
        let mut last = None;
        for (i, p) in all.iter().enumerate() {
            let keep = stands_out(p)
                || (i > 0 && p.relative >= c.incoherent_relative && {
                    let cov = cov.get_or_insert_with(|| {
                        SpatialCovariance::of(spec, self.kept_frames(spec).into_iter().flatten())
                    });
                    all[..i].iter().all(|s| {
                        self.source_coherence(cov, s, p)
                            .is_some_and(|g| g < c.max_incoherence)
                    })
                });
            if keep {
                if i == n {
                    last = Some(*p);
                } else {
                    kept.push(*p);
                }
            }
        }
        (kept, last)
    }

    /// The source coherence of two DoAs in the recording whose covariance is `cov`
    /// ([`SpatialCovariance::source_coherence`]).
    pub(super) fn source_coherence(
        &self,
        cov: &SpatialCovariance,
        a: &Doa,
        b: &Doa,
    ) -> Option<f64> {
        let unit = |d: &Doa| unit_vector(d.azimuth_deg, d.elevation_deg);
        cov.source_coherence(
            self.array.positions(),
            f64::from(self.sample_rate),
            self.stft.frame_len(),
            self.config.speed_of_sound,
            unit(a),
            unit(b),
        )
    }

    /// `doas` and `next` (strongest first) without the peaks that do not stand more than
    /// [`SslConfig::sidelobe_ratio`] times above the sidelobes of the stronger peaks kept,
    /// unless they were the strongest direction of a block ([`Doa::dominant_blocks`]). As
    /// with the other thresholds, a peak dropped leaves its place empty.
    pub(super) fn drop_sidelobes(
        &self,
        doas: Vec<Doa>,
        next: Option<Doa>,
    ) -> Result<(Vec<Doa>, Option<Doa>)> {
        let n = doas.len();
        let ratio = self.config.sidelobe_ratio;
        let mut scratch = Scratch::default();
        // The kept peaks, each with its plane wave's profile once a weaker peak needs it.
        let mut kept: Vec<(Doa, Option<Vec<f32>>)> = Vec::new();
        let mut last = None;
        for (i, p) in doas.into_iter().chain(next).enumerate() {
            // A peak that was the strongest direction of a block is not a sidelobe: in a
            // block where a source sounds, its main lobe stands above its sidelobes.
            if !kept.is_empty() && p.dominant_blocks == 0 {
                let at = self.grid.azimuth_cell(p.azimuth_deg);
                let mut sidelobe = 0.0f64;
                for (k, profile) in &mut kept {
                    if profile.is_none() {
                        *profile = Some(self.plane_wave_profile(
                            k.azimuth_deg,
                            k.elevation_deg,
                            &mut scratch,
                        )?);
                    }
                    let profile = profile.as_deref().unwrap_or_default();
                    // Within 2 degrees: the sidelobe may stand a cell or two aside.
                    let here = self
                        .grid
                        .azimuth_window(at, 2.0)
                        .map(|j| profile[j])
                        .fold(0.0f32, f32::max);
                    sidelobe = sidelobe.max(k.relative * f64::from(here));
                }
                if p.relative <= ratio * sidelobe {
                    continue;
                }
            }
            if i == n {
                last = Some(p);
            } else {
                kept.push((p, None));
            }
        }
        Ok((kept.into_iter().map(|(d, _)| d).collect(), last))
    }

    /// The method's pooled azimuth profile of an ideal plane wave from `azimuth_deg`,
    /// `elevation_deg` (array frame) through this localizer's array, band, grid and
    /// settings, as heights above its median relative to its top (1 at the wave's
    /// direction; its sidelobes where they stand): one block of a periodic noise with a
    /// flat spectrum, delayed exactly at every microphone.
    ///
    /// # Errors
    /// None in practice (the synthetic recording fits the localizer by construction).
    pub fn plane_wave_profile(
        &self,
        azimuth_deg: f64,
        elevation_deg: f64,
        scratch: &mut Scratch,
    ) -> Result<Vec<f32>> {
        let len = self.wave_fft.len();
        let nbins = len / 2 + 1;
        let phases = &self.wave_phases;
        let u = unit_vector(azimuth_deg, elevation_deg);
        let fs = f64::from(self.sample_rate);
        let c = self.config.speed_of_sound;
        let channels = self
            .array
            .positions()
            .iter()
            .map(|p| {
                // A microphone further along `u` hears the wave earlier by `lead` seconds:
                // x(t) = s(t + lead), X = S e^(i w lead).
                let lead = (p[0] * u[0] + p[1] * u[1] + p[2] * u[2]) / c;
                let mut spec: Vec<Complex32> = (0..nbins)
                    .map(|k| {
                        if k == 0 || (len % 2 == 0 && k == nbins - 1) {
                            return Complex32::default();
                        }
                        let w = std::f64::consts::TAU * k as f64 / len as f64 * fs;
                        let (im, re) = (phases[k] + w * lead).sin_cos();
                        Complex32::new(re as f32, im as f32)
                    })
                    .collect();
                let mut x = vec![0.0f32; len];
                self.wave_fft
                    .process(&mut spec, &mut x)
                    .expect("a spectrum of the planned length, real at DC and Nyquist");
                x
            })
            .collect();
        let audio = Audio::new(self.sample_rate, channels)?;
        self.analyse(&audio, scratch)?;
        // The method's own response to the wave: the robot's noise is no part of it.
        scratch.spec.noise = None;
        let (profile, _) = self.pooled(scratch, Blocks::Estimate).azimuth_profile();
        let median = crate::spectrum::median(&profile);
        let top = profile.iter().copied().fold(f32::MIN, f32::max);
        let span = (top - median).max(f32::MIN_POSITIVE);
        Ok(profile.iter().map(|v| (v - median) / span).collect())
    }

    /// The PHAT coherence of `spec` that [`Localizer::significance`] steers: with `u`
    /// each channel's unit phasors, `G_ij(b) = sum_f u_i u_j^*` over all frames, for every
    /// pair `i < j` and bin `b`.
    pub(super) fn coherence(&self, spec: &Spectrogram) -> Coherence {
        let m = self.array.len();
        let nf = spec.num_frames();
        let bins = spec.bins();
        let nb = bins.len();
        let pairs: Vec<(usize, usize)> = (0..m)
            .flat_map(|i| (i + 1..m).map(move |j| (i, j)))
            .collect();
        let np = pairs.len();
        // G_p(b) = sum over frames of u_i u_j^*, u the unit phasors; real and imaginary
        // parts apart, bins contiguous, so that the sums vectorise.
        let (mut gr, mut gi) = (vec![0.0f32; np * nb], vec![0.0f32; np * nb]);
        let (mut ur, mut ui) = (vec![0.0f32; m * nb], vec![0.0f32; m * nb]);
        // With the robot's noise ([`crate::noise`]): per pair and bin, its coherence
        // `N_ij / sqrt(N_ii N_jj)` and `sqrt(N_ii N_jj)`; per channel and bin, `1 / |x|`.
        let noise: Option<(Vec<Complex32>, Vec<f32>)> = spec.noise().map(|field| {
            let mut gamma = Vec::with_capacity(np * nb);
            let mut own = Vec::with_capacity(np * nb);
            for &(i, j) in &pairs {
                for b in bins.clone() {
                    let o = (field.power(b, i) * field.power(b, j)).sqrt();
                    own.push(o);
                    gamma.push(if o > f32::MIN_POSITIVE {
                        field.cross(b, i, j) / o
                    } else {
                        Complex32::default()
                    });
                }
            }
            (gamma, own)
        });
        let mut inv_mag = vec![0.0f32; if noise.is_some() { m * nb } else { 0 }];
        for f in 0..nf {
            for i in 0..m {
                let x = spec.frame(f, i);
                let r = ur[i * nb..(i + 1) * nb].iter_mut();
                let im = ui[i * nb..(i + 1) * nb].iter_mut();
                for (k, ((v, r), im)) in x.iter().zip(r).zip(im).enumerate() {
                    let n2 = v.re * v.re + v.im * v.im;
                    let inv = if n2 > 0.0 { n2.sqrt().recip() } else { 0.0 };
                    *r = v.re * inv;
                    *im = v.im * inv;
                    if let Some(w) = inv_mag.get_mut(i * nb + k) {
                        *w = inv;
                    }
                }
            }
            for (p, &(i, j)) in pairs.iter().enumerate() {
                let (ar, ai) = (&ur[i * nb..(i + 1) * nb], &ui[i * nb..(i + 1) * nb]);
                let (br, bi) = (&ur[j * nb..(j + 1) * nb], &ui[j * nb..(j + 1) * nb]);
                let sums = gr[p * nb..(p + 1) * nb]
                    .iter_mut()
                    .zip(&mut gi[p * nb..(p + 1) * nb]);
                for ((((sr, si), ar), ai), (br, bi)) in sums.zip(ar).zip(ai).zip(br.iter().zip(bi))
                {
                    *sr += ar * br + ai * bi;
                    *si += ai * br - ar * bi;
                }
            }
            if let Some((gamma, own)) = &noise {
                // Less the robot's noise: its coherence, in proportion to its share of the
                // frame's `|x_i| |x_j|` (at most all of it). Each term stays a phasor's
                // size, so the statistic's spread under independent noise stays what the
                // test assumes.
                for (p, &(i, j)) in pairs.iter().enumerate() {
                    let (wi, wj) = (
                        &inv_mag[i * nb..(i + 1) * nb],
                        &inv_mag[j * nb..(j + 1) * nb],
                    );
                    let at = p * nb..(p + 1) * nb;
                    let terms = gamma[at.clone()]
                        .iter()
                        .zip(&own[at])
                        .zip(wi.iter().zip(wj));
                    for (k, ((g, o), (a, b))) in terms.enumerate() {
                        let share = (o * a * b).min(1.0);
                        gr[p * nb + k] -= g.re * share;
                        gi[p * nb + k] -= g.im * share;
                    }
                }
            }
        }
        Coherence {
            frames: nf,
            bins,
            pairs,
            re: gr,
            im: gi,
        }
    }

    /// Each DoA's [`Doa::significance`] in the recording whose [`Coherence`] is `g`: the
    /// statistic `sum_(i<j) sum_b Re(G_ij(b) e^(-i w_b tau_ij)) / (F B P)` at the pairs'
    /// delays `tau_ij` of the direction, divided by its standard deviation under
    /// independent noise, `1 / sqrt(2 F B P)` (each term then has mean 0 and variance 1/2).
    pub(super) fn significance(&self, g: &Coherence, doas: &[Doa]) -> Vec<f64> {
        let pos = self.array.positions();
        let fs = f64::from(self.sample_rate);
        let c = self.config.speed_of_sound;
        let frame_len = self.stft.frame_len() as f64;
        let Coherence {
            frames: nf,
            bins,
            pairs,
            re: gr,
            im: gi,
        } = g;
        let (nf, nb, np) = (*nf, bins.len(), pairs.len());
        let sigma0 = (1.0 / (2.0 * nf as f64 * nb as f64 * np as f64)).sqrt();
        doas.iter()
            .map(|d| {
                let u = unit_vector(d.azimuth_deg, d.elevation_deg);
                let lead: Vec<f64> = pos
                    .iter()
                    .map(|q| (q[0] * u[0] + q[1] * u[1] + q[2] * u[2]) / c * fs)
                    .collect();
                let mut total = 0.0f64;
                for (p, &(i, j)) in pairs.iter().enumerate() {
                    // e^(-i w_b tau) over the band's bins, a geometric progression in b.
                    let step = -std::f64::consts::TAU / frame_len * (lead[i] - lead[j]);
                    let (mut re, mut im) = (step * bins.start as f64).sin_cos();
                    (re, im) = (im, re);
                    let (sr, si) = (step.cos(), step.sin());
                    let (g_re, g_im) = (&gr[p * nb..(p + 1) * nb], &gi[p * nb..(p + 1) * nb]);
                    for (a, b) in g_re.iter().zip(g_im) {
                        // Re(G e^(-i w tau)), with e^(-i w tau) = re + i im.
                        total += f64::from(*a) * re - f64::from(*b) * im;
                        (re, im) = (re * sr - im * si, re * si + im * sr);
                    }
                }
                total / (nf as f64 * nb as f64 * np as f64) / sigma0
            })
            .collect()
    }
}

/// A recording's PHAT coherence per microphone pair and bin ([`Localizer::coherence`]).
pub(super) struct Coherence {
    /// Frames summed.
    frames: usize,
    /// The FFT bins, as the spectrogram kept them.
    bins: Range<usize>,
    /// The pairs `(i, j)`, `i < j`.
    pairs: Vec<(usize, usize)>,
    /// Real and imaginary parts of `G`, per pair then bin.
    re: Vec<f32>,
    im: Vec<f32>,
}
