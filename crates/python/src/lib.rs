//! `iasm._iasm`: the extension module behind the Python package `iasm`.
//!
//! It calls the same library code as the `iasm` command line, never the binary: the SSL's
//! localizer as `iasm ssl` builds it (`iasm::pipeline::localizer`), the settings through
//! the settings file's own parser and checks (`iasm::settings::Settings::from_toml`, so a
//! keyword argument has a setting's name, type and range, and a wrong one the same
//! message), the mapper as `iasm map` runs it (`asm::Mapper::run_rows`, seeded the same),
//! scenes as `iasm simulate` renders them. The Python layer (`python/iasm/__init__.py`)
//! checks shapes and dtypes, and turns what this module returns into Python objects.
//!
//! What crosses the boundary: numpy arrays in (read in place; a recording's channels are
//! copied once into the `f32` rows the SSL takes), numpy arrays out for bulk data (a
//! spectrum, a rendered scene's audio), and JSON text for the reports, which is exactly
//! the CLI's JSON (`serde` on the same structs) and which Python's `json` turns into dicts.
//! The GIL is released while the work runs.

use std::io::ErrorKind;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow};
use asm::map::{Cell, OccupancyMap};
use asm::{MapRng, Pose};
use numpy::{
    Complex32, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyReadonlyArray3,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyFileNotFoundError, PyMemoryError, PyValueError};
use pyo3::prelude::*;
use rand::SeedableRng;

use iasm::settings::Settings;

/// An error as Python expects it: `MemoryError` when a size bound is exceeded (a grid of
/// more cells than a map may have, a recording longer than one localisation takes),
/// `FileNotFoundError` when a file is missing, else `ValueError`; the message is the
/// CLI's (every cause, outermost first).
fn py_err(e: anyhow::Error) -> PyErr {
    let msg = format!("{e:#}");
    let too_large = e.chain().any(|c| {
        matches!(
            c.downcast_ref::<asm::MapError>(),
            Some(asm::MapError::TooLarge { .. })
        ) || matches!(
            c.downcast_ref::<ssl::Error>(),
            Some(ssl::Error::TooLong { .. })
        )
    });
    if too_large {
        return PyMemoryError::new_err(msg);
    }
    let missing = e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == ErrorKind::NotFound)
    });
    if missing {
        PyFileNotFoundError::new_err(msg)
    } else {
        PyValueError::new_err(msg)
    }
}

/// The settings file's tables from JSON (`{"ssl": {...}, "iasm": {...}, "array": ...}`),
/// through the settings file's own parser and checks.
fn settings(json: &str) -> Result<Settings> {
    let value: serde_json::Value = serde_json::from_str(json).context("settings")?;
    let table = toml::Value::try_from(value).map_err(|e| anyhow!("settings: {e}"))?;
    let text = toml::to_string(&table).map_err(|e| anyhow!("settings: {e}"))?;
    let s = Settings::from_toml(&text)?;
    s.validate()?;
    Ok(s)
}

/// The array: `positions` (`(M, 3)`, m) when given, else the preset or file `spec`.
fn mic_array(spec: &str, positions: Option<PyReadonlyArray2<'_, f64>>) -> Result<ssl::MicArray> {
    match positions {
        Some(p) => {
            let p = p.as_array();
            let rows: Vec<[f64; 3]> = p.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
            Ok(ssl::MicArray::new("array", rows)?)
        }
        None => Ok(ssl::MicArray::from_spec(spec)?),
    }
}

/// A recording from an `(M, samples)` array (validated by the Python layer).
fn audio(signals: &PyReadonlyArray2<'_, f32>, fs: u32) -> Result<ssl::Audio> {
    let (m, n) = signals.as_array().dim();
    // The CLI's bound on a WAV, before the channels are copied.
    ssl::audio::check_length("the recording", m, n, fs)?;
    let channels: Vec<Vec<f32>> = signals
        .as_array()
        .rows()
        .into_iter()
        .map(|r| r.to_vec())
        .collect();
    Ok(ssl::Audio::new(fs, channels)?)
}

/// One recording's JSON row and, when asked, its pooled spectrum (azimuths and
/// elevations in degrees, values `(elevations, azimuths)`).
type Row<'py> = (
    String,
    Option<(
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray2<f32>>,
    )>,
);

/// A localizer planned once for a sample rate, an array and the `[ssl]` settings (the
/// STFT, the grid, the steering and lag tables), as `iasm ssl` plans one per sample rate
/// and keeps it for every recording; `iasm.locate` keeps the last few it used.
#[pyclass(module = "iasm._iasm")]
struct Localizer {
    loc: ssl::Localizer,
    scratch: ssl::Scratch,
}

impl Localizer {
    /// The row's JSON (the CLI's fields) and the spectrum as numpy arrays.
    fn answer<'py>(
        py: Python<'py>,
        row: &ssl::Located,
        microphones: usize,
        spectrum: Option<ssl::AngularSpectrum>,
    ) -> PyResult<Row<'py>> {
        let report = serde_json::json!({
            "doas": row.doas,
            "extra": row.extra,
            "cut": row.cut,
            "pooling": row.pooling,
            "faulty_channels": iasm::pipeline::FaultyChannel::of(row, microphones),
        });
        let spec = match spectrum {
            None => None,
            Some(sp) => {
                let g = sp.grid();
                let (ne, na) = (g.elevations().len(), g.azimuths().len());
                let values = PyArray1::from_vec(py, sp.values().to_vec()).reshape([ne, na])?;
                Some((
                    PyArray1::from_vec(py, g.azimuths().to_vec()),
                    PyArray1::from_vec(py, g.elevations().to_vec()),
                    values,
                ))
            }
        };
        Ok((report.to_string(), spec))
    }
}

#[pymethods]
impl Localizer {
    #[new]
    #[pyo3(signature = (fs, array, positions, settings_json))]
    fn new(
        fs: u32,
        array: &str,
        positions: Option<PyReadonlyArray2<'_, f64>>,
        settings_json: &str,
    ) -> PyResult<Self> {
        let array = mic_array(array, positions).map_err(py_err)?;
        let s = settings(settings_json).map_err(py_err)?;
        let loc = iasm::pipeline::localizer(&array, fs, &s.ssl, None).map_err(py_err)?;
        Ok(Self {
            loc,
            scratch: ssl::Scratch::default(),
        })
    }

    /// Localises one recording (`(M, samples)` float32), as `iasm ssl` does: its row as
    /// the CLI's JSON, and the pooled spectrum when `spectrum`.
    fn locate<'py>(
        &mut self,
        py: Python<'py>,
        signals: PyReadonlyArray2<'py, f32>,
        spectrum: bool,
    ) -> PyResult<Row<'py>> {
        let fs = self.loc.sample_rate();
        let audio = audio(&signals, fs).map_err(py_err)?;
        let (loc, scratch) = (&self.loc, &mut self.scratch);
        let (row, sp) = py
            .detach(|| -> Result<_> {
                let row = loc.locate_row_with_scratch(&audio, scratch)?;
                let sp = spectrum
                    .then(|| loc.spectrum_with_scratch(&audio, scratch))
                    .transpose()?;
                Ok((row, sp))
            })
            .map_err(py_err)?;
        Self::answer(py, &row, self.loc.array().len(), sp)
    }

    /// Localises an STFT computed elsewhere (pyroomacoustics' `X`, as `iasm.doa` takes
    /// it): `frames` is `(frames, M, nfft / 2 + 1)`, complex64, and the settings'
    /// `frame_len` is the FFT's length. The row's JSON and the pooled spectrum.
    fn locate_stft<'py>(
        &mut self,
        py: Python<'py>,
        frames: PyReadonlyArray3<'py, Complex32>,
    ) -> PyResult<Row<'py>> {
        let [nt, nm, nb] = [frames.shape()[0], frames.shape()[1], frames.shape()[2]];
        let data: Vec<Complex32> = match frames.as_slice() {
            Ok(d) => d.to_vec(),
            Err(_) => frames.as_array().iter().copied().collect(),
        };
        let (loc, scratch) = (&self.loc, &mut self.scratch);
        let (row, sp) = py
            .detach(|| -> Result<_> {
                let spec = ssl::Spectrogram::from_frames(nt, nm, 0..nb, data)?;
                Ok(loc.locate_spectrogram(&spec, scratch)?)
            })
            .map_err(py_err)?;
        Self::answer(py, &row, self.loc.array().len(), Some(sp))
    }
}

/// The occupancy map: a map file (YAML), an `(H, W)` grid of ROS occupancy values (0 free,
/// 100 occupied, -1 unknown; row 0 at `origin`'s y), or with neither, the region within
/// the CLI's margin of the stops (`iasm map` without `--map`).
fn occupancy(
    yaml: Option<PathBuf>,
    grid: Option<PyReadonlyArray2<'_, i8>>,
    resolution: f64,
    origin: [f64; 2],
    poses: &[Pose],
) -> Result<OccupancyMap> {
    if let Some(path) = yaml {
        return iasm::dataset::load_map(&path);
    }
    if let Some(g) = grid {
        let g = g.as_array();
        let (h, w) = g.dim();
        // The CLI's checks of a map file, before any cell is built.
        asm::map::check_grid(w, h, resolution, origin)?;
        let cells: Vec<Cell> = g
            .iter()
            .map(|&v| match v {
                0..=49 => Cell::Free,
                50..=100 => Cell::Occupied,
                _ => Cell::Unknown,
            })
            .collect();
        return Ok(OccupancyMap::new(w, h, resolution, origin, cells));
    }
    let stops: Vec<[f64; 2]> = poses.iter().map(|p| [p.x, p.y]).collect();
    Ok(OccupancyMap::open_around(
        &stops,
        iasm::pipeline::OPEN_MARGIN_M,
        iasm::pipeline::OPEN_RESOLUTION_M,
    )?)
}

/// An occupancy map as the Python layer passes it: a map file, or a grid with its
/// resolution (m) and origin (m), or neither (see [`occupancy`]).
type MapSpec<'py> = (
    Option<PathBuf>,
    Option<PyReadonlyArray2<'py, i8>>,
    f64,
    [f64; 2],
);

/// `(K, 3)` poses (x, y in m, heading in rad).
fn poses(p: &PyReadonlyArray2<'_, f64>) -> Vec<Pose> {
    p.as_array()
        .rows()
        .into_iter()
        .map(|r| Pose::new(r[0], r[1], r[2]))
        .collect()
}

/// The map JSON of a mapper's result, as `iasm map` writes its sources, refusals and counts;
/// each source with its `signature` when `signatures` holds one.
fn map_json(
    r: &asm::MapResult,
    seed: u64,
    warnings: &[String],
    signatures: &[Option<ssl::signature::Signature>],
) -> String {
    let mut sources = serde_json::to_value(&r.sources).unwrap_or_default();
    if let Some(list) = sources.as_array_mut() {
        for (s, sig) in list.iter_mut().zip(signatures) {
            if let (Some(obj), Some(sig)) = (s.as_object_mut(), sig) {
                obj.insert(
                    "signature".to_owned(),
                    serde_json::to_value(sig).unwrap_or_default(),
                );
            }
        }
    }
    serde_json::json!({
        "warnings": warnings,
        "seed": seed,
        "rounds": r.rounds,
        "particles": r.particles,
        "unexplained_doas": r.unexplained,
        "removed_sources": r.removed,
        "refused": r.refused,
        "sources": sources,
    })
    .to_string()
}

/// Maps the sources of a survey (see `iasm.map_sources`); returns the map as JSON.
#[pyfunction]
#[pyo3(signature = (poses_xyt, doas_deg, cut, map, settings_json, seed, recordings=None, fs=0, array_spec="iasm6", positions=None))]
#[allow(clippy::too_many_arguments)]
fn map_sources(
    py: Python<'_>,
    poses_xyt: PyReadonlyArray2<'_, f64>,
    doas_deg: Vec<Vec<f64>>,
    cut: Option<Vec<bool>>,
    map: MapSpec<'_>,
    settings_json: &str,
    seed: u64,
    recordings: Option<Vec<PyReadonlyArray2<'_, f32>>>,
    fs: u32,
    array_spec: &str,
    positions: Option<PyReadonlyArray2<'_, f64>>,
) -> PyResult<String> {
    let poses = poses(&poses_xyt);
    let s = settings(settings_json).map_err(py_err)?;
    let (map_yaml, grid, resolution, origin) = map;
    let map = occupancy(map_yaml, grid, resolution, origin, &poses).map_err(py_err)?;
    // The recordings, when given, for each source's signature (copied while the GIL is
    // held; the mapping and the beams then run without it).
    let heard = match recordings {
        None => None,
        Some(recs) => {
            if recs.len() != poses.len() {
                return Err(PyValueError::new_err(format!(
                    "recordings: {} for {} stops; they must match one to one",
                    recs.len(),
                    poses.len()
                )));
            }
            let audio: Vec<ssl::Audio> = recs
                .iter()
                .enumerate()
                .map(|(k, r)| audio(r, fs).with_context(|| format!("recordings[{k}]")))
                .collect::<Result<_>>()
                .map_err(py_err)?;
            Some((audio, mic_array(array_spec, positions).map_err(py_err)?))
        }
    };
    py.detach(|| -> Result<String> {
        let mapper = asm::Mapper::new(&map, &s.iasm)?;
        let rad: Vec<Vec<f64>> = doas_deg
            .iter()
            .map(|r| r.iter().map(|a| a.to_radians()).collect())
            .collect();
        let r = mapper.run_rows(
            &poses,
            &rad,
            cut.as_deref(),
            &mut MapRng::seed_from_u64(seed),
        )?;
        let warnings = iasm::pipeline::map_warnings(&map, &poses, &s.iasm, &r);
        let signatures = match &heard {
            Some((audio, array)) => {
                iasm::pipeline::signatures(&r, &poses, array, &|k| Ok(audio[k].clone()))?
            }
            None => Vec::new(),
        };
        Ok(map_json(&r, seed, &warnings, &signatures))
    })
    .map_err(py_err)
}

/// The stop-by-stop mapper (see `iasm.OnlineMapper`).
#[pyclass(module = "iasm._iasm")]
struct OnlineMapper {
    inner: asm::OnlineMapper,
    seed: u64,
}

#[pymethods]
impl OnlineMapper {
    #[new]
    #[pyo3(signature = (map, settings_json, seed))]
    fn new(map: MapSpec<'_>, settings_json: &str, seed: u64) -> PyResult<Self> {
        let s = settings(settings_json).map_err(py_err)?;
        let (map_yaml, grid, resolution, origin) = map;
        if map_yaml.is_none() && grid.is_none() {
            return Err(PyValueError::new_err(
                "the online mapper needs an occupancy map (a map file or a grid): its stops are not known in advance",
            ));
        }
        let map = occupancy(map_yaml, grid, resolution, origin, &[]).map_err(py_err)?;
        let mapper = asm::Mapper::new(&map, &s.iasm)
            .map_err(anyhow::Error::from)
            .map_err(py_err)?;
        Ok(Self {
            inner: asm::OnlineMapper::new(mapper, seed),
            seed,
        })
    }

    /// Adds one stop; returns what it changed, as JSON.
    #[pyo3(signature = (x, y, theta, doas_deg, cut=None))]
    fn add_stop(
        &mut self,
        py: Python<'_>,
        x: f64,
        y: f64,
        theta: f64,
        doas_deg: Vec<f64>,
        cut: Option<bool>,
    ) -> PyResult<String> {
        let rad: Vec<f64> = doas_deg.iter().map(|a| a.to_radians()).collect();
        let inner = &mut self.inner;
        let u = py
            .detach(|| inner.add_row(Pose::new(x, y, theta), &rad, cut))
            .map_err(anyhow::Error::from)
            .map_err(py_err)?;
        Ok(serde_json::json!({
            "stop": u.stop,
            "associated": u.associated,
            "found": u.found,
            "rounds": u.rounds,
            "sources": u.sources,
            "full": u.full,
            "adopted": u.full_ms.is_some(),
        })
        .to_string())
    }

    /// The map after the stops so far, as JSON.
    fn map(&self) -> String {
        map_json(&self.inner.map(), self.seed, &[], &[])
    }

    /// Replaces the map with the batch map over every stop so far; returns its rounds.
    fn consolidate(&mut self, py: Python<'_>) -> usize {
        let inner = &mut self.inner;
        py.detach(|| inner.consolidate())
    }

    /// Stops taken so far.
    fn stops(&self) -> usize {
        self.inner.stops()
    }
}

/// OSPA (Schuhmacher et al. 2008) between `estimate` and `truth` (`(n, 2)`, m), cutoff
/// `c` (m), order `p`: total, localisation and cardinality parts.
#[pyfunction]
fn ospa(
    estimate: PyReadonlyArray2<'_, f64>,
    truth: PyReadonlyArray2<'_, f64>,
    c: f64,
    p: f64,
) -> PyResult<(f64, f64, f64)> {
    let pts = |a: &PyReadonlyArray2<'_, f64>| -> Vec<[f64; 2]> {
        a.as_array()
            .rows()
            .into_iter()
            .map(|r| [r[0], r[1]])
            .collect()
    };
    asm::ospa::check_params(c, p).map_err(PyValueError::new_err)?;
    let o = asm::ospa::ospa(&pts(&estimate), &pts(&truth), c, p);
    Ok((o.total, o.localization, o.cardinality))
}

/// Refuses a recording of `channels` x `samples` at `fs` Hz longer than one localisation
/// takes, as the CLI refuses such a WAV: `MemoryError`, before the Python layer copies it.
#[pyfunction]
fn check_recording(channels: usize, samples: usize, fs: u32) -> PyResult<()> {
    ssl::audio::check_length("the recording", channels, samples, fs).map_err(|e| py_err(e.into()))
}

/// A rendered scene: per stop the audio (`(M, samples)`, float32), and the scene's poses,
/// truth, array, sample rate and occupancy grid.
type Rendered<'py> = (
    u32,
    Vec<Bound<'py, PyArray2<f32>>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    (Bound<'py, PyArray2<i8>>, f64, [f64; 2]),
    String,
);

/// Renders a scene (see `iasm.simulate`): a scene file, or a scene's TOML text with `base`
/// the folder its relative paths are read from; writes it as a data set folder to `out`
/// when given.
#[pyfunction]
#[pyo3(signature = (path, text, base, out))]
fn simulate<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    text: Option<String>,
    base: PathBuf,
    out: Option<PathBuf>,
) -> PyResult<Rendered<'py>> {
    let sim = py
        .detach(|| -> Result<iasm::pipeline::Simulated> {
            let (prepared, name) = match (&path, &text) {
                (Some(p), _) => (
                    iasm::scenes::load_scene(p)?.0,
                    p.file_stem()
                        .map(|s| s.to_string_lossy().into_owned())
                        .unwrap_or_default(),
                ),
                (None, Some(t)) => {
                    let (mut scene, _) = iasm::scenes::parse_scene(t)?;
                    scene.resolve_paths(&base);
                    (iasm::scenes::prepare(scene)?, "scene".to_owned())
                }
                (None, None) => anyhow::bail!("a scene file or a scene's text"),
            };
            if let Some(out) = &out {
                iasm::scenes::write_dataset(&prepared, out)
                    .with_context(|| format!("writing {}", out.display()))?;
            }
            iasm::pipeline::Simulated::render(prepared, name)
        })
        .map_err(py_err)?;
    let fs = sim.audio.first().map_or(0, ssl::Audio::sample_rate);
    let audio = sim
        .audio
        .iter()
        .map(|a| {
            let rows: Vec<Vec<f32>> = a.channels().to_vec();
            PyArray2::from_vec2(py, &rows).map_err(|e| PyValueError::new_err(e.to_string()))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let poses: Vec<Vec<f64>> = sim
        .poses()
        .iter()
        .map(|p| vec![p.x, p.y, p.theta])
        .collect();
    let truth: Vec<Vec<f64>> = sim.truth.iter().map(|t| t.to_vec()).collect();
    let mics: Vec<Vec<f64>> = sim.array.positions().iter().map(|p| p.to_vec()).collect();
    let m = &sim.map;
    let cells: Vec<i8> = (0..m.height())
        .flat_map(|j| (0..m.width()).map(move |i| (i, j)))
        .map(|(i, j)| match m.cell(i, j) {
            Cell::Free => 0,
            Cell::Occupied => 100,
            Cell::Unknown => -1,
        })
        .collect();
    let grid = PyArray1::from_vec(py, cells).reshape([m.height(), m.width()])?;
    let v2 = |v: &[Vec<f64>], cols: usize| -> PyResult<Bound<'py, PyArray2<f64>>> {
        if v.is_empty() {
            return PyArray1::from_vec(py, Vec::new()).reshape([0, cols]);
        }
        PyArray2::from_vec2(py, v).map_err(|e| PyValueError::new_err(e.to_string()))
    };
    Ok((
        fs,
        audio,
        v2(&poses, 3)?,
        v2(&truth, 2)?,
        v2(&mics, 3)?,
        (grid, m.resolution(), m.origin()),
        sim.name.clone(),
    ))
}

/// Reads a WAV file as the CLI does: `(M, samples)` float32 and the sample rate.
#[pyfunction]
fn read_wav<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyArray2<f32>>, u32)> {
    if !path.exists() {
        return Err(PyFileNotFoundError::new_err(format!(
            "{}: no such file",
            path.display()
        )));
    }
    let a = ssl::read_wav(Path::new(&path))
        .map_err(anyhow::Error::from)
        .map_err(py_err)?;
    let rows: Vec<Vec<f32>> = a.channels().to_vec();
    let arr = PyArray2::from_vec2(py, &rows).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((arr, a.sample_rate()))
}

/// A data set folder as `iasm map --dataset` reads it: its recordings (natural order), its
/// poses (`(K, 3)`; theta in radians, or in degrees when `theta_degrees`), its ground
/// truth (`(S, 2)`) and occupancy map file when it has them, and its DoA tables.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn read_dataset<'py>(
    py: Python<'py>,
    root: PathBuf,
    theta_degrees: bool,
) -> PyResult<(
    Vec<PathBuf>,
    Option<Bound<'py, PyArray2<f64>>>,
    Option<Bound<'py, PyArray2<f64>>>,
    Option<PathBuf>,
    Vec<PathBuf>,
)> {
    if !root.is_dir() {
        return Err(PyFileNotFoundError::new_err(format!(
            "{}: no such folder",
            root.display()
        )));
    }
    let (ds, poses, truth, map) = (|| -> Result<_> {
        let ds = iasm::dataset::Dataset::open(&root)?;
        let poses = ds
            .poses
            .as_deref()
            .map(|p| iasm::dataset::read_poses(p, !theta_degrees))
            .transpose()?;
        let truth = ds
            .sources
            .as_deref()
            .map(iasm::dataset::read_sources)
            .transpose()?;
        let map = if ds.root.join("map").is_dir() {
            Some(iasm::dataset::first_with_ext(&ds.root.join("map"), "yaml")?)
        } else {
            None
        };
        Ok((ds, poses, truth, map))
    })()
    .map_err(py_err)?;
    let to2 = |rows: Vec<Vec<f64>>| -> PyResult<Bound<'py, PyArray2<f64>>> {
        PyArray2::from_vec2(py, &rows).map_err(|e| PyValueError::new_err(e.to_string()))
    };
    let poses = poses
        .map(|p| to2(p.iter().map(|p| vec![p.x, p.y, p.theta]).collect()))
        .transpose()?;
    let truth = truth
        .map(|t| to2(t.iter().map(|t| t.to_vec()).collect()))
        .transpose()?;
    Ok((ds.audio, poses, truth, map, ds.doa_tables))
}

/// The extension module.
#[pymodule]
fn _iasm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(map_sources, m)?)?;
    m.add_function(wrap_pyfunction!(ospa, m)?)?;
    m.add_function(wrap_pyfunction!(check_recording, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(read_wav, m)?)?;
    m.add_function(wrap_pyfunction!(read_dataset, m)?)?;
    m.add_class::<OnlineMapper>()?;
    m.add_class::<Localizer>()?;
    m.add("ARRAY_PRESETS", ssl::array::PRESETS.to_vec())?;
    // The crates' version, which the wheel's metadata and `iasm --version` also carry.
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
