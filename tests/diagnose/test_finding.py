"""What the diagnosis found for one candidate, in words (the --apply warning), and the
diagnosis's JSON read back as the diagnosis it was."""

import json

from nfs.diagnose import Diagnosis, candidate_finding
from nfs.diagnose.candidates import Candidate
from nfs.diagnose.result import CandidateScore


def _score(effect, target, significant, holm_p, before, after, channel, beyond):
    return CandidateScore(effect, target, significant, before, after, 0.5, {"m": 1.0},
                          {"m": (0.5, 1.5)}, holm_p, holm_p, 5.0, 1, 0.9, channel=channel,
                          beyond_structure_p=beyond)


DIAGNOSIS = Diagnosis(
    ranking=(_score("magnetic", None, True, 1e-6, 0.01, 0.004, "drift_dph", 0.001),
             _score("shupe_rate", "board", True, 0.01, 0.01, 0.008, "drift_dph", 0.4),
             _score("heat_source", "coil_outer", False, 0.9, 0.02, 0.02, "thermometers",
                    None)),
    not_tried=(Candidate("aux_linear", None, "gyro", ("k",), (), False, "no aux channel"),),
    unexplained={"ljung_box": {"p_value": 0.3, "consistent": True}}, baseline=None,
    time_s=1.0)


def test_significant_tied_not_significant_not_scored_and_unknown():
    sig, text = candidate_finding(DIAGNOSIS, "magnetic", None)
    assert sig is True and "'magnetic' is significant (Holm p = 1e-06" in text
    assert "rank 1 of 3" in text and "deg/h" in text and "tied" not in text
    sig, text = DIAGNOSIS.support_for("shupe_rate", "board")
    assert sig is True and "'shupe_rate:board' is significant" in text and "tied" in text
    sig, text = candidate_finding(DIAGNOSIS, "heat_source", "coil_outer")
    assert sig is False and "not significant" in text and " K, rank 3 of 3" in text
    assert candidate_finding(DIAGNOSIS, "aux_linear", None) == \
        (None, "'aux_linear' was not scored: no aux channel")
    sig, text = candidate_finding(DIAGNOSIS, "magnetic", "x")
    assert sig is None and "not among the candidates" in text


def test_the_json_reads_back_as_the_same_diagnosis():
    doc = json.loads(json.dumps(DIAGNOSIS.to_dict()))
    assert doc["schema"] == "nfs-diagnosis/1" and doc["answer"]["kind"] == "add"
    assert doc["ranking"][0]["cv_drop"] == 0.6        # derived, written for a reader
    back = Diagnosis.from_dict(doc)
    assert back == DIAGNOSIS
    assert back.answer == DIAGNOSIS.answer and back.verdict.startswith("add magnetic")
