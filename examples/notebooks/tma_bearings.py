# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # Bearings-only TMA on a bearings array
#
# An observer on two legs (East, then North at 6 m/s) takes a bearing every 10 s of a
# target 10 km North moving East at 5 m/s; the bearings carry 0.3 degree noise.
# `seatrack.tma` estimates the target's position, course and speed with their
# uncertainty.

# %%
import numpy as np

import seatrack
from seatrack.geometry import bearing
from seatrack.geometry import bearing_rad_to_deg

rng = np.random.default_rng(3)
t = np.arange(0.0, 1201.0, 10.0)
ox = np.where(t < 600, 6.0 * t, 3600.0)
oy = np.where(t < 600, 0.0, 6.0 * (t - 600.0))
true_bearing = bearing(5.0 * t - ox, 10000.0 - oy)
measured = bearing_rad_to_deg(true_bearing + np.radians(0.3) * rng.standard_normal(t.size))

# %%
result = seatrack.tma(
    {"time_s": t, "bearing_deg": measured, "observer_x_m": ox, "observer_y_m": oy},
    sigma_deg=0.3,
    detect=False,
)
frame = result.to_frame()
frame[["contact", "x_m", "y_m", "vx_mps", "vy_mps", "last_range_m", "last_sigma_range_m"]]

# %% [markdown]
# The target started at (0, 10000) m with velocity (5, 0) m/s: the estimate lies within a
# few of its standard deviations.

# %%
sol = result["1"]
print(
    f"start ({sol['x_m']:.0f}, {sol['y_m']:.0f}) m, velocity ({sol['vx_mps']:.2f}, "
    f"{sol['vy_mps']:.2f}) m/s, observable {sol['observable']}"
)
assert sol["observable"] and sol["converged"]
assert abs(sol["vx_mps"] - 5.0) < 1.0 and abs(sol["y_m"] - 10000.0) < 1000.0
