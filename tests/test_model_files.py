"""Model files (nfs-model/1): every method round-trips exactly, and loading runs no code.

Oracles: invariants.  A model file holds the fitted arrays and is read back onto the same
classes, so the loaded model predicts bit for bit as the one saved, and saving it again gives
the same bytes; a file that names the classes by their paths before the estimators moved to
nfs.learners reads as the same model.  Every method of the registry is round-tripped (a
method registered in the package is covered without naming it here), and so is a user's
own method whose classes it lists (model_classes); one that lists none is refused in one
line that names the method and the class.  Stored data: model files and a pickle written before
that move (tests/data/model_files, README.md there), whose predictions when written are
stored beside them.  A file whose unpickling would create a marker file (``__reduce__`` calling
``os.system``; a control shows the marker appears when the bytes are unpickled) is refused
by ``nfs compensate`` with one line and exit 2, and the marker does not appear.
"""

import io
import json
import os
import pickle
import shlex
import sys
import warnings
import zipfile
from pathlib import Path

import joblib
import numpy as np
import pytest

from nfs.cli import main
from sklearn.linear_model import LinearRegression, Ridge
from sklearn.pipeline import Pipeline, make_pipeline
from sklearn.preprocessing import StandardScaler

from nfs.compensate import (DriftCompensator, available_methods, get_method, load_compensator,
                            register_method, train_compensator, unregister_method)
from nfs.compensate.model_file import (ESTIMATORS, FORMAT, FORMER_NAMES, RECORDS,
                                       ModelFileError, ModelVersionWarning, former_modules,
                                       model_file_kind, read_model_file, write_model_file)
from nfs.learners import CubicLeastSquares, IRLSSVMRegressor
from nfs.io.measurement import read_runs
from nfs.io.provenance import sha256_of_file

#: Model files and a pickle written before the estimators moved to nfs.learners.
STORED = Path(__file__).resolve().parent / "data" / "model_files"


def _data(n=60, seed=0):
    """A smooth drift of three features, three runs (validation groups) of n / 3 samples."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 3))
    y = np.sin(X[:, 0]) + 0.1 * X[:, 1] * X[:, 2]
    return X, y, np.repeat(np.arange(3), n // 3), rng.normal(size=(40, 3))


@pytest.fixture
def user_methods():
    """Two methods of a user's own, registered for the test: a ridge regression on the
    standardised features whose classes a model file may hold, and an ordinary least
    squares whose class it may not."""
    register_method("ridge", make_pipeline(StandardScaler(), Ridge(alpha=1e-3)), name="Ridge",
                    reference="ridge regression on the features",
                    model_classes=(Pipeline, StandardScaler, Ridge))
    register_method("ols", LinearRegression(), name="OLS", reference="least squares")
    yield
    for key in ("ridge", "ols"):
        if key in available_methods():
            unregister_method(key)


@pytest.mark.parametrize("key", [
    pytest.param(k, marks=pytest.mark.requires("optuna")) if get_method(k).tuner == "tpe"
    else k for k in available_methods()])
def test_every_method_round_trips_bit_for_bit(tmp_path, key):
    _round_trip(tmp_path, get_method(key))


def test_a_users_method_whose_classes_are_listed_round_trips(tmp_path, user_methods):
    _round_trip(tmp_path, get_method("ridge"))
    with zipfile.ZipFile(tmp_path / "model.npz") as zf:
        doc = json.loads(zf.read("header.json"))
    # the classes by their public paths, not scikit-learn's private modules
    assert doc["estimator"]["$estimator"] == "sklearn.pipeline.Pipeline"
    assert '"sklearn.linear_model.Ridge"' in json.dumps(doc)


def test_a_users_method_whose_class_is_not_listed_is_refused_in_one_line(tmp_path,
                                                                         user_methods):
    X, y, _, _ = _data()
    spec = get_method("ols")
    comp = DriftCompensator(method=spec.name, feature_names=("a", "b", "c"),
                            estimator=spec.build(budget=1, random_state=0, n_jobs=1).fit(X, y))
    with pytest.raises(ModelFileError) as exc:
        comp.save(tmp_path / "model.npz")
    assert str(exc.value).startswith("method 'OLS': estimator: a "
                                     "sklearn.linear_model.LinearRegression cannot be written")
    assert "model_classes" in str(exc.value) and "\n" not in str(exc.value)
    assert not (tmp_path / "model.npz").exists()
    # and a file naming a class the reading process has not registered is not read
    _round_trip(tmp_path, get_method("ridge"))
    unregister_method("ridge")
    with pytest.raises(ModelFileError, match="estimator class 'sklearn.pipeline.Pipeline' is "
                                             "not one a model file may hold"):
        load_compensator(tmp_path / "model.npz")


def _round_trip(tmp_path, spec):
    """Fit ``spec``'s estimator on a small problem, save, load, save again: the same
    predictions bit for bit and the same bytes."""
    X, y, groups, X_new = _data()
    est = spec.build(budget=6, random_state=0, n_jobs=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # a 6-candidate search on 60 samples
        est.fit(X, y, groups=groups) if spec.tuned else est.fit(X, y)
    comp = DriftCompensator(method=spec.name, estimator=est, feature_names=("a", "b", "c"),
                            features_mode="causal", settings={"budget": 6})
    path = comp.save(tmp_path / "model.npz")
    assert model_file_kind(path) == "nfs-model"
    loaded = load_compensator(path)
    assert type(loaded.estimator) is type(est)
    assert loaded.estimator.predict(X_new).tobytes() == est.predict(X_new).tobytes()
    assert (loaded.method, loaded.feature_names, loaded.features_mode, loaded.settings) == \
        (spec.name, ("a", "b", "c"), "causal", {"budget": 6})
    again = loaded.save(tmp_path / "again.npz")
    assert again.read_bytes() == path.read_bytes()
    if spec.tuned:
        assert loaded.estimator.best_params_ == est.best_params_
    # the same file with every class named by its path before the move to nfs.learners
    # (a file of nothing but another library's classes had no other names)
    former = _with_former_names(path, tmp_path / "former.npz")
    if not any(type(o).__module__.startswith("nfs.learners.") for o in _parts(est)):
        return
    assert former.read_bytes() != path.read_bytes()
    loaded = load_compensator(former)
    assert type(loaded.estimator) is type(est)
    assert loaded.estimator.predict(X_new).tobytes() == est.predict(X_new).tobytes()


def _parts(est):
    """``est`` and the estimators among its parameters (a search's, a pipeline's steps)."""
    inner = [v for v in est.get_params(deep=True).values() if hasattr(v, "get_params")]
    return [est, *inner]


def test_the_header_names_the_class_its_parameters_the_features_and_the_runs(tmp_path):
    X, y, _, _ = _data()
    comp = DriftCompensator(method="LS", estimator=CubicLeastSquares(degree=2).fit(X, y),
                            feature_names=("T_fog", "dT_fog", "G"), trained_on=("r1",),
                            provenance={"runs": [{"name": "r1", "sha256": "ab"}]})
    path = comp.save(tmp_path / "model.npz")
    with zipfile.ZipFile(path) as zf:
        doc = json.loads(zf.read("header.json"))
        assert all(n == "header.json" or n.endswith(".npy") for n in zf.namelist())
    assert doc["format"] == FORMAT and doc["features_mode"] == "cycle"
    assert doc["feature_names"] == ["T_fog", "dT_fog", "G"]
    assert doc["provenance"]["runs"][0]["sha256"] == "ab"
    assert doc["estimator"]["$estimator"] == "nfs.learners.linear.CubicLeastSquares"
    assert doc["estimator"]["params"] == {"degree": 2, "include_interactions": True,
                                          "alpha": 0.0}
    with np.load(path, allow_pickle=False) as npz:   # the arrays need no pickle
        assert all(npz[k].dtype != object for k in npz.files if k != "header.json")


def test_an_object_not_on_the_lists_is_not_written(tmp_path):
    X, y, _, _ = _data()
    est = IRLSSVMRegressor(weight=lambda r: np.ones_like(r)).fit(X, y)
    comp = DriftCompensator(method="mine", estimator=est, feature_names=("a", "b", "c"))
    with pytest.raises(ModelFileError, match=r"^method 'mine': estimator\.weight: a "
                                             r"builtins\.function cannot be written"):
        comp.save(tmp_path / "model.npz")
    assert not (tmp_path / "model.npz").exists()


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Two short simulated runs and an LS model trained on them (nfs train)."""
    from tests.conftest import _scenario_text
    d = tmp_path_factory.mktemp("runs")
    (d / "s.toml").write_text(_scenario_text("small", 5, (-20.0, 40.0), 700.0))
    assert main(["simulate", str(d / "s.toml"), "-o", str(d / "runs"), "-q"]) == 0
    assert main(["train", str(d / "runs"), "--method", "ls", "-o", str(d / "ls.npz"),
                 "-q"]) == 0
    return d


def test_train_records_the_runs_it_read_by_hash(runs):
    comp = load_compensator(runs / "ls.npz")
    files = sorted((runs / "runs").glob("*.csv"))
    assert sorted(r["sha256"] for r in comp.provenance["runs"]) == \
        sorted(sha256_of_file(f) for f in files)
    assert comp.versions["nfs"] and comp.fit_time_s >= 0


def test_train_takes_a_registered_method_and_says_in_one_line_when_it_cannot_save_it(
        runs, tmp_path, capsys, user_methods):
    # nfs train --method reads the registry: a method of the user's own, registered in the
    # process that runs the command
    code = main(["train", str(runs / "runs"), "--method", "ridge", "-o",
                 str(tmp_path / "ridge.npz"), "-q"])
    assert code == 0, capsys.readouterr().err
    comp = load_compensator(tmp_path / "ridge.npz")
    assert comp.method == "Ridge" and type(comp.estimator) is Pipeline
    capsys.readouterr()
    code = main(["train", str(runs / "runs"), "--method", "ols", "-o",
                 str(tmp_path / "ols.npz"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("nfs: error: method 'OLS': estimator: a sklearn.linear_model."
                          "LinearRegression cannot be written to a model file")
    assert not (tmp_path / "ols.npz").exists()


class _Touch:
    """Unpickling this calls os.system('touch MARKER')."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {shlex.quote(str(self.marker))}",)


def _pickle(path, marker):
    path.write_bytes(pickle.dumps(_Touch(marker), protocol=4))


def _pickle_v2(path, marker):
    path.write_bytes(pickle.dumps(_Touch(marker), protocol=2))


def _joblib(compress):
    def write(path, marker):
        joblib.dump(_Touch(marker), path, compress=compress)
    return write


def _zip_with_pickle(path, marker):
    """A zip holding a pickle, as PyTorch's checkpoints are."""
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("archive/data.pkl", pickle.dumps(_Touch(marker)))


def _model_with_pickled_array(path, marker):
    """A model file whose array member is an object array: a pickle inside the .npy."""
    X, y, _, _ = _data()
    comp = DriftCompensator(method="LS", estimator=CubicLeastSquares().fit(X, y),
                            feature_names=("a", "b", "c"))
    comp.save(path)
    evil = io.BytesIO()
    np.save(evil, np.array([_Touch(marker)], dtype=object), allow_pickle=True)
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    members["a0.npy"] = evil.getvalue()
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)


def _model_naming_a_foreign_class(path, marker):
    """A model file whose header names os.system as the estimator's class."""
    X, y, _, _ = _data()
    header = {"method": "LS"}
    write_model_file(path, header, CubicLeastSquares().fit(X, y))
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    doc = json.loads(members["header.json"])
    doc["estimator"]["$estimator"] = "posix.system"
    doc["estimator"]["params"] = {"command": f"touch {marker}"}
    members["header.json"] = json.dumps(doc).encode()
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)


@pytest.mark.parametrize("write, why", [
    (_pickle, "a pickle, not a nfs-model/1 model file"),
    (_pickle_v2, "a pickle, not a nfs-model/1 model file"),
    (_joblib(("zlib", 3)), "a pickle"), (_joblib(("gzip", 3)), "a pickle"),
    (_joblib(("bz2", 3)), "a pickle"), (_joblib(("lzma", 3)), "a pickle"),
    (_joblib(("xz", 3)), "a pickle"),
    (_zip_with_pickle, "a zip archive without header.json"),
    (_model_with_pickled_array, "corrupt model file"),
    (_model_naming_a_foreign_class, "estimator class 'posix.system' is not one"),
])
def test_a_file_that_would_run_code_is_refused_before_it_runs(runs, tmp_path, capsys, write,
                                                               why):
    marker = tmp_path / "marker"
    evil = tmp_path / "model.joblib"
    write(evil, marker)
    assert not marker.exists()
    code = main(["compensate", str(runs / "runs"), "--model", str(evil),
                 "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert err.startswith(f"nfs: error: {evil}: ") and why in err
    assert not marker.exists() and not (tmp_path / "out").exists()


def test_the_marker_appears_when_such_a_file_is_unpickled(tmp_path):
    # The control of the test above: its pickles do run their code when unpickled.
    marker = tmp_path / "marker"
    _pickle(tmp_path / "evil", marker)
    pickle.loads((tmp_path / "evil").read_bytes())
    assert marker.exists()


@pytest.mark.parametrize("content, why", [
    (b"T_fog,gyro_dph\n1,2\n", "neither a model file nor a pickle"),
    (b"", "neither a model file nor a pickle"),
    (None, "model file not found"),
])
def test_a_foreign_or_missing_file_is_one_line(runs, tmp_path, capsys, content, why):
    path = tmp_path / "model.npz"
    if content is not None:
        path.write_bytes(content)
    code = main(["compensate", str(runs / "runs"), "--model", str(path),
                 "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and why in err


def test_a_later_format_is_refused_by_name(tmp_path):
    X, y, _, _ = _data()
    path = write_model_file(tmp_path / "m.npz", {}, CubicLeastSquares().fit(X, y))
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    members["header.json"] = members["header.json"].replace(FORMAT.encode(), b"nfs-model/2")
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    with pytest.raises(ModelFileError, match="model format 'nfs-model/2': this version of "
                                             "nfs reads nfs-model/1"):
        read_model_file(path)


def test_a_trusted_pickle_of_an_earlier_version_still_loads(runs, tmp_path, capsys):
    comp = load_compensator(runs / "ls.npz")
    old = tmp_path / "old.joblib"
    joblib.dump({"format": "nfs-compensator/1", "compensator": comp}, old)
    code = main(["compensate", str(runs / "runs"), "--model", str(old),
                 "-o", str(tmp_path / "out"), "--trust-pickle"])
    err = capsys.readouterr().err
    assert code == 0
    assert err.startswith(f"nfs: warning: --trust-pickle: unpickling {old} runs any code")
    assert len(list((tmp_path / "out").glob("*.csv"))) == 2
    converted = load_compensator(old, trust_pickle=True).save(tmp_path / "new.npz")
    assert converted.read_bytes() == comp.save(tmp_path / "same.npz").read_bytes()


def test_every_estimator_on_the_list_is_the_packages_or_inside_one():
    # The list is the package's estimators and the two scikit-learn models they hold.
    outside = sorted(n for n in ESTIMATORS if not n.startswith("nfs.learners."))
    assert outside == ["sklearn.neural_network.MLPRegressor", "sklearn.svm.SVR"]


def test_every_name_on_the_lists_is_where_its_class_is_found():
    # The name written is the class's module and qualified name (scikit-learn's: the public
    # module it is imported from), so a name in a file says where its class is defined.
    for name, cls in {**ESTIMATORS, **RECORDS}.items():
        module, _, qualname = name.rpartition(".")
        if name.startswith("nfs."):
            assert (cls.__module__, cls.__qualname__) == (module, qualname)
        else:
            __import__(module)
            assert getattr(sys.modules[module], qualname) is cls


def test_every_former_name_reads_as_the_class_of_the_same_name():
    # Oracle: the former paths (nfs.compensate.kernels, regression, neural, search, tuners)
    # of every class a file of that time could name, each to a listed class of its name.
    listed = {**ESTIMATORS, **RECORDS}
    assert {n for n in listed if n.startswith("nfs.")} == set(FORMER_NAMES.values())
    for former, current in FORMER_NAMES.items():
        assert former.startswith("nfs.compensate.") and former not in listed
        assert former.rsplit(".", 1)[1] == current.rsplit(".", 1)[1]


def _with_former_names(path, out):
    """A copy of the model file ``path`` at ``out`` whose header names every class by its
    path before the move to nfs.learners."""
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    text = members["header.json"].decode()
    for former, current in FORMER_NAMES.items():
        text = text.replace(json.dumps(current), json.dumps(former))
    members["header.json"] = text.encode()
    with zipfile.ZipFile(out, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return out


@pytest.mark.parametrize("key", ["ls", "stepwise", "rbf", "lssvm", "ir-lssvm", "hho-rvr"])
def test_a_file_written_before_the_learners_moved_still_loads(tmp_path, key):
    # Stored data: written by nfs before the move (tests/data/model_files/README.md), with
    # its predictions at X_new then.  Tolerance 1e-12 relative: the same arrays through the
    # same arithmetic, up to another machine's BLAS summation order.
    path = STORED / f"{key}.npz"
    with zipfile.ZipFile(path) as zf:
        names = json.loads(zf.read("header.json"))["estimator"]
    assert names["$estimator"].startswith("nfs.compensate.")   # a file of that time
    header, est = read_model_file(path)
    assert header["method"] == key
    np.testing.assert_allclose(est.predict(header["X_new"]), header["prediction"],
                               rtol=1e-12, atol=1e-15)
    again = write_model_file(tmp_path / "again.npz", header, est)
    with zipfile.ZipFile(again) as zf:
        text = zf.read("header.json").decode()
    assert all(former not in text for former in FORMER_NAMES) and "nfs.learners." in text


def test_a_trusted_pickle_written_before_the_learners_moved_still_loads():
    # Stored data: a joblib pickle of an LS compensator that names its estimator
    # nfs.compensate.regression.CubicLeastSquares, with the predictions when written.
    path = STORED / "ls.joblib"
    assert b"nfs.compensate.regression" in path.read_bytes()
    comp = load_compensator(path, trust_pickle=True)
    assert type(comp.estimator) is CubicLeastSquares
    assert "nfs.compensate.regression" not in sys.modules     # the stand-in was removed
    with former_modules():
        stored = joblib.load(path)                             # X_new and the prediction
    np.testing.assert_allclose(comp.estimator.predict(stored["X_new"]), stored["prediction"],
                               rtol=1e-12, atol=1e-15)


def test_a_prepared_training_set_is_recorded_by_run_name(runs):
    from nfs.compensate import drift_dataset
    data = drift_dataset(read_runs(runs / "runs"), "seed004")
    comp = train_compensator("ls", data)
    assert comp.provenance == {"runs": [{"name": n} for n in data.run_names]}


def test_a_file_of_another_scikit_learn_version_loads_with_one_warning(tmp_path, runs,
                                                                       capsys):
    comp = load_compensator(runs / "ls.npz")
    path = DriftCompensator(**{**vars(comp), "versions": {"scikit-learn": "0.0"}}).save(
        tmp_path / "old_sklearn.npz")
    with pytest.warns(ModelVersionWarning, match="written with scikit-learn 0.0, read with"):
        load_compensator(path)
    code = main(["compensate", str(runs / "runs"), "--model", str(path),
                 "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 0 and err.startswith("nfs: warning: ") and err.count("\n") == 1
