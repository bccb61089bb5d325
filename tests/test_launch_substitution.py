"""$(...) substitution args: roslaunch's order, errors and the $(eval) sandbox."""
from dataclasses import dataclass, field

import pytest

from orchestra.launch.substitution import ArgNotSet, SubstitutionError, collect, resolve


@dataclass
class Scope:
    args: dict = field(default_factory=dict)
    filename: str | None = "/pkgs/demo/launch/x.launch"


def test_text_without_dollar_is_returned_untouched():
    assert resolve("plain (text)", Scope()) == "plain (text)"
    assert resolve(None, Scope()) is None


def test_arg_env_and_optenv_are_replaced(monkeypatch):
    monkeypatch.setenv("ROBOT", "pr2")
    monkeypatch.delenv("MISSING", raising=False)
    got = resolve("$(arg a)-$(env ROBOT)-$(optenv MISSING def  ault)", Scope({"a": "1"}))
    assert got == "1-pr2-def ault"


def test_env_of_unset_variable_is_an_error(monkeypatch):
    monkeypatch.delenv("NOPE_NOT_SET", raising=False)
    with pytest.raises(SubstitutionError, match="NOPE_NOT_SET"):
        resolve("$(env NOPE_NOT_SET)", Scope())


def test_undeclared_arg_raises_arg_not_set_naming_it():
    with pytest.raises(ArgNotSet) as info:
        resolve("x $(arg ghost)", Scope())
    assert info.value.name == "ghost"


def test_find_runs_after_args_so_the_path_can_come_from_an_arg(monkeypatch):
    import orchestra.launch.substitution as sub
    monkeypatch.setattr(sub, "_find_package", lambda name: f"/ws/{name}")
    got = resolve("$(find demo)/$(arg f) tail", Scope({"f": "launch/a.launch"}))
    assert got == "/ws/demo/launch/a.launch tail"
    assert resolve("$(find demo)/", Scope()) == "/ws/demo"


def test_dollar_inside_a_substitution_is_an_error():
    with pytest.raises(SubstitutionError):
        collect("$(arg $(arg x))")


def test_unknown_command_is_an_error():
    with pytest.raises(SubstitutionError, match="unknown substitution"):
        resolve("$(bogus x)", Scope())


def test_anon_is_the_same_for_the_same_id():
    first = resolve("$(anon n)", Scope())
    assert resolve("$(anon n) $(anon n)", Scope()) == f"{first} {first}"


def test_dirname_is_the_directory_of_the_current_file():
    assert resolve("$(dirname)/x", Scope()) == "/pkgs/demo/launch/x"


def test_eval_sees_typed_args_and_arg_function():
    scope = Scope({"flag": "false", "n": "3"})
    assert resolve("$(eval not arg('flag'))", scope) == "True"
    assert resolve("$(eval n * 2 + len('ab'))", scope) == "8"
    assert resolve("$(eval optenv('NOPE_NOT_SET', 'd').upper())", scope) == "D"


@pytest.mark.parametrize("expr", [
    "__import__('os').system('true')",
    "open('/etc/passwd').read()",
    "().__class__.__bases__",
    "(lambda: 1)()",
    "getattr(1, 'real')",
    "'{0.__class__}'.format(1)",
    "arg('x')._secret",
])
def test_eval_sandbox_refuses_escapes(expr):
    with pytest.raises(SubstitutionError):
        resolve(f"$(eval {expr})", Scope({"x": "1"}))


def test_eval_only_applies_to_a_whole_value():
    with pytest.raises(SubstitutionError):
        resolve("x $(eval 1 + 1)", Scope())


def test_eval_refuses_runaway_exponents():
    with pytest.raises(SubstitutionError, match="bits"):
        resolve("$(eval 10**10**10)", Scope())
    assert resolve("$(eval 2**10)", Scope()) == "1024"
