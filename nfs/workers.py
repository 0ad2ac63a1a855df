"""Results of joblib worker pools left unread.

A study's trainings and a sweep's cells come back from joblib as a generator
(``return_as="generator_unordered"``).  When the caller stops reading it (an error, an
interrupt, a callback that raises), joblib cancels the jobs still running and warns that
it did, often only when the generator is collected at the interpreter's exit, after the
error the user should read.  :func:`close_unread` cancels them at once, without the warning.
"""

from __future__ import annotations

import warnings

__all__ = ["close_unread"]


def close_unread(results) -> None:
    """Close the generator ``results`` of a joblib ``Parallel`` call: the jobs still
    running are cancelled (joblib's UserWarning about them, "N tasks ...", is not shown;
    any other warning is); a generator read to its end is left as it is."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"\d+ tasks ", category=UserWarning)
        results.close()
