#!/usr/bin/env python3
"""The suite's budget sheet (BENCHMARKS.md, "Test suite budget").

Runs `.ci/run` with every step timed (its `bash -x` trace marks where each
command starts) and each test's own time reported (libtest's
`--report-time`, switched on through `SUITE_TEST_ARGS`), then prints:
- the wall time of each step of `.ci/run`,
- per test group (the module of tests/suite/main.rs), the number of tests and
  the sum of their times (tests run side by side, so the sums add up to
  more than the step's wall time), slowest first,
- the slowest tests.

Run it from a clean clone with nothing else running:
    git clone . /tmp/budget && cd /tmp/budget && scripts/suite-budget.py
The full log is kept in target/suite-budget.log.
"""

import os
import re
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

root = Path(__file__).resolve().parent.parent
os.chdir(root)
(root / "target").mkdir(exist_ok=True)
log_path = root / "target" / "suite-budget.log"

env = dict(os.environ)
# `--report-time` is an unstable libtest option; RUSTC_BOOTSTRAP=1 in the
# test binary's environment lets the stable harness accept it. It is set
# through cargo's runner, so only the test binaries see it: in the build's
# environment it would change the fingerprints and rebuild every crate.
host = subprocess.run(
    ["rustc", "-vV"], capture_output=True, text=True, check=True
).stdout.split("host: ")[1].split()[0]
runner = "CARGO_TARGET_" + host.upper().replace("-", "_") + "_RUNNER"
env[runner] = "env RUSTC_BOOTSTRAP=1"
env["SUITE_TEST_ARGS"] = "-Z unstable-options --report-time"

steps = []  # (command, start seconds)
tests = []  # (name, seconds)
start = time.time()
test_line = re.compile(r"^test (\S+) \.\.\. ok <([0-9.]+)s>")
with open(log_path, "w") as log:
    proc = subprocess.Popen(
        ["bash", "-x", ".ci/run"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        env=env,
        text=True,
        bufsize=1,
    )
    for line in proc.stdout:
        now = time.time() - start
        log.write(f"{now:9.1f} {line}")
        log.flush()
        if line.startswith("+ ") and not line.startswith("+ ["):
            steps.append((line[2:].strip(), now))
        m = test_line.match(line.strip())
        if m:
            tests.append((m.group(1), float(m.group(2))))
    rc = proc.wait()
end = time.time() - start

print(f"`.ci/run` exit {rc}, {end / 60:.1f} min wall\n")
print("| step | wall |")
print("| --- | ---: |")
for i, (cmd, t0) in enumerate(steps):
    t1 = steps[i + 1][1] if i + 1 < len(steps) else end
    if t1 - t0 >= 0.5:
        print(f"| `{cmd}` | {t1 - t0:.0f} s |")

groups = defaultdict(lambda: [0, 0.0])
for name, secs in tests:
    group = name.split("::")[0] if "::" in name else "(library unit tests)"
    groups[group][0] += 1
    groups[group][1] += secs
print("\n| test group | tests | summed test time |")
print("| --- | ---: | ---: |")
for group, (count, secs) in sorted(groups.items(), key=lambda g: -g[1][1]):
    print(f"| {group} | {count} | {secs:.0f} s |")

print("\nslowest tests:")
for name, secs in sorted(tests, key=lambda t: -t[1])[:15]:
    print(f"  {secs:7.1f} s  {name}")
sys.exit(rc)
