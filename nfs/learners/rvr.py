"""Relevance vector regression: sparse Bayesian kernel regression (Tipping 2001).

Liang et al.'s (2021) drift model, there tuned by Harris hawks optimisation.  The basis
functions are the Gaussian kernel of :mod:`~nfs.learners.kernels` centred on the training
inputs, plus a bias.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg.lapack
from sklearn.exceptions import ConvergenceWarning
from sklearn.utils import gen_batches

from .kernels import PREDICT_BATCH, KernelRegressor, gaussian_kernel, kernel_from_sq_distances
from .validation import HyperparameterError, check_count, check_positive

__all__ = ["RVRRegressor"]


#: Diagonal loadings tried in turn when H = beta Phi^T Phi + diag(alpha) does not factorise
#: [multiples of n eps max_i H_ii, n the bases kept]: none first, then 1, 10, 100.
LOADINGS = (0.0, 1.0, 10.0, 100.0)


def _cholesky(PtP: np.ndarray, alpha: np.ndarray, beta: float) -> np.ndarray | None:
    """Lower Cholesky factor L of H = beta Phi^T Phi + diag(alpha) (H = L L^T; LAPACK potrf
    in place), or of H + delta I when H is numerically not positive definite, with the
    first loading delta of :data:`LOADINGS` (x n eps max_i H_ii) that factorises; None if
    none does.

    The loading regularises what the floating-point H cannot resolve: a nearly noiseless
    target drives beta to its cap (noise 1e-8 of the target's STD) and the kernel columns of
    one input are nearly collinear, so H's condition number exceeds 1/eps.  delta is at the
    level of H's rounding errors (Cholesky's backward error is ~n eps max H_ii, Higham 2002,
    Theorem 10.3), the same order as the eigenvalue floor (eps x the largest) of the eigen-
    decomposition it replaced, at a tenth of its cost.
    """
    return _loaded_cholesky(_evidence_h, PtP, alpha, beta)


def _evidence_h(PtP: np.ndarray, alpha: np.ndarray, beta: float) -> np.ndarray:
    """H = beta Phi^T Phi + diag(alpha), a new array."""
    H = beta * PtP
    H.reshape(-1)[::H.shape[0] + 1] += alpha      # a view of H's diagonal
    return H


def _loaded_cholesky(make_h, *args) -> np.ndarray | None:
    """Lower Cholesky factor of the symmetric positive semi-definite matrix ``make_h(*args)``
    (made anew for each attempt: LAPACK potrf factorises it in place), with the diagonal
    loadings of :data:`LOADINGS` tried in turn (x n eps max_i H_ii); None if none
    factorises.  :func:`_cholesky` for H, :func:`_low_rank_sweep` for the Woodbury core C."""
    scale = None
    for load in LOADINGS:
        H = make_h(*args)
        n = H.shape[0]
        diag = H.reshape(-1)[::n + 1]           # a view of H's diagonal
        if load:
            if scale is None:
                scale = n * np.finfo(float).eps * max(float(np.max(diag)),
                                                      np.finfo(float).tiny)
            diag += load * scale
        # H is exactly symmetric (a symmetric product plus a diagonal): its transpose is the
        # same matrix in Fortran order, which LAPACK factorises in place
        c, info = scipy.linalg.lapack.dpotrf(H.T, lower=True, clean=True, overwrite_a=True)
        if info == 0:
            return c
    return None


#: Order at and below which :func:`_lower_inverse` calls LAPACK's trtri directly.
TRTRI_LEAF = 64


def _lower_inverse(c: np.ndarray) -> tuple[np.ndarray, int]:
    """(L^-1, info) of a lower-triangular L (the Cholesky factor of :func:`_cholesky`, its
    upper triangle zero): info 0, or LAPACK trtri's info > 0 for a zero pivot.

    By blocks (L = [[A, 0], [B, C]], L^-1 = [[A^-1, 0], [-C^-1 B A^-1, C^-1]]), halving down
    to :data:`TRTRI_LEAF`: the off-diagonal blocks are matrix products, which BLAS runs
    two to three times faster than LAPACK's trtri runs the whole inverse at the orders of an
    RVR's sweeps (a 338 x 338 factor: 1.1 ms against 1.7 ms on one core).  The same inverse
    to rounding (max difference ~1e-16 of its largest entry).
    """
    n = c.shape[0]
    if n <= TRTRI_LEAF:
        # trtri writes only the lower triangle of its copy of c, whose upper triangle potrf
        # has already zeroed (clean=True), so np.tril (a mask built per call, a quarter of
        # this function's time in an HHO-RVR search) is a C-ordered copy: the products
        # downstream see the same memory layout, hence the same bits
        Li, info = scipy.linalg.lapack.dtrtri(c, lower=True)
        return np.ascontiguousarray(Li), info
    k = n // 2
    A, info = _lower_inverse(c[:k, :k])
    if info:
        return A, info
    C, info = _lower_inverse(c[k:, k:])
    if info:
        return C, info + k
    out = np.zeros((n, n))
    out[:k, :k] = A
    out[k:, k:] = C
    out[k:, :k] = -(C @ (c[k:, :k] @ A))
    return out, 0


def _eigen_posterior(PtP: np.ndarray, alpha: np.ndarray, beta: float
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(V, w) of H = beta Phi^T Phi + diag(alpha) = V diag(w) V^T with the eigenvalues
    floored at eps x the largest: the last resort when no loading of :func:`_cholesky`
    factorises."""
    H = beta * PtP
    H[np.diag_indices_from(H)] += alpha
    w, V = np.linalg.eigh(H)
    w = np.maximum(w, np.finfo(float).eps * max(w.max(), np.finfo(float).tiny))
    return V, w


#: Tolerance of :func:`_kernel_factor` on the kernel's unit diagonal [-]: the factor stops
#: when no remaining pivot exceeds it, so every entry of K - B B^T (positive semi-definite)
#: is at most 1e-8 in size (|dK_ij| <= sqrt(dK_ii dK_jj)).  Chosen against the noise the
#: evidence finds (6 % of the target's STD on the default table's folds, beta ~ 276) and
#: measured on the HHO-RVR searches of the default and ramp calibration tables: every
#: search makes the same candidates and chooses the same sigma as with the exact sweeps,
#: their validation scores within 2e-5 of themselves (1e-10: within 1e-6, the default's
#: searches 25 % costlier; 1e-6 moved two of the default's three chosen widths).
RANK_TOL = 1e-8
#: The sweeps work on the kernel's factor F (M, r) while r <= LOW_RANK_SHARE x M, the kept
#: bases M: a sweep then costs ~2 M r^2 against ~2/3 M^3 for H's factor and inverse, the
#: same at r = M / sqrt(3).
LOW_RANK_SHARE = 0.58


def _kernel_factor(K: np.ndarray) -> np.ndarray:
    """B (n, r) with K ~= B B^T: the pivoted Cholesky factor of the Gram matrix K (n, n)
    (LAPACK pstrf, P^T K P = L L^T, B = P L), stopped once no remaining pivot exceeds
    :data:`RANK_TOL`: K - B B^T is positive semi-definite with every entry below it.

    A Gaussian kernel that is wide against the spread of the inputs is numerically of low
    rank: one input (the ramp calibration's thermometer), r 4-20 of 350 for sigma 0.5-20
    standard deviations; the nine default features, r 120-220 of 338 at the widths the
    tuners choose (sigma 5-14), where the factor pays for the first, costliest sweeps.
    """
    c, piv, r, info = scipy.linalg.lapack.dpstrf(K, lower=1, tol=RANK_TOL)
    if info < 0:
        raise ValueError(f"LAPACK pstrf: argument {-info} is invalid")
    B = np.empty((K.shape[0], r))
    B[piv - 1] = np.tril(c[:, :r])
    return B


def _low_rank_basis(B: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(F, c, e2) with Phi^T Phi = F F^T, Phi^T t = F c and ||t - Phi w||^2 = e2 +
    ||c - F^T w||^2 for every w, F (n + 1, r + 1), for the RVR's basis Phi = [1, K] and
    K = B B^T (:func:`_kernel_factor`).

    Phi = Z W with Z = [1, B] (n, r + 1) and W = diag(1, B^T); Z = Q R (thin QR), so
    Phi = Q (R W), F = (R W)^T = [R[:, 0]^T; B R[:, 1:]^T], c = Q^T t, and e2 = ||t - Q c||^2
    is the part of t no weights can fit.
    """
    n = B.shape[0]
    Q, R = np.linalg.qr(np.hstack([np.ones((n, 1)), B]))
    F = np.empty((n + 1, R.shape[0]))
    F[0] = R[:, 0]
    F[1:] = B @ R[:, 1:].T
    c = Q.T @ t
    return F, c, float(np.sum((t - Q @ c) ** 2))


def _woodbury_core(G: np.ndarray, beta: float) -> np.ndarray:
    """C = I / beta + G^T G, a new array (:func:`_low_rank_sweep`)."""
    C = G.T @ G
    C.reshape(-1)[::C.shape[0] + 1] += 1.0 / beta
    return C


def _low_rank_sweep(F: np.ndarray, c: np.ndarray, alpha: np.ndarray, beta: float,
                    full: bool = False) -> tuple[np.ndarray, np.ndarray] | None:
    """The posterior of Tipping 2001 eq. (12)-(13) when Phi^T Phi = F F^T and Phi^T t = F c
    with F (M, r), r < M (:func:`_low_rank_basis`, the rows of the kept bases): (mu, g),
    g_i = 1 - alpha_i Sigma_ii, or (mu, Sigma) when ``full``; None when the r x r core
    does not factorise.

    By the Woodbury identity, with A = diag(alpha), G = A^-1/2 F and C = I / beta + G^T G
    (r x r, positive definite)::

        Sigma = A^-1 - A^-1/2 G C^-1 G^T A^-1/2,    g_i = ||(L^-1 G^T)_i||^2  (C = L L^T)
        mu = beta Sigma F c = A^-1/2 G C^-1 c        (as (C - G^T G) = I / beta)

    so a sweep costs O(M r^2) instead of the O(M^3) of H = beta F F^T + A, and g_i comes
    without the cancellation of 1 - alpha_i Sigma_ii.  Exact in exact arithmetic; it differs
    from :meth:`RVRRegressor._posterior_diag` on the same problem by rounding.
    """
    s = 1.0 / np.sqrt(alpha)
    G = F * s[:, None]
    L = _loaded_cholesky(_woodbury_core, G, beta)
    if L is None:
        return None
    # L^-1 [G^T, c] in one LAPACK trtrs call (scipy's solve_triangular checks and copies
    # its arguments at a cost that rivals the solve at these orders)
    m = G.shape[0]
    rhs = np.empty((G.shape[1], m + 1), order="F")
    rhs[:, :m] = G.T
    rhs[:, m] = c
    sol, _ = scipy.linalg.lapack.dtrtrs(L, rhs, lower=1, overwrite_b=1)
    E = sol[:, :m]                                       # L^-1 G^T
    mu = s * (E.T @ sol[:, m])
    if full:
        Es = E * s
        Sigma = -(Es.T @ Es)
        Sigma.reshape(-1)[::m + 1] += s * s
        return mu, Sigma
    return mu, np.einsum("ki,ki->i", E, E)


class RVRRegressor(KernelRegressor):
    """Relevance vector regression: sparse Bayesian kernel regression (Tipping 2001, JMLR 1,
    211-244, section 2; Liang et al.'s (2021) model, there tuned by Harris hawks optimisation).

    Written here by hand: no maintained scikit-learn-compatible RVR package exists.

    Model on the scaled problem (x~, t)::

        t = Phi w + noise,  noise ~ N(0, 1/beta),  Phi = [1, K(x~, x~_1), ..., K(x~, x~_N)]
        p(w_i | alpha_i) = N(0, 1/alpha_i)   (one precision per basis function, bias included)

    Posterior (Tipping 2001 eq. (12)-(13))::

        Sigma = (beta Phi^T Phi + diag(alpha))^-1,   mu = beta Sigma Phi^T t

    Evidence re-estimation (eq. (16)-(18))::

        g_i = 1 - alpha_i Sigma_ii,   alpha_i <- g_i / mu_i^2,
        1/beta <- ||t - Phi mu||^2 / (N - sum_i g_i)

    iterated from alpha_i = 1/N^2 and beta = 100 / var(t) (noise at a tenth of the target's
    standard deviation), pruning each basis function whose alpha_i exceeds
    ``alpha_threshold`` (its weight is then zero), until ``max |Delta log alpha_i|`` < ``tol``
    over the kept ones.  Prediction (eq. (21)-(22))::

        y(x) = phi(x)^T mu,   var(x) = 1/beta + phi(x)^T Sigma phi(x)

    mapped back as ``y_mean_ + y_scale_ y(x)`` and ``y_scale_ sqrt(var(x))``.  Not yet checked
    against Tipping 2001 down to the equation numbers above.

    A sweep solves eq. (12)-(13) one of two ways, the same posterior to the kernel's
    rounding: while the kernel matrix is numerically of low rank r against the kept bases M
    (its pivoted Cholesky factor to :data:`RANK_TOL`, r <= :data:`LOW_RANK_SHARE` x M), by
    the Woodbury identity on an r x r matrix (:func:`_low_rank_sweep`, O(M r^2)); otherwise
    by the Cholesky factor of H = beta Phi^T Phi + diag(alpha) and its inverse (O(M^3)).
    Tipping & Faul's (2003) fast sequential algorithm, which adds and deletes one basis at a
    time, was not tried: it converges to the evidence's maximum where these fits stop after
    ``max_iter`` sweeps (a different model), and at these orders (n ~ 400; a full sweep 2 ms
    of BLAS) its hundreds of small steps, a dozen NumPy calls each, are estimated to cost
    about what the sweeps do.

    Parameters
    ----------
    kernel : str, default "rbf"
        Basis kernel; only "rbf" (the Gaussian kernel, :func:`gaussian_kernel`), the one Liang et
        al. (2021) use.
    sigma : float, default 1.0
        Kernel width [standard deviations of the inputs when ``standardize``], > 0; the one
        hyperparameter Liang et al. (2021) tunes.
    max_iter : int, default 300
        Maximum number of re-estimation sweeps (>= 1).
    tol : float, default 1e-3
        Convergence threshold on ``max |Delta log alpha_i|`` [-].
    alpha_threshold : float, default 1e9
        Prune a basis function once its precision exceeds this [1/unit of t^2; t is the
        standardised target when ``standardize``].
    standardize : bool, default True
        Standardise the input columns, and centre the target and divide it by its standard
        deviation, so that ``alpha_threshold`` and the initial noise level mean the same
        whatever the units of y.

    Attributes
    ----------
    relevance_indices_ : array of int (n_rv,)
        Training-sample indices of the relevance vectors.
    relevance_vectors_ : array (n_rv, n_features)
        The relevance vectors (training inputs, as given).
    bias_used_ : bool
        Whether the bias basis function survived the pruning.
    alpha_ : array (n_basis,)
        Precisions of the kept basis functions (bias first when kept) [1/unit of t^2].
    beta_ : float
        Noise precision [1/unit of t^2].
    mu_ : array (n_basis,)
        Posterior mean weights [unit of t].
    Sigma_ : array (n_basis, n_basis)
        Posterior weight covariance [unit of t^2].
    x_mean_, x_scale_, y_mean_, y_scale_ : input and target scaling (see ``standardize``).
    n_iter_ : int
        Re-estimation sweeps made.
    converged_ : bool
        Whether the sweeps converged (else a ConvergenceWarning was issued: typically some
        alpha_i were still growing towards the threshold; their weights are ~0 already).
    n_features_in_ : int
    """

    _KERNELS = ("rbf",)

    def __init__(self, kernel: str = "rbf", sigma: float = 1.0, max_iter: int = 300,
                 tol: float = 1e-3, alpha_threshold: float = 1e9, standardize: bool = True):
        self.kernel = kernel
        self.sigma = sigma
        self.max_iter = max_iter
        self.tol = tol
        self.alpha_threshold = alpha_threshold
        self.standardize = standardize

    @staticmethod
    def _posterior(PtP: np.ndarray, Ptt: np.ndarray, alpha: np.ndarray, beta: float
                   ) -> tuple[np.ndarray, np.ndarray]:
        """mu and Sigma (Tipping 2001 eq. (12)-(13)) from Phi^T Phi and Phi^T t (Sigma from
        the Cholesky factor of :func:`_cholesky` by LAPACK potri)."""
        c = _cholesky(PtP, alpha, beta)
        info = -1
        if c is not None:
            inv, info = scipy.linalg.lapack.dpotri(c, lower=True, overwrite_c=True)
        if info == 0:
            Sigma = np.tril(inv) + np.tril(inv, -1).T
        else:
            V, w = _eigen_posterior(PtP, alpha, beta)
            Sigma = (V / w) @ V.T
        return beta * (Sigma @ Ptt), Sigma

    @staticmethod
    def _posterior_diag(PtP: np.ndarray, Ptt: np.ndarray, alpha: np.ndarray, beta: float
                        ) -> tuple[np.ndarray, np.ndarray]:
        """mu and the diagonal of Sigma, all that a re-estimation sweep needs: from the
        Cholesky factor H = L L^T of :func:`_cholesky`, Sigma_ii = sum_k (L^-1)_ki^2 and
        mu = beta L^-T L^-1 Phi^T t, without forming Sigma (the eigen-decomposition of
        :func:`_eigen_posterior` when no loading factorises)."""
        c = _cholesky(PtP, alpha, beta)
        info = -1
        if c is not None:
            Li, info = _lower_inverse(c)
        if info == 0:
            return beta * (Li.T @ (Li @ Ptt)), np.einsum("ki,ki->i", Li, Li)
        V, w = _eigen_posterior(PtP, alpha, beta)
        return beta * (V @ ((V.T @ Ptt) / w)), np.einsum("ik,ik->i", V / w, V)

    def fit(self, X, y, sq_distances=None):
        """Fit on features X (n_samples, n_features) and drift y (n_samples,). Returns self.

        ``sq_distances``: the (n_samples, n_samples) squared distances of the scaled training
        inputs, :meth:`~nfs.learners.kernels.KernelRegressor.training_sq_distances` of X,
        when a search already holds them (computed here otherwise; the same bits)."""
        X, y = self._validate_fit(X, y)
        if self.kernel not in self._KERNELS:
            raise HyperparameterError(
                f"unknown kernel {self.kernel!r}; valid: {', '.join(self._KERNELS)}")
        sigma = check_positive("sigma", self.sigma)
        max_iter = check_count("max_iter", self.max_iter)
        tol = check_positive("tol", self.tol)
        threshold = check_positive("alpha_threshold", self.alpha_threshold)
        Xs, t = self._fit_scaling(X, y, scale_y=True)
        n = Xs.shape[0]
        K = kernel_from_sq_distances(self._train_sq_distances(Xs, sq_distances), sigma)
        # Phi^T Phi through the kernel's low-rank factor F while that is cheaper (r + 1 at
        # most LOW_RANK_SHARE of the kept bases), then the kept bases' own blocks of Phi^T Phi
        # and Phi^T t; Phi = [1, K] itself only when the factor never pays
        B = _kernel_factor(K)
        low = B.shape[1] + 1 <= LOW_RANK_SHARE * (n + 1)
        if low:
            F, c, e2 = _low_rank_basis(B, t)
            Phi_kept = PtP = Ptt = None
        else:
            F = None
            Phi_kept = np.hstack([np.ones((n, 1)), K])
            # formed once; cut down as bases are pruned
            PtP, Ptt = Phi_kept.T @ Phi_kept, Phi_kept.T @ t
        tiny = np.finfo(float).tiny
        eps = np.finfo(float).eps

        # the kept bases: their indices (column 0 is the bias), precisions, rows of F (or
        # columns of Phi), blocks of Phi^T Phi and Phi^T t once formed, cut when one is pruned
        keep = np.arange(n + 1)
        alpha = np.full(n + 1, 1.0 / n**2)
        var_t = max(float(np.var(t)), eps)
        beta = 100.0 / var_t
        beta_max = 1.0 / (eps * var_t)                # noise >= 1e-8 of the target's STD
        n_iter, converged = 0, False
        for n_iter in range(1, max_iter + 1):
            sweep = None
            if low and F.shape[1] <= LOW_RANK_SHARE * keep.size:
                sweep = _low_rank_sweep(F, c, alpha, beta)
            if sweep is None:
                if low:           # the factor no longer pays: H of the kept bases from it
                    low = False
                    PtP, Ptt = F @ F.T, F @ c
                mu, diag = self._posterior_diag(PtP, Ptt, alpha, beta)
                g = 1.0 - alpha * diag
            else:
                mu, g = sweep
            if F is not None:
                rss = e2 + float(np.sum((c - F.T @ mu) ** 2))
            else:
                rss = float(np.sum((t - Phi_kept @ mu) ** 2))
            g = np.clip(g, eps, 1.0)
            with np.errstate(divide="ignore"):
                alpha_new = g / (mu * mu)
            beta = max(n - float(g.sum()), eps * n) / max(rss, tiny)
            beta = min(beta, beta_max)
            finite = np.isfinite(alpha_new)
            dlog = np.log(alpha_new[finite]) - np.log(alpha[finite])
            change = float(np.max(np.abs(dlog), initial=0.0))
            alpha = alpha_new
            kept = alpha < threshold
            if not kept.all():
                keep, alpha = keep[kept], alpha[kept]
                if F is not None:
                    F = F[kept]
                else:
                    Phi_kept = Phi_kept[:, kept]
                if PtP is not None:
                    PtP, Ptt = PtP[np.ix_(kept, kept)], Ptt[kept]
            if keep.size == 0 or (change < tol and np.all(finite)):
                converged = True
                break
        if not converged:
            warnings.warn(f"RVR stopped after max_iter={max_iter} sweeps with max |Delta log "
                          f"alpha| = {change:.3g} >= tol={tol:g} (usually bases still on "
                          "their way to pruning; raise max_iter)", ConvergenceWarning,
                          stacklevel=2)

        final = None
        if keep.size and low:
            final = _low_rank_sweep(F, c, alpha, beta, full=True)
            if final is None:
                PtP, Ptt = F @ F.T, F @ c
        if final is not None:
            mu, Sigma = final
        elif keep.size:
            mu, Sigma = self._posterior(PtP, Ptt, alpha, beta)
        else:
            mu, Sigma = np.zeros(0), np.zeros((0, 0))
        self.bias_used_ = bool(keep.size and keep[0] == 0)
        self.relevance_indices_ = keep[keep > 0] - 1
        self.relevance_vectors_ = X[self.relevance_indices_]
        self.alpha_ = alpha
        self.beta_ = float(beta)
        self.mu_ = mu
        self.Sigma_ = Sigma
        self.n_iter_ = n_iter
        self.converged_ = converged
        return self

    def predict(self, X, return_std: bool = False):
        """Predicted drift [unit of y] for X (n_samples, n_features); with ``return_std``
        also the predictive standard deviation [unit of y] (Tipping 2001 eq. (22)), noise
        included."""
        Xs = self._validate_predict(X)
        rv = self._scale_X(self.relevance_vectors_)
        mean = np.empty(Xs.shape[0])
        var = np.empty(Xs.shape[0])
        for sl in gen_batches(Xs.shape[0], PREDICT_BATCH):
            phi = gaussian_kernel(Xs[sl], rv, self.sigma)
            if self.bias_used_:
                phi = np.hstack([np.ones((phi.shape[0], 1)), phi])
            mean[sl] = phi @ self.mu_
            if return_std:
                var[sl] = 1.0 / self.beta_ + np.einsum("ij,jk,ik->i", phi, self.Sigma_, phi)
        y = self.y_mean_ + self.y_scale_ * mean
        if return_std:
            return y, self.y_scale_ * np.sqrt(var)
        return y
