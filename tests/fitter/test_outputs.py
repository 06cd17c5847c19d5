"""A run's set of files is staged and moved in whole, or leaves nothing behind."""

import pytest

from bodyfit.fitter.outputs import staged_directory, write_text


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
