"""The Debrief narrowband sample (tests/data/debrief, see its README): bearings and one
tonal's frequencies from an own ship with two turns, a target with two course changes,
solved with automatic leg detection and compared with the target's truth track."""

import math

import numpy as np
import pytest

from seatrack.geometry import course_speed
from seatrack.geometry import knots_to_mps
from seatrack.geometry import velocity_from_course
from seatrack.io.rep import read_rep
from seatrack.io.rep import read_tma_files
from seatrack.io.tma import MeasurementDefaults
from seatrack.tma import solve
from seatrack.tma.measurements import doppler_ratio

DATA = "tests/data/debrief/"


@pytest.fixture(scope="module")
def case():
    # the bearings are rounded to 0.1 deg and the frequencies to 1 mHz; the sigmas used are
    # larger than that rounding (0.1 deg, 0.1 Hz)
    inp, frame = read_tma_files(
        [DATA + "Freq_BlueSensor.rep", DATA + "Freq_BlueTrack.rep"],
        MeasurementDefaults(bearing=math.radians(0.1), frequency=0.1),
    )
    b = inp.contacts["SENSOR"]
    truth = read_rep([DATA + "Freq_RedTrack.rep"]).tracks["SUBJECT"]
    lat, lon = np.array(truth.lat_deg), np.array(truth.lon_deg)
    xy = frame.to_local(lat, lon)
    vel = velocity_from_course(
        np.array(truth.course) + frame.convergence(lat, lon), np.array(truth.speed_mps)
    )
    return b, np.array(truth.time_s), xy, vel, solve(b, manoeuvres="auto")


def test_debrief_sample_solved_against_truth(case):
    b, tt, xy, vel, sol = case
    assert sol.valid and sol.manoeuvres_detected
    # the target's course changes at 12:37:30 and 13:41:40 (truth file), found from the data
    assert np.allclose(sol.manoeuvres - b.t[0], [2250.0, 6100.0], atol=100.0)
    k = int(np.searchsorted(tt, b.t[-1]))
    rng = np.hypot(*(xy[k] - b.observer[-1]))
    err = np.hypot(*(sol.position_at(b.t[-1]) - xy[k]))
    assert err < 0.02 * rng  # issue target: final position within 2 % of range
    crs, spd = course_speed(*sol.state.reshape(-1, 2)[-1])
    true_crs, true_spd = course_speed(*vel[k])
    assert abs(math.remainder(crs - true_crs, 2 * math.pi)) < math.radians(5.0)
    assert abs(spd - true_spd) < float(knots_to_mps(0.5))


def test_debrief_base_frequency_matches_the_truth_tracks(case):
    """The files do not state f0; the truth tracks imply it: f / g(truth) at every sample."""
    b, tt, xy, vel, sol = case
    fr = b.frequencies
    i = np.searchsorted(tt, fr.t)
    g = doppler_ratio(xy[i] - fr.observer, fr.observer_velocity, vel[i], 1500.0)[0]
    implied = float(np.median(fr.frequency / g))
    assert implied == pytest.approx(150.0, abs=0.01)
    assert abs(sol.base_frequency[0] - implied) < 0.05  # issue target
