#!/usr/bin/env python3
"""Runs a documentation page as a reader would: every ```sh block in order, then every ```python
block, in a fresh directory where `examples/` and `data/` are the checkout's, with the build's
`sdftrace` on PATH and its Python module importable. Each must exit 0. Images the page shows must
exist. Blocks fenced with a bare ``` (interactive commands, output, JSON fragments) are not run.

    run_guide.py SOURCE_DIR BUILD_DIR PAGE.md
"""
import os
import re
import subprocess
import sys
import tempfile
import time

source, build, page = sys.argv[1:4]
text = open(page, encoding="utf-8").read()
blocks = re.findall(r"^```(sh|python)\n(.*?)^```", text, flags=re.S | re.M)
failures = []

for image in re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", text):
    if not os.path.exists(os.path.join(os.path.dirname(page), image)):
        failures.append("image %s not found" % image)

env = dict(os.environ)
env["PATH"] = os.path.join(build, "apps", "sdftrace") + os.pathsep + env.get("PATH", "")
env["PYTHONPATH"] = os.path.join(build, "python")
# mpirun as root (CI) on a machine with fewer cores than ranks.
env.update({"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
            "OMPI_MCA_rmaps_base_oversubscribe": "1",
            "OMPI_MCA_btl_vader_single_copy_mechanism": "none"})

with tempfile.TemporaryDirectory() as work:
    for name in ("examples", "data"):
        os.symlink(os.path.join(source, name), os.path.join(work, name))
    ran = 0
    for kind, body in blocks:
        start = time.time()
        if kind == "sh":
            cmd = ["bash", "-euo", "pipefail", "-c", body]
        else:
            cmd = ["/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable,
                   "-c", body]
        r = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, timeout=600)
        ran += 1
        first = body.strip().splitlines()[0]
        print("%s: %-70.70s %5.1f s, exit %d" % (kind, first, time.time() - start, r.returncode))
        if r.returncode != 0:
            failures.append("%s block '%s' exited %d:\n%s%s" % (kind, first, r.returncode,
                                                               r.stdout[-2000:], r.stderr[-2000:]))
    if ran == 0 and "```sh" in text:
        failures.append("no block ran")

if failures:
    print("%s:\n  " % page + "\n  ".join(failures))
    print("1 failed")
    sys.exit(1)
print("%s: %d blocks ran" % (os.path.basename(page), len(blocks)))
