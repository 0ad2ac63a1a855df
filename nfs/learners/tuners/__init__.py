"""Metaheuristic tuners: plain minimisers of a batch objective on the box [-1, 1]^d.

Every method has one interface (:func:`minimize` dispatches by name through :data:`TUNERS`)::

    result = minimize(objective_batch, n_dims, method="ssa", budget=300, random_state=0)

``objective_batch(X)`` takes a whole population ``X`` of shape (m, d) with every row in
[-1, 1]^d and returns the m objective values (lower is better) as an array of shape (m,).
Passing a population at once lets the caller spread one batch over cores (see
:class:`nfs.learners.search.MetaheuristicSearchCV`, which evaluates candidates x folds with
joblib).  The caller maps the normalised box to real parameters (e.g. log10 C in [-2, 3]).

Budget
------
``budget`` is the maximum number of objective evaluations (rows passed to
``objective_batch``), the initial population included.  All methods share one evaluator
(:class:`~.evaluation.Evaluator`): when a method asks for a batch larger than what is left,
**only the first ``remaining`` rows of that batch (in the method's own order: rank order for SSA,
particle order for PSO, ...) are evaluated, the other rows are discarded unevaluated, and the
run ends**.  So ``n_evaluations == budget`` whenever the method runs to its end (grid and
TPE stop at exactly ``budget`` as well) and methods are compared at equal budget.  The
schedules that the papers write in iterations (PSO's inertia weight, GWO's ``a``, SSA's
``iter_max``) use the number of generations the budget allows; HHO, whose cost per generation
varies with its rapid dives, runs its escape-energy schedule on the spent fraction of the
budget instead (see :func:`~.swarm.hho`).

Conventions
-----------
* Every random draw comes from one ``numpy.random.Generator`` made from ``random_state``
  (int, Generator, legacy RandomState or None); the same seed gives the same history.
* ``population`` (swarm, pack, flock size) defaults to :func:`default_population`.
* Initial populations are uniform in the box; every candidate position is clipped to the box
  before it is evaluated (positions outside are never passed to the objective).
* A NaN objective value (a failed fit) is treated as +inf.

Known bias toward the origin
----------------------------
Several published update rules multiply positions by factors that pull toward the origin of
the search space: SSA's producer rule ``X * exp(-i / (alpha iter_max))`` and the "fly
elsewhere" scrounger rule ``Q exp(...)`` (Xue & Shen 2020 eqs. (3), (4)), GWO's
``|C X_p - X|`` with ``C`` in [0, 2] (Mirjalili et al. 2014 eq. (3.1)), and HHO's soft
besiege ``X_rabbit - X - E|J X_rabbit - X|`` (a difference of positions, not a position;
Heidari et al. 2019 eq. (4)) and perch rule ``(X_rabbit - X_m) - r3 (LB + r4 (UB - LB))``
(eq. (1)).  On benchmark functions whose optimum is the origin these rules look better than
they are.  The functions below keep the papers' forms; the tests check every method on
optima away from the origin (``tests/learners/test_tuners.py``) and print the difference.
The normalised box puts the middle of each real range at 0, so a tuner biased to the origin
is biased to the middle of the user's ranges.

Modules
-------
* :mod:`~.evaluation`: the box, the budget and the record every tuner shares
  (:class:`~.evaluation.TuneResult`, :class:`~.evaluation.Evaluator`);
* :mod:`~.sampling`: positions fixed in advance, :func:`~.sampling.grid` and
  :func:`~.sampling.random_search`;
* :mod:`~.swarm`: the population metaheuristics of the seed papers, one function per
  published algorithm: :func:`~.swarm.pso`, :func:`~.swarm.gwo`, :func:`~.swarm.hho`,
  :func:`~.swarm.ssa`;
* :mod:`~.model_based`: :func:`~.model_based.tpe` (Optuna's tree-structured Parzen
  estimator, optional);
* :mod:`~.registry`: :data:`~.registry.TUNERS` (name -> function),
  :func:`~.registry.register_tuner`, :func:`~.registry.get_tuner` and
  :func:`~.registry.minimize`.
"""

from .evaluation import TuneResult, TuningError, default_population
from .model_based import tpe
from .registry import TUNERS, get_tuner, minimize, register_tuner
from .sampling import grid, random_search
from .swarm import gwo, hho, pso, ssa

__all__ = [
    "TuneResult",
    "TuningError",
    "TUNERS",
    "register_tuner",
    "get_tuner",
    "minimize",
    "grid",
    "random_search",
    "pso",
    "gwo",
    "hho",
    "ssa",
    "tpe",
    "default_population",
]
