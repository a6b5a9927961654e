//! Mapping while the robot records: a [`Session`] localises each new recording and adds it
//! to an [`asm::OnlineMapper`] as the next stop; a [`Follower`] finds the next complete
//! recording and its pose in a folder that a recorder is still writing.
//!
//! `iasm watch` is these two in a loop (woken by file-system notifications, with polling
//! as the fallback); `iasm watch --replay` feeds a finished data set through the same
//! session, stop by stop, and writes the curve the authors' online program records.

mod follower;

use std::time::Instant;

use anyhow::{Context, Result};
use asm::map::OccupancyMap;
use asm::ospa::{Ospa, ospa};
use asm::{MapResult, Mapper, OnlineMapper, Pose};
use serde::Serialize;
use ssl::{Audio, Localizer, MicArray, Scratch, SslConfig};

use crate::settings::Settings;

pub use follower::{Follower, Next};

/// What one stop did, one row of the curve.
#[derive(Clone, Debug, Serialize)]
pub struct StopRecord {
    /// The stop's number (from 1).
    pub stop: usize,
    /// The recording's file name.
    pub file: String,
    /// DoAs the SSL returned.
    pub doas: usize,
    /// Sources on the map after the stop.
    pub sources: usize,
    /// OSPA of the map against the truth, when it is known.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub ospa: Option<Ospa>,
    /// Milliseconds to read and localise the recording.
    pub ssl_ms: f64,
    /// Milliseconds to update the map.
    pub map_ms: f64,
    /// Whether the stop started a full map over every stop so far (see [`asm::online`]: it
    /// runs beside the next stops, and the next stop takes it in).
    pub full_map: bool,
    /// Where the stop took in the full map the stop before it started: how long that map
    /// ran on its own thread (ms; not part of `map_ms`: it ran between the stops). `None`
    /// at every other stop.
    pub full_map_ms: Option<f64>,
    /// The recording's channels found not to hear the room ([`ssl::channels`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub faulty_channels: Vec<crate::pipeline::FaultyChannel>,
}

/// The SSL front end and the online mapper, fed one recording at a time.
pub struct Session {
    array: MicArray,
    /// Which channels of each recording are the array's microphones
    /// ([`Settings::channels`]).
    channels: Option<Vec<usize>>,
    ssl: SslConfig,
    /// The robot's own noise, subtracted by the SSL ([`Settings::noise`]).
    noise: Option<crate::pipeline::RobotNoise>,
    localizers: Vec<Localizer>,
    scratch: Scratch,
    mapper: OnlineMapper,
    truth: Option<Vec<[f64; 2]>>,
    ospa_c: f64,
    ospa_p: f64,
    poses: Vec<Pose>,
    /// Each stop's DoAs as given (degrees, array frame), for the rays a map is shown with.
    doas_deg: Vec<Vec<f64>>,
    recompute: bool,
}

impl Session {
    /// A session mapping on `map` with `settings`, seeded by `seed`; OSPA (cutoff `ospa_c`
    /// m, order `ospa_p`) against `truth` when given.
    ///
    /// # Errors
    /// Refused settings, an unreadable recording of the robot alone, or a map with no
    /// room for particles.
    pub fn new(
        map: &OccupancyMap,
        settings: &Settings,
        seed: u64,
        truth: Option<Vec<[f64; 2]>>,
        ospa_c: f64,
        ospa_p: f64,
    ) -> Result<Self> {
        let array = settings.mic_array()?;
        let config = asm::IasmConfig {
            mirror_axis_deg: settings.iasm.mirror_axis_deg.or(array.mirror_axis_deg()),
            ..settings.iasm.clone()
        };
        Ok(Self {
            array,
            channels: settings.channels.clone(),
            ssl: settings.ssl.clone(),
            noise: crate::pipeline::RobotNoise::of(settings)?,
            localizers: Vec::new(),
            scratch: Scratch::default(),
            mapper: OnlineMapper::new(Mapper::new(map, &config)?, seed),
            truth,
            ospa_c,
            ospa_p,
            poses: Vec::new(),
            doas_deg: Vec::new(),
            recompute: false,
        })
    }

    /// Maps every stop from scratch, over all the stops so far, as the authors' online
    /// program does: the baseline the incremental mapper is measured against.
    pub fn recompute_every_stop(mut self) -> Self {
        self.recompute = true;
        self
    }

    /// The DoAs of one recording (azimuths in degrees, strongest first), and whether N cut
    /// the row ([`ssl::Located::cut`]).
    ///
    /// # Errors
    /// A recording the array or the SSL settings cannot take.
    pub fn localise_row(&mut self, audio: &Audio) -> Result<(Vec<f64>, bool)> {
        let row = self.locate(audio)?;
        Ok((row.all().map(|d| d.azimuth_deg).collect(), row.cut))
    }

    /// The SSL's row for `audio` (a recording's every channel: the settings' `channels`
    /// are picked here), with a localizer for its sample rate.
    fn locate(&mut self, audio: &Audio) -> Result<ssl::Located> {
        let picked;
        let audio = match &self.channels {
            None => audio,
            Some(c) => {
                picked = crate::dataset::pick_channels(audio, c)?;
                &picked
            }
        };
        let fs = audio.sample_rate();
        let i = match self.localizers.iter().position(|l| l.sample_rate() == fs) {
            Some(i) => i,
            None => {
                self.localizers.push(crate::pipeline::localizer(
                    &self.array,
                    fs,
                    &self.ssl,
                    self.noise.as_ref(),
                )?);
                self.localizers.len() - 1
            }
        };
        self.localizers[i]
            .locate_row_with_scratch(audio, &mut self.scratch)
            .map_err(|e| crate::pipeline::with_channel_hint(e, self.channels.as_deref()))
    }

    /// Localises `audio` (the recording `name`, heard at `pose`) and adds it as the next
    /// stop.
    ///
    /// # Errors
    /// As [`Session::localise_row`], or a pose the mapper refuses; named.
    pub fn add_recording(&mut self, name: &str, pose: Pose, audio: &Audio) -> Result<StopRecord> {
        let t0 = Instant::now();
        let row = self
            .locate(audio)
            .with_context(|| format!("localising {name}"))?;
        let doas: Vec<f64> = row.all().map(|d| d.azimuth_deg).collect();
        let ssl_ms = 1e3 * t0.elapsed().as_secs_f64();
        let mut r = self.add_row(name, pose, &doas, Some(row.cut))?;
        r.ssl_ms = ssl_ms;
        r.faulty_channels = crate::pipeline::FaultyChannel::of(&row, self.array.len());
        Ok(r)
    }

    /// Adds a stop whose DoAs (degrees, array frame) are already known, told whether the
    /// SSL cut the row at N (`None`: not known, as for a table; see
    /// [`asm::Mapper::run_rows`]).
    ///
    /// # Errors
    /// A non-finite pose or more DoAs than N, naming the stop.
    pub fn add_row(
        &mut self,
        name: &str,
        pose: Pose,
        doas_deg: &[f64],
        cut: Option<bool>,
    ) -> Result<StopRecord> {
        let t0 = Instant::now();
        let rad = self.mapped_row(doas_deg, cut);
        let u = self
            .mapper
            .add_row(pose, &rad, cut)
            .with_context(|| format!("stop {} ({name})", self.poses.len() + 1))?;
        self.poses.push(pose);
        self.doas_deg.push(doas_deg.to_vec());
        if self.recompute {
            self.mapper.consolidate();
        }
        let map_ms = 1e3 * t0.elapsed().as_secs_f64();
        Ok(StopRecord {
            stop: u.stop + 1,
            file: name.to_owned(),
            doas: doas_deg.len(),
            sources: u.sources,
            ospa: self.ospa(&self.mapper.map()),
            ssl_ms: 0.0,
            map_ms,
            full_map: u.full,
            full_map_ms: u.full_ms,
            faulty_channels: Vec::new(),
        })
    }

    /// A row of DoAs (degrees) as the mapper takes it (rad): a table's row past N is cut to
    /// N, as `iasm map` reads a table; a row the SSL cut keeps its extra DoAs.
    fn mapped_row(&self, doas_deg: &[f64], cut: Option<bool>) -> Vec<f64> {
        let n = self.mapper.mapper().config().num_doas;
        let keep = if cut == Some(true) {
            doas_deg.len()
        } else {
            doas_deg.len().min(n)
        };
        doas_deg[..keep].iter().map(|a| a.to_radians()).collect()
    }

    /// Adds stops whose DoAs (degrees) are known, `(pose, DoAs, cut)` as
    /// [`Session::add_row`] takes each, mapped at once with one full map
    /// ([`OnlineMapper::add_history`]): how a map is rebuilt over the stops so far when its
    /// region changes or a merging node starts late, at the cost of one batch map.
    ///
    /// # Errors
    /// A non-finite pose, a stop outside the map or more DoAs than N, naming the stop; the
    /// session is then unchanged.
    pub fn add_history<'a>(
        &mut self,
        rows: impl IntoIterator<Item = (Pose, &'a [f64], Option<bool>)>,
    ) -> Result<()> {
        let rows: Vec<_> = rows.into_iter().collect();
        let rad: Vec<Vec<f64>> = (rows.iter())
            .map(|&(_, d, cut)| self.mapped_row(d, cut))
            .collect();
        self.mapper
            .add_history(rows.iter().zip(&rad).map(|(&(p, _, c), r)| (p, &r[..], c)))
            .context("mapping the stops so far")?;
        for (pose, d, _) in rows {
            self.poses.push(pose);
            self.doas_deg.push(d.to_vec());
        }
        Ok(())
    }

    /// Ends the run with a full map over every stop (what `iasm map` gives on the same
    /// DoAs and seed), and returns it.
    pub fn finish(&mut self) -> MapResult {
        self.mapper.consolidate();
        self.mapper.map()
    }

    /// The current map.
    pub fn map(&self) -> MapResult {
        self.mapper.map()
    }

    /// Waits for the full map running beside the stops, if one does
    /// ([`OnlineMapper::wait_for_full_map`]): a replay calls it between stops, where a
    /// robot drives and records for seconds.
    pub fn wait_for_full_map(&mut self) {
        self.mapper.wait_for_full_map();
    }

    /// The stops so far.
    pub fn poses(&self) -> &[Pose] {
        &self.poses
    }

    /// Each stop's DoAs as given (degrees, array frame, strongest first).
    pub fn doas_deg(&self) -> &[Vec<f64>] {
        &self.doas_deg
    }

    /// The truth, when known.
    pub fn truth(&self) -> Option<&[[f64; 2]]> {
        self.truth.as_deref()
    }

    /// The OSPA of `map` against the truth, when it is known.
    pub fn ospa(&self, map: &MapResult) -> Option<Ospa> {
        self.truth
            .as_ref()
            .map(|t| ospa(&map.positions(), t, self.ospa_c, self.ospa_p))
    }
}

/// The curve as CSV: one row per stop, the stop number first.
pub fn curve_csv(records: &[StopRecord]) -> String {
    let mut s = String::from(
        "stop,file,doas,sources,ospa_m,localisation_m,cardinality_m,ssl_ms,map_ms,full_map,full_map_ms\n",
    );
    for r in records {
        let o = |f: fn(&Ospa) -> f64| {
            r.ospa
                .as_ref()
                .map_or(String::new(), |o| format!("{:.4}", f(o)))
        };
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{:.2},{:.2},{},{}\n",
            r.stop,
            r.file,
            r.doas,
            r.sources,
            o(|o| o.total),
            o(|o| o.localization),
            o(|o| o.cardinality),
            r.ssl_ms,
            r.map_ms,
            u8::from(r.full_map),
            r.full_map_ms.map_or(String::new(), |ms| format!("{ms:.2}"))
        ));
    }
    s
}
