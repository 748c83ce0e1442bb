#!/usr/bin/env python3
"""Runs a command and prints its wall time and peak resident memory (of it and its children)."""
import resource
import subprocess
import sys
import time

if len(sys.argv) < 2:
    sys.exit("usage: run-measured.py COMMAND [ARG...]")
started = time.monotonic()
code = subprocess.call(sys.argv[1:])
wall = time.monotonic() - started
peak_kib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
print(f"wall time {wall:.1f} s, peak memory {peak_kib / 1024:.0f} MiB ({' '.join(sys.argv[1:2])})",
      flush=True)
sys.exit(code)
