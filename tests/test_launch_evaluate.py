"""The ``$(eval)`` interpreter: roslaunch's results for the grammar launch files use, and a
refusal (never a hang, never Python's eval) for everything else."""
from __future__ import annotations

import json
import os
import subprocess

import pytest

from orchestra.launch import evaluate as ev
from orchestra.launch.evaluate import EvalError, problem

ARGS = {"flag": "false", "n": "3", "name": "abc", "ratio": "0.5", "on": "True", "empty": ""}

# what real launch files (the compat corpus, roslaunch's fixtures) and common idioms write
ALLOWED = [
    "1 == 1", "0 > 1", "not arg('flag')", "arg('flag') or arg('on')", "n * 2 + len('ab')",
    "arg('name') == 'abc'", "arg('name') not in ['ompl', 'chomp']", "empty == ''",
    "'' if arg('flag') else '-unpause'", "on and (40+2) == 42", "flag or (40-2) != 38",
    "optenv('NOPE_NOT_SET', 'unknown').lower().startswith('windows')",
    "optenv('NOPE_NOT_SET', 'x' + '/config/empty.yaml')", "ratio * 4", "n / 2", "n // 2",
    "n % 2", "2**10", "-n", "abs(-n)", "int('7') + float('0.5')", "str(n) + 'x'",
    "list(map(int, '1 2 3'.split()))", "dict(a=1)['a']", "name[1:]", "name[::-1]",
    "[1, 2, 3][n - 1]", "max(1, n)", "min([4, 2])", "sum([1, 2])", "pi / 2", "radians(180)",
    "sqrt(16)", "pow(2, 10)", "floor(2.5)", "round(2.567, 2)", "'%s-%d' % ('a', n)",
    "name.upper().replace('B', 'x')", "','.join(['a', 'b'])", "len(name) > 2 and name != ''",
    "1 < n <= 3", "true != false", "True is not False", "sorted([3, 1, 2])",
    "tuple([1, 2])", "{'k': n}", "{1, 2} == {2, 1}", "list(range(3))",
]


class _Scope:
    def __init__(self, args):
        self.args = args
        self.filename = "/pkgs/demo/launch/x.launch"


def ours(expr: str, args=ARGS) -> str:
    from orchestra.launch.substitution import resolve
    return resolve(f"$(eval {expr})", _Scope(args))


_ROSLAUNCH = """
import json, sys
from roslaunch.substitution_args import resolve_args
args, exprs = json.loads(sys.stdin.read())
out = []
for e in exprs:
    try:
        out.append(resolve_args('$(eval %s)' % e, context={'arg': args}))
    except Exception as exc:
        out.append('ERROR')
print(json.dumps(out))
"""


def test_allowed_grammar_gives_roslaunchs_results():
    """The same text as the real roslaunch for every form launch files use."""
    if not os.path.exists("/usr/lib/python3/dist-packages/roslaunch/substitution_args.py"):
        pytest.skip("the real roslaunch (python3-roslaunch) is not installed")
    env = {"PATH": os.environ["PATH"], "PYTHONPATH": "/usr/lib/python3/dist-packages"}
    proc = subprocess.run(["/usr/bin/python3", "-c", _ROSLAUNCH], env=env, text=True,
                          input=json.dumps([ARGS, ALLOWED]), capture_output=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    theirs = json.loads(proc.stdout)
    for expr, expected in zip(ALLOWED, theirs, strict=True):
        assert expected != "ERROR", expr
        assert ours(expr) == expected, expr


@pytest.mark.parametrize("expr, why", [
    ("(x for x in [1]).gi_frame.f_back.f_globals", "attribute access"),
    ("[g for g in [1]]", "comprehensions"),
    ("{k: 1 for k in 'ab'}", "comprehensions"),
    ("(lambda: 1)()", "lambda"),
    ("(y := 1)", "assignments"),
    ("().__class__", "double underscores"),
    ("n.real", "attribute access"),
    ("'{0}'.format(1)", "'format' is not an allowed str method"),
    ("open('/etc/passwd')", "name 'open' is not defined"),
    ("getattr(1, 'real')", "name 'getattr' is not defined"),
    ("[*name]", "unpacking"),
    ("b'x'", "bytes literals"),
    ("float", "the function float, not data"),
])
def test_grammar_outside_the_whitelist_is_refused_with_the_reason(expr, why):
    with pytest.raises(Exception) as info:
        ours(expr)
    assert why in str(info.value)
    assert f"$(eval {expr})" in str(info.value)


@pytest.mark.parametrize("expr, why", [
    ("pow(9, 9**9)", "OverflowError"),
    ("9**9**9", "bits"),
    ("1<<20000", "bits"),
    ("int('1' * 4000)", "bits"),
    ("factorial(10**6)", "bits"),
    ("'a'*10**10", "longer than"),
    ("[1]*10**9", "longer than"),
    ("sum(range(10**11))", "longer than"),
    ("'x'.center(10**10)", "longer than"),
    ("('a'*1000).replace('', 'b'*1000)", "longer than"),
    ("','.join(['a'*100000]*100)", "longer than"),
    ("'%1000000000d' % 1", "width"),
    ("f'{1:1000000000}'", "width"),
    ("[[1]*1000]*1000", "steps"),
    ("sum([[1]]*100000, [])", "steps"),
    ("round(10**1000, -10**9)", "1000 digits"),
    ("-" * 150 + "1", "nested more than"),
    ("x" * (ev.MAX_EXPRESSION + 1), "longer than"),
])
def test_runaway_computations_are_refused_before_they_run(expr, why):
    from orchestra.launch.substitution import SubstitutionError
    with pytest.raises(SubstitutionError, match=why):
        ours(expr)


def test_the_frame_walk_payload_runs_nothing(tmp_path):
    marker = tmp_path / "pwned"
    expr = ("[g for g in [(x for x in [1])]][0].gi_frame.f_back.f_back.f_globals['os']"
            f".system('touch {marker}')")
    with pytest.raises(Exception, match="is not an allowed str method"):
        ours(expr)
    assert not marker.exists()


def test_unset_arg_inside_eval_names_the_arg():
    from orchestra.launch.substitution import ArgNotSet
    with pytest.raises(ArgNotSet) as info:
        ours("arg('ghost') + 1")
    assert info.value.name == "ghost"


def test_long_expressions_are_clipped_in_the_message():
    with pytest.raises(Exception) as info:
        ours("'" + "a" * 10_000 + "'.format()")
    assert "(10011 chars)" in str(info.value) and len(str(info.value)) < 1000


def test_static_problem_reports_refused_grammar_without_evaluating():
    assert problem("arg('x') == 1") is None
    assert problem("'a' * 10**10") is None  # sizes are evaluation's business
    assert "lambda" in (problem("(lambda: 1)()") or "")
    assert "not a valid expression" in (problem("1 +") or "")


def test_names_are_exported_once_with_roslaunchs_functions():
    assert {"arg", "env", "optenv", "find", "anon", "dirname", "true", "false", "pi",
            "map", "str"} <= ev.NAMES
    assert not {"open", "getattr", "eval", "exec", "type", "__import__"} & ev.NAMES


def test_eval_error_is_an_orchestra_error():
    with pytest.raises(EvalError):
        ev.evaluate("1/0", {}, {name: (lambda *a: None) for name in ev.LAUNCH_FUNCTIONS},
                    str)


def test_an_eval_syntax_error_names_its_column_as_bag_filter_does():
    assert (problem("1 + ) 2") or "").endswith("at column 5")
    assert (problem("1 +") or "").endswith("at the end (column 4)")
