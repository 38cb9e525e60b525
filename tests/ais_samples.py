"""The real AIS samples in ../shared/data/ais (read its README for provenance; never edited),
shared by the AIS tests."""

from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "ais"
FILES = [
    "no_vestland_20220901.csv",
    "dk_northsea_20221101_1h_selected.csv",
    "dk_northsea_20221101_1h_all.csv",
    "dk_gothenburg_20170705_cpa.csv",
    "us_boston_201401_trajectools.csv",
]


def data_file(name: str) -> Path:
    """Path of sample ``name``; a clear failure when the shared folder is missing."""
    p = DATA / name
    assert p.is_file(), (
        f"real AIS test data missing: {p.resolve()} (expected the shared/ folder beside the "
        "repository, as in CI)"
    )
    return p
