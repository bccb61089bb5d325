"""Fuzzing what a stranger can hand orchestra: launch files (XML and YAML), ``$(eval)``
expressions, rosparam YAML and XML-RPC bodies sent to the master.

Every input must end in a result or a user error (``OrchestraError``) that names a file and a
line; never another exception (a traceback for the user), never a hang (the pytest timeout is
the guard; no timing is asserted). Runs a few dozen examples per target by default;
``ORCHESTRA_FUZZ_EXAMPLES=N`` runs N per target (a long run), and
``ORCHESTRA_FUZZ_REPORT=path`` appends per target the inputs tried and their outcomes (ok,
located error, error without a location, traceback) and the slowest input in ms to ``path``.
"""
from __future__ import annotations

import http.client
import json
import os
import tempfile
import time
import xmlrpc.client
from collections import Counter
from pathlib import Path
from urllib.parse import urlsplit
from xml.sax.saxutils import quoteattr

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from orchestra.errors import OrchestraError
from orchestra.launch import evaluate as ev
from orchestra.launch.interpreter import load_launch
from orchestra.params.yaml import load_rosparam_yaml

pytestmark = [pytest.mark.fuzz, pytest.mark.timeout(900),
              # Hypothesis misreads the recursive strategies below as not recursing
              pytest.mark.filterwarnings("ignore::hypothesis.errors.HypothesisDeprecationWarning")]

EXAMPLES = int(os.environ.get("ORCHESTRA_FUZZ_EXAMPLES", "25"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, database=None,
                suppress_health_check=list(HealthCheck))

STATS: dict[str, Counter] = {}


def _count(target: str, outcome: str, seconds: float) -> None:
    stats = STATS.setdefault(target, Counter())
    stats["inputs"] += 1
    stats[outcome] += 1
    stats["max_ms"] = max(stats["max_ms"], int(seconds * 1000))


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    path = os.environ.get("ORCHESTRA_FUZZ_REPORT")
    if path:
        with open(path, "a") as fh:
            fh.write(json.dumps({k: dict(v) for k, v in STATS.items()}) + "\n")


@pytest.fixture(scope="module")
def workdir():
    """A scratch directory, an empty package path and no ROS environment to lean on."""
    saved = {k: os.environ.get(k) for k in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH")}
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "pkgs").mkdir()
        os.environ["ROS_PACKAGE_PATH"] = str(Path(tmp) / "pkgs")
        os.environ.pop("CMAKE_PREFIX_PATH", None)
        yield Path(tmp)
    for key, value in saved.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value


def _load(target: str, path: Path) -> None:
    """Interpret ``path``; the only acceptable failure is a located OrchestraError."""
    start = time.monotonic()
    try:
        load_launch(str(path), {"a": "1"}, no_exec=True)
        outcome = "ok"
    except OrchestraError as exc:
        outcome = "located_error"
        located = exc.location is not None and exc.location.line is not None
        if not located:
            _count(target, "error_without_location", time.monotonic() - start)
        assert located, f"error without a line: {exc}"
    except Exception:
        _count(target, "traceback", time.monotonic() - start)
        raise
    _count(target, outcome, time.monotonic() - start)


# ------------------------------------------------------------------------ $(eval) grammar

_NAMES = sorted(ev.NAMES) + ["a", "x", "os", "open", "getattr", "type", "self"]
_ATTRS = sorted(ev.STR_METHODS) + ["gi_frame", "f_back", "f_globals", "format", "real",
                                   "_x", "mro", "system"]

_atoms = st.one_of(
    st.integers(-10**6, 10**6).map(str), st.sampled_from(["10**10", "9**9", "1<<64", "1e308"]),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.text(max_size=8).map(repr), st.sampled_from(["a", "x", "flag", "true", "pi", "None"]),
    st.sampled_from(["[]", "()", "{}", "[1, 2]", "'a'", "''", "None", "True", "'a b c'"]),
    st.sampled_from(["arg('a')", "arg('x')", "optenv('NOPE', 'd')", "dirname()",
                     "arg('missing')", "env('NOPE_UNSET')", "find('nopkg')"]),
)
# calls the way launch files write them: a known function with one or two arguments
_FUNCTIONS_1 = ["len", "str", "int", "float", "abs", "bool", "list", "tuple", "sorted", "sum",
                "max", "min", "range", "round", "sqrt", "radians", "floor", "repr", "set",
                "reversed", "enumerate", "any", "all", "factorial", "hex", "chr", "ord"]
_FUNCTIONS_2 = ["max", "min", "pow", "round", "range", "divmod", "atan2", "map", "zip",
                "filter", "optenv", "comb", "isclose", "hypot"]
_METHODS = sorted(ev.STR_METHODS)


def _compound(inner):
    return st.one_of(
        st.tuples(st.sampled_from(_FUNCTIONS_1), inner).map(lambda t: f"{t[0]}({t[1]})"),
        st.tuples(st.sampled_from(_FUNCTIONS_2), inner, inner)
        .map(lambda t: f"{t[0]}({t[1]}, {t[2]})"),
        st.tuples(st.sampled_from(["str", "int", "float"]), st.sampled_from(_FUNCTIONS_2),
                  inner).map(lambda t: f"list(map({t[0]}, {t[2]}))"),
        st.tuples(inner, st.sampled_from(_METHODS), st.lists(inner, max_size=2))
        .map(lambda t: f"str({t[0]}).{t[1]}({', '.join(t[2])})"),
        st.tuples(inner, st.sampled_from(["+", "-", "*", "/", "//", "%", "**", "<<", ">>",
                                          "&", "|", "^", "==", "<", " in ", " and ", " or ",
                                          " if True else ", " is "]), inner)
        .map(lambda t: f"({t[0]}{t[1]}{t[2]})"),
        st.tuples(st.sampled_from(["-", "not ", "~"]), inner).map(lambda t: t[0] + t[1]),
        st.tuples(st.sampled_from(_NAMES), st.lists(inner, max_size=3))
        .map(lambda t: f"{t[0]}({', '.join(t[1])})"),
        st.tuples(inner, st.sampled_from(_ATTRS), st.lists(inner, max_size=2))
        .map(lambda t: f"{t[0]}.{t[1]}({', '.join(t[2])})"),
        st.tuples(inner, st.sampled_from(_ATTRS)).map(lambda t: f"{t[0]}.{t[1]}"),
        st.tuples(inner, inner).map(lambda t: f"{t[0]}[{t[1]}]"),
        st.tuples(inner, inner, inner).map(lambda t: f"{t[0]}[{t[1]}:{t[2]}]"),
        st.lists(inner, max_size=3).map(lambda xs: f"[{', '.join(xs)}]"),
        st.sampled_from(["a", "x", "flag", "pi"]).map(lambda x: f"f'<{{{x}}}>'"),
    )


_TREES = st.recursive(_atoms, _compound, max_leaves=12)
# mostly grammar the evaluator accepts (so its runtime is exercised), some of it wrapped in
# what it must refuse, and raw text
EXPRESSIONS = st.one_of(
    _TREES, _TREES,
    _TREES.map(lambda x: f"[g for g in {x}]"), _TREES.map(lambda x: f"(lambda: {x})()"),
    _TREES.map(lambda x: f"(g for g in [{x}]).gi_frame.f_back"),
    st.text(max_size=40))


class _Scope:
    args = {"a": "1", "x": "abc", "flag": "true"}
    filename = "/nowhere/x.launch"


@FUZZ
@given(EXPRESSIONS)
def test_eval_never_escapes_hangs_or_raises_anything_but_a_user_error(expr):
    from orchestra.launch.substitution import resolve

    start = time.monotonic()
    try:
        resolve(f"$(eval {expr})", _Scope())
        outcome = "ok"
    except OrchestraError:
        outcome = "refused"
    except Exception:
        _count("eval", "traceback", time.monotonic() - start)
        raise
    _count("eval", outcome, time.monotonic() - start)


@FUZZ
@given(EXPRESSIONS)
def test_eval_errors_in_a_launch_file_name_the_line(workdir, expr):
    path = workdir / "eval.launch"
    path.write_text(f'<launch>\n  <arg name="a" default="1"/>\n'
                    f'  <param name="p" value={quoteattr(f"$(eval {expr})")}/>\n</launch>\n')
    _load("eval-in-launch", path)


# ------------------------------------------------------------------------ XML front end

_TAGS = ["launch", "node", "param", "rosparam", "arg", "group", "include", "remap", "env",
         "machine", "test", "master", "bogus"]
_ATTRIBUTES = ["name", "pkg", "type", "value", "default", "ns", "if", "unless", "file",
               "command", "output", "respawn", "respawn_delay", "required", "args", "from",
               "to", "textfile", "binfile", "subst_value", "clear_params", "pass_all_args",
               "machine", "address", "cwd", "launch-prefix", "time-limit", "retry", "doc"]
_VALUES = st.one_of(
    st.text(max_size=20),
    st.sampled_from(["true", "false", "1", "0", "screen", "log", "both", "yaml", "$(arg a)",
                     "$(arg missing)", "$(dirname)", "$(anon n)", "$(optenv X d)",
                     "$(env NOPE_UNSET)", "$(find nopkg)", "$(bogus)", "$(arg $(arg a))",
                     "~priv", "/abs/ns", "a/b", "", "load", "dump", "delete", "1e5",
                     "x.yaml", "$(dirname)/eval.launch"]),
    EXPRESSIONS.map(lambda e: f"$(eval {e})"),
)

_element = st.recursive(
    st.tuples(st.sampled_from(_TAGS), st.dictionaries(st.sampled_from(_ATTRIBUTES), _VALUES,
                                                      max_size=5), st.just([]),
              st.one_of(st.none(), st.text(max_size=30))),
    lambda inner: st.tuples(st.sampled_from(_TAGS),
                            st.dictionaries(st.sampled_from(_ATTRIBUTES), _VALUES, max_size=5),
                            st.lists(inner, max_size=4), st.none()),
    max_leaves=15)


def _xml(element, indent: int = 0) -> str:
    tag, attributes, children, text = element
    attrs = "".join(f" {k}={quoteattr(v)}" for k, v in attributes.items())
    pad = "  " * indent
    if not children and text is None:
        return f"{pad}<{tag}{attrs}/>\n"
    from xml.sax.saxutils import escape
    body = escape(text) if text is not None else "\n" + "".join(
        _xml(child, indent + 1) for child in children) + pad
    return f"{pad}<{tag}{attrs}>{body}</{tag}>\n"


def _mutate(data: bytes, edits: list[tuple[int, int, bytes]]) -> bytes:
    for position, delete, insert in edits:
        at = position % (len(data) + 1)
        data = data[:at] + insert + data[at + delete:]
    return data


_EDITS = st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 4),
                            st.binary(max_size=4) | st.sampled_from(
                                [b"\x00", b"\xff", b"\x01", b"<", b">", b"&", b'"', b"$(",
                                 b"\n", b"]]>", b"<!ENTITY x 'y'>", b"&x;"])),
                  max_size=4)


@FUZZ
@given(st.lists(_element, max_size=6), _EDITS)
def test_xml_launch_files_load_or_fail_with_a_line(workdir, children, edits):
    text = _xml(("launch", {}, children, None)) if children else "<launch/>\n"
    path = workdir / "fuzz.launch"
    path.write_bytes(_mutate(text.encode(), edits))
    _load("xml", path)


# ------------------------------------------------------------------------ YAML front end

def _yaml_doc(element):
    tag, attributes, children, text = element
    body: dict = dict(attributes)
    if children:
        body["children"] = [_yaml_doc(child) for child in children]
    if text is not None:
        body["text"] = text
    return {tag: body}


@FUZZ
@given(st.lists(_element, max_size=6), _EDITS)
def test_yaml_launch_files_load_or_fail_with_a_line(workdir, children, edits):
    doc = {"launch": [_yaml_doc(child) for child in children]}
    text = yaml.safe_dump(doc, allow_unicode=True, sort_keys=False)
    path = workdir / "fuzz.launch.yaml"
    path.write_bytes(_mutate(text.encode(), edits))
    _load("yaml", path)


_YAML_VALUES = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=10)),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=5), inner,
                                                                max_size=4),
    max_leaves=20)


@FUZZ
@given(_YAML_VALUES, _EDITS)
def test_rosparam_yaml_loads_or_fails_with_a_line(value, edits):
    text = yaml.safe_dump({"root": value}, allow_unicode=True)
    data = _mutate(text.encode(), edits).decode("utf-8", "replace")
    start = time.monotonic()
    try:
        load_rosparam_yaml(data, "p.yaml")
        outcome = "ok"
    except OrchestraError as exc:
        outcome = "located_error"
        if exc.location is None or exc.location.line is None:
            _count("rosparam-yaml", "error_without_location", time.monotonic() - start)
            raise AssertionError(f"error without a line: {exc}") from None
    except Exception:
        _count("rosparam-yaml", "traceback", time.monotonic() - start)
        raise
    _count("rosparam-yaml", outcome, time.monotonic() - start)


# ------------------------------------------------------------------------ master XML-RPC

@pytest.fixture(scope="module")
def master_uri():
    from orchestra.master import start_master

    handle = start_master(host="127.0.0.1", port=0)
    yield handle.uri
    handle.shutdown()


_PARAMS = st.recursive(
    st.one_of(st.integers(-2**31, 2**31 - 1).map(lambda i: f"<int>{i}</int>"),
              st.text(max_size=10).map(lambda s: f"<string>{s}</string>"),
              st.sampled_from(["<boolean>1</boolean>", "<double>1e400</double>", "<nil/>",
                               "<i8>99999999999999999999999</i8>", "<int>x</int>",
                               "<base64>!!!</base64>", "<dateTime.iso8601>x</dateTime.iso8601>",
                               "<struct><member><name>a</name></member></struct>", "<bogus/>",
                               "plain"])),
    lambda inner: st.lists(inner, max_size=3).map(
        lambda xs: "<array><data>" + "".join(f"<value>{x}</value>" for x in xs)
        + "</data></array>"),
    max_leaves=10)

_RPC_METHODS = ["getPid", "getUri", "getParam", "setParam", "hasParam", "deleteParam",
            "searchParam", "getParamNames", "registerPublisher", "registerSubscriber",
            "unregisterPublisher", "lookupNode", "getSystemState", "getTopicTypes",
            "getPublishedTopics", "subscribeParam", "lookupService", "registerService",
            "system.multicall", "shutdown_not", "__init__", ""]


@FUZZ
@given(st.sampled_from(_RPC_METHODS), st.lists(_PARAMS, max_size=4), _EDITS)
def test_master_answers_malformed_xmlrpc_bodies_and_keeps_serving(master_uri, capfd, method,
                                                                  params, edits):
    body = ("<?xml version='1.0'?><methodCall><methodName>" + method + "</methodName><params>"
            + "".join(f"<param><value>{p}</value></param>" for p in params)
            + "</params></methodCall>").encode()
    body = _mutate(body, edits)
    where = urlsplit(master_uri)
    start = time.monotonic()
    conn = http.client.HTTPConnection(where.hostname, where.port, timeout=60)
    try:
        conn.request("POST", "/RPC2", body, {"Content-Type": "text/xml"})
        response = conn.getresponse()
        answer = response.read()
    finally:
        conn.close()
    ok = response.status in (200, 400, 411, 413, 414, 500, 501) and b"Traceback" not in answer
    if not ok:
        _count("master-xmlrpc", "traceback", time.monotonic() - start)
    assert ok, (response.status, answer[:500])
    # still serving, and nothing dumped on the console by the server thread
    with xmlrpc.client.ServerProxy(master_uri) as proxy:
        code, _, pid = proxy.getPid("/fuzz")
    assert code == 1 and pid == os.getpid()
    printed = capfd.readouterr().err
    if "Traceback" in printed:
        _count("master-xmlrpc", "traceback", time.monotonic() - start)
    assert "Traceback" not in printed, printed[-2000:]
    _count("master-xmlrpc", "answered", time.monotonic() - start)
