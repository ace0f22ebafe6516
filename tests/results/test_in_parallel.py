"""preview.html is written by a forked process while the rest of the plan folder is
written here: its errors must still reach the user as they were."""

import pytest

from offline_prog.results.plan_folder import InParallel


def test_a_child_error_is_raised_in_the_parent_as_it_was():
    def fails():
        raise FileNotFoundError(2, "No such file or directory", "/nowhere/preview.html")

    job = InParallel(fails)
    with pytest.raises(FileNotFoundError, match="/nowhere/preview.html"):
        job.wait()


def test_a_child_that_works_returns_its_result(tmp_path):
    target = tmp_path / "written.txt"
    job = InParallel(lambda: {"drawn": target} if target.write_text("drawn") else None)
    assert job.wait() == {"drawn": target} and target.read_text() == "drawn"


def test_cancel_stops_the_child_before_its_folder_goes(tmp_path):
    import time

    target = tmp_path / "late.txt"

    def slow():
        time.sleep(0.5)
        target.write_text("too late")

    job = InParallel(slow)
    job.cancel()
    time.sleep(1.0)  # past the time it would have written
    assert job.process is None and not target.exists()
