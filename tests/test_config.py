"""The one configuration layer: edge units, unknown keys, types, bounds."""

import dataclasses
import math
from dataclasses import dataclass

import pytest

from seatrack.config import Checked
from seatrack.config import ConfigError
from seatrack.config import describe
from seatrack.config import is_positive_integer
from seatrack.config import is_positive_number
from seatrack.config import param
from seatrack.config import parse_config
from seatrack.config import redefault
from seatrack.config import require
from seatrack.config import to_edge


@dataclass(frozen=True)
class Demo:
    q: float = param(1.0, unit="m^2/s^3", doc="accel PSD", min=0)
    sigma_azimuth: float = param(
        0.5, key="sigma_azimuth_deg", unit="deg", doc="az", min=0, exclusive_min=True
    )
    speed: float = param(10.0, key="speed_kn", unit="kn", aliases=("speed_knots",))
    mode: str = param("a", choices=("a", "b"))
    flag: bool = param(True)
    count: int = param(3, min=1)
    alphas: tuple[float, ...] = param((1.0, 2.0), unit="g")

    def __post_init__(self) -> None:
        if self.count > 100:
            raise ValueError("count must be <= 100")


def test_defaults_are_converted_to_si():
    c = Demo()
    assert c.sigma_azimuth == pytest.approx(math.radians(0.5))
    assert c.speed == pytest.approx(10 * 1852 / 3600)
    assert c.alphas == pytest.approx((9.80665, 2 * 9.80665))


def test_user_keys_field_names_and_aliases():
    c = parse_config(Demo, {"sigma_azimuth_deg": 2, "speed_knots": 1.0, "q": 3})
    assert c.sigma_azimuth == pytest.approx(math.radians(2))
    assert c.speed == pytest.approx(1852 / 3600)
    assert c.q == 3.0
    # the SI field name takes an SI value
    assert parse_config(Demo, {"sigma_azimuth": 0.1}).sigma_azimuth == 0.1


def test_round_trip_to_edge():
    c = parse_config(Demo, {"sigma_azimuth_deg": 2.5, "alphas": [3, 4]})
    assert parse_config(Demo, to_edge(c)) == c


@pytest.mark.parametrize(
    "table, message",
    [
        ({"sigma_rnage_m": 1}, "unknown key 'sigma_rnage_m'; valid keys: alphas, count"),
        ({"q": "abc"}, "f.toml: q: expected a number, got 'abc'"),
        ({"q": True}, "q: expected a number"),
        ({"q": float("nan")}, "q: must be finite"),
        ({"q": -1}, "q: must be >= 0"),
        ({"sigma_azimuth_deg": 0}, "sigma_azimuth_deg: must be > 0"),
        ({"mode": "c"}, "mode: must be one of a, b"),
        ({"flag": 1}, "flag: expected true or false"),
        ({"count": 2.5}, "count: expected an integer"),
        ({"count": 101}, "f.toml: count must be <= 100"),
        ({"speed_kn": 1, "speed_knots": 2}, "set the same parameter"),
        ({"alphas": 3}, "alphas: expected a list"),
    ],
)
def test_errors_name_file_and_key(table, message):
    with pytest.raises(ConfigError) as exc:
        parse_config(Demo, table, source="f.toml")
    assert message in str(exc.value)
    assert str(exc.value).startswith("f.toml: ")


def test_ignore_and_base():
    base = parse_config(Demo, {"q": 5})
    c = parse_config(Demo, {"count": 4, "other": 1}, base=base, ignore=("other",))
    assert (c.q, c.count) == (5.0, 4)


def test_describe_lists_edge_defaults():
    rows = {r[0]: r for r in describe(Demo)}
    assert rows["sigma_azimuth_deg"][1] == pytest.approx(0.5)
    assert rows["sigma_azimuth_deg"][2] == "deg"


def test_redefault_changes_only_the_default_in_edge_units():
    @dataclass(frozen=True)
    class Faster(Demo):
        speed: float = redefault(Demo, "speed", 20.0)

    assert Faster().speed == pytest.approx(20.0 * 1852.0 / 3600.0)
    assert Faster().sigma_azimuth == Demo().sigma_azimuth
    assert parse_config(Faster, {"speed_knots": 5.0}).speed == pytest.approx(5 * 1852 / 3600)
    meta = {f.name: f.metadata for f in dataclasses.fields(Faster)}
    assert meta["speed"] == {f.name: f.metadata for f in dataclasses.fields(Demo)}["speed"]


def test_checked_runs_the_bounds_and_then_the_subclass_check():
    @dataclasses.dataclass(frozen=True)
    class Limits(Checked):
        low: float = param(1.0, key="low_deg", unit="deg", min=0)
        high: float = param(2.0, key="high_deg", unit="deg", min=0)

        def __post_init__(self) -> None:
            super().__post_init__()
            if self.low > self.high:
                raise ValueError("low_deg must not exceed high_deg")

    assert Limits().low == pytest.approx(math.radians(1.0))
    with pytest.raises(ConfigError, match=r"Limits\.low \(low_deg\): must be >= 0 deg"):
        Limits(low=-0.1)
    with pytest.raises(ConfigError, match="must be finite"):
        Limits(high=math.nan)
    with pytest.raises(ValueError, match="must not exceed"):
        Limits(low=0.5, high=0.1)


def test_require_names_the_first_failing_field_and_its_value():
    @dataclasses.dataclass(frozen=True)
    class Budget:
        rows: int = 10
        share: float = 0.5
        scale: float = 1.0

        def __post_init__(self) -> None:
            require(self, ("rows",), lambda n: n >= 0, ">= 0", prefix="Budget.")
            require(self, ("share", "scale"), lambda v: 0.0 < v < 1.0, "in (0, 1)")

    assert Budget(scale=0.5).rows == 10
    with pytest.raises(ValueError, match=r"^Budget\.rows must be >= 0, got -1$"):
        Budget(rows=-1, share=2.0)  # the first check that fails
    with pytest.raises(ValueError, match=r"^share must be in \(0, 1\), got nan$"):
        Budget(share=math.nan, scale=0.5)
    with pytest.raises(ValueError, match=r"^scale must be in \(0, 1\), got 1.0$"):
        Budget()
    with pytest.raises(ConfigError, match=r"^c\.toml: scale must be in \(0, 1\), got 2.0$"):
        parse_config(Budget, {"scale": 2.0, "share": 0.5}, source="c.toml")


def test_positive_number_and_integer_tests():
    assert [is_positive_number(v) for v in (1e-300, 2, 0.0, -1.0, math.nan, math.inf)] == [
        True, True, False, False, False, False,
    ]  # fmt: skip
    assert [is_positive_integer(v) for v in (1, 3.0, 0, 1.5, -2)] == [
        True, True, False, False, False,
    ]  # fmt: skip
    with pytest.raises(ValueError, match="NaN"):
        is_positive_integer(math.nan)


def test_every_param_config_of_the_package_is_checked():
    """Each dataclass of seatrack with :func:`param` fields derives from Checked (found
    by the modules' text, so that a new config class is covered without a list)."""
    import importlib
    import inspect
    from pathlib import Path

    import seatrack

    src = Path(seatrack.__file__).parent
    found = []
    for path in sorted(src.rglob("*.py")):
        if "= param(" not in path.read_text(encoding="utf-8") or path.name == "config.py":
            continue
        rel = path.relative_to(src.parent).with_suffix("")
        module = importlib.import_module(".".join(rel.parts).removesuffix(".__init__"))
        for _, cls in inspect.getmembers(module, inspect.isclass):
            if cls.__module__ != module.__name__ or not dataclasses.is_dataclass(cls):
                continue
            if any("factor" in f.metadata for f in dataclasses.fields(cls)):
                found.append(cls)
                assert issubclass(cls, Checked), cls
    assert len(found) >= 20
