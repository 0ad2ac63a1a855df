"""The drawn unit beside its runs: ``unit_00.toml``, ``unit_01.toml``, ...

A simulated unit's numbers are drawn (:mod:`nfs.variability`: with a scenario's realistic
variability every drift coefficient is scattered by about 20 %), so the values a fit of its
runs should find are the unit's, not the scenario's instrument's.  Every command that
simulates runs into a folder writes each unit that made them as an instrument TOML
(:meth:`nfs.instrument.Instrument.to_toml`, read back by ``nfs fit --model unit_00.toml``
to the same values, bit for bit), names it in the folder's manifest (``units``: file, unit,
scenario, runs) and in each run's sidecar (``unit_file``).

A drawn value can lie outside its typical range by design (the draw's tails): loading a
unit file the manifest beside it names, with the SHA-256 it recorded, gives one summary line
instead of a warning per value (:func:`drawn_unit_entry`, :func:`nfs.instrument.load_instrument`).
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import ScenarioError
from ..ranges import check_tree, warn_unusual
from .outdir import MANIFEST_NAME, read_manifest
from .provenance import sha256_of_file
from .tomlio import check_keys, table

__all__ = ["UNIT_SIDECAR_KEY", "unit_file_name", "unit_file_text", "unit_entry",
           "drawn_unit_entry", "drawn_unit_note", "fitted_departures", "check_values_as_declared"]

#: Key of a run's sidecar (``NAME.toml``) that names the unit file the run was made by.
UNIT_SIDECAR_KEY = "unit_file"


def unit_file_name(unit: int) -> str:
    """``unit_00.toml`` for unit 0 (two digits at least, more for unit 100 on)."""
    return f"unit_{unit:02d}.toml"


def unit_file_text(toml_text: str, *, unit: int, scenario: str, drawn: str) -> str:
    """The unit file: a comment saying what the unit is, then the instrument's TOML text.

    Parameters
    ----------
    toml_text : str
        The unit's instrument as :meth:`~nfs.instrument.Instrument.to_toml` writes it.
    unit : int
        The unit's number in the scenario.
    scenario : str
        The scenario's name.
    drawn : str
        How the unit was drawn, in one line (:meth:`nfs.variability.Variability.describe`).
    """
    return (f"# Unit {unit} of scenario '{scenario}', as simulated: the scenario's instrument "
            "with the unit's own draw\n"
            f"# of every parameter that scatters from unit to unit ({drawn}).\n"
            "# These are the values a fit of this unit's runs should find: "
            f"nfs fit RUNS --model {unit_file_name(unit)}\n"
            + toml_text)


def unit_entry(unit: int, scenario: str, drawn: bool, runs: int) -> dict:
    """The manifest's record of one unit file (``units`` of ``nfs-manifest.json``)."""
    return {"file": unit_file_name(unit), "unit": unit, "scenario": scenario,
            "drawn": drawn, "runs": runs}


def drawn_unit_entry(path: str | os.PathLike) -> dict | None:
    """The manifest's record of the unit file ``path`` when the manifest beside it names it
    as a unit drawn by a simulation and lists the file with the SHA-256 it has now (an
    edited copy is a user's instrument again); None otherwise."""
    p = Path(path)
    manifest = read_manifest(p.parent)
    if manifest is None:
        return None
    entry = next((u for u in manifest.get("units", []) if isinstance(u, dict)
                  and u.get("file") == p.name and u.get("drawn") is True), None)
    listed = next((f for f in manifest.get("files", []) if isinstance(f, dict)
                   and f.get("path") == p.name), None)
    if entry is None or listed is None:
        return None
    try:
        same = listed.get("sha256") == sha256_of_file(p)
    except OSError:
        return None
    return entry if same else None


def drawn_unit_note(keys: list[str], entry: dict) -> str:
    """The one line that stands for the range warnings of a drawn unit's file: its unusual
    values' ``keys`` (as :func:`nfs.ranges.check_tree` returns them) and its manifest record
    ``entry``: how many values, which keys, and why that is no slip."""
    shown = ", ".join(keys[:4]) + (", ..." if len(keys) > 4 else "")
    return (f"{len(keys)} value(s) outside their typical ranges ({shown}): unit "
            f"{entry.get('unit')} of scenario '{entry.get('scenario')}' as its variability "
            f"drew it ({MANIFEST_NAME} beside it), a draw's tail, not a slip")


def fitted_departures(tree: dict, file=None) -> tuple[str, ...]:
    """The keys a fitted model's ``[fit] departures`` lists (what
    :func:`nfs.fit.write_fitted_model` writes: values its fit put beyond their typical range,
    stated with what each points to in the file's header)."""
    fit = table(tree, "fit", "", file, {})
    check_keys(fit, ("departures",), "fit", file)
    keys = fit.get("departures", [])
    if not isinstance(keys, list) or not all(isinstance(k, str) for k in keys):
        raise ScenarioError(f"must be a list of key paths (strings), got {keys!r}",
                            file=file, key="fit.departures")
    return tuple(keys)


def check_values_as_declared(tree: dict, file=None, drawn: dict | None = None) -> None:
    """Check every value of an instrument file against its range
    (:func:`nfs.ranges.check_tree`), the values its writer declared unusual said in one line
    instead of one warning each: those a fitted model lists (:func:`fitted_departures`), or
    every one of a drawn unit's file (``drawn``: its manifest record,
    :func:`drawn_unit_entry`)."""
    fitted = fitted_departures(tree, file)
    quieted = check_tree(tree, file=file, error=ScenarioError, skip=("fit.*",),
                         quiet=True if drawn is not None else fitted)
    if drawn is not None and quieted:
        warn_unusual(drawn_unit_note(quieted, drawn), file=file, once=("drawn", str(file)))
    elif fitted:
        warn_unusual(f"{len(fitted)} fitted values lie beyond their typical range, as the fit "
                     f"that wrote this file states in its header ({', '.join(fitted)})",
                     file=file, key="fit.departures", once=("fit.departures", str(file)))
