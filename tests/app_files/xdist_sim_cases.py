"""Eight copies of the fixture's turtlesim test, for pytest-xdist (run by
test_app_api.py::test_eight_fixture_runs_in_parallel_under_xdist_do_not_collide, or by hand:
``python -m pytest -n 8 tests/app_files/xdist_sim_cases.py``). Not collected by the suite
itself (the name does not start with test_)."""
from pathlib import Path

import psutil
import pytest

from orchestra.supervise.process import State

SIM = Path(__file__).resolve().parent / "respawning_sim.launch"


@pytest.mark.parametrize("copy", range(8))
def test_sim_respawns_in_its_own_graph(launch, copy):
    run = launch(SIM)
    run.wait_for(topic="/turtle1/pose", timeout=60)
    first = run.process("/sim").pid
    run.kill("/sim")
    for _ in range(600):          # up to 60 s for the respawn (the run ending stops it too)
        info = run.process("/sim")
        if info.restarts == 1 and info.state == State.RUNNING and info.pid != first:
            break
        assert run.wait(timeout=0.1) is None, "the run ended instead of respawning /sim"
    run.wait_for(topic="/turtle1/pose", timeout=60)
    assert run.process("/sim").restarts == 1
    report = run.stop()
    assert report.processes["/sim"].state == State.EXITED
    assert [p for p in psutil.Process().children(recursive=True)
            if p.status() != psutil.STATUS_ZOMBIE] == []
