"""visproxy for Blender: shadow proxies for the selected objects, and for assets exported by
`visproxy export`.

Two operators (View3D > Object > visproxy, or F3):

- "Build Shadow Proxies" builds a proxy of each selected mesh object's evaluated mesh
  (modifiers applied) with the visproxy Python module, rounds it to float32 with its claim
  proved again (visproxy.float_proxy), and adds it as a child of the object.
- "Use Shadow Proxies" finds the objects an imported glTF marks with the custom property
  `visproxy` (`visproxy export` writes it into each proxy node's extras) and sets their ray
  visibility.

Either way the proxy casts the shadows and the object does not: in Cycles the proxy is
visible to shadow rays only and the object is invisible to shadow rays. The proxy's
custom property `visproxy` holds its kind, claim and whether the claim was proved.

The visproxy module must be importable in Blender's Python (Debian's Blender runs the
system's Python 3.11): PYTHONPATH=build/release/python, or the installed module.
"""

bl_info = {
    "name": "visproxy shadow proxies",
    "description": "Proved visibility proxies that cast an object's shadows in Cycles",
    "blender": (3, 4, 0),
    "category": "Object",
    "location": "View3D > Object > visproxy",
}

import bpy
import numpy as np

SHADOW_ONLY = {
    "visible_camera": False,
    "visible_diffuse": False,
    "visible_glossy": False,
    "visible_transmission": False,
    "visible_volume_scatter": False,
    "visible_shadow": True,
}


def evaluated_triangles(obj, depsgraph):
    """The object's evaluated mesh (modifiers applied) in its own coordinates, as
    (V, 3) float64 vertices and (T, 3) int64 triangles."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        mesh.calc_loop_triangles()
        vertices = np.empty(3 * len(mesh.vertices), dtype=np.float32)
        mesh.vertices.foreach_get("co", vertices)
        triangles = np.empty(3 * len(mesh.loop_triangles), dtype=np.int64)
        mesh.loop_triangles.foreach_get("vertices", triangles)
    finally:
        evaluated.to_mesh_clear()
    return vertices.reshape(-1, 3).astype(np.float64), triangles.reshape(-1, 3)


def make_shadow_caster(proxy_obj, source_obj):
    """Ray visibility: the proxy casts the shadows, the object no longer does."""
    for name, value in SHADOW_ONLY.items():
        setattr(proxy_obj, name, value)
    proxy_obj.display_type = "WIRE"
    if source_obj is not None:
        source_obj.visible_shadow = False


def add_proxy_object(context, source_obj, name, vertices, triangles, properties):
    """A mesh object of exactly these float32 vertices, parented to `source_obj` with no
    offset (the proxy is in the object's own coordinates)."""
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", np.ascontiguousarray(vertices, dtype=np.float32).ravel())
    mesh.loops.add(3 * len(triangles))
    mesh.loops.foreach_set("vertex_index", np.ascontiguousarray(triangles, dtype=np.int32).ravel())
    mesh.polygons.add(len(triangles))
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(triangles), 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(triangles), 3, dtype=np.int32))
    mesh.update(calc_edges=True)
    mesh.validate(clean_customdata=False)
    obj = bpy.data.objects.new(name, mesh)
    context.collection.objects.link(obj)
    obj.parent = source_obj
    obj.matrix_parent_inverse.identity()
    obj["visproxy"] = properties
    make_shadow_caster(obj, source_obj)
    return obj


def shadow_stage_scene(scene, stage, samples=64, seed=7):
    """Sets up `scene` as the stage of visproxy's shadow pictures (visproxy.shadow_stage, in
    the mesh's frame, +y up): a ground square four times the pictured one, the square area
    light facing -y, an orthographic camera from straight above whose pixels are the
    picture's (columns to +x, rows to +z), a black world, Cycles on the CPU with direct
    light only, a fixed seed and no denoising. Returns the ground object."""
    import math

    side, height = stage["ground_side"], stage["ground_height"]
    cx, cz = stage["ground_x0"] + side / 2, stage["ground_z0"] + side / 2
    mesh = bpy.data.meshes.new("visproxy ground")
    mesh.from_pydata([(cx - 2 * side, height, cz - 2 * side), (cx + 2 * side, height, cz - 2 * side),
                      (cx + 2 * side, height, cz + 2 * side), (cx - 2 * side, height, cz + 2 * side)], [],
                     [(0, 3, 2), (0, 2, 1)])
    ground = bpy.data.objects.new("visproxy ground", mesh)
    scene.collection.objects.link(ground)
    corner, u, v = (np.array(stage[key], dtype=np.float64) for key in ("light_corner", "light_u", "light_v"))
    light_data = bpy.data.lights.new("visproxy light", "AREA")
    light_data.shape = "SQUARE"
    light_data.size = float(np.linalg.norm(u))
    light_data.energy = 1000.0
    light = bpy.data.objects.new("visproxy light", light_data)
    light.location = tuple(corner + u / 2 + v / 2)
    light.rotation_euler = (-math.pi / 2, 0.0, 0.0)  # its -z, where it shines, to -y
    scene.collection.objects.link(light)
    camera_data = bpy.data.cameras.new("visproxy camera")
    camera_data.type = "ORTHO"
    camera_data.ortho_scale = side
    camera_data.clip_end = 100 * side
    camera = bpy.data.objects.new("visproxy camera", camera_data)
    camera.location = (cx, height + 10 * side, cz)
    camera.rotation_euler = (-math.pi / 2, 0.0, 0.0)  # looks down -y, image rows toward +z
    scene.collection.objects.link(camera)
    scene.camera = camera
    world = bpy.data.worlds.new("visproxy black")
    world.color = (0, 0, 0)
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.seed = seed
    scene.cycles.max_bounces = 0
    scene.cycles.filter_width = 0.01
    scene.render.resolution_x = scene.render.resolution_y = int(stage["size"])
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    return ground


def render_red(scene, path):
    """Renders `scene` to the EXR `path` and returns its red channel, top row first, and the
    render's wall seconds."""
    import time

    scene.render.filepath = path
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - start
    image = bpy.data.images.load(path)
    height, width = image.size[1], image.size[0]
    pixels = np.array(image.pixels[:], dtype=np.float64).reshape(height, width, 4)[::-1, :, 0]
    bpy.data.images.remove(image)
    return pixels, seconds


def shadow_difference(mesh_image, proxy_image, lit_image):
    """The shadow a proxy misses and adds, as visproxy's pictures count it: with V the
    fraction of light a ground pixel gets (the image over the image with nothing casting),
    the sums of max(V_proxy - V_mesh, 0) and max(V_mesh - V_proxy, 0) over the sum of
    1 - V_mesh."""
    v_mesh = np.clip(mesh_image / lit_image, 0, 1)
    v_proxy = np.clip(proxy_image / lit_image, 0, 1)
    shadow = float(np.sum(1 - v_mesh))
    return (float(np.sum(np.maximum(v_proxy - v_mesh, 0))) / shadow,
            float(np.sum(np.maximum(v_mesh - v_proxy, 0))) / shadow, shadow)


class VISPROXY_OT_build_shadow_proxies(bpy.types.Operator):
    """Build a proved shadow proxy of each selected mesh object and let it cast the object's shadows"""

    bl_idname = "object.visproxy_build_shadow_proxies"
    bl_label = "Build Shadow Proxies"
    bl_options = {"REGISTER", "UNDO"}

    spec: bpy.props.StringProperty(
        name="Proxy",
        description="visproxy proxy spec: hull, hull:32, obb, outer:512, wrap, inside:40, quadric:512, ...",
        default="hull:32",
    )
    seed: bpy.props.IntProperty(name="Seed", default=1, min=0)

    @classmethod
    def poll(cls, context):
        return any(obj.type == "MESH" for obj in context.selected_objects)

    def execute(self, context):
        import visproxy as vp

        depsgraph = context.evaluated_depsgraph_get()
        built = []
        for obj in [o for o in context.selected_objects if o.type == "MESH"]:
            vertices, triangles = evaluated_triangles(obj, depsgraph)
            try:
                proxy = vp.build(vertices, triangles, [self.spec], seed=self.seed, hausdorff_samples=1000,
                                 source=obj.name)[0]
                rounded = vp.float_proxy(vertices, triangles, proxy, source=obj.name)
            except vp.Error as error:
                self.report({"ERROR"}, f"{obj.name}: {error}")
                return {"CANCELLED"}
            properties = {
                "shadow_only": True,
                "proxy": proxy["name"],
                "spec": self.spec,
                "kind": rounded["kind"],
                "claimed": rounded["claimed"],
                "proved": rounded["kind"] != "general",
                "moved": rounded["moved"],
            }
            if rounded["note"]:
                self.report({"WARNING"}, f"{obj.name}: {rounded['note']}")
            built.append(add_proxy_object(context, obj, f"{obj.name}.{proxy['name']}", rounded["vertices"],
                                          rounded["triangles"], properties))
        self.report({"INFO"}, f"visproxy: {len(built)} shadow proxies built")
        return {"FINISHED"}


class VISPROXY_OT_use_shadow_proxies(bpy.types.Operator):
    """Let the proxies of an imported visproxy export cast their objects' shadows"""

    bl_idname = "object.visproxy_use_shadow_proxies"
    bl_label = "Use Shadow Proxies"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        count = 0
        for obj in context.scene.objects:
            marks = obj.get("visproxy")
            if marks is None or not marks.get("shadow_only", False):
                continue
            make_shadow_caster(obj, obj.parent)
            count += 1
        self.report({"INFO"}, f"visproxy: {count} shadow proxies in use")
        return {"FINISHED"}


class VISPROXY_MT_menu(bpy.types.Menu):
    bl_idname = "VIEW3D_MT_visproxy"
    bl_label = "visproxy"

    def draw(self, context):
        self.layout.operator(VISPROXY_OT_build_shadow_proxies.bl_idname)
        self.layout.operator(VISPROXY_OT_use_shadow_proxies.bl_idname)


def menu_entry(self, context):
    self.layout.menu(VISPROXY_MT_menu.bl_idname)


CLASSES = (VISPROXY_OT_build_shadow_proxies, VISPROXY_OT_use_shadow_proxies, VISPROXY_MT_menu)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.VIEW3D_MT_object.append(menu_entry)


def unregister():
    bpy.types.VIEW3D_MT_object.remove(menu_entry)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
