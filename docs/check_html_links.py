"""Check the links of a built HTML site, without the network.

Usage (from the repository root, after the Sphinx build; ``.ci/run`` does this)::

    python docs/check_html_links.py docs/_build/html

Every ``.html`` file under the folder is parsed (``html.parser`` of the standard library).
For every ``href`` and ``src`` of it:

- a relative link must name a file that exists (``page.html``, ``../_images/a.png``, a
  folder with its ``index.html``);
- a fragment (``page.html#name`` or ``#name``) must be an ``id`` or a ``<a name>`` of the
  target page.

External links (``http:``, ``https:``, ``mailto:``, ...) are counted, never fetched. The
script prints one line per bad link, ``file -> href: what is wrong``, and exits 1 when there
is any, 0 otherwise.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

__all__ = ["PageLinks", "parse_page", "check_site", "main"]

#: Attributes whose value is a link to check (``<a href>``, ``<link href>``, ``<img src>``,
#: ``<script src>``, ``<iframe src>``, ``<source src>``).
LINK_ATTRIBUTES = ("href", "src")


@dataclass(frozen=True)
class PageLinks:
    """What one HTML page offers and points at."""

    #: Every ``id`` and every ``<a name>`` of the page: the fragments a link may name.
    anchors: frozenset[str]
    #: Every ``href`` / ``src`` value, in document order.
    links: tuple[str, ...]


class _Collector(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.anchors: set[str] = set()
        self.links: list[str] = []

    def handle_starttag(self, tag, attrs):
        for key, value in attrs:
            if value is None:
                continue
            if key == "id" or (key == "name" and tag == "a"):
                self.anchors.add(value)
            elif key in LINK_ATTRIBUTES:
                self.links.append(value)

    handle_startendtag = handle_starttag


def parse_page(text: str) -> PageLinks:
    """The anchors and links of one HTML page's text."""
    collector = _Collector()
    collector.feed(text)
    collector.close()
    return PageLinks(frozenset(collector.anchors), tuple(collector.links))


def _is_external(href: str) -> bool:
    parts = urlsplit(href)
    return bool(parts.scheme) or href.startswith("//")


def check_site(root: Path) -> tuple[list[str], int]:
    """Every bad link under ``root`` as ``"file -> href: reason"``, and the external count.

    ``file`` is relative to ``root``. A link to a page outside ``root`` is reported as
    missing too: the site must stand on its own.
    """
    root = Path(root).resolve()
    pages: dict[Path, PageLinks] = {}
    for path in sorted(root.rglob("*.html")):
        pages[path] = parse_page(path.read_text(encoding="utf-8", errors="replace"))

    def anchors_of(target: Path) -> frozenset[str]:
        if target not in pages:
            text = target.read_text(encoding="utf-8", errors="replace")
            pages[target] = parse_page(text)
        return pages[target].anchors

    problems: list[str] = []
    external = 0
    for path, page in list(pages.items()):
        rel = path.relative_to(root).as_posix()
        for href in page.links:
            href = href.strip()
            if not href or href.startswith("javascript:"):
                continue
            if _is_external(href):
                external += 1
                continue
            parts = urlsplit(href)
            fragment = unquote(parts.fragment)
            if parts.path:
                target = (path.parent / unquote(parts.path)).resolve()
                if target.is_dir():
                    target = target / "index.html"
                if root not in target.parents and target != root:
                    problems.append(f"{rel} -> {href}: outside the site")
                    continue
                if not target.is_file():
                    problems.append(f"{rel} -> {href}: no such file")
                    continue
            else:
                target = path
            if fragment and target.suffix == ".html" and fragment not in anchors_of(target):
                problems.append(f"{rel} -> {href}: no anchor '{fragment}' in "
                                f"{target.relative_to(root).as_posix()}")
    return problems, external


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("site", type=Path, help="the built HTML folder (docs/_build/html)")
    args = parser.parse_args(argv)
    if not (args.site / "index.html").is_file():
        print(f"check_html_links: {args.site}: no index.html (build the site first)",
              file=sys.stderr)
        return 2
    problems, external = check_site(args.site)
    n_pages = sum(1 for _ in args.site.rglob("*.html"))
    for line in problems:
        print(line)
    print(f"check_html_links: {n_pages} pages, {len(problems)} bad links, "
          f"{external} external links not fetched")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
