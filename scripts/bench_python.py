"""The Python package against the command line, side by side in one run (`scripts/bench python`).

For each job: the median wall time of the package's call (inputs from memory, results back as
arrays and dicts) and of the binary run as a process on files (the same work, its outputs
written), and peak memory of each in a fresh process for the large planarize.

usage: bench_python.py LAMINA_BIN WORKDIR
"""

import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import lamina

ROOT = Path(__file__).resolve().parents[1]
RUNS = 11
ROUNDS = 7


def median_time(fn, runs=RUNS):
    times = []
    out = None
    for _ in range(runs):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def cli_time(binary, work, argv, runs=RUNS, ok=(0,)):
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        p = subprocess.run([binary, *argv], cwd=work, capture_output=True)
        assert p.returncode in ok, p.stderr
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def peak_mib(argv, cwd):
    """Peak RSS of a process (GNU time), MiB."""
    p = subprocess.run(["/usr/bin/time", "-f", "%M", *argv], cwd=cwd, capture_output=True,
                       text=True)
    if p.returncode not in (0, 1):
        raise RuntimeError(p.stderr)
    return int(p.stderr.strip().splitlines()[-1]) / 1024


def honeycomb(target: int):
    """A honeycomb (every node of degree 3 inside) on a paraboloid, about `target` nodes, 20 mm
    cells: positions, edges and the surface normals."""
    # Brick-wall form of a hexagonal lattice: rows of nodes, every node linked along its row,
    # and every other node linked to the row above (alternating by row).
    n = int(np.sqrt(target))
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    x, y = i.ravel() * 17.3 - n * 8.65, j.ravel() * 10.0 - n * 5.0
    z = (x * x + y * y) / (4 * 1500.0)
    p = np.column_stack([x, y, z])
    nrm = np.column_stack([-x / 3000.0, -y / 3000.0, np.ones_like(x)])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    idx = (i * n + j).ravel()
    along = np.column_stack([idx.reshape(n, n)[:, :-1].ravel(), idx.reshape(n, n)[:, 1:].ravel()])
    ii, jj = i[:-1, :], j[:-1, :]
    up = ((ii + jj) % 2 == 0)
    a = (ii * n + jj)[up]
    across = np.column_stack([a, a + n])
    return p, np.vstack([along, across]), nrm


def main():
    binary, work = sys.argv[1], Path(sys.argv[2])
    work.mkdir(parents=True, exist_ok=True)
    rows = []

    calyx = lamina.read_network(ROOT / "fixtures/networks/calyx_veins.json")
    lamina.write_network(work / "network.json", calyx)
    py_t, solved = median_time(lambda: lamina.planarize(calyx, fix_normal=["z<1:0,0,1"]))
    cli_t = cli_time(binary, work, ["planarize", "network.json", "--fix-normal", "z<1:0,0,1",
                                    "-o", "axes.json", "--report", "report.json"])
    rows.append(("planarize Calyx (248 nodes, L-BFGS)", py_t, cli_t))

    sizing = lamina.size(solved, support="z<1", load="self-weight", groups=7)
    subprocess.run([binary, "size", "axes.json", "-o", "sizing.json", "--support", "z<1",
                    "--load", "self-weight", "--groups", "7"], cwd=work, capture_output=True)
    py_t, made = median_time(lambda: lamina.plates(solved, sizing=sizing, groups=7))
    py_out_t, written = median_time(lambda: lamina.plates(solved, sizing=sizing, groups=7,
                                                    out=work / "py-plates"))
    cli_t = cli_time(binary, work, ["plates", "axes.json", "--sizing", "sizing.json",
                                    "--groups", "7", "-o", "plates"], ok=(0, 1))
    n = len(made["plates"]["plates"])
    rows.append((f"plates Calyx, sized, 7 groups ({n} plates), in memory", py_t, cli_t))
    rows.append((f"plates Calyx, the same with out= (its {len(written['files'])} files)", py_out_t,
                 cli_t))

    rng = np.random.default_rng(1)
    quads = np.zeros((90_000, 4, 3))
    quads[:, 1, 0] = quads[:, 2, 0] = 100.0
    quads[:, 2, 1] = quads[:, 3, 1] = 80.0
    quads += rng.normal(0.0, 0.01, quads.shape)
    quads += (np.arange(90_000)[:, None, None] * np.array([0.0, 0.0, 7.0]))
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in quads.reshape(-1, 3).tolist()]
    lines += [f"f {4 * k + 1} {4 * k + 2} {4 * k + 3} {4 * k + 4}" for k in range(len(quads))]
    (work / "quads.obj").write_text("\n".join(lines) + "\n")
    py_t, a = median_time(lambda: lamina.audit(quads, tolerance=0.05), runs=5)
    cli_t = cli_time(binary, work, ["audit", "quads.obj", "--tolerance", "0.05", "--report",
                                    "quads.report.json"], runs=5, ok=(0, 1))
    rows.append(("audit 90,000 quads (P×4×3 array; the CLI reads an OBJ)", py_t, cli_t))

    # The command's own compute: the stage functions it calls, timed in Rust on the same files,
    # in rounds that alternate with the Python calls (this machine's speed drifts by tens of
    # per cent over a minute, so each ratio compares timings taken side by side).
    rounds = []
    for _ in range(ROUNDS):
        plates_t, _ = median_time(lambda: lamina.plates(solved, sizing=sizing, groups=7))
        audit_t, _ = median_time(lambda: lamina.audit(quads, tolerance=0.05), runs=5)
        p = subprocess.run(["cargo", "bench", "-q", "--bench", "stages"], cwd=ROOT,
                           env={**os.environ, "LAMINA_BENCH_WORK": str(work)},
                           capture_output=True, text=True, check=True)
        compute = json.loads(p.stdout.strip().splitlines()[-1])
        rounds.append({"plates": plates_t, "audit": audit_t, **compute})

    p, e, nrm = honeycomb(90_000)
    np.save(work / "comb-p.npy", p)
    np.save(work / "comb-e.npy", e)
    np.save(work / "comb-n.npy", nrm)
    lamina.write_network(work / "comb.json", {"positions": p, "edges": e, "normals": nrm})
    argv = ["planarize", "comb.json", "--method", "newton", "-o", "comb-axes.json", "--report",
            "comb-report.json"]
    t = time.perf_counter()
    cli_rss = peak_mib([binary, *argv], work)
    cli_t = time.perf_counter() - t
    script = ("import numpy as np, lamina, time; p = np.load('comb-p.npy'); e = np.load('comb-e.npy');"
              " n = np.load('comb-n.npy'); t = time.perf_counter();"
              " r = lamina.planarize(p, e, n, method='newton');"
              " print(time.perf_counter() - t, r['within'], r['summary']['max_deviation'])")
    t = time.perf_counter()
    py_rss = peak_mib([sys.executable, "-c", script], work)
    py_t = time.perf_counter() - t
    base = peak_mib([sys.executable, "-c", "import numpy, lamina"], work)
    report_mb = (work / "comb-report.json").stat().st_size / 1e6
    rows.append((f"planarize {len(p):,} nodes (Gauss-Newton), whole process", py_t, cli_t))

    print(f"{'job':62} {'python':>10} {'cli':>10} {'ratio':>6}")
    for name, pt, ct in rows:
        print(f"{name:62} {pt * 1000:8.1f}ms {ct * 1000:8.1f}ms {pt / ct:6.2f}")
    for what, suffix in [("the stage function alone", "_s"),
                         ("the stage and the outputs the call returns, in memory", "_out_s")]:
        print(f"against the command's own compute, in Rust, no files: {what} "
              f"({ROUNDS} rounds, each Python then Rust; the median ratio and each round's)")
        for name, key in [(rows[1][0], "plates"), (rows[3][0], "audit")]:
            ratios = [r[key] / r[key + suffix] for r in rounds]
            each = ", ".join(f"{r[key] * 1000:.1f}/{r[key + suffix] * 1000:.1f} ms"
                             for r in rounds)
            print(f"{name:62} ratio {statistics.median(ratios):5.2f} "
                  f"(each {', '.join(f'{x:.2f}' for x in ratios)}; {each})")
    print(f"planarize {len(p):,} nodes, peak memory: Python process {py_rss:.0f} MiB "
          f"(of which {base:.0f} MiB is the interpreter with numpy and lamina loaded), the "
          f"command {cli_rss:.0f} MiB (its report file {report_mb:.1f} MB): ratio "
          f"{py_rss / cli_rss:.2f}")


if __name__ == "__main__":
    main()
