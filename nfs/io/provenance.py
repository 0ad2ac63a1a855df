"""What produced an output: package and library versions, hashes of what was read.

Recorded in every output folder's manifest (:mod:`nfs.io.outdir`), in the JSON outputs and
beside a saved compensator, so that a number can be traced to the code and the inputs that
made it. Versions are read from the installed distributions' metadata
(:func:`importlib.metadata.version`), which needs no import of the libraries themselves.
"""

from __future__ import annotations

import dataclasses
import hashlib
import platform
from collections.abc import Iterable
from importlib.metadata import PackageNotFoundError, version

from .. import __version__

__all__ = ["library_versions", "sha256_of_file", "sha256_of_text", "runs_provenance", "scenario_provenance",
           "instrument_provenance", "platform_tag", "output_provenance"]

#: Distributions whose versions change the numbers (name in the metadata -> key written).
_LIBRARIES = (("numpy", "numpy"), ("scipy", "scipy"), ("scikit-learn", "scikit-learn"),
              ("PyWavelets", "pywavelets"), ("joblib", "joblib"))


def library_versions() -> dict[str, str]:
    """Versions of the package, the numerical libraries and Python (``"absent"`` if one is not
    installed)."""
    out = {"nfs": __version__}
    for dist, key in _LIBRARIES:
        try:
            out[key] = version(dist)
        except PackageNotFoundError:
            out[key] = "absent"
    out["python"] = platform.python_version()
    return out


def sha256_of_file(path) -> str:
    """SHA-256 of a file's bytes, read in blocks of 1 MiB (hex)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def sha256_of_text(text: str) -> str:
    """SHA-256 (hex) of *text* encoded as UTF-8."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def runs_provenance(runs: Iterable) -> list[dict]:
    """Name, file and SHA-256 of each run's CSV file (as read), in the order given, and what
    the reader was asked to accept in it (``caveats``: a partial run, missing samples;
    :attr:`nfs.run.Run.caveats`) when anything."""
    out = []
    for run in runs:
        entry = {"name": run.name}
        path = getattr(run, "path", None)
        if path is not None:
            entry["file"] = str(path)
            try:
                entry["sha256"] = sha256_of_file(path)
            except OSError:
                pass
        if getattr(run, "caveats", ()):
            entry["caveats"] = list(run.caveats)
        out.append(entry)
    return out


def instrument_provenance(instrument) -> dict:
    """Name and SHA-256 of an instrument as loaded (its TOML text, every parameter)."""
    return {"name": instrument.name, "sha256": sha256_of_text(instrument.to_toml())}


def scenario_provenance(scenario) -> dict:
    """Name, file, seed and SHA-256 of a scenario as loaded, and its instrument's.

    The scenario's hash covers every setting but its instrument (hashed apart, from its TOML
    text) and the file path, so that a copy of a scenario file in another folder hashes the
    same.
    """
    rest = dataclasses.replace(scenario, instrument=None, path=None)
    return {"name": scenario.name,
            "file": str(scenario.path) if scenario.path is not None else "built-in default",
            "seed": scenario.seed,
            "sha256": sha256_of_text(repr(rest)),
            "instrument": instrument_provenance(scenario.instrument)}


def platform_tag() -> str:
    """Operating system and machine, e.g. ``Linux-x86_64`` (no host name, no kernel build:
    what can change floating-point results, not what identifies a computer)."""
    return f"{platform.system()}-{platform.machine()}"


def output_provenance(*, scenario=None, instrument=None, runs=None,
                      seeds: dict | None = None) -> dict:
    """The ``"provenance"`` entry of a JSON output: what produced it.

    Parameters
    ----------
    scenario : Scenario, optional
        Recorded with :func:`scenario_provenance` (its hash, its instrument's hash, its seed).
    instrument : Instrument, optional
        A model used without a scenario (``nfs compare``, ``nfs diagnose``).
    runs : iterable of Run, optional
        Measurement files read (:func:`runs_provenance`).
    seeds : dict, optional
        Every seed behind the numbers, by what it seeds.

    Returns
    -------
    dict
        ``{"versions": {nfs, numpy, scipy, scikit-learn, pywavelets, joblib, python},
        "platform": ..., "scenario": ..., "instrument": ..., "runs": ..., "seeds": ...}``
        (the keys given only); no time stamp, so the same inputs give the same bytes.
    """
    out: dict = {"versions": library_versions(), "platform": platform_tag()}
    if scenario is not None:
        out["scenario"] = scenario_provenance(scenario)
    if instrument is not None:
        out["instrument"] = instrument_provenance(instrument)
    if runs is not None:
        out["runs"] = runs_provenance(runs)
    if seeds is not None:
        out["seeds"] = dict(seeds)
    return out
