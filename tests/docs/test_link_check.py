"""docs/check_html_links.py, the offline link check of the built site, on tiny fake sites.

Oracle: sites written here with known faults (a link to a page that does not exist, a
fragment that no id or <a name> of its page holds) and a site without any.
"""

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("check_html_links",
                                               ROOT / "docs" / "check_html_links.py")
check_html_links = importlib.util.module_from_spec(_spec)
sys.modules["check_html_links"] = check_html_links   # its dataclass looks itself up there
_spec.loader.exec_module(check_html_links)


def _site(tmp_path: Path, pages: dict[str, str]) -> Path:
    for name, body in pages.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(f"<!DOCTYPE html><html><body>{body}</body></html>", encoding="utf-8")
    return tmp_path


GOOD = {
    "index.html": ('<a href="guide/physics.html#eq-2-1">eq</a> <a href="#top">top</a>'
                   '<h1 id="top">x</h1> <a href="guide/">folder</a>'
                   '<img src="_images/a.png"> <a href="https://example.org/x#y">out</a>'
                   '<a href="mailto:a@b.c">mail</a> <a href="guide/physics.html#old%20name">n</a>'),
    "guide/index.html": '<a href="../index.html">up</a>',
    "guide/physics.html": ('<span id="eq-2-1"></span><a name="old name"></a>'
                           '<a href="../index.html#top">home</a>'),
    "_images/a.png": "",
}


def test_good_site_passes(tmp_path, capsys):
    site = _site(tmp_path, GOOD)
    problems, external = check_html_links.check_site(site)
    assert problems == []
    assert external == 2
    assert check_html_links.main([str(site)]) == 0
    assert "0 bad links, 2 external links not fetched" in capsys.readouterr().out


def test_missing_page_and_dangling_anchor_are_reported(tmp_path, capsys):
    pages = dict(GOOD)
    pages["index.html"] += ('<a href="guide/missing.html">gone</a>'
                            '<a href="guide/physics.html#eq-9-9">no such equation</a>'
                            '<a href="#nowhere">self</a>')
    site = _site(tmp_path, pages)
    problems, _ = check_html_links.check_site(site)
    assert problems == [
        "index.html -> guide/missing.html: no such file",
        "index.html -> guide/physics.html#eq-9-9: no anchor 'eq-9-9' in guide/physics.html",
        "index.html -> #nowhere: no anchor 'nowhere' in index.html",
    ]
    assert check_html_links.main([str(site)]) == 1
    out = capsys.readouterr().out
    assert "index.html -> guide/missing.html: no such file" in out
    assert "3 bad links" in out


def test_link_out_of_the_site_is_reported(tmp_path):
    site = _site(tmp_path / "html", {"index.html": '<a href="../secret.html">x</a>'})
    (tmp_path / "secret.html").write_text("<html></html>")
    problems, _ = check_html_links.check_site(site)
    assert problems == ["index.html -> ../secret.html: outside the site"]


def test_folder_without_a_site_is_refused(tmp_path, capsys):
    assert check_html_links.main([str(tmp_path)]) == 2
    assert "no index.html" in capsys.readouterr().err


@pytest.mark.parametrize("text, anchors, links", [
    ('<p id="a"><a name="b" href="x.html#c">', {"a", "b"}, ("x.html#c",)),
    ('<img src="i.png"/><meta name="viewport">', set(), ("i.png",)),
])
def test_parse_page(text, anchors, links):
    page = check_html_links.parse_page(text)
    assert page.anchors == anchors and page.links == links
