"""iasm for Python: sound source localisation, I-ASM mapping, room simulation and OSPA
on numpy arrays.

The same library code as the ``iasm`` command line runs underneath (the Rust crates
``iasm-ssl``, ``iasm-asm``, ``iasm-sim`` and the app's pipeline), so a recording gives the
same DoAs here as ``iasm ssl`` gives, and a survey the same map as ``iasm map`` for the
same seed. Settings are the settings file's (``[ssl]`` and ``[iasm]``): keyword arguments
or a dict with the same names, checked by the same code, refused with the same messages.

Errors are Python exceptions: ``ValueError`` for a value refused (the CLI's message),
``FileNotFoundError`` for a missing file, ``TypeError`` for an argument of the wrong type.
The GIL is released while the work runs, so threads localise recordings in parallel.

Conventions: angles in degrees at the edges (azimuth counter-clockwise from the array's
``x`` axis, the robot's heading, wrapped to ``[-180, 180)``; elevation above the array's
plane); positions in metres; a pose is ``(x, y, theta)`` with ``theta`` in radians, as the
data sets' pose tables hold it.
"""

from __future__ import annotations

import json
import os
import threading
import warnings
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _iasm

__all__ = [
    "__version__",
    "ARRAY_PRESETS",
    "Doa",
    "Located",
    "Spectrum",
    "Ospa",
    "Scene",
    "OnlineMapper",
    "locate",
    "locate_row",
    "angular_spectrum",
    "map_sources",
    "map_runs",
    "ospa",
    "simulate",
    "read_wav",
    "read_dataset",
    "Dataset",
    "doa",
]

#: The package's version: the Rust crates' it was built from (as ``iasm --version`` says).
__version__: str = _iasm.__version__


def __dir__() -> List[str]:
    """The public API only (``__all__``), not the modules and typing names it is built on."""
    return sorted(__all__)


#: The array presets ``array=`` takes by name (``iasm6``: the paper's six microphones).
ARRAY_PRESETS: Tuple[str, ...] = tuple(_iasm.ARRAY_PRESETS)


@dataclass(frozen=True)
class Doa:
    """One direction of arrival, as ``iasm ssl --json`` reports it.

    ``azimuth`` and ``elevation`` in degrees (array frame); ``strength`` the pooled
    spectrum's value there; ``relative`` its height over the spectrum's median;
    ``dominant_blocks`` the blocks whose strongest direction it was; ``prominence`` and
    ``significance`` what the SSL's peak rules measured.
    """

    azimuth: float
    elevation: float
    strength: float
    relative: float = float("nan")
    dominant_blocks: int = 0
    prominence: float = float("nan")
    significance: float = float("nan")

    @classmethod
    def _of(cls, d: Mapping[str, Any]) -> "Doa":
        return cls(
            azimuth=d["azimuth_deg"],
            elevation=d["elevation_deg"],
            strength=d["strength"],
            relative=d.get("relative", float("nan")),
            dominant_blocks=d.get("dominant_blocks", 0),
            prominence=d.get("prominence", float("nan")),
            significance=d.get("significance", float("nan")),
        )


@dataclass(frozen=True)
class Located:
    """One recording's row: its DoAs (strongest first, at most N), whether N cut it (a
    further peak passed the SSL's thresholds), the directions beyond N its octaves heard
    (``extra``, in a cut row), how its blocks were pooled, and the channels found not to
    hear the room."""

    doas: List[Doa]
    cut: bool
    extra: List[Doa]
    pooling: str
    faulty_channels: List[Dict[str, Any]]


@dataclass(frozen=True)
class Spectrum:
    """A pooled angular spectrum: ``values[e, a]`` at elevation ``elevation[e]`` and
    azimuth ``azimuth[a]`` (degrees)."""

    azimuth: np.ndarray
    elevation: np.ndarray
    values: np.ndarray


@dataclass(frozen=True)
class Ospa:
    """OSPA distance (m) and its localisation and cardinality parts."""

    total: float
    localisation: float
    cardinality: float


@dataclass(frozen=True)
class Scene:
    """A rendered scene: ``signals[k]`` is stop ``k``'s recording, ``(M, samples)``
    float32 at ``fs`` Hz; ``poses`` ``(K, 3)`` (x, y, theta); ``truth`` ``(S, 2)`` the
    room's sources; ``array`` ``(M, 3)`` the microphones; ``grid`` the occupancy map
    (ROS values: 0 free, 100 occupied, -1 unknown; row 0 at ``origin``'s y) with its
    ``resolution`` (m) and ``origin`` (m)."""

    name: str
    fs: int
    signals: List[np.ndarray]
    poses: np.ndarray
    truth: np.ndarray
    array: np.ndarray
    grid: np.ndarray
    resolution: float
    origin: Tuple[float, float]


@dataclass(frozen=True)
class Dataset:
    """A data set folder as ``iasm map --dataset`` reads it: its recordings (in natural
    order), its poses ``(K, 3)`` (x, y in m, theta in rad) and ground truth ``(S, 2)``
    when it has them, its occupancy map file (YAML) and its DoA tables."""

    root: str
    recordings: List[str]
    poses: Optional[np.ndarray]
    truth: Optional[np.ndarray]
    map: Optional[str]
    doa_tables: List[str]


ArrayLike = Union[np.ndarray, Sequence[Any]]


def _signals(signals: ArrayLike, fs: int) -> np.ndarray:
    """``(M, samples)`` float32: a float32 array as it is (no copy), a float64 one cast."""
    a = signals if isinstance(signals, np.ndarray) else np.asarray(signals)
    if a.dtype.kind != "f":
        raise TypeError(
            f"signals must be a float32 or float64 array (samples in [-1, 1]), got dtype {a.dtype}"
        )
    if a.ndim != 2:
        raise ValueError(
            f"signals must have the shape (microphones, samples), got shape {a.shape}"
        )
    # The CLI's bound on a recording (MemoryError beyond it), before anything is copied.
    _iasm.check_recording(a.shape[0], a.shape[1], fs)
    if a.dtype != np.float32:
        a = a.astype(np.float32)
    bad = ~np.isfinite(a)
    if bad.any():
        ch, s = np.argwhere(bad)[0]
        raise ValueError(
            f"signals: channel {ch + 1} holds a non-finite sample ({a[ch, s]}) at sample {s}"
        )
    return a


def _fs(fs: Any) -> int:
    if isinstance(fs, bool) or not float(fs).is_integer() or fs <= 0:
        raise ValueError(f"fs must be a positive whole number of hertz, got {fs!r}")
    return int(fs)


def _array(array: Union[str, os.PathLike, ArrayLike, None]) -> Tuple[str, Optional[np.ndarray]]:
    if array is None:
        return "iasm6", None
    if isinstance(array, (str, os.PathLike)):
        return os.fspath(array), None
    p = np.asarray(array, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(
            f"array positions must have the shape (microphones, 3) in metres, got shape {p.shape}"
        )
    if not np.isfinite(p).all():
        raise ValueError("array positions must be finite")
    return "array", np.ascontiguousarray(p)


def _table(settings: Optional[Mapping[str, Any]], extra: Mapping[str, Any]) -> Dict[str, Any]:
    out: Dict[str, Any] = dict(settings or {})
    out.update({k: v for k, v in extra.items() if v is not None})
    return out


def _json(obj: Any) -> str:
    def default(o: Any) -> Any:
        if isinstance(o, np.generic):
            return o.item()
        if isinstance(o, np.ndarray):
            return o.tolist()
        if isinstance(o, os.PathLike):
            return os.fspath(o)
        raise TypeError(f"a setting of type {type(o).__name__} ({o!r})")

    return json.dumps(obj, default=default, allow_nan=False)


def _ssl_settings(method: str, num: int, settings: Optional[Mapping[str, Any]], kw: Mapping[str, Any]) -> str:
    ssl = _table(settings, kw)
    ssl.setdefault("method", method)
    ssl.setdefault("num_peaks", num)
    return _json({"ssl": ssl})


def locate_row(
    signals: ArrayLike,
    fs: int,
    array: Union[str, os.PathLike, ArrayLike, None] = "iasm6",
    method: str = "mvdr",
    num: int = 4,
    *,
    settings: Optional[Mapping[str, Any]] = None,
    **ssl_settings: Any,
) -> Located:
    """:func:`locate`, with the whole row the SSL gives (see :class:`Located`)."""
    row, _ = _locate(signals, fs, array, method, num, settings, ssl_settings, False)
    return row


class _Planned:
    """A planned localizer and the lock of its working memory."""

    def __init__(self, obj: Any) -> None:
        self.obj = obj
        self._lock = threading.Lock()


# The localizers planned most recently, by sample rate, array and settings: planning (the
# STFT, the grid, the steering tables) costs as much as localising a short recording, and
# `iasm ssl` plans once per sample rate too.
_PLANNED: "OrderedDict[tuple, Any]" = OrderedDict()
_PLANNED_KEEP = 8
_PLANNED_LOCK = threading.Lock()


def _localizer(fs: int, spec: str, positions: Optional[np.ndarray], settings_json: str):
    key = (fs, spec, None if positions is None else positions.tobytes(), settings_json)
    with _PLANNED_LOCK:
        loc = _PLANNED.pop(key, None)
    if loc is None:
        loc = _Planned(_iasm.Localizer(fs, spec, positions, settings_json))
    with _PLANNED_LOCK:
        _PLANNED[key] = loc
        while len(_PLANNED) > _PLANNED_KEEP:
            _PLANNED.popitem(last=False)
    return loc


def _locate(signals, fs, array, method, num, settings, kw, spectrum):
    spec, positions = _array(array)
    fs = _fs(fs)
    x = _signals(signals, fs)
    settings_json = _ssl_settings(method, num, settings, kw)
    loc = _localizer(fs, spec, positions, settings_json)
    # A localizer keeps working memory: one thread at a time uses it, others plan their own.
    if loc._lock.acquire(blocking=False):
        try:
            text, sp = loc.obj.locate(x, spectrum)
        finally:
            loc._lock.release()
    else:
        text, sp = _iasm.Localizer(fs, spec, positions, settings_json).locate(x, spectrum)
    r = json.loads(text)
    row = Located(
        doas=[Doa._of(d) for d in r["doas"]],
        cut=r["cut"],
        extra=[Doa._of(d) for d in r["extra"]],
        pooling=r["pooling"],
        faulty_channels=r["faulty_channels"],
    )
    return row, (Spectrum(*sp) if sp is not None else None)


def locate(
    signals: ArrayLike,
    fs: int,
    array: Union[str, os.PathLike, ArrayLike, None] = "iasm6",
    method: str = "mvdr",
    num: int = 4,
    *,
    spectrum: bool = False,
    settings: Optional[Mapping[str, Any]] = None,
    **ssl_settings: Any,
):
    """The ranked DoAs of one recording, as ``iasm ssl`` finds them.

    ``signals``: ``(M, samples)`` float32 or float64 (float32 is read in place), channel
    ``i`` microphone ``i``. ``array``: a preset name (:data:`ARRAY_PRESETS`), an array file
    (TOML or JSON, as ``--array`` takes), or ``(M, 3)`` positions in metres (array frame:
    ``x`` the robot's heading, ``z`` up). ``method``: ``gcc-phat``, ``mvdr``, ``srp-phat``,
    ``music`` or ``normmusic``. ``num``: N, the most DoAs returned. Any ``[ssl]`` setting
    of the settings file by its name, as a keyword or in ``settings`` (``fmin_hz=300``,
    ``pooling="mean"``, ...).

    Returns a list of :class:`Doa`, strongest first; with ``spectrum=True``, a pair
    ``(doas, Spectrum)`` whose spectrum is the pooled angular spectrum on its grid.
    """
    row, sp = _locate(signals, fs, array, method, num, settings, ssl_settings, spectrum)
    return (row.doas, sp) if spectrum else row.doas


def angular_spectrum(
    signals: ArrayLike,
    fs: int,
    array: Union[str, os.PathLike, ArrayLike, None] = "iasm6",
    method: str = "mvdr",
    *,
    settings: Optional[Mapping[str, Any]] = None,
    **ssl_settings: Any,
) -> Spectrum:
    """The pooled angular spectrum of one recording on the SSL's grid (see :func:`locate`)."""
    _, sp = _locate(signals, fs, array, method, 4, settings, ssl_settings, True)
    return sp


def _poses(poses: ArrayLike) -> np.ndarray:
    p = np.ascontiguousarray(np.asarray(poses, dtype=np.float64))
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"poses must have the shape (stops, 3): x, y (m), theta (rad); got shape {p.shape}")
    return p


def _rows(doas: Union[ArrayLike, Sequence[ArrayLike]], stops: int) -> List[List[float]]:
    if isinstance(doas, np.ndarray) and doas.ndim == 2:
        rows = [list(map(float, r)) for r in doas]
    elif isinstance(doas, np.ndarray) and doas.ndim == 1 and doas.dtype != object:
        raise ValueError("doas must be one row per stop: a list of arrays, or a (stops, N) array with NaN for none")
    else:
        rows = [list(map(float, np.atleast_1d(np.asarray(r, dtype=np.float64)))) for r in doas]
    if len(rows) != stops:
        raise ValueError(f"doas has {len(rows)} rows for {stops} poses: one row of DoAs per stop")
    # NaN marks an empty cell, as a table's missing value: the row is its DoAs, as the CLI
    # reads a table.
    return [[a for a in r if a == a] for r in rows]


def _map_args(map: Any, resolution: Optional[float], origin: Optional[Sequence[float]]):
    """The map as the extension takes it: (yaml path, grid, resolution, origin)."""
    if map is None:
        return None, None, 0.05, [0.0, 0.0]
    if isinstance(map, (str, os.PathLike)):
        return os.fspath(map), None, 0.05, [0.0, 0.0]
    g = np.asarray(map)
    if g.ndim != 2:
        raise ValueError(f"an occupancy grid must be 2-D (rows, columns), got shape {g.shape}")
    if resolution is None or origin is None:
        raise ValueError("an occupancy grid needs its resolution (m per cell) and origin (x, y of cell (0, 0), m)")
    return None, np.ascontiguousarray(g, dtype=np.int8), float(resolution), [float(origin[0]), float(origin[1])]


def map_sources(
    poses: ArrayLike,
    doas: Union[ArrayLike, Sequence[ArrayLike]],
    map: Union[str, os.PathLike, ArrayLike, None] = None,
    *,
    resolution: Optional[float] = None,
    origin: Optional[Sequence[float]] = None,
    cut: Optional[Sequence[bool]] = None,
    seed: int = 0,
    num: Optional[int] = None,
    settings: Optional[Mapping[str, Any]] = None,
    recordings: Optional[Sequence[ArrayLike]] = None,
    fs: Optional[int] = None,
    array: Union[str, os.PathLike, ArrayLike, None] = None,
    **iasm_settings: Any,
) -> Dict[str, Any]:
    """Maps the sources that a survey's DoAs show, with I-ASM, as ``iasm map`` does.

    ``poses``: ``(K, 3)`` (x, y in m, theta in rad). ``doas``: each stop's DoAs (azimuths
    in degrees, array frame, strongest first): a list of arrays, or a ``(K, N)`` array
    with NaN for none. ``map``: an occupancy map file (the YAML of a ROS map), a grid
    of ROS values (0 free, 100 occupied, -1 unknown; with ``resolution`` and ``origin``),
    or ``None`` for the region within 3 m of the stops. ``cut``: per stop, whether the
    SSL cut the row at N (:attr:`Located.cut`); ``None`` for a table. ``num``: N (the
    settings' default, 4, when not given). Any ``[iasm]`` setting by its name.

    Returns the map as ``iasm map``'s JSON holds it: ``sources`` (each with ``x``, ``y``,
    ``covariance``, ``observations``, ..., and when it was heard: ``first_stop``,
    ``last_stop``, ``heard_stops``, ``heard_share``, ``state`` (``"active"`` or
    ``"silent"`` with ``since``), ``appeared_at``, ``moved_to``, ``moved_from`` where
    they apply), ``refused`` (with the rule), ``rounds``, ``unexplained_doas``, ...

    With ``recordings`` (each stop's ``(M, samples)`` recording at ``fs`` Hz, heard by
    ``array``: a preset name, an array file, or ``(M, 3)`` positions; the paper's array when
    not given), each source also says what it sounds like, as ``iasm map --signatures``:
    ``signature`` with ``kind`` (``"speech"``, ``"tonal"`` or ``"broadband"``),
    ``level_db`` (0 for the loudest source), ``level_spread_db``, ``modulation``,
    ``fluctuation``, ``gap_db``, ``tonality``, ``band_hz``, ``spectrum_db`` (third-octave
    centres and levels) and ``stops``.
    """
    p = _poses(poses)
    rows = _rows(doas, len(p))
    table = _table(settings, iasm_settings)
    if num is not None:
        table["num_doas"] = num
    extra: Dict[str, Any] = {}
    if recordings is not None:
        if fs is None:
            raise ValueError("recordings need their sample rate: fs")
        rate = _fs(fs)
        spec, positions = _array(array)
        extra = dict(
            recordings=[_signals(r, rate) for r in recordings], fs=rate, array_spec=spec,
            positions=positions,
        )
    text = _iasm.map_sources(
        p, rows, None if cut is None else [bool(c) for c in cut], _map_args(map, resolution, origin),
        _json({"iasm": table}), int(seed), **extra,
    )
    m = json.loads(text)
    # What `iasm map` prints as warnings: some stops outside the map, particles thinned.
    for w in m.pop("warnings", []):
        warnings.warn(w, stacklevel=2)
    return m


class OnlineMapper:
    """The stop-by-stop mapper of ``iasm watch``: :meth:`add_stop` takes one stop at a
    time, :meth:`map` answers the map so far; :meth:`consolidate` runs the full map over
    every stop (at the last stop, the map :func:`map_sources` gives for the same seed).

    ``map`` (required: the stops are not known in advance), ``resolution``, ``origin``,
    ``num``, ``seed`` and the ``[iasm]`` settings as :func:`map_sources` takes them."""

    def __init__(
        self,
        map: Union[str, os.PathLike, ArrayLike],
        *,
        resolution: Optional[float] = None,
        origin: Optional[Sequence[float]] = None,
        seed: int = 0,
        num: Optional[int] = None,
        settings: Optional[Mapping[str, Any]] = None,
        **iasm_settings: Any,
    ) -> None:
        if map is None:
            raise ValueError("the online mapper needs an occupancy map (a map file or a grid)")
        table = _table(settings, iasm_settings)
        if num is not None:
            table["num_doas"] = num
        self._inner = _iasm.OnlineMapper(_map_args(map, resolution, origin), _json({"iasm": table}), int(seed))

    def add_stop(self, pose: ArrayLike, doas: ArrayLike, cut: Optional[bool] = None) -> Dict[str, Any]:
        """Adds one stop: its pose ``(x, y, theta)`` and DoAs (degrees, strongest first).
        Returns what it changed (``associated``, ``found``, ``rounds``, ``sources``;
        ``full``: it started the full map over every stop so far, which runs beside the
        next stops; ``adopted``: it took in the full map the stop before started)."""
        x, y, theta = (float(v) for v in np.asarray(pose, dtype=np.float64).reshape(3))
        row = [float(a) for a in np.atleast_1d(np.asarray(doas, dtype=np.float64))]
        return json.loads(self._inner.add_stop(x, y, theta, row, cut))

    def map(self) -> Dict[str, Any]:
        """The map after the stops so far (as :func:`map_sources` returns it)."""
        m = json.loads(self._inner.map())
        m.pop("warnings", None)
        return m

    def consolidate(self) -> int:
        """Replaces the map with the full map over every stop so far; returns its rounds."""
        return self._inner.consolidate()

    @property
    def stops(self) -> int:
        """Stops taken so far."""
        return self._inner.stops()


def ospa(estimate: ArrayLike, truth: ArrayLike, c: float = 1.0, p: float = 1.0) -> Ospa:
    """OSPA (Schuhmacher et al. 2008) between two sets of 2-D points (``(n, 2)``, m), with
    cutoff ``c`` (m) and order ``p``, as ``iasm eval`` scores maps."""

    def pts(a: ArrayLike, what: str) -> np.ndarray:
        x = np.asarray(a, dtype=np.float64)
        if x.size == 0:
            return np.zeros((0, 2))
        if x.ndim != 2 or x.shape[1] != 2:
            raise ValueError(f"{what} must have the shape (points, 2), got shape {x.shape}")
        if not np.isfinite(x).all():
            raise ValueError(f"{what} must be finite")
        return np.ascontiguousarray(x)

    return Ospa(*_iasm.ospa(pts(estimate, "estimate"), pts(truth, "truth"), float(c), float(p)))


def simulate(
    scene: Union[str, os.PathLike, Mapping[str, Any]],
    out: Union[str, os.PathLike, None] = None,
    *,
    base: Union[str, os.PathLike, None] = None,
) -> Scene:
    """Renders a scene as ``iasm simulate`` does (image sources; the robot carrying the
    array along its stops). ``scene``: a scene file (TOML), a scene's TOML text, or the
    same scene as a dict; relative paths in a text or a dict are read from ``base`` (the
    working folder when not given). With ``out``, also writes the data set folder
    ``iasm map --dataset`` reads. Returns the recordings and the scene's truth."""
    path = text = None
    if isinstance(scene, Mapping):
        text = _toml(scene)
    elif isinstance(scene, os.PathLike) or (isinstance(scene, str) and "\n" not in scene and "=" not in scene):
        path = os.fspath(scene)
    else:
        text = str(scene)
    name, fs, signals, poses, truth, array, (grid, res, origin) = _unpack(
        _iasm.simulate(path, text, os.fspath(base or os.getcwd()), None if out is None else os.fspath(out))
    )
    return Scene(name, fs, signals, poses, truth, array, grid, res, (origin[0], origin[1]))


def _unpack(t):
    fs, signals, poses, truth, array, grid, name = t
    return name, fs, signals, poses, truth, array, grid


def _toml(d: Mapping[str, Any], prefix: str = "") -> str:
    """A scene dict as TOML text (tables, arrays of tables, scalars and lists)."""

    def scalar(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float, np.integer, np.floating)):
            return repr(float(v)) if isinstance(v, (float, np.floating)) else str(int(v))
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, (list, tuple, np.ndarray)):
            return "[" + ", ".join(scalar(x) for x in v) + "]"
        if isinstance(v, Mapping):
            return "{" + ", ".join(f"{k} = {scalar(x)}" for k, x in v.items()) + "}"
        raise TypeError(f"a scene value of type {type(v).__name__} ({v!r})")

    lines: List[str] = []
    tables: List[str] = []
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, Mapping):
            tables.append(f"[{key}]\n" + _toml(v, key + "."))
        elif isinstance(v, (list, tuple)) and v and all(isinstance(x, Mapping) for x in v):
            for x in v:
                tables.append(f"[[{key}]]\n" + _toml(x, key + "."))
        else:
            lines.append(f"{k} = {scalar(v)}")
    return "\n".join(lines + [""] + tables)


def read_wav(path: Union[str, os.PathLike]) -> Tuple[np.ndarray, int]:
    """A WAV file as the CLI reads it: ``(M, samples)`` float32 in ``[-1, 1]``, and its
    sample rate."""
    return _iasm.read_wav(os.fspath(path))


def map_runs(
    runs: Sequence[Sequence[Any]],
    map: Union[str, os.PathLike, ArrayLike, None] = None,
    *,
    names: Optional[Sequence[str]] = None,
    resolution: Optional[float] = None,
    origin: Optional[Sequence[float]] = None,
    seed: int = 0,
    num: Optional[int] = None,
    settings: Optional[Mapping[str, Any]] = None,
    **iasm_settings: Any,
) -> Dict[str, Any]:
    """Maps several runs of one building as one survey, as ``iasm map --dataset A --dataset
    B`` does: several robots, or one robot's several runs, whose poses share the building's
    map frame. ``runs``: each run's ``(poses, doas)`` or ``(poses, doas, cut)``, as
    :func:`map_sources` takes them; their stops are mapped one run after the other (``cut``
    is used when every run gives it). ``map``: the building's map, as for
    :func:`map_sources`. ``names``: the runs' names (default ``run 1``, ``run 2``, ...).

    Returns :func:`map_sources`' map, with ``runs``: each run's ``name``, its
    ``first_stop`` in the union (counted from 1) and how many ``stops`` it has.
    """
    if len(runs) == 0:
        raise ValueError("map_runs needs at least one run: (poses, doas) or (poses, doas, cut)")
    if names is not None and len(names) != len(runs):
        raise ValueError(f"{len(names)} names for {len(runs)} runs")
    poses: List[np.ndarray] = []
    doas: List[List[float]] = []
    cuts: List[Optional[List[bool]]] = []
    for k, run in enumerate(runs):
        if len(run) not in (2, 3):
            raise ValueError(f"run {k + 1}: expected (poses, doas) or (poses, doas, cut), got {len(run)} items")
        p = _poses(run[0])
        poses.append(p)
        doas.extend(_rows(run[1], len(p)))
        cuts.append(None if len(run) == 2 or run[2] is None else [bool(c) for c in run[2]])
    for k, (p, c) in enumerate(zip(poses, cuts)):
        if c is not None and len(c) != len(p):
            raise ValueError(f"run {k + 1}: {len(c)} cut flags for {len(p)} poses")
    cut: Optional[List[bool]] = None
    if all(c is not None for c in cuts):
        cut = [x for c in cuts if c is not None for x in c]
    m = map_sources(
        np.concatenate(poses), doas, map, resolution=resolution, origin=origin, cut=cut,
        seed=seed, num=num, settings=settings, **iasm_settings,
    )
    first, spans = 1, []
    for k, p in enumerate(poses):
        name = names[k] if names is not None else f"run {k + 1}"
        spans.append({"name": name, "first_stop": first, "stops": len(p)})
        first += len(p)
    m["runs"] = spans
    return m


def read_dataset(root: Union[str, os.PathLike], *, theta_degrees: bool = False) -> Dataset:
    """A data set folder (``audio/``, ``pose/``, ``map/``, a ground-truth table, DoA
    tables), read as the CLI reads it; ``theta_degrees`` when its pose table gives the
    heading in degrees (``iasm map --theta deg``)."""
    audio, poses, truth, map_yaml, tables = _iasm.read_dataset(os.fspath(root), bool(theta_degrees))
    return Dataset(
        root=os.fspath(root),
        recordings=[os.fspath(p) for p in audio],
        poses=poses,
        truth=truth,
        map=None if map_yaml is None else os.fspath(map_yaml),
        doa_tables=[os.fspath(p) for p in tables],
    )


from . import doa  # noqa: E402  (it builds on the names above)
