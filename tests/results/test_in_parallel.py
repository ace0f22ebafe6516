"""preview.html is written by a forked process while the rest of the plan folder is
written here: its errors must still reach the user as they were."""

import pytest

from offline_prog.results.plan_folder import in_parallel


def test_a_child_error_is_raised_in_the_parent_as_it_was():
    def fails():
        raise FileNotFoundError(2, "No such file or directory", "/nowhere/preview.html")

    wait = in_parallel(fails)
    with pytest.raises(FileNotFoundError, match="/nowhere/preview.html"):
        wait()


def test_a_child_that_works_returns_nothing(tmp_path):
    target = tmp_path / "written.txt"
    wait = in_parallel(lambda: target.write_text("drawn"))
    assert wait() is None and target.read_text() == "drawn"
