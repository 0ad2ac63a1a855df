"""Neural-network drift models: the BP network of the FOG start-up paper and the RBF network of
Cheng et al. (2015).

Both map thermometer features X (n_samples, n_features) -- temperatures [degC], their
rates [degC/s], gradients [degC], T * dT/dt, ... -- to the FOG thermal drift y [deg/h] and
follow scikit-learn's estimator contract.  Inputs are standardised
inside, ``z_j = (x_j - mean_j) / scale_j`` (``mean_``, ``scale_``), so that features of
very different units share one set of weights or one kernel width.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist, pdist
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.cluster import KMeans
from sklearn.neural_network import MLPRegressor
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted

from .kernels import gaussian_kernel
from .linear import ridge_lstsq
from .validation import check_int, check_real, fit_scaling, validate

__all__ = [
    "BPNetwork",
    "RBFNetwork",
]

_SEED_HIGH = np.iinfo(np.int32).max
"""Exclusive upper bound of the integer seeds drawn from a resolved random_state."""


class BPNetwork(RegressorMixin, BaseEstimator):
    """Back-propagation (multilayer perceptron) drift model, the "BP" comparator of the FOG
    start-up paper.

    A feed-forward network with ``len(hidden_layer_sizes)`` hidden layers, trained by
    back-propagation of the squared error (scikit-learn's ``MLPRegressor``)::

        h_0 = z,   h_l = g(W_l h_{l-1} + b_l),   y_hat = y_mean_ + y_scale_ (w_out . h_L + b_out)

    with ``z`` the standardised inputs, ``g`` the activation, and the target standardised
    as well, ``(y - y_mean_) / y_scale_``: a drift of 1e-2 deg/h is far below the output
    scale at which the default initialisation and learning rate work.  The loss minimised
    is ``1/(2n) sum_i (t_i - t_hat_i)^2 + alpha/(2n) ||W||^2`` on the standardised target t.

    Parameters
    ----------
    hidden_layer_sizes : tuple of int, default=(10,)
        Neurons in each hidden layer [-].
    activation : {"tanh", "logistic", "relu", "identity"}, default="tanh"
        Hidden-layer activation g (tanh, the classic BP sigmoid centred on zero).
    solver : {"adam", "sgd", "lbfgs"}, default="adam"
        Weight update; "sgd" is textbook gradient-descent BP, "adam" its adaptive-step
        variant, "lbfgs" a full-batch quasi-Newton method (often best on a few hundred
        samples, but slower per iteration on large records).
    alpha : float, default=1e-4
        L2 penalty on the weights [-] (in standardised units).
    batch_size : int or "auto", default="auto"
        Minibatch size [samples] for "adam"/"sgd"; "auto" is min(200, n_samples).
    learning_rate_init : float, default=1e-2
        Initial step size [-] for "adam"/"sgd".
    max_iter : int, default=2000
        Largest number of epochs ("adam"/"sgd") or iterations ("lbfgs") [-].
    tol : float, default=1e-6
        Training stops when the loss improves by less than ``tol`` for
        ``n_iter_no_change`` consecutive epochs [-, standardised loss].
    n_iter_no_change : int, default=50
        See ``tol`` [epochs].  Larger than scikit-learn's 10: with tanh units a fit first
        sits tens of epochs on the plateau of the best linear model, and a patience of 10
        stopped there (RMS 0.42 on sin(x), x in [0, 2 pi]) for 6 of 8 seeds.
    early_stopping : bool, default=False
        Hold out ``validation_fraction`` of the samples and stop on its score instead of
        the training loss; off by default, so that every sample is used for training.
    validation_fraction : float, default=0.1
        Held-out share for ``early_stopping`` [-].
    random_state : int, RandomState or None, default=None
        Seed of the weight initialisation and of the minibatch shuffling; resolved in
        ``fit`` (an integer gives identical fits).

    Attributes
    ----------
    mean_, scale_ : ndarray, shape (``n_features_in_``,)
        Input standardisation [unit of each feature].
    y_mean_, y_scale_ : float
        Target standardisation [unit of y].
    mlp_ : sklearn.neural_network.MLPRegressor
        The fitted network (on standardised inputs and target); its ``coefs_`` and
        ``intercepts_`` are the W_l and b_l above.
    n_iter_ : int
        Iterations run [-].
    loss_ : float
        Final training loss [-, standardised target].
    n_features_in_, feature_names_in_
        As in scikit-learn.

    References
    ----------
    The FOG start-up paper (FOG start-up drift compensation of a north finder with SSA-tuned SVR),
    Table 2 and Table 3: the BP network is the comparison baseline (its architecture is
    not given there; one hidden layer of 10 tanh neurons is this package's choice).
    Rumelhart, Hinton & Williams (1986), Nature 323, 533-536 (back-propagation).
    """

    def __init__(self, hidden_layer_sizes=(10,), activation: str = "tanh",
                 solver: str = "adam", alpha: float = 1e-4, batch_size="auto",
                 learning_rate_init: float = 1e-2, max_iter: int = 2000, tol: float = 1e-6,
                 n_iter_no_change: int = 50, early_stopping: bool = False,
                 validation_fraction: float = 0.1, random_state=None):
        self.hidden_layer_sizes = hidden_layer_sizes
        self.activation = activation
        self.solver = solver
        self.alpha = alpha
        self.batch_size = batch_size
        self.learning_rate_init = learning_rate_init
        self.max_iter = max_iter
        self.tol = tol
        self.n_iter_no_change = n_iter_no_change
        self.early_stopping = early_stopping
        self.validation_fraction = validation_fraction
        self.random_state = random_state

    def fit(self, X, y):
        """Train on features X (n_samples, n_features) and drift y (n_samples,) [deg/h];
        returns self."""
        X, y = validate(self, X, y, reset=True)
        rng = check_random_state(self.random_state)
        self.mean_, self.scale_ = fit_scaling(X)
        self.y_mean_ = float(y.mean())
        y_scale = float(y.std())
        self.y_scale_ = y_scale if y_scale > 0.0 else 1.0
        self.mlp_ = MLPRegressor(
            hidden_layer_sizes=self.hidden_layer_sizes, activation=self.activation,
            solver=self.solver, alpha=self.alpha, batch_size=self.batch_size,
            learning_rate_init=self.learning_rate_init, max_iter=self.max_iter,
            tol=self.tol, n_iter_no_change=self.n_iter_no_change,
            early_stopping=self.early_stopping,
            validation_fraction=self.validation_fraction,
            random_state=int(rng.randint(_SEED_HIGH)), shuffle=True,
        )
        self.mlp_.fit((X - self.mean_) / self.scale_, (y - self.y_mean_) / self.y_scale_)
        self.n_iter_ = int(self.mlp_.n_iter_)
        self.loss_ = float(self.mlp_.loss_)
        return self

    def predict(self, X) -> np.ndarray:
        """Predicted drift [unit of the training target, e.g. deg/h] for X
        (n_samples, ``n_features_in_``)."""
        check_is_fitted(self, "mlp_")
        X = validate(self, X, reset=False)
        t = self.mlp_.predict((X - self.mean_) / self.scale_)
        return self.y_mean_ + self.y_scale_ * np.asarray(t, dtype=float).reshape(-1)


_KMEANS_N_INIT = 4
"""k-means restarts of :class:`RBFNetwork` (fixed, so a random_state fixes the centres)."""


class RBFNetwork(RegressorMixin, BaseEstimator):
    """Gaussian radial-basis-function network, the drift model of Cheng et al. (2015) (section 3).

    One hidden layer of K Gaussian units and a linear output (Cheng et al. (2015) eqs. (15)-(16),
    plus a bias)::

        phi_j(z) = exp(-||z - c_j||^2 / (2 sigma^2)),   j = 1 .. K
        y_hat    = intercept_ + sum_j w_j phi_j(z)

    on the standardised inputs z.  Cheng et al. (2015) adapts c_j, sigma_j and w_j by gradient
    descent (its eqs. (17)-(19)); this class uses the two-stage "hybrid" training of
    Moody & Darken (1989) instead, which has no local minima and is deterministic:

    1. centres c_j: k-means of the standardised training inputs (``KMeans`` with
       ``n_init=4``, seeded from ``random_state``), K = min(``n_centers``, number of
       distinct samples);
    2. one common width for every unit: ``sigma = width * d_mean``, with d_mean the mean
       Euclidean distance over all pairs of distinct centres (with a single centre, the
       mean distance of the samples to it; 1 if that is zero too).  This is the global
       variant of Moody & Darken's nearest-neighbour width heuristic;
    3. output weights w and intercept by ridge least squares,
       ``min ||y - b - Phi w||^2 + alpha n ||w||^2`` (intercept not penalised, the penalty
       scaled by the n samples so ``alpha`` does not depend on the record length).

    Parameters
    ----------
    n_centers : int, default=20
        Number K of Gaussian hidden units [-] (fewer if there are fewer distinct samples).
    width : float, default=1.0
        Width factor [-]: sigma = width x mean distance between centres (in standardised
        input units).  Larger is smoother.
    alpha : float, default=1e-6
        Ridge penalty of the output layer [-], relative to the mean square of a hidden
        activation (which lies in (0, 1]).
    random_state : int, RandomState or None, default=None
        Seed of k-means' initialisation; resolved in ``fit``.

    Attributes
    ----------
    mean_, scale_ : ndarray, shape (``n_features_in_``,)
        Input standardisation [unit of each feature].
    centers_ : ndarray, shape (K, ``n_features_in_``)
        Centres c_j [standardised input units].
    width_ : float
        Common width sigma [standardised input units].
    weights_ : ndarray, shape (K,)
        Output weights w_j [unit of y].
    intercept_ : float
        Output bias [unit of y].
    n_features_in_, feature_names_in_
        As in scikit-learn.

    References
    ----------
    Cheng et al. (2015): Cheng, Qi, Chen & Landry (2015), "Modification of an RBF ANN-based
    temperature compensation model of interferometric fiber optical gyroscopes", Sensors
    15, 11189-11207, section 3, eqs. (15)-(16) (inputs T, dT, T x dT, eq. (21)).
    Moody, J. & Darken, C. J. (1989), "Fast learning in networks of locally-tuned
    processing units", Neural Computation 1(2), 281-294 (k-means centres, widths from the
    spread of the centres, linear output layer).  The width rule has not been checked
    against Moody & Darken's text down to equation number.
    """

    def __init__(self, n_centers: int = 20, width: float = 1.0, alpha: float = 1e-6,
                 random_state=None):
        self.n_centers = n_centers
        self.width = width
        self.alpha = alpha
        self.random_state = random_state

    def fit(self, X, y):
        """Place the centres and solve the output layer for features X
        (n_samples, n_features) and drift y (n_samples,) [deg/h]; returns self."""
        check_int(self.n_centers, "n_centers", 1)
        check_real(self.width, "width", 0.0, low_open=True)
        check_real(self.alpha, "alpha", 0.0)
        X, y = validate(self, X, y, reset=True)
        rng = check_random_state(self.random_state)
        self.mean_, self.scale_ = fit_scaling(X)
        Z = (X - self.mean_) / self.scale_
        n_distinct = np.unique(Z, axis=0).shape[0]
        k = min(int(self.n_centers), n_distinct)
        kmeans = KMeans(n_clusters=k, n_init=_KMEANS_N_INIT,
                        random_state=int(rng.randint(_SEED_HIGH)))
        self.centers_ = kmeans.fit(Z).cluster_centers_
        d = pdist(self.centers_) if k > 1 else cdist(Z, self.centers_).ravel()
        d_mean = float(d.mean()) if d.size else 0.0
        self.width_ = float(self.width) * (d_mean if d_mean > 0.0 else 1.0)
        self.weights_, self.intercept_ = ridge_lstsq(self._hidden(Z), y, float(self.alpha))
        return self

    def _hidden(self, Z: np.ndarray) -> np.ndarray:
        """Gaussian activations phi_j(z) (n_samples, K), Cheng et al. (2015) eq. (15): the
        kernel of the kernel regressors (:func:`~nfs.learners.kernels.gaussian_kernel`)."""
        return gaussian_kernel(Z, self.centers_, self.width_)

    def predict(self, X) -> np.ndarray:
        """Predicted drift [unit of the training target, e.g. deg/h] for X
        (n_samples, ``n_features_in_``)."""
        check_is_fitted(self, "weights_")
        X = validate(self, X, reset=False)
        return self._hidden((X - self.mean_) / self.scale_) @ self.weights_ + self.intercept_
