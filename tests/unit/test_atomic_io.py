"""Atomic writes: a failed write leaves the old file and no temporary behind; a good one is world-readable."""

import json
import stat

import pytest

from gendex_envs.atomic_io import atomic_path, write_json


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
