//! A simulated scene end to end: rendered, localised and mapped, as the regression suite
//! and the demo run it.

use super::*;

/// A scene rendered at every stop: recordings with known truth, ready for the pipeline.
pub struct Simulated {
    /// The scene's name (or its file's stem).
    pub name: String,
    /// The checked scene.
    pub scene: PreparedScene,
    /// What the array heard at each stop.
    pub audio: Vec<Audio>,
    /// The scene's array.
    pub array: MicArray,
    /// True source positions (m): every place a source stands at during the run.
    pub truth: Vec<[f64; 2]>,
    /// Where each source stands and at which stops ([`sim::scene::Place`]).
    pub places: Vec<sim::scene::Place>,
    /// The scene's occupancy map.
    pub map: OccupancyMap,
    /// For a scene with sources on the robot: the robot alone, rendered at the first stop
    /// ([`sim::scene::PreparedScene::render_robot_alone`]), which the SSL subtracts as a user's
    /// recording of their robot.
    pub noise: Option<RobotNoise>,
}

/// One run of the pipeline on a [`Simulated`] scene.
pub struct SceneRun {
    /// The DoAs, with the scene's poses, map and truth.
    pub survey: Survey,
    /// The DoA score of the first N DoAs per stop (hit within 5 degrees).
    pub score: DoaScore,
    /// The I-ASM map.
    pub map: MapResult,
    /// Its OSPA (p = 1, c = 1 m).
    pub ospa: Ospa,
}

impl Simulated {
    /// Renders a checked scene (`fallback_name` when it has none), every stop in parallel.
    ///
    /// # Errors
    /// If the scene's array cannot be built.
    pub fn render(scene: PreparedScene, fallback_name: String) -> Result<Self> {
        let name = if scene.scene.name.is_empty() {
            fallback_name
        } else {
            scene.scene.name.clone()
        };
        let fs = scene.scene.fs;
        let audio: Vec<Audio> = (0..scene.stops.len())
            .into_par_iter()
            .map(|k| {
                let ch = scene
                    .render_stop(k)
                    .into_iter()
                    .map(|c| c.into_iter().map(|v| v as f32).collect())
                    .collect();
                Audio::new(fs, ch).map_err(anyhow::Error::from)
            })
            .collect::<Result<_>>()?;
        let array = MicArray::new(name.clone(), scene.mics.clone())?;
        let places = scene.places();
        let truth = places.iter().map(|p| [p.pos[0], p.pos[1]]).collect();
        let map = crate::scenes::scene_map(&scene);
        let noise = scene
            .render_robot_alone(0)
            .map(|ch| -> Result<RobotNoise> {
                let ch = ch
                    .into_iter()
                    .map(|c| c.into_iter().map(|v| v as f32).collect())
                    .collect();
                Ok(RobotNoise {
                    path: PathBuf::from(format!("{name} (the robot alone, rendered)")),
                    audio: Audio::new(fs, ch)?,
                })
            })
            .transpose()?;
        Ok(Self {
            name,
            scene,
            audio,
            array,
            truth,
            places,
            map,
            noise,
        })
    }

    /// The robot's stops.
    pub fn poses(&self) -> &[Pose] {
        &self.scene.stops
    }

    /// Localises every stop with `ssl` (the scene's own array, whatever `ssl` says; the
    /// robot's noise subtracted when the scene has some).
    ///
    /// # Errors
    /// Settings refused for this array and rate.
    pub fn survey(&self, ssl: &SslConfig) -> Result<Survey> {
        let loc = localizer(&self.array, self.scene.scene.fs, ssl, self.noise.as_ref())
            .with_context(|| format!("scene {}", self.name))?;
        let rows: Vec<Located> = self
            .audio
            .par_iter()
            .map_init(Scratch::default, |scratch, a| {
                loc.locate_row_with_scratch(a, scratch)
            })
            .collect::<Result<_, _>>()
            .with_context(|| format!("localising scene {}", self.name))?;
        Ok(Survey {
            map: self.map.clone(),
            open_margin_m: None,
            poses: self.scene.stops.clone(),
            doas_deg: mapped_table(
                rows.iter().map(|r| (&r.doas[..], &r.extra[..])),
                ssl.num_peaks,
            ),
            cut: Some(rows.iter().map(|r| r.cut).collect()),
            truth: Some(self.truth.clone()),
            doa_source: format!("ssl:{}", ssl.method),
            mirror_axis_deg: self.array.mirror_axis_deg(),
        })
    }

    /// The whole pipeline with `settings`: localise, score, map with `seed`, OSPA (p = 1,
    /// c = 1 m). The score counts the first `min(N, sources)` DoAs of each stop (hit within
    /// 5 degrees): N is an upper bound a user guesses, and a stop cannot hear more sources
    /// than there are, so DoAs beyond the true count are neither rewarded nor punished.
    ///
    /// # Errors
    /// Settings refused.
    pub fn run(&self, settings: &Settings, seed: u64) -> Result<SceneRun> {
        let survey = self.survey(&settings.ssl)?;
        let score = score_doas(
            &survey.doas_deg,
            &survey.poses,
            &self.truth,
            settings.ssl.num_peaks.min(self.truth.len()),
            5.0,
            survey.mirror_axis_deg,
        )?;
        let map = survey.map(&settings.iasm, seed)?;
        let ospa = ospa(&map.positions(), &self.truth, 1.0, 1.0);
        Ok(SceneRun {
            survey,
            score,
            map,
            ospa,
        })
    }
}

/// The settings the suite and the demo run a scene with: `base`, with `method` and N.
pub fn scene_settings(base: &Settings, method: ssl::Method, n: usize) -> Settings {
    let mut s = base.clone();
    s.ssl.method = method;
    s.set_num(n);
    s
}
