"""The public API: lazy import, argument checks, tables from memory, the docstring examples."""

from __future__ import annotations

import doctest
import importlib
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import seatrack
from seatrack.config import ConfigError
from seatrack.filters.base import SensorNoise
from seatrack.io.table import InputError
from seatrack.tracking import TrackerConfig


def test_import_seatrack_loads_no_compiled_plotting_or_web_module():
    code = (
        "import sys, seatrack\n"
        "bad = [m for m in sys.modules if m.split('.')[0] in "
        "('numba', 'matplotlib', 'pandas', 'scipy', 'typer', 'dask', 'distributed')]\n"
        "bad += [m for m in sys.modules if m.startswith('seatrack.') and m != 'seatrack']\n"
        "print(','.join(bad))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_the_command_line_loads_no_compiled_or_plotting_module_before_a_command_runs():
    code = (
        "import sys, seatrack.cli\n"
        "print(','.join(m for m in sys.modules if m.split('.')[0] in "
        "('numba', 'matplotlib', 'pandas', 'scipy', 'pyarrow')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_public_names_resolve_lazily():
    assert seatrack.__version__
    assert {"tma", "track", "ais", "navigate", "simulate", "evaluate", "Sensor"} <= set(
        dir(seatrack)
    )
    for name in ("tma", "track", "ais", "navigate", "simulate", "evaluate", "Sensor"):
        assert callable(getattr(seatrack, name))
    assert seatrack.TMAResult.__name__ == "TMAResult"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        seatrack.nothing  # noqa: B018


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"sigma_range_m": -1.0}, "sigma_range_m"),
        ({"sigma_range_m": 0.0}, "sigma_range_m"),
        ({"sigma_azimuth_deg": float("nan")}, "sigma_azimuth_deg"),
        ({"sigma_elevation_deg": float("inf")}, "sigma_elevation_deg"),
        ({"sigma_range_rate_mps": -0.5}, "sigma_range_rate_mps"),
    ],
)
def test_sensor_refuses_a_bad_sigma_naming_the_argument(kw, name):
    with pytest.raises(ValueError, match=f"^Sensor: {name}: "):
        seatrack.Sensor(**kw)


def test_sensor_converts_degrees_to_radians():
    s = seatrack.Sensor(sigma_range_m=20.0, sigma_azimuth_deg=0.3, sigma_range_rate_mps=0.5)
    n = s.noise()
    assert n.sigma_range == 20.0 and n.sigma_range_rate == 0.5
    assert n.sigma_azimuth == pytest.approx(np.radians(0.3), rel=1e-15)
    assert n.sigma_elevation == SensorNoise().sigma_elevation  # the default
    assert seatrack.Sensor.from_noise(n).noise() == n


def test_configs_built_directly_check_their_bounds():
    with pytest.raises(ConfigError, match=r"SensorNoise.sigma_azimuth \(sigma_azimuth_deg\)"):
        SensorNoise(sigma_azimuth=-0.01)
    with pytest.raises(ConfigError, match="must be finite"):
        SensorNoise(sigma_range=float("nan"))
    with pytest.raises(ConfigError, match=r"TrackerConfig.max_speed \(max_speed_kn\)"):
        TrackerConfig(max_speed=-1.0)
    SensorNoise(sigma_azimuth=np.pi)  # the upper bound itself (180 deg) is allowed


def _plots() -> dict[str, np.ndarray]:
    t = np.arange(0.0, 40.0, 2.0)
    return {
        "track": np.array(["A"] * t.size),
        "time_s": t,
        "range_m": 5000.0 + 10.0 * t,
        "azimuth_deg": np.full(t.size, 45.0),
    }


@pytest.mark.parametrize("kind", ["dict", "DataFrame", "pyarrow Table", "path"])
def test_track_reads_every_kind_of_table_alike(kind, tmp_path):
    import pyarrow as pa

    d = _plots()
    frame = pd.DataFrame(d)
    path = tmp_path / "plots.csv"
    frame.to_csv(path, index=False)
    data = {"dict": d, "DataFrame": frame, "pyarrow Table": pa.table(d), "path": path}[kind]
    out = seatrack.track(data, method="ekf")
    ref = seatrack.track(path, method="ekf")
    pd.testing.assert_frame_equal(out, ref)
    assert list(out.columns[:3]) == ["track", "time_s", "x_m"]


def test_a_bad_table_is_reported_by_row_like_a_bad_file(tmp_path):
    d = _plots()
    d["range_m"] = d["range_m"].copy()
    d["range_m"][3] = -5.0
    with pytest.raises(InputError, match=r"^plots \(DataFrame\), row 3: range_m must be > 0"):
        seatrack.track(pd.DataFrame(d))
    path = tmp_path / "plots.csv"
    pd.DataFrame(d).to_csv(path, index=False)
    with pytest.raises(InputError, match=rf"^{path}, line 5: range_m must be > 0"):
        seatrack.track(path)


def test_track_arguments_are_checked():
    with pytest.raises(ValueError, match="unknown method"):
        seatrack.track(_plots(), method="nope")
    with pytest.raises(InputError, match="association: must be gnn or jpda"):
        seatrack.track(_plots(), association="nn")
    sensor = seatrack.Sensor(sigma_range_m=5.0)
    with pytest.raises(ConfigError, match="both in the config and as sensor="):
        seatrack.track(_plots(), sensor=sensor, config={"sigma_range_m": 3.0})
    with pytest.raises(InputError, match="expected a file path, a pandas DataFrame"):
        seatrack.track(42)


def test_sensor_given_as_argument_equals_the_same_config_keys():
    sensor = seatrack.Sensor(sigma_range_m=5.0, sigma_azimuth_deg=0.1)
    a = seatrack.track(_plots(), sensor=sensor)
    b = seatrack.track(
        _plots(), config={"sensor": {"sigma_range_m": 5.0, "sigma_azimuth_deg": 0.1}}
    )
    pd.testing.assert_frame_equal(a, b)
    c = seatrack.track(_plots())
    assert not np.array_equal(a["std_x_m"].to_numpy(), c["std_x_m"].to_numpy())


@pytest.mark.parametrize(
    "module",
    [
        "seatrack.api.sensor",
        "seatrack.api.track",
        "seatrack.api.tma",
        "seatrack.api.simulate",
        "seatrack.api.evaluate",
        "seatrack.api.ais",
        "seatrack.api.navigate",
    ],
)
def test_docstring_examples_run(module):
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
