"""Studies: simulate a scenario's start-ups, north-find them, train the compensators and score
them, the chain behind ``nfs table``.

- :mod:`~nfs.studies.scenario_runs`: a scenario's runs simulated and north-found, the
  uncompensated table (before / stable / floor);
- :mod:`~nfs.studies.startup_study`: the compensation study over start-ups (the FOG start-up
  paper's Table 3);
- :mod:`~nfs.studies.cycle_study`: the drift table over chamber-program cycles or runs;
- :mod:`~nfs.studies.parameter_study`: the parameters every cycle calibrates, modelled
  against temperature;
- :mod:`~nfs.studies.runs_folder`: a scenario's runs written into a folder with the units
  that made them, resumed run by run (``nfs simulate``);
- :mod:`~nfs.studies.job_estimate`: a job's runs, time, disk and memory before it starts,
  and the counts of a scenario a command ignores.
"""

from .cycle_study import CycleStudy, run_cycle_study, run_runs_study
from .parameter_study import ParameterStudy, run_parameter_study
from .scenario_runs import (ScenarioResult, floor_deg, northfind_runs, run_scenario,
                            uncompensated_table)
from .job_estimate import (JOB_LIMITS, JOB_NOTICE, JobEstimate, JobLimits, JobTooBig,
                           check_job, estimate_runs, estimate_table, ignored_keys,
                           table_scenarios)
from .runs_folder import (SimulatedFolder, check_runs_folder, simulate_to_folder,
                          unit_file_instrument)
from .startup_study import CompensationStudy, run_study

__all__ = ["ScenarioResult", "run_scenario", "northfind_runs", "uncompensated_table", "floor_deg",
           "CompensationStudy", "run_study", "CycleStudy", "run_cycle_study", "run_runs_study",
           "ParameterStudy", "run_parameter_study",
           "SimulatedFolder", "simulate_to_folder", "check_runs_folder", "unit_file_instrument",
           "JobEstimate", "JobLimits", "JOB_LIMITS", "JOB_NOTICE", "JobTooBig", "estimate_runs",
           "estimate_table", "check_job", "ignored_keys", "table_scenarios"]
