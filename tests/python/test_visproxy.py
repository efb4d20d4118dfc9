"""The Python module against the library's guarantees and the CLI's own output.

Run by CTest (tests/CMakeLists.txt) with PYTHONPATH at the built module and, in the
environment, VISPROXY_CLI (the visproxy executable), VISPROXY_MESH_DIR (the libcgal-demo
meshes) and VISPROXY_SOURCE_DIR.
"""

import json
import os
import pathlib
import subprocess
import sys
import threading

import numpy as np
import pytest

import visproxy as vp

CLI = os.environ.get("VISPROXY_CLI", "visproxy")
MESHES = pathlib.Path(os.environ["VISPROXY_MESH_DIR"])
SOURCE = pathlib.Path(os.environ["VISPROXY_SOURCE_DIR"])
KNOT = MESHES / "knot1.off"  # closed, 6400 triangles
ELEPHANT = MESHES / "elephant-with-holes.off"  # open

EVERY_BUILDER = ["aabb", "obb", "hull", "hull:32", "wrap", "outer:64", "quadric:200", "cluster:0.05",
                 "inside:10", "spheres:30,10"]


def cli(*arguments, check=True):
    result = subprocess.run([CLI, *map(str, arguments)], capture_output=True, text=True)
    if check:
        assert result.returncode == 0, result.stderr
    return result


@pytest.fixture(scope="module")
def knot():
    return vp.read_mesh(KNOT)


@pytest.fixture(scope="module")
def knot_proxies(knot):
    return vp.build(*knot, EVERY_BUILDER, seed=7)


# ---- meshes as numpy arrays ---------------------------------------------------------

def test_read_mesh_gives_float64_vertices_and_int64_triangles(knot):
    vertices, triangles = knot
    assert vertices.dtype == np.float64 and vertices.shape == (3200, 3)
    assert triangles.dtype == np.int64 and triangles.shape == (6400, 3)
    assert triangles.min() == 0 and triangles.max() == 3199
    report = vp.inspect(vertices, triangles)
    assert report["closed"] and report["watertight"] and report["components"] == 1
    assert report["triangles"] == 6400 and report["volume"] > 0


@pytest.mark.parametrize("extension", ["ply", "obj"])
def test_meshes_round_trip_through_every_format(tmp_path, knot, extension):
    vertices, triangles = knot
    path = tmp_path / f"knot.{extension}"
    vp.write_mesh(path, vertices, triangles)
    again_vertices, again_triangles = vp.read_mesh(path, weld="never")
    assert np.array_equal(again_triangles, triangles)
    assert np.array_equal(again_vertices, vertices)  # doubles, exactly


def test_arrays_of_other_types_and_layouts_are_read_as_their_values(knot):
    vertices, triangles = knot
    reference = vp.inspect(vertices, triangles)
    # float32 vertices, uint32 triangles, Fortran order, and a strided view
    fortran = np.asfortranarray(vertices.astype(np.float32).astype(np.float64))
    for v, t in [(fortran, triangles.astype(np.uint32)), (vertices, triangles.astype(np.int32)),
                 (np.hstack([vertices, vertices])[:, :3], np.hstack([triangles, triangles])[:, 3:])]:
        report = vp.inspect(v, t)
        assert report["triangles"] == reference["triangles"]
        assert report["watertight"]
        assert report["volume"] == pytest.approx(reference["volume"], rel=1e-6)


# ---- every builder --------------------------------------------------------------------

def test_every_builder_returns_its_proxies_as_arrays_with_their_manifest_entries(knot, knot_proxies):
    vertices, _ = knot
    names = [proxy["name"] for proxy in knot_proxies]
    assert names == ["aabb", "obb", "hull", "hull-32", "wrap", "outer-64", "quadric-200", "cluster-0.05", "inside-10",
                     "spheres-30", "spheres-10"]
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    for proxy in knot_proxies:
        entry = proxy["manifest"]
        assert entry["name"] == proxy["name"] and entry["kind"] == proxy["kind"]
        assert proxy["kind"] in ("outside", "inside", "general")
        if proxy["primitive_type"] == "sphere":
            spheres = proxy["spheres"]
            assert proxy["vertices"] is None and spheres.dtype == np.float64 and spheres.shape[1] == 4
            assert 0 < len(spheres) <= int(proxy["name"].split("-")[1])
            assert len(spheres) == entry["primitives"]
            assert (spheres[:, 3] > 0).all()
        else:
            assert proxy["spheres"] is None
            assert proxy["vertices"].shape[1] == 3 and proxy["triangles"].shape[1] == 3
            assert proxy["triangles"].max() < len(proxy["vertices"])
            if proxy["kind"] == "outside":  # an outside proxy's box holds the mesh's
                assert (proxy["vertices"].min(axis=0) <= low).all() and (proxy["vertices"].max(axis=0) >= high).all()
    hull32 = knot_proxies[names.index("hull-32")]
    assert len(hull32["triangles"]) <= 32 * 30  # at most 32 faces, triangulated
    assert len(knot_proxies[names.index("quadric-200")]["triangles"]) <= 200


def test_builders_at_once_give_the_proxies_of_one_after_another(knot, knot_proxies):
    one = vp.build(*knot, EVERY_BUILDER, seed=7, builders_at_once=1)
    three = vp.build(*knot, EVERY_BUILDER, seed=7, builders_at_once=3)
    assert [p["name"] for p in one] == [p["name"] for p in knot_proxies] == [p["name"] for p in three]
    for a, b, c in zip(one, three, knot_proxies):
        for key in ("vertices", "triangles", "spheres"):
            if a[key] is None:
                assert b[key] is None and c[key] is None
            else:
                assert np.array_equal(a[key], b[key]) and np.array_equal(a[key], c[key])
        entries = [{k: v for k, v in p["manifest"].items() if k != "build_seconds"} for p in (a, b, c)]
        assert entries[0] == entries[1] == entries[2]


def test_every_claim_of_every_builder_is_verified(knot, knot_proxies):
    verdicts = vp.verify(*knot, knot_proxies)
    assert len(verdicts) == len(knot_proxies)
    for proxy, verdict in zip(knot_proxies, verdicts):
        expected = {"outside": "contains the mesh", "inside": "lies within the mesh", "general": "none"}[proxy["kind"]]
        assert verdict["claim"] == expected, proxy["name"]
        assert verdict["holds"], (proxy["name"], verdict["counterexample"])
        if proxy["kind"] != "general":
            assert verdict["margin"] >= 0


def test_a_proxy_edited_by_hand_is_judged_as_it_is(knot, knot_proxies):
    vertices, _ = knot
    hull = dict(next(p for p in knot_proxies if p["name"] == "hull"))
    centre = vertices.mean(axis=0)
    moved = hull["vertices"].copy()
    far = int(np.argmax(np.linalg.norm(moved - centre, axis=1)))
    moved[far] = centre + 0.5 * (moved[far] - centre)  # pulled halfway in: mesh vertices now outside
    hull["vertices"] = moved
    verdict = vp.verify(*knot, hull)[0]
    assert not verdict["holds"]
    assert verdict["margin"] < 0 and "vertex" in verdict["counterexample"]
    # and an inside sphere grown past the surface
    inside = dict(next(p for p in knot_proxies if p["name"] == "inside-10"))
    grown = inside["spheres"].copy()
    grown[0, 3] *= 1.01
    inside["spheres"] = grown
    verdict = vp.verify(*knot, inside)[0]
    assert not verdict["holds"] and "sphere 0" in verdict["counterexample"]


def test_an_outside_claim_made_for_a_proxy_that_is_not_outside_fails(knot):
    vertices, triangles = knot
    shrunk = vertices.mean(axis=0) + 0.9 * (vertices - vertices.mean(axis=0))
    verdict = vp.verify(vertices, triangles, {"kind": "outside", "vertices": shrunk, "triangles": triangles})[0]
    assert not verdict["holds"]


def test_measure_gives_the_outside_and_inside_forms(knot, knot_proxies):
    # Seed 3 draws a line that starts inside outer-64 where it reaches beyond the knot's
    # bounding sphere, and hits the knot: the proxy must be traced on the whole line.
    figures = vp.measure(*knot, knot_proxies, rays=20000, seed=3, timed_rays=2000)
    assert len(figures) == len(knot_proxies)
    for proxy, measured in zip(knot_proxies, figures):
        assert measured["rays"]["count"] == 20000 and measured["rays"]["seed"] == 3
        assert sum(measured["counts"]) == 20000
        if proxy["kind"] == "outside":
            assert measured["f_hit"]["value"] == 1.0 and measured["rays_contradicting_claim"] == 0
        if proxy["kind"] == "inside":
            assert measured["f_miss"]["value"] == 1.0 and measured["rays_contradicting_claim"] == 0
        probabilities = measured["probabilities"]
        assert probabilities["p1"] + probabilities["p2"] + probabilities["p3"] == pytest.approx(1.0)


def test_the_same_seed_gives_the_same_proxies_and_the_calls_run_beside_other_threads(knot):
    results = [None, None]

    def build(slot):
        results[slot] = vp.build(*knot, ["spheres:20", "wrap"], seed=5)

    threads = [threading.Thread(target=build, args=(slot,)) for slot in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for first, second in zip(*results):
        assert np.array_equal(first["spheres"] if first["spheres"] is not None else first["vertices"],
                              second["spheres"] if second["spheres"] is not None else second["vertices"])
        assert first["manifest"]["error"] == second["manifest"]["error"]


# ---- the CLI's output, bit for bit ----------------------------------------------------

def test_build_verify_and_measure_equal_the_cli_bit_for_bit(tmp_path, knot):
    specs = ["aabb", "hull:32", "outer:64", "quadric:200", "inside:10", "spheres:30"]
    folder = tmp_path / "cli"
    cli("build", KNOT, "-o", folder, "--seed", 11, *[f"--proxy={s}" for s in specs])
    cli("verify", KNOT, folder)
    cli("measure", KNOT, folder, "--rays", 20000, "--seed", 4, "--timed-rays", 1000)
    from_cli = vp.read_proxies(folder)
    ours = vp.build(*knot, specs, seed=11, output=tmp_path / "python", source=str(KNOT))
    assert [p["name"] for p in ours] == [p["name"] for p in from_cli]
    for mine, theirs in zip(ours, from_cli):
        for key in ("vertices", "triangles", "spheres"):
            if theirs[key] is None:
                assert mine[key] is None
            else:
                assert mine[key].dtype == theirs[key].dtype and np.array_equal(mine[key], theirs[key]), (mine["name"], key)
        for key in ("kind", "method", "params", "primitives", "error"):
            assert mine["manifest"][key] == theirs["manifest"][key], (mine["name"], key)
        # the files written from Python are the CLI's, byte for byte
        name = theirs["manifest"]["file"]
        assert (tmp_path / "python" / name).read_bytes() == (folder / name).read_bytes(), name
    for mine, theirs in zip(vp.verify(*knot, ours), from_cli):
        recorded = theirs["manifest"]["verify"]
        for key in ("claim", "holds", "margin", "counterexample", "mesh_hash", "proxy_hash"):
            assert mine[key] == recorded[key], (theirs["name"], key)
    for mine, theirs in zip(vp.measure(*knot, ours, rays=20000, seed=4, timed_rays=1000), from_cli):
        recorded = theirs["manifest"]["measure"]
        for key in ("counts", "f_hit", "f_miss", "v_avg", "gssa_ratio", "probabilities", "variance", "rays"):
            assert mine[key] == recorded[key], (theirs["name"], key)
    # The report written from Python is the CLI's, byte for byte, and its recommendation is returned.
    cli("report", folder, "--picture-size", 48)
    files = ["recommendation.json", "report.md", "report.html"] + [f"pictures/{p.name}" for p in (folder / "pictures").iterdir()]
    assert len(files) == 3 + 1 + 3 * len(specs)
    written = {name: (folder / name).read_bytes() for name in files}
    recommendation = vp.report(folder, picture_size=48)
    for name, content in written.items():
        assert (folder / name).read_bytes() == content, name
    assert recommendation == json.loads(written["recommendation.json"])
    assert recommendation["uses"]["bounds"]["proxy"] in ("aabb", "hull-32", "outer-64", "inside-10")


def test_export_equals_the_cli_file_byte_for_byte_and_keeps_every_claim(tmp_path):
    folder = tmp_path / "knot"
    cli("build", KNOT, "-o", folder, "--proxy", "hull:32", "--proxy", "inside:10", "--proxy", "quadric:200",
        "--hausdorff-samples", 500)
    cli("export", folder, "-o", tmp_path / "cli.glb")
    exported = vp.export(folder, tmp_path / "python.glb")
    assert (tmp_path / "python.glb").read_bytes() == (tmp_path / "cli.glb").read_bytes()
    assert [(p["name"], p["claimed"], p["kind"]) for p in exported] == [
        ("hull-32", "outside", "outside"), ("inside-10", "inside", "inside"), ("quadric-200", "general", "general")]
    assert all(p["note"] == "" and p["node"] == "knot1." + p["name"] for p in exported)
    with pytest.raises(vp.InvalidInputError, match="lists no proxy named 'wrap'"):
        vp.export(folder, tmp_path / "x.glb", proxies=["wrap"])
    assert not (tmp_path / "x.glb").exists()


def test_report_of_a_per_mesh_folder_equals_the_cli_one(tmp_path):
    engine = MESHES.parent / "assimp-testmodels/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"
    if not engine.exists():
        pytest.skip(f"{engine} is missing (Debian's assimp-testmodels)")
    folder = tmp_path / "engine"
    cli("build", engine, "-o", folder, "--per-mesh", "--proxy", "obb", "--proxy", "hull", "--hausdorff-samples", 200)
    # Python builds the same folder: the same listing, and every proxy file byte for byte.
    listing = vp.build_asset(engine, tmp_path / "python", ["obb", "hull"], hausdorff_samples=200)
    assert listing == json.loads((folder / "asset.json").read_text())
    for part in listing["parts"]:
        for name in ("obb.ply", "hull.ply"):
            assert (tmp_path / "python" / part["folder"] / name).read_bytes() == (folder / part["folder"] / name).read_bytes()
    cli("measure", engine, folder, "--rays", 2000, "--timed-rays", 500)
    cli("report", folder, "--no-pictures")
    written = (folder / "recommendation.json").read_bytes()
    summary = vp.report(folder, pictures=False)
    assert (folder / "recommendation.json").read_bytes() == written
    assert summary == json.loads(written)
    assert len(summary["parts"]) == 29 and summary["total"]["triangles"] > 0


def write_scene(path, mesh_path):
    scene = {
        "format": "visproxy-scene", "format_version": 1,
        "description": "A knot over a floor under a square light",
        "meshes": {
            "floor": {"positions": [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]], "triangles": [[0, 2, 1], [0, 3, 2]]},
            "knot": {"file": str(mesh_path)},
        },
        "instances": [
            {"mesh": "floor", "albedo": [0.7, 0.7, 0.7]},
            {"mesh": "knot", "albedo": [0.7, 0.7, 0.7],
             "transform": {"fit": {"base": [0, 0.1, 0], "height": 1.0}}, "proxies": ["hull:32", "inside:10"]},
        ],
        "lights": [{"type": "parallelogram", "corner": [-0.5, 3, -0.5], "edge1": [1, 0, 0], "edge2": [0, 0, 1],
                    "radiance": [10, 10, 10]}],
        "camera": {"from": [0, 2.5, 4], "at": [0, 0.5, 0], "up": [0, 1, 0], "fov_degrees": 45, "width": 40, "height": 30},
    }
    path.write_text(json.dumps(scene))


def read_pfm(path):
    data = path.read_bytes()
    header, rest = data.split(b"\n", 1)
    size, rest = rest.split(b"\n", 1)
    scale, pixels = rest.split(b"\n", 1)
    assert header == b"PF" and float(scale) < 0
    width, height = map(int, size.split())
    return np.frombuffer(pixels, dtype="<f4").reshape(height, width, 3)[::-1]


@pytest.mark.parametrize("options", [["--visibility", "exact"],
                                     ["--visibility", "stochastic", "--estimator", "control-variate",
                                      "--probabilities", "learned"],
                                     ["--visibility", "bounds"]])
def test_render_equals_the_cli_image(tmp_path, options):
    scene = tmp_path / "knot.json"
    write_scene(scene, KNOT)
    cache = tmp_path / "cache"
    cli("render", scene, "-o", tmp_path / "cli.pfm", "--spp", 3, "--seed", 9, "--cache", cache, *options)
    keywords = {options[i].lstrip("-").replace("-", "_"): options[i + 1] for i in range(0, len(options), 2)}
    rendered = vp.render(scene, spp=3, seed=9, cache=cache, output=tmp_path / "python.pfm", **keywords)
    image = rendered["image"]
    assert image.shape == (30, 40, 3) and image.dtype == np.float64
    assert np.isfinite(image).all() and image.max() > 0
    assert np.array_equal(image.astype(np.float32), read_pfm(tmp_path / "cli.pfm"))
    assert (tmp_path / "python.pfm").read_bytes() == (tmp_path / "cli.pfm").read_bytes()
    assert rendered["stats"]["passes"] == 3
    cli_stats = json.loads((tmp_path / "cli.stats.json").read_text())["stats"]
    assert rendered["stats"]["shadow_rays"] == cli_stats["shadow_rays"]


def test_lightcuts_with_bounds_equals_the_cli_image(tmp_path):
    scene = tmp_path / "room.json"
    cli("generate", "room", "-o", scene, "--width", 32, "--height", 24, "--proxy", "hull", "--proxy", "inside:40")
    cache = tmp_path / "cache"
    cli("render", scene, "-o", tmp_path / "cli.pfm", "--spp", 1, "--cache", cache, "--integrator", "lightcuts",
        "--light-points", 64, "--visibility-bounds", "both", "--check-proofs")
    rendered = vp.render(scene, spp=1, cache=cache, integrator="lightcuts", light_points=64, visibility_bounds="both",
                         check_proofs=True, output=tmp_path / "python.pfm")
    assert np.array_equal(rendered["image"].astype(np.float32), read_pfm(tmp_path / "cli.pfm"))
    cuts = rendered["stats"]["integrator"]
    cli_cuts = json.loads((tmp_path / "cli.stats.json").read_text())["stats"]["integrator"]
    assert cuts["cut_size_mean"] == cli_cuts["cut_size_mean"]
    assert cuts["proof_disagreements"] == 0 and cuts["clusters_proved_occluded"] > 0
    assert rendered["cut_map"].shape == (24, 32, 3) and rendered["cut_map"].min() >= 1
    with pytest.raises(vp.Error):
        vp.render(scene, spp=1, cache=cache, integrator="lightcuts", visibility="stochastic")


# ---- bad input: the CLI's one-line messages as exceptions ---------------------------

def cli_message(*arguments):
    result = cli(*arguments, check=False)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("visproxy: ")
    return lines[0][len("visproxy: "):]


def test_a_missing_file_raises_file_error_with_the_cli_message(tmp_path):
    missing = tmp_path / "missing.off"
    with pytest.raises(vp.FileError) as raised:
        vp.read_mesh(missing)
    assert isinstance(raised.value, OSError) and isinstance(raised.value, vp.Error)
    assert str(raised.value) == cli_message("info", missing)


@pytest.mark.parametrize("name,content", [
    ("truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n"),
    ("bad-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
    ("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"),
    ("header.ply", "ply\nformat ascii 1.0\nelement vertex 99999999999\nend_header\n"),
    ("empty.stl", ""),
])
def test_a_malformed_file_raises_invalid_input_with_the_cli_message(tmp_path, name, content):
    path = tmp_path / name
    path.write_text(content)
    with pytest.raises(vp.InvalidInputError) as raised:
        vp.read_mesh(path)
    assert isinstance(raised.value, ValueError)
    message = str(raised.value)
    assert str(path) in message and "\n" not in message
    assert message == cli_message("info", path)


def test_a_bad_spec_and_a_builder_refusal_give_the_cli_message(tmp_path):
    vertices, triangles = vp.read_mesh(ELEPHANT)
    with pytest.raises(vp.Error) as raised:
        vp.build(vertices, triangles, ["hull:many"])
    assert str(raised.value) == cli_message("build", ELEPHANT, "-o", tmp_path / "a", "--proxy", "hull:many")
    with pytest.raises(vp.InvalidInputError) as raised:
        vp.build(vertices, triangles, ["inside:10"], source=str(ELEPHANT))
    assert str(raised.value) == cli_message("build", ELEPHANT, "-o", tmp_path / "b", "--proxy", "inside:10")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


@pytest.mark.parametrize("vertices,triangles,expected", [
    (np.zeros((3, 2)), np.array([[0, 1, 2]]), "vertices: must have shape (N, 3)"),
    (np.zeros((3, 3)), np.array([[0.0, 1.0, 2.0]]), "triangles: must hold integer vertex indices, not float64"),
    (np.zeros((3, 3)), np.array([[0, 1, 3]]), "triangles[0, 2]: vertex index 3 is out of range (3 vertices)"),
    (np.zeros((3, 3)), np.array([[0, -1, 2]]), "triangles[0, 1]: vertex index -1 is out of range (3 vertices)"),
    (np.zeros((3, 3)), np.array([[0, 1, 2**64 - 1]], dtype=np.uint64), "triangles[0, 2]: vertex index 18446744073709551615"),
    (np.array([[0, 0, 0], [1, 0, 0], [np.inf, 1, 0]]), np.array([[0, 1, 2]]), "vertex 2: x is not finite (inf)"),
    # A NaN between zeros: the case a maximum over the coordinates can step over.
    (np.array([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]]), np.array([[0, 1, 2]]), "vertex 2: y is not finite (nan)"),
    (np.array([[0, 0, 0], [0, 0, -np.inf], [0, 1, 0]]), np.array([[0, 1, 2]]), "vertex 1: z is not finite (-inf)"),
    (np.array([["a", "b", "c"]] * 3), np.array([[0, 1, 2]]), "vertices: must hold real numbers"),
])
def test_bad_arrays_raise_invalid_input_naming_the_array(vertices, triangles, expected):
    with pytest.raises(vp.InvalidInputError) as raised:
        vp.inspect(vertices, triangles, source="my arrays")
    assert str(raised.value).startswith("my arrays: ") and expected in str(raised.value)


def test_every_entry_point_refuses_a_nan_vertex_up_front(knot):
    vertices = knot[0].copy()
    vertices[7, 1] = np.nan
    calls = {
        "inspect": lambda: vp.inspect(vertices, knot[1], source="k"),
        "build": lambda: vp.build(vertices, knot[1], ["aabb"], source="k"),
        "verify": lambda: vp.verify(vertices, knot[1], [], source="k"),
        "measure": lambda: vp.measure(vertices, knot[1], [], source="k"),
    }
    for name, call in calls.items():
        with pytest.raises(vp.InvalidInputError) as raised:
            call()
        assert str(raised.value) == "k: vertex 7: y is not finite (nan)", name


def test_arguments_of_the_wrong_type_raise_a_short_type_error(knot):
    # A list of vertices (not an array) with a wrong argument beside it: the message names
    # the signatures and the types given, never the values (they printed in full, 190 KB).
    vertices = knot[0].tolist()
    for call in (lambda: vp.build(vertices, knot[1], 5), lambda: vp.measure(vertices, knot[1], [], rays="many"),
                 lambda: vp.inspect(vertices, knot[1], source=3)):
        with pytest.raises(TypeError) as raised:
            call()
        message = str(raised.value)
        assert len(message) < 2000, message[:300]
        assert "incompatible function arguments" in message and "Invoked with types: (list, ndarray" in message
    assert vp.build.__name__ == "build" and "vertices" in vp.build.__doc__


def test_bad_proxy_dicts_and_options_raise(knot):
    with pytest.raises(vp.InvalidInputError, match="needs a kind"):
        vp.verify(*knot, {"vertices": knot[0], "triangles": knot[1]})
    with pytest.raises(vp.InvalidInputError, match="spheres\\[1\\]: needs a finite centre and a positive finite radius"):
        vp.verify(*knot, {"kind": "inside", "spheres": np.array([[0, 0, 0, 0.1], [0, 0, 0, -1.0]])})
    with pytest.raises(TypeError):
        vp.verify(*knot, [42])
    with pytest.raises(ValueError, match="visibility: 'fast' is not one of"):
        vp.render(SOURCE / "data/scenes/cornell.json", visibility="fast")
    with pytest.raises(ValueError, match="learned needs"):
        vp.render(SOURCE / "data/scenes/cornell.json", probabilities="learned")
    with pytest.raises(vp.InvalidInputError, match="unsupported image format"):
        vp.render(SOURCE / "data/scenes/cornell.json", output="image.jpg")


def test_gltf_is_read_through_assimp_and_a_file_that_crashes_assimp_only_raises(tmp_path):
    vertices, triangles = vp.read_mesh(SOURCE / "data/scenes/boxes.gltf")
    assert len(triangles) == 2 + 2 * 12 + 2  # the floor, the box placed twice, the lamp
    assert vp.inspect(vertices, triangles)["components"] == 4
    crash = tmp_path / "crash.gltf"
    crash.write_bytes((SOURCE / "tests/fuzz/corpus/gltf-assimp-segfault").read_bytes()[1:])
    with pytest.raises(vp.InvalidInputError, match="Assimp crashed reading it"):
        vp.read_mesh(crash)
    assert vp.read_mesh(KNOT)[1].shape == (6400, 3)  # and this interpreter goes on


def _thp_enabled(pid="self"):
    """The kernel's THP_enabled for a process (Linux), or None where it does not say."""
    status = pathlib.Path(f"/proc/{pid}/status")
    if not status.exists():
        return None
    for line in status.read_text().splitlines():
        if line.startswith("THP_enabled:"):
            return int(line.split()[1])
    return None


@pytest.mark.skipif(_thp_enabled() is None, reason="the kernel does not report THP_enabled")
def test_transparent_huge_pages_are_turned_off_only_when_asked():
    # In a child interpreter, so that this process keeps its setting.
    script = ("import sys, visproxy as vp; before = open('/proc/self/status').read().count('THP_enabled:\\t1'); "
              "off = vp.disable_transparent_huge_pages(); "
              "after = open('/proc/self/status').read().count('THP_enabled:\\t1'); print(before, int(off), after)")
    inherited = str(_thp_enabled())  # a child starts with its parent's setting
    env = {k: v for k, v in os.environ.items() if k != "VISPROXY_TRANSPARENT_HUGE_PAGES"}
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True)
    assert result.stdout.split() == [inherited, "1", "0"]
    env["VISPROXY_TRANSPARENT_HUGE_PAGES"] = "1"
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True)
    assert result.stdout.split() == [inherited, "0", inherited]

