"""Frequency (Doppler) and ATB rows: the model, analytic Jacobians against numerical ones
(one and several legs), the base-frequency elimination, observability with frequencies."""

import math
from dataclasses import replace

import numpy as np
import pytest

from seatrack.models import numerical_jacobian
from seatrack.simulate import Leg
from seatrack.simulate import trajectory
from seatrack.simulate.tma import scenario_from_trajectories
from seatrack.tma import Bearings
from seatrack.tma import solve
from seatrack.tma.legs import leg_index
from seatrack.tma.legs import leg_starts
from seatrack.tma.legs import leg_time_matrix
from seatrack.tma.measurements import BowAngles
from seatrack.tma.measurements import Frequencies
from seatrack.tma.measurements import bow_angle
from seatrack.tma.measurements import bow_angle_residuals
from seatrack.tma.measurements import doppler_ratio
from seatrack.tma.measurements import frequency_residuals
from seatrack.tma.measurements import observer_velocity
from seatrack.tma.problem import Problem

rng = np.random.default_rng(5)
T = np.linspace(0.0, 1800.0, 21)
OBS = np.stack([3.0 * T, 200.0 * np.sin(T / 400.0)], axis=1)
VOWN = np.stack([np.full(T.size, 3.0), 0.5 * np.cos(T / 400.0)], axis=1)
C_SOUND = 1500.0


def _beta(n_legs):
    b = [rng.uniform(3000, 9000), rng.uniform(-4000, 4000)]
    for _ in range(n_legs):
        b += list(rng.uniform(-6, 6, 2))
    return np.array(b)


def _rows(starts):
    E = np.zeros((T.size, starts.size + 1))
    E[np.arange(T.size), 1 + leg_index(T, starts)] = 1.0
    return leg_time_matrix(T, starts), E


def test_doppler_ratio_signs_and_formula():
    """Closing raises the frequency; the ratio is (c + v_own.u) / (c + v_tgt.u)."""
    d = np.array([1000.0, 0.0])  # target due East
    g, _, _ = doppler_ratio(d, np.array([5.0, 0.0]), np.array([-5.0, 0.0]), C_SOUND)
    assert g == pytest.approx((1500.0 + 5.0) / (1500.0 - 5.0))
    g, _, _ = doppler_ratio(d, np.zeros(2), np.array([5.0, 0.0]), C_SOUND)  # opening
    assert g < 1.0
    g, _, _ = doppler_ratio(d, np.zeros(2), np.array([0.0, 7.0]), C_SOUND)  # crossing
    assert g == pytest.approx(1.0)


def test_bow_angle_convention():
    """0 = heading at the own ship; own ship on the target's starboard side = positive."""
    d = np.array([0.0, 1000.0])  # target due North of the own ship
    assert bow_angle(d, np.array([0.0, -5.0])) == pytest.approx(0.0, abs=1e-12)
    assert abs(bow_angle(d, np.array([0.0, 5.0]))) == pytest.approx(math.pi)
    # target heading West: the own ship (South of it) is on its port side
    assert bow_angle(d, np.array([-5.0, 0.0])) == pytest.approx(-math.pi / 2)


@pytest.mark.parametrize("manoeuvres", [(), (700.0,), (500.0, 1100.0)])
def test_frequency_jacobian_matches_numerical(manoeuvres):
    starts = leg_starts(T[0], manoeuvres)
    C, E = _rows(starts)
    beta = _beta(starts.size)
    f0 = np.array([310.0])
    O = np.ones((T.size, 1))
    w = np.full(T.size, 1 / 0.05**2)

    def h(b):
        B = b.reshape(-1, 2)
        return f0[0] * doppler_ratio(C @ B - OBS, VOWN, E @ B, C_SOUND)[0]

    z = h(beta) + 0.03
    r, J, f0_out, g = frequency_residuals(beta, C, E, OBS, VOWN, z, w, O, f0, C_SOUND)
    assert np.allclose(r, 0.03)
    assert f0_out == pytest.approx(f0)
    # compared as d(f / f0) (values near 1) with a step of 1e-4 relative: the
    # Doppler ratio is nearly linear in the state, rounding dominates the truncation error
    Jn = numerical_jacobian(lambda b: h(b) / f0[0], beta, eps=1e-4)
    assert np.allclose(J / f0[0], Jn, rtol=1e-6, atol=1e-11)


@pytest.mark.parametrize("manoeuvres", [(), (900.0,)])
def test_bow_angle_jacobian_matches_numerical(manoeuvres):
    starts = leg_starts(T[0], manoeuvres)
    C, E = _rows(starts)
    beta = _beta(starts.size)

    def h(b):
        B = b.reshape(-1, 2)
        return bow_angle(C @ B - OBS, E @ B)

    r, J = bow_angle_residuals(beta, C, E, OBS, h(beta))
    assert np.allclose(r, 0.0, atol=1e-12)
    Jn = numerical_jacobian(h, beta, angular=np.ones(T.size, bool))
    assert np.allclose(J, Jn, rtol=1e-6, atol=1e-10)


def test_base_frequency_elimination_is_the_schur_complement():
    """Unknown f0 of two tonals: the residual is the weighted LS one, and the projected
    Gauss-Newton matrix equals the Schur complement of the joint information."""
    starts = leg_starts(T[0], (800.0,))
    C, E = _rows(starts)
    beta = _beta(2)
    tonal = np.where(np.arange(T.size) % 2 == 0, "a", "b")
    O = np.stack([tonal == "a", tonal == "b"], axis=1).astype(float)
    f0_true = np.array([120.0, 455.0])
    g = doppler_ratio(C @ beta.reshape(-1, 2) - OBS, VOWN, E @ beta.reshape(-1, 2), C_SOUND)[0]
    z = (O @ f0_true) * g + rng.normal(0, 0.05, T.size)
    w = rng.uniform(100, 600, T.size)
    nan = np.full(2, np.nan)
    r, J, f0, gg = frequency_residuals(beta, C, E, OBS, VOWN, z, w, O, nan, C_SOUND)
    for k in range(2):  # f0 minimises the weighted cost of its tonal
        m = O[:, k] > 0
        assert f0[k] == pytest.approx(np.sum(w[m] * z[m] * g[m]) / np.sum(w[m] * g[m] ** 2))
    _, J_plain, _, _ = frequency_residuals(beta, C, E, OBS, VOWN, z, w, O, f0, C_SOUND)
    Ja = np.concatenate([J_plain, gg[:, None] * O], axis=1)  # joint (beta, f0) Jacobian
    Ia = Ja.T @ (w[:, None] * Ja)
    n = beta.size
    schur = Ia[:n, :n] - Ia[:n, n:] @ np.linalg.solve(Ia[n:, n:], Ia[n:, :n])
    assert np.allclose(J.T @ (w[:, None] * J), schur, rtol=1e-8)
    # a known f0 is not projected: rows equal the plain Jacobian
    _, J_fixed, _, _ = frequency_residuals(beta, C, E, OBS, VOWN, z, w, O, f0_true, C_SOUND)
    assert not np.allclose(J_fixed, J)


def test_augmented_jacobian_matches_numerical():
    """Problem.augmented: the joint Jacobian w.r.t. (beta, f0) of bearings, frequencies, ATB."""
    starts = leg_starts(T[0], (800.0,))
    beta = _beta(2)
    C, E = _rows(starts)
    z = np.zeros(T.size)
    b = Bearings(
        T, z, OBS,
        frequencies=Frequencies(T, np.full(T.size, 200.0), OBS, VOWN, 0.1),
        bow_angles=BowAngles(T, z, OBS, 0.2),
    )  # fmt: skip
    prob = Problem.build(b, [], starts, 0.01)
    f0, Ja = prob.augmented(beta)
    assert Ja.shape == (3 * T.size, beta.size + 1)

    def h(theta):
        bb = theta[:-1].reshape(-1, 2)
        p, v = C @ bb, E @ bb
        from seatrack.geometry import bearing

        hb = bearing(*(p - OBS).T)
        hf = theta[-1] * doppler_ratio(p - OBS, VOWN, v, C_SOUND)[0] / 200.0
        return np.concatenate([hb, hf, bow_angle(p - OBS, v)])

    theta = np.concatenate([beta, f0])
    ang = np.r_[np.ones(T.size, bool), np.zeros(T.size, bool), np.ones(T.size, bool)]
    Ja[T.size : 2 * T.size] /= 200.0  # frequency rows compared as f / 200 Hz (values near 1)
    assert np.allclose(
        Ja, numerical_jacobian(h, theta, eps=1e-4, angular=ang), rtol=1e-6, atol=1e-11
    )


def test_observer_velocity_from_positions():
    t = np.array([0.0, 10.0, 20.0, 40.0])
    o = np.stack([2.0 * t, -1.0 * t + 5], axis=1)
    assert np.allclose(observer_velocity(t, o), [[2.0, -1.0]] * 4)


def _steady(target_start, course_deg, speed, n=61, dt=30.0):
    times = dt * np.arange(n)
    obs = trajectory([0, 0], 0.0, 5.0, [Leg.straight(times[-1] + 1)], times=times)
    tgt = trajectory(
        target_start, math.radians(course_deg), speed, [Leg.straight(times[-1] + 1)], times=times
    )
    return scenario_from_trajectories(tgt, obs, math.radians(1.0))


def test_steady_own_ship_frequency_makes_it_observable():
    sc = _steady([8000, 6000], 250.0, 6.0)
    r = np.random.default_rng(1)
    b = sc.bearings(r)
    only = solve(b)
    assert not only.observable
    assert only.determined == {
        "x": False, "y": False, "range": False, "bearing": True, "course": False, "speed": False
    }  # fmt: skip
    with_f = solve(replace(b, frequencies=sc.frequencies(r, 300.0, 0.05)))
    assert with_f.observable and with_f.converged
    assert all(with_f.determined.values())
    err = with_f.state - sc.state
    assert np.all(np.abs(err) < 4 * np.sqrt(np.diag(with_f.covariance)))
    assert abs(with_f.base_frequency[0] - 300.0) < 4 * with_f.sigma_base_frequency[0]
    assert set(with_f.nis) == {"bearing", "frequency"}


def test_radial_course_gives_no_doppler_change_and_stays_unobservable():
    """Target on a collision course (constant bearing, constant range rate): the bearings
    and the constant frequency fix neither range nor f0."""
    p0 = np.array([6000.0, 8000.0])
    u = p0 / np.linalg.norm(p0)
    v_t = np.array([0.0, 5.0]) - 4.0 * u  # own-ship velocity plus a closing radial speed
    sc = _steady(p0, math.degrees(math.atan2(v_t[0], v_t[1])), float(np.linalg.norm(v_t)))
    r = np.random.default_rng(2)
    b = replace(sc.bearings(r), frequencies=sc.frequencies(r, 300.0, 0.05))
    sol = solve(b, manoeuvres=None)
    assert not sol.observable
    assert not sol.determined["range"] and not sol.determined["f0:1"]
    assert sol.determined["bearing"]
    assert math.isnan(sol.last.range)


def test_solve_many_pads_frequency_rows_and_tonals():
    """Contacts with two tonals, one tonal and none in one batch: each solution equals the
    contact solved alone."""
    from seatrack.tma import solve_many

    sc = _steady([8000, 6000], 250.0, 6.0)
    r = np.random.default_rng(3)
    b = sc.bearings(r)
    f1, f2 = sc.frequencies(r, 300.0, 0.05, tonal="a"), sc.frequencies(r, 120.0, 0.05, tonal="b")
    two = Frequencies(
        np.r_[f1.t, f2.t[::2]], np.r_[f1.frequency, f2.frequency[::2]],
        np.r_[f1.observer, f2.observer[::2]],
        np.r_[f1.observer_velocity, f2.observer_velocity[::2]],
        np.r_[f1.sigma, f2.sigma[::2]], np.r_[f1.tonal, f2.tonal[::2]], {"b": 120.0},
    )  # fmt: skip
    contacts = {"two": replace(b, frequencies=two), "one": replace(b, frequencies=f1), "none": b}
    many = solve_many(contacts, manoeuvres=None)
    for cid, bb in contacts.items():
        alone = solve(bb, manoeuvres=None)
        assert np.allclose(many[cid].state, alone.state, rtol=1e-9, atol=1e-6)
        assert np.allclose(many[cid].base_frequency, alone.base_frequency)
    assert many["two"].tonals == ("a", "b")
    assert many["two"].base_frequency_fixed.tolist() == [False, True]
    assert many["two"].base_frequency[1] == 120.0 and many["two"].sigma_base_frequency[1] == 0
    assert "f0:b" not in many["two"].determined


def test_crb_of_a_mix_with_the_base_frequency_as_nuisance():
    from seatrack.information import SingularMatrixError
    from seatrack.tma import crb
    from seatrack.tma import position_crb

    sc = _steady([8000, 6000], 250.0, 6.0)
    fr = sc.frequencies(np.random.default_rng(0), 300.0, 0.05)
    obs = sc.observer.pos[:, :2]
    with pytest.raises(SingularMatrixError):  # bearings only, steady own ship
        crb(sc.state, sc.times, obs, sc.sigma)
    P = crb(sc.state, sc.times, obs, sc.sigma, frequencies=fr, base_frequency={"1": 300.0})
    assert P.shape == (5, 5) and np.all(np.linalg.eigvalsh(P) > 0)
    # a known f0 gives more information: a smaller state bound
    known = replace(fr, base_frequency={"1": 300.0})
    Pk = crb(sc.state, sc.times, obs, sc.sigma, frequencies=known, base_frequency={"1": 300.0})
    assert Pk.shape == (4, 4)
    assert np.trace(position_crb(Pk, sc.starts, 1800.0)) < np.trace(
        position_crb(P, sc.starts, 1800.0)
    )
    with pytest.raises(ValueError, match="true f0 of tonal"):
        crb(sc.state, sc.times, obs, sc.sigma, frequencies=fr)
