"""The README's numbers (and the user guide's tables, docs/compensation.md) are rebuilt by
docs/readme_numbers.py and must agree with it: every page that shows a block
(readme_numbers.PAGES) is checked."""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("readme_numbers", ROOT / "docs" / "readme_numbers.py")
readme_numbers = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(readme_numbers)


def _check(name):
    table, _ = readme_numbers.compute(name)
    pages = readme_numbers.PAGES[name]
    assert pages
    for page in pages:
        text = page.read_text(encoding="utf-8")
        assert readme_numbers.differences(name, text, table) == [], page


@pytest.mark.integration       # the default table's whole study (nfs table): about 30 s
def test_default_table_in_readme_is_what_the_package_prints():
    _check("default-table")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["fleet-table", "precise-table"])
def test_other_tables_in_readme(name):
    _check(name)


def test_the_check_fails_on_a_changed_number():
    # Oracle: a README whose before row is off by one in the last digit, or whose compensated
    # mean lies outside its own stated interval, is reported.
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert ROOT / "README.md" in readme_numbers.PAGES["default-table"]
    rows = readme_numbers.parse("default-table", text)
    assert {"before", "stable", "floor", "SSA-SVR"} <= set(rows)
    from nfs.scoring.heading_table import HeadingTable, TableRow
    n_t = len(rows["before"]) - 4
    temps = tuple(float(t) for t in range(n_t))

    def row(name, bump=0.0):
        vals = [float(v) for v in rows[name][:n_t]]
        return TableRow(name, tuple(v + bump for v in vals))
    ok = [row(n) for n in rows if n in readme_numbers.EXACT_ROWS]
    far = TableRow("SSA-SVR", (1.0,) * n_t)          # a mean of 1 deg: outside any interval
    bad = HeadingTable(temps, tuple([row("before", 1e-4)] + ok[1:] + [far]))
    for page in readme_numbers.PAGES["default-table"]:   # the README and the user guide
        problems = readme_numbers.differences("default-table",
                                              page.read_text(encoding="utf-8"), bad)
        assert any(p.startswith("default-table: before: README") for p in problems), page
        assert any(p.startswith("default-table: SSA-SVR: mean 1.0000 outside the README's "
                                "interval") for p in problems), page
