"""Scenario files: the TOML reader (inheritance, overrides, checks against the table of ranges)
and the built-in scenarios and sweeps found by name."""

from .presets import (default_scenario_path, scenario_file, scenario_preset_names,
                      scenario_preset_path, sweep_preset_names, sweep_preset_path)
from .scenario import OVERRIDE_KEYS, TRUST_EFFECTS_ENV, load_scenario

__all__ = ["load_scenario", "OVERRIDE_KEYS", "TRUST_EFFECTS_ENV", "default_scenario_path",
           "scenario_file", "scenario_preset_names", "scenario_preset_path",
           "sweep_preset_names", "sweep_preset_path"]
