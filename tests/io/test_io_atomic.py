"""Atomic output (nfs.io.atomic).

Oracle: the invariant of an atomic write -- after a failure the destination holds exactly its
previous bytes (or is still absent) and no temporary file is left in the folder; after a
success it holds exactly the new bytes.
"""

from __future__ import annotations

import os
import stat

import pytest

from nfs.io.atomic import atomic_output, atomic_write_bytes, atomic_write_files, atomic_write_text


class Boom(Exception):
    pass


def _listing(folder):
    return sorted(p.name for p in folder.iterdir())


def test_write_text_and_bytes(tmp_path):
    atomic_write_text(tmp_path / "a.txt", "x = 1\nµ\r\n")
    atomic_write_bytes(tmp_path / "b.bin", b"\x00\xff")
    # UTF-8, no newline translation on any platform
    assert (tmp_path / "a.txt").read_bytes() == "x = 1\nµ\r\n".encode("utf-8")
    assert (tmp_path / "b.bin").read_bytes() == b"\x00\xff"
    assert _listing(tmp_path) == ["a.txt", "b.bin"]


def test_replaces_existing_content(tmp_path):
    path = tmp_path / "a.csv"
    path.write_text("old\n")
    atomic_write_text(path, "new\n")
    assert path.read_text() == "new\n"
    assert _listing(tmp_path) == ["a.csv"]


@pytest.mark.parametrize("mode", ["w", "wb"])
def test_writer_raising_midway_keeps_previous_content(tmp_path, mode):
    path = tmp_path / "fig.png"
    path.write_bytes(b"previous")
    chunk = "partial" if mode == "w" else b"partial"
    with pytest.raises(Boom):
        with atomic_output(path, mode) as f:
            f.write(chunk * 1000)
            f.flush()
            raise Boom
    assert path.read_bytes() == b"previous"
    assert _listing(tmp_path) == ["fig.png"]


def test_writer_raising_leaves_absent_file_absent(tmp_path):
    with pytest.raises(Boom):
        with atomic_output(tmp_path / "new.json") as f:
            f.write("{")
            raise Boom
    assert _listing(tmp_path) == []


def test_keyboard_interrupt_also_cleans_up(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("keep")
    with pytest.raises(KeyboardInterrupt):
        with atomic_output(path) as f:
            f.write("half")
            raise KeyboardInterrupt
    assert path.read_text() == "keep"
    assert _listing(tmp_path) == ["a.txt"]


def test_streaming_writer_success(tmp_path):
    path = tmp_path / "out.bin"
    with atomic_output(path, "wb") as f:
        for k in range(10):
            f.write(bytes([k]))
        # nothing visible at the destination before the block ends
        assert not path.exists()
    assert path.read_bytes() == bytes(range(10))
    assert _listing(tmp_path) == ["out.bin"]


def test_encoding_error_keeps_previous_content(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("keep")
    with pytest.raises(UnicodeEncodeError):
        atomic_write_text(path, "snowman \u2603", encoding="ascii")
    assert path.read_text() == "keep"
    assert _listing(tmp_path) == ["a.txt"]


def test_write_files_all_or_nothing(tmp_path):
    first, second = tmp_path / "run.csv", tmp_path / "run.toml"
    first.write_text("old csv")
    second.write_text("old toml")
    with pytest.raises(TypeError):
        atomic_write_files({first: "new csv", second: 12345})  # second cannot be written
    assert first.read_text() == "old csv"
    assert second.read_text() == "old toml"
    assert _listing(tmp_path) == ["run.csv", "run.toml"]
    atomic_write_files({first: "new csv", second: b"new toml"})
    assert first.read_text() == "new csv"
    assert second.read_text() == "new toml"
    assert _listing(tmp_path) == ["run.csv", "run.toml"]


def test_missing_folder_raises_and_writes_nothing(tmp_path):
    with pytest.raises(FileNotFoundError):
        atomic_write_text(tmp_path / "no" / "such" / "a.txt", "x")
    assert _listing(tmp_path) == []


def test_bad_mode(tmp_path):
    with pytest.raises(ValueError, match="mode"):
        with atomic_output(tmp_path / "a.txt", "a"):
            pass
    assert _listing(tmp_path) == []


@pytest.mark.skipif(os.name != "posix", reason="POSIX permission bits")
def test_permissions(tmp_path):
    # a new file gets the permissions of an ordinary open() (0o666 minus the umask) ...
    ordinary = tmp_path / "ordinary"
    ordinary.write_text("x")
    atomic_write_text(tmp_path / "new", "x")
    assert stat.S_IMODE((tmp_path / "new").stat().st_mode) == \
        stat.S_IMODE(ordinary.stat().st_mode)
    # ... and a replaced file keeps its own
    kept = tmp_path / "kept"
    kept.write_text("x")
    kept.chmod(0o640)
    atomic_write_text(kept, "y")
    assert stat.S_IMODE(kept.stat().st_mode) == 0o640
