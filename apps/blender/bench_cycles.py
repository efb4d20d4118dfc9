"""Cycles render time and shadow difference, the mesh casting its shadow against each of
its proxies casting it, at equal samples and seed, on the stage of visproxy's shadow
pictures (visproxy.shadow_stage: ground, square area light, camera from above):

    blender -b --factory-startup --python apps/blender/bench_cycles.py -- \
        PYTHON_MODULE_DIR MESH SUBDIVISIONS SPECS REPEATS SAMPLES SIZE WORK_DIR

MESH gets a Subdivision Surface modifier of SUBDIVISIONS levels (0: none); the add-on
builds each proxy of SPECS (comma-separated) from the evaluated mesh, as an artist's
click does. The renders (nothing casting, the mesh, each proxy) are interleaved, REPEATS
rounds; the table gives each one's wall-time range over the rounds, its ratio to the
mesh's range, and the shadow each proxy misses and adds on Cycles' pictures beside
visproxy's own figures. The mesh stays in the scene for every render, hidden from the
camera: what differs between the renders is what casts the shadow rays' hits.
"""
import os
import sys

import bpy
import numpy as np

arguments = sys.argv[sys.argv.index("--") + 1:]
module_dir, mesh_path, levels, specs, repeats, samples, size, work = arguments[:8]
levels, repeats, samples, size = int(levels), int(repeats), int(samples), int(size)
sys.path.insert(0, module_dir)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__))))
os.makedirs(work, exist_ok=True)

import visproxy as vp  # noqa: E402
import visproxy_blender  # noqa: E402

bpy.ops.wm.read_factory_settings(use_empty=True)
visproxy_blender.register()
scene = bpy.context.scene
vertices, triangles = vp.read_mesh(mesh_path)
data = bpy.data.meshes.new("mesh")
data.from_pydata([tuple(map(float, p)) for p in vertices], [], [tuple(map(int, t)) for t in triangles])
mesh_obj = bpy.data.objects.new("mesh", data)
scene.collection.objects.link(mesh_obj)
if levels > 0:
    modifier = mesh_obj.modifiers.new("subdivision", "SUBSURF")
    modifier.levels = modifier.render_levels = levels
bpy.context.view_layer.objects.active = mesh_obj
mesh_obj.select_set(True)
evaluated_vertices, evaluated_triangles = visproxy_blender.evaluated_triangles(mesh_obj, bpy.context.evaluated_depsgraph_get())

proxies = []
for spec in specs.split(","):
    before = set(mesh_obj.children)
    bpy.ops.object.visproxy_build_shadow_proxies(spec=spec)
    (proxy_obj,) = set(mesh_obj.children) - before
    proxy_obj.hide_render = True
    count = len(proxy_obj.data.polygons)
    points = np.empty(3 * len(proxy_obj.data.vertices), dtype=np.float32)
    proxy_obj.data.vertices.foreach_get("co", points)
    faces = np.empty(3 * count, dtype=np.int64)
    proxy_obj.data.polygons.foreach_get("vertices", faces)
    proxy_dict = {"name": spec, "kind": proxy_obj["visproxy"]["kind"], "vertices": points.reshape(-1, 3).astype(np.float64),
                  "triangles": faces.reshape(-1, 3)}
    figures = vp.shadow_stage(evaluated_vertices, evaluated_triangles, proxy_dict, size=size)
    proxies.append({"spec": spec, "object": proxy_obj, "triangles": count, "kind": proxy_dict["kind"], "stage": figures})

stage = proxies[0]["stage"]
visproxy_blender.shadow_stage_scene(scene, stage, samples=samples)
mesh_obj.visible_camera = False


def render(name, caster):
    mesh_obj.visible_shadow = caster == "mesh"
    for proxy in proxies:
        proxy["object"].hide_render = proxy["spec"] != caster
    return visproxy_blender.render_red(scene, os.path.join(work, name + ".exr"))


times = {name: [] for name in ["nothing", "mesh"] + [p["spec"] for p in proxies]}
images = {}
for round_index in range(repeats):
    for name in times:
        image, seconds = render(name.replace(":", "-"), name)
        times[name].append(seconds)
        images[name] = image

mesh_triangles = len(evaluated_triangles)
print(f"Cycles {bpy.app.version_string}, {samples} samples, {size} x {size} pixels, seed 7, direct light only, "
      f"{repeats} rounds; {os.path.basename(mesh_path)} with {levels} subdivision levels: {mesh_triangles} triangles")
print("| shadow caster | triangles | kind | Cycles s (range) | time / mesh's | missed shadow, Cycles / visproxy | extra shadow, Cycles / visproxy |")
print("|---|---|---|---|---|---|---|")
low, high = min(times["mesh"]), max(times["mesh"])
print(f"| mesh | {mesh_triangles} | - | {low:.2f}-{high:.2f} | 1 | - | - |")
for proxy in proxies:
    spec = proxy["spec"]
    missed, extra, _ = visproxy_blender.shadow_difference(images["mesh"], images[spec], images["nothing"])
    t = times[spec]
    print(f"| {spec} | {proxy['triangles']} | {proxy['kind']} | {min(t):.2f}-{max(t):.2f} | "
          f"{min(t) / high:.2f}-{max(t) / low:.2f} | {100 * missed:.1f} % / {100 * proxy['stage']['missed_shadow']:.1f} % | "
          f"{100 * extra:.1f} % / {100 * proxy['stage']['extra_shadow']:.1f} % |")
t = times["nothing"]
print(f"| nothing | 0 | - | {min(t):.2f}-{max(t):.2f} | {min(t) / high:.2f}-{max(t) / low:.2f} | 100 % | 0 % |")
