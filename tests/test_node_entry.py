"""run_main: the exit codes of a node script's __main__."""
import pytest

from orchestra.node import ROSException, ROSInterruptException
from orchestra.node.entry import run_main


def _exit_code(main):
    with pytest.raises(SystemExit) as info:
        run_main(main)
    return info.value.code


def test_run_main_exits_with_mains_return_code():
    assert _exit_code(lambda: 3) == 3
    assert _exit_code(lambda: None) == 0


def test_run_main_treats_shutdown_as_success():
    def main():
        raise ROSInterruptException("shutdown")
    assert _exit_code(main) == 0


def test_run_main_reports_ros_error_in_one_line(capsys):
    def main():
        raise ROSException("cannot reach the master")
    assert _exit_code(main) == 1
    err = capsys.readouterr().err
    assert "cannot reach the master" in err and "Traceback" not in err
