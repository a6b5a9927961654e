"""The faults a notebook brings to the Python door (issue 71): every bad argument gives a
result or the exception the guide names (ValueError for bad values and shapes, TypeError
for types, MemoryError where a size bound is exceeded), never a panic, an abort or a hang,
and the same checks as the CLI's."""

import signal

import numpy as np
import pytest

import iasm

GRID = np.zeros((120, 140), dtype=np.int8)  # 7 x 6 m of free cells at 5 cm
POSES = np.array([[1.0, 1.0, 0.0], [2.0, 1.0, 0.0], [3.0, 1.0, 0.0]])
DOAS = [[30.0], [45.0], [60.0]]


@pytest.mark.parametrize(
    "origin",
    [(float("nan"), 0.0), (0.0, float("nan")), (float("inf"), 0.0), (1e300, 0.0), (2e4, 0.0)],
)
def test_an_origin_that_is_not_finite_or_far_is_a_value_error(origin):
    with pytest.raises(ValueError, match="origin"):
        iasm.map_sources(POSES, DOAS, GRID, resolution=0.05, origin=origin)
    with pytest.raises(ValueError, match="origin"):
        iasm.OnlineMapper(GRID, resolution=0.05, origin=origin)


@pytest.mark.parametrize("resolution", [1e-9, 1e9, 0.0, float("nan")])
def test_a_resolution_no_map_has_is_a_value_error(resolution):
    with pytest.raises(ValueError, match="resolution"):
        iasm.map_sources(POSES, DOAS, GRID, resolution=resolution, origin=(0.0, 0.0))


def test_a_grid_of_more_cells_than_a_map_may_have_is_a_memory_error():
    # 6000 x 6000 cells: more than the CLI's 25,000,000, refused before any cell is built.
    big = np.zeros((6000, 6000), dtype=np.int8)
    with pytest.raises(MemoryError, match="more than a map may have"):
        iasm.map_sources(POSES, DOAS, big, resolution=0.05, origin=(0.0, 0.0))


def test_a_recording_longer_than_one_localisation_is_a_memory_error():
    # 52 minutes of six channels at 48 kHz, as a view that takes no memory: refused
    # before anything is copied.
    long = np.broadcast_to(np.zeros((1, 1), np.float32), (6, 150_000_000))
    with pytest.raises(MemoryError, match="longer than one localisation takes"):
        iasm.locate(long, 48000)


def test_stops_that_all_lie_outside_the_map_are_a_value_error():
    far = POSES + np.array([100.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="none of the 3 stops lies in the occupancy map"):
        iasm.map_sources(far, DOAS, GRID, resolution=0.05, origin=(0.0, 0.0))
    m = iasm.OnlineMapper(GRID, resolution=0.05, origin=(0.0, 0.0))
    with pytest.raises(ValueError, match="lies outside the occupancy map"):
        m.add_stop((101.0, 1.0, 0.0), [30.0])
    # The same mapper goes on with a stop that lies in it.
    assert m.add_stop((1.0, 1.0, 0.0), [30.0])["stop"] == 0


def test_what_the_cli_warns_of_reaches_python_as_a_warning():
    # One stop of three beyond the grid: mapped, and said, as `iasm map` says it.
    some_far = POSES.copy()
    some_far[2, 0] += 100.0
    with pytest.warns(UserWarning, match="1 of 3 stops lie outside the occupancy map"):
        m = iasm.map_sources(some_far, DOAS, GRID, resolution=0.05, origin=(0.0, 0.0))
    assert "warnings" not in m


def test_ospa_is_finite_whatever_c_to_the_p_is():
    # The definition's figures, computed by hand: a lone miss of 50 m at c = 100 is 50 m
    # for every p; equal sets are at 0; a miss as large as c costs c.
    assert iasm.ospa([[50, 0]], [[0, 0]], c=100, p=200).total == pytest.approx(50.0)
    assert iasm.ospa([[0, 0]], [[0, 0]], c=10, p=400).total == 0.0
    assert iasm.ospa([[1e160, 0]], [[0, 0]], c=1e160, p=2).total == pytest.approx(1e160)
    with pytest.raises(ValueError, match="finite cutoff"):
        iasm.ospa([[0, 0]], [[0, 0]], c=float("inf"), p=1)


class _Timeout(Exception):
    pass


def _alarm(signum, frame):
    raise _Timeout()


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_mutated_arguments_give_a_result_or_a_named_exception_in_bounded_time():
    """A seeded sweep over the mapper's and OSPA's arguments (shapes, dtypes, NaN and inf,
    sizes): each call returns, or raises ValueError, TypeError or MemoryError, within 10 s."""
    rng = np.random.default_rng(71)
    specials = [np.nan, np.inf, -np.inf, 1e300, -1e300, 0.0, 1e-300]

    def mutate(a):
        a = np.array(a, dtype=np.float64, copy=True)
        if a.size and rng.random() < 0.7:
            a.flat[rng.integers(a.size)] = specials[rng.integers(len(specials))]
        if rng.random() < 0.2:
            a = a.reshape(-1)
        if rng.random() < 0.1:
            a = a.astype(np.int64) if (np.abs(a) < 1e15).all() else a
        return a

    calls = [
        lambda: iasm.map_sources(mutate(POSES), [list(mutate(r)) for r in DOAS], GRID,
                                 resolution=float(mutate([0.05])[0]), origin=tuple(mutate([0.0, 0.0]))),
        lambda: iasm.ospa(mutate([[1.0, 2.0], [3.0, 4.0]]), mutate([[0.0, 0.0]]),
                          c=float(mutate([1.0])[0]), p=float(mutate([2.0])[0])),
        lambda: iasm.OnlineMapper(GRID, resolution=0.05, origin=(0.0, 0.0)).add_stop(
            tuple(mutate([1.0, 1.0, 0.0])), list(mutate([30.0, 60.0]))),
    ]
    old = signal.signal(signal.SIGALRM, _alarm)
    try:
        for i in range(300):
            call = calls[i % len(calls)]
            signal.alarm(10)
            try:
                call()
            except (ValueError, TypeError, MemoryError):
                pass
            except _Timeout:
                pytest.fail(f"call {i} did not return within 10 s")
            finally:
                signal.alarm(0)
    finally:
        signal.signal(signal.SIGALRM, old)
