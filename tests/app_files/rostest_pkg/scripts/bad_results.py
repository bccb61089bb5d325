#!/usr/bin/env python3
"""Writes a results file that is not XML, then exits 0 (orchestra test: an error verdict)."""
import sys

FLAG = "--gtest_output=xml:"
for arg in sys.argv:
    if arg.startswith(FLAG):
        with open(arg[len(FLAG):], "w") as fh:
            fh.write("<testsuite tests='1'><testcase name='x'>  -- cut short")
