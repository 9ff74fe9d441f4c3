"""Running build/mpm for the report: Runner (one OpenMP thread per run, `jobs` runs at a time,
in a work directory; `mpm run`, `study`, `bench` and `reconstruct`) and massmatrix (`mpm
massmatrix --csv`)."""
import csv
import json
import os
import re
import subprocess
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

from .common import EX


class Runner:
    """Runs build/mpm (one OpenMP thread per run, `jobs` runs at a time) in a work directory."""

    def __init__(self, mpm, jobs, work):
        self.mpm, self.jobs, self.work = mpm, jobs, work
        self.env = dict(os.environ, OMP_NUM_THREADS="1")
        self.count = 0

    def _dir(self, name):
        self.count += 1
        return os.path.join(self.work, f"{self.count:04d}_{re.sub(r'[^A-Za-z0-9_.-]', '_', name)}")

    def run(self, example, sets=(), frames=1, name=None, out=None):
        """One `mpm run`; returns summary.json as a dict with '_dir' added."""
        out = out or self._dir(name or example)
        cmd = [self.mpm, "run", os.path.join(EX, example + ".toml"), "-q", "--out", out,
               "--set", "output.vtk=false", "--set", f"output.frames={frames}",
               "--set", f"output.csv={'true' if frames else 'false'}"]
        for s in sets:
            cmd += ["--set", s]
        subprocess.run(cmd, capture_output=True, env=self.env)
        path = os.path.join(out, "summary.json")
        if not os.path.exists(path):
            return {"status": "failed", "errors": {}, "conservation": {}, "_dir": out}
        with open(path) as f:
            r = json.load(f)
        r["_dir"] = out
        return r

    def many(self, specs):
        """Runs [(example, sets), ...] in parallel; results in order."""
        with ThreadPoolExecutor(max_workers=self.jobs) as ex:
            return list(ex.map(lambda s: self.run(*s), specs))

    def study(self, example, refine, methods=None, sets=(), name=None):
        """`mpm study`; returns (out_dir, {method: [rows sorted by h descending]})."""
        out = self._dir(name or ("study_" + example))
        cmd = [self.mpm, "study", os.path.join(EX, example + ".toml"), "--refine", refine,
               "--out", out, "-j", str(self.jobs),
               "--set", "output.vtk=false", "--set", "output.frames=1"]
        if methods:
            cmd += ["--methods", methods]
        for s in sets:
            cmd += ["--set", s]
        subprocess.run(cmd, capture_output=True, env=self.env)
        rows = {}
        with open(os.path.join(out, "study.csv"), newline="") as f:
            for row in csv.DictReader(f):
                for k, v in list(row.items()):
                    if k not in ("method", "status") and v not in ("", None):
                        try:
                            row[k] = float(v)
                        except ValueError:
                            pass
                    elif v == "":
                        row[k] = None
                rows.setdefault(row["method"], []).append(row)
        for m in rows:
            rows[m].sort(key=lambda r: -r["h"])
        return out, rows

    def bench(self, args):
        """`mpm bench ARGS` with one thread; returns the median ns per particle-step."""
        p = subprocess.run([self.mpm, "bench", "--threads", "1"] + args, capture_output=True,
                           text=True, env=self.env)
        m = re.search(r"median ([0-9.eE+-]+) ns", p.stdout) or re.search(
            r"([0-9.eE+-]+) ns per particle-step", p.stdout)
        return float(m.group(1)) if m else None

    def reconstruct(self, args):
        """`mpm reconstruct`; returns (rms, relative integral error)."""
        p = subprocess.run([self.mpm, "reconstruct"] + args, capture_output=True, text=True,
                           env=self.env)
        rms = re.search(r"RMS error .*?([0-9.eE+-]+)\s*$", p.stdout, re.M)
        integ = re.search(r"relative integral error\s+([0-9.eE+-]+)", p.stdout)
        return (float(rms.group(1)) if rms else None, float(integ.group(1)) if integ else None)


def massmatrix(mpm, env, args):
    """`mpm massmatrix ARGS --csv`; returns {(degree, cells): row dict} and the wall time."""
    t = time.time()
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "m.csv")
        subprocess.run([mpm, "massmatrix", "--csv", path] + args, capture_output=True, env=env)
        if not os.path.exists(path):
            return {}, time.time() - t
        with open(path, newline="") as f:
            rows = {(int(r["degree"]), int(r["cells"])): {k: (float(v) if v not in ("",) else None)
                                                          for k, v in r.items()}
                    for r in csv.DictReader(f)}
    return rows, time.time() - t
