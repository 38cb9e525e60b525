# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # One filter on a plot file
#
# `seatrack.simulate` writes the bundled `demo` scenario's radar plots (two targets,
# labelled by a `track` column); `seatrack.track` runs one method over every track of the
# file, as `seatrack track plots.csv --method imm` does.

# %%
import tempfile
from pathlib import Path

import numpy as np

import seatrack

folder = Path(tempfile.mkdtemp())
sim = seatrack.simulate("demo")
sim["plots_radar"].to_csv(folder / "plots.csv", index=False)
sim["plots_radar"].head()

# %%
sensor = seatrack.Sensor(sigma_range_m=20.0, sigma_azimuth_deg=0.3, sigma_range_rate_mps=1.0)
track = seatrack.track(folder / "plots.csv", method="imm", sensor=sensor)
track[["track", "time_s", "x_m", "y_m", "vx_mps", "vy_mps", "std_x_m", "status"]].tail()

# %% [markdown]
# The position error against the simulated truth, per target (the truth is sampled every
# second; the plots every two).

# %%
truth = sim["truth"]
for name, est in track.groupby("track"):
    tr = truth[truth["target"] == name].set_index("time_s").loc[est["time_s"]]
    err = np.hypot(
        est["x_m"].to_numpy() - tr["x_m"].to_numpy(), est["y_m"].to_numpy() - tr["y_m"].to_numpy()
    )
    print(f"{name}: RMS position error {np.sqrt(np.mean(err[5:] ** 2)):.1f} m")
    assert np.sqrt(np.mean(err[5:] ** 2)) < 200.0
