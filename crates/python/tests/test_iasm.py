"""The Python package against the CLI it wraps, against numbers computed independently
(a plane wave's direction, OSPA by hand), and against bad input."""

import json
import os
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest

import iasm

ROOT = Path(__file__).resolve().parents[3]
SCENE = ROOT / "fixtures" / "rooms" / "one_source.toml"
TWO = ROOT / "fixtures" / "rooms" / "two_talkers.toml"


def cli():
    """The `iasm` binary: $IASM_BIN, else the workspace's release build."""
    path = Path(os.environ.get("IASM_BIN", ROOT / "target" / "release" / "iasm"))
    if not path.exists():
        pytest.skip(f"no iasm binary at {path} (set IASM_BIN)")
    return str(path)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    """The two-talker scene rendered and written as a data set folder."""
    out = tmp_path_factory.mktemp("two") / "ds"
    scene = iasm.simulate(TWO, out=out)
    return scene, out


def test_the_version_is_the_installed_wheels_and_the_clis():
    from importlib.metadata import version

    assert iasm.__version__ == version("iasm")
    said = subprocess.run([cli(), "--version"], capture_output=True, text=True, check=True)
    assert said.stdout.split() == ["iasm", iasm.__version__]


def test_dir_shows_the_api_and_every_name_of_it_exists():
    assert dir(iasm) == sorted(iasm.__all__)
    assert all(hasattr(iasm, name) for name in iasm.__all__)
    # Nothing the module is built on: no numpy, os, json or typing names.
    assert not {"np", "os", "json", "threading", "Dict", "Any"} & set(dir(iasm))


@pytest.mark.parametrize("method", ["mvdr", "gcc-phat", "normmusic"])
def test_locate_gives_the_clis_doas_to_the_last_digit(dataset, method):
    scene, out = dataset
    ds = iasm.read_dataset(out)
    got = subprocess.run(
        [cli(), "ssl", *ds.recordings, "--array", str(out / "array.toml"), "--method", method,
         "--num", "3", "--json"],
        check=True, capture_output=True, text=True,
    ).stdout
    files = json.loads(got)["files"]
    assert len(files) == len(ds.recordings) == len(scene.signals)
    for f, path in zip(files, ds.recordings):
        signals, fs = iasm.read_wav(path)
        row = iasm.locate_row(signals, fs, out / "array.toml", method, 3)
        want = [(d["azimuth_deg"], d["elevation_deg"], d["strength"]) for d in f["doas"]]
        assert [(d.azimuth, d.elevation, d.strength) for d in row.doas] == want, path
        assert row.pooling == f["pooling"]


def test_a_map_is_the_clis_map_for_the_same_seed(dataset, tmp_path):
    scene, out = dataset
    report = tmp_path / "map.json"
    subprocess.run(
        [cli(), "map", "--dataset", str(out), "--method", "mvdr", "--num", "3", "--seed", "7",
         "--out", str(report)],
        check=True, capture_output=True, text=True,
    )
    want = json.loads(report.read_text())
    ds = iasm.read_dataset(out)
    rows = [iasm.locate_row(*iasm.read_wav(p), out / "array.toml", "mvdr", 3) for p in ds.recordings]
    doas = [[d.azimuth for d in r.doas] + [d.azimuth for d in r.extra] for r in rows]
    got = iasm.map_sources(ds.poses, doas, ds.map, cut=[r.cut for r in rows], num=3, seed=7)
    assert [(s["x"], s["y"]) for s in got["sources"]] == [(s["x"], s["y"]) for s in want["sources"]]
    assert got["refused"] == want["refused"]
    # Both talkers, where the scene put them.
    found = np.array([[s["x"], s["y"]] for s in got["sources"]])
    assert iasm.ospa(found, scene.truth).total < 0.1


def test_two_robots_runs_map_as_the_clis_union(tmp_path):
    # Two robots in one L-shaped building (fixtures/buildings): the union of their stops
    # is the CLI's `--dataset A --dataset B` map, and holds the talker only one robot heard.
    outs = []
    for which in ("west", "wing"):
        out = tmp_path / which
        subprocess.run([cli(), "simulate", str(ROOT / "fixtures" / "buildings" / f"two_robots_{which}.toml"),
                        "--out", str(out)], check=True, capture_output=True, text=True)
        outs.append(out)
    report = tmp_path / "map.json"
    subprocess.run(
        [cli(), "map", "--dataset", str(outs[0]), "--dataset", str(outs[1]), "--method", "mvdr",
         "--num", "4", "--seed", "7", "--out", str(report)],
        check=True, capture_output=True, text=True,
    )
    want = json.loads(report.read_text())
    runs = []
    for out in outs:
        ds = iasm.read_dataset(out)
        rows = [iasm.locate_row(*iasm.read_wav(p), out / "array.toml", "mvdr", 4) for p in ds.recordings]
        doas = [[d.azimuth for d in r.doas] + [d.azimuth for d in r.extra] for r in rows]
        runs.append((ds.poses, doas, [r.cut for r in rows]))
    got = iasm.map_runs(runs, iasm.read_dataset(outs[0]).map, names=["west", "wing"], num=4, seed=7)
    assert [(s["x"], s["y"]) for s in got["sources"]] == [(s["x"], s["y"]) for s in want["sources"]]
    assert got["runs"] == [{"name": "west", "first_stop": 1, "stops": 5},
                           {"name": "wing", "first_stop": 6, "stops": 5}]
    found = np.array([[s["x"], s["y"]] for s in got["sources"]])
    assert iasm.ospa(found, [[1.2, 2.5], [7.3, 7.2], [6.0, 0.6]]).total < 0.15
    with pytest.raises(ValueError, match="cut flags"):
        iasm.map_runs([(runs[0][0], runs[0][1], [True])])


def test_the_online_mapper_consolidated_is_the_batch_map(dataset):
    scene, out = dataset
    rows = [iasm.locate(s, scene.fs, scene.array, "mvdr", 3) for s in scene.signals]
    doas = [[d.azimuth for d in r] for r in rows]
    batch = iasm.map_sources(scene.poses, doas, scene.grid, resolution=scene.resolution,
                             origin=scene.origin, num=3, seed=3)
    online = iasm.OnlineMapper(scene.grid, resolution=scene.resolution, origin=scene.origin,
                               num=3, seed=3)
    for pose, row in zip(scene.poses, doas):
        online.add_stop(pose, row)
    assert online.stops == len(scene.poses)
    online.consolidate()
    assert online.map()["sources"] == batch["sources"]


def test_a_plane_wave_is_located_at_its_azimuth():
    # White noise reaching each microphone of the paper's array with the far-field delay
    # of a source at azimuth 60 degrees, elevation 0: delays applied in the frequency
    # domain (exact fractional delays), computed here from the array's geometry.
    sc = iasm.simulate(SCENE)
    fs, n, az = 16000, 16000, np.deg2rad(60.0)
    u = np.array([np.cos(az), np.sin(az), 0.0])
    lead = sc.array @ u / 343.0  # seconds each microphone hears it before the centre
    x = np.fft.rfft(np.random.default_rng(1).standard_normal(n))
    f = np.fft.rfftfreq(n, 1 / fs)
    sig = np.stack([np.fft.irfft(x * np.exp(2j * np.pi * f * t), n) for t in lead])
    sig = (0.3 * sig / np.abs(sig).max()).astype(np.float32)
    for method in ["gcc-phat", "mvdr", "srp-phat", "music", "normmusic"]:
        doas = iasm.locate(sig, fs, sc.array, method, 1)
        assert abs(doas[0].azimuth - 60.0) < 2.0, (method, doas)


def test_ospa_against_hand_computed_values():
    # One point 5 m from its match, cutoff 10: 5. One match exact and one missing, c = 1:
    # (0 + 1) / 2, all cardinality.
    assert iasm.ospa([[0, 0]], [[3, 4]], c=10).total == pytest.approx(5.0)
    o = iasm.ospa([[0, 0]], [[0, 0], [1, 1]], c=1, p=1)
    assert (o.total, o.localisation, o.cardinality) == pytest.approx((0.5, 0.0, 0.5))
    assert iasm.ospa([], [], c=1).total == 0.0


def test_a_scene_as_a_dict_renders_as_its_file():
    tomllib = pytest.importorskip("tomllib")  # Python 3.11 on: the scene file as a dict
    d = tomllib.loads(SCENE.read_text())
    a, b = iasm.simulate(SCENE), iasm.simulate(d, base=SCENE.parent)
    assert a.fs == b.fs and len(a.signals) == len(b.signals)
    assert all(np.array_equal(x, y) for x, y in zip(a.signals, b.signals))
    np.testing.assert_array_equal(a.poses, b.poses)


def test_threads_localise_at_once_with_the_same_answers():
    sc = iasm.simulate(SCENE)
    want = [iasm.locate(s, sc.fs, sc.array) for s in sc.signals]
    got = [None] * len(sc.signals)

    def work(k):
        got[k] = iasm.locate(sc.signals[k], sc.fs, sc.array)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(sc.signals))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert got == want


def test_bad_input_raises_a_clear_exception():
    sc = iasm.simulate(SCENE)
    s = sc.signals[0]
    with pytest.raises(TypeError, match="float32 or float64"):
        iasm.locate(s.astype(np.int16), sc.fs, sc.array)
    with pytest.raises(ValueError, match=r"shape \(microphones, samples\)"):
        iasm.locate(s[0], sc.fs, sc.array)
    bad = s.copy()
    bad[2, 100] = np.nan
    with pytest.raises(ValueError, match="channel 3 holds a non-finite sample"):
        iasm.locate(bad, sc.fs, sc.array)
    with pytest.raises(ValueError, match="3 channels but the array has 6 microphones"):
        iasm.locate(s[:3], sc.fs, sc.array)
    with pytest.raises(ValueError, match="fmin_hz"):
        iasm.locate(s, sc.fs, sc.array, fmin_hz=-3)
    with pytest.raises(ValueError, match="unknown field `not_a_setting`"):
        iasm.locate(s, sc.fs, sc.array, not_a_setting=1)
    with pytest.raises(ValueError, match="method"):
        iasm.locate(s, sc.fs, sc.array, "beamforming")
    with pytest.raises(ValueError, match="fs must be a positive whole number"):
        iasm.locate(s, 0, sc.array)
    with pytest.raises(ValueError, match=r"shape \(microphones, 3\)"):
        iasm.locate(s, sc.fs, np.zeros((6, 2)))
    with pytest.raises(FileNotFoundError):
        iasm.read_wav("/nonexistent/recording.wav")
    with pytest.raises(FileNotFoundError):
        iasm.simulate("/nonexistent/scene.toml")
    with pytest.raises(ValueError, match=r"poses must have the shape \(stops, 3\)"):
        iasm.map_sources(np.zeros((4, 2)), [[0.0]] * 4)
    with pytest.raises(ValueError, match="rows for"):
        iasm.map_sources(sc.poses, [[0.0]] * 2)
    with pytest.raises(ValueError, match="9 azimuths but N = 3"):
        iasm.map_sources(sc.poses, [[1.0] * 9] * len(sc.poses), num=3)
    with pytest.raises(ValueError, match="resolution"):
        iasm.map_sources(sc.poses, [[0.0]] * len(sc.poses), sc.grid)


def test_the_readmes_example_runs_as_written(tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    text = (ROOT / "README.md").read_text()
    code = text.split("```python\n", 1)[1].split("```", 1)[0]
    # From the repository's root, as the README says, writing its picture elsewhere.
    monkeypatch.chdir(ROOT)
    code = code.replace('"map.png"', repr(str(tmp_path / "map.png")))
    exec(compile(code, "README.md", "exec"), {})
    assert (tmp_path / "map.png").stat().st_size > 0


def test_a_talker_who_falls_silent_is_dated_in_the_map():
    # 30 stops along y = 0, turning 0.3 rad a stop; a talker at (1.5, 1.2) heard at stops
    # 0-14 and silent from 15 on, a machine at (3, -1.5) heard at every stop. Exact
    # bearings, in degrees in the array frame, computed here.
    k = np.arange(30)
    poses = np.stack([6.0 * k / 29, np.zeros(30), 0.3 * k], axis=1)
    talker, machine = np.array([1.5, 1.2]), np.array([3.0, -1.5])

    def bearing(p, q):
        a = np.degrees(np.arctan2(q[1] - p[1], q[0] - p[0]) - p[2])
        return float((a + 180.0) % 360.0 - 180.0)

    doas = [[bearing(p, talker)] * (i < 15) + [bearing(p, machine)] for i, p in enumerate(poses)]
    got = iasm.map_sources(poses, doas, num=3, seed=1)
    assert len(got["sources"]) == 2
    at = {("talker" if s["y"] > 0 else "machine"): s for s in got["sources"]}
    assert np.hypot(at["talker"]["x"] - 1.5, at["talker"]["y"] - 1.2) < 0.1
    t, m = at["talker"], at["machine"]
    assert (t["first_stop"], t["last_stop"], t["heard_stops"]) == (0, 14, 15)
    assert (t["state"], t["since"]) == ("silent", 15)
    assert (m["first_stop"], m["last_stop"], m["state"]) == (0, 29, "active")
    assert "since" not in m and "appeared_at" not in m


def test_each_source_says_what_it_sounds_like_from_the_recordings():
    # The one-source scene: a voiced hum with a steady 130-Hz pitch at (3.5, 3.2), so
    # tonal; the two-talker scene: two noises with speech's long-term spectrum and no
    # syllables, so broadband. The map from the scene's own true bearings, the signatures
    # from its recordings.
    for path, kinds in [(SCENE, ["tonal"]), (TWO, ["broadband", "broadband"])]:
        sc = iasm.simulate(path)

        def bearing(p, q):
            a = np.degrees(np.arctan2(q[1] - p[1], q[0] - p[0]) - p[2])
            return float((a + 180.0) % 360.0 - 180.0)

        doas = [[bearing(p, t) for t in sc.truth] for p in sc.poses]
        got = iasm.map_sources(
            sc.poses, doas, sc.grid, resolution=sc.resolution, origin=sc.origin, num=3, seed=1,
            recordings=sc.signals, fs=sc.fs, array=sc.array,
        )
        assert len(got["sources"]) == len(kinds)
        for s, kind in zip(got["sources"], kinds):
            sig = s["signature"]
            assert sig["kind"] == kind, sig
            assert sig["stops"] >= 3 and sig["level_db"] <= 0.0
        assert max(s["signature"]["level_db"] for s in got["sources"]) == 0.0
        # Without recordings, no signature.
        plain = iasm.map_sources(sc.poses, doas, sc.grid, resolution=sc.resolution, origin=sc.origin, num=3, seed=1)
        assert all("signature" not in s for s in plain["sources"])
    with pytest.raises(ValueError, match="sample rate"):
        iasm.map_sources(sc.poses, doas, recordings=sc.signals)
    with pytest.raises(ValueError, match="must match one to one"):
        iasm.map_sources(sc.poses, doas, recordings=sc.signals[:2], fs=sc.fs, array=sc.array)
