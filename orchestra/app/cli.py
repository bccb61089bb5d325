"""``orchestra launch``, ``orchestra core`` and ``orchestra status``: the CLI edge of a run.

Click's flags become a RunOptions here, and the run's one-line messages are echoed here;
the run itself is ``orchestra.app.run.LaunchRun``, the same object the Python API returns.
Start-up time matters (tools call ``orchestra launch --dump-plan`` hundreds of times), so
this module imports only click and the errors at import time; the rest is imported when a
command runs.
"""
from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable
from typing import Any

import click

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
    click.option("--with-tests", is_flag=True, help="Also run the <test> nodes (test mode)."),
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
    return RunOptions.from_kwargs(values)


def echo_err(text: str) -> None:
    click.echo(text, err=True)


def serve_plan(plan: Any, options: Any) -> int:
    """Run ``plan`` in the foreground until it ends; orchestra's exit code."""
    from orchestra.app.run import LaunchRun

    report = LaunchRun(plan, options, report=echo_err).serve()
    if report.exit_code != 0:
        echo_err(f"orchestra: error: {report.reason}")
    else:
        echo_err(f"orchestra: {report.reason}; all processes stopped")
    return report.exit_code


def _dump_json(plan: Any) -> str:
    from orchestra.launch.interpreter import binary_to_json
    from orchestra.supervise.command import exec_table

    doc = plan.to_json()
    doc["exec"] = exec_table(plan)
    return json.dumps(doc, indent=1, default=binary_to_json)


def _node_args(plan: Any, name: str) -> str:
    import shlex

    from orchestra.launch.load import find_node
    from orchestra.supervise.command import exec_table

    node = find_node(plan, name)
    entry = exec_table(plan, include_tests=True).get(node.full_name)
    if entry is None:
        raise OrchestraError(f"no command line for node [{node.full_name}]")
    env = [f"{k}={shlex.quote(v)}" for k, v in entry["env"].items()]
    return " ".join([*env, *(shlex.quote(a) for a in entry["argv"])])


def launch_words(words: tuple[str, ...], command: str) -> tuple[list[str], dict[str, str]]:
    """Files and args of ``orchestra COMMAND [PKG] FILE [name:=value ...]``."""
    from orchestra.launch.load import split_words

    if not any(":=" not in word for word in words):
        raise click.UsageError(f"give a launch file: orchestra {command} [PKG] FILE "
                               "[name:=value ...]")
    return split_words(words)


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("words", nargs=-1)
@click.option("--dump-plan", is_flag=True, help="Print the resolved plan as JSON and exit.")
@click.option("--dump-params", is_flag=True, help="Print the parameters as YAML and exit.")
@click.option("--nodes", is_flag=True, help="List the nodes' full names and exit.")
@click.option("--args", "node_args", metavar="NODE", help="Print NODE's command line and exit.")
@click.option("--files", is_flag=True, help="List the launch files read and exit.")
@click.option("--find-node", metavar="NODE", help="Print the file declaring NODE and exit.")
@click.option("--ros-args", is_flag=True, help="Show the launch file's <arg>s and exit.")
@click.option("--no-exec", is_flag=True,
              help="Do not run command= params; record them as {__command__: cmd}.")
@run_options
def launch(words: tuple[str, ...], dump_plan: bool, dump_params: bool, nodes: bool,
           node_args: str | None, files: bool, find_node: str | None, ros_args: bool,
           no_exec: bool, **run_opts: Any) -> None:
    """Resolve and run a roslaunch file: orchestra launch [PKG] FILE [name:=value ...]."""
    from orchestra.launch.load import find_node as find_declared
    from orchestra.launch.load import interpret, ros_args_text

    paths, args = launch_words(words, "launch")
    if ros_args:
        click.echo(ros_args_text(paths, args))
        return
    dumping = dump_plan or dump_params or nodes or bool(node_args) or files or bool(find_node)
    # like roslaunch, everything but the two dumps loads roscore.xml's params first; when the
    # plan is going to run, command= params always run (--no-exec only shapes the dumps)
    interp = interpret(paths, args, no_exec=no_exec and dumping,
                       roscore=not (dump_plan or dump_params))
    plan = interp.plan()
    if dump_plan:
        click.echo(_dump_json(plan))
    elif dump_params:
        import yaml

        from orchestra.launch.interpreter import Binary
        yaml.SafeDumper.add_representer(Binary, yaml.SafeDumper.represent_binary)
        # roslaunch prints the YAML document (which ends in a newline) with print(), so its
        # output ends in an empty line; scripts diff the two, so match it byte for byte
        click.echo(yaml.safe_dump(dict(plan.params), default_flow_style=False))
    elif nodes:
        names = [n.full_name for n in (*plan.nodes, *plan.tests) if n.name]
        if names:
            click.echo("\n".join(names))
    elif node_args:
        click.echo(_node_args(plan, node_args))
    elif files:
        seen: list[str] = []
        for path in plan.files_loaded:
            full = os.path.abspath(path)
            if full not in seen:
                seen.append(full)
        click.echo("\n".join(seen))
    elif find_node:
        node = find_declared(plan, find_node)
        click.echo(node.filename or "")
    else:
        sys.exit(serve_plan(plan, options_from_cli(run_opts)))


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
    sys.exit(0 if all(o.verdict == PASSED for o in outcomes) else 1)
