"""The user documentation (docs/) against the package it documents.

Oracles: the effect registry (every built-in effect has an entry in docs/effects.md, and no
registered effect is still announced as coming); the file system (every page README.md and
the docs link to exists); the section and equation numbers of docs/physics.md (every
"docs/physics.md section N" or "(N.M)" the code cites exists there, as a heading or as the
``\\tag{N.M}`` of a display equation); the bibliography (every
"Author (year)" a page cites has an entry in docs/references.md, and the papers the package
reproduces carry a year).
"""

import re
from pathlib import Path

import pytest

from nfs.effects import available_effects, get_effect

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

#: Folders whose files may cite docs/physics.md (code, presets, scenarios, examples).
CITING = ("nfs", "thermal", "scenarios", "examples", "benchmarks")
CITING_SUFFIXES = {".py", ".toml", ".md"}

#: Keys in docs/references.md of the papers the package reproduces (the start-up experiment,
#: its reference tables, and the compensation methods of `nfs table`).
REPRODUCED = ("FOG start-up paper", "Tao et al. (2019)", "Cheng et al. (2015)",
              "Liang et al. (2021)")

_NOT_YET = "## Not yet in the library"


def _read(name: str) -> str:
    path = DOCS / name
    assert path.is_file(), f"{path} is missing"
    return path.read_text(encoding="utf-8")


def _builtin_effects() -> list[str]:
    """Registered effects defined by the package itself (user and test effects excluded)."""
    return [n for n in available_effects()
            if get_effect(n).function.__module__.startswith("nfs.effects.")]


def _library_part(text: str) -> str:
    """docs/effects.md up to its "Not yet in the library" section."""
    return text.split(_NOT_YET)[0]


def _documented(text: str, name: str) -> bool:
    """``name`` has a heading (### `name`) or a table row (| `name` | ...) in ``text``."""
    pattern = rf"^(#+ `{re.escape(name)}`\s*$|\| `{re.escape(name)}` \|)"
    return re.search(pattern, text, flags=re.M) is not None


# --------------------------------------------------------------------------------------------
# effects.md against the registry

def test_builtin_effects_found():
    names = _builtin_effects()
    assert "shupe_gradient" in names and "null" in names and len(names) >= 15


@pytest.mark.parametrize("name", _builtin_effects())
def test_every_registered_effect_is_documented(name):
    library = _library_part(_read("effects.md"))
    assert _documented(library, name), (
        f"effect '{name}' is registered but docs/effects.md has no heading '### `{name}`' or "
        f"table row for it above '{_NOT_YET}' (move it out of that section when it lands)")


def test_every_registered_effect_has_a_heading_with_its_parameters():
    library = _library_part(_read("effects.md"))
    for name in _builtin_effects():
        m = re.search(rf"^### `{re.escape(name)}`\s*$(.*?)(?=^#{{2,3}} )", library,
                      flags=re.M | re.S)
        assert m, f"docs/effects.md: no section '### `{name}`'"
        body = m.group(1)
        for p in get_effect(name).parameters:
            assert p.name in body, f"docs/effects.md, `{name}`: parameter '{p.name}' not named"
            if p.unit:
                assert p.unit in body, (f"docs/effects.md, `{name}`: unit [{p.unit}] of "
                                        f"'{p.name}' not given")


def test_effects_announced_as_coming_are_not_registered():
    text = _read("effects.md")
    assert _NOT_YET in text
    coming = re.findall(r"^\| `([a-z_]+)` \(coming\) \|", text.split(_NOT_YET)[1], flags=re.M)
    registered = set(available_effects())
    landed = sorted(set(coming) & registered)
    assert not landed, (f"{landed} registered now: document them in docs/effects.md like the "
                        "other effects and drop their '(coming)' rows")


_GRID_ROW = re.compile(r"^\| `([a-z_]+)` \| (\w+) \[[^\]]*\] \| ([^|(]+)", flags=re.M)


def test_grid_table_matches_the_registry():
    """Oracle: the registry.  docs/effects.md's table of the grids the diagnosis tries (in
    "Your own effects") lists every built-in parameter with a grid, with its values."""
    own = _read("effects.md").split("## Your own effects")[1].split("\n## ")[0]
    documented = {(e, p): v.strip() for e, p, v in _GRID_ROW.findall(own)}
    registered = {(n, p.name): ", ".join(f"{v:g}" for v in p.grid)
                  for n in _builtin_effects() for p in get_effect(n).parameters
                  if p.grid is not None}
    assert registered and documented == registered


# --------------------------------------------------------------------------------------------
# links

_LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


def _local_links(text: str) -> list[str]:
    return [t.split("#")[0] for t in _LINK.findall(text)
            if not re.match(r"[a-z]+:", t) and not t.startswith("#")]


def test_link_parser():
    text = "see [a](docs/a.md), [b](https://x.org/b.md), [c](#top) and [d](../e.md#sec)"
    assert _local_links(text) == ["docs/a.md", "../e.md"]


def test_readme_links_exist():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    links = _local_links(readme)
    for page in ("docs/physics.md", "docs/effects.md", "docs/measurement-format.md",
                 "docs/references.md"):
        assert page in links, f"README.md does not link {page}"
    missing = [t for t in links if not (ROOT / t).exists()]
    assert not missing, f"README.md links missing files: {missing}"


@pytest.mark.parametrize("page", sorted(p.name for p in DOCS.glob("*.md")))
def test_docs_links_exist(page):
    links = _local_links(_read(page))
    missing = [t for t in links if not (DOCS / t).exists()]
    assert not missing, f"docs/{page} links missing files: {missing}"


# --------------------------------------------------------------------------------------------
# physics.md: the sections and equations the code cites

_SECTION_CITE = re.compile(
    r"docs/physics\.md,?\s+(?:sections?|sec\.?)\s+(\d+(?:\s*(?:,|and|&)\s*\d+)*)")
_EQUATION_CITE = re.compile(r"docs/physics\.md,?\s+(?:eq\.?\s*|equation\s*)?\((\d+\.\d+)\)")


def _cited_sections(text: str) -> set[int]:
    return {int(n) for m in _SECTION_CITE.finditer(text) for n in re.findall(r"\d+", m.group(1))}


def _cited_equations(text: str) -> set[str]:
    return set(_EQUATION_CITE.findall(text))


def _physics_sections() -> set[int]:
    return {int(n) for n in re.findall(r"^## (\d+)\. ", _read("physics.md"), flags=re.M)}


def _physics_equations() -> set[str]:
    """The numbers of the page's display equations: ``\\tag{N.M}`` in their ``$$`` blocks."""
    return set(re.findall(r"\\tag\{(\d+\.\d+)\}", _read("physics.md")))


def _citing_files():
    for folder in CITING:
        for path in sorted((ROOT / folder).rglob("*")):
            if path.suffix in CITING_SUFFIXES and path.is_file():
                yield path


def test_citation_parser():
    text = ("(docs/physics.md section 5) docs/physics.md sections 4 and 5; "
            "docs/physics.md, sec. 2, docs/physics.md sections 1, 3 and 7; "
            "docs/physics.md (5.3) and docs/physics.md eq. (2.4)")
    assert _cited_sections(text) == {1, 2, 3, 4, 5, 7}
    assert _cited_equations(text) == {"5.3", "2.4"}


def test_physics_keeps_the_spec_numbering():
    """The sections the code cited as the internal physics spec keep their topics."""
    text = _read("physics.md")
    for n, topic in ((1, "instrument and the experiment"), (2, "thermal network"),
                     (3, "FOG drift and noise"), (4, "Accelerometers and tilt"),
                     (5, "Multiposition north finding"), (6, "Compensation"),
                     (7, "Effects a first model tends to miss")):
        assert re.search(rf"^## {n}\. .*{topic}", text, flags=re.M | re.I), (n, topic)


def test_every_cited_physics_section_exists():
    sections = _physics_sections()
    equations = _physics_equations()
    assert {1, 2, 3, 4, 5, 6, 7, 8} <= sections
    assert {"2.4", "3.2", "5.3", "5.5"} <= equations
    bad = []
    for path in _citing_files():
        text = path.read_text(encoding="utf-8", errors="replace")
        rel = path.relative_to(ROOT)
        bad += [f"{rel}: section {n}" for n in sorted(_cited_sections(text) - sections)]
        bad += [f"{rel}: ({e})" for e in sorted(_cited_equations(text) - equations)]
    assert not bad, "cited but not in docs/physics.md: " + "; ".join(bad)


# --------------------------------------------------------------------------------------------
# references

def _reference_rows() -> dict[str, str]:
    """Key -> the whole table row, from docs/references.md."""
    rows = re.findall(r"^\| ([^|]+?) \| (.+) \|\s*$", _read("references.md"), flags=re.M)
    return {k: v for k, v in rows if k not in ("key", "---")}


def test_reproduced_papers_have_a_year():
    rows = _reference_rows()
    for key in REPRODUCED:
        assert key in rows, f"docs/references.md has no entry '{key}'"
        years = [int(y) for y in re.findall(r"\b(19\d\d|20\d\d)\b", key + " " + rows[key])]
        assert years, f"docs/references.md, '{key}': no year"
        assert all(1950 <= y <= 2100 for y in years)


_CITATION = re.compile(r"\b([A-Z][A-Za-z\u00C0-\u017F-]+)(?: et al\.| and [A-Z][A-Za-z-]+)?"
                       r",? \(?((?:19|20)\d\d)\b")


def test_citation_pattern():
    text = "Shupe (1980), Cheng et al. (2015, eq. (6)), (Van Loan 1978), Holm and Smith 1979"
    assert {c for c in _CITATION.findall(text)} == {("Shupe", "1980"), ("Cheng", "2015"),
                                                   ("Loan", "1978"), ("Holm", "1979")}


@pytest.mark.parametrize("page", ["physics.md", "effects.md", "measurement-format.md"])
def test_every_citation_is_in_the_bibliography(page):
    keys = list(_reference_rows())
    missing = sorted({f"{name} {year}" for name, year in _CITATION.findall(_read(page))
                      if not any(name in k and year in k for k in keys)})
    assert not missing, f"docs/{page} cites works not in docs/references.md: {missing}"
