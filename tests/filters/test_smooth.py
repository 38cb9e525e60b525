"""RTS smoother: equal to the brute-force batch (least-squares) solution of a linear-Gaussian
track, and better than the filter on a simulated EKF track."""

from __future__ import annotations

import math

import numpy as np

from seatrack import kalman
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import plot_gaussian
from seatrack.filters.driver import run_tracks
from seatrack.filters.ekf import EKF
from seatrack.filters.ekf import EKFConfig
from seatrack.filters.smooth import rts_smooth
from seatrack.filters.smooth import smooth_track
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory


def _linear_track(seed: int, K: int = 12):
    rng = np.random.default_rng(seed)
    dts = rng.uniform(0.5, 3.0, K)
    q, r = 0.3, 4.0
    H = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    R = np.eye(2) * r
    m0 = np.array([10.0, -5.0, 1.0, 2.0])
    P0 = np.diag([25.0, 25.0, 4.0, 4.0])
    x = rng.multivariate_normal(m0, P0)
    z = []
    for k in range(K):
        if k:
            x = cv_transition(dts[k]) @ x + rng.multivariate_normal(
                np.zeros(4), cv_noise(dts[k], q)
            )
        z.append(H @ x + rng.normal(0, math.sqrt(r), 2))
    return dts, q, H, R, m0, P0, np.array(z)


def test_rts_equals_the_batch_least_squares_solution():
    for seed in range(3):
        dts, q, H, R, m0, P0, z = _linear_track(seed)
        K, n = len(z), 4
        xf, Pf = np.empty((K, n)), np.empty((K, n, n))
        xp, Pp, F = np.zeros((K, n)), np.zeros((K, n, n)), np.zeros((K, n, n))
        x, P = m0, P0
        for k in range(K):
            if k:
                F[k] = cv_transition(dts[k])
                x, P = kalman.predict(x, P, F[k], cv_noise(dts[k], q))
                xp[k], Pp[k] = x, P
            u = kalman.update(x, P, z[k], H, R)
            x, P = u.x, u.P
            xf[k], Pf[k] = x, P
        xs, Ps = rts_smooth(xf, Pf, xp, Pp, F)
        # brute force: the Gaussian posterior of all states from the whole information matrix
        A = np.zeros((K * n, K * n))
        b = np.zeros(K * n)
        A[:n, :n] += np.linalg.inv(P0)
        b[:n] += np.linalg.solve(P0, m0)
        Ri = np.linalg.inv(R)
        for k in range(K):
            s = slice(k * n, (k + 1) * n)
            A[s, s] += H.T @ Ri @ H
            b[s] += H.T @ Ri @ z[k]
            if k:
                Qi = np.linalg.inv(cv_noise(dts[k], q))
                G = np.hstack([-F[k], np.eye(n)])  # x_k - F x_{k-1}
                s2 = slice((k - 1) * n, (k + 1) * n)
                A[s2, s2] += G.T @ Qi @ G
        cov = np.linalg.inv(A)
        mean = cov @ b
        np.testing.assert_allclose(xs.ravel(), mean, rtol=1e-8, atol=1e-8)
        for k in range(K):
            s = slice(k * n, (k + 1) * n)
            np.testing.assert_allclose(Ps[k], cov[s, s], rtol=1e-7, atol=1e-9)


def test_smooth_track_improves_on_the_ekf():
    tr = trajectory([4000.0, 7000.0], 1.0, 12.0, [Leg.straight(400)], dt=2.0)
    sensor = SensorNoise(20.0, math.radians(0.5))
    ekf = EKF(EKFConfig(q=1e-3), sensor)
    err_f, err_s = [], []
    for seed in range(5):
        m = observe(
            tr, None, ["range", "azimuth"], NoiseModel([20.0, math.radians(0.5)]),
            np.random.default_rng(seed),
        )  # fmt: skip
        plots = Plots(tr.t, m.z[:, 0], m.z[:, 1])
        xs, Ps = smooth_track(ekf, plots, lambda p: plot_gaussian(p, sensor, 20.0))
        init = lambda p: plot_gaussian(p, sensor, 20.0)  # noqa: E731
        out = run_tracks(ekf, plots, np.zeros(len(plots), np.int64), init)
        mid = slice(20, -20)
        err_f.append(np.hypot(out["x_m"] - tr.pos[:, 0], out["y_m"] - tr.pos[:, 1])[mid])
        err_s.append(np.hypot(xs[:, 0] - tr.pos[:, 0], xs[:, 1] - tr.pos[:, 1])[mid])
        assert (np.linalg.eigvalsh(Ps) > 0).all()
        # smoothing never increases a variance
        assert (np.sqrt(Ps[:, 0, 0]) <= out["std_x_m"] + 1e-9).all()
    rf = np.sqrt(np.mean(np.square(err_f)))
    rs = np.sqrt(np.mean(np.square(err_s)))
    assert rs < 0.8 * rf
