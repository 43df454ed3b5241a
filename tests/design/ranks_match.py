#!/usr/bin/env python3
"""tangent-opt on 1 process and under `mpirun -np 2`: the result files must agree bit for bit
(every field but the timings). Usage: ranks_match.py TANGENT_OPT MPIEXEC RUN.json WORKDIR"""
import json
import os
import subprocess
import sys

tangent_opt, mpiexec, run, work = sys.argv[1:5]
os.makedirs(work, exist_ok=True)
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")
one = os.path.join(work, "one.json")
two = os.path.join(work, "two.json")
subprocess.run([tangent_opt, run, "-o", one, "--threads", "1", "--quiet"], check=True, env=env)
subprocess.run([mpiexec, "-np", "2", tangent_opt, run, "-o", two, "--threads", "1", "--quiet"],
               check=True, env=env)


def load(path):
    with open(path) as f:
        r = json.load(f)
    for c in r["results"]:
        c.pop("time_ms", None)
    return json.dumps(r, sort_keys=True)


a, b = load(one), load(two)
cases = json.loads(a)["cases"]
if a != b:
    print(f"ranks_match: 1-rank and 2-rank results differ ({cases} cases)")
    sys.exit(1)
print(f"ranks_match: 1 rank and 2 ranks agree bit for bit on {cases} cases")
