"""The lamina Python package against the lamina binary: every function on a small input, the
same results as the command line for the same input and seed (reports byte for byte), errors
as LaminaError with the binary's message, COMPAS round trips.

The binary is $LAMINA_BIN (scripts/test gives target/debug/lamina); the command line runs in a
folder holding its inputs under the names the package gives them, so reports name the same
files."""

import json
import os
import re
import subprocess
import sys
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import lamina

ROOT = Path(__file__).resolve().parents[2]
BIN = os.environ.get("LAMINA_BIN", str(ROOT / "target" / "debug" / "lamina"))
CALYX = ROOT / "fixtures" / "networks" / "calyx_veins.json"
CALYX_SURFACE = ROOT / "fixtures" / "surfaces" / "calyx.obj"
SMALL_LOOP = ROOT / "fixtures" / "networks" / "small_loop.json"
TORUS = ROOT / "fixtures" / "surfaces" / "torus.obj"


def cli(tmp: Path, *argv, ok=(0,)) -> subprocess.CompletedProcess:
    """Runs the binary in `tmp`; fails unless it exits with one of `ok`."""
    p = subprocess.run([BIN, *map(str, argv)], cwd=tmp, capture_output=True, text=True)
    assert p.returncode in ok, p.stderr
    return p


def cli_error(tmp: Path, *argv) -> str:
    """The message the binary prints when it refuses (exit 2)."""
    p = subprocess.run([BIN, *map(str, argv)], cwd=tmp, capture_output=True, text=True)
    assert p.returncode == 2, (p.returncode, p.stdout)
    return p.stderr.strip().splitlines()[-1].removeprefix("lamina: error: ")


def untimed(text: str) -> str:
    """A report without its timings (seconds differ from run to run, on any one machine)."""
    return re.sub(r'"(seconds|elapsed_s|time_s)": [0-9.e+-]+', r'"\1": 0', text)


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
    """The same triangles in the same order, corner for corner (a file may number its vertices
    in another order)."""
    assert np.array_equal(got["vertices"][got["faces"]], want["vertices"][want["faces"]])
    assert len(got["vertices"]) == len(want["vertices"])


@pytest.fixture(scope="module")
def calyx():
    return lamina.read_network(CALYX)


@pytest.fixture(scope="module")
def solved(calyx):
    return lamina.planarize(calyx, fix_normal=["z<1:0,0,1"])


# Growing.


def test_venation_equals_cli(tmp_path):
    py = lamina.venation(shape="lanceolate", mode="open", seed=3)
    cli(tmp_path, "venation", "--shape", "lanceolate", "--mode", "open", "--seed", 3,
        "-o", "venation.json", "--report", "report.json")
    assert py["report_json"] == (tmp_path / "report.json").read_text()
    same_network(py["network"], tmp_path / "venation.json")
    assert py["network"]["meta"]["generator"] == json.loads(
        (tmp_path / "venation.json").read_text())["meta"]["generator"]


def test_venation_in_an_outline(tmp_path):
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    outline = np.column_stack([30 * np.cos(t), 50 + 50 * np.sin(t)])
    py = lamina.venation(outline=outline, root=(0.0, 0.5))
    assert py["report"]["nodes"] == len(py["network"]["positions"]) > 50
    # Every node lies in the circle.
    p = py["network"]["positions"]
    assert np.all(np.hypot(p[:, 0] / 30, (p[:, 1] - 50) / 50) <= 1 + 1e-9)


def test_venation_on_surface_equals_cli(tmp_path):
    mesh = lamina.read_mesh(ROOT / "fixtures" / "surfaces" / "sphere.obj")
    py = lamina.venation_on_surface(mesh["vertices"], mesh["faces"], sources=300, seed=2)
    lamina.write_mesh(tmp_path / "surface.obj", mesh)
    cli(tmp_path, "venation", "--surface", "surface.obj", "--sources", 300, "--seed", 2,
        "-o", "venation.json", "--report", "report.json")
    assert py["report_json"] == (tmp_path / "report.json").read_text()
    same_network(py["network"], tmp_path / "venation.json")


def test_veins_equals_cli(tmp_path):
    mesh = lamina.read_mesh(TORUS)
    py = lamina.veins(mesh["vertices"], mesh["faces"], sources=60, seed=5)
    lamina.write_mesh(tmp_path / "surface.obj", mesh)
    cli(tmp_path, "veins", "--surface", "surface.obj", "--sources", 60, "--seed", 5,
        "-o", "veins.json", "--report", "report.json")
    assert py["report_json"] == (tmp_path / "report.json").read_text()
    same_network(py["network"], tmp_path / "veins.json")
    assert 0 < py["report"]["sources"] <= 60  # about this many, Poisson-disk sampled


def test_lsystem_equals_cli(tmp_path):
    rules = {"X": "F[-X]F[+X]-X", "F": "FF"}
    py = lamina.lsystem(axiom="X", rules=rules, iterations=4, angle=25.0)
    cli(tmp_path, "lsystem", "--axiom", "X", "--rule", "X=F[-X]F[+X]-X", "--rule", "F=FF",
        "--iterations", 4, "--angle", 25, "-o", "lsystem.json", "--report", "report.json")
    assert py["report_json"] == (tmp_path / "report.json").read_text()
    same_network(py["network"], tmp_path / "lsystem.json")
    counts = lamina.lsystem(axiom="X", rules=rules, iterations=7, derive_only=True)["report"]
    want = json.loads(cli(tmp_path, "lsystem", "--axiom", "X", "--rule", "X=F[-X]F[+X]-X",
                          "--rule", "F=FF", "-n", 7, "--derive-only", "--json").stdout)
    assert counts == want


# Rationalizing.


def test_cells_equals_cli(tmp_path, calyx):
    surface = lamina.read_mesh(CALYX_SURFACE)
    py = lamina.cells(calyx, surface=surface)
    lamina.write_network(tmp_path / "network.json", calyx)
    lamina.write_mesh(tmp_path / "surface.obj", surface)
    cli(tmp_path, "cells", "network.json", "--surface", "surface.obj", "-o", "cells.obj",
        "--table", "table.json")
    assert py["table_json"] == (tmp_path / "table.json").read_text()
    obj = (tmp_path / "cells.obj").read_text().splitlines()
    rows = {k: [line.split()[1:] for line in obj if line.startswith(k + " ")]
            for k in ("v", "vn", "f")}
    assert np.array_equal(py["mesh"]["vertices"], np.array(rows["v"], dtype=float))
    assert np.array_equal(py["normals"], np.array(rows["vn"], dtype=float))
    faces = [[int(t.split("/")[0]) - 1 for t in f] for f in rows["f"]]
    assert np.array_equal(py["mesh"]["faces"], faces)
    # One vertex per node, where the node is.
    assert np.array_equal(py["mesh"]["vertices"], calyx["positions"])


def test_planarize_equals_cli(tmp_path, calyx, solved):
    lamina.write_network(tmp_path / "network.json", calyx)
    cli(tmp_path, "planarize", "network.json", "--fix-normal", "z<1:0,0,1", "-o", "axes.json",
        "--report", "report.json", "--panels", "panels.obj")
    assert untimed(solved["report_json"]) == untimed((tmp_path / "report.json").read_text())
    assert solved["axes_json"] == (tmp_path / "axes.json").read_text()
    axes = json.loads(solved["axes_json"])
    assert np.array_equal(solved["axes"], [n["axis"] for n in axes["nodes"]])
    assert solved["within"] and solved["summary"]["converged"]
    assert np.allclose(np.linalg.norm(solved["axes"], axis=1), 1.0)
    # The panels are the quads the command writes.
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
    lamina.write_network(tmp_path / "network.json", lamina.read_network(CALYX))
    cli(tmp_path, "planarize", "network.json", "--fix-normal", "z<1:0,0,1", "-o", "axes.json",
        "--panels", "panels.obj")
    py = lamina.audit(str(tmp_path / "panels.obj"), tolerance=0.01)
    cli(tmp_path, "audit", "panels.obj", "--tolerance", 0.01, "--report", "report.json")
    text = (tmp_path / "report.json").read_text()
    assert py["report_json"] == text.replace('"panels.obj"', json.dumps(
        str(tmp_path / "panels.obj"))).replace("audit of panels.obj",
                                               f"audit of {tmp_path / 'panels.obj'}")
    # Panels from memory: the same figures.
    mem = lamina.audit(list(solved["panels"]), tolerance=0.01)
    assert mem["report"]["summary"] == json.loads(text)["summary"]
    assert mem["within"]


# Steel.


@pytest.fixture(scope="module")
def steel(tmp_path_factory, calyx, solved):
    tmp = tmp_path_factory.mktemp("steel")
    lamina.write_network(tmp / "network.json", calyx)
    cli(tmp, "planarize", "network.json", "--fix-normal", "z<1:0,0,1", "-o", "axes.json")
    sizing = lamina.size(solved, support="z<1", load="self-weight", deflection_limit="L/500")
    cli(tmp, "size", "axes.json", "-o", "sizing.json", "--support", "z<1", "--load",
        "self-weight", "--deflection-limit", "L/500", ok=(0, 1))
    plates = lamina.plates(solved, sizing=sizing, groups=7)
    cli(tmp, "plates", "axes.json", "--sizing", "sizing.json", "--groups", 7, "-o", "plates",
        ok=(0, 1))
    cut = lamina.nest(plates, sheet="3000x1500", margin=10, spacing=5, lead_in=2)
    cli(tmp, "nest", "plates/plates.json", "--sheet", "3000x1500", "--margin", 10, "--spacing",
        5, "--lead-in", 2, "-o", "cut")
    return tmp, sizing, plates, cut


def files_under(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_size_equals_cli(steel):
    tmp, sizing, _, _ = steel
    assert sizing["sizing_json"] == (tmp / "sizing.json").read_text()
    assert sizing["sizing"]["format"] == "lamina-sizing"


def test_plates_equals_cli(steel):
    tmp, _, plates, _ = steel
    assert plates["plates_json"] == (tmp / "plates" / "plates.json").read_text()
    want = files_under(tmp / "plates")
    assert sorted(plates["files"]) == sorted(want)
    # The reports name their source: the package's is its own axes.json.
    for name, data in want.items():
        assert plates["files"][name] == data, name
    assert len(plates["plates"]["plates"]) > 100
    assert plates["assembly"]["faces"].shape[1] == 3


def test_nest_equals_cli(steel):
    tmp, _, _, cut = steel
    assert cut["nest_json"] == (tmp / "cut" / "nest.json").read_text()
    want = files_under(tmp / "cut")
    assert sorted(cut["files"]) == sorted(want)
    for name, data in want.items():
        assert cut["files"][name] == data, name


# Printing.


def test_solid_and_slice_equal_cli(tmp_path):
    net = lamina.read_network(SMALL_LOOP)
    py = lamina.solid(net, cell=0.25)
    lamina.write_network(tmp_path / "network.json", net)
    cli(tmp_path, "solid", "network.json", "--cell", 0.25, "-o", "solid.obj", "--report",
        "report.json")
    assert untimed(py["report_json"]) == untimed((tmp_path / "report.json").read_text())
    same_triangles(py["mesh"], lamina.read_mesh(tmp_path / "solid.obj"))

    printed = lamina.slice(py["mesh"], layer=0.05)
    lamina.write_mesh(tmp_path / "model-0.obj", py["mesh"])
    cli(tmp_path, "slice", "model-0.obj", "--layer", 0.05, "-o", "print.sl1", "--report",
        "print.json")
    assert untimed(printed["report_json"]) == untimed((tmp_path / "print.json").read_text())
    assert printed["sl1"] == (tmp_path / "print.sl1").read_bytes()
    assert printed["report"]["layers"] > 10


# Errors: LaminaError with the binary's message.


def test_bad_flag_value_is_the_cli_message(tmp_path, calyx):
    lamina.write_network(tmp_path / "network.json", calyx)
    with pytest.raises(lamina.LaminaError) as e:
        lamina.size(str(tmp_path / "nothing.json"), support="z<1", load="self-weight")
    assert str(e.value) == cli_error(tmp_path, "size", tmp_path / "nothing.json", "-o", "s.json",
                                     "--support", "z<1", "--load", "self-weight")
    with pytest.raises(lamina.LaminaError) as e:
        lamina.solid(calyx, cell=-1.0)
    assert str(e.value) == cli_error(tmp_path, "solid", "network.json", "--cell=-1", "-o",
                                     "solid.obj")


def test_bad_arrays_raise(calyx):
    with pytest.raises(lamina.LaminaError, match="index 248 is not one of the 248 points"):
        lamina.planarize(calyx["positions"], [[0, 248]], calyx["normals"])
    with pytest.raises(lamina.LaminaError, match="N×3"):
        lamina.planarize(calyx["positions"][:, :2], calyx["edges"])
    bad = calyx["positions"].copy()
    bad[3, 1] = np.nan
    with pytest.raises(lamina.LaminaError, match="node 3"):
        lamina.planarize(bad, calyx["edges"], calyx["normals"])
    with pytest.raises(lamina.LaminaError, match="unexpected argument"):
        lamina.planarize(calyx, no_such_flag=1)
    with pytest.raises(lamina.LaminaError):
        lamina.venation(shape="hexagon")


def test_notes_are_warnings(solved):
    with pytest.warns(lamina.LaminaWarning, match="material 1.4404"):
        lamina.size(solved, support="z<1", load="self-weight")


# Threads and progress.


PAPER = {"X": "F[-X]F[+X]-X", "F": "FF"}


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
    # While the derivation ran, this thread kept the interpreter (the GIL was released).
    assert ticks > 50
    assert calls, "no progress reported"
    stage, message, done_, total = calls[-1]
    assert stage == "deriving" and isinstance(message, str) and 0 < done_ <= total
    assert total == result["report"]["symbols"]


def test_progress_callback_errors_propagate():
    def boom(*_):
        raise RuntimeError("stop")

    with pytest.raises(RuntimeError, match="stop"):
        lamina.lsystem(axiom="X", rules=PAPER, iterations=15, derive_only=True, progress=boom)


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
    # A network that came through COMPAS solves to the same axes.
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
    # A quad mesh from COMPAS, triangulated, grows veins.
    quads = Mesh.from_meshgrid(dx=100, nx=12)
    grid = lc.from_mesh(quads)
    assert len(grid["faces"]) == 2 * 12 * 12
    veins = lamina.veins(grid["vertices"], grid["faces"], sources=[5, 77, 160])
    assert veins["report"]["sources"] == 3


# The documented examples.


class _Point3d:
    def __init__(self, x, y, z):
        self.X, self.Y, self.Z = float(x), float(y), float(z)

    def __add__(self, other):
        return _Point3d(self.X + other[0], self.Y + other[1], self.Z + other[2])


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


def test_grasshopper_example_runs_on_the_calyx(monkeypatch, calyx, solved):
    import sys
    import types

    rg = types.SimpleNamespace(Point3d=_Point3d, Line=_Line, Mesh=_Mesh, Curve=type(None))
    rhino = types.ModuleType("Rhino")
    rhino.Geometry = rg
    monkeypatch.setitem(sys.modules, "Rhino", rhino)
    monkeypatch.setitem(sys.modules, "Rhino.Geometry", rg)
    p, e = calyx["positions"], calyx["edges"]
    surface = lamina.read_mesh(CALYX_SURFACE)
    guide = _Mesh()
    guide.Vertices.extend(_Point3d(*v) for v in surface["vertices"])
    guide.Faces.extend(_Face(*f) for f in surface["faces"])
    scope = {"lines": [_Line(_Point3d(*p[a]), _Point3d(*p[b])) for a, b in e], "guide": guide,
             "height": 100.0, "tolerance": 0.01}
    exec(compile((ROOT / "python/examples/grasshopper_planarize.py").read_text(),
                 "grasshopper_planarize.py", "exec"), scope)
    want = lamina.planarize(calyx["positions"], calyx["edges"], surface=surface)
    assert len(scope["panels"]) == len(e) == len(want["panels"])
    assert len(scope["axes"]) == len(p)
    # The same network with its nodes in another order (the example numbers them by position):
    # the same solve up to rounding.
    got = json.loads(scope["report"])
    assert got["converged"] and got["max_deviation"] <= 0.01
    assert got["iterations"] == want["summary"]["iterations"]
    assert abs(got["max_deviation"] - want["summary"]["max_deviation"]) < 1e-6


def test_blender_example_compiles():
    compile((ROOT / "python/examples/blender_veins.py").read_text(), "blender_veins.py", "exec")


@pytest.mark.parametrize("doc", ["README.md", "docs/python.md"])
def test_documented_snippets_run(doc, tmp_path, monkeypatch):
    """The page's ```python blocks run as written, one after the other (fixtures from the
    repository; files they write land in a scratch folder)."""
    text = (ROOT / doc).read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks
    monkeypatch.chdir(tmp_path)
    scope = {}
    for block in blocks:
        block = block.replace('"fixtures/', f'"{ROOT}/fixtures/')
        exec(compile(block, doc, "exec"), scope)


def test_type_stubs_match_the_package():
    """mypy's stubtest: every stub matches what the installed package has at runtime."""
    pytest.importorskip("mypy")
    allow = Path(__file__).with_name("stubtest-allowlist.txt")
    # The allowlist holds an entry only older Pythons need.
    argv = [sys.executable, "-m", "mypy.stubtest", "lamina", "--allowlist", str(allow),
            "--ignore-unused-allowlist"]
    p = subprocess.run(argv, capture_output=True, text=True,
                       cwd=Path(lamina.__file__).parents[2])
    assert p.returncode == 0, p.stdout + p.stderr


def test_threads_run_commands_at_once():
    """Two threads, each its own captured command: the same results as one after the other."""
    want = [lamina.venation(shape=s, seed=4)["report_json"] for s in ("ovate", "cordate")]
    got = [None, None]

    def grow(k, shape):
        got[k] = lamina.venation(shape=shape, seed=4)["report_json"]

    threads = [threading.Thread(target=grow, args=(k, s))
               for k, s in enumerate(("ovate", "cordate"))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert got == want


def test_no_folder_left_behind(calyx):
    """The private folders are removed, after a failure too."""
    import tempfile

    def ours():
        return {p for p in os.listdir(tempfile.gettempdir()) if p.startswith("lamina-")}

    before = ours()
    lamina.solid(lamina.read_network(SMALL_LOOP), cell=0.5)
    with pytest.raises(lamina.LaminaError):
        lamina.size(lamina.planarize(calyx, fix_normal=["z<1:0,0,1"]), support="z<1",
                    load="nothing:1")
    assert ours() <= before


def test_solid_with_the_blade_from_meta_equals_cli(tmp_path):
    """The leaf's outline travels in the network's meta: --lamina finds it in memory too."""
    leaf = lamina.venation(shape="circle", seed=2)["network"]
    assert "outline" in leaf["meta"]["parameters"]
    py = lamina.solid(leaf, fit=10, lamina=0.3, cell=0.1)
    lamina.write_network(tmp_path / "network.json", leaf)
    cli(tmp_path, "solid", "network.json", "--fit", 10, "--lamina", 0.3, "--cell", 0.1,
        "-o", "solid.obj", "--report", "report.json")
    assert untimed(py["report_json"]) == untimed((tmp_path / "report.json").read_text())
    same_triangles(py["mesh"], lamina.read_mesh(tmp_path / "solid.obj"))


def test_command_help_and_refused_reader_flags(calyx):
    assert lamina.command("planarize", "--help").startswith("Node axes that make every panel")
    assert lamina.command("--version").strip() == f"lamina {lamina.__version__}"
    with pytest.raises(lamina.LaminaError, match="reader flags"):
        lamina.planarize(calyx, weld=0.1)
    with pytest.raises(lamina.LaminaError, match="reader flags"):
        lamina.solid(calyx, split_crossings=True)


def test_slice_refuses_bad_meshes():
    mesh = lamina.read_mesh(TORUS)
    bad = mesh["vertices"].copy()
    bad[3, 2] = np.inf
    with pytest.raises(lamina.LaminaError, match="model-0.obj: vertex 3: coordinate is not finite"):
        lamina.slice((bad, mesh["faces"]))
    with pytest.raises(lamina.LaminaError, match="model 1: faces: index"):
        lamina.slice([mesh, (mesh["vertices"], mesh["faces"] + len(mesh["vertices"]))])
    with pytest.raises(lamina.LaminaError, match="--copies"):
        lamina.slice(mesh, copies=0)


def test_files_other_tools_wrote_and_extreme_values(tmp_path):
    """OpenSCAD's STL sliced from memory and ezdxf's DXF made solid, each equal to the command
    line on the file itself; 0, negative, NaN and huge values refused as the command refuses
    them."""
    part = lamina.read_mesh(ROOT / "fixtures/surfaces/openscad_part.stl")
    printed = lamina.slice(part)
    lamina.write_mesh(tmp_path / "model-0.obj", part)
    cli(tmp_path, "slice", "model-0.obj", "-o", "print.sl1", "--report", "print.json")
    assert untimed(printed["report_json"]) == untimed((tmp_path / "print.json").read_text())
    veins = lamina.read_network(ROOT / "fixtures/networks/ezdxf_veins.dxf")
    made = lamina.solid(veins, radius=0.5, cell=0.25)
    lamina.write_network(tmp_path / "network.json", veins)
    cli(tmp_path, "solid", "network.json", "--radius", 0.5, "--cell", 0.25, "-o", "solid.obj",
        "--report", "report.json")
    assert untimed(made["report_json"]) == untimed((tmp_path / "report.json").read_text())
    flat = dict(veins, normals=np.tile([0.0, 0.0, 1.0], (len(veins["positions"]), 1)))
    for value in (0.0, -1.0, float("nan"), 1e300):
        calls = (lambda: lamina.planarize(flat, height=value),
                 lambda: lamina.solid(veins, radius=0.5, cell=value),
                 lambda: lamina.slice(part, layer=value))
        for call in calls:
            with pytest.raises(lamina.LaminaError):
                call()
