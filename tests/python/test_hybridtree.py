"""The Python module against the C++ tape (through the CLI), its argument checks and errors, its
meshes (byte-identical to `hybridtree mesh`), its threads, and the README's "Python" block."""
import concurrent.futures
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import hybridtree
from conftest import SOURCE, run_cli

GARDEN = str(SOURCE / "examples" / "bunny_garden.json")


# --- random scenes --------------------------------------------------------------------------

def random_leaf(rng):
    c = lambda: [round(float(x), 3) for x in rng.uniform(-1.0, 1.0, 3)]
    r = round(float(rng.uniform(0.3, 0.9)), 3)
    kind = rng.integers(5)
    if kind == 0:
        return {"type": "point", "center": c(), "radius": r, "strength": round(float(rng.uniform(0.6, 2.0)), 3)}
    if kind == 1:
        return {"type": "segment", "a": c(), "b": c(), "radius": r}
    if kind == 2:
        lo = c()
        return {"type": "box", "min": lo, "max": [x + 0.5 for x in lo], "radius": r}
    if kind == 3:
        return {"type": "circle", "center": c(), "normal": [0, 0, 1], "circle_radius": 0.4, "radius": r}
    return {"type": "cylinder", "a": c(), "b": c(), "cylinder_radius": 0.2, "radius": r}


def random_node(rng, depth):
    if depth >= 3 or rng.random() < 0.3:
        return random_leaf(rng)
    kind = ["blend", "union", "intersection", "difference", "twist", "affine"][rng.integers(6)]
    if kind == "twist":
        return {"type": "twist", "axis": "z", "rate": round(float(rng.uniform(-2, 2)), 3),
                "child": random_node(rng, depth + 1)}
    if kind == "affine":
        return {"type": "affine", "translate": [0.1, -0.2, 0.3], "child": random_node(rng, depth + 1)}
    children = [random_node(rng, depth + 1) for _ in range(int(rng.integers(2, 4)))]
    return {"type": kind, "children": children}


def random_scene(seed):
    rng = np.random.default_rng(seed)
    return {"hybridtree": 1, "threshold": 0.5, "root": random_node(rng, 0)}


@pytest.mark.parametrize("seed", range(12))
def test_values_equal_the_cli_tape_on_random_trees(tmp_path, seed):
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(random_scene(seed)))
    points = np.random.default_rng(100 + seed).uniform(-2.0, 2.0, (2000, 3))
    np.save(tmp_path / "points.npy", points)
    run_cli("eval", scene, "--points", tmp_path / "points.npy", "-o", tmp_path / "cli.npy", "--gradient")
    cli = np.load(tmp_path / "cli.npy")
    tree = hybridtree.load(str(scene))
    assert np.array_equal(tree.field(points), cli[:, 0])
    assert np.array_equal(tree.gradient(points), cli[:, 1:])
    # The same scene as text, and float32 or strided points (copied to float64 first).
    same = hybridtree.loads(scene.read_text())
    assert np.array_equal(same.field(points, threads=1), cli[:, 0])
    wide = np.zeros((2000, 6))
    wide[:, ::2] = points
    assert np.array_equal(tree.field(wide[:, ::2]), cli[:, 0])
    p32 = points.astype(np.float32)
    assert np.array_equal(tree.field(p32), tree.field(p32.astype(np.float64)))


# --- arguments and errors -------------------------------------------------------------------

@pytest.fixture(scope="module")
def garden():
    return hybridtree.load(GARDEN)


@pytest.mark.parametrize("bad, kind, message", [
    ([[0.0, 0.0, 0.0]], TypeError, "points: expected a NumPy array of shape (N, 3) and dtype float64 or float32, not list"),
    (np.zeros((4, 2)), ValueError, "points: expected an array of shape (N, 3), got shape (4, 2)"),
    (np.zeros(3), ValueError, "points: expected an array of shape (N, 3), got shape (3,)"),
    (np.zeros((2, 3, 1)), ValueError, "points: expected an array of shape (N, 3), got shape (2, 3, 1)"),
    (np.zeros((4, 3), dtype=np.int64), TypeError, "points: expected dtype float64 or float32, got int64"),
    (np.zeros((4, 3), dtype=np.complex128), TypeError, "points: expected dtype float64 or float32, got complex128"),
    (np.zeros((4, 3), dtype=np.float16), TypeError, "points: expected dtype float64 or float32, got float16"),
])
def test_wrong_shapes_and_dtypes_raise(garden, bad, kind, message):
    for call in (garden.field, garden.gradient):
        with pytest.raises(kind) as e:
            call(bad)
        assert str(e.value) == message


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_points_that_are_not_finite_raise(garden, value):
    p = np.zeros((5, 3))
    p[3, 2] = value
    with pytest.raises(hybridtree.InputError) as e:
        garden.field(p)
    assert str(e.value) == "points[3]: coordinate 2 is not a finite number"
    assert e.value.path == "points[3]"
    assert isinstance(e.value, ValueError) and isinstance(e.value, hybridtree.Error)


def test_empty_points_give_empty_arrays(garden):
    assert garden.field(np.zeros((0, 3))).shape == (0,)
    assert garden.gradient(np.zeros((0, 3))).shape == (0, 3)


@pytest.mark.parametrize("text, path", [
    ('{"hybridtree": 1, "root": {"type": "point", "center": [0, 0, 0], "radius": -1}}', "root.radius"),
    ('{"hybridtree": 1, "root": {"type": "blend", "children": [{"type": "nope"}]}}', "root.children[0].type"),
    ('{"hybridtree": 2, "root": {}}', "hybridtree"),
    ('{"hybridtree": 1, "root": ', ""),
    ('{"hybridtree": 1, "root": {"type": "mesh", "file": "missing.off", "radius": 0.1}}', "root.file"),
])
def test_bad_scenes_raise_the_cli_messages(tmp_path, text, path):
    scene = tmp_path / "bad.json"
    scene.write_text(text)
    cli = run_cli("info", scene, check=False)
    assert cli.returncode == 2
    with pytest.raises(hybridtree.SceneError) as e:
        hybridtree.load(str(scene))
    assert cli.stderr == "hybridtree: " + str(e.value) + "\n"
    assert e.value.file == str(scene) and e.value.path == path


def test_missing_scene_file_raises(tmp_path):
    with pytest.raises(hybridtree.SceneError, match="cannot open the scene file") as e:
        hybridtree.load(str(tmp_path / "none.json"))
    assert e.value.file == str(tmp_path / "none.json")


def test_builder_checks_and_builds():
    b = hybridtree.Builder(0.5)
    with pytest.raises(hybridtree.InputError) as e:
        b.point((0, 0, 0), radius=-1.0)
    assert str(e.value) == "radius: must be > 0" and e.value.path == "radius"
    with pytest.raises(hybridtree.InputError):
        b.blend([7])
    a = b.point((0, 0, 0), radius=1.0)
    s = b.segment((0.5, 0, 0), (1.5, 0, 0), radius=0.8)
    tree = b.build(b.blend([a, s]))
    text = hybridtree.loads(json.dumps({"hybridtree": 1, "root": {"type": "blend", "children": [
        {"type": "point", "center": [0, 0, 0], "radius": 1.0},
        {"type": "segment", "a": [0.5, 0, 0], "b": [1.5, 0, 0], "radius": 0.8}]}}))
    p = np.random.default_rng(3).uniform(-2, 2, (500, 3))
    assert np.array_equal(tree.field(p), text.field(p))


def test_builder_modes_ffd_names_hints_and_json():
    b = hybridtree.Builder(0.5)
    a = b.point((0, 0, 0), radius=1.0)
    c = b.point((0.6, 0, 0), radius=1.0)
    u = b.unite([a, c], boolean="rfunction")
    b.set_name(u, "pair")
    b.set_mesher(u, "global")
    with pytest.raises(ValueError):
        b.unite([a, c], boolean="smooth")
    with pytest.raises(ValueError):
        b.set_mesher(u, "fast")
    lattice = np.array([(x, y, z) for z in (-2, 2) for y in (-2, 2) for x in (-2, 2)], dtype=np.float64)
    f = b.ffd(b.box((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5), radius=0.3), (-2, -2, -2), (2, 2, 2), (1, 1, 1), lattice,
              radius=0.1)
    tree = b.build(b.blend([u, f]))
    scene = json.loads(tree.to_json())
    assert scene["root"]["children"][0]["name"] == "pair"
    # Under a blend, auto means R-functions: the optimized tree may say either.
    assert scene["root"]["children"][0].get("boolean", "auto") in ("auto", "rfunction")
    assert scene["root"]["children"][0]["mesher"] == "global"
    assert scene["root"]["children"][1]["type"] == "ffd"
    back = hybridtree.loads(tree.to_json())
    p = np.random.default_rng(4).uniform(-1.5, 1.5, (300, 3))
    assert np.allclose(tree.field(p), back.field(p), atol=1e-6)


def test_mesh_options_are_checked(garden):
    with pytest.raises(hybridtree.InputError, match="precision: must be >= 0"):
        garden.mesh(precision=-1.0)
    with pytest.raises(ValueError, match="strategy"):
        garden.mesh(strategy="fast")
    with pytest.raises(hybridtree.MemoryBudgetError) as e:
        garden.mesh(precision=0.002, memory_budget_gib=0.001)
    assert e.value.file == GARDEN and isinstance(e.value, hybridtree.MeshingError)


def test_meshing_errors_have_the_cli_message(tmp_path):
    scene = tmp_path / "point.json"
    scene.write_text(json.dumps({"hybridtree": 1, "root": {"type": "point", "center": [0, 0, 0], "radius": 1}}))
    cli = run_cli("mesh", scene, "-o", tmp_path / "out.ply", "--precision", 1e-8, "--strategy", "global", check=False)
    assert cli.returncode == 2
    with pytest.raises(hybridtree.MeshingError) as e:
        hybridtree.load(str(scene)).mesh(precision=1e-8, strategy="global")
    assert cli.stderr == "hybridtree: " + str(e.value) + "\n"
    assert e.value.file == str(scene)


def test_write_mesh_checks(tmp_path):
    v = np.zeros((3, 3))
    with pytest.raises(hybridtree.InputError, match="unsupported output extension"):
        hybridtree.write_mesh(str(tmp_path / "a.xyz"), v, np.array([[0, 1, 2]]))
    with pytest.raises(hybridtree.InputError, match="names vertex 5 of 3"):
        hybridtree.write_mesh(str(tmp_path / "a.ply"), v, np.array([[0, 1, 5]]))
    with pytest.raises(ValueError, match="out of range"):
        hybridtree.write_mesh(str(tmp_path / "a.ply"), v, np.array([[0, 1, -1]]))
    with pytest.raises(hybridtree.WriteError):
        hybridtree.write_mesh(str(tmp_path / "no" / "a.ply"), v, np.array([[0, 1, 2]], dtype=np.uint32))


# --- meshing ----------------------------------------------------------------------------------

@pytest.mark.parametrize("strategy", ["auto", "global"])
def test_mesh_is_byte_identical_to_the_cli(tmp_path, garden, strategy):
    h = 0.03
    run_cli("mesh", GARDEN, "-o", tmp_path / "cli.ply", "--precision", h, "--strategy", strategy,
            "--stats-json", tmp_path / "cli.json")
    fractions = []
    vertices, triangles, stats = garden.mesh(precision=h, strategy=strategy, progress=fractions.append)
    assert vertices.dtype == np.float64 and vertices.shape[1] == 3
    assert triangles.dtype == np.uint32 and triangles.shape[1] == 3
    hybridtree.write_mesh(str(tmp_path / "py.ply"), vertices, triangles)
    assert (tmp_path / "py.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()
    cli = json.loads((tmp_path / "cli.json").read_text())
    assert stats["triangles"] == cli["triangles"] == len(triangles)
    assert stats["checks"] == cli["checks"] and stats["strategy"] == strategy
    assert fractions and fractions == sorted(fractions) and fractions[-1] == 1.0


def test_mesh_is_the_same_at_any_thread_count(garden):
    one = garden.mesh(precision=0.04, threads=1)
    two = garden.mesh(precision=0.04, threads=2)
    assert np.array_equal(one[0], two[0]) and np.array_equal(one[1], two[1])


def test_progress_can_cancel_and_errors_in_it_propagate(garden):
    with pytest.raises(hybridtree.CancelledError):
        garden.mesh(precision=0.03, progress=lambda f: False)

    def boom(f):
        raise KeyError("from the callback")
    with pytest.raises(KeyError, match="from the callback"):
        garden.mesh(precision=0.03, progress=boom)


# --- threads ----------------------------------------------------------------------------------

def test_many_threads_on_one_tree_give_the_single_thread_results(garden):
    points = np.random.default_rng(7).uniform(-1.0, 1.0, (20000, 3))
    values = garden.field(points, threads=1)
    grads = garden.gradient(points, threads=1)

    def work(i):
        t = 1 + i % 2
        return garden.field(points, threads=t), garden.gradient(points, threads=t)
    with concurrent.futures.ThreadPoolExecutor(max_workers=8) as pool:
        for f, g in pool.map(work, range(16)):
            assert np.array_equal(f, values) and np.array_equal(g, grads)


# --- the README -------------------------------------------------------------------------------

def test_the_readme_python_block_runs_as_printed(tmp_path):
    blocks = SOURCE / "tests" / "embedding" / "readme_blocks.py"
    code = subprocess.run([sys.executable, str(blocks), str(SOURCE / "README.md"), "Python", "python"],
                          capture_output=True, text=True, check=True).stdout
    (tmp_path / "examples").symlink_to(SOURCE / "examples")
    (tmp_path / "data").symlink_to(SOURCE / "data")
    subprocess.run([sys.executable, "-c", code], cwd=tmp_path, check=True, env=dict(os.environ))
    assert (tmp_path / "garden.ply").stat().st_size > 0
