# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # The multi-target tracker on NumPy arrays
#
# Three ships cross in front of a radar at the origin, with clutter; the plots carry no
# target label. `seatrack.track` on plots without a `track` column runs the multi-target
# tracker (automatic noise levels, existence-based confirmation) with the chosen data
# association, as `seatrack track` does on such a file.

# %%
import numpy as np

import seatrack
from seatrack.geometry import bearing
from seatrack.geometry import bearing_rad_to_deg

rng = np.random.default_rng(11)
scans = np.arange(0.0, 120.0, 2.0)
starts = np.array([[-3000.0, 4000.0], [3000.0, 5000.0], [0.0, 2000.0]])
velocities = np.array([[8.0, 0.0], [-7.0, -1.0], [0.0, 6.0]])
t, r, az = [], [], []
for k in scans:
    pos = starts + velocities * k
    pos = pos + 10.0 * rng.standard_normal(pos.shape)
    n_clutter = rng.poisson(3)
    clutter = rng.uniform(-6000, 6000, (n_clutter, 2))
    pts = np.vstack([pos, clutter])
    t += [k] * len(pts)
    r += list(np.hypot(pts[:, 0], pts[:, 1]))
    az += list(bearing_rad_to_deg(bearing(pts[:, 0], pts[:, 1])))
plots = {"time_s": np.array(t), "range_m": np.array(r), "azimuth_deg": np.array(az)}
print(f"{len(t)} plots in {scans.size} scans")

# %%
sensor = seatrack.Sensor(sigma_range_m=10.0, sigma_azimuth_deg=0.2)
tracks = {a: seatrack.track(plots, sensor=sensor, association=a) for a in ("gnn", "jpda")}
tracks["gnn"].groupby("track")[["time_s"]].agg(["min", "max", "count"])

# %% [markdown]
# ## A user's own associator
#
# The tracker is built from roles (`seatrack.tracking.roles`: associator, initiator,
# track manager). A greedy nearest-neighbour associator -- the likeliest gated pair
# first, each plot and track used once -- is a few lines; `seatrack.track` runs it in
# place of GNN / JPDA, every other role unchanged (docs/tracking.md explains the
# arguments).

# %%
from seatrack.tracking.existence import ipda_update
from seatrack.tracking.existence import probability
from seatrack.tracking.roles import UPDATED
from seatrack.tracking.roles import Association


class NearestNeighbour:
    """Greedy nearest neighbour: the likeliest gated pair first, each plot used once."""

    def associate(self, flt, pred, scan, hyp):
        plot, lr = np.full(len(pred), -1), np.full(len(pred), -np.inf)
        for k in np.argsort(-hyp.log_lr, kind="stable"):
            i, j = hyp.track[k], hyp.plot[k]
            if plot[i] < 0 and j not in plot and hyp.weight[k] > hyp.log_miss[i]:
                plot[i], lr[i] = j, hyp.log_lr[k]
        ti = np.flatnonzero(plot >= 0)
        upd = flt.update(pred.take(ti), scan.plots.take(plot[ti]))
        hit = np.zeros(len(pred), bool)
        hit[ti] = upd.status == UPDATED
        logit = ipda_update(hyp.logit, scan.log_miss_pg, np.where(hit, lr, -np.inf))
        scan.explained += float(probability(logit[hit]).sum())
        return Association(pred.put(ti, upd), np.where(hit, plot, -1), hit, logit)


tracks["nearest"] = seatrack.track(plots, sensor=sensor, association=NearestNeighbour())

# %% [markdown]
# Each association confirms the three ships; their last estimated positions:

# %%
for name, out in tracks.items():
    last = out[out["time_s"] == out["time_s"].max()]
    print(name, np.round(last[["x_m", "y_m"]].to_numpy()))
    confirmed = last[last["status"] == "confirmed"]
    assert len(confirmed) >= 3
