"""The Python package against the command line, side by side in one run (`scripts/bench python`).

For each job: the median wall time of the package's call (inputs from memory, results back as
arrays and dicts) and of the binary run as a process on files (the same outputs asked for), the
solve time the command reports where it reports one, and each one's peak memory.

usage: bench_python.py LAMINA_BIN WORKDIR
"""

import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import lamina

ROOT = Path(__file__).resolve().parents[1]
RUNS = 21


def median_time(fn, runs=RUNS):
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def cli_run(binary, work, argv):
    """Median wall time of the binary over RUNS runs, and its peak RSS (MiB) from GNU time."""
    times = []
    for _ in range(RUNS):
        t = time.perf_counter()
        subprocess.run([binary, *argv], cwd=work, check=True, capture_output=True)
        times.append(time.perf_counter() - t)
    p = subprocess.run(["/usr/bin/time", "-f", "%M", binary, *argv], cwd=work,
                       capture_output=True, text=True)
    rss = int(p.stderr.strip().splitlines()[-1]) / 1024
    return statistics.median(times), rss


def main():
    binary, work = sys.argv[1], Path(sys.argv[2])
    work.mkdir(parents=True, exist_ok=True)
    rows = []

    calyx = lamina.read_network(ROOT / "fixtures/networks/calyx_veins.json")
    lamina.write_network(work / "network.json", calyx)
    py_t, r = median_time(lambda: lamina.planarize(calyx, fix_normal=["z<1:0,0,1"]))
    cli_t, cli_rss = cli_run(binary, work, ["planarize", "network.json", "--fix-normal",
                                            "z<1:0,0,1", "-o", "axes.json", "--report",
                                            "report.json"])
    solve = json.loads((work / "report.json").read_text())["seconds"]
    rows.append(("planarize Calyx (248 nodes, L-BFGS)", py_t, cli_t, solve, r["report"]["seconds"]))

    leaf = lamina.venation(shape="ovate", seed=1)["network"]
    lamina.write_network(work / "leaf.json", leaf)
    py_t, r = median_time(lambda: lamina.planarize(leaf, method="newton", tolerance=0.05))
    cli_t, _ = cli_run(binary, work, ["planarize", "leaf.json", "--method", "newton",
                                      "--tolerance", "0.05", "-o", "leaf-axes.json", "--report",
                                      "leaf-report.json"])
    solve = json.loads((work / "leaf-report.json").read_text())["seconds"]
    rows.append((f"planarize a grown leaf ({len(leaf['positions'])} nodes, Gauss-Newton)", py_t,
                 cli_t, solve, r["report"]["seconds"]))

    loop = lamina.read_network(ROOT / "fixtures/networks/small_loop.json")
    lamina.write_network(work / "loop.json", loop)
    py_t, r = median_time(lambda: lamina.solid(loop, cell=0.03), runs=5)
    cli_t = statistics.median(
        _time(lambda: subprocess.run([binary, "solid", "loop.json", "--cell", "0.03", "-o",
                                      "loop.stl", "--report", "loop.report.json"], cwd=work,
                                     check=True, capture_output=True)) for _ in range(5))
    rows.append((f"solid small_loop at 0.03 mm ({len(r['mesh']['faces']):,} triangles)", py_t,
                 cli_t, None, None))

    solved = lamina.planarize(calyx, fix_normal=["z<1:0,0,1"])
    plates = lamina.plates(solved, groups=7, thickness=3.0)
    (work / "plates").mkdir(exist_ok=True)
    (work / "plates/plates.json").write_text(plates["plates_json"])
    py_t, _ = median_time(lambda: lamina.nest(plates, sheet="3000x1500", margin=10, spacing=5),
                          runs=5)
    cli_t = statistics.median(
        _time(lambda: subprocess.run([binary, "nest", "plates/plates.json", "--sheet", "3000x1500",
                                      "--margin", "10", "--spacing", "5", "-o", "cut"], cwd=work,
                                     check=True, capture_output=True)) for _ in range(5))
    rows.append((f"nest the Calyx plates ({len(plates['plates']['plates'])} parts)", py_t, cli_t,
                 None, None))

    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"{'job':58} {'python':>9} {'cli':>9} {'ratio':>6} {'cli solve':>10} {'py solve':>9}")
    for name, p, c, s, ps in rows:
        solve = f"{s * 1000:8.1f}ms" if s is not None else " " * 10
        psolve = f"{ps * 1000:7.1f}ms" if ps is not None else ""
        print(f"{name:58} {p * 1000:7.1f}ms {c * 1000:7.1f}ms {p / c:6.2f} {solve} {psolve}")
    print(f"peak memory: the Python process {rss:.0f} MiB (all jobs, numpy and the package "
          f"loaded); the binary on Calyx planarize {cli_rss:.0f} MiB")


def _time(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


if __name__ == "__main__":
    main()
