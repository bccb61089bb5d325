"""``orchestra launch``, ``orchestra core`` and ``orchestra status``: the CLI edge of a run.

Click's flags become a RunOptions here, and the run's one-line messages are echoed here;
the run itself is ``orchestra.app.run.LaunchRun``, the same object the Python API returns.
Start-up time matters (tools call ``orchestra launch --dump-plan`` hundreds of times), so
this module imports only click and the errors at import time; the rest is imported when a
command runs.
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
from collections.abc import Callable, Iterator
from typing import Any

import click

from orchestra.app.launch_output import OUTPUT_OPTIONS, prints_and_exits, write_outputs
from orchestra.completion import complete_launch_words
from orchestra.errors import OrchestraError

_OPTIONS = [
    click.option("--screen", "force_screen", is_flag=True,
                 help="Force every node's output to the console."),
    click.option("--log", "force_log", is_flag=True,
                 help="Force every node's output to log files."),
    click.option("--wait", is_flag=True,
                 help="Wait for the master at ROS_MASTER_URI instead of starting one."),
    click.option("--required", "all_required", is_flag=True,
                 help="Treat every node as required: any death stops the launch."),
    click.option("--local", is_flag=True,
                 help="Do not launch remote nodes (those of a <machine> that is not this one)."),
    click.option("--disable-title", is_flag=True, help="Do not set the terminal title."),
    click.option("-p", "--port", type=click.IntRange(0, 65535), default=None,
                 help="Port of the master to use or start (default: from ROS_MASTER_URI)."),
    click.option("--run-id", "--run_id", "run_id", default=None,
                 help="The run id (default: the master's /run_id, else a new uuid1)."),
    click.option("--sigint-timeout", type=click.FloatRange(min=0), default=15.0,
                 show_default=True, help="Seconds a node has to exit after SIGINT."),
    click.option("--sigterm-timeout", type=click.FloatRange(min=0), default=2.0,
                 show_default=True, help="Seconds a node has to exit after SIGTERM, then SIGKILL."),
    click.option("--node-timeout", "node_timeouts", multiple=True,
                 metavar="NODE=SIGINT[,SIGTERM]",
                 help="Per-node stop timeouts, e.g. /camera=30,5 (repeatable)."),
    click.option("--backoff-max", type=click.FloatRange(min=0), default=30.0,
                 show_default=True, help="Longest wait between respawns of a crash-looping node."),
    click.option("--crash-limit", type=click.IntRange(min=0), default=10, show_default=True,
                 help="Short runs in a row after which a respawning node is FAILED (0: never)."),
    click.option("--log-max-size", "log_max_size", default="50M", show_default=True,
                 help="Rotate a node's log file past this size (0: never)."),
    click.option("--log-backups", type=click.IntRange(min=0), default=5, show_default=True,
                 help="Rotated log files kept per stream."),
    click.option("--status/--no-status", "status_view", default=None,
                 help="Live status table under the output (default: on a terminal)."),
    click.option("--ui/--no-ui", "ui", default=None,
                 help="--ui: the interactive view (select a node, s stop/start, r restart, "
                      "m mute, l log, / filter, q quit); it takes the keyboard from the nodes. "
                      "--no-ui: plain output, no live table."),
    click.option("--with-tests", is_flag=True, help="Also run the <test> nodes (test mode)."),
    click.option("--pid", "pid_file", default=None, metavar="FILE",
                 help="Write orchestra's pid to FILE (removed when the launch ends)."),
    click.option("--no-summary", is_flag=True, help="Do not print the SUMMARY block."),
    click.option("-t", "--timeout", "socket_timeout",
                 type=click.FloatRange(min=0, min_open=True), default=None, metavar="SECONDS",
                 help="Socket connection timeout of the master and of calls to it "
                      "(roslaunch's -t; default: none)."),
    click.option("--skip-log-check", is_flag=True,
                 help="Do not check the size of the log directory (warned past 1 GB)."),
    click.option("-c", "--child", "child_name", default=None, metavar="NAME", hidden=True),
    click.option("-u", "--server_uri", "--server-uri", "server_uri", default=None,
                 metavar="URI", hidden=True),
    click.option("--no-rosout", is_flag=True,
                 help="Do not start /rosout with the embedded master (roscore's log "
                      "aggregator: /rosout_agg and rosout.log)."),
]


def run_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator adding the run-time options of ``orchestra launch``."""
    for option in reversed(_OPTIONS):
        func = option(func)
    return func


def options_from_cli(kwargs: dict[str, Any]) -> Any:
    """click's keyword arguments of ``run_options`` -> a RunOptions (the CLI edge)."""
    from orchestra.app.options import RunOptions, parse_size

    values = dict(kwargs)
    if values.get("force_screen") and values.get("force_log"):
        raise OrchestraError("--screen and --log cannot be used together")
    if "log_max_size" in values:
        values["log_max_bytes"] = parse_size(values.pop("log_max_size"))
    if values.get("ui") is False:
        values["status_view"] = False
    return RunOptions.from_kwargs(values)


def echo_err(text: str) -> None:
    click.echo(text, err=True)


LOG_CHECK_BYTES = 1 << 30


def log_size_warning(root: str, limit: int = LOG_CHECK_BYTES) -> str | None:
    """roslaunch's log-directory check: a warning once the logs pass ``limit`` bytes."""
    total = 0
    for dirpath, _, files in os.walk(root):
        for name in files:
            try:
                total += os.lstat(os.path.join(dirpath, name)).st_size
            except OSError:
                continue
            if total > limit:
                return (f"WARNING: disk usage in log directory [{root}] is over "
                        f"{limit / (1 << 30):g}GB.\nIt's recommended that you delete old "
                        "run directories there (--skip-log-check skips this check).")
    return None


@contextlib.contextmanager
def pid_file(path: str | None) -> Iterator[None]:
    """roslaunch's ``--pid``: this process's pid in ``path`` while the run lasts."""
    if path is None:
        yield
        return
    path = os.path.expanduser(path)
    try:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(str(os.getpid()))
    except OSError as exc:
        raise OrchestraError(f"--pid: cannot write {path}: {exc.strerror or exc}") from None
    try:
        yield
    finally:
        try:
            os.unlink(path)
        except OSError:
            pass


def print_summary(plan: Any) -> Callable[[list[Any], list[Any], str], None]:
    """The ``announce`` of a run: roslaunch's SUMMARY, then ``ROS_MASTER_URI=...``."""
    from orchestra.launch.summary import summary
    from orchestra.master import core_params

    def announce(nodes: list[Any], remote: list[Any], master_uri: str) -> None:
        core = {k: v for k, v in core_params().items() if k != "/run_id"}
        click.echo(summary(plan, core, nodes + remote, remote=bool(remote)))
        click.echo(f"ROS_MASTER_URI={master_uri}\n")

    return announce


def serve_plan(plan: Any, options: Any, cli: dict[str, Any] | None = None) -> int:
    """Run ``plan`` in the foreground until it ends; orchestra's exit code.

    ``cli``: roslaunch's flags that shape the run from outside (pid file, summary, log check,
    socket timeout).
    """
    import socket

    from orchestra.app.run import LaunchRun
    from orchestra.rosdirs import log_dir_root

    cli = cli or {}
    if cli.get("socket_timeout") is not None:
        socket.setdefaulttimeout(cli["socket_timeout"])   # rosmaster's -t: every socket
    if not cli.get("skip_log_check"):
        warning = log_size_warning(log_dir_root())
        if warning:
            echo_err(warning)
    announce = None if cli.get("no_summary") else print_summary(plan)
    with pid_file(cli.get("pid_file")):
        report = LaunchRun(plan, options, report=echo_err, announce=announce).serve()
    if report.exit_code != 0:
        echo_err(f"orchestra: error: {report.reason}")
    else:
        echo_err(f"orchestra: {report.reason}; all processes stopped")
    return report.exit_code


def launch_words(words: tuple[str, ...], command: str) -> tuple[list[str], dict[str, str]]:
    """Files and args of ``orchestra COMMAND [PKG] FILE [name:=value ...]``."""
    from orchestra.launch.load import split_words

    if not any(":=" not in word for word in words):
        raise click.UsageError(f"give a launch file: orchestra {command} [PKG] FILE "
                               "[name:=value ...]")
    return split_words(words)


def output_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator adding the print-and-exit options of ``orchestra launch``, built from their
    one definition (``launch_output.OUTPUT_OPTIONS``, which also reads them without click)."""
    for option in reversed(OUTPUT_OPTIONS):
        kind: dict[str, Any] = ({"is_flag": True} if option.metavar is None
                                else {"metavar": option.metavar})
        func = click.option(option.flag, option.dest, help=option.help, **kind)(func)
    return func


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("words", nargs=-1, shell_complete=complete_launch_words)
@output_options
@click.option("--core", "core_only", is_flag=True,
              help="Run the core only (master, parameter server, rosout), like roscore.")
@run_options
@click.pass_context
def launch(ctx: click.Context, words: tuple[str, ...], core_only: bool, **options: Any) -> None:
    """Resolve and run a roslaunch file: orchestra launch [PKG] FILE [name:=value ...]."""
    from orchestra.supervise import stop_signals

    stop_signals.record()   # first: a Ctrl-C from here on is an orderly stop, never lost
    modes = {o.dest: options.pop(o.dest) for o in OUTPUT_OPTIONS}
    if prints_and_exits(modes) or modes["ros_args"]:
        stop_signals.release()   # it starts nothing: a Ctrl-C simply ends it
    run_opts = options
    cli_only = {k: run_opts.pop(k) for k in _CLI_ONLY}
    if cli_only.get("child_name") or cli_only.get("server_uri"):
        raise OrchestraError("-c/--child and -u/--server_uri run roslaunch as the child of a "
                             "remote parent launch; orchestra starts the nodes of remote "
                             "machines itself (see docs/remote.md), so it has no child mode")
    if core_only:
        _launch_core(ctx, words, run_opts, cli_only)
        return
    paths, args = launch_words(words, "launch")
    if write_outputs(paths, args, modes):
        return
    from orchestra.launch.load import interpret, undeclared_args

    # a run loads roscore.xml's params first, as roslaunch does, and always runs command=
    # params (--no-exec only shapes the dumps)
    plan = interpret(paths, args, no_exec=False, roscore=True).plan()
    for warning in undeclared_args(paths, args):
        echo_err(f"orchestra: {warning}")
    code = serve_plan(plan, options_from_cli(run_opts), cli_only)
    # the run is over and this process ends now: the interpreter's exit need not search what
    # it holds for garbage (20-50 ms, more on a busy machine, of every stop)
    import gc

    gc.freeze()
    sys.exit(code)


# roslaunch's flags that the CLI handles around a run (not RunOptions of the run itself)
_CLI_ONLY = ("pid_file", "no_summary", "socket_timeout", "skip_log_check", "child_name",
             "server_uri")


def _launch_core(ctx: click.Context, words: tuple[str, ...], run_opts: dict[str, Any],
                 cli_only: dict[str, Any]) -> None:
    """``launch --core``: ``orchestra core`` under roslaunch's rules (no files, no --wait,
    and a pid file, by default ``$ROS_HOME/roscore-<port>.pid``, while it runs)."""
    from orchestra.master import master_uri_from_env, port_from_uri
    from orchestra.rosdirs import ros_home

    if words:
        raise click.UsageError("launch files are not allowed with --core")
    if run_opts.get("wait"):
        raise click.UsageError("--wait cannot be used with --core")
    port = run_opts.get("port")
    port = port_from_uri(master_uri_from_env()) if port is None else port
    if cli_only.get("socket_timeout") is not None:
        import socket

        socket.setdefaulttimeout(cli_only["socket_timeout"])
    with pid_file(cli_only.get("pid_file") or os.path.join(ros_home(), f"roscore-{port}.pid")):
        ctx.invoke(core, port=port, host=None, no_rosout=bool(run_opts.get("no_rosout")))


@click.command()
@click.option("-p", "--port", type=click.IntRange(0, 65535), default=None,
              help="Port to serve on (default: the port of ROS_MASTER_URI, else 11311).")
@click.option("--host", default=None, metavar="ADDR",
              help="Address to bind (default 127.0.0.1; 0.0.0.0 when ROS_IP/ROS_HOSTNAME "
                   "is set).")
@click.option("--no-rosout", is_flag=True,
              help="Do not start the /rosout node (log aggregation on /rosout_agg).")
def core(port: int | None, host: str | None, no_rosout: bool) -> None:
    """Run a ROS master, parameter server and the rosout node until interrupted."""
    from orchestra.supervise import stop_signals

    stop_signals.record()   # as launch: a Ctrl-C while the master starts is an orderly stop
    from orchestra.app.core import serve_core_until_stopped

    code = serve_core_until_stopped(port, host, not no_rosout, out=click.echo,
                                    report=echo_err)
    if code:
        click.get_current_context().exit(code)


@click.command()
@click.option("--json", "as_json", is_flag=True, help="Print the snapshot(s) as JSON.")
@click.option("--socket", "socket_path", default=None, type=click.Path(),
              help="Ask only the launch behind this status socket.")
@click.option("--master", "use_master", is_flag=True,
              help="Ask the launches registered on the master at ROS_MASTER_URI "
                   "(/roslaunch/uris), also those of other users and machines.")
@click.option("--all", "all_launches", is_flag=True,
              help="Every launch of this user on this machine, whatever its master.")
def status(as_json: bool, socket_path: str | None, use_master: bool,
           all_launches: bool) -> int:
    """Show the nodes of the running launch: state, pid, restarts, uptime, CPU%, RSS, and
    why a node is not running.

    By default the launch of this user whose master is at ROS_MASTER_URI answers over its
    local socket (as rosnode/rostopic talk to the ROS_MASTER_URI graph only).
    """
    from orchestra.master import master_uri_from_env
    from orchestra.supervise.status import (
        launches_at,
        launches_on_master,
        query,
        running_launches,
        table_lines,
    )

    uri = master_uri_from_env()
    if socket_path:
        try:
            launches = [query(socket_path)]
        except OSError as exc:
            raise click.ClickException(f"no launch answers at {socket_path}: {exc}") from None
    elif use_master:
        try:
            launches = launches_on_master(uri)
        except OSError as exc:
            raise click.ClickException(str(exc)) from None
    elif all_launches:
        launches = running_launches()
    else:
        launches = launches_at(uri)
    if as_json:
        import json

        click.echo(json.dumps(launches if not socket_path else launches[0], indent=1))
        return 0
    if not launches:
        others = 0 if (socket_path or use_master or all_launches) else len(running_launches())
        hint = (f" at {uri} ({others} other launch(es) of yours run on other masters: "
                "orchestra status --all)") if others else ""
        click.echo(f"no running orchestra launch{hint}", err=True)
        return 1
    for i, launch in enumerate(launches):
        if i:
            click.echo()
        files = " ".join(launch.get("launch_files", [])[:1]) or "?"
        click.echo(f"launch {files} (pid {launch['pid']}, master {launch.get('master_uri')})")
        for line in table_lines(launch["nodes"]):
            click.echo(line)
    return 0


@click.command(name="test", context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("words", nargs=-1)
@click.option("--junit-xml", "junit_xml", type=click.Path(dir_okay=False), default=None,
              help="Write the combined JUnit XML here (default: "
                   "RESULTS_DIR/<pkg>/rostest-<file>.xml).")
@click.option("--results-dir", type=click.Path(file_okay=False), default=None,
              help="Where tests write their results (default: ROS_TEST_RESULTS_DIR, else "
                   "ROS_HOME/test_results).")
@click.option("--text", is_flag=True,
              help="Test output on the console, and --text passed to each test.")
@click.option("--reuse-master", "-r", is_flag=True,
              help="Use the master at ROS_MASTER_URI for every test instead of a fresh one.")
@click.option("-t", "--test", "only", multiple=True, metavar="TEST",
              help="Run only this test (its test-name; repeatable).")
@click.option("--sigint-timeout", type=click.FloatRange(min=0), default=15.0,
              show_default=True, help="Seconds a node has to exit after SIGINT.")
@click.option("--sigterm-timeout", type=click.FloatRange(min=0), default=2.0,
              show_default=True, help="Seconds a node has to exit after SIGTERM, then SIGKILL.")
def test_command(words: tuple[str, ...], junit_xml: str | None, results_dir: str | None,
                 text: bool, reuse_master: bool, only: tuple[str, ...],
                 sigint_timeout: float, sigterm_timeout: float) -> None:
    """Run a launch file's <test>s as rostest does: orchestra test [PKG] FILE [name:=value ...].

    Each test gets the file's nodes on a fresh master, --gtest_output=xml:PATH and its
    time-limit; the summary and one combined JUnit file report every test. Exit code 0 when
    every test passed, 1 otherwise, 2 for a launch file that cannot be loaded.
    """
    from orchestra.supervise import stop_signals

    stop_signals.record()   # as launch: a Ctrl-C from here on stops the tests in order
    from orchestra.app.junit import PASSED, combined_xml, summary_lines
    from orchestra.app.options import RunOptions
    from orchestra.app.testrun import TestOptions, TestRunner, select_tests
    from orchestra.launch.load import interpret

    paths, args = launch_words(words, "test")
    interp = interpret(paths, args, no_exec=False, roscore=True, keep_broken_tests=True)
    plan = interp.plan()
    options = TestOptions(results_dir=results_dir, text=text, reuse_master=reuse_master,
                          only=only)
    tests, broken = select_tests(plan.tests, interp.broken_tests, only)
    if not tests and not broken:
        raise OrchestraError(f"{paths[0]}: no <test> to run")
    runner = TestRunner(plan, paths[0], options,
                        RunOptions(sigint_timeout=sigint_timeout,
                                   sigterm_timeout=sigterm_timeout), echo_err)
    outcomes = runner.run(tests, broken)
    stem = os.path.splitext(os.path.basename(paths[0]))[0]
    out = junit_xml or os.path.join(runner.results_dir, f"rostest-{stem}.xml")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "wb") as fh:
        fh.write(combined_xml(f"{runner.package}.{stem}", outcomes))
    click.echo("\n".join(summary_lines(outcomes, colour=sys.stdout.isatty())))
    click.echo(f"\nJUnit results: {out}")
    if runner.interrupted:
        echo_err(f"orchestra: {runner.interrupted} received, tests stopped")
        sys.exit(128 + signal.Signals[runner.interrupted])
    sys.exit(0 if all(o.verdict == PASSED for o in outcomes) else 1)
