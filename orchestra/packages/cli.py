"""``orchestra pkg`` (rospack) and ``orchestra create-pkg`` (catkin_create_pkg).

Thin wrappers: every decision is made in the library modules next to this one. (``orchestra
run``, rosrun, gives the executable the ROS 1 layer's environment, so it lives a layer up,
in ros1/cli.py.)
"""
from __future__ import annotations

import os
import shlex

import click


@click.group()
def pkg() -> None:
    """Find packages and their dependencies (like rospack)."""


@pkg.command("list")
@click.option("--duplicates", is_flag=True,
              help="Only packages found more than once: the winner, then the shadowed copies.")
@click.option("-n", "--names-only", is_flag=True, help="Print names only.")
@click.option("--origins", is_flag=True,
              help="Also say which search root each package came from.")
def list_cmd(duplicates: bool, names_only: bool, origins: bool) -> None:
    """Every package on the search path, with its directory."""
    from orchestra.packages.index import get_index

    index = get_index()
    if duplicates:
        for name in sorted(index.duplicates):
            click.echo(f"{name} {index.packages[name]}")
            for shadowed in index.duplicates[name]:
                click.echo(f"{name} {shadowed} (shadowed)")
        return
    for name in index.names():
        if names_only:
            click.echo(name)
        elif origins:
            click.echo(f"{name} {index.packages[name]} [{index.origins[name].origin}]")
        else:
            click.echo(f"{name} {index.packages[name]}")


@pkg.command("find")
@click.argument("name")
def find_cmd(name: str) -> None:
    """The directory of package NAME (what $(find NAME) gives)."""
    from orchestra.packages.index import find_package

    click.echo(find_package(name))


@pkg.command("show")
@click.argument("name")
def show_cmd(name: str) -> None:
    """What package NAME's manifest says: metadata, dependencies by kind, exports."""
    from orchestra.packages.index import find_package
    from orchestra.packages.manifest import parse_manifest

    manifest = parse_manifest(find_package(name))
    people = lambda persons: ", ".join(  # noqa: E731
        f"{p.name} <{p.email}>" if p.email else p.name for p in persons)
    click.echo(f"name: {manifest.name}")
    click.echo(f"path: {os.path.dirname(manifest.path)}")
    click.echo(f"format: {manifest.format or 'rosbuild manifest.xml'}")
    click.echo(f"version: {manifest.version or ''}")
    click.echo(f"description: {manifest.description}")
    click.echo(f"maintainers: {people(manifest.maintainers)}")
    if manifest.authors:
        click.echo(f"authors: {people(manifest.authors)}")
    click.echo(f"licenses: {', '.join(manifest.licenses)}")
    for kind, names in manifest.dependencies_by_kind().items():
        if names:
            click.echo(f"{kind}_depends: {' '.join(names)}")
    for tag in ("conflict", "replace", "group_depend", "member_of_group"):
        if manifest.relation(tag):
            click.echo(f"{tag}: {' '.join(manifest.relation(tag))}")
    for export in manifest.exports:
        attrs = " ".join(f'{k}="{v}"' for k, v in export.attributes)
        click.echo(f"export: <{export.tag}{' ' + attrs if attrs else ''}>{export.content}")
    for warning in manifest.warnings:
        click.echo(f"orchestra: warning: {manifest.path}: {warning}", err=True)


@pkg.command("plugins")
@click.argument("tool")
@click.option("--attrib", default="plugin", show_default=True,
              help="Attribute of the <TOOL> export tag to print.")
def plugins_cmd(tool: str, attrib: str) -> None:
    """Exports for TOOL (rospack plugins): `package value` for each package depending on TOOL
    whose package.xml has <export><TOOL ATTRIB="value"/></export>."""
    from orchestra.packages.plugins import find_plugins

    for export in find_plugins(tool, attrib):
        click.echo(f"{export.package} {export.value}")


@pkg.command("roots")
def roots_cmd() -> None:
    """The directories searched for packages, highest priority first."""
    from orchestra.packages.discovery import search_roots

    for root in search_roots():
        mark = "" if os.path.isdir(root.path) else " (missing)"
        click.echo(f"{root.path} [{root.origin}]{mark}")


@pkg.command("which")
@click.argument("package")
@click.argument("exe")
def which_cmd(package: str, exe: str) -> None:
    """The executable EXE of PACKAGE that `orchestra run` and <node> would start."""
    from orchestra.packages.executables import find_executable

    click.echo(find_executable(package, exe))


@pkg.command("deps")
@click.argument("name")
@click.option("-1", "--direct", is_flag=True, help="Direct dependencies only (rospack depends1).")
@click.option("-k", "--kind", "kinds", multiple=True,
              type=click.Choice(["buildtool", "buildtool_export", "build", "build_export",
                                 "exec", "test", "doc"]),
              help="Dependency kinds to follow (repeatable; default: build and exec kinds).")
@click.option("--on", "reverse", is_flag=True,
              help="Packages that depend on NAME instead (rospack depends-on).")
@click.option("--missing", is_flag=True,
              help="Only dependencies no package on the path provides (system deps, typos).")
def deps_cmd(name: str, direct: bool, kinds: tuple[str, ...], reverse: bool, missing: bool) -> None:
    """Dependencies of package NAME, transitive by default, each after its own dependencies."""
    from orchestra.packages.deps import DEFAULT_KINDS, all_packages_graph, build_graph

    chosen = tuple(kinds) or DEFAULT_KINDS
    if reverse:
        graph = all_packages_graph(chosen)
        names = sorted(graph.graph.predecessors(name)) if direct else graph.dependents(name)
    else:
        graph = build_graph([name], chosen)
        names = graph.direct(name) if direct else graph.transitive(name)
        if missing:
            absent = set(graph.missing)
            names = [n for n in names if n in absent]
    for dep in names:
        click.echo(dep)


CREATE_HELP = """Create catkin package NAME depending on DEPS (like catkin_create_pkg).

\b
Options (as catkin_create_pkg):
  -s, --sys-deps DEP...      system dependencies (take every following word)
  -b, --boost-comps COMP...  Boost components (adds the boost system dependency)
  -V, --pkg_version VERSION  initial version (default 0.0.0)
  -D, --description TEXT     description
  -l, --license NAME         a license (repeatable; default TODO)
  -a, --author NAME          an author (repeatable)
  -m, --maintainer NAME      a maintainer (repeatable; default: your user name)
  --rosdistro NAME           accepted for compatibility (templates do not vary by distro)
  --meta                     make a metapackage
Orchestra additions:
  --python-node NODE         also write scripts/NODE (a node on orchestra's runtime) and
                             launch/NAME.launch starting it
  -C, --directory DIR        create the package in DIR instead of the current directory
"""

_GREEDY = {"-s": "sys_deps", "--sys-deps": "sys_deps", "-b": "boost_comps",
           "--boost-comps": "boost_comps"}
_SINGLE = {"-V": "version", "--pkg_version": "version", "--pkg-version": "version",
           "-D": "description", "--description": "description", "--rosdistro": "rosdistro",
           "--python-node": "python_node", "-C": "directory", "--directory": "directory"}
_APPEND = {"-l": "licenses", "--license": "licenses", "-a": "authors", "--author": "authors",
           "-m": "maintainers", "--maintainer": "maintainers"}


def parse_create_args(argv: list[str]) -> tuple[dict, str]:
    """catkin_create_pkg's argument grammar -> (PackageRequest fields, target directory).

    Hand-written because ``-s``/``-b`` take "every following word" (argparse ``nargs='*'``),
    which click options cannot express.
    """
    fields: dict = {"dependencies": [], "sys_deps": [], "boost_comps": [], "licenses": [],
                    "authors": [], "maintainers": []}
    positional: list[str] = []
    directory = "."
    i = 0
    options_done = False
    while i < len(argv):
        token = argv[i]
        i += 1
        if options_done or not token.startswith("-") or token == "-":
            positional.append(token)
            continue
        if token == "--":
            options_done = True
            continue
        value = None
        if token.startswith("--") and "=" in token:
            token, value = token.split("=", 1)
        if token == "--meta":
            fields["meta"] = True
        elif token in _GREEDY:
            bucket = fields[_GREEDY[token]]
            if value is not None:
                bucket.append(value)
            while i < len(argv) and not argv[i].startswith("-"):
                bucket.append(argv[i])
                i += 1
        elif token in _SINGLE or token in _APPEND:
            if value is None:
                if i >= len(argv):
                    raise click.UsageError(f"option {token} needs a value")
                value = argv[i]
                i += 1
            if token in _SINGLE:
                if _SINGLE[token] == "directory":
                    directory = value
                else:
                    fields[_SINGLE[token]] = value
            else:
                fields[_APPEND[token]].append(value)
        else:
            raise click.UsageError(f"no such option: {token}")
    if not positional:
        raise click.UsageError("missing the package NAME")
    fields["name"] = positional[0]
    fields["dependencies"] = positional[1:]
    for key in ("dependencies", "sys_deps", "boost_comps", "licenses", "authors", "maintainers"):
        fields[key] = tuple(fields[key])
    return fields, directory


@click.command(help=CREATE_HELP, options_metavar="",
               context_settings={"ignore_unknown_options": True,
                                 "help_option_names": ["-h", "--help"]})
@click.argument("argv", nargs=-1, type=click.UNPROCESSED, metavar="NAME [DEPS...] [OPTIONS]")
def create_pkg(argv: tuple[str, ...]) -> None:
    from orchestra.packages.create import PackageRequest, create_package
    from orchestra.packages.discovery import search_roots

    fields, directory = parse_create_args(list(argv))
    created = create_package(PackageRequest(**fields), directory)
    for warning in created.warnings:
        click.echo(f"orchestra: warning: {warning}", err=True)
    base = os.path.dirname(created.path)
    for relative in created.files:
        click.echo(f"Created file {os.path.relpath(os.path.join(created.path, relative), base)}")
    for relative in created.dirs:
        click.echo(f"Created folder {os.path.relpath(os.path.join(created.path, relative), base)}")
    click.echo(f"Successfully created files in {created.path}. "
               "Please adjust the values in package.xml.")
    parent = os.path.dirname(created.path)
    roots = [root.path for root in search_roots()]
    if not any(parent == root or parent.startswith(root + os.sep) for root in roots):
        click.echo(f"note: {parent} is not on the package search path; to use the package run\n"
                   f"  export ROS_PACKAGE_PATH={shlex.quote(parent)}:$ROS_PACKAGE_PATH", err=True)
