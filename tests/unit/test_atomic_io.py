"""Atomic writes: a failed write leaves the old file (or folder) and no temporary; a good one is world-readable."""

import json
import stat

import pytest

from gendex_envs.atomic_io import atomic_dir, atomic_path, write_bytes, write_json, write_text


def test_failed_write_keeps_the_old_file(tmp_path):
    path = write_json(tmp_path / "record.json", {"v": 1})
    with pytest.raises(RuntimeError), atomic_path(path) as tmp:
        tmp.write_text("half")
        raise RuntimeError("killed")
    assert json.loads(path.read_text()) == {"v": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["record.json"]


def test_written_file_is_readable_by_all(tmp_path):
    path = write_json(tmp_path / "sub" / "r.json", [1, 2], indent=1)
    assert json.loads(path.read_text()) == [1, 2]
    assert path.stat().st_mode & stat.S_IROTH


def test_text_and_bytes_are_written_as_given(tmp_path):
    assert write_text(tmp_path / "a.md", "é\r\nline\n").read_bytes() == "é\r\nline\n".encode()
    assert write_bytes(tmp_path / "b.bin", b"\x00\xff", fsync=True).read_bytes() == b"\x00\xff"
    assert write_json(tmp_path / "c.json", {"k": [1]}, indent=1, fsync=True).read_text() == '{\n "k": [\n  1\n ]\n}\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.md", "b.bin", "c.json"]


def test_a_failed_encoding_leaves_nothing(tmp_path):
    with pytest.raises(UnicodeEncodeError):
        write_text(tmp_path / "a.txt", "é", encoding="ascii")
    assert list(tmp_path.iterdir()) == []


def test_atomic_path_keeps_the_suffix_for_writers_that_pick_a_format_by_it(tmp_path):
    with atomic_path(tmp_path / "img.png") as tmp:
        assert tmp.suffix == ".png" and tmp.parent == tmp_path and tmp.name.startswith(".")
        tmp.write_bytes(b"png")
    assert (tmp_path / "img.png").read_bytes() == b"png"


def test_atomic_dir_appears_whole_or_not_at_all(tmp_path):
    dest = tmp_path / "sub" / "built"
    with pytest.raises(RuntimeError), atomic_dir(dest) as tmp:
        (tmp / "half").write_text("x")
        raise RuntimeError("killed")
    assert list((tmp_path / "sub").iterdir()) == []
    with atomic_dir(dest) as tmp:
        (tmp / "f").write_text("1")
    assert [p.name for p in dest.iterdir()] == ["f"]
    with pytest.raises(FileExistsError), atomic_dir(dest) as tmp:  # lost a race: the winner's copy stays
        (tmp / "g").write_text("2")
    assert [p.name for p in dest.iterdir()] == ["f"]
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["built"]
    with atomic_dir(dest, replace=True) as tmp:
        (tmp / "g").write_text("2")
    assert [p.name for p in dest.iterdir()] == ["g"]
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["built"]
