"""The learners as a layer: what nfs.learners imports, what it exports, what is checked.

Oracles: invariants of the layout (style.md, "Layout"): nfs.learners imports of nfs only
nfs.errors and nfs.docfields, read from the source of every module and confirmed by the
modules an import of nfs.learners loads in a fresh interpreter; and every estimator it
exports is run through scikit-learn's estimator checks by a test of tests/learners (read
from those tests' source).
"""

import ast
import subprocess
import sys
from pathlib import Path

from sklearn.base import BaseEstimator

import nfs.learners

ROOT = Path(__file__).resolve().parents[2]
LEARNERS = ROOT / "nfs" / "learners"

#: The modules of nfs outside nfs.learners that it may import.
ALLOWED = {"nfs.errors", "nfs.docfields"}


def _imported_modules(path: Path) -> set[str]:
    """Absolute names of the modules that ``path`` (a module of nfs.learners) imports."""
    package = ".".join(path.relative_to(ROOT).with_suffix("").parts)
    if path.name != "__init__.py":
        package = package.rsplit(".", 1)[0]
    else:
        package = package.removesuffix(".__init__")
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                name = f"{base}.{node.module}" if node.module else base
                # "from . import x" imports the submodule x
                out.update({name} if node.module else {f"{base}.{a.name}" for a in node.names})
            else:
                out.add(node.module)
    return out


def test_learners_import_nothing_of_the_domain():
    sources = sorted(LEARNERS.rglob("*.py"))
    assert len(sources) >= 10
    for path in sources:
        outside = {m for m in _imported_modules(path)
                   if (m == "nfs" or m.startswith("nfs.")) and not m.startswith("nfs.learners")}
        assert outside <= ALLOWED, f"{path.relative_to(ROOT)} imports {sorted(outside - ALLOWED)}"


def test_importing_the_learners_loads_no_domain_module():
    code = ("import sys, nfs.learners; "
            "print(' '.join(sorted(m for m in sys.modules if m.startswith('nfs'))))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True, cwd=ROOT).stdout.split()
    outside = {m for m in loaded if not m.startswith("nfs.learners")}
    assert outside <= ALLOWED | {"nfs"}, sorted(outside)


def _checked_classes() -> set[str]:
    """Names of the classes instantiated in the arguments of parametrize_with_checks and
    check_estimator in tests/learners (through the variable, where one is passed)."""
    names = set()
    for path in Path(__file__).parent.glob("test_*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        assigned: dict[str, list[ast.AST]] = {}
        for node in ast.walk(tree):
            if isinstance(node, ast.Assign):
                for t in node.targets:
                    if isinstance(t, ast.Name):
                        assigned.setdefault(t.id, []).append(node.value)
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id in ("parametrize_with_checks", "check_estimator")):
                continue
            for arg in node.args:
                values = assigned.get(arg.id, [arg]) if isinstance(arg, ast.Name) else [arg]
                names.update(n.func.id for v in values for n in ast.walk(v)
                             if isinstance(n, ast.Call) and isinstance(n.func, ast.Name))
    return names


def test_every_exported_estimator_is_run_through_the_estimator_checks():
    exported = {name for name in nfs.learners.__all__
                if isinstance(getattr(nfs.learners, name), type)
                and issubclass(getattr(nfs.learners, name), BaseEstimator)}
    assert len(exported) == 9
    missing = exported - _checked_classes()
    assert not missing, f"no estimator check runs {sorted(missing)}"
