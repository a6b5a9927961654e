"""Type stubs of the extension module `iasm._iasm` (the Rust crate `iasm-python`).

Use the package's own functions (`iasm.locate`, `iasm.map_sources`, ...): they check their
arguments and return Python objects; these take what they have checked."""

from os import PathLike
from typing import List, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "map_sources",
    "ospa",
    "check_recording",
    "simulate",
    "read_wav",
    "read_dataset",
    "OnlineMapper",
    "Localizer",
    "ARRAY_PRESETS",
    "__version__",
]
ARRAY_PRESETS: List[str]
__version__: str

_Spectrum = Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float32]]

@final
class Localizer:
    def __new__(
        cls,
        fs: int,
        array: str,
        positions: Optional[npt.NDArray[np.float64]],
        settings_json: str,
    ) -> "Localizer": ...
    def locate(
        self, signals: npt.NDArray[np.float32], spectrum: bool
    ) -> Tuple[str, Optional[_Spectrum]]: ...
    def locate_stft(self, frames: npt.NDArray[np.complex64]) -> Tuple[str, _Spectrum]: ...

# A map file, or a grid of ROS values with its resolution and origin (m), or neither.
_MapSpec = Tuple[
    Optional[Union[str, PathLike[str]]], Optional[npt.NDArray[np.int8]], float, Sequence[float]
]

def map_sources(
    poses_xyt: npt.NDArray[np.float64],
    doas_deg: Sequence[Sequence[float]],
    cut: Optional[Sequence[bool]],
    map: _MapSpec,
    settings_json: str,
    seed: int,
    recordings: Optional[Sequence[npt.NDArray[np.float32]]] = None,
    fs: int = 0,
    array_spec: str = "iasm6",
    positions: Optional[npt.NDArray[np.float64]] = None,
) -> str: ...

@final
class OnlineMapper:
    def __new__(cls, map: _MapSpec, settings_json: str, seed: int) -> "OnlineMapper": ...
    def add_stop(
        self, x: float, y: float, theta: float, doas_deg: Sequence[float], cut: Optional[bool] = None
    ) -> str: ...
    def map(self) -> str: ...
    def consolidate(self) -> int: ...
    def stops(self) -> int: ...

def check_recording(channels: int, samples: int, fs: int) -> None: ...
def ospa(
    estimate: npt.NDArray[np.float64], truth: npt.NDArray[np.float64], c: float, p: float
) -> Tuple[float, float, float]: ...
def simulate(
    path: Optional[Union[str, PathLike[str]]],
    text: Optional[str],
    base: Union[str, PathLike[str]],
    out: Optional[Union[str, PathLike[str]]],
) -> Tuple[
    int,
    List[npt.NDArray[np.float32]],
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    Tuple[npt.NDArray[np.int8], float, Tuple[float, float]],
    str,
]: ...
def read_wav(path: Union[str, PathLike[str]]) -> Tuple[npt.NDArray[np.float32], int]: ...
def read_dataset(
    root: Union[str, PathLike[str]], theta_degrees: bool
) -> Tuple[
    List[str],
    Optional[npt.NDArray[np.float64]],
    Optional[npt.NDArray[np.float64]],
    Optional[str],
    List[str],
]: ...
