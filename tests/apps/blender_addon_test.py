"""The Blender add-on (apps/blender) in Debian's Blender, headless, Cycles on the CPU:

    blender -b --factory-startup --python-exit-code 1 --python blender_addon_test.py -- \
        SOURCE_DIR PYTHON_MODULE_DIR MESH WORK_DIR [ASSET]

1. "Build Shadow Proxies" on a real mesh gives a child object holding exactly the floats
   visproxy.float_proxy proves, marked and with ray visibility set: the proxy casts the
   shadows, the object does not.
2. Cycles renders the report's shadow stage (visproxy.shadow_stage: ground, square area
   light, camera from above) three times at equal samples and seed: the mesh casting, the
   proxy casting, nothing casting. The shadow the proxy misses and adds, measured on
   Cycles' pictures, agrees with visproxy's own figures within 0.02 + 10 % of them; an
   outside proxy misses (almost) none.
3. A .glb written by `visproxy export` imports through Blender's glTF importer with each
   proxy's extras as the custom property `visproxy`, and "Use Shadow Proxies" sets their
   ray visibility. With ASSET (a multi-mesh glTF), its per-mesh export imports with every
   proxy parented to an object that shows its mesh.
Prints one line per check and exits 1 on the first failure.
"""
import json
import os
import subprocess
import sys
import time

import bpy
import numpy as np

arguments = sys.argv[sys.argv.index("--") + 1:]
source_dir, module_dir, mesh_path, work = arguments[:4]
asset = arguments[4] if len(arguments) > 4 else None
sys.path.insert(0, module_dir)
sys.path.insert(0, os.path.join(source_dir, "apps", "blender"))
os.makedirs(work, exist_ok=True)

import visproxy as vp  # noqa: E402
import visproxy_blender  # noqa: E402

SIZE = 96
SAMPLES = 64


def check(condition, message):
    print(("ok: " if condition else "FAILED: ") + message, flush=True)
    if not condition:
        sys.exit(1)


def mesh_object(name, vertices, triangles):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(map(float, p)) for p in vertices], [], [tuple(map(int, t)) for t in triangles])
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def object_vertices(obj):
    values = np.empty(3 * len(obj.data.vertices), dtype=np.float32)
    obj.data.vertices.foreach_get("co", values)
    return values.reshape(-1, 3)


def object_triangles(obj):
    values = np.empty(3 * len(obj.data.polygons), dtype=np.int64)
    obj.data.polygons.foreach_get("vertices", values)
    return values.reshape(-1, 3)


bpy.ops.wm.read_factory_settings(use_empty=True)
visproxy_blender.register()
scene = bpy.context.scene

# ---- 1. the operator ---------------------------------------------------------------
vertices, triangles = vp.read_mesh(mesh_path)
knot = mesh_object("knot", vertices, triangles)
bpy.context.view_layer.objects.active = knot
knot.select_set(True)
result = bpy.ops.object.visproxy_build_shadow_proxies(spec="hull:32")
check(result == {"FINISHED"}, "Build Shadow Proxies finished")
children = [o for o in knot.children]
check(len(children) == 1, "one proxy object, a child of the mesh's")
proxy_obj = children[0]
marks = proxy_obj["visproxy"]
check(marks["kind"] == "outside" and marks["proved"] and marks["shadow_only"], f"its marks: {dict(marks)}")
blender_vertices = object_vertices(knot).astype(np.float64)
expected = vp.float_proxy(blender_vertices, triangles, vp.build(blender_vertices, triangles, ["hull:32"], hausdorff_samples=1000)[0])
check(np.array_equal(object_vertices(proxy_obj), expected["vertices"]), "its vertices are the proved floats, bit for bit")
check(np.array_equal(object_triangles(proxy_obj), expected["triangles"]), "its triangles are the proxy's")
check(proxy_obj.visible_shadow and not proxy_obj.visible_camera and not proxy_obj.visible_diffuse, "the proxy is visible to shadow rays only")
check(not knot.visible_shadow and knot.visible_camera, "the mesh no longer casts shadows and is still seen")
check(proxy_obj.matrix_world == knot.matrix_world, "the proxy sits where the mesh is")

# ---- 2. the shadows in Cycles against visproxy's own --------------------------------
proxy_dict = {"name": "hull-32", "kind": "outside", "vertices": object_vertices(proxy_obj).astype(np.float64),
              "triangles": object_triangles(proxy_obj)}
stage = vp.shadow_stage(blender_vertices, triangles, proxy_dict, size=SIZE)
visproxy_blender.shadow_stage_scene(scene, stage, samples=SAMPLES)
knot.visible_camera = False  # the ground is seen everywhere, as in visproxy's picture


def render(name, mesh_casts, proxy_casts):
    knot.visible_shadow = mesh_casts
    proxy_obj.hide_render = not proxy_casts
    return visproxy_blender.render_red(scene, os.path.join(work, name + ".exr"))


mesh_image, mesh_seconds = render("mesh", True, False)
proxy_image, proxy_seconds = render("proxy", False, True)
lit_image, _ = render("nothing", False, False)
check(float(lit_image.min()) > 0, "the whole pictured ground is lit when nothing casts a shadow")
missed, extra, shadow = visproxy_blender.shadow_difference(mesh_image, proxy_image, lit_image)
check(shadow > 0.02 * SIZE * SIZE, f"the mesh casts a shadow on the pictured ground ({shadow:.1f} pixels' worth)")
figures = {"cycles": {"missed": missed, "extra": extra, "mesh_seconds": mesh_seconds, "proxy_seconds": proxy_seconds},
           "visproxy": {"missed": stage["missed_shadow"], "extra": stage["extra_shadow"]}, "size": SIZE, "samples": SAMPLES}
with open(os.path.join(work, "shadow-figures.json"), "w") as out:
    json.dump(figures, out, indent=2)
print(json.dumps(figures), flush=True)
for key in ("missed", "extra"):
    ours, cycles = stage[key + "_shadow"], figures["cycles"][key]
    check(abs(cycles - ours) <= 0.02 + 0.1 * ours,
          f"{key} shadow: Cycles {100 * cycles:.2f} %, visproxy {100 * ours:.2f} % (tolerance 2 points + 10 %)")
check(missed <= 0.02, f"the outside proxy misses almost no shadow in Cycles ({100 * missed:.2f} %)")

# ---- 3. an exported .glb through Blender's glTF importer -----------------------------
folder = os.path.join(work, "knot-proxies")
glb = os.path.join(work, "knot-proxies.glb")
cli = os.path.join(os.path.dirname(module_dir), "apps", "visproxy")
subprocess.run([cli, "build", mesh_path, "-o", folder, "--proxy", "obb", "--hausdorff-samples", "500"], check=True,
               capture_output=True)
subprocess.run([cli, "export", folder, "-o", glb], check=True, capture_output=True)
# Debian 12's Blender 3.4 importer calls numpy.bool, which numpy 1.24 removed.
if "bool" not in np.__dict__:
    np.bool = bool
visproxy_blender.unregister()
bpy.ops.wm.read_factory_settings(use_empty=True)
visproxy_blender.register()
result = bpy.ops.import_scene.gltf(filepath=glb)
check(result == {"FINISHED"}, "Blender's glTF importer reads the exported .glb")
marked = [o for o in bpy.context.scene.objects if o.get("visproxy") is not None]
check(len(marked) == 1 and marked[0].name.startswith("knot1.obb"), f"the proxy carries its extras: {[o.name for o in marked]}")
check(marked[0]["visproxy"]["kind"] == "outside" and marked[0]["visproxy"]["proved"], "with its proved claim")
check(bpy.ops.object.visproxy_use_shadow_proxies() == {"FINISHED"}, "Use Shadow Proxies finished")
check(marked[0].visible_shadow and not marked[0].visible_camera, "the imported proxy is visible to shadow rays only")

if asset is not None:
    parts = os.path.join(work, "asset-parts")
    subprocess.run([cli, "build", asset, "-o", parts, "--per-mesh", "--proxy", "obb", "--hausdorff-samples", "500"],
                   check=True, capture_output=True)
    subprocess.run([cli, "export", parts, "-o", os.path.join(work, "asset.glb")], check=True, capture_output=True)
    with open(os.path.join(parts, "asset.json")) as listing:
        instances = sum(len(part["instances"]) for part in json.load(listing)["parts"])
    visproxy_blender.unregister()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    visproxy_blender.register()
    check(bpy.ops.import_scene.gltf(filepath=os.path.join(work, "asset.glb")) == {"FINISHED"}, "the per-mesh export imports")
    marked = [o for o in bpy.context.scene.objects if o.get("visproxy") is not None]
    check(len(marked) == instances, f"one proxy object per node showing a mesh ({len(marked)} of {instances})")
    check(all(o.parent is not None and o.parent.type == "MESH" and o.name.split(".")[0] in o.parent.data.name
              for o in marked), "each parented to an object showing the mesh it stands for")
    bpy.ops.object.visproxy_use_shadow_proxies()
    check(all(o.visible_shadow and not o.visible_camera and not o.parent.visible_shadow for o in marked),
          "every proxy casts its object's shadow instead of the object")

print("blender_addon_test: all checks passed", flush=True)
