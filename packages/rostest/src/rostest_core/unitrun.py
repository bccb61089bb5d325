"""Run one unittest TestCase class as a rostest test: results as JUnit XML where
``--gtest_output=xml:PATH`` says (what rostest and ``orchestra test`` pass), a text report
on stdout with ``--text`` or without a path; exit status 0 only when every case passed.
"""
from __future__ import annotations

import sys
import time
import traceback
import unittest
from xml.sax.saxutils import quoteattr

FLAG = "--gtest_output=xml:"


def results_path(argv: list[str]) -> str | None:
    """The path after ``--gtest_output=xml:``, None when not given."""
    for arg in argv:
        if arg.startswith(FLAG):
            return arg[len(FLAG):]
    return None


class _Recorder(unittest.TestResult):
    """Every case's verdict, message, traceback and time."""

    def __init__(self) -> None:
        super().__init__()
        self.cases: list[tuple[str, str, str, str, float]] = []
        self._started = 0.0

    def startTest(self, test: unittest.TestCase) -> None:
        super().startTest(test)
        self._started = time.monotonic()

    def _record(self, test: unittest.TestCase, verdict: str, err=None) -> None:
        message = text = ""
        if err is not None:
            message = str(err[1]).splitlines()[0] if str(err[1]) else err[0].__name__
            text = "".join(traceback.format_exception(*err))
        self.cases.append((test.id().split(".")[-1], verdict, message, text,
                           time.monotonic() - self._started))

    def addSuccess(self, test: unittest.TestCase) -> None:
        super().addSuccess(test)
        self._record(test, "passed")

    def addFailure(self, test: unittest.TestCase, err) -> None:
        super().addFailure(test, err)
        self._record(test, "failure", err)

    def addError(self, test: unittest.TestCase, err) -> None:
        super().addError(test, err)
        self._record(test, "error", err)

    def addSkip(self, test: unittest.TestCase, reason: str) -> None:
        super().addSkip(test, reason)
        self.cases.append((test.id().split(".")[-1], "skipped", reason, "", 0.0))


def junit_xml(suite: str, classname: str, cases) -> str:
    """A JUnit document for the recorded cases (rosunit's form)."""
    failures = sum(c[1] == "failure" for c in cases)
    errors = sum(c[1] == "error" for c in cases)
    total = sum(c[4] for c in cases)
    lines = ['<?xml version="1.0" encoding="utf-8"?>',
             f'<testsuite name={quoteattr(suite)} tests="{len(cases)}" errors="{errors}" '
             f'failures="{failures}" time="{total:.3f}">']
    for name, verdict, message, text, seconds in cases:
        head = (f'  <testcase classname={quoteattr(classname)} name={quoteattr(name)} '
                f'time="{seconds:.3f}"')
        if verdict == "passed":
            lines.append(head + "/>")
            continue
        if verdict == "skipped":
            lines += [head + ">", f"    <skipped message={quoteattr(message)}/>",
                      "  </testcase>"]
            continue
        body = text.replace("]]>", "]]]]><![CDATA[>")
        lines += [head + ">",
                  f'    <{verdict} type="" message={quoteattr(message)}><![CDATA[{body}]]>'
                  f"</{verdict}>",
                  "  </testcase>"]
    lines.append("</testsuite>")
    return "\n".join(lines) + "\n"


def run(package: str, name: str, case_class: type[unittest.TestCase],
        argv: list[str] | None = None) -> int:
    """Run ``case_class``'s tests; write the results; return the exit status."""
    argv = sys.argv if argv is None else argv
    suite = unittest.TestLoader().loadTestsFromTestCase(case_class)
    recorder = _Recorder()
    suite.run(recorder)
    path = results_path(argv)
    if path and "--text" not in argv:
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(junit_xml(name, f"{package}.{name}.{case_class.__name__}",
                               recorder.cases))
    for case_name, verdict, _message, text, _ in recorder.cases:
        print(f"[{package}.{name}/{case_name}][{verdict}]")
        if text:
            print(text, end="")
    return 0 if recorder.wasSuccessful() else 1
