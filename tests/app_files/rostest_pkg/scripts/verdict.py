#!/usr/bin/env python3
"""A rostest test program without ROS: ``verdict.py pass|fail|hang|flaky``.

One unittest case that passes, fails, never ends, or (flaky) fails on its first run in this
working directory and passes afterwards; its JUnit results go where
``--gtest_output=xml:PATH`` says, as rosunit writes them. Standard library only, so Debian's
rostest and ``orchestra test`` run the very same program.
"""
import os
import sys
import time
import unittest
from xml.sax.saxutils import quoteattr

MODE = next((a for a in sys.argv[1:] if a in ("pass", "fail", "hang", "flaky")), "pass")
if MODE == "flaky":
    MODE = "pass" if os.path.exists("flaky.ran") else "fail"
    open("flaky.ran", "w").close()
FLAG = "--gtest_output=xml:"


class Verdict(unittest.TestCase):
    def test_verdict(self):
        if MODE == "hang":
            time.sleep(3600)
        self.assertEqual(MODE, "pass", "this test was asked to fail")


result = unittest.TestResult()
unittest.TestLoader().loadTestsFromTestCase(Verdict).run(result)
path = next((a[len(FLAG):] for a in sys.argv if a.startswith(FLAG)), None)
if path:
    failure = "".join(
        f'<failure type="" message={quoteattr(str(err).splitlines()[-1])}/>'
        for _case, err in result.failures + result.errors)
    with open(path, "w") as fh:
        fh.write('<?xml version="1.0" encoding="utf-8"?>\n'
                 f'<testsuite name="verdict" tests="1" failures="{len(result.failures)}" '
                 f'errors="{len(result.errors)}" time="0.0">'
                 f'<testcase classname="rostest_pkg.Verdict" name="test_verdict" time="0.0">'
                 f"{failure}</testcase></testsuite>\n")
sys.exit(0 if result.wasSuccessful() else 1)
