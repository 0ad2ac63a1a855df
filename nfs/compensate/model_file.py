"""The model file of a trained compensator (``nfs-model/1``): read without running any code.

A pickle (what ``joblib.dump`` writes) rebuilds its objects by calling whatever functions the
file names, so loading a pickle from an untrusted source runs its code (scikit-learn's
documentation warns so for its own models).  A model file instead holds only data:

* a zip archive (the layout of NumPy's ``.npz``), whose member ``header.json`` is a JSON
  document and whose other members ``a0.npy``, ``a1.npy``, ... are arrays in NumPy's ``.npy``
  format, read with ``allow_pickle=False`` (numbers, booleans and text only);
* the header: ``format`` (:data:`FORMAT`), the package version, what the caller stores
  beside the model (features, features mode, settings, training provenance), and the
  fitted estimator as a tree of JSON values.

The estimator tree names every object's class by a key of :data:`ESTIMATORS` or
:data:`RECORDS`, an explicit list of the package's own estimators and the few
scikit-learn estimators inside them (``sklearn.svm.SVR`` in the SVR rows, ``MLPRegressor``
in the BP network), or of a class a registered method lists in its ``model_classes`` (a
user's own, registered where the file is written and where it is read).  An estimator
is written as its class, its hyper-parameters (``get_params(deep=False)``) and its fitted
state (every other attribute), and read back by setting that state on a bare instance of
the listed class, without calling ``fit``: the loaded model predicts with the same arrays
through the same code, bit for bit.  Reading a name that is not on the lists is an error,
and so is writing an object of another class (one line that names it); nothing in a file
selects code to run.  A name is the class's module and qualified name
(``nfs.learners.svr.SVRRegressor``; a registered method's class by its public path,
``sklearn.linear_model.Ridge``); the names of the files written before the estimators
moved to :mod:`nfs.learners` (``nfs.compensate.kernels.SVRRegressor``, ...) are read as the
same classes (:data:`FORMER_NAMES`), and so are the classes of a trusted pickle of that
time (:func:`former_modules`).

Value encoding in the tree (a JSON object with a key starting with ``$`` is one of these):

========================  ==============================================================
``{"$array": "a3"}``      an array (member ``a3.npy``)
``{"$number": dtype,      a NumPy scalar of that dtype (``value`` a JSON number, or
"value": v}``             ``{"$float": "nan"}``)
``{"$float": "inf"}``     a non-finite float (JSON has none)
``{"$tuple": [...]}``     a tuple
``{"$strings": [...],     an object array of str (scikit-learn's feature names)
"shape": [...]}``
``{"$dict": {...}}``      a dict whose keys start with ``$``
``{"$estimator": name,    an estimator of :data:`ESTIMATORS`
"params": {...},
"fitted": {...}}``
``{"$record": name,       a frozen dataclass of :data:`RECORDS` (a stepwise step, a
"fields": {...}}``        search dimension, a tuner's result)
``{"$function": name}``   a function of :data:`FUNCTIONS` (the tuners' score)
``{"$random_state":       a NumPy ``RandomState`` and its state
{...}}``
========================  ==============================================================

Not written: the state of ``MLPRegressor``'s stochastic optimiser (``_optimizer``: Adam's
moment estimates, used only to continue training; a ``partial_fit`` of a loaded BP network
starts a new optimiser).  The scikit-learn estimators are restored from their attributes, as
a pickle restores them: a file read by another scikit-learn version than the one that wrote
it gets a warning, and its private attributes may have changed.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import math
import sys
import types
import warnings
import zipfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import sklearn
from sklearn.base import BaseEstimator
from sklearn.exceptions import InconsistentVersionWarning
from sklearn.neural_network import MLPRegressor
from sklearn.svm import SVR

from .. import __version__
from ..errors import InputError
from ..io.atomic import atomic_write_bytes
from ..learners.linear import CubicLeastSquares
from ..learners.lssvm import IRLSSVMRegressor, LSSVMRegressor
from ..learners.neural import BPNetwork, RBFNetwork
from ..learners.rvr import RVRRegressor
from ..learners.search import Integer, MetaheuristicSearchCV, Real
from ..learners.stepwise import StepwiseRegression, StepwiseStep
from ..learners.svr import SVRRegressor
from ..learners.tuners.evaluation import TuneResult
from .methods import neg_residual_std
from .registry import class_path, model_classes

__all__ = ["FORMAT", "HEADER_NAME", "ESTIMATORS", "RECORDS", "FUNCTIONS", "FORMER_NAMES",
           "ModelFileError", "ModelVersionWarning", "write_model_file", "read_model_file",
           "model_file_kind", "former_modules"]

#: Format tag of a model file.
FORMAT = "nfs-model/1"

#: The zip member that holds the JSON header.
HEADER_NAME = "header.json"

#: Estimators a model file may hold, by the name written in it: the module and qualified
#: name of the package's own classes, the public path of scikit-learn's.
ESTIMATORS: dict[str, type] = {
    "nfs.learners.linear.CubicLeastSquares": CubicLeastSquares,
    "nfs.learners.stepwise.StepwiseRegression": StepwiseRegression,
    "nfs.learners.neural.BPNetwork": BPNetwork,
    "nfs.learners.neural.RBFNetwork": RBFNetwork,
    "nfs.learners.lssvm.LSSVMRegressor": LSSVMRegressor,
    "nfs.learners.lssvm.IRLSSVMRegressor": IRLSSVMRegressor,
    "nfs.learners.svr.SVRRegressor": SVRRegressor,
    "nfs.learners.rvr.RVRRegressor": RVRRegressor,
    "nfs.learners.search.MetaheuristicSearchCV": MetaheuristicSearchCV,
    "sklearn.svm.SVR": SVR,                              # inside SVRRegressor
    "sklearn.neural_network.MLPRegressor": MLPRegressor,  # inside BPNetwork
}

#: Frozen dataclasses an estimator's state may hold, by name (rebuilt by their constructor).
RECORDS: dict[str, type] = {
    "nfs.learners.stepwise.StepwiseStep": StepwiseStep,
    "nfs.learners.search.Real": Real,
    "nfs.learners.search.Integer": Integer,
    "nfs.learners.tuners.evaluation.TuneResult": TuneResult,
}

#: The names that files written before the estimators and tuners moved to
#: :mod:`nfs.learners` (nfs 0.1.0 up to that move) give the same classes, and the names read
#: in their place.  Read, never written.
FORMER_NAMES: dict[str, str] = {
    "nfs.compensate.regression.CubicLeastSquares": "nfs.learners.linear.CubicLeastSquares",
    "nfs.compensate.regression.StepwiseRegression": "nfs.learners.stepwise.StepwiseRegression",
    "nfs.compensate.neural.BPNetwork": "nfs.learners.neural.BPNetwork",
    "nfs.compensate.neural.RBFNetwork": "nfs.learners.neural.RBFNetwork",
    "nfs.compensate.kernels.LSSVMRegressor": "nfs.learners.lssvm.LSSVMRegressor",
    "nfs.compensate.kernels.IRLSSVMRegressor": "nfs.learners.lssvm.IRLSSVMRegressor",
    "nfs.compensate.kernels.SVRRegressor": "nfs.learners.svr.SVRRegressor",
    "nfs.compensate.kernels.RVRRegressor": "nfs.learners.rvr.RVRRegressor",
    "nfs.compensate.search.MetaheuristicSearchCV": "nfs.learners.search.MetaheuristicSearchCV",
    "nfs.compensate.regression.StepwiseStep": "nfs.learners.stepwise.StepwiseStep",
    "nfs.compensate.search.Real": "nfs.learners.search.Real",
    "nfs.compensate.search.Integer": "nfs.learners.search.Integer",
    "nfs.compensate.tuners.TuneResult": "nfs.learners.tuners.evaluation.TuneResult",
}


@contextlib.contextmanager
def former_modules() -> Iterator[None]:
    """Make the former modules of :data:`FORMER_NAMES` importable while the block runs.

    A trusted pickle of an earlier version (``load_compensator(path, trust_pickle=True)``)
    names its classes by the modules they lived in (``nfs.compensate.kernels``, ...), which
    no longer exist, and unpickling imports a class's module by that name.  Each former
    module is put in ``sys.modules`` as a stand-in holding its former classes (the current
    ones), for the block only, and only where no module of that name is imported already.
    """
    classes = {**ESTIMATORS, **RECORDS}
    stand_ins: dict[str, types.ModuleType] = {}
    for former, current in FORMER_NAMES.items():
        module, _, name = former.rpartition(".")
        if module in sys.modules and module not in stand_ins:
            continue
        stand_in = stand_ins.setdefault(module, types.ModuleType(
            module, f"Stand-in for {module} while a trusted pickle is read"))
        setattr(stand_in, name, classes[current])
    sys.modules.update(stand_ins)
    try:
        yield
    finally:
        for module, stand_in in stand_ins.items():
            if sys.modules.get(module) is stand_in:
                del sys.modules[module]


#: Functions an estimator's state may refer to, by name (the tuners' scoring).
FUNCTIONS: dict[str, Callable] = {
    "nfs.compensate.methods.neg_residual_std": neg_residual_std,
}

#: Attributes not written, by class, and why.
_NOT_WRITTEN: dict[type, dict[str, str]] = {
    MLPRegressor: {"_optimizer": "the stochastic solver's state, used only to go on training"},
}

_FUNCTION_NAME = {id(f): name for name, f in FUNCTIONS.items()}

#: Array dtypes written (booleans, integers, floats, complex, text): none needs a pickle.
_ARRAY_KINDS = "biufcU"

#: Zip member time stamp: fixed, so that one model writes the same bytes every time.
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)

#: Leading bytes of a pickle (protocol 2 and later: PROTO opcode) and of the compressed
#: files joblib writes pickles into (joblib.compressor: gzip, bz2, lzma, xz, lz4; ZF the
#: format of joblib before 0.10; zlib is told by its header check, :func:`_is_zlib`).
_PICKLE_PREFIXES = (b"\x80\x02", b"\x80\x03", b"\x80\x04", b"\x80\x05")
_JOBLIB_PREFIXES = (b"\x1f\x8b", b"BZh", b"]\x00", b"\xfd7zXZ", b'\x04"M\x18', b"ZF")
_ZIP_PREFIXES = (b"PK\x03\x04", b"PK\x05\x06")


class ModelFileError(InputError):
    """A file that is not a model file this version can read, or a model it cannot write."""


class ModelVersionWarning(UserWarning):
    """A model file written with another scikit-learn version than the one reading it."""


# --------------------------------------------------------------------------------------
# writing
# --------------------------------------------------------------------------------------

class _Encoder:
    """Turns an estimator into JSON values, collecting its arrays (a class is written by
    the package's own name where a registered method lists it too)."""

    def __init__(self) -> None:
        self.arrays: list[np.ndarray] = []
        self.names = {c: n for n, c in {**model_classes(), **ESTIMATORS, **RECORDS}.items()}

    def __call__(self, value: Any, where: str) -> Any:
        if value is None or isinstance(value, (bool, str)):
            return value
        if isinstance(value, int) and not isinstance(value, np.integer):
            return value
        if isinstance(value, float) and not isinstance(value, np.floating):
            return value if math.isfinite(value) else {"$float": repr(value)}
        if isinstance(value, np.generic):
            if value.dtype.kind not in _ARRAY_KINDS or value.dtype.kind in "cU":
                raise ModelFileError(f"{where}: a NumPy scalar of dtype {value.dtype} cannot "
                                     "be written to a model file")
            return {"$number": value.dtype.str, "value": self(value.item(), where)}
        if isinstance(value, np.ndarray):
            return self._array(value, where)
        if isinstance(value, list):
            return [self(v, f"{where}[{i}]") for i, v in enumerate(value)]
        if isinstance(value, tuple):
            return {"$tuple": [self(v, f"{where}[{i}]") for i, v in enumerate(value)]}
        if isinstance(value, dict):
            return self._dict(value, where)
        if isinstance(value, np.random.RandomState):
            return {"$random_state": self(value.get_state(legacy=False), where)}
        if callable(value) and id(value) in _FUNCTION_NAME:
            return {"$function": _FUNCTION_NAME[id(value)]}
        name = self.names.get(type(value))
        if name is None:
            raise ModelFileError(
                f"{where}: a {class_path(type(value))} cannot be written to a model file, "
                "which holds the package's own estimators ("
                + ", ".join(n.rsplit(".", 1)[1] for n in ESTIMATORS) + ") and the classes "
                "a registered method lists in register_method(..., model_classes=)")
        if name in RECORDS:
            return {"$record": name,
                    "fields": {f.name: self(getattr(value, f.name), f"{where}.{f.name}")
                               for f in dataclasses.fields(value)}}
        return self._estimator(name, value, where)

    def _array(self, value: np.ndarray, where: str) -> dict:
        if value.dtype.kind == "O":
            flat = value.ravel().tolist()
            if not all(isinstance(s, str) for s in flat):
                raise ModelFileError(f"{where}: an object array of other values than text "
                                     "cannot be written to a model file")
            return {"$strings": flat, "shape": list(value.shape)}
        if value.dtype.kind not in _ARRAY_KINDS or value.dtype.names is not None:
            raise ModelFileError(f"{where}: an array of dtype {value.dtype} cannot be written "
                                 "to a model file")
        self.arrays.append(value)
        return {"$array": f"a{len(self.arrays) - 1}"}

    def _dict(self, value: dict, where: str) -> dict:
        if not all(isinstance(k, str) for k in value):
            raise ModelFileError(f"{where}: a dict with keys other than text cannot be "
                                 "written to a model file")
        out = {k: self(v, f"{where}.{k}") for k, v in value.items()}
        return {"$dict": out} if any(k.startswith("$") for k in value) else out

    def _estimator(self, name: str, est: BaseEstimator, where: str) -> dict:
        state = est.__getstate__()
        params = est.get_params(deep=False)
        skip = _NOT_WRITTEN.get(type(est), {})
        return {"$estimator": name,
                "params": {k: self(v, f"{where}.{k}") for k, v in state.items() if k in params},
                "fitted": {k: self(v, f"{where}.{k}") for k, v in state.items()
                           if k not in params and k not in skip}}


def write_model_file(path: str | Path, header: dict, estimator: Any) -> Path:
    """Write ``estimator`` and ``header`` as a model file at ``path``, atomically.

    Parameters
    ----------
    path : str or Path
        The file (written as given, whatever its extension; ``.npz`` is the natural one).
    header : dict
        JSON values stored beside the model (features, settings, provenance, ...); the keys
        ``format``, ``nfs_version`` and ``estimator`` are set here.
    estimator : estimator of :data:`ESTIMATORS` or of a registered method's model_classes
        The fitted model.

    Returns
    -------
    Path

    Raises
    ------
    ModelFileError
        When the estimator holds an object that is not on the lists (e.g. a user's own
        weight function), naming where.
    """
    enc = _Encoder()
    doc = {"format": FORMAT, "nfs_version": __version__}
    doc.update({k: enc(v, k) for k, v in header.items()
                if k not in ("format", "nfs_version", "estimator")})
    doc["estimator"] = enc(estimator, "estimator")
    text = json.dumps(doc, indent=1, allow_nan=False) + "\n"
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr(_member(HEADER_NAME), text.encode("utf-8"))
        for i, arr in enumerate(enc.arrays):
            member = io.BytesIO()
            np.lib.format.write_array(member, arr, allow_pickle=False)
            zf.writestr(_member(f"a{i}.npy"), member.getvalue())
    atomic_write_bytes(path, buf.getvalue())
    return Path(path)


def _member(name: str) -> zipfile.ZipInfo:
    info = zipfile.ZipInfo(name, date_time=_ZIP_TIME)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = 0o644 << 16
    return info


# --------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------

def model_file_kind(path: str | Path) -> str:
    """What a file is, from its leading bytes and zip layout, without loading it.

    Returns
    -------
    str
        ``"nfs-model"`` (a zip archive with ``header.json``), ``"pickle"`` (a pickle, or a
        file compressed as joblib compresses its pickles), ``"zip"`` (another zip archive,
        e.g. one holding a pickle as PyTorch writes), ``"other"``, or ``"missing"``.
    """
    path = Path(path)
    if not path.is_file():
        return "missing"
    with open(path, "rb") as f:
        head = f.read(8)
    if head.startswith(_ZIP_PREFIXES):
        try:
            with zipfile.ZipFile(path) as zf:
                return "nfs-model" if HEADER_NAME in zf.namelist() else "zip"
        except zipfile.BadZipFile:
            return "other"
    if head.startswith(_PICKLE_PREFIXES) or head.startswith(_JOBLIB_PREFIXES) or \
            _is_zlib(head):
        return "pickle"
    return "other"


def _is_zlib(head: bytes) -> bool:
    """A zlib stream of the deflate method with a 32 KiB window, as joblib's zlib writes
    (RFC 1950 section 2.2: CMF = 0x78, and CMF * 256 + FLG a multiple of 31)."""
    return len(head) >= 2 and head[0] == 0x78 and (head[0] * 256 + head[1]) % 31 == 0


def read_model_file(path: str | Path) -> tuple[dict, Any]:
    """Read a file written by :func:`write_model_file`: its header and its estimator.

    Only JSON and ``.npy`` arrays are parsed (``numpy.load(..., allow_pickle=False)``), and
    only the classes of :data:`ESTIMATORS` and :data:`RECORDS` and those the registered
    methods list are instantiated; nothing in the file is run.  A pickle is refused by its
    leading bytes, before it is opened as one.

    Returns
    -------
    header : dict
        The JSON header with its values decoded (the ``estimator`` entry removed).
    estimator
        The fitted estimator.

    Raises
    ------
    ModelFileError
        A missing file, a pickle, a foreign or corrupt file, or an unknown format, in one
        line that names the file and says why.
    """
    path = Path(path)
    kind = model_file_kind(path)
    if kind == "missing":
        raise ModelFileError("model file not found", file=path)
    if kind == "pickle":
        raise ModelFileError(
            f"a pickle, not a {FORMAT} model file: unpickling runs whatever code it holds, "
            "so it is not loaded; retrain with nfs train, or pass --trust-pickle "
            "(trust_pickle=True) if you trust its source", file=path)
    if kind != "nfs-model":
        what = "a zip archive without header.json" if kind == "zip" else "neither a model " \
            "file nor a pickle"
        raise ModelFileError(f"not a compensator model file ({what}; expected {FORMAT})",
                             file=path)
    data = path.read_bytes()
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as zf:
            doc = json.loads(zf.read(HEADER_NAME).decode("utf-8"))
        fmt = doc.get("format") if isinstance(doc, dict) else None
        if fmt != FORMAT:
            raise ModelFileError(f"model format {fmt!r}: this version of nfs reads {FORMAT} "
                                 f"(nfs {__version__})", file=path)
        with np.load(io.BytesIO(data), allow_pickle=False) as npz, \
                warnings.catch_warnings():
            warnings.simplefilter("ignore", InconsistentVersionWarning)
            dec = _Decoder(npz)
            estimator = dec(doc.pop("estimator"))
            header = {k: dec(v) for k, v in doc.items()}
    except ModelFileError as exc:
        if exc.file is None:
            raise ModelFileError(exc.message, file=path) from None
        raise
    except (ValueError, KeyError, TypeError, AttributeError, RecursionError, OSError,
            zipfile.BadZipFile, UnicodeDecodeError) as exc:
        raise ModelFileError(f"corrupt model file ({type(exc).__name__}: {exc})",
                             file=path) from None
    written = (header.get("versions") or {}).get("scikit-learn")
    if isinstance(written, str) and written != sklearn.__version__:
        warnings.warn(f"{path}: written with scikit-learn {written}, read with "
                      f"{sklearn.__version__}: its scikit-learn parts may predict otherwise",
                      ModelVersionWarning, stacklevel=2)
    return header, estimator


class _Decoder:
    """Turns the JSON values of a header back into Python objects."""

    def __init__(self, npz) -> None:
        self.npz = npz

    def __call__(self, value: Any) -> Any:
        if isinstance(value, list):
            return [self(v) for v in value]
        if not isinstance(value, dict):
            return value
        marker = [k for k in value if k.startswith("$")]
        if not marker:
            return {k: self(v) for k, v in value.items()}
        kind = marker[0]
        if len(marker) != 1:
            raise ValueError(f"an object with several markers {marker}")
        body = value[kind]
        if kind == "$array":
            if not isinstance(body, str) or f"{body}.npy" not in self.npz.zip.namelist():
                raise ValueError(f"no array member {body!r}")
            return self.npz[body]
        if kind == "$number":
            dtype = np.dtype(body)
            if dtype.kind not in "biuf":
                raise ValueError(f"a scalar of dtype {dtype}")
            return dtype.type(self(value["value"]))
        if kind == "$float":
            if body not in ("nan", "inf", "-inf"):
                raise ValueError(f"a float {body!r}")
            return float(body)
        if kind == "$tuple":
            return tuple(self(body))
        if kind == "$strings":
            if not all(isinstance(s, str) for s in body):
                raise ValueError("$strings holds other values than text")
            out = np.empty(len(body), dtype=object)
            out[:] = body
            return out.reshape([int(n) for n in value["shape"]])
        if kind == "$dict":
            return {k: self(v) for k, v in body.items()}
        if kind == "$function":
            return FUNCTIONS[body]
        if kind == "$random_state":
            rs = np.random.RandomState()
            rs.set_state(self(body))
            return rs
        if kind == "$record":
            cls = _listed(RECORDS, body, "record")
            return cls(**{k: self(v) for k, v in value["fields"].items()})
        if kind == "$estimator":
            cls = _listed({**model_classes(), **ESTIMATORS}, body, "estimator")
            est = cls.__new__(cls)
            est.__setstate__({**{k: self(v) for k, v in value["params"].items()},
                              **{k: self(v) for k, v in value["fitted"].items()}})
            return est
        raise ValueError(f"unknown marker {kind!r}")


def _listed(table: dict[str, type], name, what: str) -> type:
    try:
        return table[FORMER_NAMES.get(name, name)]
    except (KeyError, TypeError):
        raise ModelFileError(f"{what} class {name!r} is not one a model file may hold "
                             f"({', '.join(table)})") from None
