"""pteryla feathers for Blender: feather the active mesh with the pteryla library (docs/blender.md).

A client of the Python module `pteryla` (python/): the add-on turns the mesh, its vertex groups and the
panel's settings into a pteryla.Session, and the session's frame into a child mesh "<name>_coat". On a
frame change it hands the session the evaluated (armature- or shape-key-deformed) skin as the pose.
Nothing here raises through Blender: operators report errors, the frame handler records them in the
panel and the console.
"""

bl_info = {
    "name": "pteryla feathers",
    "author": "pteryla",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Feathers",
    "description": "Feather coats on the active mesh: tracts from vertex groups, packed, posed and moulted",
    "category": "Object",
}

import json
import os
import sys
import time
import traceback

import bpy
import numpy as np
from bpy.app.handlers import persistent
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, FloatProperty, IntProperty,
                       PointerProperty, StringProperty)

# Sessions by skin object name: (session, key of the inputs it was built from). Not saved with the file:
# "Feather" (or the first frame change after loading) builds them again.
_sessions = {}


def _module():
    """The pteryla module: importable already, or from the add-on preference / PTERYLA_PYTHON_DIR."""
    try:
        import pteryla
        return pteryla
    except ImportError:
        pass
    dirs = [os.environ.get("PTERYLA_PYTHON_DIR", "")]
    addon = bpy.context.preferences.addons.get(__name__)
    if addon is not None:
        dirs.insert(0, addon.preferences.module_dir)
    for d in dirs:
        if d and os.path.isdir(os.path.join(d, "pteryla")) and d not in sys.path:
            sys.path.insert(0, d)
    try:
        import pteryla
        return pteryla
    except ImportError as e:
        raise RuntimeError("the pteryla Python module is not found: build pteryla (tools/build.sh) and set the "
                           "add-on's 'Module directory' to <build>/python (docs/blender.md): " + str(e))


def _feather_items(self, context):
    items = [("contour", "contour", "bundled contour feather")]
    try:
        d = os.path.join(_module().data_directory(), "feathers")
        names = sorted(f[:-5] for f in os.listdir(d) if f.endswith(".json"))
        items = [(n, n, "bundled feather data/feathers/" + n + ".json") for n in names]
    except Exception:
        pass
    items.append(("FILE", "File...", "a feather definition file (docs/feather-format.md)"))
    return items


class PterylaPreferences(bpy.types.AddonPreferences):
    bl_idname = __name__
    module_dir: StringProperty(name="Module directory", subtype="DIR_PATH",
                               description="Directory holding the built pteryla package (<build>/python)")

    def draw(self, context):
        self.layout.prop(self, "module_dir")


class PterylaTract(bpy.types.PropertyGroup):
    name: StringProperty(name="Name", default="tract")
    vertex_group: StringProperty(name="Vertex group",
                                 description="Faces whose three vertices are all in this group carry the tract")
    feather: EnumProperty(name="Feather", items=_feather_items)
    feather_file: StringProperty(name="File", subtype="FILE_PATH")
    use_count: BoolProperty(name="Exact count", default=True)
    count: IntProperty(name="Count", default=100, min=1)
    density: FloatProperty(name="Density", default=20.0, min=0.0,
                           description="Follicles per unit area (object space)")
    seed: IntProperty(name="Seed", default=-1, min=-1,
                      description="This tract's own follicle seed: changing it re-scatters only this tract "
                                  "(-1: derived from the coat's seed)")
    moult: BoolProperty(name="Moults", default=True,
                        description="Loses and regrows its feathers when the coat's moult is on")


class PterylaSettings(bpy.types.PropertyGroup):
    tracts: CollectionProperty(type=PterylaTract)
    active_tract: IntProperty(default=0)
    seed: IntProperty(name="Seed", default=1, min=0, description="Same mesh, set-up and seed: same coat")
    axis_object: PointerProperty(name="Axis", type=bpy.types.Object,
                                 poll=lambda self, o: o.type in {"EMPTY", "CURVE"},
                                 description="A curve from head to tail, or an empty whose Z axis runs head "
                                             "to tail (none: the longest bounding-box axis)")
    ordering: EnumProperty(name="Ordering", items=[("axis", "Axis", "roof tiles along the body axis"),
                                                   ("tracts", "Tracts", "tract by tract, in list order"),
                                                   ("flow", "Flow", "along the feather flow")])
    packing: EnumProperty(name="Packing", items=[("drape", "Drape", "docs/packing.md"),
                                                 ("height_field", "Height field", "docs/packing.md")])
    lod: FloatProperty(name="Detail", default=0.3, min=0.01, max=1.0, description="Fraction of barbs meshed")
    live: BoolProperty(name="Follow animation", default=True,
                       description="Re-evaluate on frame change with the deformed mesh as the pose")
    pose_mode: EnumProperty(name="Pose", default="follow",
                            items=[("follow", "Follow skin", "Lay the coat once on the rest mesh and let the deformed "
                                    "mesh carry it: fast frames, elevations fixed as laid"),
                                   ("repack", "Repack", "Re-lay the coat on every deformed pose: slow, the packing's "
                                    "guarantees hold at every pose")])
    moult: BoolProperty(name="Moult", default=False,
                        description="Feathers are lost and regrow in a window moving through each tract")
    moult_start: FloatProperty(name="Start", default=0.0, description="Time (seconds) the moult begins")
    moult_duration: FloatProperty(name="Duration", default=10.0, min=1e-3,
                                  description="Seconds until the last feather is renewed")
    moult_window: FloatProperty(name="Window", default=0.2, min=0.01, max=1.0,
                                description="Fraction of a tract's feathers moulting at once")
    moult_sequence: EnumProperty(name="Sequence", items=[
        ("centre_out", "Centre out", "from the tract's centre to its boundary"),
        ("boundary_in", "Boundary in", "from the boundary to the centre"),
        ("increasing_u", "Along U", "sequentially along the tract (flight feathers)"),
        ("decreasing_u", "Against U", "sequentially, the other way"),
        ("radial", "Radial", "a circular wave"),
        ("random", "Random", "in a seeded random order")])
    status: StringProperty(name="Status", default="")


# ---- inputs -------------------------------------------------------------------------------------------

def rest_arrays(obj):
    """Rest skin of `obj` (its own mesh, object space): float32 (n, 3) positions, uint32 (m, 3) triangles."""
    me = obj.data
    n = len(me.vertices)
    pos = np.empty(3 * n, np.float32)
    me.vertices.foreach_get("co", pos)
    me.calc_loop_triangles()
    tri = np.empty(3 * len(me.loop_triangles), np.uint32)
    me.loop_triangles.foreach_get("vertices", tri)
    return pos.reshape(-1, 3), tri.reshape(-1, 3)


def group_members(obj):
    """Per vertex group index: bool (n,) of the vertices with a weight above 0. One pass over the mesh."""
    n = len(obj.data.vertices)
    members = {g.index: np.zeros(n, bool) for g in obj.vertex_groups}
    for v in obj.data.vertices:
        for g in v.groups:
            if g.weight > 0 and g.group in members:
                members[g.group][v.index] = True
    return members


def tract_faces(obj, tri):
    """Triangle indices per tract: a triangle goes to the first tract whose group holds its three vertices."""
    settings = obj.pteryla
    taken = np.zeros(len(tri), bool)
    members = group_members(obj)
    out = []
    for t in settings.tracts:
        where = f"tract '{t.name}'"
        if not t.vertex_group:
            raise ValueError(f"{where}: choose a vertex group")
        vg = obj.vertex_groups.get(t.vertex_group)
        if vg is None:
            raise ValueError(f"{where}: the vertex group '{t.vertex_group}' does not exist")
        faces = np.flatnonzero(members[vg.index][tri].all(axis=1) & ~taken)
        if len(faces) == 0:
            raise ValueError(f"{where}: the vertex group '{t.vertex_group}' holds no face (all three vertices "
                             f"of a triangle must be in it, and not taken by an earlier tract)")
        taken[faces] = True
        out.append(faces.astype(np.uint32))
    return out


def body_axis(obj, pos):
    """Head-to-tail axis points in object space: a curve's points in order, an empty's Z axis, or the
    longest bounding-box axis."""
    s = obj.pteryla
    ax = s.axis_object
    if ax is not None:
        to_local = obj.matrix_world.inverted()
        if ax.type == "CURVE":
            ev = ax.evaluated_get(bpy.context.evaluated_depsgraph_get())
            me = ev.to_mesh()
            try:
                pts = [tuple(to_local @ (ax.matrix_world @ v.co)) for v in me.vertices]
            finally:
                ev.to_mesh_clear()
            pts = [p for i, p in enumerate(pts) if i == 0 or p != pts[i - 1]]
            if len(pts) < 2:
                raise ValueError(f"axis curve '{ax.name}' has fewer than two distinct points")
            return pts
        m = ax.matrix_world
        a = to_local @ m.translation
        b = to_local @ (m.translation + m.to_3x3().col[2].normalized())
        return [tuple(a), tuple(b)]
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    k = int(np.argmax(hi - lo))
    c = (lo + hi) / 2
    a, b = c.copy(), c.copy()
    a[k], b[k] = hi[k], lo[k]
    return [tuple(float(x) for x in a), tuple(float(x) for x in b)]


def feather_path(t):
    if t.feather == "FILE":
        if not t.feather_file:
            raise ValueError(f"tract '{t.name}': choose a feather file")
        return bpy.path.abspath(t.feather_file)
    return os.path.join(_module().data_directory(), "feathers", t.feather + ".json")


def setup_dict(obj, pos, tri):
    """The coat set-up in the scene format's sections (also what export_scene writes)."""
    s = obj.pteryla
    if len(s.tracts) == 0:
        raise ValueError("add a tract (a vertex group) first")
    faces = tract_faces(obj, tri)
    tracts = []
    for t, f in zip(s.tracts, faces):
        d = {"name": t.name, "faces": f.tolist(), "feather": feather_path(t)}
        if t.use_count:
            d["count"] = int(t.count)
        else:
            d["density"] = float(t.density)
        if t.seed >= 0:
            d["seed"] = int(t.seed)
        if s.moult and not t.moult:
            d["moult"] = False
        tracts.append(d)
    names = [t.name for t in s.tracts]
    if len(set(names)) != len(names):
        raise ValueError("tract names must be unique")
    axis = body_axis(obj, pos)
    setup = {"seed": int(s.seed), "tracts": tracts, "directions": {"axis": [list(p) for p in axis]},
             "ordering": {"method": s.ordering}, "packing": {"method": s.packing}}
    if s.moult:
        setup["moult"] = {"start": float(s.moult_start), "duration": float(s.moult_duration),
                          "window": float(s.moult_window), "sequence": s.moult_sequence}
    return setup


def check_mesh(obj, pos, tri):
    if len(tri) == 0:
        raise ValueError(f"'{obj.name}' has no faces: pteryla feathers a closed or open triangle surface")
    bad = np.flatnonzero(~np.isfinite(pos).all(axis=1))
    if len(bad):
        raise ValueError(f"'{obj.name}': vertex {int(bad[0])} has a coordinate that is not a finite number")


def session_for(obj):
    """The object's session, built again when its inputs changed."""
    pt = _module()
    pos, tri = rest_arrays(obj)
    check_mesh(obj, pos, tri)
    setup = setup_dict(obj, pos, tri)
    key = (json.dumps(setup, sort_keys=True), pos.tobytes(), tri.tobytes())
    cached = _sessions.get(obj.name)
    if cached is not None and cached[1] == key:
        return cached[0]
    _sessions.pop(obj.name, None)
    s = pt.Session(pos, tri, setup)
    _sessions[obj.name] = (s, key)
    return s


def posed_positions(obj, depsgraph):
    """The evaluated (deformed) skin in object space, or None when it is the rest skin."""
    ev = obj.evaluated_get(depsgraph)
    me = ev.to_mesh()
    try:
        n = len(me.vertices)
        if n != len(obj.data.vertices):
            raise ValueError(f"'{obj.name}': the deformed mesh has {n} vertices, the mesh {len(obj.data.vertices)}: "
                             "modifiers that add or remove vertices cannot pose the coat")
        pos = np.empty(3 * n, np.float32)
        me.vertices.foreach_get("co", pos)
    finally:
        ev.to_mesh_clear()
    return pos.reshape(-1, 3)


# ---- the coat object ----------------------------------------------------------------------------------

def _material(m):
    """A Cycles/EEVEE material for one pteryla material (colour and alpha textures, or the base colour)."""
    name = "pteryla_" + m["name"]
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.use_nodes = True
    mat.blend_method = "CLIP"
    mat.shadow_method = "CLIP"
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    r, g, b = m["base_color"]
    bsdf.inputs["Base Color"].default_value = (r, g, b, 1.0)
    uv = nt.nodes.new("ShaderNodeUVMap")
    uv.uv_map = "UVMap"
    if m["texture"] and os.path.isfile(m["texture"]):
        tex = nt.nodes.new("ShaderNodeTexImage")
        tex.image = bpy.data.images.load(m["texture"], check_existing=True)
        nt.links.new(uv.outputs["UV"], tex.inputs["Vector"])
        nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    alpha = nt.nodes.new("ShaderNodeAttribute")
    alpha.attribute_name = "alpha"
    if m["alpha_texture"] and os.path.isfile(m["alpha_texture"]):
        atex = nt.nodes.new("ShaderNodeTexImage")
        atex.image = bpy.data.images.load(m["alpha_texture"], check_existing=True)
        atex.image.colorspace_settings.name = "Non-Color"
        nt.links.new(uv.outputs["UV"], atex.inputs["Vector"])
        mul = nt.nodes.new("ShaderNodeMath")
        mul.operation = "MULTIPLY"
        nt.links.new(atex.outputs["Color"], mul.inputs[0])
        nt.links.new(alpha.outputs["Fac"], mul.inputs[1])
        nt.links.new(mul.outputs["Value"], bsdf.inputs["Alpha"])
    else:
        nt.links.new(alpha.outputs["Fac"], bsdf.inputs["Alpha"])
    return mat


def coat_object(skin):
    name = skin.name + "_coat"
    obj = bpy.data.objects.get(name)
    if obj is None or obj.type != "MESH":
        me = bpy.data.meshes.new(name)
        obj = bpy.data.objects.new(name, me)
        for coll in skin.users_collection:
            coll.objects.link(obj)
    obj.parent = skin
    obj.matrix_parent_inverse.identity()
    obj.matrix_basis.identity()
    return obj


def write_coat(skin, frame):
    """Writes the frame into "<name>_coat": rebuilt when the topology changed, else only moved."""
    obj = coat_object(skin)
    me = obj.data
    pos = frame.positions
    tris = frame.triangles
    same = len(me.vertices) == len(pos) and len(me.polygons) == len(tris)
    if same:
        me.vertices.foreach_set("co", pos.ravel())
        me.update()
        return obj
    me.clear_geometry()
    me.vertices.add(len(pos))
    me.vertices.foreach_set("co", pos.ravel())
    me.loops.add(tris.size)
    me.loops.foreach_set("vertex_index", tris.ravel().astype(np.int32))
    me.polygons.add(len(tris))
    me.polygons.foreach_set("loop_start", np.arange(0, tris.size, 3, dtype=np.int32))
    me.polygons.foreach_set("loop_total", np.full(len(tris), 3, np.int32))
    uv = me.uv_layers.new(name="UVMap")
    if len(frame.uvs) == len(pos):
        uv.data.foreach_set("uv", frame.uvs[tris.ravel()].ravel())
    fid = me.attributes.new("feather_id", "INT", "POINT")
    fid.data.foreach_set("value", frame.vertex_feathers.astype(np.int32))
    alpha = me.attributes.new("alpha", "FLOAT", "POINT")
    alpha.data.foreach_set("value", frame.alphas if len(frame.alphas) == len(pos) else np.ones(len(pos), np.float32))
    me.materials.clear()
    for m in frame.materials:
        me.materials.append(_material(m))
    mat_index = np.zeros(len(tris), np.int32)
    for feather, first, count, material in frame.ranges:
        mat_index[first // 3:(first + count) // 3] = material
    me.polygons.foreach_set("material_index", mat_index)
    me.polygons.foreach_set("use_smooth", np.ones(len(tris), bool))
    me.update()  # no validate(): it would drop degenerate feather triangles and break feather_id's alignment
    return obj


def evaluate_into_coat(skin, depsgraph=None, report_progress=True, scene=None):
    """Evaluates the skin's session (posed when a depsgraph is given) and writes the coat. Returns seconds."""
    t0 = time.perf_counter()
    s = session_for(skin)
    scene = scene or bpy.context.scene
    s.set_lod(skin.pteryla.lod)
    s.pose_mode = skin.pteryla.pose_mode
    s.set_time(scene.frame_current / (scene.render.fps / scene.render.fps_base))
    if depsgraph is not None:
        s.set_pose(posed_positions(skin, depsgraph))
    else:
        s.clear_pose()
    wm = bpy.context.window_manager
    stages = ["distribute", "interpolate", "pack", "mesh"]
    wm.progress_begin(0, 100)
    try:
        def progress(stage, fraction):
            k = stages.index(stage) if stage in stages else 0
            wm.progress_update(int(100 * (k + fraction) / len(stages)))
            return True
        if not s.evaluate(progress=progress if report_progress else None):
            raise RuntimeError("evaluation cancelled")
    finally:
        wm.progress_end()
    write_coat(skin, s.frame())
    dt = time.perf_counter() - t0
    skin.pteryla.status = f"{s.frame().feather_count} feathers, {dt:.2f} s"
    return dt


def _message(e):
    el = getattr(e, "element", "")
    return f"{e} ({el})" if el and el not in str(e) else str(e)


# ---- operators --------------------------------------------------------------------------------------

def _active_mesh(context):
    obj = context.active_object
    if obj is None or obj.type != "MESH":
        return None
    return obj


class PTERYLA_OT_feather(bpy.types.Operator):
    """Feather the active mesh: creates or updates the child mesh "<name>_coat\""""
    bl_idname = "pteryla.feather"
    bl_label = "Feather"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _active_mesh(context) is not None

    def execute(self, context):
        obj = _active_mesh(context)
        try:
            depsgraph = context.evaluated_depsgraph_get()
            dt = evaluate_into_coat(obj, depsgraph)
        except Exception as e:
            obj.pteryla.status = "error: " + _message(e)
            self.report({"ERROR"}, "pteryla: " + _message(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"pteryla: {obj.pteryla.status} ({dt:.2f} s)")
        return {"FINISHED"}


class PTERYLA_OT_tract_add(bpy.types.Operator):
    """Add a tract from the active vertex group"""
    bl_idname = "pteryla.tract_add"
    bl_label = "Add tract"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _active_mesh(context) is not None

    def execute(self, context):
        obj = _active_mesh(context)
        t = obj.pteryla.tracts.add()
        vg = obj.vertex_groups.active
        t.vertex_group = vg.name if vg else ""
        t.name = vg.name if vg else f"tract{len(obj.pteryla.tracts)}"
        obj.pteryla.active_tract = len(obj.pteryla.tracts) - 1
        return {"FINISHED"}


class PTERYLA_OT_tract_remove(bpy.types.Operator):
    """Remove the selected tract"""
    bl_idname = "pteryla.tract_remove"
    bl_label = "Remove tract"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = _active_mesh(context)
        return obj is not None and len(obj.pteryla.tracts) > 0

    def execute(self, context):
        s = _active_mesh(context).pteryla
        s.tracts.remove(s.active_tract)
        s.active_tract = max(0, min(s.active_tract, len(s.tracts) - 1))
        return {"FINISHED"}


def write_obj(path, pos, tri):
    with open(path, "w") as f:
        f.write("# pteryla_blender: the rest skin, triangulated, vertex order kept\n")
        for p in pos:
            f.write("v %.9g %.9g %.9g\n" % (p[0], p[1], p[2]))
        for t in tri:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def export_scene(obj, path):
    """Writes a pteryla scene file and the skin beside it (<stem>.obj): opens in the CLI and the viewer."""
    pos, tri = rest_arrays(obj)
    check_mesh(obj, pos, tri)
    setup = setup_dict(obj, pos, tri)
    stem = os.path.splitext(os.path.basename(path))[0]
    mesh_path = os.path.join(os.path.dirname(os.path.abspath(path)), stem + ".obj")
    write_obj(mesh_path, pos, tri)
    feathers, tracts = {}, []
    for t in setup["tracts"]:
        fname = os.path.splitext(os.path.basename(t["feather"]))[0]
        feathers.setdefault(fname, t["feather"])
        # The same sections the host API's typed set-up stands for (src/host/session.cpp), so the
        # CLI evaluates the coat the add-on shows.
        d = dict(t, feather=fname, feather_scale="auto", feather_spacings=3.5, relax={"iterations": 40},
                 parameterization={"method": "projection"})
        tracts.append(d)
    scene = {"pteryla": 1, "name": obj.name, "seed": setup["seed"], "mesh": os.path.basename(mesh_path),
             "feathers": feathers, "tracts": tracts, "directions": setup["directions"],
             "ordering": dict(setup["ordering"], **({"axis": setup["directions"]["axis"]}
                                                    if setup["ordering"]["method"] == "axis" else {})),
             "packing": setup["packing"], "render": {"lod": obj.pteryla.lod}}
    if "moult" in setup:
        scene["moult"] = setup["moult"]
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
    return scene


def import_scene(context, path):
    """A new mesh object from a pteryla scene whose mesh is an OBJ, with its tracts as vertex groups."""
    with open(path) as f:
        scene = json.load(f)
    base = os.path.dirname(os.path.abspath(path))
    mesh_path = os.path.join(base, scene.get("mesh", ""))
    if not mesh_path.lower().endswith(".obj") or not os.path.isfile(mesh_path):
        raise ValueError(f"{path}: mesh: only an existing .obj skin can be imported, got '{scene.get('mesh')}'")
    verts, faces = [], []
    with open(mesh_path) as f:
        for line in f:
            p = line.split()
            if p and p[0] == "v":
                verts.append(tuple(float(x) for x in p[1:4]))
            elif p and p[0] == "f":
                faces.append(tuple(int(x.split("/")[0]) - 1 for x in p[1:]))
    me = bpy.data.meshes.new(scene.get("name", "pteryla"))
    me.from_pydata(verts, [], faces)
    me.update()
    obj = bpy.data.objects.new(me.name, me)
    context.collection.objects.link(obj)
    s = obj.pteryla
    s.seed = int(scene.get("seed", 1))
    s.ordering = scene.get("ordering", {}).get("method", "axis")
    s.packing = scene.get("packing", {}).get("method", "drape")
    s.lod = float(scene.get("render", {}).get("lod", s.lod))
    moult = scene.get("moult")
    if isinstance(moult, dict) and moult.get("enabled", True):
        s.moult = True
        s.moult_start = float(moult.get("start", 0.0))
        s.moult_duration = float(moult.get("duration", 1.0))
        s.moult_window = float(moult.get("window", 0.2))
        seq = moult.get("sequence", "centre_out").replace("center", "centre")
        if seq not in {i.identifier for i in s.bl_rna.properties["moult_sequence"].enum_items}:
            raise ValueError(f"{path}: moult.sequence: '{seq}' has no choice in the add-on")
        s.moult_sequence = seq
    feathers = scene.get("feathers", {})
    bundled = os.path.join(_module().data_directory(), "feathers")
    for i, t in enumerate(scene.get("tracts", [])):
        if "faces" not in t:
            raise ValueError(f"{path}: tracts[{i}]: only tracts given by 'faces' can be imported")
        vg = obj.vertex_groups.new(name=t.get("name", f"tract{i}"))
        vg.add(sorted({v for fi in t["faces"] for v in faces[fi]}), 1.0, "REPLACE")
        tr = s.tracts.add()
        tr.name = vg.name
        tr.vertex_group = vg.name
        fpath = feathers.get(t.get("feather", ""), "")
        fpath = fpath if os.path.isabs(fpath) else os.path.join(base, fpath)
        stem = os.path.splitext(os.path.basename(fpath))[0]
        if os.path.normpath(os.path.dirname(fpath)) == os.path.normpath(bundled):
            tr.feather = stem
        else:
            tr.feather = "FILE"
            tr.feather_file = fpath
        if "count" in t:
            tr.use_count, tr.count = True, int(t["count"])
        elif "density" in t:
            tr.use_count, tr.density = False, float(t["density"])
        if "seed" in t:
            tr.seed = int(t["seed"])
        if t.get("moult", True) is False:
            tr.moult = False
    return obj


class PTERYLA_OT_export_scene(bpy.types.Operator):
    """Write a pteryla scene file (and the skin as <name>.obj beside it) for the CLI and the viewer"""
    bl_idname = "pteryla.export_scene"
    bl_label = "Export pteryla scene"
    filepath: StringProperty(subtype="FILE_PATH")
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        return _active_mesh(context) is not None

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        try:
            export_scene(_active_mesh(context), bpy.path.abspath(self.filepath))
        except Exception as e:
            self.report({"ERROR"}, "pteryla: " + _message(e))
            return {"CANCELLED"}
        return {"FINISHED"}


class PTERYLA_OT_import_scene(bpy.types.Operator):
    """Import a pteryla scene file: its skin as a mesh, its tracts as vertex groups"""
    bl_idname = "pteryla.import_scene"
    bl_label = "Import pteryla scene"
    bl_options = {"REGISTER", "UNDO"}
    filepath: StringProperty(subtype="FILE_PATH")
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        try:
            obj = import_scene(context, bpy.path.abspath(self.filepath))
        except Exception as e:
            self.report({"ERROR"}, "pteryla: " + _message(e))
            return {"CANCELLED"}
        context.view_layer.objects.active = obj
        return {"FINISHED"}


# ---- panel -------------------------------------------------------------------------------------------

class PTERYLA_UL_tracts(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index):
        layout.prop(item, "name", text="", emboss=False, icon="GROUP_VERTEX")
        layout.label(text=item.vertex_group)


class PTERYLA_PT_feathers(bpy.types.Panel):
    bl_label = "Feathers"
    bl_idname = "PTERYLA_PT_feathers"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Feathers"

    @classmethod
    def poll(cls, context):
        return _active_mesh(context) is not None

    def draw(self, context):
        obj = _active_mesh(context)
        s = obj.pteryla
        col = self.layout.column()
        row = col.row()
        row.template_list("PTERYLA_UL_tracts", "", s, "tracts", s, "active_tract", rows=3)
        sub = row.column(align=True)
        sub.operator("pteryla.tract_add", icon="ADD", text="")
        sub.operator("pteryla.tract_remove", icon="REMOVE", text="")
        if 0 <= s.active_tract < len(s.tracts):
            t = s.tracts[s.active_tract]
            box = col.box()
            box.prop_search(t, "vertex_group", obj, "vertex_groups")
            box.prop(t, "feather")
            if t.feather == "FILE":
                box.prop(t, "feather_file")
            box.prop(t, "use_count")
            box.prop(t, "count" if t.use_count else "density")
            box.prop(t, "seed")
            if s.moult:
                box.prop(t, "moult")
        col.prop(s, "seed")
        col.prop(s, "axis_object")
        col.prop(s, "ordering")
        col.prop(s, "packing")
        col.prop(s, "lod")
        col.prop(s, "live")
        col.prop(s, "pose_mode")
        col.prop(s, "moult")
        if s.moult:
            box = col.box()
            box.prop(s, "moult_start")
            box.prop(s, "moult_duration")
            box.prop(s, "moult_window")
            box.prop(s, "moult_sequence")
        col.operator("pteryla.feather", icon="OUTLINER_OB_CURVES")
        row = col.row(align=True)
        row.operator("pteryla.import_scene", text="Import", icon="IMPORT")
        row.operator("pteryla.export_scene", text="Export", icon="EXPORT")
        if s.status:
            col.label(text=s.status, icon="ERROR" if s.status.startswith("error") else "INFO")


# ---- frame change ----------------------------------------------------------------------------------

@persistent
def on_frame_change(scene, depsgraph=None):
    """Re-evaluates every live coat of the scene with its skin's deformed mesh. Never raises."""
    for obj in scene.objects:
        try:
            if obj.type != "MESH" or not obj.pteryla.live or not len(obj.pteryla.tracts):
                continue
            if bpy.data.objects.get(obj.name + "_coat") is None:
                continue  # not feathered yet: "Feather" first
            evaluate_into_coat(obj, depsgraph or bpy.context.evaluated_depsgraph_get(), report_progress=False,
                               scene=scene)
        except Exception as e:
            obj.pteryla.status = "error: " + _message(e)
            print(f"pteryla: {obj.name}: {_message(e)}", file=sys.stderr)
            if not isinstance(e, (ValueError, RuntimeError)) and type(e).__name__ != "Error":
                traceback.print_exc()


def _menu_import(self, context):
    self.layout.operator(PTERYLA_OT_import_scene.bl_idname, text="pteryla scene (.json)")


def _menu_export(self, context):
    self.layout.operator(PTERYLA_OT_export_scene.bl_idname, text="pteryla scene (.json)")


_classes = (PterylaPreferences, PterylaTract, PterylaSettings, PTERYLA_OT_feather, PTERYLA_OT_tract_add,
            PTERYLA_OT_tract_remove, PTERYLA_OT_export_scene, PTERYLA_OT_import_scene, PTERYLA_UL_tracts,
            PTERYLA_PT_feathers)


def register():
    for c in _classes:
        bpy.utils.register_class(c)
    bpy.types.Object.pteryla = PointerProperty(type=PterylaSettings)
    bpy.app.handlers.frame_change_post.append(on_frame_change)
    bpy.types.TOPBAR_MT_file_import.append(_menu_import)
    bpy.types.TOPBAR_MT_file_export.append(_menu_export)


def unregister():
    bpy.types.TOPBAR_MT_file_export.remove(_menu_export)
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
    if on_frame_change in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.remove(on_frame_change)
    del bpy.types.Object.pteryla
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
    _sessions.clear()
