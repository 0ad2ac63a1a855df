"""A heading table set beside a baseline, rendered: the change of every cell in % as Markdown,
and the comparison's files (``baseline_comparison.md`` and ``.json``).

The statistics (each cell's change, its bootstrap interval and verdict) are
:func:`nfs.scoring.baseline.compare_tables`'s; this module only writes what it found.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..io.atomic import atomic_write_text
from ..scoring.baseline import BaselineComparison

__all__ = ["baseline_comparison_markdown", "write_baseline_comparison"]


def baseline_comparison_markdown(comparison: BaselineComparison) -> str:
    """The change of every cell in % (method x start temperature, mean), each marked
    ``(worse)`` or ``(better)`` beyond noise and tolerance; the notes and the summary
    below."""
    labels = [f"{t:g}" for t in comparison.temperatures_c] + ["mean"]
    lines = ["| method | " + " | ".join(labels) + " |",
             "|---|" + "---:|" * len(labels)]
    by = {(c.method, c.column): c for c in comparison.cells}
    for m in comparison.methods:
        cells = []
        for lab in labels:
            c = by[(m, lab)]
            if c.verdict == "n/a":
                cells.append("-")
                continue
            text = _pct(c.relative)
            cells.append(text + (f" ({c.verdict})" if c.verdict != "within noise" else ""))
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    tol = f"{100.0 * comparison.tolerance:g} %"
    text = "\n".join(lines) + "\n\n"
    text += (f"Change of each cell against the baseline (new / baseline - 1); (worse): its "
             f"95 % interval above 0 and the change above {tol}; (better): below 0 and "
             f"below -{tol}; unmarked: within noise.\n\n")
    text += "".join(f"- {n}\n" for n in comparison.notes)
    return text + "\n" + comparison.summary() + "\n"


def _pct(r: float) -> str:
    if not math.isfinite(r):
        return "n/a"
    return "0 %" if r == 0.0 else f"{100.0 * r:+.1f} %"


def write_baseline_comparison(comparison: BaselineComparison, out_dir) -> list[Path]:
    """Write ``baseline_comparison.md`` and ``.json`` into ``out_dir`` (atomically)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    md, js = out / "baseline_comparison.md", out / "baseline_comparison.json"
    atomic_write_text(md, "# Against the baseline\n\n" + f"Baseline: {comparison.baseline}\n\n"
                      + baseline_comparison_markdown(comparison))
    atomic_write_text(js, comparison.to_json())
    return [md, js]
