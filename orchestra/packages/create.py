"""``orchestra create-pkg``: a new catkin package, equal to what ``catkin_create_pkg`` makes.

"Equal" is checked by the tests against the real tool: the same file tree, a package.xml
(format 2) that parses to the same metadata and dependencies, and a CMakeLists.txt with the
same non-comment lines. The guidance comments are orchestra's own (jinja2 templates in
``templates/``). On top, ``--python-node`` adds a runnable node on orchestra's runtime and a
launch file starting it.

Pure planning (``plan_package``: arguments -> ``PackageSpec``, with catkin's rules for where
each dependency goes) is kept apart from rendering and from writing, which happens in a
temporary sibling directory renamed into place, so a failure never leaves half a package.
"""
from __future__ import annotations

import getpass
import os
import re
import shutil
import tempfile
from dataclasses import dataclass, field

import jinja2

from orchestra.errors import Location, OrchestraError
from orchestra.packages.manifest import Person

TEMPLATES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "templates")

#: catkin rejects other names; upper case and dashes are accepted with a warning
NAME_OK = re.compile(r"^[a-zA-Z0-9][a-zA-Z0-9_-]*$")
NAME_CONVENTION = re.compile(r"^[a-z][a-z0-9_-]*$")
VERSION_OK = re.compile(r"^[0-9]+\.[0-9]+\.[0-9]+$")
EMAIL_OK = re.compile(r"^[-a-zA-Z0-9_%+]+(\.[-a-zA-Z0-9_%+]+)*"
                      r"@[-a-zA-Z0-9%]+(\.[-a-zA-Z0-9%]+)*\.[a-zA-Z]{2,}$")
NODE_NAME_OK = re.compile(r"^[a-zA-Z][a-zA-Z0-9_]*$")


class InvalidPackageRequest(OrchestraError):
    """Arguments that cannot make a valid package (bad name, version, target exists...)."""


@dataclass(frozen=True)
class PackageRequest:
    """The command-line arguments, as catkin_create_pkg takes them."""

    name: str
    dependencies: tuple[str, ...] = ()
    sys_deps: tuple[str, ...] = ()
    boost_comps: tuple[str, ...] = ()
    version: str | None = None
    description: str | None = None
    licenses: tuple[str, ...] = ()
    authors: tuple[str, ...] = ()
    maintainers: tuple[str, ...] = ()
    rosdistro: str | None = None
    meta: bool = False
    python_node: str | None = None


@dataclass(frozen=True)
class PackageSpec:
    """Everything the templates need, already sorted and classified."""

    name: str
    version: str
    description: str
    maintainers: tuple[Person, ...]
    authors: tuple[Person, ...]
    licenses: tuple[str, ...]
    catkin_deps: tuple[str, ...]  # CMake find_package COMPONENTS (sorted)
    system_deps: tuple[str, ...]  # in the order given, boost appended when components asked
    boost_comps: tuple[str, ...]
    buildtool_depends: tuple[str, ...]
    build_depends: tuple[str, ...]
    build_export_depends: tuple[str, ...]
    exec_depends: tuple[str, ...]
    meta: bool = False
    python_node: str | None = None
    warnings: tuple[str, ...] = field(default=(), compare=False)

    @property
    def message_packages(self) -> list[str]:
        return [dep for dep in self.catkin_deps if dep.endswith("_msgs")]

    def dependency_tags(self) -> list[tuple[str, tuple[str, ...]]]:
        return [("buildtool_depend", self.buildtool_depends), ("build_depend", self.build_depends),
                ("build_export_depend", self.build_export_depends),
                ("exec_depend", self.exec_depends)]

    @property
    def makes_src(self) -> bool:
        return "roscpp" in self.catkin_deps or "rospy" in self.catkin_deps

    @property
    def makes_include(self) -> bool:
        return "roscpp" in self.catkin_deps


def _fail(message: str, where: str | None = None) -> InvalidPackageRequest:
    return InvalidPackageRequest(message, Location(where) if where else None)


def _default_user() -> str:
    try:
        return getpass.getuser()
    except Exception:  # no login name and no password entry (containers)
        return "user"


def plan_package(request: PackageRequest) -> PackageSpec:
    """Apply catkin_create_pkg's rules to the arguments; raise on what catkin would reject.

    Where dependencies go: a catkin dependency becomes build + build_export + exec
    (``<depend>``), except message_generation (build only), message_runtime (exec only) and
    genmsg (buildtool); a system dependency likewise, except ``python-*`` keys (exec only);
    boost components imply the ``boost`` system dependency.
    """
    warnings: list[str] = []
    name = request.name
    if not NAME_OK.match(name):
        raise _fail(f"invalid package name '{name}': it must start with a letter or digit and "
                    "contain only letters, digits, underscores and dashes")
    if not NAME_CONVENTION.match(name):
        warnings.append(f"package name '{name}' does not follow the naming conventions: it "
                        "should start with a lower case letter and contain only lower case "
                        "letters, digits, underscores and dashes")
    version = request.version or "0.0.0"
    if not VERSION_OK.match(version):
        raise _fail(f"invalid version '{version}': expected MAJOR.MINOR.PATCH such as 1.0.0")
    if request.python_node is not None and not NODE_NAME_OK.match(request.python_node):
        raise _fail(f"invalid node name '{request.python_node}': it must start with a letter "
                    "and contain only letters, digits and underscores")

    maintainers = []
    for maintainer in sorted(request.maintainers or (_default_user(),)):
        words = maintainer.split()
        if not words:
            raise _fail("a maintainer name must not be empty")
        email = f"{words[-1]}@todo.todo"
        if not EMAIL_OK.match(email):
            raise _fail(f"cannot make an email address for maintainer '{maintainer}' "
                        f"('{email}' is not valid): use a plain last name")
        maintainers.append(Person(maintainer, email))
    authors = tuple(Person(author) for author in sorted(request.authors))
    licenses = tuple(sorted(request.licenses or ("TODO",)))
    if any(not lic.strip() for lic in licenses):
        raise _fail("a license must not be empty")

    catkin_deps = sorted(dep for dep in request.dependencies if dep.lower() != "catkin")
    if name in catkin_deps or name in request.sys_deps:
        raise _fail(f"package '{name}' must not depend on itself")
    buildtool, build, exec_, both = ["catkin"], [], [], []
    for dep in catkin_deps:
        lowered = dep.lower()
        if lowered == "genmsg":
            warnings.append("packages with messages or services should depend on "
                            "message_generation and message_runtime, not genmsg")
            buildtool.append(dep)
        elif lowered == "message_generation":
            if "message_runtime" not in catkin_deps:
                warnings.append("packages with messages or services should depend on both "
                                "message_generation and message_runtime")
            build.append(dep)
        elif lowered == "message_runtime":
            if "message_generation" not in catkin_deps:
                warnings.append("packages with messages or services should depend on both "
                                "message_generation and message_runtime")
            exec_.append(dep)
        else:
            both.append(dep)
    system_deps = list(request.sys_deps)
    if request.boost_comps and "boost" not in system_deps:
        system_deps.append("boost")
    for dep in system_deps:
        (exec_ if dep.lower().startswith("python-") else both).append(dep)

    return PackageSpec(
        name=name, version=version,
        description=request.description or f"The {name} package",
        maintainers=tuple(maintainers), authors=authors, licenses=licenses,
        catkin_deps=tuple(catkin_deps), system_deps=tuple(system_deps),
        boost_comps=tuple(request.boost_comps),
        buildtool_depends=tuple(sorted(buildtool)),
        build_depends=tuple(sorted(build + both)),
        build_export_depends=tuple(sorted(both)),
        exec_depends=tuple(sorted(exec_ + both)),
        meta=request.meta, python_node=request.python_node, warnings=tuple(warnings))


def _environment(autoescape: bool) -> jinja2.Environment:
    return jinja2.Environment(loader=jinja2.FileSystemLoader(TEMPLATES), autoescape=autoescape,
                              trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
                              undefined=jinja2.StrictUndefined)


def render_package(spec: PackageSpec) -> tuple[dict[str, str], list[str]]:
    """The files (relative path -> text) and the extra empty directories of the package."""
    xml = _environment(autoescape=True)
    text = _environment(autoescape=False)
    cmake = "metapackage.CMakeLists.txt.j2" if spec.meta else "CMakeLists.txt.j2"
    files = {
        "package.xml": xml.get_template("package.xml.j2").render(spec=spec),
        "CMakeLists.txt": text.get_template(cmake).render(spec=spec),
    }
    dirs = []
    if spec.makes_include:
        dirs.append(os.path.join("include", spec.name))
    if spec.makes_src:
        dirs.append("src")
    if spec.python_node:
        files[os.path.join("scripts", spec.python_node)] = \
            text.get_template("node.py.j2").render(spec=spec)
        files[os.path.join("launch", f"{spec.name}.launch")] = \
            xml.get_template("node.launch.j2").render(spec=spec)
    return files, dirs


@dataclass(frozen=True)
class CreatedPackage:
    path: str
    files: tuple[str, ...]
    dirs: tuple[str, ...]
    warnings: tuple[str, ...]


def create_package(request: PackageRequest, parent: str) -> CreatedPackage:
    """Write the package into ``parent/<name>``; the directory must not exist yet."""
    spec = plan_package(request)
    target = os.path.join(os.path.abspath(parent), spec.name)
    if os.path.lexists(target):
        raise _fail(f"'{target}' already exists: choose another name or remove it first", target)
    if not os.path.isdir(parent):
        raise _fail(f"'{parent}' is not a directory", parent)
    files, dirs = render_package(spec)
    try:
        staging = tempfile.mkdtemp(prefix=f".{spec.name}-", dir=parent)
    except OSError as exc:
        raise _fail(f"cannot create the package here: {exc.strerror}", parent) from None
    try:
        os.chmod(staging, 0o777 & ~_umask())
        for relative, content in files.items():
            path = os.path.join(staging, relative)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "w", encoding="utf-8") as fh:
                fh.write(content)
            if relative.startswith("scripts" + os.sep):
                os.chmod(path, 0o777 & ~_umask())
        for relative in dirs:
            os.makedirs(os.path.join(staging, relative), exist_ok=True)
        os.rename(staging, target)  # one step: the package appears whole or not at all
    except OSError as exc:
        shutil.rmtree(staging, ignore_errors=True)
        raise _fail(f"cannot create the package: {exc.strerror or exc}", target) from None
    return CreatedPackage(target, tuple(files), tuple(dirs), spec.warnings)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
