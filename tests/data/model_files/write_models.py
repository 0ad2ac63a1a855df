"""Write the stored model files of tests/test_model_files.py (one per method, nfs-model/1).

Run from the repository root::

    python tests/data/model_files/write_models.py tests/data/model_files

Each file holds one method's estimator trained on a small seeded problem (three features,
60 samples, three validation groups) and, in its header, ``X_new`` and the estimator's
``prediction`` there when it was written.  Only methods whose fitted state is the package's
own arrays are stored (no scikit-learn model inside, whose private attributes change between
scikit-learn versions).  ``ls.joblib`` is the LS compensator as the joblib pickle that
earlier versions wrote (read only with ``trust_pickle=True``), with the same ``X_new`` and
``prediction`` beside it in the pickled dict.  See README.md beside this script for when
the stored files were written.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

import joblib

from nfs.compensate.compensator import PICKLE_FORMAT, DriftCompensator
from nfs.compensate import METHODS  # with the seed papers' methods registered
from nfs.compensate.model_file import write_model_file

#: Methods stored: every one whose state holds no scikit-learn estimator.
STORED = ("ls", "stepwise", "rbf", "lssvm", "ir-lssvm", "hho-rvr")


def problem(n: int = 60, seed: int = 0):
    """A smooth drift of three features, three runs (validation groups) of n / 3 samples,
    and 40 new feature rows to predict at."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 3))
    y = np.sin(X[:, 0]) + 0.1 * X[:, 1] * X[:, 2]
    return X, y, np.repeat(np.arange(3), n // 3), rng.normal(size=(40, 3))


def main(folder: str) -> None:
    out = Path(folder)
    X, y, groups, X_new = problem()
    for key in STORED:
        spec = METHODS[key]
        est = spec.build(budget=6, random_state=0, n_jobs=1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")      # a 6-candidate search on 60 samples
            est.fit(X, y, groups=groups) if spec.tuned else est.fit(X, y)
        header = {"method": key, "X_new": X_new, "prediction": est.predict(X_new)}
        print(write_model_file(out / f"{key}.npz", header, est))
        if key == "ls":
            comp = DriftCompensator(method=spec.name, estimator=est,
                                    feature_names=("a", "b", "c"))
            joblib.dump({"format": PICKLE_FORMAT, "compensator": comp, "X_new": X_new,
                         "prediction": header["prediction"]}, out / "ls.joblib")
            print(out / "ls.joblib")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else str(Path(__file__).parent))
