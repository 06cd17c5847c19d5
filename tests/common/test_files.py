"""Atomic output files (bodyfit.common.files): whole files or none, folders made and
removed with them."""

import pytest

from bodyfit.common.errors import UserError
from bodyfit.common.files import created_folders, write_atomic


def test_write_atomic_replaces_whole_files_and_leaves_no_temporaries(tmp_path):
    target = tmp_path / "out.bin"
    write_atomic(target, b"first")
    write_atomic(target, b"second")
    assert target.read_bytes() == b"second"
    assert [p.name for p in tmp_path.iterdir()] == ["out.bin"]


def test_write_atomic_creates_missing_folders(tmp_path):
    write_atomic(tmp_path / "a" / "b" / "out.bin", b"x")
    assert (tmp_path / "a" / "b" / "out.bin").read_bytes() == b"x"


def test_write_atomic_failure_removes_the_folders_it_created(tmp_path):
    (tmp_path / "file").write_bytes(b"")
    with pytest.raises(UserError, match="is a file"):
        write_atomic(tmp_path / "file" / "sub" / "out.bin", b"x")
    with pytest.raises(UserError, match="cannot write"):  # the target is a folder
        (tmp_path / "new" / "taken").mkdir(parents=True)
        write_atomic(tmp_path / "new" / "taken", b"x")
    with pytest.raises(UserError, match="cannot write"):  # a name longer than any allowed
        write_atomic(tmp_path / "made" / "deeper" / ("x" * 300), b"x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "new"]


def test_created_folders_removes_what_it_made_when_the_block_fails(tmp_path):
    with pytest.raises(RuntimeError):
        with created_folders(tmp_path / "a" / "b"):
            assert (tmp_path / "a" / "b").is_dir()
            raise RuntimeError("the command failed")
    assert list(tmp_path.iterdir()) == []
    with created_folders(tmp_path / "kept"):
        pass
    assert (tmp_path / "kept").is_dir()


def test_temp_file_pattern_names_write_atomics_temporary_files(tmp_path, monkeypatch):
    from bodyfit.common import files

    seen = []
    real_replace = files.os.replace
    monkeypatch.setattr(files.os, "replace",
                        lambda source, target: (seen.append(source), real_replace(source, target)))
    write_atomic(tmp_path / "summary.csv", b"x")
    assert files.TEMP_FILE_PATTERN.fullmatch(seen[0].name).group(1) == "summary.csv"
