"""Blender 3.4's own glTF importer opens pteryla's glTF exports (issue #25):

    blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_gltf_import.py

Environment: PTERYLA_CLI (the pteryla program), PTERYLA_DATA (data/), PTERYLA_TEST_OUT (a scratch
directory). `pteryla export` writes the bundled bird (.glb, 20% detail) and a moult range (.gltf); each
is imported, and the triangles, materials with their textures and the frame nodes Blender made are checked
against the file's own accessors. Each check raises AssertionError (exit 1).
"""
import json
import os
import struct
import subprocess
import tempfile
import time
import warnings

import bpy
import numpy

# Debian 12 ships Blender 3.4.1 with numpy 1.24, which removed the `numpy.bool` alias that Blender 3.4's
# glTF importer still uses for smooth shading (io_scene_gltf2/blender/imp/gltf2_blender_mesh.py,
# set_poly_smoothing): without this alias the importer fails on any glTF with normals, pteryla's or not.
# Blender 3.5 uses `bool`; docs/export.md tells users of the Debian package the same one-line fix.
with warnings.catch_warnings():
    warnings.simplefilter("ignore", FutureWarning)
    try:
        numpy.bool  # noqa: B018  (AttributeError on numpy >= 1.24)
    except AttributeError:
        numpy.bool = bool

OUT = os.environ.get("PTERYLA_TEST_OUT") or tempfile.mkdtemp(prefix="pteryla_gltf_")
os.makedirs(OUT, exist_ok=True)
DATA = os.environ["PTERYLA_DATA"]


def export(scene, out, *extra):
    t0 = time.perf_counter()
    r = subprocess.run([os.environ["PTERYLA_CLI"], "export", os.path.join(DATA, "scenes", scene), "--out", out,
                        "-q", *extra], capture_output=True, text=True)
    assert r.returncode == 0, f"pteryla export {scene}: exit {r.returncode}: {r.stderr}"
    print(f"test_gltf_import: exported {scene} in {time.perf_counter() - t0:.1f} s", flush=True)


def gltf_json(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF":
        length = struct.unpack_from("<I", data, 12)[0]
        return json.loads(data[20:20 + length])
    return json.loads(data)


def triangles_in_file(doc):
    """Triangles per mesh name, from the index accessors (mode 4 = TRIANGLES)."""
    out = {}
    for mesh in doc["meshes"]:
        n = 0
        for p in mesh["primitives"]:
            assert p.get("mode", 4) == 4
            n += doc["accessors"][p["indices"]]["count"] // 3
        out[mesh.get("name", "")] = n
    return out


def import_file(path):
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)
    for m in list(bpy.data.meshes):
        bpy.data.meshes.remove(m)
    for m in list(bpy.data.materials):
        bpy.data.materials.remove(m)
    for i in list(bpy.data.images):
        bpy.data.images.remove(i)
    t0 = time.perf_counter()
    result = bpy.ops.import_scene.gltf(filepath=path)
    assert result == {"FINISHED"}, f"import of {path}: {result}"
    print(f"test_gltf_import: imported {os.path.basename(path)} in {time.perf_counter() - t0:.1f} s", flush=True)


def check_import(path, frames):
    doc = gltf_json(path)
    import_file(path)
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    assert len(meshes) == frames, f"{path}: {len(meshes)} mesh objects, expected one per frame ({frames})"
    want = sum(triangles_in_file(doc).values())
    got = 0
    for o in meshes:
        o.data.calc_loop_triangles()
        got += len(o.data.loop_triangles)
    # Blender merges nothing and drops nothing: every triangle of the file is in the scene.
    assert got == want, f"{path}: Blender has {got} triangles, the file {want}"
    used = {m for o in meshes for m in o.data.materials if m is not None}
    assert any(m.name.split(".")[0] == "skin" for m in used), f"{path}: no skin material"
    feather_mats = [m for m in used if m.name.split(".")[0] != "skin"]
    assert feather_mats, f"{path}: no feather materials imported"
    textured = {m["name"]: "baseColorTexture" in m.get("pbrMetallicRoughness", {}) for m in doc["materials"]}
    for m in feather_mats:
        assert m.use_nodes and m.node_tree, f"{path}: material {m.name} has no shader nodes"
        assert m.blend_method in {"BLEND", "HASHED", "CLIP"}, f"{path}: material {m.name} is opaque"
        if not textured.get(m.name.split(".")[0], False):
            continue  # a colour-only feather: nothing to load
        images = [n.image for n in m.node_tree.nodes if n.type == "TEX_IMAGE" and n.image is not None]
        assert images, f"{path}: material {m.name} lost its colour texture"
        assert images[0].size[0] > 0 and images[0].size[1] > 0, f"{path}: material {m.name}: empty texture"
    assert any(textured.values()) == any(textured.get(m.name.split(".")[0], False) for m in feather_mats)
    return got


def main():
    bird = os.path.join(OUT, "bird.glb")
    export("bird.json", bird, "--lod", "0.2")
    tris = check_import(bird, 1)
    print(f"test_gltf_import: bird ok ({tris} triangles)", flush=True)
    moult = os.path.join(OUT, "moult.gltf")
    export("moult.json", moult, "--from", "2", "--to", "4", "--fps", "1", "--lod", "0.1")
    check_import(moult, 3)
    # The flipbook: the frames' visibility animation came through as an action.
    assert bpy.data.actions, "the frame range's animation was not imported"
    print("test_gltf_import: moult range ok", flush=True)


main()
