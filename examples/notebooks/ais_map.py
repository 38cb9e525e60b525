# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # A day of AIS to a map
#
# `seatrack.ais` cleans and smooths the tracks of every vessel of an AIS file (duplicates
# and impossible positions rejected, outliers flagged, tracks split at long gaps);
# `seatrack.api.ais.track_to_files` writes the same tracks with a GeoJSON file and an
# offline HTML map, as `seatrack ais --geojson --html` does. The file is a bundled sample
# of Danish Maritime Authority data (the approaches to Gothenburg, 5 July 2017).

# %%
import tempfile
from pathlib import Path

import seatrack
from seatrack.api.ais import ais_config
from seatrack.api.ais import track_to_files
from seatrack.data import ais_sample

source = ais_sample("dk_gothenburg_20170705_cpa.csv")
tracks = seatrack.ais(source, max_speed_kn=40.0)
tracks.groupby("mmsi").agg(
    reports=("lat", "size"), outliers=("outlier", "sum"), mean_speed_kn=("speed_kn", "mean")
)

# %%
folder = Path(tempfile.mkdtemp())
lines = track_to_files(
    [source],
    folder / "tracks.csv",
    ais_config(max_speed_kn=40.0),
    1 << 30,
    geojson=folder / "tracks.geojson",
    html=folder / "map.html",
)
print("\n".join(lines))
assert (folder / "map.html").stat().st_size > 0
assert (folder / "tracks.geojson").read_text().startswith("{")
