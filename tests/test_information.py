"""seatrack.information: the explicit scaled rank test and checked inverses.

Every matrix here is built so that its rank decision is unambiguous in floating point
(exact rank deficiency, or a scaled smallest singular value many orders of magnitude away
from the tolerance), so the tests do not depend on the BLAS/LAPACK build.
"""

import numpy as np
import pytest

from seatrack.information import JACOBIAN_RTOL
from seatrack.information import SingularMatrixError
from seatrack.information import as_float64
from seatrack.information import check_information
from seatrack.information import check_jacobian
from seatrack.information import covariance_from_jacobian
from seatrack.information import fisher_information
from seatrack.information import invert_information
from seatrack.information import invert_jacobian_information
from seatrack.information import whiten

# columns scaled by wildly different units (m, km/s, mrad ...): the decision must not move
UNITS = np.array([1e-6, 1.0, 1e3, 1e7])


def _jacobian(delta: float) -> np.ndarray:
    """4 columns; column 3 = column 0 + column 1 + delta * e_0 (delta = 0: exactly rank 3)."""
    J = np.array(
        [
            [1.0, 0.0, 1.0, 2.0],
            [0.0, 1.0, 1.0, -1.0],
            [2.0, 1.0, 3.0, 0.5],
            [1.0, 3.0, 4.0, 1.0],
            [0.0, 2.0, 2.0, 3.0],
        ]
    )
    J[0, 2] += delta
    return J


def test_exactly_rank_deficient_jacobian_is_refused_in_any_units():
    for scale in (np.ones(4), UNITS):
        J = _jacobian(0.0) * scale
        chk = check_jacobian(J)
        assert chk.rank == 3 and not chk.full_rank
        assert chk.smallest <= JACOBIAN_RTOL * chk.largest
        P, chk2 = covariance_from_jacobian(J)
        assert P is None and chk2.rank == 3
        with pytest.raises(SingularMatrixError, match="rank 3 of 4.*not observable"):
            invert_jacobian_information(J, np.ones(5), "test information")
        with pytest.raises(np.linalg.LinAlgError):  # the named error is a LinAlgError
            invert_jacobian_information(J, 2.0)


def test_nearly_rank_deficient_jacobian_decision_is_unambiguous():
    # delta 1e-14: scaled smallest singular value ~1e-15, five decades below the tolerance
    assert not check_jacobian(_jacobian(1e-14) * UNITS).full_rank
    # delta 1e-3: ~1e-4, six decades above it; the inverse is right in every unit system
    J = _jacobian(1e-3)
    chk = check_jacobian(J)
    assert chk.full_rank and chk.smallest > 1e4 * JACOBIAN_RTOL * chk.largest
    exact = np.linalg.inv(J.T @ J)
    for scale in (np.ones(4), UNITS):
        P = invert_jacobian_information(J * scale, np.ones(5))
        np.testing.assert_allclose(P * np.outer(scale, scale), exact, rtol=1e-9)
        c2 = check_jacobian(J * scale)
        assert c2.rank == 4 and np.isclose(c2.condition, chk.condition, rtol=1e-9)


def test_zero_column_and_too_few_rows_are_rank_deficiency():
    J = np.array([[1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])
    chk = check_jacobian(J)
    assert chk.rank == 1 and chk.smallest == 0.0 and chk.condition == np.inf
    assert check_jacobian(np.array([[1.0, 2.0, 3.0]])).rank == 1


def test_information_matrix_rank_test_is_scale_invariant():
    singular = np.array([[1.0, 2.0], [2.0, 4.0]])  # exactly rank 1
    near = np.array([[1.0, 1.0], [1.0, 1.0 + 1e-15]])  # scaled eigenvalue ~2.5e-16
    regular = np.array([[1.0, 1.0], [1.0, 1.0 + 1e-5]])  # scaled eigenvalue ~2.5e-6
    D = np.diag([1e-4, 1e5])
    for A in (singular, near):
        for M in (A, D @ A @ D):
            assert check_information(M).rank == 1
            with pytest.raises(SingularMatrixError, match="information"):
                invert_information(M)
    exact = np.array([[1.0 + 1e-5, -1.0], [-1.0, 1.0]]) / 1e-5
    Di = np.linalg.inv(D)
    for M, ref in ((regular, exact), (D @ regular @ D, Di @ exact @ Di)):
        assert check_information(M).full_rank
        np.testing.assert_allclose(invert_information(M), ref, rtol=1e-8)


def test_indefinite_zero_diagonal_and_non_finite_matrices():
    with pytest.raises(SingularMatrixError):
        invert_information(np.array([[1.0, 2.0], [2.0, 1.0]]))  # eigenvalues -1, 3
    chk = check_information(np.diag([1.0, 0.0, 2.0]))
    assert chk.rank == 2 and chk.smallest == 0.0
    with pytest.raises(SingularMatrixError, match="prior covariance"):
        invert_information(np.diag([1.0, 0.0]), "prior covariance")
    with pytest.raises(ValueError, match="non-finite"):
        check_information(np.array([[1.0, np.nan], [np.nan, 1.0]]))
    with pytest.raises(ValueError, match="non-finite"):
        check_jacobian(np.array([[1.0, np.inf]]))


def test_whitening_with_scalar_vector_and_matrix_weights():
    rng = np.random.default_rng(1)
    J = rng.standard_normal((6, 3))
    w = rng.uniform(0.5, 4.0, 6)
    ref = J.T @ np.diag(w) @ J
    np.testing.assert_allclose(fisher_information(J, w), ref, rtol=1e-12)
    np.testing.assert_allclose(fisher_information(J, np.diag(w)), ref, rtol=1e-12)
    np.testing.assert_allclose(whiten(J, 4.0), 2.0 * J)
    with pytest.raises(ValueError, match="weight vector"):
        whiten(J, np.ones(5))
    with pytest.raises(ValueError, match="weight matrix"):
        whiten(J, np.zeros((6, 6)))


def test_ill_conditioned_but_regular_jacobian_is_inverted_from_its_svd():
    """Singular values 1 .. 1e-7 (full rank for the 1e-10 tolerance): the inverse comes from
    the SVD of J itself and matches the exact one -- forming J^T J would square the
    condition number (1e14) and lose most digits."""
    rng = np.random.default_rng(3)
    U, _ = np.linalg.qr(rng.standard_normal((6, 4)))
    V, _ = np.linalg.qr(rng.standard_normal((4, 4)))
    sv = np.array([1.0, 0.5, 0.2, 1e-7])
    J = (U * sv) @ V.T
    exact = (V / sv**2) @ V.T  # (J^T J)^-1 = V S^-2 V^T
    for scale in (np.ones(4), UNITS):
        P, chk = covariance_from_jacobian(J * scale)
        assert chk.full_rank and chk.smallest < 1e-5 * chk.largest
        np.testing.assert_allclose(P * np.outer(scale, scale), exact, rtol=1e-6)


def test_as_float64_converts_and_does_not_copy_float64():
    a = as_float64([1, 2])
    assert a.dtype == np.float64 and a.tolist() == [1.0, 2.0]
    assert as_float64(a) is a
