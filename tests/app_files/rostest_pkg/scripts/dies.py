#!/usr/bin/env python3
"""A node that dies (exit code 3) once ``~after`` seconds have passed (default 1)."""
import sys
import time

after = next((float(a.split(":=", 1)[1]) for a in sys.argv if a.startswith("_after:=")), 1.0)
time.sleep(after)
sys.exit(3)
