"""The lamina Python package against the lamina binary: every function on a small input gives
the command line's result for the same input and seed (reports equal to the files the command
writes, tables compared row by row), with no file written (the calls run with an unusable
temporary folder, a file in its place, and a read-only working directory that must stay as it
was, since root writes there anyway); errors as LaminaError naming the argument; forks,
pickles, Ctrl-C, progress callbacks, units and a Dask sweep.

The binary is $LAMINA_BIN (scripts/test gives the one it built); the command line runs in a
folder of its own."""

import json
import math
import multiprocessing
import os
import pickle
import re
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import lamina

ROOT = Path(__file__).resolve().parents[2]
BIN = os.environ.get("LAMINA_BIN", str(ROOT / "target" / "release" / "lamina"))
CALYX = ROOT / "fixtures" / "networks" / "calyx_veins.json"
CALYX_SURFACE = ROOT / "fixtures" / "surfaces" / "calyx.obj"
SMALL_LOOP = ROOT / "fixtures" / "networks" / "small_loop.json"
TORUS = ROOT / "fixtures" / "surfaces" / "torus.obj"
SPHERE = ROOT / "fixtures" / "surfaces" / "sphere.obj"


@pytest.fixture(scope="session", autouse=True)
def read_only_temp(tmp_path_factory):
    """Every call of the package runs with a read-only temporary folder and working directory:
    a call that wrote a file anywhere but where it was told would fail."""
    tmp_path_factory.getbasetemp()
    ro = tmp_path_factory.mktemp("read-only")
    # Root writes into read-only folders, so the temporary "folder" is a file: nothing can be
    # made under it by anyone (NotADirectoryError), and the working folder is watched instead
    # (`nothing_written_here`).
    temp = ro / "not-a-folder"
    temp.write_bytes(b"")
    ro.chmod(stat.S_IRUSR | stat.S_IXUSR)
    old = (os.environ.get("TMPDIR"), tempfile.tempdir, os.getcwd())
    os.environ["TMPDIR"] = str(temp)
    tempfile.tempdir = str(temp)
    os.chdir(ro)
    try:
        yield ro
    finally:
        os.chdir(old[2])
        tempfile.tempdir = old[1]
        if old[0] is None:
            del os.environ["TMPDIR"]
        else:
            os.environ["TMPDIR"] = old[0]
        ro.chmod(stat.S_IRWXU)


@pytest.fixture(autouse=True)
def nothing_written_here(read_only_temp):
    """After every test, the working folder holds what it held before (root can write there)."""
    yield
    assert sorted(os.listdir(read_only_temp)) == ["not-a-folder"]


def test_the_temporary_folder_is_unusable(read_only_temp):
    with pytest.raises(OSError):
        tempfile.mkstemp()
    with pytest.raises(OSError):
        tempfile.mkstemp(dir=os.environ["TMPDIR"])


def cli(tmp: Path, *argv, ok=(0,)) -> subprocess.CompletedProcess:
    """Runs the binary in `tmp`; fails unless it exits with one of `ok`."""
    env = dict(os.environ, TMPDIR=str(tmp))
    p = subprocess.run([BIN, *map(str, argv)], cwd=tmp, capture_output=True, text=True, env=env)
    assert p.returncode in ok, p.stderr
    return p


def cli_error(tmp: Path, *argv) -> str:
    """The message the binary prints when it refuses (exit 2)."""
    env = dict(os.environ, TMPDIR=str(tmp))
    p = subprocess.run([BIN, *map(str, argv)], cwd=tmp, capture_output=True, text=True, env=env)
    assert p.returncode == 2, (p.returncode, p.stdout)
    return p.stderr.strip().splitlines()[-1].removeprefix("lamina: error: ")


def plain(v, tables=()):
    """A report as the JSON the command writes would read: numpy arrays as lists, tables
    (columns) as rows, NaN as None, timings zeroed."""
    if isinstance(v, dict):
        out = {}
        for k, x in v.items():
            if k in ("seconds", "elapsed_s"):
                out[k] = 0
            elif k in tables and isinstance(x, dict):
                out[k] = [plain(r, tables) for r in lamina.rows(x)]
            else:
                out[k] = plain(x, tables)
        return out
    if isinstance(v, np.ndarray):
        return plain(v.tolist(), tables)
    if isinstance(v, (list, tuple)):
        return [plain(x, tables) for x in v]
    if isinstance(v, float) and math.isnan(v):
        return None
    return v


def file_json(path: Path, drop=()) -> dict:
    doc = plain(json.loads(path.read_text()))
    for k in drop:
        doc.pop(k, None)
    return doc


def same_report(py: dict, path: Path, tables=(), drop=()) -> None:
    got = plain(py, tables)
    want = file_json(path, drop)
    for k in drop:
        got.pop(k, None)
    assert got == want


def cli_network(path: Path) -> dict:
    doc = json.loads(path.read_text())
    return {
        "positions": np.array([n["p"] for n in doc["nodes"]], dtype=float).reshape(-1, 3),
        "edges": np.array([[e["a"], e["b"]] for e in doc["edges"]], dtype=np.int64).reshape(-1, 2),
        "edge_radius": np.array([e.get("radius", 0.0) for e in doc["edges"]], dtype=float),
        "node_radius": np.array([n.get("radius", 0.0) for n in doc["nodes"]], dtype=float),
    }


def same_network(py: dict, path: Path) -> None:
    want = cli_network(path)
    for k, v in want.items():
        assert np.array_equal(py[k], v), k


def same_triangles(got: dict, want: dict) -> None:
    """The same triangles in the same order, corner for corner."""
    assert np.array_equal(got["vertices"][got["faces"]], want["vertices"][want["faces"]])
    assert len(got["vertices"]) == len(want["vertices"])


@pytest.fixture(scope="module")
def calyx():
    return lamina.read_network(CALYX)


@pytest.fixture(scope="module")
def solved(calyx):
    return lamina.planarize(calyx, fix_normal=["z<1:0,0,1"], name="network.json")


# Growing.


def test_venation_equals_cli(tmp_path):
    py = lamina.venation(shape="lanceolate", mode="open", seed=3)
    cli(tmp_path, "venation", "--shape", "lanceolate", "--mode", "open", "--seed", 3,
        "-o", "venation.json", "--report", "report.json")
    same_report(py["report"], tmp_path / "report.json", drop=("output",))
    same_network(py["network"], tmp_path / "venation.json")
    assert py["network"]["meta"]["generator"] == json.loads(
        (tmp_path / "venation.json").read_text())["meta"]["generator"]


def test_venation_in_an_outline():
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    outline = np.column_stack([30 * np.cos(t), 50 + 50 * np.sin(t)])
    py = lamina.venation(outline=outline, root=(0.0, 0.5))
    assert py["report"]["nodes"] == len(py["network"]["positions"]) > 50
    p = py["network"]["positions"]
    assert np.all(np.hypot(p[:, 0] / 30, (p[:, 1] - 50) / 50) <= 1 + 1e-9)


def test_venation_on_surface_equals_cli(tmp_path):
    mesh = lamina.read_mesh(SPHERE)
    py = lamina.venation_on_surface(mesh, sources=300, seed=2)
    cli(tmp_path, "venation", "--surface", SPHERE, "--sources", 300, "--seed", 2,
        "-o", "venation.json", "--report", "report.json")
    same_report(py["report"], tmp_path / "report.json", drop=("output", "surface"))
    same_network(py["network"], tmp_path / "venation.json")


def test_venation_on_two_bodies_names_the_one_without_a_root():
    mesh = lamina.read_mesh(ROOT / "fixtures" / "surfaces" / "two_bodies.stl")
    with pytest.warns(lamina.LaminaWarning) as said:
        one = lamina.venation_on_surface(mesh, root=(0.0, 0.0, -5.0), sources=200)
    assert [str(w.message).split(":")[0] for w in said] == [
        "1 of its 2 bodies have no root, so growth cannot reach them (94 sources there left out); "
        "give a root= on each body to grow on it", "body 1"]
    u = one["report"]["quality"]["unrooted"]
    assert (u["bodies"], u["bodies_without_root"]) == (2, 1)
    assert u["without_root"][0]["lowest_vertex"] == 10
    assert any(n.startswith("body 1: 12 triangles") for n in one["notes"])
    with pytest.warns(lamina.LaminaWarning, match="each grow from their lowest vertex"):
        each = lamina.venation_on_surface(mesh, sources=200)
    assert each["report"]["quality"]["unrooted"]["bodies_without_root"] == 0
    assert each["report"]["quality"]["components"] == 2


def test_read_network_reads_hatch_boundaries_when_asked(tmp_path):
    dxf = ROOT / "fixtures" / "networks" / "ezdxf_hatches.dxf"
    with pytest.warns(lamina.LaminaWarning, match="HATCH"):
        plain = lamina.read_network(dxf)
    assert len(plain["edges"]) == 1
    with pytest.warns(lamina.LaminaWarning, match="1 paper-space entity"):
        read = lamina.read_network(dxf, hatch_boundaries=True)
    cli(tmp_path, "convert", "--hatch-boundaries", dxf, "hatches.json")
    same_network(read, tmp_path / "hatches.json")


def test_veins_equals_cli(tmp_path):
    mesh = lamina.read_mesh(TORUS)
    py = lamina.veins(mesh["vertices"], mesh["faces"], sources=60, seed=5)
    cli(tmp_path, "veins", "--surface", TORUS, "--sources", 60, "--seed", 5,
        "-o", "veins.json", "--report", "report.json")
    same_report(py["report"], tmp_path / "report.json", drop=("output", "surface"))
    same_network(py["network"], tmp_path / "veins.json")


def test_lsystem_and_bifurcate_equal_cli(tmp_path):
    rules = {"X": "F[-X]F[+X]-X", "F": "FF"}
    py = lamina.lsystem(axiom="X", rules=rules, iterations=4, angle=25.0)
    cli(tmp_path, "lsystem", "--axiom", "X", "--rule", "X=F[-X]F[+X]-X", "--rule", "F=FF",
        "--iterations", 4, "--angle", 25, "-o", "lsystem.json", "--report", "report.json")
    same_report(py["report"], tmp_path / "report.json")
    same_network(py["network"], tmp_path / "lsystem.json")
    counts = lamina.lsystem(axiom="X", rules=rules, iterations=7, derive_only=True)["report"]
    want = json.loads(cli(tmp_path, "lsystem", "--axiom", "X", "--rule", "X=F[-X]F[+X]-X",
                          "--rule", "F=FF", "-n", 7, "--derive-only", "--json").stdout)
    assert counts == want
    tree = lamina.bifurcate(depth=7, angle="15..35", seed=4, boundary=(8000, 4000))
    cli(tmp_path, "bifurcate", "--depth", 7, "--angle", "15..35", "--seed", 4, "--boundary",
        "rect:8000,4000", "-o", "tree.json", "--report", "tree.report.json")
    same_report(tree["report"], tmp_path / "tree.report.json")
    same_network(tree["network"], tmp_path / "tree.json")


def test_buds_equals_cli(tmp_path):
    program = ROOT / "fixtures" / "buds" / "split.bud"
    py = lamina.buds(str(program), cells=600, seed=2)
    cli(tmp_path, "buds", program, "--cells", 600, "--seed", 2, "-o", "form.stl", "--report",
        "report.json")
    same_report(py["report"], tmp_path / "report.json")
    want = lamina.read_mesh(tmp_path / "form.stl")
    assert len(py["mesh"]["faces"]) == len(want["faces"])


# Rationalizing.


def test_cells_equals_cli(tmp_path, calyx):
    surface = lamina.read_mesh(CALYX_SURFACE)
    py = lamina.cells(calyx, surface=surface)
    cli(tmp_path, "cells", CALYX, "--surface", CALYX_SURFACE, "-o", "cells.obj",
        "--table", "table.json")
    table = plain(py["table"], ("cells", "holes"))
    want = file_json(tmp_path / "table.json")
    # The note naming the surface says its file name on the command line.
    table["notes"] = table["notes"][1:]
    want["notes"] = want["notes"][1:]
    assert table == want
    obj = (tmp_path / "cells.obj").read_text().splitlines()
    rows = {k: [line.split()[1:] for line in obj if line.startswith(k + " ")]
            for k in ("v", "vn", "f")}
    assert np.array_equal(py["mesh"]["vertices"], np.array(rows["v"], dtype=float))
    assert np.array_equal(py["normals"], np.array(rows["vn"], dtype=float))
    faces = [[int(t.split("/")[0]) - 1 for t in f] for f in rows["f"]]
    assert np.array_equal(py["mesh"]["faces"], faces)


def test_simplify_equals_cli(tmp_path, calyx):
    py = lamina.simplify(calyx, max_deviation=10)
    cli(tmp_path, "simplify", CALYX, "--max-deviation", 10, "-o", "simple.json", "--report",
        "report.json")
    same_report(py["report"], tmp_path / "report.json")
    same_network(py["network"], tmp_path / "simple.json")


def test_planarize_equals_cli(tmp_path, calyx, solved):
    cli(tmp_path, "planarize", CALYX, "--fix-normal", "z<1:0,0,1", "-o", "axes.json",
        "--report", "report.json", "--panels", "panels.obj")
    report = plain(solved["report"], ("panels", "worst"))
    want = file_json(tmp_path / "report.json")
    for r in (report, want):
        r["title"] = r["source"] = ""
    assert report == want
    axes = json.loads((tmp_path / "axes.json").read_text())
    assert np.array_equal(solved["axes"], [n["axis"] for n in axes["nodes"]])
    assert plain(solved["summary"]) == axes["summary"]
    assert solved["within"] and solved["summary"]["converged"]
    obj = (tmp_path / "panels.obj").read_text().splitlines()
    v = np.array([line.split()[1:4] for line in obj if line.startswith("v ")], dtype=float)
    f = np.array([[int(t) - 1 for t in line.split()[1:5]] for line in obj
                  if line.startswith("f ")])
    assert np.array_equal(solved["panels"], v[f])


def test_planarize_methods_and_heights(calyx):
    r = lamina.planarize(calyx["positions"], calyx["edges"], calyx["normals"], height=50,
                         tolerance=0.05, method="newton", fix_normal=["z<1:0,0,1"])
    assert r["report"]["method"].startswith("Gauss-Newton")
    assert np.all(r["heights"] == 50)
    assert r["summary"]["max_deviation"] <= 0.05


def test_audit_equals_cli(tmp_path, solved):
    cli(tmp_path, "planarize", CALYX, "--fix-normal", "z<1:0,0,1", "-o", "axes.json",
        "--panels", "panels.obj")
    cli(tmp_path, "audit", "panels.obj", "--tolerance", 0.01, "--report", "report.json")
    py = lamina.audit(str(tmp_path / "panels.obj"), tolerance=0.01)
    report = plain(py["report"], ("panels", "worst"))
    want = file_json(tmp_path / "report.json")
    for r in (report, want):
        r["title"] = r["source"] = ""
    assert report == want
    mem = lamina.audit(list(solved["panels"]), tolerance=0.01)
    assert plain(mem["report"]["summary"]) == want["summary"]
    assert mem["within"]


# Steel.


@pytest.fixture(scope="module")
def steel(tmp_path_factory, solved):
    tmp = tmp_path_factory.mktemp("steel")
    cli(tmp, "planarize", CALYX, "--fix-normal", "z<1:0,0,1", "-o", "axes.json")
    sizing = lamina.size(solved, support="z<1", load="self-weight", deflection_limit="L/500",
                         groups=7)
    cli(tmp, "size", "axes.json", "-o", "sizing.json", "--support", "z<1", "--load",
        "self-weight", "--deflection-limit", "L/500", "--groups", 7, ok=(0, 1))
    out = tmp / "py-plates"
    plates = lamina.plates(solved, sizing=sizing, groups=7, out=out)
    cli(tmp, "plates", "axes.json", "--sizing", "sizing.json", "--groups", 7, "-o", "plates",
        ok=(0, 1))
    cut = lamina.nest(plates, sheet="3000x1500", margin=10, spacing=5, lead_in=2, nc="gcode",
                      post="qtplasmac", out=tmp / "py-cut")
    cli(tmp, "nest", "plates/plates.json", "--sheet", "3000x1500", "--margin", 10, "--spacing",
        5, "--lead-in", 2, "--nc", "gcode", "--post", "qtplasmac", "-o", "cut")
    return tmp, sizing, plates, cut


def files_under(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_size_equals_cli(steel):
    tmp, sizing, _, _ = steel
    same_report(sizing["sizing"], tmp / "sizing.json", tables=("edges", "nodes"))
    assert sizing["within"]


def test_plates_equal_cli(steel):
    tmp, _, plates, _ = steel
    same_report(plates["plates"], tmp / "plates" / "plates.json")
    same_report(plates["welds"], tmp / "plates" / "welds.json")
    want = files_under(tmp / "plates")
    got = files_under(tmp / "py-plates")
    assert sorted(got) == sorted(want) == sorted(plates["files"])
    # The weld page's viewer names the files it came from; every other file is the same.
    for name in want:
        if name != "welds.html":
            assert got[name] == want[name], name
    assert plates["assembly"]["faces"].shape[1] == 3


def test_the_plates_weigh_what_the_sizing_analysed_with_its_joints(steel, solved):
    _, sizing, plates, _ = steel
    edges = lamina.rows(sizing["sizing"]["edges"])
    rho = sizing["sizing"]["material"]["density"] * 1e-6
    cut = [0.0] * len(edges)
    for p in plates["plates"]["plates"]:
        cut[p["edge"]] += p["area_mm2"] * p["thickness"] * rho
    assert all(abs(e["mass_kg"] - c) <= 1e-9 * c for e, c in zip(edges, cut))
    # Joints other than the sizing weighed are refused, naming the option.
    with pytest.raises(lamina.LaminaError, match=r"^weld_gap= is 2 but the sizing"):
        lamina.plates(solved, sizing=sizing, groups=7, weld_gap=2)


def test_nest_equals_cli(steel):
    tmp, _, _, cut = steel
    same_report(cut["nest"], tmp / "cut" / "nest.json", tables=("placements",))
    want = files_under(tmp / "cut")
    got = files_under(tmp / "py-cut")
    assert got == want
    assert cut["bom"].encode() == want["bom.csv"]
    assert sorted(cut["files"]) == sorted(want)
    # The NC programs in memory, as the command wrote them: one per sheet.
    programs = {k: v for k, v in want.items() if k.endswith(".ngc")}
    assert len(programs) == len(cut["nest"]["sheets"]) > 0
    assert {k: v.encode() for k, v in cut["nc"].items()} == programs
    # Without nc= there are none; a post without nc=, or one of the other format, is refused.
    plates = file_json(tmp / "plates" / "plates.json")
    assert lamina.nest(plates, sheet="3000x1500", tries=1)["nc"] == {}
    with pytest.raises(lamina.LaminaError, match=r"^post= needs nc="):
        lamina.nest(plates, post="linuxcnc")
    with pytest.raises(lamina.LaminaError, match=r"^post= `essi` is not a gcode post"):
        lamina.nest(plates, nc="gcode", post="essi")
    with pytest.raises(lamina.LaminaError, match=r'^nc= must be "gcode" or "essi"'):
        lamina.nest(plates, nc="dxf")
    with pytest.raises(lamina.LaminaError, match=r"^nc_on= give 1 to 80 printable"):
        lamina.nest(plates, nc="essi", nc_on="")


# Printing.


def test_solid_slice_and_print_equal_cli(tmp_path):
    net = lamina.read_network(SMALL_LOOP)
    py = lamina.solid(net, cell=0.25)
    cli(tmp_path, "solid", SMALL_LOOP, "--cell", 0.25, "-o", "solid.obj", "--report",
        "report.json")
    same_report(py["report"], tmp_path / "report.json")
    same_triangles(py["mesh"], lamina.read_mesh(tmp_path / "solid.obj"))
    printed = lamina.slice(py["mesh"], layer=0.05)
    lamina.write_mesh(tmp_path / "model-0.obj", py["mesh"])
    cli(tmp_path, "slice", "model-0.obj", "--layer", 0.05, "-o", "lamina.sl1", "--report",
        "print.json")
    report = plain(printed["report"], ("islands", "placements"))
    want = file_json(tmp_path / "print.json")
    assert report["models"] == ["model-0"] and want["models"] == ["model-0.obj"]
    for r in (report, want):
        r["models"] = r["archive"] = None
    assert report == want
    assert printed["sl1"] == (tmp_path / "lamina.sl1").read_bytes()
    straight = lamina.print(net, fit=20)
    cli(tmp_path, "print", SMALL_LOOP, "--fit", 20, "-o", "lamina.sl1", "--report", "p.json")
    assert straight["sl1"] == (tmp_path / "lamina.sl1").read_bytes()
    # fit="auto" fills the display, as --fit auto; fit="keep" refuses what does not fit.
    filled = lamina.print(net, fit="auto")
    cli(tmp_path, "print", SMALL_LOOP, "--fit", "auto", "-o", "lamina.sl1")
    assert filled["sl1"] == (tmp_path / "lamina.sl1").read_bytes()
    assert filled["report"]["solid"]["scale"] > 1
    with pytest.raises(lamina.LaminaError, match=r"fit= auto, or fit= in mm"):
        lamina.print(net, fit=1000, upright=True)
    with pytest.raises(lamina.LaminaError, match=r'fit="loose": expected'):
        lamina.print(net, fit="loose")


# Errors: LaminaError naming the argument.


def test_bad_options_name_the_argument(tmp_path, calyx):
    with pytest.raises(lamina.LaminaError, match=r"^cell= must be a positive number"):
        lamina.solid(calyx, cell=-1.0)
    # The command line says the same of its flag.
    assert "--cell must be a positive number" in cli_error(tmp_path, "solid", CALYX, "--cell=-1",
                                                            "-o", "s.obj")
    with pytest.raises(lamina.LaminaError, match=r"^tolerance= must be a positive distance"):
        lamina.planarize(calyx, tolerance=0.0)
    with pytest.raises(lamina.LaminaError, match="support= is needed"):
        lamina.size(lamina.planarize(calyx), load="self-weight")
    with pytest.raises(TypeError, match="'fix_normals'; did you mean 'fix_normal'"):
        lamina.planarize(calyx, fix_normals=["z<1:0,0,1"])
    with pytest.raises(lamina.LaminaError, match="shape="):
        lamina.venation(shape="hexagon")
    with pytest.raises(lamina.LaminaError, match="units="):
        lamina.planarize(calyx, units="furlong")
    solved = lamina.planarize(calyx, fix_normal=["z<1:0,0,1"])
    with pytest.raises(lamina.LaminaError, match=r"^weld_gap= 0: .* node_core="):
        lamina.plates(solved, weld_gap=0.0)
    with pytest.raises(lamina.LaminaError,
                       match=r"^weld_gap_tolerance= 0.5 mm is more than weld_gap= 0.2 mm"):
        lamina.plates(solved, weld_gap=0.2)


@pytest.mark.parametrize("case, where", [
    ("empty", "positions: the network has no nodes"),
    ("no edges", "edges: the network has no edges"),
    ("duplicate edge", r"edges\[3\]: edge 3: repeats edge"),
    ("self loop", r"edges\[1\]: edge 1: self-loop"),
    ("edge out of range", r"edges\[0\]: edge 0: joins nodes 0 and 248"),
    ("negative index", r"edges\[2\]: index \[-1, 4\]"),
    ("nan position", r"positions\[3\]: is not finite"),
    ("inf position", r"positions\[5\]: is not finite"),
    ("huge position", r"positions\[7\]: 1e300 is beyond"),
    ("nan radius", r"edge_radius\[6\]: edge 6: radius NaN"),
    ("negative node radius", r"node_radius\[2\]: node 2: radius -1"),
    ("nan normal", r"normals\[4\]: node 4: normal is not finite"),
    ("wrong shape", r"positions: expected an N×3 array"),
    ("float edges", "edges: expected integer indices"),
])
def test_bad_arrays_raise_naming_the_argument(calyx, case, where):
    net = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in calyx.items()}
    if case == "empty":
        net["positions"] = np.zeros((0, 3))
        net["edges"] = np.zeros((0, 2), dtype=int)
        net["node_radius"] = net["normals"] = None
        net["edge_radius"] = None
    elif case == "no edges":
        net["edges"] = np.zeros((0, 2), dtype=int)
        net["edge_radius"] = None
    elif case == "duplicate edge":
        net["edges"][3] = net["edges"][0][::-1]
    elif case == "self loop":
        net["edges"][1] = [2, 2]
    elif case == "edge out of range":
        net["edges"][0] = [0, 248]
    elif case == "negative index":
        net["edges"][2] = [-1, 4]
    elif case == "nan position":
        net["positions"][3, 1] = np.nan
    elif case == "inf position":
        net["positions"][5, 0] = np.inf
    elif case == "huge position":
        net["positions"][7, 2] = 1e300
    elif case == "nan radius":
        net["edge_radius"][6] = np.nan
    elif case == "negative node radius":
        net["node_radius"][2] = -1.0
    elif case == "nan normal":
        net["normals"][4] = [np.nan, 0, 1]
    elif case == "wrong shape":
        net["positions"] = net["positions"][:, :2]
    elif case == "float edges":
        net["edges"] = net["edges"].astype(float)
    for call in (lambda: lamina.planarize(net), lambda: lamina.solid(net, radius=0.5)):
        with pytest.raises(lamina.LaminaError, match=where):
            call()


def test_extreme_option_values_are_refused(calyx):
    part = lamina.read_mesh(ROOT / "fixtures/surfaces/openscad_part.stl")
    veins = lamina.read_network(ROOT / "fixtures/networks/ezdxf_veins.dxf")
    flat = dict(veins, normals=np.tile([0.0, 0.0, 1.0], (len(veins["positions"]), 1)))
    for value in (0.0, -1.0, float("nan"), 1e300):
        for call in (lambda: lamina.planarize(flat, height=value),
                     lambda: lamina.solid(veins, radius=0.5, cell=value),
                     lambda: lamina.slice(part, layer=value)):
            with pytest.raises(lamina.LaminaError):
                call()


def test_notes_are_warnings_at_the_callers_line(solved):
    with pytest.warns(lamina.LaminaWarning, match="material 1.4404") as w:
        lamina.size(solved, support="z<1", load="self-weight")
    assert w[0].filename == __file__


def test_a_model_in_metres_warns_and_units_fix_it(calyx):
    metres = dict(calyx, positions=calyx["positions"] / 1000)
    with pytest.warns(lamina.LaminaWarning, match="give units=") as w:
        lamina.planarize(metres, fix_normal=["z<0.001:0,0,1"])
    assert w[0].filename == __file__
    with warnings.catch_warnings():
        warnings.simplefilter("error", lamina.LaminaWarning)
        r = lamina.planarize(metres, units="m", fix_normal=["z<1:0,0,1"])
    mm = lamina.planarize(calyx, fix_normal=["z<1:0,0,1"])
    assert r["units"] == "m"
    assert np.allclose(r["axes"], mm["axes"], atol=1e-9)
    assert np.allclose(r["heights"], 0.1)  # the default 100 mm, in metres
    assert np.allclose(r["positions"], metres["positions"])


# Picklable errors and results; forks, spawns and Dask.


def test_errors_and_results_pickle(solved):
    e = pickle.loads(pickle.dumps(lamina.LaminaError("tolerance= must be positive")))
    assert type(e) is lamina.LaminaError and str(e) == "tolerance= must be positive"
    assert isinstance(e, ValueError)
    w = pickle.loads(pickle.dumps(lamina.LaminaWarning("a note")))
    assert type(w) is lamina.LaminaWarning
    back = pickle.loads(pickle.dumps(solved))
    assert np.array_equal(back["axes"], solved["axes"])
    try:
        lamina.solid(lamina.read_network(SMALL_LOOP), cell=-1.0)
    except lamina.LaminaError as raised:
        again = pickle.loads(pickle.dumps(raised))
        assert str(again) == str(raised)


def grow_and_audit(seed: int) -> tuple:
    """A sweep's step: a leaf, its node axes, their audit."""
    leaf = lamina.venation(shape="circle", seed=seed, birth=4.0, tip_radius=0.3)["network"]
    solved = lamina.planarize(leaf, height=2.0, tolerance=0.01)
    audited = lamina.audit(list(solved["panels"]), tolerance=0.01, metric="corner")
    return seed, len(leaf["edges"]), solved["summary"]["max_deviation"], audited["within"]


def fails(_):
    lamina.solid(lamina.read_network(SMALL_LOOP), cell=-1.0)


def test_fork_pool_after_a_call_then_spawn_pool(calyx):
    lamina.planarize(calyx, fix_normal=["z<1:0,0,1"])  # the parent's thread pool is running
    serial = [grow_and_audit(s) for s in range(4)]
    with multiprocessing.get_context("fork").Pool(4) as pool:
        assert pool.map_async(grow_and_audit, range(4)).get(timeout=120) == serial
        with pytest.raises(lamina.LaminaError, match="cell="):
            pool.map_async(fails, [0]).get(timeout=60)
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        assert pool.map_async(grow_and_audit, range(4)).get(timeout=180) == serial


@pytest.fixture
def engine_temp(tmp_path, monkeypatch):
    """A writable temporary folder for an engine's own files (Dask's worker space), not lamina's."""
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    return tmp_path


def test_dask_sweep_equals_the_serial_sweep(engine_temp):
    distributed = pytest.importorskip("dask.distributed")
    serial = [grow_and_audit(s) for s in range(6)]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            futures = client.map(grow_and_audit, range(6))
            assert client.gather(futures) == serial
            bad = client.submit(fails, 0)
            with pytest.raises(lamina.LaminaError, match="cell="):
                bad.result()


# Cancelling, progress, threads.


PAPER = {"X": "F[-X]F[+X]-X", "F": "FF"}


def long_solid():
    # About 4 s and 5 M triangles here (marched only: tolerance=False, as --full).
    return lamina.read_network(SMALL_LOOP), dict(cell=0.015, tolerance=False)


@pytest.fixture
def ctrl_c_raises():
    # A process started in the background by a non-interactive shell (as scripts/test starts its
    # checks) inherits SIGINT ignored, and Python then leaves it ignored: give it Python's own
    # handler, as an interactive session, Jupyter or Grasshopper has.
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def test_ctrl_c_stops_a_long_solid_promptly(ctrl_c_raises):
    net, opts = long_solid()
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)

    timer = threading.Timer(1.0, interrupt)
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            lamina.solid(net, **opts)
        stopped = time.monotonic()
    finally:
        timer.cancel()
        timer.join()
    assert sent, f"the solid ended after {stopped - start:.2f} s, before the signal"
    # The watcher sees the signal within 20 ms; the stage stops at its next brick.
    assert stopped - sent[0] < 0.2, stopped - sent[0]


def test_a_progress_callback_stops_the_run():
    calls = []

    def stop_at_some_progress(stage, message, done, total):
        calls.append((stage, done, total))
        return False if done > 0 else None

    net, opts = long_solid()
    with pytest.raises(lamina.Cancelled):
        lamina.solid(net, progress=stop_at_some_progress, **opts)
    assert calls and calls[0][0] == "meshing"

    def boom(*_):
        raise RuntimeError("stop")

    with pytest.raises(RuntimeError, match="stop"):
        lamina.lsystem(axiom="X", rules=PAPER, iterations=15, derive_only=True, progress=boom)
    cut_stop = []
    plates = lamina.plates(lamina.planarize(lamina.read_network(CALYX)), thickness=3.0)
    with pytest.raises(lamina.Cancelled):
        lamina.nest(plates, tries=50, progress=lambda *a: cut_stop.append(a) or False)


def test_gil_released_and_progress():
    calls = []
    done = threading.Event()
    ticks = 0
    result = {}

    def work():
        try:
            result.update(lamina.lsystem(axiom="X", rules=PAPER, iterations=15, derive_only=True,
                                         progress=lambda *a: calls.append(a)))
        finally:
            done.set()

    t = threading.Thread(target=work)
    t.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    t.join()
    assert ticks > 50
    assert calls, "no progress reported"
    stage, message, done_, total = calls[-1]
    assert stage == "deriving" and isinstance(message, str) and 0 < done_ <= total
    assert total == result["report"]["symbols"]


def test_threads_run_stages_at_once():
    want = [plain(lamina.venation(shape=s, seed=4)["report"]) for s in ("ovate", "cordate")]
    got = [None, None]

    def grow(k, shape):
        got[k] = plain(lamina.venation(shape=shape, seed=4)["report"])

    threads = [threading.Thread(target=grow, args=(k, s))
               for k, s in enumerate(("ovate", "cordate"))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert got == want


# COMPAS.


def test_compas_network_round_trip(calyx, solved):
    compas = pytest.importorskip("compas")
    from lamina import compas as lc

    g = lc.to_network(calyx)
    assert g.number_of_nodes() == len(calyx["positions"])
    assert g.number_of_edges() == len(calyx["edges"])
    back = lc.from_network(compas.json_loads(compas.json_dumps(g)))
    for k in ("positions", "edges", "node_radius", "edge_radius", "normals"):
        assert np.array_equal(back[k], calyx[k]), k
    assert np.array_equal(lamina.planarize(back, fix_normal=["z<1:0,0,1"])["axes"],
                          solved["axes"])


def test_compas_mesh_round_trip():
    compas = pytest.importorskip("compas")
    from compas.datastructures import Mesh

    from lamina import compas as lc

    mesh = lamina.read_mesh(TORUS)
    m = lc.to_mesh(mesh)
    assert isinstance(m, Mesh)
    back = lc.from_mesh(compas.json_loads(compas.json_dumps(m)))
    assert np.array_equal(back["vertices"], mesh["vertices"])
    assert np.array_equal(back["faces"], mesh["faces"])
    quads = Mesh.from_meshgrid(dx=100, nx=12)
    grid = lc.from_mesh(quads)
    assert len(grid["faces"]) == 2 * 12 * 12
    veins = lamina.veins(grid["vertices"], grid["faces"], sources=[5, 77, 160])
    assert veins["report"]["sources"] == 3


# The documented examples.


class _Point3d:
    def __init__(self, x, y, z):
        self.X, self.Y, self.Z = float(x), float(y), float(z)


class _Line:
    def __init__(self, a, b):
        self.From, self.To = a, b


class _List(list):
    def Add(self, *xyz):
        self.append(xyz)

    def AddFace(self, *corners):
        self.append(corners)

    def ComputeNormals(self):
        pass

    def ConvertQuadsToTriangles(self):
        pass


class _Face:
    def __init__(self, a, b, c):
        self.A, self.B, self.C = a, b, c


class _Mesh:
    """The little of Rhino.Geometry.Mesh the Grasshopper example uses."""

    def __init__(self):
        self.Vertices, self.Faces, self.Normals = _List(), _List(), _List()


@pytest.mark.parametrize("rhino_units", ["mm", "m"])
def test_grasshopper_example_runs_on_the_calyx(monkeypatch, calyx, rhino_units):
    import types

    k = 1000.0 if rhino_units == "m" else 1.0
    rg = types.SimpleNamespace(Point3d=_Point3d, Line=_Line, Mesh=_Mesh, Curve=type(None))
    rhino = types.ModuleType("Rhino")
    rhino.Geometry = rg
    system = type("UnitSystem", (), {"__str__": lambda self: {"mm": "Millimeters",
                                                              "m": "Meters"}[rhino_units]})
    rhino.RhinoDoc = types.SimpleNamespace(
        ActiveDoc=types.SimpleNamespace(ModelUnitSystem=system()))
    monkeypatch.setitem(sys.modules, "Rhino", rhino)
    monkeypatch.setitem(sys.modules, "Rhino.Geometry", rg)
    p, e = calyx["positions"] / k, calyx["edges"]
    surface = lamina.read_mesh(CALYX_SURFACE)
    guide = _Mesh()
    guide.Vertices.extend(_Point3d(*v) for v in surface["vertices"] / k)
    guide.Faces.extend(_Face(*f) for f in surface["faces"])
    scope = {"lines": [_Line(_Point3d(*p[a]), _Point3d(*p[b])) for a, b in e], "guide": guide,
             "height": None, "tolerance": None}
    with warnings.catch_warnings():
        warnings.simplefilter("error", lamina.LaminaWarning)
        exec(compile((ROOT / "python/examples/grasshopper_planarize.py").read_text(),
                     "grasshopper_planarize.py", "exec"), scope)
    want = lamina.planarize(calyx["positions"], calyx["edges"], surface=surface)
    assert len(scope["panels"]) == len(e) == len(want["panels"])
    assert len(scope["axes"]) == len(p)
    got = json.loads(scope["report"])
    assert got["converged"] and got["max_deviation"] <= 0.01
    assert got["iterations"] == want["summary"]["iterations"]


def test_blender_example_compiles():
    compile((ROOT / "python/examples/blender_veins.py").read_text(), "blender_veins.py", "exec")


@pytest.mark.parametrize("doc", ["README.md", "docs/python.md"])
def test_documented_snippets_run(doc, tmp_path):
    """The page's ```python blocks run as written in a scratch folder (fixtures from the
    repository): a block with its own `if __name__ == "__main__":` as the script it shows,
    the others one after the other as one session."""
    text = (ROOT / doc).read_text()
    blocks = [b.replace('"fixtures/', f'"{ROOT}/fixtures/')
              for b in re.findall(r"```python\n(.*?)```", text, flags=re.S)]
    assert blocks
    scripts = [b for b in blocks if 'if __name__ == "__main__":' in b]
    session = "\n".join(b for b in blocks if b not in scripts)
    env = dict(os.environ, TMPDIR=str(tmp_path))
    for k, script in enumerate(([session] if session else []) + scripts):
        (tmp_path / f"snippet{k}.py").write_text(script)
        p = subprocess.run([sys.executable, f"snippet{k}.py"], cwd=tmp_path,
                           capture_output=True, text=True, env=env, timeout=600)
        assert p.returncode == 0, f"{doc}, script {k}:\n{script}\n{p.stderr}"


def test_type_stubs_match_the_package(tmp_path):
    """mypy's stubtest: every stub matches what the installed package has at runtime."""
    pytest.importorskip("mypy")
    allow = Path(__file__).with_name("stubtest-allowlist.txt")
    argv = [sys.executable, "-m", "mypy.stubtest", "lamina", "--allowlist", str(allow),
            "--ignore-unused-allowlist"]
    env = dict(os.environ, TMPDIR=str(tmp_path), MYPY_CACHE_DIR=str(tmp_path / "mypy-cache"))
    p = subprocess.run(argv, capture_output=True, text=True, env=env, cwd=tmp_path)
    assert p.returncode == 0, p.stdout + p.stderr


def test_slice_drops_collapsed_triangles_and_welds_on_request():
    # A cube and 200 slivers whose corners differ only in the sign of zero (binary STL).
    mesh = lamina.read_mesh(ROOT / "fixtures" / "surfaces" / "signed_zero_slivers.stl")
    small = dict(layer=1.0, pixel=0.1, resolution=(400, 300))
    done = lamina.slice(mesh, **small)
    assert any("200 triangles with two corners at one point dropped" in n for n in done["notes"])
    welded = lamina.slice(mesh, weld=0.001, **small)
    assert any("200 triangles collapsed and dropped" in n for n in welded["notes"])
    assert welded["sl1"] == done["sl1"]
    with pytest.raises(lamina.LaminaError, match="weld and weld_rel: give one"):
        lamina.slice(mesh, weld=0.001, weld_rel=1e-6, **small)
    with pytest.raises(lamina.LaminaError, match="weld_rel= must be"):
        lamina.slice(mesh, weld_rel=0.9, **small)
    # No mesh at all is refused, not sliced into one blank layer.
    with pytest.raises(lamina.LaminaError, match="models= none given"):
        lamina.slice([], **small)


def test_slice_supports_any_mesh_as_the_command_does(tmp_path):
    # manifold3d's overhang piece: two islands, held; the same archive as `slice --supports`.
    path = ROOT / "fixtures" / "print" / "manifold_overhang.stl"
    mesh = lamina.read_mesh(path)
    bare = lamina.slice(mesh)
    held = lamina.slice(mesh, supports=True, support_spacing=2.5)
    assert bare["report"]["island_count"] == 2
    assert held["report"]["island_count"] == 0
    assert held["report"]["supports"]["tips"] >= 2
    cli(tmp_path, "slice", path, "--supports", "-o", "lamina.sl1")
    assert held["sl1"] == (tmp_path / "lamina.sl1").read_bytes()
    with pytest.raises(lamina.LaminaError, match="needs supports=True"):
        lamina.slice(mesh, support_tip=0.3)
