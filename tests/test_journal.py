"""Outputs published together: on an exception, undone in reverse order; on success, kept."""

import os

import pytest

from fosmodel.io.journal import KEPT, all_or_nothing, created, durable, replace


def _new(folder, name, text):
    path = folder / f".{name}.new"
    path.write_text(text)
    return path


def _listing(folder):
    return {str(p.relative_to(folder)): p.read_text() if p.is_file() else None
            for p in sorted(folder.rglob("*"))}


def test_outputs_are_undone_newest_first_when_the_block_raises(tmp_path):
    (tmp_path / "a.txt").write_text("old a")
    (tmp_path / "link.txt").symlink_to(tmp_path / "a.txt")
    before = _listing(tmp_path)
    with pytest.raises(RuntimeError), all_or_nothing():
        replace(_new(tmp_path, "a", "new a"), tmp_path / "a.txt")
        replace(_new(tmp_path, "b", "new b"), tmp_path / "b.txt")
        replace(_new(tmp_path, "a2", "newer a"), tmp_path / "a.txt")  # the same file twice
        replace(_new(tmp_path, "l", "new link"), tmp_path / "link.txt")
        (tmp_path / "dir" / "sub").mkdir(parents=True)
        created(tmp_path / "dir")
        assert (tmp_path / "a.txt").read_text() == "newer a"
        raise RuntimeError
    assert _listing(tmp_path) == before and (tmp_path / "link.txt").is_symlink()


def test_outputs_stay_and_the_kept_files_go_when_the_block_ends(tmp_path):
    (tmp_path / "a.txt").write_text("old")
    with all_or_nothing():
        replace(_new(tmp_path, "a", "new"), tmp_path / "a.txt")
        assert [p.name for p in tmp_path.iterdir() if p.name.endswith(KEPT)]
    assert _listing(tmp_path) == {"a.txt": "new"}


def test_durable_outputs_stay_whatever_follows(tmp_path):
    with pytest.raises(KeyboardInterrupt), all_or_nothing():
        with durable():
            replace(_new(tmp_path, "a", "kept"), tmp_path / "a.txt")
        replace(_new(tmp_path, "b", "undone"), tmp_path / "b.txt")
        raise KeyboardInterrupt
    assert _listing(tmp_path) == {"a.txt": "kept"}


def test_without_hard_links_the_replaced_file_is_copied(tmp_path, monkeypatch):
    (tmp_path / "a.txt").write_text("old")

    def no_links(*args, **kwargs):
        raise PermissionError(1, "Operation not permitted")
    monkeypatch.setattr(os, "link", no_links)
    with pytest.raises(RuntimeError), all_or_nothing():
        replace(_new(tmp_path, "a", "new"), tmp_path / "a.txt")
        raise RuntimeError
    assert _listing(tmp_path) == {"a.txt": "old"}


def test_outside_all_or_nothing_a_replace_is_a_rename(tmp_path):
    (tmp_path / "a.txt").write_text("old")
    replace(_new(tmp_path, "a", "new"), tmp_path / "a.txt")
    assert _listing(tmp_path) == {"a.txt": "new"}
