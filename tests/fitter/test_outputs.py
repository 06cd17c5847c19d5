"""A run's set of files is staged and moved in whole, or leaves nothing behind."""

import pytest

from bodyfit.fitter.output.result_files import staged_directory, write_text


def test_staged_directory_moves_every_file_in_at_the_end(tmp_path):
    with staged_directory(tmp_path / "new" / "out") as stage:
        write_text(stage / "a.txt", "a")
        assert not (tmp_path / "new" / "out").exists()
    assert [p.name for p in (tmp_path / "new" / "out").iterdir()] == ["a.txt"]
    assert [p.name for p in (tmp_path / "new").iterdir()] == ["out"]


def test_failed_run_leaves_no_file_and_no_folder_it_made(tmp_path):
    with pytest.raises(RuntimeError):
        with staged_directory(tmp_path / "new" / "out") as stage:
            write_text(stage / "a.txt", "a")
            raise RuntimeError("the fit failed")
    assert list(tmp_path.iterdir()) == []


def test_staged_directory_becomes_the_new_folder_with_the_umask_permissions(tmp_path):
    import os

    with staged_directory(tmp_path / "out") as stage:
        write_text(stage / "a.txt", "a")
        assert stage.parent == tmp_path and stage.name.startswith(".out.")
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "out").stat().st_mode & 0o777 == 0o777 & ~umask  # not mkdtemp's 0700
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_staged_directory_fills_an_existing_folder_and_keeps_its_other_files(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "notes.txt").write_text("mine")
    (tmp_path / "out" / "a.txt").write_text("old")
    with staged_directory(tmp_path / "out") as stage:
        write_text(stage / "a.txt", "new")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["a.txt", "notes.txt"]
    assert (tmp_path / "out" / "a.txt").read_text() == "new"


def test_staged_directory_takes_an_empty_folders_place_in_one_step(tmp_path):
    (tmp_path / "out").mkdir()
    empty = (tmp_path / "out").stat().st_ino
    with staged_directory(tmp_path / "out") as stage:
        write_text(stage / "a.txt", "a")
        staged = stage.stat().st_ino
    assert (tmp_path / "out").stat().st_ino == staged != empty  # renamed, not filled
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_stage_pattern_names_the_folder_a_staging_folder_is_for(tmp_path):
    from bodyfit.fitter.output.result_files import STAGE_PATTERN

    for name in ("s1", "a.b", "x.0123abcd"):
        with staged_directory(tmp_path / name) as stage:
            assert STAGE_PATTERN.fullmatch(stage.name).group(1) == name
    assert STAGE_PATTERN.fullmatch(".s1.0123abcd.part") is None
