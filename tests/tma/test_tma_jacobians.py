"""Numerical-Jacobian checks: bearing rows (one and several legs), support rows (linear and
squared, every kind, in multi-leg states) and the operator-value Jacobian."""

import numpy as np
import pytest

from seatrack.geometry import bearing
from seatrack.models import numerical_jacobian
from seatrack.tma.bounds import operator_values
from seatrack.tma.legs import leg_starts
from seatrack.tma.legs import leg_time_matrix
from seatrack.tma.legs import position_map
from seatrack.tma.problem import bearing_residuals
from seatrack.tma.support import SupportValue
from seatrack.tma.support import support_residuals
from seatrack.tma.support import support_rows

rng = np.random.default_rng(11)
T = np.linspace(0.0, 1800.0, 25)
OBS = np.stack([3.0 * T, 200.0 * np.sin(T / 400.0)], axis=1)


def _beta(n_legs):
    b = [rng.uniform(3000, 9000), rng.uniform(-4000, 4000)]
    for _ in range(n_legs):
        b += list(rng.uniform(-6, 6, 2))
    return np.array(b)


@pytest.mark.parametrize("manoeuvres", [(), (700.0,), (500.0, 1100.0)])
def test_bearing_jacobian_matches_numerical(manoeuvres):
    starts = leg_starts(T[0], manoeuvres)
    C = leg_time_matrix(T, starts)
    beta = _beta(len(starts))
    z = bearing(*(C @ beta.reshape(-1, 2) - OBS).T)  # noise-free bearings

    def h(b):  # predicted bearing = z - residual (unwrapped consistently)
        return bearing(*(C @ b.reshape(-1, 2) - OBS).T)

    r, J = bearing_residuals(beta, C, OBS, z)
    assert np.allclose(r, 0.0, atol=1e-12)
    Jn = numerical_jacobian(h, beta, angular=np.ones(T.size, bool))
    assert np.allclose(J, Jn, rtol=1e-6, atol=1e-10)


def test_single_leg_rows_are_the_spec_formula():
    """J_i = [R_y, -R_x, T R_y, -T R_x] / R^2 (spec "Model")."""
    starts = leg_starts(T[0])
    C = leg_time_matrix(T, starts)
    beta = _beta(1)
    d = C @ beta.reshape(-1, 2) - OBS
    R2 = d[:, 0] ** 2 + d[:, 1] ** 2
    spec = np.stack([d[:, 1], -d[:, 0], T * d[:, 1], -T * d[:, 0]], 1) / R2[:, None]
    _, J = bearing_residuals(beta, C, OBS, np.zeros(T.size))
    assert np.allclose(J, spec, rtol=1e-12)


def test_batched_residuals_equal_single():
    starts = leg_starts(T[0], (900.0,))
    C = leg_time_matrix(T, starts)
    betas = np.stack([_beta(2) for _ in range(3)])
    z = rng.uniform(0, 2 * np.pi, T.size)
    rb, Jb = bearing_residuals(betas, C, OBS, z)
    for k in range(3):
        r, J = bearing_residuals(betas[k], C, OBS, z)
        assert np.allclose(rb[k], r) and np.allclose(Jb[k], J)


@pytest.mark.parametrize("square", [False, True])
@pytest.mark.parametrize("manoeuvres", [(), (600.0, 1200.0)])
def test_support_jacobian_matches_numerical(square, manoeuvres):
    starts = leg_starts(T[0], manoeuvres)
    beta = _beta(len(starts))
    sup = [
        SupportValue("range", 100.0, 5000.0, 50.0, (10.0, -20.0)),
        SupportValue("range", 1500.0, 4000.0, 50.0, (4000.0, 30.0)),
        SupportValue("speed", 300.0, 4.0, 0.5),
        SupportValue("speed", 1700.0, 3.0, 0.5),
        SupportValue("course", 900.0, 1.0, 0.1),
        SupportValue("course", 1300.0, 6.0, 0.1),
    ]
    rows = support_rows(sup, starts, square)

    def f(b):
        r, _ = support_residuals(
            b.reshape(-1, 2), rows.kind, rows.A, rows.offset, rows.value, square
        )
        return -r  # residual = value - f(beta) (course wrapped)

    _, J = support_residuals(
        beta.reshape(-1, 2), rows.kind, rows.A, rows.offset, rows.value, square
    )
    ang = rows.kind == 3
    Jn = numerical_jacobian(f, beta, angular=ang)
    assert np.allclose(J, Jn, rtol=1e-6, atol=1e-9)
    # speed / course rows touch only the velocity of the leg their time falls in
    for i, v in enumerate(sup):
        if v.kind != "range":
            j = int(np.searchsorted(starts, v.t, side="right") - 1)
            nz = np.flatnonzero(J[i])
            assert set(nz) <= {2 + 2 * j, 3 + 2 * j}


def test_leg_time_function():
    """T'_ij = max(0, min(t_i - T_Aj, T_A(j+1) - T_Aj)) (spec eq. 15 / claim 14)."""
    starts = np.array([0.0, 100.0, 250.0])
    C = leg_time_matrix(np.array([0.0, 50.0, 100.0, 180.0, 400.0]), starts)
    expected = np.array(
        [
            [1, 0, 0, 0],
            [1, 50, 0, 0],
            [1, 100, 0, 0],
            [1, 100, 80, 0],
            [1, 100, 150, 150],
        ],
        dtype=float,
    )
    assert np.array_equal(C, expected)
    M = position_map(C[3])
    beta = np.arange(8.0)
    assert np.allclose(M @ beta, C[3] @ beta.reshape(-1, 2))


@pytest.mark.parametrize("manoeuvres", [(), (800.0,)])
def test_operator_values_jacobian(manoeuvres):
    starts = leg_starts(T[0], manoeuvres)
    beta = _beta(len(starts))
    t, o = 1500.0, np.array([1000.0, -300.0])
    vals, G = operator_values(beta, starts, t, o)
    Gn = numerical_jacobian(
        lambda b: operator_values(b, starts, t, o)[0], beta, angular=[0, 0, 0, 1, 1, 0]
    )
    assert np.allclose(G, Gn, rtol=1e-6, atol=1e-9)
    p = leg_time_matrix(np.array([t]), starts)[0] @ beta.reshape(-1, 2)
    assert np.allclose(vals[:2], p)
    assert np.isclose(vals[2], np.hypot(*(p - o)))
