"""The recursive-filter contract every tracking method honours.

One shape for every filter, so that filters compose: any filter can be a model of the IMM,
the per-track filter of the multi-target tracker, or a method of ``seatrack track``.

* :class:`Plots` -- a set of radar/sonar plots (SI units, radians): one track over time,
  one scan of many plots, or a batch aligned with a batch of tracks.
* :class:`TrackState` -- the explicit state of a *batch* of tracks (leading axis ``B``):
  mean ``x (B, n)``, covariance ``P (B, n, n)``, time ``t (B,)``, the normalised innovation
  squared and log-likelihood of the last update, a per-track :class:`PlotStatus`, and
  method-specific fields in ``aux`` (arrays with leading axis ``B``, or nested
  TrackStates, e.g. the model states of an IMM). A single track is a batch of one.
* :class:`RecursiveFilter` -- the protocol: ``initiate``, ``predict``, ``update``,
  ``innovation``, ``columns``. Filters hold configuration only; state goes in and out.

State layout: ``x`` starts with the Cartesian position and velocity in the order of
``state_names`` (``x, y, [z], vx, vy, [vz]``, then method-specific components such as
``w`` (turn rate) or accelerations), so that states of different filters can be mixed by
component name.

Bad plots never break a track: an update whose plot is non-finite, or whose innovation
covariance is not positive definite, or that would give a non-finite state, leaves that
track at its prediction with status :attr:`PlotStatus.REJECTED`; the other tracks of the
batch are updated normally (:func:`finish_update`).

The driver :func:`seatrack.filters.driver.run_tracks` runs a filter over every labelled
track of a file at once: step ``k`` processes the ``k``-th plot of all tracks that have one,
as one batch.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from collections.abc import Iterator
from collections.abc import Mapping
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
from enum import IntEnum
from typing import Any
from typing import ClassVar
from typing import Protocol
from typing import runtime_checkable

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack import kalman
from seatrack.config import Checked
from seatrack.config import param
from seatrack.filters.converted import convert_plots
from seatrack.filters.converted import polar_jacobian
from seatrack.geometry import spherical_to_cart
from seatrack.geometry import wrap_pi
from seatrack.models.measurement import RangeBearing
from seatrack.models.measurement import RangeBearingElevation
from seatrack.models.measurement import RangeRate
from seatrack.models.measurement import Stacked

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "PlotStatus",
    "Plots",
    "TrackState",
    "SensorNoise",
    "RecursiveFilter",
    "measurement_model",
    "measurement_noise",
    "plot_gaussian",
    "two_point_gaussian",
    "common_columns",
    "cartesian_names",
    "converted_positions",
    "accel_sigma_param",
    "conversion_param",
    "speed_sigma_param",
    "usable",
    "finish_update",
    "predicted",
    "step_times",
    "wrap_angles",
    "COMMON_COLUMNS",
    "CartesianState",
    "ConfiguredFilter",
    "STATE_COLUMNS",
]

#: Cartesian position and velocity columns (m, m/s): named alike in track outputs and
#: truth files (``seatrack.simulate.files.TRUTH_COLUMNS``) so that they can be compared
STATE_COLUMNS = ("x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps")
#: the columns every method writes, in this order (z columns NaN -- empty -- for 2-D plots)
COMMON_COLUMNS = (*STATE_COLUMNS, "std_x_m", "std_y_m", "std_z_m")


class PlotStatus(IntEnum):
    """What happened to a track at a plot (the ``status`` output column)."""

    UPDATED = 0  #: the plot updated the track
    INITIATED = 1  #: the track was started (or restarted) on this plot
    PREDICTED = 2  #: no plot: prediction only (coasting)
    REJECTED = 3  #: the plot was unusable or a gross error; the track kept its prediction

    @property
    def label(self) -> str:
        return self.name.lower()


# ---------------------------------------------------------------------------
# Plots
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Plots:
    """A set of plots, SI units and radians (leading axis = plot).

    Attributes
    ----------
    t : (N,) s
    range : (N,) m -- slant range
    azimuth : (N,) rad -- true azimuth / bearing, clockwise from North
    elevation : (N,) rad, or None for 2-D plots
    range_rate : (N,) m/s (positive opening), or None
    sensor : (N, 3) m -- sensor position East, North, Up
    sensor_vel : (N, 3) m/s -- sensor velocity
    line : (N,) int -- input line of each plot (-1 when not read from a file)
    track : (N,) str, or None -- track label of each plot (labelled files only)
    derived : per-plot quantities a filter computed once for all plots (leading axis
        ``N``; :meth:`RecursiveFilter.derive`), carried along by :meth:`take`
    """

    t: FloatArray
    range: FloatArray
    azimuth: FloatArray
    elevation: FloatArray | None = None
    range_rate: FloatArray | None = None
    sensor: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    sensor_vel: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    line: IntArray = field(default_factory=lambda: np.zeros(0, np.int64))
    track: NDArray[Any] | None = None
    derived: Mapping[str, NDArray[Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = int(np.shape(self.t)[0])
        # defaults: sensor at rest at the origin, no input lines
        if np.shape(self.sensor)[0] != n:
            object.__setattr__(self, "sensor", np.zeros((n, 3)))
        if np.shape(self.sensor_vel)[0] != n:
            object.__setattr__(self, "sensor_vel", np.zeros((n, 3)))
        if np.shape(self.line)[0] != n:
            object.__setattr__(self, "line", np.full(n, -1, np.int64))

    @property
    def is_3d(self) -> bool:
        return self.elevation is not None

    @property
    def label(self) -> str:
        """The track label of single-track plots ("" when unlabelled)."""
        return "" if self.track is None or len(self.track) == 0 else str(self.track[0])

    @property
    def has_range_rate(self) -> bool:
        return self.range_rate is not None

    @property
    def d(self) -> int:
        """Spatial dimensions of the plots (2 or 3)."""
        return 3 if self.elevation is not None else 2

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def take(self, idx: ArrayLike) -> Plots:
        """The plots at ``idx`` (an index array or boolean mask)."""
        ix = np.asarray(idx)

        def sub(a: Any) -> Any:
            return None if a is None else a[ix]

        return Plots(
            self.t[ix],
            self.range[ix],
            self.azimuth[ix],
            sub(self.elevation),
            sub(self.range_rate),
            self.sensor[ix],
            self.sensor_vel[ix],
            self.line[ix],
            sub(self.track),
            {k: v[ix] for k, v in self.derived.items()},
        )

    def horizontal(self) -> Plots:
        """2-D plots of these plots: horizontal range ``r cos(elevation)``, no elevation
        (for the methods that track in the horizontal plane only)."""
        if self.elevation is None:
            return self
        rng = self.range * np.cos(self.elevation)
        return dataclasses.replace(self, range=rng, elevation=None, derived={})

    def polar(self, range_rate: bool = True) -> FloatArray:
        """Measurement vectors ``(N, m)``: range, azimuth, [elevation], [range rate]."""
        cols = [self.range, self.azimuth]
        if self.elevation is not None:
            cols.append(self.elevation)
        if range_rate and self.range_rate is not None:
            cols.append(self.range_rate)
        return np.stack(cols, -1)

    def positions(self) -> FloatArray:
        """Plot positions ``(N, d)`` East, North[, Up] (polar -> Cartesian plus the sensor)."""
        el = self.elevation if self.elevation is not None else np.zeros_like(self.range)
        p = spherical_to_cart(self.range, self.azimuth, el) + self.sensor
        return np.asarray(p[:, : self.d])


# ---------------------------------------------------------------------------
# Track state
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class TrackState:
    """State of a batch of ``B`` tracks (every array has the leading axis ``B``).

    Attributes
    ----------
    t : (B,) s -- time the estimate refers to
    x : (B, n) -- mean, layout ``state_names`` of the filter (positions first)
    P : (B, n, n) -- covariance (symmetric positive definite)
    nis : (B,) -- normalised innovation squared of the last update (NaN otherwise)
    log_likelihood : (B,) -- log N(y; 0, S) of the last update (NaN otherwise)
    status : (B,) int8 -- :class:`PlotStatus` of the last step
    aux : method-specific fields: arrays ``(B, ...)`` or nested TrackStates
    """

    t: FloatArray
    x: FloatArray
    P: FloatArray
    nis: FloatArray
    log_likelihood: FloatArray
    status: NDArray[np.int8]
    aux: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def new(
        cls, t: ArrayLike, x: ArrayLike, P: ArrayLike, aux: Mapping[str, Any] | None = None
    ) -> TrackState:
        """A freshly initiated batch (status INITIATED, no NIS / likelihood yet)."""
        xx = np.asarray(x, dtype=float)
        B = xx.shape[0]
        tt = np.broadcast_to(np.asarray(t, dtype=float), (B,)).copy()
        nan = np.full(B, np.nan)
        status = np.full(B, PlotStatus.INITIATED, np.int8)
        return cls(tt, xx, np.asarray(P, dtype=float), nan, nan.copy(), status, dict(aux or {}))

    def __len__(self) -> int:
        return int(self.x.shape[0])

    def replace(self, **changes: Any) -> TrackState:
        """A copy with some fields replaced (``aux`` entries merge when given as a dict)."""
        if "aux" in changes:
            changes["aux"] = {**self.aux, **changes["aux"]}
        return dataclasses.replace(self, **changes)

    def map(self, fn: Callable[[NDArray[Any]], NDArray[Any]]) -> TrackState:
        """Apply ``fn`` to every array (recursively into nested states)."""
        aux = {k: (v.map(fn) if isinstance(v, TrackState) else fn(v)) for k, v in self.aux.items()}
        return TrackState(
            fn(self.t),
            fn(self.x),
            fn(self.P),
            fn(self.nis),
            fn(self.log_likelihood),
            fn(self.status),
            aux,
        )

    def take(self, idx: ArrayLike) -> TrackState:
        """The tracks at ``idx`` (index array or boolean mask), as a new batch."""
        ix = np.asarray(idx)
        return self.map(lambda a: a[ix])

    def put(self, idx: ArrayLike, other: TrackState) -> TrackState:
        """A copy of this batch with the tracks at ``idx`` replaced by ``other``."""
        ix = np.asarray(idx)
        return _zip(self, other, lambda a, b: _put(a, ix, b))

    def where(self, mask: ArrayLike, other: TrackState) -> TrackState:
        """Per track: ``other`` where ``mask`` is true, else this state."""
        m = np.asarray(mask, dtype=bool)
        return _zip(self, other, lambda a, b: np.where(_expand(m, a), b, a))

    @staticmethod
    def concat(states: Sequence[TrackState]) -> TrackState:
        """One batch from several (same filter, same layout)."""
        first = states[0]
        return _zip_many(states, lambda arrs: np.concatenate(arrs, axis=0), first)

    def iter_arrays(self) -> Iterator[NDArray[Any]]:
        """Every array of the state (recursively), e.g. for finiteness checks."""
        yield from (self.t, self.x, self.P, self.nis, self.log_likelihood, self.status)
        for v in self.aux.values():
            if isinstance(v, TrackState):
                yield from v.iter_arrays()
            else:
                yield v


def _expand(m: NDArray[np.bool_], a: NDArray[Any]) -> NDArray[np.bool_]:
    return m.reshape(m.shape + (1,) * (a.ndim - 1))


def _put(a: NDArray[Any], ix: NDArray[Any], b: NDArray[Any]) -> NDArray[Any]:
    out = a.copy()
    out[ix] = b
    return out


def _zip(
    a: TrackState, b: TrackState, fn: Callable[[NDArray[Any], NDArray[Any]], NDArray[Any]]
) -> TrackState:
    aux: dict[str, Any] = {}
    for k, v in a.aux.items():
        w = b.aux[k]
        aux[k] = _zip(v, w, fn) if isinstance(v, TrackState) else fn(v, w)
    return TrackState(
        fn(a.t, b.t),
        fn(a.x, b.x),
        fn(a.P, b.P),
        fn(a.nis, b.nis),
        fn(a.log_likelihood, b.log_likelihood),
        fn(a.status, b.status),
        aux,
    )


def _zip_many(
    states: Sequence[TrackState], fn: Callable[[list[NDArray[Any]]], NDArray[Any]], first: Any
) -> TrackState:
    aux: dict[str, Any] = {}
    for k, v in first.aux.items():
        parts = [s.aux[k] for s in states]
        aux[k] = _zip_many(parts, fn, v) if isinstance(v, TrackState) else fn(parts)
    return TrackState(
        fn([s.t for s in states]),
        fn([s.x for s in states]),
        fn([s.P for s in states]),
        fn([s.nis for s in states]),
        fn([s.log_likelihood for s in states]),
        fn([s.status for s in states]),
        aux,
    )


# ---------------------------------------------------------------------------
# The sensor section shared by every method
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class SensorNoise(Checked):
    """Measurement noise of the plots: the ``[sensor]`` section every method shares.

    One documented default for every method (a typical coastal / naval surveillance radar);
    give your sensor's nominal values -- they are all a method needs to work well.
    """

    # upper bounds: physical limits of any sensor (1,000 km, a half turn, 100 km/s), so
    # that an absurd value is an error naming the key, not an overflow in a method
    sigma_range: float = param(
        10.0, key="sigma_range_m", unit="m", doc="range noise std", min=0, exclusive_min=True,
        max=1e6,
    )  # fmt: skip
    sigma_azimuth: float = param(
        0.5, key="sigma_azimuth_deg", unit="deg", doc="azimuth noise std", min=0,
        exclusive_min=True, max=180.0,
    )  # fmt: skip
    sigma_elevation: float = param(
        0.5, key="sigma_elevation_deg", unit="deg", doc="elevation noise std", min=0,
        exclusive_min=True, max=90.0,
    )  # fmt: skip
    sigma_range_rate: float = param(
        1.0, key="sigma_range_rate_mps", unit="m/s", doc="range-rate noise std", min=0,
        exclusive_min=True, max=1e5,
    )  # fmt: skip

    def __post_init__(self) -> None:
        super().__post_init__()


def speed_sigma_param(default: float, aliases: Sequence[str] = ()) -> Any:
    """The ``initial_speed_sigma`` field every method's config has (key
    ``initial_speed_sigma_mps``): the velocity std per axis the initiator gives a new track."""
    return param(
        default,
        key="initial_speed_sigma_mps",
        unit="m/s",
        doc="velocity std of a new track (per axis)",
        min=1e-3,  # bounds: below, the inverse variance underflows; above, its square overflows
        max=1e5,
        aliases=aliases,
    )


def accel_sigma_param(key: str, psd: str) -> Any:
    """An acceleration-std field (m/s^2, default 0: none) whose PSD ``a^2 T`` is added each
    scan to the PSD field named ``psd`` -- what a target class sets so that the process
    noise follows the scan interval."""
    return param(
        0.0,
        key=key,
        unit="m/s^2",
        doc=f"acceleration std whose PSD a^2 T is added to {psd} each scan (a target sets it)",
        min=0,
        max=1e4,  # 1000 g: a larger value is a typo (its square would overflow)
    )


def conversion_param() -> Any:
    """The ``conversion`` field of the methods on converted plots."""
    return param(
        "unbiased", choices=("unbiased", "linearized"), doc="polar-to-Cartesian conversion"
    )


def cartesian_names(d: int) -> tuple[str, ...]:
    """``x, y, [z], vx, vy, [vz]``: the first components of every filter's state."""
    axes = ("x", "y", "z")[:d]
    return axes + tuple("v" + a for a in axes)


class CartesianState:
    """Base of the filters whose state is Cartesian position and velocity on ``d`` axes
    (:func:`cartesian_names`)."""

    d: int

    @property
    def state_names(self) -> tuple[str, ...]:
        return cartesian_names(self.d)


class ConfiguredFilter:
    """The constructor ``(config, sensor, d, range_rate)`` of a registered method: the
    configuration (default ``Config()``) and the plots' measurement noise (default
    :class:`SensorNoise`), ``d`` checked against ``dims``, range rate used when the plots
    carry it and the configuration's ``use_range_rate`` (if it has one) says so; then
    :meth:`_setup` builds the method's own fields."""

    Config: ClassVar[type]
    #: plot dimensions the method handles
    dims: ClassVar[tuple[int, ...]] = (2, 3)

    def __init__(
        self,
        config: Any = None,
        sensor: SensorNoise | None = None,
        d: int = 2,
        range_rate: bool = False,
    ) -> None:
        if d not in self.dims:
            raise ValueError(f"{type(self).__name__} tracks in {self.dims} dimensions, got {d}")
        self.config: Any = config if config is not None else self.Config()
        self.sensor = sensor or SensorNoise()
        self.d = d
        self.range_rate = bool(range_rate and getattr(self.config, "use_range_rate", False))
        self._setup()

    def _setup(self) -> None:
        """The method's fields, from ``config``, ``sensor``, ``d`` and ``range_rate``."""


def converted_positions(
    plots: Plots, sensor: SensorNoise, method: str
) -> tuple[FloatArray, FloatArray]:
    """Converted Cartesian plot positions ``(N, d)`` and covariances ``(N, d, d)``
    (:func:`seatrack.filters.converted.convert_plots`); absurd plots give non-finite
    values, without warnings."""
    with np.errstate(all="ignore"):
        cm = convert_plots(
            plots.range,
            plots.azimuth,
            plots.elevation,
            sensor.sigma_range,
            sensor.sigma_azimuth,
            sensor.sigma_elevation if plots.elevation is not None else None,
            sensor=plots.sensor,
            method=method,  # type: ignore[arg-type]
        )
    return cm.z, cm.R


def usable(z: FloatArray, hx: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Plots ``z (B, m)`` with every unusable (non-finite) one replaced by its prediction
    ``hx`` -- so that an update runs without warnings -- and the mask of the usable ones
    (pass it to :func:`finish_update` as ``ok``)."""
    ok = np.asarray(np.isfinite(z).all(-1), dtype=bool)
    return np.where(ok[:, None], z, np.where(np.isfinite(hx), hx, 0.0)), ok


def measurement_model(d: int, n: int, range_rate: bool) -> Any:
    """Polar measurement model of plots for a state with positions ``0..d-1`` and velocities
    ``d..2d-1`` in a state of size ``n``: range, azimuth, [elevation], [range rate]."""
    if d not in (2, 3):
        raise ValueError(f"plots are 2-D or 3-D, got d = {d}")
    base: Any = RangeBearing(n=n, pos=(0, 1)) if d == 2 else RangeBearingElevation(n=n)
    if not range_rate:
        return base
    rr = RangeRate(n=n, pos=tuple(range(d)), vel=tuple(range(d, 2 * d)))
    return Stacked([base, rr])


def measurement_noise(sensor: SensorNoise, d: int, range_rate: bool) -> FloatArray:
    """Diagonal measurement-noise covariance ``R`` matching :func:`measurement_model`."""
    sig = [sensor.sigma_range, sensor.sigma_azimuth]
    if d == 3:
        sig.append(sensor.sigma_elevation)
    if range_rate:
        sig.append(sensor.sigma_range_rate)
    return np.diag(np.square(sig))


# ---------------------------------------------------------------------------
# The protocol
# ---------------------------------------------------------------------------
@runtime_checkable
class RecursiveFilter(Protocol):
    """What every tracking filter provides. Configuration in the constructor, state in calls.

    Attributes
    ----------
    d : spatial dimensions of the plots it was built for (2 or 3).
    range_rate : whether its updates use the plots' range rate.
    state_names : component names of ``TrackState.x`` (``x, y, [z], vx, vy, [vz], ...``).
    """

    d: int
    range_rate: bool

    @property
    def state_names(self) -> tuple[str, ...]: ...

    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        """Start tracks at times ``t (B,)`` from Cartesian Gaussians ``x (B, 2d)`` =
        ``[position, velocity]`` and ``P (B, 2d, 2d)`` (see :func:`plot_gaussian`)."""
        ...

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        """Predict every track to its time ``t (B,)`` (``t >= state.t``; equal: no change)."""
        ...

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        """Update predicted tracks with one plot each (``len(plots) == len(state)``); sets
        ``nis``, ``log_likelihood`` and ``status`` (bad plots: REJECTED, track unchanged)."""
        ...

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        """Innovation ``y (B, m)`` (angles wrapped) and its covariance ``S (B, m, m)`` of
        one plot per predicted track, without updating: for gating and association."""
        ...

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        """Output columns, one value per track: :data:`COMMON_COLUMNS` then the method's own."""
        ...

    # Optional: ``derive(plots) -> dict[str, array]``, per-plot quantities that do not depend
    # on the state (e.g. converted positions), computed once for all plots of a file by
    # :func:`seatrack.filters.driver.run_tracks` and handed back in ``Plots.derived``; an
    # ``update`` / ``innovation`` must give the same result without them.


# ---------------------------------------------------------------------------
# Initiation: one plot or two plots -> Cartesian Gaussian
# ---------------------------------------------------------------------------
def _polar_position_cov(plots: Plots, sensor: SensorNoise) -> tuple[FloatArray, FloatArray]:
    """Cartesian positions ``(N, d)`` and their linearised covariances ``(N, d, d)``
    (``G R G^T`` with ``G`` the Jacobian of the polar-to-Cartesian conversion). An absurd
    plot gives non-finite values, never a warning: the caller rejects it."""
    d = plots.d
    sig = [sensor.sigma_range, sensor.sigma_azimuth, sensor.sigma_elevation][:d]
    with np.errstate(all="ignore"):
        p = plots.positions()
        G = polar_jacobian(plots.range, plots.azimuth, plots.elevation)
        C = (G * np.square(sig)[None, None, :]) @ np.swapaxes(G, -1, -2)
    return p, kalman.symmetrize(C)


def plot_gaussian(
    plots: Plots, sensor: SensorNoise, speed_sigma: float, range_rate: bool = True
) -> tuple[FloatArray, FloatArray]:
    """One-plot initiation: Cartesian ``x (N, 2d)`` and ``P (N, 2d, 2d)`` per plot.

    Position: the plot converted to Cartesian, with the linearised polar covariance.
    Velocity: zero with standard deviation ``speed_sigma`` (m/s) per axis -- except, with a
    range rate, along the line of sight, where it is the measured range rate plus the
    sensor's own radial velocity, with the range-rate variance.
    """
    d = plots.d
    p, C = _polar_position_cov(plots, sensor)
    N = len(plots)
    x = np.zeros((N, 2 * d))
    P = np.zeros((N, 2 * d, 2 * d))
    x[:, :d] = p
    P[:, :d, :d] = C
    Pv = np.broadcast_to(np.eye(d) * speed_sigma**2, (N, d, d)).copy()
    if range_rate and plots.range_rate is not None:
        with np.errstate(all="ignore"):  # an absurd plot: non-finite start, rejected
            u = p - plots.sensor[:, :d]
            u /= np.linalg.norm(u, axis=-1, keepdims=True)
            vr = plots.range_rate + np.einsum("ij,ij->i", u, plots.sensor_vel[:, :d])
            x[:, d:] = u * vr[:, None]
            uu = u[:, :, None] * u[:, None, :]
            Pv = Pv - uu * (speed_sigma**2 - sensor.sigma_range_rate**2)
    P[:, d:, d:] = Pv
    return x, P


def two_point_gaussian(
    first: Plots, second: Plots, sensor: SensorNoise
) -> tuple[FloatArray, FloatArray]:
    """Two-plot initiation (pairs ``first[i]``, ``second[i]``): position of the second plot,
    velocity from the difference over the time between them, covariance propagated from the
    two plots' Cartesian covariances (``x = [p2, (p2 - p1)/dt]``)."""
    d = first.d
    p1, C1 = _polar_position_cov(first, sensor)
    p2, C2 = _polar_position_cov(second, sensor)
    dt = (second.t - first.t)[:, None]
    if np.any(dt <= 0):
        raise ValueError("two-point initiation needs the second plot later than the first")
    N = len(first)
    x = np.concatenate([p2, (p2 - p1) / dt], -1)
    P = np.zeros((N, 2 * d, 2 * d))
    inv = 1.0 / dt[:, :, None]
    P[:, :d, :d] = C2
    P[:, :d, d:] = C2 * inv
    P[:, d:, :d] = C2 * inv
    P[:, d:, d:] = (C1 + C2) * inv**2
    return x, P


# ---------------------------------------------------------------------------
# Shared plumbing of the filters
# ---------------------------------------------------------------------------
def common_columns(x: FloatArray, P: FloatArray, d: int) -> dict[str, FloatArray]:
    """The :data:`COMMON_COLUMNS` from states whose first ``2d`` components are
    ``[position, velocity]``; for 2-D (``d = 2``) the z columns are NaN (written empty)."""
    N = x.shape[0]
    std = np.sqrt(np.maximum(np.diagonal(P, axis1=-2, axis2=-1), 0.0))
    nan = np.full(N, np.nan)
    return {
        "x_m": x[:, 0],
        "y_m": x[:, 1],
        "z_m": x[:, 2] if d == 3 else nan,
        "vx_mps": x[:, d],
        "vy_mps": x[:, d + 1],
        "vz_mps": x[:, d + 2] if d == 3 else nan,
        "std_x_m": std[:, 0],
        "std_y_m": std[:, 1],
        "std_z_m": std[:, 2] if d == 3 else nan,
    }


def wrap_angles(y: FloatArray, angular: FloatArray) -> FloatArray:
    """Wrap the components of innovations ``y (..., m)`` flagged in ``angular (m,)`` to
    ``(-pi, pi]``."""
    return np.where(np.asarray(angular) > 0, wrap_pi(y), y)


def step_times(state: TrackState, t: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Target times ``(B,)`` of a prediction and the intervals ``dt = t - state.t`` (s).

    Raises ``ValueError`` when a track would go back in time.
    """
    tt = np.broadcast_to(np.asarray(t, dtype=float), state.t.shape).copy()
    dt = tt - state.t
    if np.any(dt < 0):
        raise ValueError("predict: a track would go back in time")
    return tt, dt


def predicted(
    state: TrackState,
    t: FloatArray,
    x: FloatArray,
    P: FloatArray,
    aux: Mapping[str, Any] | None = None,
) -> TrackState:
    """A predicted batch: new ``t``, ``x``, ``P`` (and ``aux`` entries), status PREDICTED,
    no NIS / likelihood."""
    nan = np.full(len(state), np.nan)
    status = np.full(len(state), PlotStatus.PREDICTED, np.int8)
    return TrackState(t, x, P, nan, nan.copy(), status, {**state.aux, **(aux or {})})


def finish_update(
    prior: TrackState,
    x: FloatArray,
    P: FloatArray,
    nis: FloatArray,
    log_likelihood: FloatArray,
    t: FloatArray,
    aux: Mapping[str, Any] | None = None,
    ok: NDArray[np.bool_] | None = None,
) -> TrackState:
    """Assemble an updated batch, isolating bad plots.

    Tracks where ``ok`` is false, or where the update gave a non-finite state, covariance or
    likelihood, keep the ``prior`` (their prediction) with status REJECTED; the others get
    the update with status UPDATED. ``aux`` entries follow the same rule.
    """
    good = np.isfinite(log_likelihood) & np.isfinite(x).all(-1) & np.isfinite(P).all((-1, -2))
    if ok is not None:
        good &= ok
    if good.all():  # every plot updated its track: the usual scan
        status = np.full(good.shape, PlotStatus.UPDATED, np.int8)
        nis_o, ll_o = np.asarray(nis, dtype=float), np.asarray(log_likelihood, dtype=float)
        return TrackState(
            np.asarray(t, dtype=float), x, P, nis_o, ll_o, status, {**prior.aux, **(aux or {})}
        )
    status = np.where(good, PlotStatus.UPDATED, PlotStatus.REJECTED).astype(np.int8)
    nan = np.full(good.shape, np.nan)
    new = TrackState(
        np.asarray(t, dtype=float), x, P, np.where(good, nis, nan),
        np.where(good, log_likelihood, nan), status, {**prior.aux, **(aux or {})},
    )  # fmt: skip
    kept = prior.replace(nis=nan, log_likelihood=nan.copy(), status=status, t=new.t)
    return kept.where(good, new)
