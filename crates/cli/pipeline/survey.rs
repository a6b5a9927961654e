//! A robot run as the mapper takes it: the inputs, the survey loaded from them (a DoA
//! table, or the recordings localised), one map and its score.

use std::path::Path;

use super::*;

/// Where a survey's parts come from: a data set folder, and files that override its parts.
#[derive(Clone, Debug, Default)]
pub struct SurveyInputs {
    /// A data set folder in the published layout.
    pub dataset: Option<PathBuf>,
    /// A ROS occupancy map YAML.
    pub map: Option<PathBuf>,
    /// A pose table (x, y, theta per stop).
    pub poses: Option<PathBuf>,
    /// Whether the pose table's theta is in radians (else degrees).
    pub theta_in_radians: bool,
    /// A DoA table (degrees, array frame); when absent the recordings are localised.
    pub doas: Option<PathBuf>,
    /// A folder of recordings, one per stop (default: the data set's `audio/`).
    pub audio: Option<PathBuf>,
    /// Ground-truth source positions.
    pub truth: Option<PathBuf>,
    /// One continuous recording instead of one per stop: cut into a window of `window_s`
    /// seconds from each pose's time stamp (the pose table then has t, x, y, theta).
    pub recording: Option<PathBuf>,
    /// The window per pose of a continuous recording (s).
    pub window_s: f64,
    /// Without an occupancy map (no `map` and no data set with a `map/` folder): the
    /// sources are searched within this many metres of a stop (default
    /// [`OPEN_MARGIN_M`]; see [`asm::map::OccupancyMap::open_around`]).
    pub open_margin_m: Option<f64>,
}

/// How far from the stops a survey without an occupancy map searches for sources (m): a
/// room's half-width, where a robot driving through a room hears the sources in it.
pub const OPEN_MARGIN_M: f64 = 3.0;

/// The grid of an open region (m): as fine as the ROS maps robots build.
pub const OPEN_RESOLUTION_M: f64 = 0.05;

/// What one robot run gives the mapper.
#[derive(Clone, Debug)]
pub struct Survey {
    /// The occupancy map.
    pub map: OccupancyMap,
    /// `Some(margin)` when no occupancy map was given and [`Survey::map`] is the region
    /// within `margin` metres of the stops ([`asm::map::OccupancyMap::open_around`]).
    pub open_margin_m: Option<f64>,
    /// One pose per stop.
    pub poses: Vec<Pose>,
    /// The DoAs heard at each stop: azimuths in degrees, array frame, strongest first;
    /// `None` for an empty cell.
    pub doas_deg: Table,
    /// Per stop, whether the SSL cut its row at N (a further peak passed its thresholds;
    /// [`ssl::Located::cut`]); `None` for a DoA table, whose rows do not say (the mapper
    /// then takes a full row as cut; see [`asm::Mapper::run_rows`]).
    pub cut: Option<Vec<bool>>,
    /// The true source positions (m), when known.
    pub truth: Option<Vec<[f64; 2]>>,
    /// Where the DoAs came from: a table's path, or `ssl:<method>`.
    pub doa_source: String,
    /// For a linear array, the azimuth of its line (degrees, array frame;
    /// [`ssl::MicArray::mirror_axis_deg`]): the mapper takes each DoA and its mirror image
    /// (see [`Survey::mapper_config`]). A DoA table is taken to be in the frame of the
    /// settings' array.
    pub mirror_axis_deg: Option<f64>,
}

/// What a user of a linear array must know, or `None` for any other array.
pub fn linear_array_note(array: &MicArray) -> Option<String> {
    array.mirror_axis_deg().map(|axis| {
        format!(
            "note: the array {} is linear (its line at {axis:.1} deg): it cannot tell a source at azimuth a from one at {:.1} - a, its mirror image; DoAs are reported between {axis:.1} and {:.1} deg, and the mapper weighs both sides (only a robot that turns tells them apart; a source it cannot place is marked with its mirror position)",
            array.name(),
            2.0 * axis,
            axis + 180.0
        )
    })
}

impl Survey {
    /// Reads and checks a survey: the map, the poses, the truth, and the DoAs from a table
    /// or, when none is given, by localising the recordings with `settings`.
    ///
    /// # Errors
    /// Missing or unreadable inputs, or tables that do not match one to one, named.
    pub fn load(inputs: &SurveyInputs, settings: &Settings) -> Result<Self> {
        Self::load_with_doas(inputs, settings, None)
    }

    /// [`Survey::load`] with the DoAs given (a table and where it came from) instead of
    /// read or localised: several DoA sources on one survey.
    ///
    /// # Errors
    /// As [`Survey::load`].
    pub fn load_with_doas(
        inputs: &SurveyInputs,
        settings: &Settings,
        doas: Option<(Table, String)>,
    ) -> Result<Self> {
        let ds = inputs.dataset.as_deref().map(Dataset::open).transpose()?;
        let map_path = match (&inputs.map, &ds) {
            (Some(p), _) => Some(p.clone()),
            (None, Some(d)) if d.root.join("map").is_dir() => {
                Some(first_with_ext(&d.root.join("map"), "yaml")?)
            }
            (None, _) => None,
        };
        let map = map_path.as_deref().map(load_map).transpose()?;
        let pose_path = match (&inputs.poses, &ds) {
            (Some(p), _) => p.clone(),
            (None, Some(d)) => d
                .poses
                .clone()
                .with_context(|| format!("{}: no pose table in pose/", d.root.display()))?,
            (None, None) => bail!("give --dataset DIR or --poses FILE"),
        };
        let timed = match &inputs.recording {
            Some(_) => Some(read_timed_poses(&pose_path, inputs.theta_in_radians)?),
            None => None,
        };
        let poses = match &timed {
            Some(t) => t.iter().map(|p| p.1).collect(),
            None => read_poses(&pose_path, inputs.theta_in_radians)?,
        };
        let truth_path = inputs
            .truth
            .clone()
            .or_else(|| ds.as_ref().and_then(|d| d.sources.clone()));
        let truth = truth_path.as_deref().map(read_sources).transpose()?;
        let (doas_deg, doa_source, cut) = if let Some((table, from)) = doas {
            (table, from, None)
        } else if let (Some(rec), Some(timed)) = (&inputs.recording, &timed) {
            localise_recording(rec, timed, &pose_path, inputs.window_s, settings)?
        } else if let Some(t) = &inputs.doas {
            (
                first_columns(read_table(t)?, settings.iasm.num_doas, t),
                t.display().to_string(),
                None,
            )
        } else {
            localise_folder(inputs, ds.as_ref(), poses.len(), &pose_path, settings)?
        };
        let (map, open_margin_m) = match map {
            Some(map) => (map, None),
            None => {
                let margin = inputs.open_margin_m.unwrap_or(OPEN_MARGIN_M);
                let stops: Vec<[f64; 2]> = poses.iter().map(|p| [p.x, p.y]).collect();
                let map = OccupancyMap::open_around(&stops, margin, OPEN_RESOLUTION_M)
                    .with_context(|| format!("poses from {}", pose_path.display()))?;
                (map, Some(margin))
            }
        };
        let survey = Self {
            map,
            open_margin_m,
            poses,
            doas_deg: Table::new(),
            cut: None,
            truth,
            doa_source: String::new(),
            mirror_axis_deg: settings.mic_array()?.mirror_axis_deg(),
        }
        .with_doas(doas_deg, doa_source, cut)
        .with_context(|| format!("poses from {}", pose_path.display()))?;
        Ok(survey)
    }

    /// What a user should know about the map when no occupancy map was given: where the
    /// sources were searched for, and how to change it.
    pub fn map_note(&self) -> Option<String> {
        self.open_margin_m.map(|m| {
            format!(
                "note: no occupancy map given: the sources are searched within {m} m of the stops (--open-margin M to change it; a map in map/ or --map bounds the search by the room)"
            )
        })
    }

    /// The same survey heard through other DoAs (a table, where it came from, and per
    /// stop whether the SSL cut its row, when it says; see [`Survey::cut`]): several DoA
    /// sources compared on one map, poses and truth, read once.
    ///
    /// # Errors
    /// If the table or the flags have not one row per pose.
    pub fn with_doas(
        self,
        doas_deg: Table,
        doa_source: String,
        cut: Option<Vec<bool>>,
    ) -> Result<Self> {
        ensure!(
            doas_deg.len() == self.poses.len(),
            "{} rows of DoAs ({doa_source}) but {} poses: they must match one to one",
            doas_deg.len(),
            self.poses.len()
        );
        if let Some(cut) = &cut {
            ensure!(
                cut.len() == self.poses.len(),
                "{} row-cut flags ({doa_source}) but {} poses: they must match one to one",
                cut.len(),
                self.poses.len()
            );
        }
        Ok(Self {
            doas_deg,
            cut,
            doa_source,
            ..self
        })
    }

    /// The DoAs as the mapper takes them: radians, empty cells dropped.
    pub fn doas_rad(&self) -> Vec<Vec<f64>> {
        self.doas_deg
            .iter()
            .map(|row| row.iter().flatten().map(|a| a.to_radians()).collect())
            .collect()
    }

    /// `config` as the mapper takes it for this survey: with the linear array's mirror axis
    /// ([`Survey::mirror_axis_deg`]) unless `config` sets one.
    pub fn mapper_config(&self, config: &IasmConfig) -> IasmConfig {
        IasmConfig {
            mirror_axis_deg: config.mirror_axis_deg.or(self.mirror_axis_deg),
            ..config.clone()
        }
    }

    /// One I-ASM map with `config` (see [`Survey::mapper_config`]), seeded by `seed`.
    ///
    /// # Errors
    /// As [`Mapper::new`] and [`Mapper::run`].
    pub fn map(&self, config: &IasmConfig, seed: u64) -> Result<MapResult> {
        let mapper = Mapper::new(&self.map, &self.mapper_config(config))?;
        Ok(mapper.run_seeded(&self.poses, &self.doas_rad(), self.cut.as_deref(), seed)?)
    }

    /// The OSPA of `result` against the truth (cutoff `c` m, order `p`), when it is known.
    pub fn ospa(&self, result: &MapResult, c: f64, p: f64) -> Option<Ospa> {
        self.truth
            .as_ref()
            .map(|t| ospa(&result.positions(), t, c, p))
    }
}

/// The first `n` columns of a DoA table (ranked tables list the strongest first, and are
/// often wider than the N a user maps with), saying once on stderr when it cuts.
pub fn first_columns(mut table: Table, n: usize, path: &std::path::Path) -> Table {
    let widest = table.iter().map(Vec::len).max().unwrap_or(0);
    if widest > n {
        eprintln!(
            "note: {} has up to {widest} DoAs per stop; mapping the first {n} (N = {n}, strongest first)",
            path.display()
        );
        table.iter_mut().for_each(|row| row.truncate(n));
    }
    table
}

/// A survey's DoAs: the table (degrees, array frame), where it came from, and which rows
/// the SSL cut at `N` (`None` for a table read, whose rows say nothing of it).
type Doas = (Table, String, Option<Vec<bool>>);

/// The DoAs of windows of `window_s` seconds cut from the continuous recording `rec` at
/// the times of the timed poses (from `pose_path`), localised with `settings`; a faulty
/// channel said on stderr.
fn localise_recording(
    rec: &Path,
    timed: &[(f64, Pose)],
    pose_path: &Path,
    window_s: f64,
    settings: &Settings,
) -> Result<Doas> {
    let audio = read_recording(rec, settings.channels.as_deref())?;
    let array = settings.mic_array()?;
    let times: Vec<f64> = timed.iter().map(|p| p.0).collect();
    let windows = cut_windows(&audio, &times, window_s).with_context(|| {
        format!(
            "cutting {} at the times of {}",
            rec.display(),
            pose_path.display()
        )
    })?;
    let rows = localise_audio(
        &windows,
        &array,
        settings.channels.as_deref(),
        &settings.ssl,
        RobotNoise::of(settings)?.as_ref(),
    )
    .with_context(|| format!("localising {}", rec.display()))?;
    let names: Vec<String> = (1..=rows.len()).map(|k| format!("window {k}")).collect();
    let faults: Vec<Vec<FaultyChannel>> = rows
        .iter()
        .map(|r| FaultyChannel::of(r, array.len()))
        .collect();
    for w in faulty_channel_warnings(names.iter().zip(&faults).map(|(n, f)| (n.as_str(), &f[..]))) {
        eprintln!("{}: {w}", rec.display());
    }
    Ok((
        mapped_table(
            rows.iter().map(|r| (&r.doas[..], &r.extra[..])),
            settings.ssl.num_peaks,
        ),
        format!("ssl:{}", settings.ssl.method),
        Some(rows.iter().map(|r| r.cut).collect()),
    ))
}

/// The DoAs of a folder of recordings, one per stop (`--audio`, or the data set's
/// `audio/`), localised with `settings`: as many as the `stops` of `pose_path`.
fn localise_folder(
    inputs: &SurveyInputs,
    ds: Option<&Dataset>,
    stops: usize,
    pose_path: &Path,
    settings: &Settings,
) -> Result<Doas> {
    let (files, folder) = match (&inputs.audio, ds) {
        (Some(dir), _) => (list_files(dir, "wav")?, dir.clone()),
        (None, Some(d)) => (d.audio.clone(), d.root.join("audio")),
        (None, None) => bail!("give --doas TABLE, --audio DIR or --dataset DIR"),
    };
    ensure!(
        !files.is_empty(),
        "{}: no WAV file to localise",
        folder.display()
    );
    ensure!(
        files.len() == stops,
        "{} recordings but {} poses in {}: they must match one to one",
        files.len(),
        stops,
        pose_path.display()
    );
    let rows = localise_files(
        &files,
        &settings.mic_array()?,
        settings.channels.as_deref(),
        &settings.ssl,
        RobotNoise::of(settings)?.as_ref(),
    )?;
    warn_recordings(&rows);
    Ok((
        mapped_table(
            rows.iter().map(|r| (&r.doas[..], &r.extra[..])),
            settings.ssl.num_peaks,
        ),
        format!("ssl:{}", settings.ssl.method),
        Some(rows.iter().map(|r| r.cut).collect()),
    ))
}

/// What a user should be told of a map that the map itself does not say: stops that lie
/// outside the occupancy map (some of them: none at all is an error,
/// [`asm::Error::NoStopInMap`]), and a map too large for the paper's particle density
/// (`asm::MAX_PARTICLES`). `iasm map` prints them as warnings and the Python bindings raise
/// them as `warnings.warn`.
pub fn map_warnings(
    map: &OccupancyMap,
    poses: &[Pose],
    config: &IasmConfig,
    result: &MapResult,
) -> Vec<String> {
    let mut out = Vec::new();
    let outside = poses
        .iter()
        .filter(|p| map.world_to_cell([p.x, p.y]).is_none())
        .count();
    if outside > 0 {
        out.push(format!(
            "{outside} of {} stops lie outside the occupancy map: their DoAs point from \
             beyond it (are all the poses in the map's frame?)",
            poses.len()
        ));
    }
    let known = map.known_cells().count();
    if result.particles == asm::MAX_PARTICLES
        && known as f64 / config.density_d > 1.0 + result.particles as f64
    {
        out.push(format!(
            "the map has {known} known cells: {} particles per round (the most a round has), \
             one per {:.0} cells instead of density_d = {}; crop the map to the surveyed area \
             for the paper's density",
            result.particles,
            known as f64 / result.particles as f64,
            config.density_d
        ));
    }
    out
}
