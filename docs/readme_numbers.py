"""The README's numbers, rebuilt: each heading-RMSE table the README and the user guide show,
with its sentences.

    python docs/readme_numbers.py                      # check every page (exit 1 if one differs)
    python docs/readme_numbers.py --write              # rewrite every marked block
    python docs/readme_numbers.py --only default-table # one block

Each block between ``<!-- readme-numbers:NAME -->`` and ``<!-- /readme-numbers:NAME -->`` is
this script's output for one scenario (:data:`BLOCKS`), never typed by hand, on every page
:data:`PAGES` names for it: the default table in README.md and in the user guide's
docs/compensation.md, the fleet and precise tables in docs/compensation.md.
``tests/test_readme.py`` checks the default table on every test run and the others among the
slow tests, so no page can drift from what the package prints.

What must agree: the uncompensated rows (``before``, ``stable``, ``floor``) digit for digit
(the simulation is seeded and its arithmetic fixed); every compensated row's mean within the
95 % interval that the README states for it. The tuners' searches are chaotic in the last
bits of their floating-point sums (BLAS kernels and summation order differ between machines),
so a tuned row's cells can move by more than their last printed digit on another platform
while the table's conclusions stay.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import time
from pathlib import Path

from nfs.studies.startup_study import run_study
from nfs.config.scenario import load_scenario
from nfs.scoring.heading_table import REFERENCE_ROWS

ROOT = Path(__file__).resolve().parents[1]
#: Block name -> scenario file (None: the built-in default).
BLOCKS = {"default-table": None,
          "fleet-table": ROOT / "scenarios" / "startup_7temps_fleet.toml",
          "precise-table": ROOT / "scenarios" / "startup_7temps_precise.toml"}
#: Block name -> the pages that show it (each checked and rewritten alike).
PAGES = {"default-table": (ROOT / "README.md", ROOT / "docs" / "compensation.md"),
         "fleet-table": (ROOT / "docs" / "compensation.md",),
         "precise-table": (ROOT / "docs" / "compensation.md",)}
#: Rows that must agree digit for digit on every machine.
EXACT_ROWS = REFERENCE_ROWS


def markers(name: str) -> tuple[str, str]:
    """The opening and closing markers of block ``name``."""
    return f"<!-- readme-numbers:{name} -->", f"<!-- /readme-numbers:{name} -->"


def compute(name: str):
    """The heading table ``nfs table`` prints for block ``name``'s scenario, and its time [s]."""
    scenario = load_scenario(BLOCKS[name])
    t0 = time.perf_counter()
    table = run_study(scenario, scenario.compensation).heading_table()
    return table, time.perf_counter() - t0


def block(name: str, table) -> str:
    """The README block: the table, the SSA-SVR sentence and the key comparisons."""
    begin, end = markers(name)
    md = table.to_markdown()
    grid = md.split("\n\n")[0].rstrip("\n")
    rows = {r.method: r for r in table.rows}
    lines = [begin, grid]
    if "SSA-SVR" in rows and table.best is not None:
        before, ssa = rows["before"].mean_deg, rows["SSA-SVR"].mean_deg
        best = rows[table.best]
        key = table.key_comparisons()
        vs_before = [c for c in key if c.method_b == "before"]
        below = [c for c in vs_before if c.distinguishable and c.difference_deg < 0]
        lines += ["", f"SSA-SVR brings {before:.4f} to {ssa:.4f} deg ({ssa / before:.2f}x); the "
                  f"best row is {table.best} at {best.mean_deg:.4f} deg [{best.ci_low_deg:.4f}, "
                  f"{best.ci_high_deg:.4f}]; {len(below)} of {len(vs_before)} compensated rows "
                  "are below `before` beyond the noise. Paired comparisons (difference of the "
                  f"means, its 95 % interval, Holm over the {len(table.comparisons)} "
                  "comparisons made):", ""]
        lines += [f"- {c.sentence(4)}" for c in key if c.method_b != "before"]
    return "\n".join(lines + [end])


def parse(name: str, text: str) -> dict[str, list[str]]:
    """Row label -> its cells, from the Markdown table inside the README's block ``name``."""
    begin, end = markers(name)
    inner = text.split(begin, 1)[1].split(end, 1)[0]
    out = {}
    for line in inner.splitlines():
        if line.startswith("| ") and not line.startswith("| method"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            out[cells[0]] = cells[1:]
    return out


def differences(name: str, readme_text: str, table) -> list[str]:
    """What in the README's block ``name`` disagrees with ``table`` (empty: it agrees)."""
    begin, end = markers(name)
    if begin not in readme_text or end not in readme_text:
        return [f"the page has no block {begin} ... {end}"]
    stated = parse(name, readme_text)
    fresh = parse(name, block(name, table))
    problems = []
    if set(stated) != set(fresh):
        problems.append(f"{name}: rows differ: README {sorted(stated)}, fresh {sorted(fresh)}")
    n_t = len(table.temperatures_c)
    for r in table.rows:
        if r.method not in stated:
            continue
        if r.method in EXACT_ROWS:
            if stated[r.method][:n_t + 1] != fresh[r.method][:n_t + 1]:
                problems.append(f"{name}: {r.method}: README {stated[r.method][:n_t + 1]}, "
                                f"fresh {fresh[r.method][:n_t + 1]}")
            continue
        ci = re.match(r"\[([-0-9.]+), ([-0-9.]+)\]", stated[r.method][n_t + 1])
        if ci is None:
            problems.append(f"{name}: {r.method}: no 95 % interval in the README")
            continue
        lo, hi = float(ci.group(1)), float(ci.group(2))
        if not (math.isfinite(r.mean_deg) and lo <= r.mean_deg <= hi):
            problems.append(f"{name}: {r.method}: mean {r.mean_deg:.4f} outside the README's "
                            f"interval [{lo:.4f}, {hi:.4f}]")
    return problems


def rewrite(text: str, name: str, table) -> str:
    """``text`` with block ``name`` replaced by the block of ``table``."""
    begin, end = markers(name)
    head, rest = text.split(begin, 1)
    return head + block(name, table) + rest.split(end, 1)[1]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--write", action="store_true", help="rewrite the pages' blocks")
    p.add_argument("--only", nargs="+", choices=sorted(BLOCKS), default=sorted(BLOCKS),
                   help="blocks to check or rewrite (default: all)")
    p.add_argument("--page", default=None,
                   help="only this page (default: every page of PAGES that shows the block)")
    args = p.parse_args(argv)
    only_page = None if args.page is None else Path(args.page).resolve()
    texts = {}
    for name in args.only:
        for page in PAGES[name]:
            if only_page is None or page.resolve() == only_page:
                texts.setdefault(page, page.read_text(encoding="utf-8"))
    problems = []
    for name in args.only:
        pages = [pg for pg in PAGES[name] if pg in texts]
        if not pages:
            continue
        for page in pages:
            begin, end = markers(name)
            if begin not in texts[page] or end not in texts[page]:
                print(f"{page}: no block {begin} ... {end}", file=sys.stderr)
                return 2
        table, seconds = compute(name)
        print(f"{name}: computed in {seconds:.1f} s", file=sys.stderr)
        for page in pages:
            if args.write:
                texts[page] = rewrite(texts[page], name, table)
            else:
                problems += [f"{page}: {line}" for line in differences(name, texts[page], table)]
    if args.write:
        for page, text in texts.items():
            page.write_text(text, encoding="utf-8")
        print(f"rewrote {', '.join(args.only)} in {', '.join(str(pg) for pg in texts)}")
        return 0
    for line in problems:
        print(line)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
