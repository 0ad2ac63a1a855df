"""The catalogue of method names a scenario's reader checks without building a method.

Oracles: the built-in names equal what the seed papers' methods register (key, row, tuned,
default row), in the table's order; a name is found by key or row label; an unknown name is
one MethodError listing the known keys; a method a user registers is known too.
"""

import pytest
from sklearn.linear_model import Ridge

from nfs.compensate import METHODS, register_method, unregister_method
from nfs.compensate.catalog import (BUILTIN, MethodError, MethodName, known_methods,
                                    lookup_method, table_methods)


def test_the_builtin_names_are_what_the_methods_register():
    registered = {k: MethodName(m.key, m.name, m.tuned, m.table) for k, m in METHODS.items()
                  if k in BUILTIN}
    assert list(registered) == list(BUILTIN)
    assert registered == BUILTIN


def test_lookup_by_key_or_row_and_unknown_names():
    assert lookup_method("ssa-svr") == lookup_method("SSA-SVR") == BUILTIN["ssa-svr"]
    assert lookup_method("LS").tuned is False and lookup_method("tpe-svr").table is False
    with pytest.raises(MethodError, match="unknown compensation method 'svm'; methods: ls, "):
        lookup_method("svm")


def test_a_registered_method_is_known():
    register_method("ridge-catalog", Ridge(alpha=1.0), name="Ridge (catalogue)")
    try:
        assert lookup_method("Ridge (catalogue)").key == "ridge-catalog"
        assert "ridge-catalog" in known_methods() and "ridge-catalog" in table_methods()
    finally:
        unregister_method("ridge-catalog")
    assert "ridge-catalog" not in known_methods()
