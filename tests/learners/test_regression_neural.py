"""Tests of nfs.learners.linear, nfs.learners.stepwise and nfs.learners.neural: cubic least squares,
stepwise regression, the BP and the RBF network.

Each test names its oracle."""

from __future__ import annotations


import numpy as np
import pytest
from sklearn.base import clone
from sklearn.preprocessing import PolynomialFeatures
from sklearn.utils.estimator_checks import parametrize_with_checks

from nfs.learners.linear import CubicLeastSquares
from nfs.learners.neural import BPNetwork, RBFNetwork
from nfs.learners.stepwise import StepwiseRegression, StepwiseStep
from nfs.errors import InputError

# Small max_iter / n_centers keep the ~200 estimator checks to a few seconds; the
# defaults pass the same checks (test_default_estimators_pass_checks, marked slow).
CHECKED = [
    CubicLeastSquares(),
    StepwiseRegression(),
    BPNetwork(max_iter=200),
    RBFNetwork(n_centers=10),
]
DEFAULTS = [CubicLeastSquares(), StepwiseRegression(), BPNetwork(), RBFNetwork()]


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")
@parametrize_with_checks(CHECKED)
def test_estimator_contract(estimator, check, sklearn_check):
    """Oracle: scikit-learn's own estimator checks (style practice 7).  None is marked
    xfail."""
    sklearn_check(check, estimator)


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")
@parametrize_with_checks(DEFAULTS)
def test_default_estimators_pass_checks(estimator, check, sklearn_check):
    """Oracle: scikit-learn's estimator checks, on the default hyperparameters."""
    sklearn_check(check, estimator)


# --------------------------------------------------------------------------------------
# Cubic least squares
# --------------------------------------------------------------------------------------

def _raw_cubic_case():
    """Noiseless drift [deg/h] as a known cubic in T [degC] and dT/dt [degC/s], at the
    scales of a start-up record (T from -40 to 70 degC)."""
    rng = np.random.default_rng(7)
    n = 300
    X = np.column_stack([rng.uniform(-40.0, 70.0, n), rng.uniform(-0.05, 0.05, n)])
    # exponents (T, dT/dt) -> coefficient; every other monomial of degree <= 3 is zero
    true = {(1, 0): 1e-2, (0, 1): 5.0, (2, 0): -2e-4, (1, 1): 2e-2, (3, 0): 3e-6,
            (1, 2): -0.8, (0, 3): 40.0}
    intercept = 0.3

    def f(X):
        return intercept + sum(k * X[:, 0] ** a * X[:, 1] ** b for (a, b), k in true.items())

    return X, f, true, intercept


def test_cubic_recovers_known_polynomial():
    """Oracle: a noiseless cubic is in the model's span, so least squares returns it
    exactly (to rounding, 1e-8 relative): predictions at new points and the coefficients
    expanded back to raw units (binomial theorem, raw_polynomial)."""
    X, f, true, intercept = _raw_cubic_case()
    model = CubicLeastSquares().fit(X, f(X))

    X_new = np.column_stack([np.linspace(-35.0, 65.0, 50), np.linspace(0.04, -0.04, 50)])
    y_new = f(X_new)
    np.testing.assert_allclose(model.predict(X_new), y_new,
                               rtol=0, atol=1e-8 * np.abs(y_new).max())

    powers, coef, b = model.raw_polynomial()
    assert b == pytest.approx(intercept, rel=1e-8)
    for row, k in zip(powers, coef):
        expected = true.get(tuple(int(p) for p in row), 0.0)
        # tolerance of each raw coefficient: 1e-8 of y's range per unit of the monomial
        term_range = np.abs(np.prod(X ** row, axis=1)).max()
        assert abs(k - expected) <= 1e-8 * np.abs(f(X)).max() / term_range, (row, k)


def test_cubic_one_feature_is_seed_000_model():
    """Oracle: Tao et al. (2019) section 4.1, B = k0 + k1 X + k2 X^2 + k3 X^3 -- one feature gives
    exactly the three powers, and the known coefficients come back."""
    x = np.linspace(-40.0, 70.0, 111)[:, None]
    k = [1.4e-3, 4.9e-4, -4.6e-6, 2.0e-8]
    y = k[0] + k[1] * x[:, 0] + k[2] * x[:, 0] ** 2 + k[3] * x[:, 0] ** 3
    model = CubicLeastSquares().fit(x, y)
    np.testing.assert_array_equal(model.powers_, [[1], [2], [3]])
    powers, coef, b = model.raw_polynomial()
    np.testing.assert_array_equal(powers, [[1], [2], [3]])
    np.testing.assert_allclose([b, *coef], k, rtol=1e-8)
    assert model.equation(3, "B").startswith("B = 0.0014 + 0.00049 x0 - 4.6e-06 x0^2")


def test_cubic_monomials_match_polynomial_features():
    """Oracle: sklearn.preprocessing.PolynomialFeatures enumerates the same monomials in
    the same order; without interactions only the pure powers remain."""
    X = np.random.default_rng(0).normal(size=(40, 3))
    y = X[:, 0]
    model = CubicLeastSquares().fit(X, y)
    reference = PolynomialFeatures(degree=3, include_bias=False).fit(X)
    np.testing.assert_array_equal(model.powers_, reference.powers_)
    np.testing.assert_array_equal(model.get_feature_names_out(),
                                  reference.get_feature_names_out())
    pure = CubicLeastSquares(include_interactions=False).fit(X, y)
    assert len(pure.powers_) == 3 * 3
    assert ((pure.powers_ > 0).sum(axis=1) == 1).all()


def test_cubic_ridge_shrinks_coefficients():
    """Oracle: a ridge penalty can only lower the coefficient norm (monotone in alpha)."""
    X, f, _, _ = _raw_cubic_case()
    y = f(X) + np.random.default_rng(1).normal(0.0, 1e-3, len(X))
    norms = [np.linalg.norm(CubicLeastSquares(alpha=a).fit(X, y).coef_)
             for a in (0.0, 1e-6, 1e-3, 1e-1)]
    assert all(a >= b for a, b in zip(norms, norms[1:]))


# --------------------------------------------------------------------------------------
# Stepwise regression
# --------------------------------------------------------------------------------------

def _stepwise_case(seed: int, n: int = 500, noise: float = 0.5):
    """y = 2 x0 + 0.5 x0 x1 + noise with 5 independent standard-normal features."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 5))
    y = 2.0 * X[:, 0] + 0.5 * X[:, 0] * X[:, 1] + noise * rng.normal(size=n)
    return X, y


def test_stepwise_picks_exactly_the_true_terms():
    """Oracle: the generating model's support {x0, x0 x1}.

    With degree 2 there are 20 candidates; at p_enter = 0.05 each forward step tests ~18
    null candidates, so a spurious entry is likely (the classic weakness of stepwise
    selection).  The test therefore uses a Bonferroni level, 0.05 / 20 to enter and
    0.10 / 20 to leave; the data are seeded, so the result is deterministic."""
    X, y = _stepwise_case(seed=0)
    model = StepwiseRegression(degree=2, p_enter=0.05 / 20, p_remove=0.10 / 20).fit(X, y)
    assert len(model.candidate_powers_) == 20
    assert set(model.selected_names_) == {"x0", "x0 x1"}
    assert [s.term for s in model.history_] == ["x0", "x0 x1"]  # strongest first
    assert all(isinstance(s, StepwiseStep) and s.action == "enter" for s in model.history_)
    assert (model.pvalues_ < 1e-20).all()
    # the selected terms' coefficients in raw units are the generating ones
    powers, coef, _ = model.raw_polynomial()
    fitted = {tuple(int(p) for p in row): k for row, k in zip(powers, coef)}
    assert fitted[(1, 0, 0, 0, 0)] == pytest.approx(2.0, abs=0.1)
    assert fitted[(1, 1, 0, 0, 0)] == pytest.approx(0.5, abs=0.1)
    # deterministic: a clone refitted gives the same selection and coefficients
    again = clone(model).fit(X, y)
    np.testing.assert_array_equal(again.selected_, model.selected_)
    np.testing.assert_array_equal(again.coef_, model.coef_)


def test_stepwise_default_levels_always_keep_the_true_terms():
    """Oracle: the true terms' partial F statistics are in the hundreds (n = 500), so at
    Tao et al.'s (2019) levels (0.05 / 0.10) they enter in every one of 20 seeded data sets
    (extra, spurious terms are allowed here)."""
    for seed in range(20):
        X, y = _stepwise_case(seed)
        model = StepwiseRegression().fit(X, y)
        assert {"x0", "x0 x1"} <= set(model.selected_names_), seed


def test_stepwise_noiseless_and_limits():
    """Oracle: noiseless data are fitted exactly by the true terms, after which nothing is
    left to explain (no further entry); max_terms = 1 keeps only the strongest term; a
    constant target selects nothing."""
    X, _ = _stepwise_case(seed=3, n=60)
    y = 2.0 * X[:, 0] + 0.5 * X[:, 0] * X[:, 1]
    model = StepwiseRegression().fit(X, y)
    assert set(model.selected_names_) == {"x0", "x0 x1"}
    np.testing.assert_allclose(model.predict(X), y, atol=1e-10)
    assert list(StepwiseRegression(max_terms=1).fit(X, y).selected_names_) == ["x0"]
    flat = StepwiseRegression().fit(X, np.full(len(X), 0.25))
    assert len(flat.selected_) == 0 and flat.intercept_ == pytest.approx(0.25)


def test_stepwise_removes_a_term_made_redundant():
    """Oracle: Efroymson's backward step on a case built for it.  y = x0 + x1 + noise and
    x2 = x0 + x1 + more noise: x2 has the largest correlation with y and enters first;
    once x0 and x1 are both in, x2 explains nothing more than the noise and must leave.
    Invariants checked besides: every entry had p < p_enter, every removal p > p_remove,
    and each final term has p <= p_remove."""
    rng = np.random.default_rng(11)
    n = 200
    x0, x1 = rng.normal(size=n), rng.normal(size=n)
    x2 = x0 + x1 + 0.3 * rng.normal(size=n)
    X = np.column_stack([x0, x1, x2])
    y = x0 + x1 + 0.1 * rng.normal(size=n)
    model = StepwiseRegression(degree=1).fit(X, y)
    actions = [(s.action, s.term) for s in model.history_]
    assert actions[0] == ("enter", "x2")
    assert ("remove", "x2") in actions
    assert set(model.selected_names_) == {"x0", "x1"}
    for s in model.history_:
        assert (s.p_value < 0.05) if s.action == "enter" else (s.p_value > 0.10)
    assert (model.pvalues_ <= 0.10).all()


def test_stepwise_explicit_library_and_bad_levels():
    """Oracle: an explicit exponent array is used as the library as given; p_enter above
    p_remove (Efroymson's F_in < F_out, a possible endless cycle) is refused."""
    X, y = _stepwise_case(seed=0)
    library = np.array([[1, 0, 0, 0, 0], [0, 0, 1, 0, 0], [1, 1, 0, 0, 0]])
    model = StepwiseRegression(candidates=library).fit(X, y)
    assert set(model.selected_names_) == {"x0", "x0 x1"}
    with pytest.raises(InputError, match="p_enter"):
        StepwiseRegression(p_enter=0.2, p_remove=0.1).fit(X, y)
    with pytest.raises(InputError, match="candidates"):
        StepwiseRegression(candidates="cubic").fit(X, y)


# --------------------------------------------------------------------------------------
# Neural networks
# --------------------------------------------------------------------------------------

def _sine():
    """sin(x) on x in [0, 2 pi]: 200 training points, 333 test points in between."""
    x = np.linspace(0.0, 2.0 * np.pi, 200)[:, None]
    x_test = np.linspace(0.01, 2.0 * np.pi - 0.01, 333)[:, None]
    return x, np.sin(x[:, 0]), x_test, np.sin(x_test[:, 0])


@pytest.mark.parametrize("estimator, rms_max", [
    (BPNetwork(random_state=0), 0.03),
    (RBFNetwork(random_state=0), 0.02),
])
def test_network_fits_sine(estimator, rms_max):
    """Oracle: the closed form sin(x).  A 10-unit tanh MLP and a 20-centre Gaussian RBF
    network are universal approximators; the bounds (3 % and 2 % of the amplitude RMS at
    unseen points) hold with margin for these seeds (measured 0.004-0.025 over BP seeds
    0-7 and 0.007 for the RBF network)."""
    x, y, x_test, y_test = _sine()
    model = clone(estimator).fit(x, y)
    rms = float(np.sqrt(np.mean((model.predict(x_test) - y_test) ** 2)))
    assert rms < rms_max


@pytest.mark.parametrize("cls", [BPNetwork, RBFNetwork])
def test_network_random_state(cls):
    """Oracle: determinism -- an integer random_state fixes the initialisation (weights,
    k-means seeding), so two fits give identical predictions; another seed gives a
    different local solution (different predictions)."""
    x, y, x_test, _ = _sine()
    p1 = cls(random_state=1).fit(x, y).predict(x_test)
    p2 = cls(random_state=1).fit(x, y).predict(x_test)
    p3 = cls(random_state=2).fit(x, y).predict(x_test)
    np.testing.assert_array_equal(p1, p2)
    assert np.abs(p1 - p3).max() > 1e-9


def test_bp_standardises_the_target():
    """Oracle: invariance -- the network sees (y - mean) / std, so the model of a drift
    in deg/h scaled by 1e-3 and offset is the same model scaled and offset."""
    x, y, x_test, _ = _sine()
    a = BPNetwork(random_state=0).fit(x, y).predict(x_test)
    b = BPNetwork(random_state=0).fit(x, 1e-3 * y + 0.02).predict(x_test)
    np.testing.assert_allclose(b, 1e-3 * a + 0.02, rtol=0, atol=1e-9)


def test_rbf_width_rule():
    """Oracle: the documented rule sigma = width x mean distance between distinct centres
    (in standardised inputs), and the Gaussian of Cheng et al. (2015) eq. (15) at a centre is 1."""
    x, y, _, _ = _sine()
    model = RBFNetwork(n_centers=5, width=0.7, random_state=0).fit(x, y)
    c = model.centers_
    d = [np.linalg.norm(c[i] - c[j]) for i in range(5) for j in range(i + 1, 5)]
    assert model.width_ == pytest.approx(0.7 * np.mean(d), rel=1e-12)
    phi = model._hidden(c)
    np.testing.assert_allclose(np.diag(phi), 1.0)
    # fewer distinct samples than centres: one centre per distinct sample
    few = RBFNetwork(n_centers=20, random_state=0).fit(np.repeat([[0.0], [1.0], [2.0]], 4,
                                                                 axis=0), np.arange(12.0))
    assert few.centers_.shape == (3, 1)


# --------------------------------------------------------------------------------------
# Speed sanity
# --------------------------------------------------------------------------------------
