import numpy as np
import pytest

from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory
from seatrack.simulate import uniform_clutter


def _tracks():
    tgt = trajectory([4000, 3000, 500], 2.0, 10.0, [Leg.straight(2000)], dt=1.0)
    own = trajectory([0, 0], 0.5, 5.0, [Leg.straight(2000)], dt=1.0)
    return tgt, own


def test_noise_statistics_and_reproducibility():
    tgt, own = _tracks()
    sig = [5.0, np.radians(1.0), np.radians(0.5), 0.3]
    nm = NoiseModel(sig)
    a = observe(
        tgt, own, ["range", "azimuth", "elevation", "range_rate"], nm, np.random.default_rng(1)
    )
    b = observe(
        tgt, own, ["range", "azimuth", "elevation", "range_rate"], nm, np.random.default_rng(1)
    )
    np.testing.assert_array_equal(a.z, b.z)
    err = a.z - a.truth
    err[:, 1] = (err[:, 1] + np.pi) % (2 * np.pi) - np.pi
    std = err.std(axis=0)
    np.testing.assert_allclose(
        std, sig, rtol=0.1
    )  # 2001 samples: 10 % is > 4 sigma of the std estimate
    assert a.angular.tolist() == [False, True, True, False]


def test_contamination_fraction_and_scale():
    tgt, own = _tracks()
    nm = NoiseModel([1.5, np.radians(2.0)], epsilon=0.2, outlier_scale=[10.0, 25.0])
    m = observe(tgt, own, ["range", "bearing"], nm, np.random.default_rng(5))
    frac = m.outlier.mean(axis=0)
    assert np.all(np.abs(frac - 0.2) < 0.03)
    e = m.z[:, 0] - m.truth[:, 0]
    assert e[m.outlier[:, 0]].std() == pytest.approx(1.5 * np.sqrt(10), rel=0.15)
    assert e[~m.outlier[:, 0]].std() == pytest.approx(1.5, rel=0.1)


def test_missed_detections_and_fixed_observer():
    tgt, _ = _tracks()
    m = observe(
        tgt, [100.0, 200.0], ["azimuth"], NoiseModel([0.01]), np.random.default_rng(2), p_detect=0.7
    )
    assert abs(m.detected.mean() - 0.7) < 0.05
    assert np.isnan(m.z[~m.detected]).all() and not np.isnan(m.z[m.detected]).any()
    np.testing.assert_allclose(m.sensor_pos[0], [100, 200, 0])


def test_bad_arguments():
    tgt, own = _tracks()
    with pytest.raises(ValueError, match="unknown component"):
        observe(tgt, own, ["doppler"], NoiseModel([1.0]), np.random.default_rng(0))
    with pytest.raises(ValueError, match="sigmas"):
        observe(tgt, own, ["range", "azimuth"], NoiseModel([1.0]), np.random.default_rng(0))
    with pytest.raises(ValueError, match="epsilon"):
        NoiseModel([1.0], epsilon=1.5)


def test_uniform_clutter():
    t, r, a = uniform_clutter(
        np.arange(1000.0), 3.0, (100.0, 5000.0), (0.0, 2 * np.pi), np.random.default_rng(0)
    )
    assert abs(t.size / 1000 - 3.0) < 0.2
    assert r.min() >= 100 and r.max() <= 5000 and a.min() >= 0 and a.max() < 2 * np.pi
