"""help() on the result classes shows every field with its documentation."""

import dataclasses
import pydoc

import pytest

from nfs.studies.startup_study import CompensationStudy, MethodResult, SeedResult
from nfs.fit.fit_result import FitResult
from nfs.diagnose.result import CandidateScore, Diagnosis
from nfs.docfields import document_fields, field_docs
from nfs.experiment import SimulationResult
from nfs.studies.scenario_runs import ScenarioResult
from nfs.run import Run, RunMeta
from nfs.scenario import Scenario
from nfs.northfind.heading import NorthFindResult
from nfs.scoring.heading_table import HeadingTable, TableRow


@document_fields
@dataclasses.dataclass(frozen=True)
class _Example:
    """A result."""

    rmse_deg: float
    """Heading RMSE [deg]
    over every cycle."""
    n: int = 3
    """Cycles."""
    undocumented: int = 0


def test_attributes_section_from_field_docstrings():
    doc = _Example.__doc__
    assert doc.startswith("A result.\n\nAttributes\n----------\n")
    assert "rmse_deg : float\n    Heading RMSE [deg]\n    over every cycle.\nn : int\n" in doc
    assert "undocumented" not in doc
    assert field_docs(_Example)["n"] == ("int", "Cycles.")
    assert document_fields(_Example) is _Example and _Example.__doc__ == doc   # idempotent


@pytest.mark.parametrize("cls", [Run, RunMeta, HeadingTable, TableRow, CompensationStudy,
                                 MethodResult, SeedResult, FitResult, Diagnosis,
                                 CandidateScore, Scenario, SimulationResult, ScenarioResult,
                                 NorthFindResult], ids=lambda c: c.__name__)
def test_help_shows_every_documented_field(cls):
    text = pydoc.render_doc(cls, renderer=pydoc.plaintext)
    docs = field_docs(cls)
    assert docs, f"{cls.__name__} has no field docstrings"
    for f in dataclasses.fields(cls):
        if f.name in docs:
            first = docs[f.name][1].splitlines()[0]
            assert f.name in text and first[:40] in text, (cls.__name__, f.name)
