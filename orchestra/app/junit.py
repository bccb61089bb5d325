"""Test results as data: read a test's XML (JUnit, gtest, rosunit forms), write the combined
JUnit file, and the rostest-style summary.

Pure functions, no processes: ``testrun.py`` runs the tests and hands their outcomes here.
Results files are untrusted input (a test writes whatever it wants): parsed without DTDs,
entities or network, and a file that is not valid XML is an *error* verdict for its test
(rostest only warns and counts zero tests, so a crashed writer would pass).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from lxml import etree

PASSED, FAILURE, ERROR, SKIPPED = "passed", "failure", "error", "skipped"

_PARSER_OPTIONS = {"resolve_entities": False, "no_network": True, "load_dtd": False,
                   "huge_tree": False}
_MAX_TEXT = 16384     # per failure text kept in the combined file and the summary


@dataclass(frozen=True)
class CaseResult:
    """One test case: a method of a unittest, a gtest TEST, or a whole ``<test>``."""

    name: str
    classname: str
    verdict: str = PASSED
    message: str = ""
    text: str = ""
    time: float = 0.0


@dataclass
class TestOutcome:
    """What one ``<test>`` entry came to: its cases (from its results file, or one case
    made from what went wrong), plus what the runner saw (time-limit, missing file...)."""

    name: str
    cases: list[CaseResult] = field(default_factory=list)
    duration: float = 0.0
    results_file: str | None = None
    attempts: int = 1

    @property
    def verdict(self) -> str:
        verdicts = {case.verdict for case in self.cases}
        for worst in (ERROR, FAILURE):
            if worst in verdicts:
                return worst
        return PASSED

    @property
    def counts(self) -> tuple[int, int, int]:
        """(tests, failures, errors)."""
        return (len(self.cases), sum(c.verdict == FAILURE for c in self.cases),
                sum(c.verdict == ERROR for c in self.cases))


class ResultsError(ValueError):
    """The results file exists but cannot be read as test results."""


def _float(text: str | None) -> float:
    try:
        value = float(text or 0.0)
    except ValueError:
        return 0.0
    return value if math.isfinite(value) else 0.0


def _clip(text: str) -> str:
    return text if len(text) <= _MAX_TEXT else text[:_MAX_TEXT] + "\n... (clipped)"


def _case(element: etree._Element, suite_name: str) -> CaseResult:
    name = element.get("name") or "?"
    classname = element.get("classname") or suite_name
    time = _float(element.get("time"))
    for tag, verdict in (("error", ERROR), ("failure", FAILURE)):
        child = element.find(tag)
        if child is not None:
            return CaseResult(name, classname, verdict, _clip(child.get("message") or ""),
                              _clip(child.text or ""), time)
    if element.find("skipped") is not None or element.get("status") == "notrun" \
            or element.get("result") in ("skipped", "suppressed"):
        return CaseResult(name, classname, SKIPPED, time=time)
    return CaseResult(name, classname, PASSED, time=time)


def parse_results(data: bytes, default_name: str) -> list[CaseResult]:
    """The cases of a results document: ``<testsuites>``/``<testsuite>`` with ``<testcase>``
    children (JUnit, gtest, rosunit). A suite with counts but no cases (rostest's own
    failure files) gives that many synthetic cases. ResultsError when it is not such XML."""
    if not data.strip():
        raise ResultsError("the results file is empty")
    try:
        root = etree.fromstring(data, etree.XMLParser(**_PARSER_OPTIONS))
    except etree.XMLSyntaxError as exc:
        raise ResultsError(f"the results file is not valid XML: {exc}") from None
    if root.tag not in ("testsuite", "testsuites"):
        raise ResultsError(f"the results file's root is <{root.tag}>, not <testsuite> "
                           "or <testsuites>")
    suites = [root] if root.tag == "testsuite" else list(root.iter("testsuite"))
    cases: list[CaseResult] = []
    for suite in suites:
        suite_name = suite.get("name") or default_name
        own = [_case(case, suite_name) for case in suite.findall("testcase")]
        if own:
            cases += own
            continue
        failures = int(_float(suite.get("failures")))
        errors = int(_float(suite.get("errors")))
        total = max(int(_float(suite.get("tests"))), failures + errors)
        cases += [CaseResult(f"{suite_name}_{i}", suite_name,
                             ERROR if i < errors else FAILURE if i < errors + failures
                             else PASSED, "counted by the suite, no <testcase>")
                  for i in range(total)]
    return cases


def combined_xml(suite_name: str, outcomes: Sequence[TestOutcome]) -> bytes:
    """One JUnit document: a ``<testsuite>`` per ``<test>`` under ``<testsuites>``."""
    root = etree.Element("testsuites", name=suite_name)
    totals = [0, 0, 0]
    total_time = 0.0
    for outcome in outcomes:
        tests, failures, errors = outcome.counts
        totals = [totals[0] + tests, totals[1] + failures, totals[2] + errors]
        total_time += outcome.duration
        suite = etree.SubElement(root, "testsuite", name=outcome.name, tests=str(tests),
                                 failures=str(failures), errors=str(errors),
                                 skipped=str(sum(c.verdict == SKIPPED for c in outcome.cases)),
                                 time=f"{outcome.duration:.3f}")
        for case in outcome.cases:
            element = etree.SubElement(suite, "testcase", name=case.name,
                                       classname=case.classname, time=f"{case.time:.3f}")
            if case.verdict in (FAILURE, ERROR):
                child = etree.SubElement(element, case.verdict, message=_xml_safe(case.message),
                                         type="")
                child.text = _xml_safe(case.text or case.message)
            elif case.verdict == SKIPPED:
                etree.SubElement(element, "skipped")
    root.set("tests", str(totals[0]))
    root.set("failures", str(totals[1]))
    root.set("errors", str(totals[2]))
    root.set("time", f"{total_time:.3f}")
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)


def _xml_safe(text: str) -> str:
    """XML 1.0 cannot carry most control characters; a test's output may contain them."""
    return "".join(ch if ch in "\t\n\r" or ord(ch) >= 32 else "?" for ch in text)


def summary_lines(outcomes: Sequence[TestOutcome], colour: bool = False) -> list[str]:
    """rostest's summary: one block per case that did not pass, then the totals."""
    red, green, reset = ("\x1b[1;31m", "\x1b[32m", "\x1b[0m") if colour else ("", "", "")
    lines = ["[ROSTEST]" + "-" * 71, ""]
    for outcome in outcomes:
        for case in outcome.cases:
            label = f"[{outcome.name}.{case.name}]" if case.name != outcome.name \
                else f"[{outcome.name}]"
            if case.verdict in (PASSED, SKIPPED):
                lines.append(f"{label}[{case.verdict}]")
                continue
            head = f"{label}[{case.verdict.upper()}]"
            lines += [head + "-" * max(0, 80 - len(head)), case.text or case.message,
                      "-" * 80, ""]
    tests = sum(o.counts[0] for o in outcomes)
    failures = sum(o.counts[1] for o in outcomes)
    errors = sum(o.counts[2] for o in outcomes)
    ok = not failures and not errors
    lines += ["", "SUMMARY",
              f"{green} * RESULT: SUCCESS{reset}" if ok else f"{red} * RESULT: FAIL{reset}",
              f" * TESTS: {tests}",
              f"{red if errors else ''} * ERRORS: {errors}{reset if errors else ''}",
              f"{red if failures else ''} * FAILURES: {failures}{reset if failures else ''}"]
    bad = [o for o in outcomes if o.verdict != PASSED]
    if bad:
        lines += ["", "The following tests did not pass:"]
        lines += [f" * {o.name}: {o.verdict}" + (f" ({_first_line(o)})" if _first_line(o) else "")
                  for o in bad]
    return lines


def _first_line(outcome: TestOutcome) -> str:
    for case in outcome.cases:
        if case.verdict in (FAILURE, ERROR) and case.message:
            return case.message.splitlines()[0][:200]
    return ""
