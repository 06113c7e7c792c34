"""Atomic writing: a failure part-way leaves the output directory as it was."""

import pytest

from hoseline.io.atomic import staged_directory, write_text


def test_staged_directory_writes_all_files_on_success(tmp_path):
    out = tmp_path / "a" / "b"
    with staged_directory(out) as staging:
        write_text(staging / "one.txt", "1")
        (staging / "sub").mkdir()
        write_text(staging / "sub" / "two.txt", "2")
    assert (out / "one.txt").read_text() == "1"
    assert (out / "sub" / "two.txt").read_text() == "2"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a"]


def test_staged_directory_writes_nothing_on_failure(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    write_text(out / "old.txt", "old")
    with pytest.raises(RuntimeError):
        with staged_directory(out) as staging:
            write_text(staging / "old.txt", "new")
            raise RuntimeError("the second file failed")
    assert (out / "old.txt").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    assert sorted(p.name for p in out.iterdir()) == ["old.txt"]


def test_write_text_replaces_the_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "f.txt"
    write_text(target, "first")
    write_text(target, "second")
    assert target.read_text() == "second"
    assert [p.name for p in tmp_path.iterdir()] == ["f.txt"]
