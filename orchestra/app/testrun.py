"""``orchestra test``: rostest's procedure on a LaunchRun.

For each ``<test>`` of the file, one at a time and in file order, as rostest does: bring the
file's nodes up (a LaunchRun with its own master on a free port, unless ``--reuse-master``),
start the test with ``--gtest_output=xml:PATH``, wait for it to end — at most its
``time-limit`` (default 60 s), and no longer than the required nodes live — read the
results it wrote, stop everything, and try again while ``retry`` allows. Each test's
outcome becomes cases of one combined JUnit file and a rostest-style summary.

What goes wrong is that test's verdict, never the end of the run: a ``<test>`` the launch
file declares wrongly (error, with file:line), an executable that does not exist (error), a
results file that is not valid XML (error), a test past its time-limit or whose required
node died (failure), a test that wrote no results (failure). The other tests still run.

A stop signal (Ctrl-C, SIGTERM, SIGHUP) is the end of the run, in order: the test that runs
is stopped and fails as interrupted, its nodes are stopped as their timeouts say (a second
signal kills them), the tests not started yet are skipped, and the summary and the JUnit
file still say all that. rostest dies of a KeyboardInterrupt there, reporting nothing.
"""
from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import IO, Any

from orchestra.app.junit import (
    ERROR,
    FAILURE,
    PASSED,
    SKIPPED,
    CaseResult,
    ResultsError,
    TestOutcome,
)
from orchestra.app.junit import parse_results as parse_results_xml
from orchestra.app.options import RunOptions
from orchestra.app.run import LaunchRun
from orchestra.errors import OrchestraError
from orchestra.launch.plan import LaunchPlan, Test
from orchestra.rosdirs import ros_home
from orchestra.supervise import stop_signals
from orchestra.supervise.command import find_node_executable
from orchestra.supervise.output import Screen
from orchestra.supervise.reaper import (
    MARK_VARIABLE,
    child_setup,
    marked_pids,
    new_mark,
    signal_group,
)
from orchestra.supervise.specs import build_specs

Report = Callable[[str], None]

GTEST_FLAG = "--gtest_output=xml:"     # what rostest passes (rosunit and gtest both read it)
KILL_GRACE = 2.0                       # seconds between SIGINT and SIGKILL for a test


@dataclass(frozen=True)
class TestOptions:
    """The flags of ``orchestra test`` that are about the tests, not the run."""

    results_dir: str | None = None      # default: ROS_TEST_RESULTS_DIR, else ROS_HOME/test_results
    text: bool = False                  # test output on the console, ``--text`` to the test
    reuse_master: bool = False          # the master at ROS_MASTER_URI for every test
    only: tuple[str, ...] = ()          # -t: run only these test names


def results_root(options: TestOptions, environ: dict[str, str] | None = None) -> str:
    """rospkg's test results directory: ROS_TEST_RESULTS_DIR, else $ROS_HOME/test_results."""
    env = dict(os.environ if environ is None else environ)
    if options.results_dir:
        return options.results_dir
    return env.get("ROS_TEST_RESULTS_DIR") or os.path.join(ros_home(env), "test_results")


def package_of(path: str) -> str:
    """The name rostest files results under: the package directory holding ``path``
    (the nearest package.xml above it), else the file's directory name."""
    directory = os.path.dirname(os.path.abspath(path))
    here = directory
    while True:
        if os.path.isfile(os.path.join(here, "package.xml")):
            return os.path.basename(here)
        parent = os.path.dirname(here)
        if parent == here:
            return os.path.basename(directory) or "tests"
        here = parent


def results_file_name(test_name: str) -> str:
    """rosunit's per-test file name, with the characters that break file names replaced."""
    safe = "".join("_" if ch in " \"'&$!`/\\" else ch for ch in test_name)
    return f"rosunit-{safe}.xml"


def select_tests(tests: Sequence[Test], broken: Sequence[tuple[str, OrchestraError]],
                 only: Sequence[str]) -> tuple[list[Test], list[tuple[str, OrchestraError]]]:
    """The tests ``-t`` asks for (all when none); an unknown name is a user error."""
    if not only:
        return list(tests), list(broken)
    known = [t.test_name for t in tests] + [label for label, _ in broken]
    unknown = [name for name in only if name not in known]
    if unknown:
        listing = ", ".join(known) or "none"
        raise OrchestraError(f"-t {unknown[0]}: no such test in the file (tests: {listing})")
    return ([t for t in tests if t.test_name in only],
            [(label, exc) for label, exc in broken if label in only])


def error_case(name: str, message: str) -> CaseResult:
    return CaseResult(name, name, ERROR, message, message)


def skipped_case(name: str, message: str) -> CaseResult:
    return CaseResult(name, name, SKIPPED, message=message)


def failure_case(name: str, message: str, text: str = "") -> CaseResult:
    return CaseResult(name, name, FAILURE, message, text or message)


class TestRunner:
    """Runs the ``<test>`` entries of one plan; see the module docstring."""

    def __init__(self, plan: LaunchPlan, launch_file: str, options: TestOptions,
                 run_options: RunOptions, report: Report, screen: Screen | None = None):
        self.plan = replace(plan, tests=())          # the fixture: the file without its tests
        self.tests = list(plan.tests)
        self.options = options
        self.run_options = replace(run_options, fresh_master=not options.reuse_master,
                                   with_tests=False, disable_title=True, status_view=False)
        self.report = report
        self.screen = screen
        self.package = package_of(launch_file)
        self.results_dir = os.path.join(results_root(options), self.package)
        self.interrupted = ""           # the stop signal that ended the tests (``SIGINT``)

    def run(self, tests: Sequence[Test], broken: Sequence[tuple[str, OrchestraError]]
            ) -> list[TestOutcome]:
        """Every selected test in file order; broken ``<test>`` entries as errors first."""
        outcomes = [TestOutcome(label, [error_case(label, str(exc))]) for label, exc in broken]
        for label, exc in broken:
            self.report(f"[ROSTEST] test [{label}] cannot run: {exc}")
        seen: set[str] = set()
        for test in tests:
            if self._interrupted():
                outcomes.append(TestOutcome(test.test_name, [skipped_case(
                    test.test_name, f"not run: {self.interrupted} received before it started")]))
                continue
            if test.test_name in seen:     # rostest: a second test of that name fails
                outcomes.append(TestOutcome(test.test_name, [error_case(
                    test.test_name, f"{_where(test)}more than one <test> is named "
                                    f"[{test.test_name}]")]))
                continue
            seen.add(test.test_name)
            outcomes.append(self.run_one(test))
        return outcomes

    def run_one(self, test: Test) -> TestOutcome:
        name = test.test_name
        try:
            executable = find_node_executable(test)
        except OrchestraError as exc:
            self.report(f"[ROSTEST] test [{name}]: {exc}")
            return TestOutcome(name, [error_case(name, f"test executable not found: {exc}")])
        attempts = max(0, test.retry) + 1
        outcome = TestOutcome(name)
        for attempt in range(1, attempts + 1):
            self.report(f"[ROSTEST] running test [{name}]"
                        + (f" (attempt {attempt} of {attempts})" if attempts > 1 else ""))
            started = time.monotonic()
            cases, results_file = self._attempt(test, executable)
            outcome = TestOutcome(name, cases, time.monotonic() - started, results_file, attempt)
            if outcome.verdict == PASSED or attempt == attempts or self._interrupted():
                break
            self.report(f"[ROSTEST] test [{name}] failed, retrying. "
                        f"Retries left: {attempts - attempt}")
        self.report(f"[ROSTEST] test [{name}] {outcome.verdict} "
                    f"({outcome.counts[0]} case(s), {outcome.duration:.1f} s)")
        return outcome

    # ------------------------------------------------------------------ one attempt

    def _attempt(self, test: Test, executable: str) -> tuple[list[CaseResult], str | None]:
        name = test.test_name
        run = LaunchRun(self.plan, self.run_options, report=self.report, screen=self.screen)
        try:
            run.start()
        except OrchestraError as exc:
            return [error_case(name, f"the test's nodes did not start: {exc}")], None
        try:
            os.makedirs(self.results_dir, exist_ok=True)
            results_file = os.path.join(self.results_dir, results_file_name(name))
            if os.path.exists(results_file):
                os.remove(results_file)
            return self._run_test(run, test, executable, results_file), results_file
        finally:
            self._stop_run(run)

    def _interrupted(self) -> bool:
        """A stop signal came (now or earlier): no more tests, no more attempts."""
        taken = stop_signals.take()
        if taken and not self.interrupted:
            self.interrupted = stop_signals.name(taken[0])
        return bool(self.interrupted)

    def _stop_run(self, run: LaunchRun) -> None:
        """Stop the run in order; a stop signal meanwhile kills what is still stopping."""
        stopped = threading.Event()

        def stop() -> None:
            run.stop()
            stopped.set()

        threading.Thread(target=stop, daemon=True, name="orchestra test stop").start()
        while not stop_signals.wait_event(stopped):
            taken = stop_signals.take()
            if taken and not self.interrupted:     # the first: this is already the orderly stop
                self.interrupted = stop_signals.name(taken.pop(0))
            if taken:
                run.kill_all()

    def _run_test(self, run: LaunchRun, test: Test, executable: str,
                  results_file: str) -> list[CaseResult]:
        name = test.test_name
        assert run.supervisor is not None
        spec = build_specs([test], {test.full_name: executable}, run.master_uri, run.log_dir,
                           self.run_options)[0]
        argv = [*spec.argv, GTEST_FLAG + results_file] + (["--text"] if self.options.text
                                                           else [])
        # its own mark: what the test leaves behind is found and stopped with it (the run's
        # mark would have the run's stray sweep reap our child under our feet)
        mark = new_mark()
        env = {**spec.env, MARK_VARIABLE: mark}
        output: IO[Any] | None = None
        if not self.options.text and run.log_dir:
            output = open(os.path.join(run.log_dir, f"{spec.log_name}-stdout.log"), "ab")
        try:
            try:
                os.makedirs(spec.cwd, exist_ok=True)
                proc = subprocess.Popen(argv, cwd=spec.cwd, env=env, stdin=subprocess.DEVNULL,
                                        stdout=output, stderr=subprocess.STDOUT if output else None,
                                        start_new_session=True,
                                        preexec_fn=child_setup(os.getpid()))
            except OSError as exc:
                return [error_case(name, f"cannot start test [{name}] ({argv[0]}): "
                                         f"{exc.strerror or exc}")]
            why = self._wait(run, proc, test.time_limit)
            _stop_marked(mark)
        finally:
            if output is not None:
                output.close()
        if why:
            self.report(f"[ROSTEST] test [{name}] {why}")
            return [failure_case(name, f"test [{name}] {why}")]
        return self._read_results(name, results_file, proc.returncode)

    def _wait(self, run: LaunchRun, proc: subprocess.Popen[bytes], time_limit: float) -> str:
        """Wait for the test to end; '' when it did, else why it was stopped."""
        ended = threading.Event()

        def wait_test() -> None:
            proc.wait()
            ended.set()

        def wait_run() -> None:
            run.wait()
            ended.set()

        for target in (wait_test, wait_run):
            threading.Thread(target=target, daemon=True, name="orchestra test wait").start()
        finished = stop_signals.wait_event(ended, time_limit)
        code = proc.poll()
        # the run stops by itself only when a required node ended (we stop it afterwards)
        ending = run.supervisor.result if run.supervisor is not None else None
        why = ""
        if not finished and self._interrupted():
            why = f"was interrupted: {self.interrupted} received"
        elif not finished:
            why = f"failed to complete in time: time-limit of {time_limit:g} s exceeded"
        elif ending is not None and code != 0:
            why = f"was stopped: the run ended during the test ({ending.reason})"
        self._stop(proc)
        return why

    @staticmethod
    def _stop(proc: subprocess.Popen[bytes]) -> None:
        """SIGINT to the test's group, SIGKILL after a grace period; the group always goes."""
        if proc.poll() is None:
            signal_group(proc.pid, signal.SIGINT)
            try:
                proc.wait(KILL_GRACE)
            except subprocess.TimeoutExpired:
                pass
        signal_group(proc.pid, signal.SIGKILL)
        proc.wait()

    def _read_results(self, name: str, results_file: str, code: int | None
                      ) -> list[CaseResult]:
        try:
            with open(results_file, "rb") as fh:
                data = fh.read()
        except FileNotFoundError:
            if self.options.text:       # rosunit writes no file in --text mode
                return [CaseResult(name, name) if code == 0 else failure_case(
                    name, f"test [{name}] exited with code {code}")]
            return [failure_case(name, f"test [{name}] did not generate test results "
                                       f"(exit code {code})")]
        except OSError as exc:
            return [error_case(name, f"cannot read results file {results_file}: "
                                     f"{exc.strerror}")]
        try:
            cases = parse_results_xml(data, name)
        except ResultsError as exc:
            return [error_case(name, f"{results_file}: {exc}")]
        if not cases:
            return [error_case(name, f"{results_file}: contains no test cases")]
        return cases


def _stop_marked(mark: str) -> None:
    """SIGKILL whatever the test left running outside its process group (setsid, daemons)."""
    for pid in marked_pids(mark):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def _where(test: Test) -> str:
    return f"{test.filename}:{test.line}: " if test.filename else ""
