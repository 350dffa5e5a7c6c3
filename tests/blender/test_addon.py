"""Headless test of the Blender add-on (plugins/blender/pteryla_blender):

    blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon.py

Environment: PTERYLA_PYTHON_DIR (<build>/python), PTERYLA_CLI (the pteryla program), PTERYLA_TEST_OUT
(a scratch directory). Each check raises AssertionError, which --python-exit-code turns into exit 1.
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "plugins", "blender"))
sys.path.insert(0, os.environ["PTERYLA_PYTHON_DIR"])  # Blender ignores PYTHONPATH
OUT = os.environ.get("PTERYLA_TEST_OUT") or tempfile.mkdtemp(prefix="pteryla_blender_")
os.makedirs(OUT, exist_ok=True)

import addon_utils  # noqa: E402
import pteryla  # noqa: E402

timings = {}


def step(name):
    def wrap(f):
        def run(*a, **k):
            t0 = time.perf_counter()
            r = f(*a, **k)
            timings[name] = time.perf_counter() - t0
            print(f"test_addon: {name} ok ({timings[name]:.2f} s)", flush=True)
            return r
        return run
    return wrap


def clear_scene():
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)


def make_body():
    """A capsule-like body along X (a stretched UV sphere) with an armature of two bones bending at x=0,
    and vertex groups "front" (x > 0) and "back" (x <= 0) for the tracts."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=24, ring_count=12, radius=1.0)
    body = bpy.context.active_object
    body.name = "body"
    body.data.transform(np.diag([2.0, 1.0, 1.0, 1.0]).tolist())
    co = np.array([v.co[:] for v in body.data.vertices])
    front = body.vertex_groups.new(name="front")
    back = body.vertex_groups.new(name="back")
    front.add([i for i, c in enumerate(co) if c[0] > 0], 1.0, "REPLACE")
    back.add([i for i, c in enumerate(co) if c[0] <= 0], 1.0, "REPLACE")
    # Skinning weights: a smooth blend over x in [-0.5, 0.5].
    g_root = body.vertex_groups.new(name="root")
    g_tip = body.vertex_groups.new(name="tip")
    for i, c in enumerate(co):
        w = min(1.0, max(0.0, c[0] + 0.5))
        if w < 1:
            g_root.add([i], 1 - w, "REPLACE")
        if w > 0:
            g_tip.add([i], w, "REPLACE")
    arm_data = bpy.data.armatures.new("rig")
    rig = bpy.data.objects.new("rig", arm_data)
    bpy.context.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    root = arm_data.edit_bones.new("root")
    root.head, root.tail = (-2.0, 0, 0), (0.0, 0, 0)
    tip = arm_data.edit_bones.new("tip")
    tip.head, tip.tail = (0.0, 0, 0), (2.0, 0, 0)
    tip.parent = root
    bpy.ops.object.mode_set(mode="OBJECT")
    mod = body.modifiers.new("rig", "ARMATURE")
    mod.object = rig
    pb = rig.pose.bones["tip"]
    pb.rotation_mode = "XYZ"
    pb.rotation_euler = (0, 0, 0)
    pb.keyframe_insert("rotation_euler", frame=1)
    pb.rotation_euler = (0, 0, math.radians(40))
    pb.keyframe_insert("rotation_euler", frame=5)
    bpy.context.view_layer.objects.active = body
    return body, rig


def add_tracts(body):
    s = body.pteryla
    s.seed = 7
    s.lod = 0.3
    for group, feather, count, density in (("front", "covert", 50, 0), ("back", "contour", 0, 8.0)):
        body.vertex_groups.active_index = body.vertex_groups[group].index
        assert bpy.ops.pteryla.tract_add() == {"FINISHED"}
        t = s.tracts[-1]
        t.feather = feather
        t.use_count = count > 0
        if count:
            t.count = count
        else:
            t.density = density


def coat_positions(coat):
    p = np.empty(3 * len(coat.data.vertices), np.float32)
    coat.data.vertices.foreach_get("co", p)
    return p.reshape(-1, 3)


@step("enable")
def enable():
    mod = addon_utils.enable("pteryla_blender", default_set=True, handle_error=None)
    assert mod is not None, "the add-on did not enable"
    assert hasattr(bpy.types.Object, "pteryla") and hasattr(bpy.ops.pteryla, "feather")
    return mod


@step("feather")
def feather(body):
    bpy.context.scene.frame_set(1)
    r = bpy.ops.pteryla.feather()
    assert r == {"FINISHED"}, (r, body.pteryla.status)
    coat = bpy.data.objects["body_coat"]
    assert coat.parent == body
    return coat


@step("count_vs_cli")
def count_vs_cli(addon, body, coat):
    scene_path = os.path.join(OUT, "body.json")
    addon.export_scene(body, scene_path)
    out = subprocess.run([os.environ["PTERYLA_CLI"], "check", scene_path], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    cli = json.loads(out.stdout)
    fid = np.empty(len(coat.data.vertices), np.int32)
    coat.data.attributes["feather_id"].data.foreach_get("value", fid)
    session = addon._sessions["body"][0]
    n = session.frame().feather_count
    print(f"test_addon: CLI feathers {cli['feathers']}, add-on {n}, hidden {cli['hidden_feathers']}")
    assert cli["feathers"] == n, (cli["feathers"], n)
    # The density tract's count depends on the skin's area: the CLI read the same skin from the scene.
    assert n > 50 + 10
    # Every present feather with triangles shows up in feather_id, and nothing else does.
    present = set(session.frame().ranges[:, 0].tolist())
    assert set(np.unique(fid).tolist()) == present
    return scene_path


@step("import_round_trip")
def import_round_trip(addon, body, coat, scene_path):
    """The exported scene imported back feathers into the same coat (same skin, tracts, seed)."""
    obj = addon.import_scene(bpy.context, scene_path)
    try:
        s, t = obj.pteryla, body.pteryla
        assert [(x.name, x.vertex_group, x.feather, x.use_count, x.count if x.use_count else x.density)
                for x in s.tracts] == \
            [(x.name, x.name, x.feather, x.use_count, x.count if x.use_count else x.density) for x in t.tracts]
        assert (s.seed, s.ordering, s.packing, s.lod) == (t.seed, t.ordering, t.packing, t.lod)
        bpy.context.view_layer.objects.active = obj
        assert bpy.ops.pteryla.feather() == {"FINISHED"}, s.status
        again = bpy.data.objects[obj.name + "_coat"]
        assert np.array_equal(coat_positions(again), coat_positions(coat))
    finally:
        for o in (bpy.data.objects.get(obj.name + "_coat"), obj):
            if o is not None:
                bpy.data.objects.remove(o, do_unlink=True)
        bpy.context.view_layer.objects.active = body


@step("attributes_and_materials")
def attributes_and_materials(coat):
    me = coat.data
    assert me.attributes["feather_id"].data_type == "INT" and me.attributes["feather_id"].domain == "POINT"
    assert "alpha" in me.attributes and me.uv_layers.get("UVMap") is not None
    names = sorted(m.name for m in me.materials)
    assert names == ["pteryla_contour", "pteryla_covert"], names
    used = {p.material_index for p in me.polygons}
    assert used == {0, 1}, used
    for m in me.materials:
        assert m.use_nodes and any(n.type == "BSDF_PRINCIPLED" for n in m.node_tree.nodes)


@step("frames_follow_the_armature")
def frames_follow(addon, body, coat):
    scene = bpy.context.scene
    scene.frame_set(1)
    rest = coat_positions(coat)
    frame_times = []
    for f in (2, 3, 4, 5):
        t0 = time.perf_counter()
        scene.frame_set(f)
        frame_times.append(time.perf_counter() - t0)
    bent = coat_positions(coat)
    assert bent.shape == rest.shape
    moved = np.linalg.norm(bent - rest, axis=1)
    assert moved.max() > 0.3, moved.max()  # the tip half swung by 40 degrees
    assert "error" not in body.pteryla.status, body.pteryla.status
    # The library on the same posed arrays, in the same pose mode, gives the coat the add-on wrote.
    def library(mode):
        depsgraph = bpy.context.evaluated_depsgraph_get()
        posed = addon.posed_positions(body, depsgraph)
        pos, tri = addon.rest_arrays(body)
        s = pteryla.Session(pos, tri, addon.setup_dict(body, pos, tri))
        s.set_lod(body.pteryla.lod)
        s.set_time(scene.frame_current / scene.render.fps)
        s.pose_mode = mode
        s.set_pose(posed)
        assert s.evaluate()
        return s.frame().positions
    assert body.pteryla.pose_mode == "follow"  # the default: the laid coat rides the skin
    lib = library("follow")
    assert lib.shape == bent.shape and np.array_equal(lib, bent), np.abs(lib - bent).max()
    timings["frame_change_follow_max"] = max(frame_times)
    # Repack: every pose laid again.
    body.pteryla.pose_mode = "repack"
    scene.frame_set(4)
    t0 = time.perf_counter()
    scene.frame_set(5)
    timings["frame_change_repack"] = time.perf_counter() - t0
    repacked = coat_positions(coat)
    assert np.linalg.norm(repacked - rest, axis=1).max() > 0.3
    lib = library("repack")
    assert lib.shape == repacked.shape and np.array_equal(lib, repacked), np.abs(lib - repacked).max()
    body.pteryla.pose_mode = "follow"
    # Back at the rest frame the coat is the rest coat again.
    scene.frame_set(1)
    assert np.allclose(coat_positions(coat), rest, atol=1e-6)


@step("tract_seed_and_moult")
def tract_seed_and_moult(addon, body):
    """A tract's own seed re-scatters that tract only; the moult toggle takes feathers out mid-moult, not
    from a tract that opts out, and round-trips through the scene file."""
    scene = bpy.context.scene
    scene.frame_set(1)

    def frame():
        assert bpy.ops.pteryla.feather() == {"FINISHED"}, body.pteryla.status
        f = addon._sessions["body"][0].frame()
        return f.origins.copy(), f.tracts.copy(), f.present.copy()
    o0, tr0, _ = frame()
    body.pteryla.tracts[0].seed = 12
    o1, tr1, _ = frame()
    assert not np.array_equal(o0[tr0 == 0], o1[tr1 == 0])
    assert np.array_equal(o0[tr0 == 1], o1[tr1 == 1])
    body.pteryla.tracts[0].seed = -1
    s = body.pteryla
    s.moult, s.moult_start, s.moult_duration, s.moult_window = True, 0.0, 0.5, 0.4
    s.tracts[1].moult = False
    scene.frame_set(7)  # t = 0.25 s: mid-moult
    _, tr, present = frame()
    assert not present[tr == 0].all() and present[tr == 1].all(), (present[tr == 0].mean(), present[tr == 1].mean())
    path = os.path.join(OUT, "moult.json")
    written = addon.export_scene(body, path)
    assert abs(written["moult"]["window"] - 0.4) < 1e-6 and written["tracts"][1]["moult"] is False
    obj = addon.import_scene(bpy.context, path)
    try:
        assert obj.pteryla.moult and obj.pteryla.moult_window == s.moult_window and not obj.pteryla.tracts[1].moult
    finally:
        bpy.data.objects.remove(obj, do_unlink=True)
        bpy.context.view_layer.objects.active = body
    s.moult = False
    s.tracts[1].moult = True
    scene.frame_set(1)
    frame()


@step("curve_axis")
def curve_axis(body, coat):
    """A curve as the body axis: the feathers follow it, so the coat changes; none again restores it."""
    scene = bpy.context.scene
    scene.frame_set(1)
    before = coat_positions(coat)
    curve_data = bpy.data.curves.new("spine", "CURVE")
    curve_data.dimensions = "3D"
    spline = curve_data.splines.new("POLY")
    spline.points.add(2)
    for p, co in zip(spline.points, [(2.2, 0, 0.3, 1), (0, 0, 0.8, 1), (-2.2, 0, 0.3, 1)]):
        p.co = co
    spine = bpy.data.objects.new("spine", curve_data)
    bpy.context.collection.objects.link(spine)
    body.pteryla.axis_object = spine
    bpy.context.view_layer.objects.active = body
    assert bpy.ops.pteryla.feather() == {"FINISHED"}, body.pteryla.status
    assert not np.array_equal(coat_positions(coat), before)
    body.pteryla.axis_object = None
    assert bpy.ops.pteryla.feather() == {"FINISHED"}, body.pteryla.status
    assert np.array_equal(coat_positions(coat), before)


@step("render")
def render(body, rig):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = 160, 90
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    body.hide_render = True  # only the coat: a transparent image would mean the coat did not render
    rig.hide_render = True
    cam_data = bpy.data.cameras.new("cam")
    cam = bpy.data.objects.new("cam", cam_data)
    scene.collection.objects.link(cam)
    cam.location = (0, -9, 2)
    cam.rotation_euler = (math.radians(78), 0, 0)
    scene.camera = cam
    light = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    scene.collection.objects.link(light)
    light.rotation_euler = (math.radians(40), 0, math.radians(30))
    path = os.path.join(OUT, "coat.png")
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path)
    px = np.array(img.pixels[:]).reshape(-1, 4)
    covered = float((px[:, 3] > 0.5).mean())
    print(f"test_addon: render covered fraction {covered:.3f}")
    assert covered > 0.02, covered
    assert px[px[:, 3] > 0.5, :3].max() > 0.02  # lit, not black


@step("bad_input")
def bad_input(addon):
    """A mesh without faces, a NaN vertex and an empty vertex group each give a report; Blender goes on."""
    def expect_report(obj, words):
        bpy.context.view_layer.objects.active = obj
        try:
            r = bpy.ops.pteryla.feather()
        except RuntimeError as e:  # bpy.ops turns an ERROR report into RuntimeError for the script
            msg = str(e)
        else:
            raise AssertionError(f"expected an error report, got {r}")
        assert all(w in msg for w in words), msg
        assert obj.pteryla.status.startswith("error"), obj.pteryla.status

    me = bpy.data.meshes.new("points")
    me.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [])
    pts = bpy.data.objects.new("points", me)
    bpy.context.collection.objects.link(pts)
    pts.vertex_groups.new(name="all").add([0, 1, 2], 1.0, "REPLACE")
    pts.pteryla.tracts.add().vertex_group = "all"
    expect_report(pts, ["no faces"])

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2)
    ico = bpy.context.active_object
    ico.name = "ico"
    ico.vertex_groups.new(name="all").add(list(range(len(ico.data.vertices))), 1.0, "REPLACE")
    ico.vertex_groups.new(name="empty")
    t = ico.pteryla.tracts.add()
    t.name, t.vertex_group = "all", "all"
    ico.data.vertices[5].co.x = float("nan")
    expect_report(ico, ["vertex 5", "finite"])
    ico.data.vertices[5].co.x = 0.2
    t.vertex_group = "empty"
    expect_report(ico, ["empty", "no face"])
    t.vertex_group = "all"
    t.use_count, t.count = True, 30
    assert bpy.ops.pteryla.feather() == {"FINISHED"}, ico.pteryla.status  # still working


def main():
    t_all = time.perf_counter()
    clear_scene()
    addon = enable()
    body, rig = make_body()
    add_tracts(body)
    coat = feather(body)
    scene_path = count_vs_cli(addon, body, coat)
    import_round_trip(addon, body, coat, scene_path)
    attributes_and_materials(coat)
    frames_follow(addon, body, coat)
    tract_seed_and_moult(addon, body)
    curve_axis(body, coat)
    render(body, rig)
    bad_input(addon)
    print("test_addon: timings " + ", ".join(f"{k} {v:.2f} s" for k, v in timings.items()))
    print(f"test_addon: all passed in {time.perf_counter() - t_all:.1f} s")


main()
