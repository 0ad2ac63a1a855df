"""What the diagnosis found for one candidate, in words (the --apply warning)."""

from nfs.diagnose import candidate_finding

DOC = {"alpha": 0.05,
       "ranking": [
           {"effect": "magnetic", "target": None, "significant": True, "holm_p": 1e-6,
            "cv_rms_before": 0.01, "cv_rms_after": 0.004, "channel": "drift_dph",
            "explained_by": None, "beyond_structure_p": 0.001},
           {"effect": "shupe_rate", "target": "board", "significant": True, "holm_p": 0.01,
            "cv_rms_before": 0.01, "cv_rms_after": 0.008, "channel": "drift_dph",
            "explained_by": None, "beyond_structure_p": 0.4},
           {"effect": "heat_source", "target": "coil_outer", "significant": False,
            "holm_p": 0.9, "cv_rms_before": 0.02, "cv_rms_after": 0.02,
            "channel": "thermometers", "explained_by": None, "beyond_structure_p": None}],
       "not_tried": [{"effect": "aux_linear", "target": None, "reason": "no aux channel"}]}


def test_significant_tied_not_significant_not_scored_and_unknown():
    sig, text = candidate_finding(DOC, "magnetic", None)
    assert sig is True and "'magnetic' is significant (Holm p = 1e-06" in text
    assert "rank 1 of 3" in text and "deg/h" in text and "tied" not in text
    sig, text = candidate_finding(DOC, "shupe_rate", "board")
    assert sig is True and "'shupe_rate:board' is significant" in text and "tied" in text
    sig, text = candidate_finding(DOC, "heat_source", "coil_outer")
    assert sig is False and "not significant" in text and " K, rank 3 of 3" in text
    assert candidate_finding(DOC, "aux_linear", None) == \
        (None, "'aux_linear' was not scored: no aux channel")
    sig, text = candidate_finding(DOC, "magnetic", "x")
    assert sig is None and "not among the candidates" in text
