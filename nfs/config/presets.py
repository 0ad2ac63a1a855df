"""The built-in scenarios and sweeps shipped with the package (``nfs/presets/scenarios``, the
repository's ``scenarios/`` folder), found by name."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from ..errors import ScenarioError

__all__ = ["default_scenario_path", "scenario_preset_names", "scenario_preset_path",
           "sweep_preset_names", "sweep_preset_path", "scenario_file"]


def _preset_dir(kind: str) -> Path:
    """Where the built-in scenarios (``kind = "scenarios"``) or sweeps (``"sweeps"``) are:
    the package's ``presets/scenarios`` (the repository's ``scenarios/`` folder, shipped)."""
    root = Path(str(resources.files("nfs") / "presets" / "scenarios"))
    return root if kind == "scenarios" else root / "sweeps"


def default_scenario_path() -> Path:
    """The built-in default scenario (the FOG start-up paper's seven start temperatures)."""
    return _preset_dir("scenarios") / "startup_7temps.toml"


def scenario_preset_names() -> list[str]:
    """Names of the built-in scenario presets (``nfs preset`` lists them)."""
    return sorted(p.stem for p in _preset_dir("scenarios").glob("*.toml"))


def sweep_preset_names() -> list[str]:
    """Names of the built-in sweep presets (``nfs preset`` lists them)."""
    return sorted(p.stem for p in _preset_dir("sweeps").glob("*.toml"))


def scenario_preset_path(name: str) -> Path:
    """Path of a built-in scenario preset."""
    if name not in scenario_preset_names():
        raise ScenarioError(f"unknown scenario preset '{name}'; presets: "
                            + ", ".join(scenario_preset_names()))
    return _preset_dir("scenarios") / f"{name}.toml"


def sweep_preset_path(name: str) -> Path:
    """Path of a built-in sweep preset."""
    if name not in sweep_preset_names():
        raise ScenarioError(f"unknown sweep preset '{name}'; presets: "
                            + ", ".join(sweep_preset_names()))
    return _preset_dir("sweeps") / f"{name}.toml"


def scenario_file(path_or_name: str | Path, kind: str = "scenarios") -> Path:
    """The file a command is given: a path, or the name of a built-in preset (``nfs table
    seed003_ramp_calibration`` from any folder).  A path that does not exist and names no
    preset is returned as it is (its reader says it is missing)."""
    p = Path(path_or_name)
    if p.exists() or p.suffix.lower() == ".toml" or len(p.parts) > 1:
        return p
    names = scenario_preset_names() if kind == "scenarios" else sweep_preset_names()
    if p.name in names:
        return (scenario_preset_path if kind == "scenarios" else sweep_preset_path)(p.name)
    return p
