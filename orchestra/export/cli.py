"""``orchestra export --to systemd DIR [PKG] FILE [name:=value ...]``."""
from __future__ import annotations

import os

import click

from orchestra.errors import OrchestraError


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("directory", type=click.Path(file_okay=False))
@click.argument("words", nargs=-1, required=True)
@click.option("--to", "fmt", type=click.Choice(["systemd"]), required=True,
              help="What to write (systemd: one .service per node, grouped per machine).")
@click.option("--prefix", help="Unit name prefix (default: orchestra-<launch file name>).")
@click.option("--orchestra-command", default="orchestra", show_default=True,
              help="How the units run orchestra on each machine.")
def export(directory: str, words: tuple[str, ...], fmt: str, prefix: str | None,
           orchestra_command: str) -> None:
    """Write a launch file as units for another process manager (see docs/remote.md).

    DIR gets one sub-directory per machine (``local`` and each remote <machine>), each
    with a .service per node and a .target; ``local`` also has the master, the parameter
    loader and the parameters file. Install: copy a machine's directory to
    /etc/systemd/system on that machine, ``systemctl daemon-reload``, ``systemctl enable
    --now PREFIX.target``.
    """
    from orchestra.export.systemd import ExportOptions, default_prefix, nested_params, units
    from orchestra.launch.load import interpret, split_words
    from orchestra.master import master_uri_from_env
    from orchestra.params.dump import dump_yaml
    from orchestra.remote.locality import UnresolvableAddress, is_local_machine
    from orchestra.remote.session import reachable_master_uri

    paths, args = split_words(words)
    plan = interpret(paths, args, no_exec=False, roscore=False).plan()
    used = {n.machine_name for n in plan.nodes if n.machine_name}
    is_remote: dict[str, bool] = {}
    for name in used:
        machine = plan.machines[name]
        try:
            is_remote[name] = not is_local_machine(machine.address, machine.user)
        except UnresolvableAddress:
            raise OrchestraError(f"cannot resolve host address for machine '{name}' "
                                 f"({machine.address})") from None
    master_uri = master_uri_from_env()
    master_uris = {name: reachable_master_uri(master_uri, plan.machines[name].address)
                   for name, remote in is_remote.items() if remote}
    prefix = prefix or default_prefix(plan.files_loaded)
    root = os.path.abspath(directory)
    params_path = os.path.join(root, "local", f"{prefix}-params.yaml")
    files = units(plan, ExportOptions(prefix=prefix, master_uri=master_uri,
                                      params_path=params_path, orchestra=orchestra_command,
                                      public_master=any(is_remote.values())),
                  is_remote, master_uris)
    files[f"local/{prefix}-params.yaml"] = dump_yaml(nested_params(dict(plan.params)))
    try:
        for relative, text in sorted(files.items()):
            target = os.path.join(root, relative)
            os.makedirs(os.path.dirname(target), exist_ok=True)
            with open(target, "w", encoding="utf-8") as fh:
                fh.write(text)
            click.echo(target)
    except OSError as exc:
        raise OrchestraError(f"cannot write into {root}: {exc.strerror}") from None
    click.echo(f"{len(files)} file(s) for {len(plan.nodes)} node(s) on "
               f"{len({p.split('/')[0] for p in files})} machine(s)", err=True)
