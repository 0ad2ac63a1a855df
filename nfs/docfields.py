"""Field documentation of the package's dataclasses, visible in ``help()``.

The dataclasses document each field with a string right below it (the convention of
attribute docstrings that Sphinx and IDEs read). Python itself keeps no record of those
strings, so ``help(NorthFindResult)`` would show the fields' names and types only.
:func:`document_fields` reads them from the class's source once, at import, and appends a
numpydoc ``Attributes`` section to the class docstring.

Written here because neither the standard library (before Python 3.14's ``field(doc=...)``)
nor NumPy/SciPy offers it; the source is read with :mod:`inspect` and parsed with :mod:`ast`.
Where the source is not available (a zipped or frozen install) the class is left as it was.
"""

from __future__ import annotations

import ast
import inspect
import textwrap

__all__ = ["document_fields", "field_docs"]


def field_docs(cls: type) -> dict[str, tuple[str, str]]:
    """Field name -> (annotation as written, its docstring) of a class, in source order.

    Empty when the source cannot be read.
    """
    try:
        source = textwrap.dedent(inspect.getsource(cls))
    except (OSError, TypeError):
        return {}
    tree = ast.parse(source)
    node = next((n for n in tree.body if isinstance(n, ast.ClassDef)), None)
    if node is None:
        return {}
    out: dict[str, tuple[str, str]] = {}
    for a, b in zip(node.body, node.body[1:]):
        if (isinstance(a, ast.AnnAssign) and isinstance(a.target, ast.Name)
                and isinstance(b, ast.Expr) and isinstance(b.value, ast.Constant)
                and isinstance(b.value.value, str)):
            out[a.target.id] = (ast.unparse(a.annotation), inspect.cleandoc(b.value.value))
    return out


def document_fields(cls: type) -> type:
    """Class decorator: append an ``Attributes`` section built from the field docstrings.

    A class whose docstring already has an ``Attributes`` section, or whose fields carry no
    docstrings, is returned unchanged.
    """
    doc = inspect.cleandoc(cls.__doc__ or "")
    if "\nAttributes\n---" in doc:
        return cls
    fields = field_docs(cls)
    if not fields:
        return cls
    lines = [doc, "", "Attributes", "----------"]
    for name, (annotation, text) in fields.items():
        lines.append(f"{name} : {annotation}")
        lines.extend("    " + line if line else "" for line in text.splitlines())
    cls.__doc__ = "\n".join(lines)
    return cls
