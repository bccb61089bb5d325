"""Hostile ``$(eval)`` payloads through the real command line: refused, located, harmless.

Each payload is refused by ``orchestra check``, ``launch --dump-params``, ``launch --nodes``
and ``orchestra launch`` with exit 2 and ``file:line`` on stderr, and the one that tries to
run a shell command leaves no trace. The subprocess timeout is a hang guard, not a timing.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from xml.sax.saxutils import quoteattr

import pytest

HANG_GUARD = 60


def _escape(marker: Path) -> str:
    # walks a generator's frame to the module globals of the caller, then to os.system
    return ("[g for g in [(x for x in [1])]][0].gi_frame.f_back.f_back.f_globals['os']"
            f".system('touch {marker}')")


PAYLOADS = {
    "frame-escape": _escape,
    "class-walk": lambda marker: "().__class__.__bases__[0]",
    "lambda": lambda marker: "(lambda: 1)()",
    "generator": lambda marker: f"(x for x in [1]).gi_frame.f_globals['os'].system('touch {marker}')",
    "pow": lambda marker: "pow(9, 9**9)",
    "str-repeat": lambda marker: "'a'*10**10",
    "list-repeat": lambda marker: "[1]*10**9",
    "sum-range": lambda marker: "sum(range(10**11))",
    "shift-str": lambda marker: "1<<20000",
}

COMMANDS = {
    "check": ("check",),
    "dump-params": ("launch", "--dump-params"),
    "nodes": ("launch", "--nodes"),
    "launch": ("launch",),
}


def _env(tmp_path: Path) -> dict[str, str]:
    return {"PATH": os.environ["PATH"], "ROS_PACKAGE_PATH": str(tmp_path),
            "ROS_HOME": str(tmp_path / ".ros"), "PYTHONPATH": os.environ.get("PYTHONPATH", "")}


def _launch_file(tmp_path: Path, payload: str) -> Path:
    path = tmp_path / "hostile.launch"
    path.write_text('<launch>\n  <node pkg="none" type="none" name="n"/>\n'
                    f'  <param name="p" value={quoteattr(f"$(eval {payload})")}/>\n'
                    '</launch>\n')
    return path


@pytest.mark.timeout(300)
@pytest.mark.parametrize("name", sorted(PAYLOADS))
def test_hostile_eval_is_refused_with_location_and_no_side_effect(tmp_path, name):
    marker = tmp_path / "pwned"
    path = _launch_file(tmp_path, PAYLOADS[name](marker))
    procs = {cmd: subprocess.Popen([sys.executable, "-m", "orchestra", *words, str(path)],
                                   env=_env(tmp_path), stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True, cwd=tmp_path)
             for cmd, words in COMMANDS.items()}
    for cmd, proc in procs.items():
        out, err = proc.communicate(timeout=HANG_GUARD)
        assert proc.returncode == 2, (cmd, out, err)
        assert f"{path}:3" in out + err, (cmd, out, err)
        assert "$(eval" in out + err, (cmd, out, err)
        assert "Traceback" not in err, (cmd, err)
    assert not marker.exists()
