"""From command-line words to a launch plan: ``[PKG] FILE [name:=value ...]``.

Shared by ``orchestra launch``, ``orchestra test`` and the Python API (``launch_file``), so
a file is found, its args parsed and interpreted the same way everywhere. Imports only the
standard library at import time; the interpreter is imported when a file is loaded.
"""
from __future__ import annotations

import os
import sys
from typing import Any

from orchestra.errors import OrchestraError


def find_in_package(package: str, filename: str) -> str:
    """FILE anywhere below PKG's directory (roslaunch's ``roslaunch PKG FILE`` rule)."""
    from orchestra.packages import find_package
    root = find_package(package)
    direct = os.path.join(root, filename)
    if os.path.isfile(direct):
        return direct
    base = os.path.basename(filename)
    matches = []
    for dirpath, dirnames, files in os.walk(root, followlinks=True):
        dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
        if base in files:
            matches.append(os.path.join(dirpath, base))
    if not matches:
        from orchestra.suggest import did_you_mean

        launch_files = package_launch_files(root)
        hint = did_you_mean(base, launch_files) or _listing(package, launch_files)
        raise OrchestraError(f"[{filename}] is neither a launch file in package [{package}] "
                             f"nor a launch file name{hint}")
    if len(matches) > 1:
        listing = "".join(f"\n  {m}" for m in matches)
        raise OrchestraError(f"multiple files named [{filename}] in package [{package}]:"
                             f"{listing}\nname one by its path")
    return matches[0]


def package_launch_files(root: str) -> list[str]:
    """The names of the launch files anywhere below a package's directory, sorted."""
    return sorted({f for _, _, files in os.walk(root, followlinks=True) for f in files
                   if f.endswith((".launch", ".xml", ".yaml")) and f != "package.xml"})


def _listing(package: str, launch_files: list[str]) -> str:
    """`` (its launch files: a.launch, b.launch)``: what the user can name instead."""
    if not launch_files:
        return f" (package [{package}] has no launch files)"
    more = f", ... ({len(launch_files)} in all)" if len(launch_files) > 8 else ""
    return f" (its launch files: {', '.join(launch_files[:8])}{more})"


def _package_without_file(word: str) -> None:
    """``orchestra launch PKG`` with no FILE: say so and list PKG's launch files, instead
    of reporting a missing file named like the package."""
    from orchestra.packages import find_package
    if os.sep in word or os.path.exists(word):
        return
    try:
        root = find_package(word)
    except OrchestraError:
        return
    raise OrchestraError(f"[{word}] is a package, not a launch file: name a launch file "
                         f"after it{_listing(word, package_launch_files(root))}")


def split_words(words: tuple[str, ...]) -> tuple[list[str], dict[str, str]]:
    """Launch file paths and ``name:=value`` args from the command line words."""
    from orchestra.names import load_mappings
    positional = [w for w in words if ":=" not in w]
    args = load_mappings([w for w in words if ":=" in w])
    if not positional:
        raise OrchestraError("give a launch file: [PKG] FILE [name:=value ...]")
    first = positional[0]
    if len(positional) == 1 and not first.endswith((".launch", ".xml", ".yaml", ".yml")):
        _package_without_file(first)
    if first == "-" or os.path.isfile(first) or len(positional) != 2 \
            or first.endswith((".launch", ".xml", ".yaml", ".yml")):
        files = positional
    else:
        files = [find_in_package(first, positional[1])]
    return files, args


def interpret(files: list[str], args: dict[str, str], *, no_exec: bool, roscore: bool,
              keep_broken_tests: bool = False) -> Any:
    """The Interpreter after loading ``files`` (its ``plan()``, ``broken_tests``...)."""
    from orchestra.launch.interpreter import Interpreter, LoadOptions
    interp = Interpreter(LoadOptions(args=args, no_exec=no_exec, roscore=roscore,
                                     keep_broken_tests=keep_broken_tests))
    for path in files:
        if path == "-":
            from orchestra.launch.frontends import parse_string
            interp.load_entity(parse_string(sys.stdin.read(), "<stdin>"), "<stdin>")
        else:
            missing = not os.path.isfile(path)
            if missing:
                raise OrchestraError(f"launch file not found: {path}")
            interp.load_file(os.path.abspath(path))
    return interp


def find_node(plan: Any, name: str) -> Any:
    from orchestra.names import canonicalize, make_global_ns
    wanted = canonicalize(name if name.startswith("/") else make_global_ns(
        os.environ.get("ROS_NAMESPACE", "/")) + name)
    found = [n for n in (*plan.nodes, *plan.tests) if n.name and n.full_name == wanted]
    if not found:
        names = "".join(f"\n * {n.full_name}" for n in (*plan.nodes, *plan.tests) if n.name)
        raise OrchestraError(f"cannot find node named [{wanted}]. Node names are:{names}")
    if len(found) > 1:
        raise OrchestraError(f"multiple nodes named [{wanted}]")
    return found[0]


def undeclared_args(paths: list[str], args: dict[str, str]) -> list[str]:
    """Warnings for command-line ``name:=value`` args no launch file declares, each with a
    "did you mean". roslaunch ignores such an arg silently, so a typo (``drivr:=auto``)
    runs the launch with the default; the run is the same here, but the user is told."""
    from orchestra.launch.frontends import parse_file
    from orchestra.suggest import did_you_mean

    declared: set[str] = set()

    def collect(entity: Any) -> None:
        for child in entity.children:
            if child.tag == "arg" and "name" in child.attributes:
                declared.add(child.attributes["name"])
            elif child.tag not in ("include", "node", "test"):
                collect(child)       # <group>s: their args take command-line values too

    for path in paths:
        if path != "-" and os.path.isfile(path):
            collect(parse_file(path))
    return [f"warning: arg '{name}' is not declared by the launch file (roslaunch ignores it)"
            f"{did_you_mean(name, declared)}" for name in sorted(set(args) - declared)]


def ros_args_text(paths: list[str], args: dict[str, str]) -> str:
    from orchestra.launch.declared_args import declared_args
    from orchestra.launch.frontends import parse_file, parse_string
    declared = []
    for path in paths:
        if path == "-":
            declared += declared_args(parse_string(sys.stdin.read(), "<stdin>"), "<stdin>", args)
        else:
            declared += declared_args(parse_file(path), path, args)
    required = [a for a in declared if not a.default]
    optional = [a for a in declared if a.default]
    if not required and not optional:
        return "No arguments."
    lines = []
    if required:
        lines.append("Required Arguments:")
        lines += [f"  {a.name}: {a.doc or 'undocumented'}" for a in sorted(required,
                                                                            key=lambda a: a.name)]
    if optional:
        lines.append("Optional Arguments:")
        lines += [f"  {a.name} (default \"{a.default}\"): {a.doc or 'undocumented'}"
                  for a in sorted(optional, key=lambda a: a.name)]
    return "\n".join(lines)


def load_plan(files: list[str], args: dict[str, str], *, no_exec: bool = False,
              roscore: bool = True) -> Any:
    """The plan of ``files`` with ``args`` (roscore.xml's params first when ``roscore``)."""
    return interpret(files, args, no_exec=no_exec, roscore=roscore).plan()
