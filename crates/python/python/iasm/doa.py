"""iasm's SSL methods with the interface of ``pyroomacoustics.doa``.

A pyroomacoustics script changes one line::

    doa = pra.doa.algorithms["MUSIC"](L, fs, nfft, c=c, num_src=2)   # before
    doa = iasm.doa.algorithms["MUSIC"](L, fs, nfft, c=c, num_src=2)  # after
    doa.locate_sources(X, freq_range=[300.0, 3500.0])
    doa.azimuth_recon, doa.grid.values                                 # as before

``L`` is ``(2 or 3, M)`` microphone positions (m), ``X`` the STFT frames
``(M, nfft / 2 + 1, snapshots)``, as pyroomacoustics takes them. ``azimuth_recon`` is in
radians in ``[0, 2 pi)``, as pyroomacoustics gives it, and ``grid`` holds the pooled
spectrum on the azimuth grid (``dim=2``) or on iasm's sphere grid (``dim=3``).

What differs, by design: the spectrum is iasm's (each method as the ``ssl`` crate computes
it, over one block of every snapshot given, as pyroomacoustics does; ``block_frames=4``
pools iasm's short blocks instead), the grid has ``n_grid`` azimuths spaced evenly from 0,
and the DoAs are iasm's ranked peaks (its peak rules), topped up with the spectrum's next
highest local maxima when those rules keep fewer than ``num_src``. Any ``[ssl]`` setting can
be passed by its name as a keyword (``fmin_hz`` and ``fmax_hz`` come from ``freq_range``,
``frame_len`` from ``nfft``, ``num_peaks`` from ``num_src``).
"""

from __future__ import annotations

import json
import warnings
from typing import Any, Dict, Optional, Sequence, Tuple

import numpy as np

from . import Doa, _iasm, _json

__all__ = ["algorithms", "SRP", "MUSIC", "NormMUSIC", "TOPS", "CSSM", "WAVES", "GCCPHAT", "MVDR", "Grid"]

# The settings file's [ssl] names: passed through; pyroomacoustics-only keywords are not.
_SSL_NAMES = frozenset(
    """method frame_len hop fmin_hz fmax_hz az_step_deg elevation block_frames pooling
    pool_top placement_share deflate deflate_max_residual num_peaks min_sep_deg
    min_relative dominance_blocks min_prominence sidelobe_ratio min_significance
    incoherent_relative max_incoherence subband_votes decay_gate_db decay_window_s
    speed_of_sound mvdr_loading mvdr_freq_smoothing music_sources music_freq_smoothing
    music_coarse screen_channels""".split()
)


class Grid:
    """The search grid and the spectrum on it, as pyroomacoustics' ``GridCircle`` holds
    them: ``azimuth`` (rad, from 0), ``colatitude`` (rad from ``z``; ``pi / 2`` in the
    plane), ``values`` (one per point), ``n_points``."""

    def __init__(self, azimuth: np.ndarray, colatitude: np.ndarray, values: Optional[np.ndarray] = None):
        self.azimuth = azimuth
        self.colatitude = colatitude
        self.n_points = len(azimuth)
        self.values = values

    def set_values(self, values: np.ndarray) -> None:
        self.values = np.asarray(values)


class _DOA:
    _method = ""

    def __init__(
        self,
        L: np.ndarray,
        fs: float,
        nfft: int,
        c: float = 343.0,
        num_src: int = 1,
        mode: str = "far",
        r: Any = None,
        azimuth: Optional[np.ndarray] = None,
        colatitude: Optional[np.ndarray] = None,
        n_grid: Optional[int] = None,
        dim: int = 2,
        *args: Any,
        **kwargs: Any,
    ) -> None:
        L = np.asarray(L, dtype=np.float64)
        if L.ndim != 2 or L.shape[0] not in (2, 3) or L.shape[1] < 2:
            raise ValueError(f"L must be (2 or 3, microphones) positions in metres, got shape {L.shape}")
        if dim not in (2, 3):
            raise ValueError("The dimension must be 2 or 3.")
        if dim > L.shape[0]:
            raise ValueError("Microphones locations missing dimensions.")
        if mode != "far":
            raise ValueError("iasm's methods are far-field: mode must be 'far'")
        self.L, self.fs, self.nfft, self.c = L, fs, int(nfft), float(c)
        self.M, self.D, self.dim = L.shape[1], L.shape[0], dim
        self.max_bin = self.nfft // 2 + 1
        self.num_src = int(num_src)
        self.mode = mode
        positions = np.zeros((self.M, 3))
        positions[:, : self.D] = L.T
        self._positions = np.ascontiguousarray(positions)
        if azimuth is not None:
            az = np.sort(np.mod(np.asarray(azimuth, dtype=np.float64), 2 * np.pi))
            steps = np.diff(az)
            if len(az) < 2 or not np.allclose(steps, steps[0]) or not np.isclose(az[0] % steps[0], 0.0):
                raise ValueError("iasm searches azimuths spaced evenly from 0: give n_grid, or such an azimuth array")
            n_grid = int(round(2 * np.pi / steps[0]))
        if n_grid is None:
            n_grid = 360
        self._step_deg = 360.0 / n_grid
        if colatitude is not None and dim == 3:
            warnings.warn("iasm searches its own elevation grid; colatitude is ignored")
        self._settings: Dict[str, Any] = {}
        self._extra = {}
        for k, v in kwargs.items():
            if k in _SSL_NAMES:
                self._settings[k] = v
            elif k == "frequency_normalization" and self._method in ("music", "normmusic"):
                self._method = "normmusic" if v else "music"
            else:
                self._extra[k] = v
        self.grid = Grid(np.deg2rad(np.arange(n_grid) * self._step_deg), np.full(n_grid, np.pi / 2))
        self.azimuth_recon: Optional[np.ndarray] = None
        self.colatitude_recon: Optional[np.ndarray] = None
        self.doas: list = []
        self._planned: Optional[Tuple[str, _iasm.Localizer]] = None

    def locate_sources(
        self,
        X: np.ndarray,
        num_src: Optional[int] = None,
        freq_range: Sequence[float] = (500.0, 4000.0),
        freq_bins: Optional[Sequence[int]] = None,
        freq_hz: Optional[Sequence[float]] = None,
    ) -> None:
        """Localises ``num_src`` sources from the STFT frames ``X`` (``M x F x S``)."""
        X = np.asarray(X)
        if X.ndim != 3 or X.shape[0] != self.M or X.shape[1] != self.max_bin:
            raise ValueError(
                f"X must be (M, nfft/2+1, snapshots) = ({self.M}, {self.max_bin}, S), got shape {X.shape}"
            )
        if num_src is not None:
            self.num_src = int(num_src)
        if freq_bins is not None:
            lo, hi = min(freq_bins) * self.fs / self.nfft, (max(freq_bins) + 1) * self.fs / self.nfft
        elif freq_hz is not None:
            lo, hi = min(freq_hz), max(freq_hz)
        else:
            lo, hi = freq_range
        ssl = {
            "method": self._method,
            "frame_len": self.nfft,
            "hop": self.nfft // 2,
            "fmin_hz": float(lo),
            "fmax_hz": float(hi),
            "az_step_deg": self._step_deg,
            "num_peaks": self.num_src,
            "speed_of_sound": self.c,
            # One statistic over every snapshot given, as pyroomacoustics computes it
            # (iasm's own pooling of short blocks: pass block_frames=4).
            "block_frames": X.shape[2],
        }
        if self.dim == 2:
            ssl["elevation"] = {"min_deg": 0.0, "max_deg": 0.0}
        if self._method == "music":
            # pyroomacoustics' MUSIC takes num_src as its signal subspace (iasm's own MUSIC
            # takes one per block and bin: pass music_sources to choose).
            ssl["music_sources"] = max(1, min(self.num_src, self.M - 1))
        ssl.update(self._settings)
        frames = np.ascontiguousarray(X.transpose(2, 0, 1), dtype=np.complex64)
        key = _json({"ssl": ssl})
        if self._planned is None or self._planned[0] != key:
            # Planned once per band and settings (grids, steering tables), as
            # pyroomacoustics keeps its mode vectors.
            self._planned = (key, _iasm.Localizer(int(self.fs), "array", self._positions, key))
        text, (az, el, values) = self._planned[1].locate_stft(frames)
        row = json.loads(text)
        self.doas = [Doa._of(d) for d in row["doas"]]
        if self.dim == 2:
            # iasm's azimuths run from -180; pyroomacoustics' grid from 0.
            order = np.argsort(np.mod(az, 360.0))
            self.grid.set_values(values[0][order])
            self.grid.azimuth = np.deg2rad(np.mod(az, 360.0)[order])
            self.grid.colatitude = np.full(len(az), np.pi / 2)
        else:
            A, E = np.meshgrid(az, el)
            self.grid = Grid(np.deg2rad(np.mod(A.ravel(), 360.0)), np.deg2rad(90.0 - E.ravel()), values.ravel())
        picked = [(d.azimuth, d.elevation) for d in self.doas][: self.num_src]
        if len(picked) < self.num_src:
            picked += self._top_up(az, el, values, picked)
        self.azimuth_recon = np.deg2rad(np.mod([a for a, _ in picked], 360.0))
        self.colatitude_recon = np.deg2rad(90.0 - np.array([e for _, e in picked], dtype=float))
        self.num_src = len(picked)

    def _top_up(self, az, el, values, picked):
        """The spectrum's highest local maxima (over azimuth, each elevation's row) that are
        not within 2 grid steps of a DoA already picked."""
        cands = []
        for e, row in zip(el, values):
            left, right = np.roll(row, 1), np.roll(row, -1)
            for i in np.flatnonzero((row >= left) & (row > right)):
                cands.append((row[i], az[i], e))
        cands.sort(key=lambda t: -t[0])
        out = []
        for _, a, e in cands:
            if len(picked) + len(out) >= self.num_src:
                break
            near = lambda p: abs((a - p[0] + 180.0) % 360.0 - 180.0) < 2 * self._step_deg and abs(e - p[1]) < 1e-9
            if not any(near(p) for p in picked + out):
                out.append((a, e))
        return out


class SRP(_DOA):
    """SRP-PHAT (pyroomacoustics' ``SRP``)."""

    _method = "srp-phat"


class MUSIC(_DOA):
    """MUSIC (pyroomacoustics' ``MUSIC``; ``frequency_normalization=True`` is NormMUSIC)."""

    _method = "music"


class NormMUSIC(_DOA):
    """NormMUSIC (pyroomacoustics' ``NormMUSIC``)."""

    _method = "normmusic"


class TOPS(_DOA):
    """TOPS (pyroomacoustics' ``TOPS``): one spectrum of every snapshot given, its signal
    subspace ``num_src`` wide."""

    _method = "tops"


class CSSM(_DOA):
    """CSSM (pyroomacoustics' ``CSSM``): one spectrum of every snapshot given."""

    _method = "cssm"


class WAVES(_DOA):
    """WAVES (pyroomacoustics' ``WAVES``): one spectrum of every snapshot given."""

    _method = "waves"


class GCCPHAT(_DOA):
    """GCC-PHAT, iasm's pairwise method (no pyroomacoustics twin)."""

    _method = "gcc-phat"


class MVDR(_DOA):
    """MVDR, iasm's and MBSS Locate's beamformer (no pyroomacoustics twin)."""

    _method = "mvdr"


#: pyroomacoustics' names, and iasm's two methods that it lacks.
algorithms = {
    "SRP": SRP,
    "MUSIC": MUSIC,
    "NormMUSIC": NormMUSIC,
    "TOPS": TOPS,
    "CSSM": CSSM,
    "WAVES": WAVES,
    "GCC-PHAT": GCCPHAT,
    "MVDR": MVDR,
}
