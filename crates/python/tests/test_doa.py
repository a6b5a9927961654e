"""iasm.doa, the drop-in for pyroomacoustics' DOA classes, on pyroomacoustics' own DOA
example (examples/doa_algorithms.py: one source at azimuth 61 degrees, 3 m from a
six-microphone circle of radius 37.5 mm and its centre, white noise at 0 dB SNR, nfft 256,
bins 5-59)."""

import numpy as np
import pytest

import iasm

pra = pytest.importorskip("pyroomacoustics")


def example(seed=1, azimuths=(61.0,)):
    rng = np.random.default_rng(seed)
    np.random.seed(seed)
    distance, snr, c, fs, nfft = 3.0, 0.0, 343.0, 16000, 256
    room_dim = np.r_[10.0, 10.0]
    echo = pra.circular_2D_array(center=room_dim / 2, M=6, phi0=0, radius=37.5e-3)
    echo = np.concatenate((echo, np.array(room_dim / 2, ndmin=2).T), axis=1)
    sigma2 = 10 ** (-snr / 10) / (4.0 * np.pi * distance) ** 2
    room = pra.ShoeBox(room_dim, fs=fs, max_order=0, sigma2_awgn=sigma2)
    for az in azimuths:
        a = np.deg2rad(az)
        room.add_source(room_dim / 2 + distance * np.r_[np.cos(a), np.sin(a)],
                        signal=rng.standard_normal((nfft // 2 + 1) * nfft))
    room.add_microphone_array(pra.MicrophoneArray(echo, room.fs))
    room.simulate()
    X = np.array([pra.transform.stft.analysis(s, nfft, nfft // 2).T for s in room.mic_array.signals])
    return echo, fs, nfft, c, X


def deg(rad):
    return np.sort(np.rad2deg(np.asarray(rad)) % 360.0)


@pytest.mark.parametrize("name", ["SRP", "MUSIC", "NormMUSIC", "TOPS", "CSSM", "WAVES"])
def test_the_drop_in_answers_as_pyroomacoustics_on_its_example(name):
    echo, fs, nfft, c, X = example()
    ours = iasm.doa.algorithms[name](echo, fs, nfft, c=c, num_src=1)
    theirs = pra.doa.algorithms[name](echo, fs, nfft, c=c, num_src=1)
    for d in (ours, theirs):
        d.locate_sources(X, freq_bins=np.arange(5, 60))
    assert abs(deg(ours.azimuth_recon)[0] - deg(theirs.azimuth_recon)[0]) < 1.0
    assert abs(deg(ours.azimuth_recon)[0] - 61.0) < 1.0
    # The grid as pyroomacoustics holds it: 360 azimuths from 0, a value each, the
    # largest at the DoA.
    assert ours.grid.n_points == 360 and ours.grid.values.shape == (360,)
    np.testing.assert_allclose(ours.grid.azimuth, np.deg2rad(np.arange(360.0)))
    assert abs(np.rad2deg(ours.grid.azimuth[np.argmax(ours.grid.values)]) - 61.0) <= 1.0


# Two sources at once on a 75-mm circle: the subspace methods resolve them to the degree
# (CSSM and WAVES, searched at the band's top, to 3; pyroomacoustics' own to 8);
# a beamformer's main lobe there is wider than the array's whole field of view at low
# frequencies, and the two lobes pull each other (pyroomacoustics' own SRP: 63 and 198).
@pytest.mark.parametrize(
    "name, tol",
    [("MUSIC", 1.0), ("NormMUSIC", 1.0), ("TOPS", 1.0), ("CSSM", 5.0), ("WAVES", 5.0),
     ("SRP", 10.0), ("GCC-PHAT", 10.0), ("MVDR", 10.0)],
)
def test_two_sources_are_found_with_num_src_two(name, tol):
    echo, fs, nfft, c, X = example(seed=2, azimuths=(61.0, 200.0))
    d = iasm.doa.algorithms[name](echo, fs, nfft, c=c, num_src=2)
    d.locate_sources(X, freq_range=[300.0, 3500.0])
    got = deg(d.azimuth_recon)
    assert len(got) == 2
    assert abs(got[0] - 61.0) < tol and abs(got[1] - 200.0) < tol, (name, got)


def test_the_drop_in_refuses_what_pyroomacoustics_would():
    echo, fs, nfft, c, X = example()
    d = iasm.doa.algorithms["SRP"](echo, fs, nfft, c=c)
    with pytest.raises(ValueError, match="nfft/2"):
        d.locate_sources(X[:, :100])
    with pytest.raises(ValueError, match="dimension must be 2 or 3"):
        iasm.doa.algorithms["SRP"](echo, fs, nfft, dim=4)
    with pytest.raises(ValueError, match="far-field"):
        iasm.doa.algorithms["SRP"](echo, fs, nfft, mode="near")
