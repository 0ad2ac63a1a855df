"""How the compensators are trained and compared: the ``[compensation]`` table of a scenario
as data (read by :mod:`nfs.config.scenario`, used by the studies of :mod:`nfs.studies`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..docfields import document_fields
from .catalog import table_methods
from .modes import DEFAULT_FEATURE_MODE

__all__ = ["PROTOCOLS", "CompensationSettings"]


#: What ``nfs table`` trains and tests on (:attr:`CompensationSettings.protocol`).
PROTOCOLS = ("start-ups", "cycles", "runs", "parameters")


@document_fields
@dataclass(frozen=True)
class CompensationSettings:
    """How the compensators are trained and compared (``[compensation]`` of a scenario)."""

    methods: tuple[str, ...] = field(default_factory=table_methods)
    """Method keys, in table order (default: every registered method that is a row of the
    default table, :func:`~nfs.compensate.registry.table_methods`, read when the settings
    are made)."""
    features: tuple[str, ...] = ("seed004",)
    """Input features (names, sets or patterns) of every method."""
    features_mode: str = DEFAULT_FEATURE_MODE
    """What a feature at t may use, in training and test alike (:mod:`nfs.compensate.modes`):
    ``cycle`` (up to the end of t's north-finding cycle), ``causal`` (up to t) or
    ``offline`` (the whole run: no instrument can compute it)."""
    budget: int = 40
    """Evaluations of the validation error per tuned method (the same for all)."""
    decimate_s: float = 30.0
    """Training samples are kept every ``decimate_s`` [s]."""
    cutoff_period_s: float = 512.0
    """Wavelet cutoff of the drift separation [s] (level 8 at 1 Hz)."""
    train_seed: int = 1
    """Seed of the training start-ups (the test start-ups use the scenario's seed)."""
    train_repeats: int = 1
    """Training start-ups per temperature."""
    train_temperatures_c: tuple[float, ...] | None = None
    """Start temperatures of the training start-ups (None: the scenario's)."""
    random_state: int = 0
    """Seed of every stochastic model and tuner (the first tuner seed)."""
    tuner_seeds: int = 3
    """Seeds of each stochastic tuner (``random_state``, ``random_state + 1``, ...): a tuned
    row is the seed whose mean is the median, and the table gives the spread over seeds."""
    n_jobs: int | None = -1
    """Trainings run in parallel (methods x tuner seeds; joblib workers; -1: every core)."""
    test_repeats: int | None = 5
    """Test start-ups per temperature (None: the scenario's ``repeats``).  The start-up and
    stable RMSE of a single run rest on 5 cycles each (+-30 %); five runs pool 25 (+-14 %)."""
    train_units: tuple[int, ...] | None = None
    """Units that make the training start-ups, ``train_repeats`` per temperature each (None:
    :meth:`~nfs.scenario.Scenario.unit_split`: every unit not tested, or unit 0)."""
    test_units: tuple[int, ...] | None = None
    """Units that make the test start-ups, ``test_repeats`` per temperature each (None: the
    last unit)."""
    protocol: str = "start-ups"
    """What ``nfs table`` trains and tests on: ``start-ups`` (training start-ups, then the
    test start-ups: the heading table), ``cycles`` (cycle 1 of the chamber program, then
    the other cycles: the drift table of :mod:`nfs.studies.cycle_study`), ``runs`` (the same
    drift table, training runs then test runs) or ``parameters``
    (the parameters every cycle calibrates, modelled against temperature on the training
    runs and scored on the test runs: :mod:`nfs.studies.parameter_study`)."""
