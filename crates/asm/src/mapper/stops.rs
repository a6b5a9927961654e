//! The stops a map is made from, as one list: what each stop heard and what the SSL said
//! of its row, built once and read by every step.

use super::*;

/// The stops a map is made from: for each, the robot's pose, the DoAs it heard as world
/// bearings (strongest first, `wrap(azimuth + theta)`: non-finite ones
/// dropped, a linear array's each followed by its mirror image), whether its row holds
/// every peak the SSL let through (see [`Mapper::run_rows`]), and whether the SSL said it
/// cut the row at `N`.
///
/// Built once from the tables ([`Mapper::stops`]), a stop at a time
/// ([`Mapper::push_stop`], as the online mapper takes them), or from world bearings
/// ([`Stops::new`]), so that the lists cannot differ in length. The steps of the mapper
/// read the stops from here and work on a *pool* beside it: one row per stop of the DoAs
/// no source explains yet, which starts as [`Stops::heard`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stops {
    poses: Vec<Pose>,
    heard: Vec<Vec<f64>>,
    complete: Vec<bool>,
    said_cut: Vec<bool>,
}

impl Stops {
    /// The stops from their poses, the world bearings each heard (strongest first), which
    /// rows are complete and which the SSL said it cut.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] if `heard` or `complete` has not one entry per pose,
    /// [`Error::CutMismatch`] if `said_cut` has not.
    pub fn new(
        poses: Vec<Pose>,
        heard: Vec<Vec<f64>>,
        complete: Vec<bool>,
        said_cut: Vec<bool>,
    ) -> Result<Self> {
        for n in [heard.len(), complete.len()] {
            if n != poses.len() {
                return Err(Error::LengthMismatch {
                    poses: poses.len(),
                    doas: n,
                });
            }
        }
        if said_cut.len() != poses.len() {
            return Err(Error::CutMismatch {
                poses: poses.len(),
                cut: said_cut.len(),
            });
        }
        Ok(Self {
            poses,
            heard,
            complete,
            said_cut,
        })
    }

    /// How many stops.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether there is no stop.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// The robot's pose at each stop.
    pub fn poses(&self) -> &[Pose] {
        &self.poses
    }

    /// Each stop's DoAs as world bearings (rad), strongest first.
    pub fn heard(&self) -> &[Vec<f64>] {
        &self.heard
    }

    /// Whether each stop's row holds every peak the SSL let through.
    pub fn complete(&self) -> &[bool] {
        &self.complete
    }

    /// Whether the SSL said it cut each stop's row at `N`.
    pub fn said_cut(&self) -> &[bool] {
        &self.said_cut
    }

    /// A pool in which no DoA is explained yet: a copy of [`Stops::heard`].
    pub fn pool(&self) -> Vec<Vec<f64>> {
        self.heard.clone()
    }

    fn push(&mut self, pose: Pose, heard: Vec<f64>, complete: bool, said_cut: bool) {
        self.poses.push(pose);
        self.heard.push(heard);
        self.complete.push(complete);
        self.said_cut.push(said_cut);
    }
}

impl Mapper {
    /// The stops of a survey: each pose with its DoAs (array-frame azimuths, rad,
    /// strongest first, at most `N`; non-finite ones are empty cells) and, when the SSL
    /// gives them, the rows it cut at `N` (`cut`; see [`Mapper::run_rows`]).
    ///
    /// # Errors
    /// [`Error::NoPoses`], [`Error::LengthMismatch`] or [`Error::CutMismatch`] if the
    /// tables differ in length, [`Error::NonFinitePose`] and [`Error::TooManyDoas`] naming
    /// the first such stop.
    pub fn stops(
        &self,
        poses: &[Pose],
        doas_rad: &[Vec<f64>],
        cut: Option<&[bool]>,
    ) -> Result<Stops> {
        if let Some(cut) = cut
            && cut.len() != poses.len()
        {
            return Err(Error::CutMismatch {
                poses: poses.len(),
                cut: cut.len(),
            });
        }
        if poses.is_empty() {
            return Err(Error::NoPoses);
        }
        if poses.len() != doas_rad.len() {
            return Err(Error::LengthMismatch {
                poses: poses.len(),
                doas: doas_rad.len(),
            });
        }
        if let Some(index) = poses.iter().position(|p| !p.is_finite()) {
            return Err(Error::NonFinitePose { index });
        }
        if !poses.iter().any(|p| self.in_map(*p)) {
            let (lo, hi) = poses.iter().fold(
                ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
                |(lo, hi), p| {
                    (
                        [lo[0].min(p.x), lo[1].min(p.y)],
                        [hi[0].max(p.x), hi[1].max(p.y)],
                    )
                },
            );
            return Err(Error::NoStopInMap {
                stops: poses.len(),
                stops_box: [lo[0], hi[0], lo[1], hi[1]],
                map_box: self.map_box(),
            });
        }
        let mut stops = Stops::default();
        for (k, (pose, row)) in poses.iter().zip(doas_rad).enumerate() {
            self.push_stop(&mut stops, *pose, row, cut.map(|c| c[k]))?;
        }
        Ok(stops)
    }

    /// Whether the stop at `pose` lies within the occupancy map's grid.
    pub fn in_map(&self, pose: Pose) -> bool {
        self.map.world_to_cell([pose.x, pose.y]).is_some()
    }

    /// The map's extent: x min, x max, y min, y max (m).
    fn map_box(&self) -> [f64; 4] {
        let [x0, y0] = self.map.origin();
        let r = self.map.resolution();
        [
            x0,
            x0 + r * self.map.width() as f64,
            y0,
            y0 + r * self.map.height() as f64,
        ]
    }

    /// [`Error::StopOutsideMap`] for a stop that lies outside the map: what the online
    /// mapper says of a stop it is given one at a time.
    ///
    /// # Errors
    /// As said.
    pub fn check_in_map(&self, index: usize, pose: Pose) -> Result<()> {
        if self.in_map(pose) {
            return Ok(());
        }
        Err(Error::StopOutsideMap {
            index,
            x: pose.x,
            y: pose.y,
            map_box: self.map_box(),
        })
    }

    /// Adds one stop to `stops`: the robot's pose and its DoAs (as [`Mapper::stops`]
    /// takes them), told whether the SSL cut the row at `N` (`None` when it is not known,
    /// as for a table: a full row is then taken as cut).
    ///
    /// # Errors
    /// [`Error::NonFinitePose`] or [`Error::TooManyDoas`], naming the stop; `stops` is
    /// unchanged.
    pub fn push_stop(
        &self,
        stops: &mut Stops,
        pose: Pose,
        doas_rad: &[f64],
        cut: Option<bool>,
    ) -> Result<()> {
        let index = stops.len();
        if !pose.is_finite() {
            return Err(Error::NonFinitePose { index });
        }
        if !self.row_fits(doas_rad.len(), cut) {
            return Err(Error::TooManyDoas {
                index,
                got: doas_rad.len(),
                n: self.config.num_doas,
            });
        }
        let heard = doas_rad.iter().filter(|a| a.is_finite()).count();
        let row = self.stop_bearings(&pose, doas_rad);
        stops.push(pose, row, self.complete(heard, cut), cut == Some(true));
        Ok(())
    }

    /// Whether a row of `len` DoAs is one the mapper takes: at most `N`, or, in a row the
    /// SSL says it cut at `N` (`cut`), `N` more beyond them (the extra DoAs its octaves
    /// heard: `ssl::Located::extra`).
    fn row_fits(&self, len: usize, cut: Option<bool>) -> bool {
        let n = self.config.num_doas;
        len <= n || (cut == Some(true) && len <= 2 * n)
    }

    /// Whether a row of `len` DoAs holds every peak the SSL let through: not cut at `N`
    /// when the SSL says (`cut`), else shorter than `N`. The one rule behind
    /// [`Mapper::stops`] and [`Mapper::complete_by_length`].
    fn complete(&self, len: usize, cut: Option<bool>) -> bool {
        cut.map_or(len < self.config.num_doas, |cut| !cut)
    }

    /// Which of `rows` (each stop's DoAs) hold every peak the SSL let through, when
    /// nothing else says: those with fewer than `N` DoAs (a full row may have been cut at
    /// `N`; see [`Mapper::run_rows`]).
    pub fn complete_by_length(&self, rows: &[Vec<f64>]) -> Vec<bool> {
        rows.iter().map(|r| self.complete(r.len(), None)).collect()
    }
}
