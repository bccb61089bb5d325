"""Run-time side of ``orchestra launch`` and the ``orchestra status`` command.

``run_options`` is applied by ``orchestra.launch.cli.launch`` to add the run-time flags;
``run_plan(plan, options)`` runs a plan and returns the process exit code.
"""
from __future__ import annotations

from typing import Any, Callable

import click

from orchestra.errors import OrchestraError


def run_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator adding the run-time options of ``orchestra launch`` (none yet)."""
    return func


def run_plan(plan: Any, options: dict[str, Any]) -> int:
    """Run the plan's nodes under supervision; returns orchestra's exit code."""
    raise OrchestraError("running nodes is not available yet in this build; "
                         "use --dump-plan, --dump-params, --nodes, --args or --files")
