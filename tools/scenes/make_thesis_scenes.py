#!/usr/bin/env python3
"""Write the bundled thesis scenes (Streit 2003) into data/scenes/.

    python3 tools/scenes/make_thesis_scenes.py           # write
    python3 tools/scenes/make_thesis_scenes.py --check   # exit 1 if a committed scene differs

Scenes (all but bird.json, which tools/scenes/make_bird_scene.py writes):
  wing.json                 210 feathers in two tracts on wing.obj, skeleton bends down and up (Figs 8.6, 9.19)
  wing_flap.json            the wing with one quick downstroke; its primaries bend behind the motion and
                            spring back (a dynamic control: docs/controls.md, "Dynamic blend")
  moult.json                three patches moulting sequentially, radially and randomly (Figs 8.3-8.5)
  moult_radial.json         radial moult, strictly sequential and with random jitter (Fig 8.5)
  moult_helical.json        a sequential moult of helical (Zhang & Kanai) feathers growing on the collar
  crest.json                head.obj with a crest lifted by an expressive control (AnimFur)
  blend.json                ~140 feathers between three key feathers of one shape and three looks
                            (material blending, issue #30 item 2)
  patch.json                ~60 feathers, two key feathers, relaxed (Lloyd) follicles
  patch_grid.json, patch_hex.json, patch_stretched.json
                            the same patch with pinned grid / hexagonal / stretched follicles (Fig 9.11)
  sphere_small.json, sphere.json, sphere_large.json
                            426 feathers at three scales on the 1,600-triangle sphere (Fig 9.13)
  sphere_250_small.json, sphere_250.json, sphere_250_large.json
                            the same on the 250-triangle sphere (Fig 9.12)

Hand-placed follicle positions (flight feathers, patch layouts) are computed here from the meshes and
their side files, so the scenes follow the meshes when tools/meshgen changes them.
"""
import json
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENES = os.path.join(ROOT, "data", "scenes")
MESHES = os.path.join(ROOT, "data", "meshes")


def r5(x):
    return round(x, 5)


def vec(v):
    return [r5(c) for c in v]


CHECK_ONLY = "--check" in sys.argv[1:]
STALE = []


def write(name, scene):
    """Writes a scene; with --check only compares it with the committed file."""
    path = os.path.join(SCENES, name)
    # These scenes were designed for (and their checks measure) the height-field packer; a scene without
    # a packing method is draped.
    scene["packing"] = {"method": "height_field", **scene.get("packing", {})}
    text = json.dumps(scene, indent=1) + "\n"
    if CHECK_ONLY:
        old = open(path).read() if os.path.exists(path) else None
        if old != text:
            STALE.append(os.path.relpath(path, ROOT))
        return
    with open(path, "w") as f:
        f.write(text)
    print("wrote", os.path.relpath(path, ROOT))


def read_obj(name):
    """Vertices and, per group, the source face indices and vertex indices of an OBJ mesh."""
    verts, faces, groups, group = [], [], {}, None
    for line in open(os.path.join(MESHES, name)):
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            verts.append([float(c) for c in w[1:4]])
        elif w[0] == "g":
            group = w[1]
        elif w[0] == "f":
            groups.setdefault(group, []).append(len(faces))
            faces.append([int(c.split("/")[0]) - 1 for c in w[1:]])
    return verts, faces, groups


def face_normal(verts, face):
    a, b, c = (verts[i] for i in face[:3])
    u = [b[k] - a[k] for k in range(3)]
    v = [c[k] - a[k] for k in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    length = math.sqrt(sum(x * x for x in n)) or 1.0
    return [x / length for x in n]


def polyline_resample(points, n, t0=0.0, t1=1.0):
    """n points evenly spaced by arc length between fractions t0 and t1 of the polyline."""
    seg = [math.dist(points[i], points[i + 1]) for i in range(len(points) - 1)]
    total = sum(seg)
    out = []
    for k in range(n):
        s = (t0 + (t1 - t0) * (k / (n - 1) if n > 1 else 0.5)) * total
        i = 0
        while i < len(seg) - 1 and s > seg[i]:
            s -= seg[i]
            i += 1
        a = min(1.0, s / seg[i]) if seg[i] > 0 else 0.0
        out.append([points[i][c] + a * (points[i + 1][c] - points[i][c]) for c in range(3)])
    return out


# ---------------------------------------------------------------- wing (Figs 8.6, 9.19)

WING_KEYS = [
    # (t, elbow degrees, wrist degrees) about +Z: positive bends the wing up, negative down.
    (0, 0, 0),
    (1, -20, -15),
    (2, 20, 20),
    (3, 35, 35),
    (4, 0, 0),
]


def wing_scene():
    axes = json.load(open(os.path.join(MESHES, "wing.axes.json")))
    edge = axes["trailing_edge"]
    n_remiges = 44
    # Flight feathers root in a row on the dorsal side, a little inboard of the trailing edge (6.1.5).
    pinned = []
    for p in polyline_resample(edge, n_remiges, 0.05, 0.97):
        pinned.append({"at": vec([p[0], p[1] + 0.03, p[2] - 0.07])})
    xs = [p["at"][0] for p in pinned]
    # Coverts on the dorsal side only: over the rounded leading edge a feather would either lie along the
    # span edge-on or stand above the wing.
    verts, faces, groups = read_obj("wing.obj")
    dorsal = [f for f in groups["coverts"] if face_normal(verts, faces[f])[1] > 0.55]
    keys = []
    for x, f in ((xs[0], "secondary"), (1.1, "secondary"), (1.35, "primary"), (xs[-1], "primary")):
        near = min(pinned, key=lambda p: abs(p["at"][0] - x))
        keys.append({"feather": f, "at": near["at"]})
    return {
        "pteryla": 1,
        "name": "wing",
        "seed": 819,
        "time": 1,
        "mesh": "../meshes/wing.obj",
        "feathers": {
            "covert": "../feathers/covert.json",
            "secondary": "../feathers/secondary.json",
            "primary": "../feathers/primary.json",
        },
        "tracts": [
            {"name": "coverts", "faces": dorsal, "count": 166, "feather": "covert",
             "feather_scale": "auto", "feather_spacings": 3.5, "scale_jitter": 0.06,
             "relax": {"iterations": 40}},
            {"name": "remiges", "groups": ["remiges_base"], "count": 0, "pinned": pinned,
             "key_feathers": keys, "feather_scale": 0.03},
        ],
        "directions": {
            "tracts": {
                "coverts": {"vectors": [{"at": [0.3, 0, 0], "direction": [0.2, 0, 1]},
                                        {"at": [1.1, 0, 0], "direction": [0.3, 0, 1]},
                                        {"at": [1.8, 0, 0], "direction": [0.8, 0, 1]}]},
                "remiges": {"vectors": [{"at": [0.3, 0, 0.25], "direction": [0.1, 0, 1]},
                                        {"at": [1.15, 0, 0.25], "direction": [0.35, 0, 1]},
                                        {"at": [1.85, 0, 0.1], "direction": [1, 0, 0.45]}]},
            }
        },
        "ordering": {"method": "tracts", "tracts": ["remiges", "coverts"]},
        "packing": {"skin_sample_spacing": 0.002, "shaft_band": 0.5},
        "skeleton": {
            "file": "../meshes/wing.skeleton.json",
            "interpolation": "smooth",
            "keys": [k for t, e, w in WING_KEYS for k in (
                {"joint": "elbow", "t": t, "rotation": [0, 0, 1, e]},
                {"joint": "wrist", "t": t, "rotation": [0, 0, 1, w]})],
        },
        "camera": {"eye": [1.25, 2.0, 2.0], "target": [0.95, 0.12, 0.2], "up": [0, 1, 0], "fov": 38},
        "render": {"size": [640, 360], "lod": 0.8},
    }


FLAP_KEYS = [
    # (t, elbow degrees, wrist degrees): held up, one quick downstroke, held down.
    (0, 25, 20),
    (0.25, 25, 20),
    (0.5, -20, -20),
]


def wing_flap_scene():
    """The wing with a quick downstroke; a dynamic control over the outer wing bends the primaries."""
    scene = wing_scene()
    scene["name"] = "wing_flap"
    scene["time"] = 0.45
    scene["skeleton"]["keys"] = [k for t, e, w in FLAP_KEYS for k in (
        {"joint": "elbow", "t": t, "rotation": [0, 0, 1, e]},
        {"joint": "wrist", "t": t, "rotation": [0, 0, 1, w]})]
    scene["controls"] = [
        {"name": "primaries", "at": [1.6, 0.0, 0.2], "radius": 0.75, "falloff": 0.4, "tracts": ["remiges"],
         "dynamic": 1, "spring": {"frequency": 1.2, "damping": 0.3, "segments": 6}},
    ]
    # Seen from beyond the wingtip and behind, level with the wing: the bend is out of the wing's plane.
    scene["camera"] = {"eye": [3.2, 0.0, 1.6], "target": [1.4, -0.1, 0.4], "up": [0, 1, 0], "fov": 40}
    return scene


# ---------------------------------------------------------------- moult (Figs 8.3-8.5)

def patch_strips(n):
    """Source face indices of patch.obj split into n strips along x (by face centroid)."""
    verts, faces, _ = read_obj("patch.obj")
    strips = [[] for _ in range(n)]
    for i, f in enumerate(faces):
        cx = sum(verts[v][0] for v in f) / len(f)
        strips[min(n - 1, int((cx + 1.0) / 2.0 * n))].append(i)
    return strips


def moult_scene():
    strips = patch_strips(3)
    tract = {"count": 170, "feather_scale": "auto", "feather_spacings": 2.6, "scale_jitter": 0.05,
             "relax": {"iterations": 40}}
    return {
        "pteryla": 1,
        "name": "moult",
        "seed": 83,
        "time": 4,
        "mesh": "../meshes/patch.obj",
        "feathers": {"contour": "../feathers/contour.json"},
        # Three strips, one moult sequence each: sequential along the strip (Fig 8.3), a radial wave from
        # the centre (Fig 8.5) and a random order (Fig 8.4 right). Gaps are lost feathers, short ones regrow.
        # old_age 1.8: the old plumage is worn (shorter barbs, more splits), the renewed feathers fresh (5.2.5).
        "moult": {"start": 0, "duration": 10, "window": 0.3, "gap": 0.3, "seed": 3, "old_age": 1.8},
        "tracts": [
            dict(name="sequential", faces=strips[0], moult={"sequence": "increasing_v"}, **tract),
            dict(name="radial", faces=strips[1], moult={"sequence": "radial", "pace": "distance"}, **tract),
            dict(name="random", faces=strips[2], moult={"sequence": "random"}, **tract),
        ],
        "directions": {"vectors": [{"at": [0, 0, 0], "direction": [0, 0, 1]}]},
        # Feathers point +Z: the +Z-most are the bottom layer.
        "ordering": {"method": "axis", "axis": [[0, 0, -1.5], [0, 0, 1.5]]},
        # Regrowing feathers pack with their barbs as they are meshed (the pipeline packs them as grown),
        # so the default opening_age keeps them above the skin.
        # Dense skin samples keep flat-lying barbs above the dome between samples.
        "packing": {"skin_sample_spacing": 0.005},
        "camera": {"eye": [0, 3.3, 2.0], "target": [0, 0, 0.25], "up": [0, 1, 0], "fov": 37},
        "render": {"size": [640, 360], "lod": 1.0},
    }


def moult_radial_scene():
    halves = patch_strips(2)
    tract = {"count": 230, "feather_scale": "auto", "feather_spacings": 2.6, "scale_jitter": 0.05,
             "relax": {"iterations": 40}}
    scene = moult_scene()
    scene.update({
        "name": "moult_radial",
        "time": 4,
        # Fig 8.5: a radial wave, strictly sequential on the left; on the right with random order jitter and a
        # wider window, so the wave is no longer a clean ring but every feather still develops the same way.
        "moult": {"start": 0, "duration": 10, "window": 0.3, "gap": 0.3, "seed": 5, "sequence": "radial",
                  "pace": "distance"},
        "tracts": [
            dict(name="radial", faces=halves[0], **tract),
            dict(name="radial_random", faces=halves[1], moult={"random": 0.4, "window": 0.45}, **tract),
        ],
    })
    return scene


def moult_helical_scene():
    """A sequential moult of helical (Zhang & Kanai) contour feathers: the regrowing feathers grow on the
    follicle collar, unfurl and open (docs/growth.md, "Helical feathers")."""
    scene = moult_scene()
    scene.update({
        "name": "moult_helical",
        "time": 5,
        "feathers": {"contour": "../feathers/helical-contour.json"},
        "moult": {"start": 0, "duration": 10, "window": 0.45, "gap": 0.2, "seed": 3, "old_age": 1.0},
        "tracts": [dict(name="sequential", count=60, feather_scale="auto", feather_spacings=2.6,
                        relax={"iterations": 40}, moult={"sequence": "increasing_v"})],
        "camera": {"eye": [0, 2.4, 1.6], "target": [0, 0, 0.2], "up": [0, 1, 0], "fov": 37},
    })
    return scene


# ---------------------------------------------------------------- crest (expressive controls, AnimFur)

HEAD_AXIS = [[0.62, 0.02, 0], [0.3, 0.08, 0], [0.0, 0.1, 0], [-0.3, 0.02, 0], [-0.3, -0.4, 0], [-0.25, -1.1, 0]]


def head_feather():
    """The contour feather with the barred brown pattern (not the bird's head feather, which is tuned for
    the bird and changes with it)."""
    f = json.load(open(os.path.join(ROOT, "data", "feathers", "contour.json")))
    f["name"] = "head"
    f["material"] = {"pattern": "barred_brown"}
    return f


def crest_feather():
    """The contour feather, longer, narrower and red, so the raised crest reads against the head."""
    f = json.load(open(os.path.join(ROOT, "data", "feathers", "contour.json")))
    f["name"] = "crest"
    f["rachis"]["length"] = 3.4
    f["barbs"]["length"] = 0.8
    f["material"] = {"base_color": [0.62, 0.16, 0.1]}
    return f


def crest_scene():
    return {
        "pteryla": 1,
        "name": "crest",
        "seed": 2019,
        "time": 1.5,
        "mesh": "../meshes/head.obj",
        "feathers": {"head": head_feather(), "crest": crest_feather()},
        "tracts": [
            {"name": "capital", "groups": ["capital"], "count": 1300, "feather": "head",
             "feather_scale": "auto", "feather_spacings": 3.2, "scale_jitter": 0.08, "relax": {"iterations": 30}},
            {"name": "crest", "groups": ["crest"], "count": 110, "feather": "crest",
             "feather_scale": "auto", "feather_spacings": 3.8, "scale_jitter": 0.1, "relax": {"iterations": 40}},
        ],
        "directions": {"axis": HEAD_AXIS},
        "ordering": {"method": "axis", "axis": HEAD_AXIS},
        # Small head feathers on a curved skin: dense skin samples keep flat-lying vanes above it.
        "packing": {"shaft_band": 0.5, "skin_sample_spacing": 0.004},
        # The crest rises (lift toward the skin normal), holds with a little random twist, and settles.
        "controls": [
            {"name": "crest", "at": [-0.05, 0.32, 0.0], "radius": 0.45, "falloff": 0.4, "tracts": ["crest"],
             "seed": 7, "twist_angle": 12, "max_lift": 75, "interpolation": "smooth",
             "keys": [{"t": 0, "lift": 0, "random": 0}, {"t": 1, "lift": 1, "random": 1},
                      {"t": 2, "lift": 1}, {"t": 3, "lift": 0, "random": 0}]},
        ],
        "camera": {"eye": [0.55, 0.35, 2.6], "target": [0.05, -0.2, 0], "up": [0, 1, 0], "fov": 34},
        "render": {"size": [640, 360], "lod": 0.8},
    }


# ---------------------------------------------------------------- patch layouts (Fig 9.11)

PATCH_KEYS = [{"feather": "contour", "at": [-0.8, 0.05, 0.0]}, {"feather": "covert", "at": [0.8, 0.05, 0.0]}]
PATCH_LENGTH = 0.72    # mean feather length on the patches, scene units (about 3 follicle spacings)


def patch_height(x, z):
    """A point just above patch.obj's dome (pinned follicles snap to the closest skin point)."""
    return 0.12 * max(0.0, 1.0 - 0.5 * (x * x + z * z)) + 0.01


def patch_scene(name, tract_extra, note):
    contour = json.load(open(os.path.join(ROOT, "data", "feathers", "contour.json")))
    length = contour["calamus"]["length"] + contour["rachis"]["length"]
    tract = {"name": "patch", "groups": ["patch"]}
    tract.update(tract_extra)
    if "pinned" in tract:
        tract["feather_scale"] = r5(PATCH_LENGTH / length)
    else:
        tract.update({"feather_scale": "auto", "feather_spacings": 3.0})
    tract["key_feathers"] = PATCH_KEYS
    return {
        "pteryla": 1,
        "name": name,
        "seed": 9,
        "mesh": "../meshes/patch.obj",
        "feathers": {"contour": "../feathers/contour.json", "covert": "../feathers/covert.json"},
        "tracts": [tract],
        "directions": {"vectors": [{"at": [0, 0, 0], "direction": [1, 0, 0]}]},
        "ordering": {"method": "axis", "axis": [[-1.5, 0, 0], [1.5, 0, 0]]},
        # Side by side in a grid column the vanes overlap; with the whole vane in the shaft's height field
        # (shaft_band 1) a column stacks up sideways, so lateral overlaps are left to the barbs.
        # Dense skin samples: with the automatic spacing a few barb vertices dip into the dome between them.
        "packing": {"shaft_band": 0.5, "skin_sample_spacing": 0.005},
        "camera": {"view_direction": [-0.3, -0.8, -0.5], "fov": 35},
        "render": {"size": [640, 360], "lod": 1.0},
    }, note


def blend_scene():
    """Material blending (issue #30 item 2): three key feathers with one geometry and three looks (barred,
    slate blue with glossier barbules, spotted with matte ones) at the corners of a triangle on the patch;
    every feather between them blends their colours, patterns and barbule parameters by its weights."""
    scene, _ = patch_scene("blend", {"count": 80, "relax": {"iterations": 40}}, "material blending")
    scene["feathers"] = {k: f"../feathers/blend/{k}.json" for k in ("barred", "slate", "spotted")}
    scene["tracts"][0]["key_feathers"] = [{"feather": "barred", "at": [-0.8, 0.05, -0.6]},
                                          {"feather": "slate", "at": [0.8, 0.05, -0.6]},
                                          {"feather": "spotted", "at": [0.0, 0.05, 0.8]}]
    scene["seed"] = 11
    scene["camera"] = {"view_direction": [-0.2, -0.85, -0.5], "fov": 27}
    return scene


def grid_points(nx, nz, half_x, half_z, shift_odd_rows=False):
    pts = []
    for j in range(nz):
        z = -half_z + 2 * half_z * j / (nz - 1)
        off = 0.5 if shift_odd_rows and j % 2 else 0.0
        for i in range(nx):
            if shift_odd_rows and j % 2 and i == nx - 1:
                continue
            x = -half_x + 2 * half_x * (i + off) / (nx - 1)
            pts.append({"at": vec([x, patch_height(x, z), z])})
    return pts


def patch_scenes():
    # Grid: 8 x 8 follicles. Hexagonal: rows 0.87 of the column spacing apart, odd rows shifted half a
    # spacing (8 + 7 + ... = 60). Stretched: Lloyd relaxation with a bias vector that packs the follicles
    # twice as close along the feather direction as across it (6.1.4).
    yield patch_scene("patch", {"count": 60, "relax": {"iterations": 40}}, "relaxed (Lloyd)")
    yield patch_scene("patch_grid", {"count": 0, "pinned": grid_points(8, 8, 0.84, 0.84)}, "grid")
    yield patch_scene("patch_hex", {"count": 0, "pinned": grid_points(8, 8, 0.84, 0.84 * 0.866, True)},
                      "hexagonal")
    yield patch_scene("patch_stretched", {"count": 60, "relax": {"iterations": 60, "bias": [
        {"at": [0, 0.1, 0], "direction": [1, 0, 0], "stretch": 2.0}]}}, "stretched")


# ---------------------------------------------------------------- spheres (Figs 9.12, 9.13)

SPHERE_AXIS = [[0, 1.5, 0], [0, -1.5, 0]]


def sphere_scene(name, mesh, spacings, note):
    scene = {
        "pteryla": 1,
        "name": name,
        "seed": 12,
        "mesh": "../meshes/" + mesh,
        "feathers": {"contour": "../feathers/contour.json"},
        "tracts": [
            {"name": "all", "count": 426, "feather_scale": "auto", "feather_spacings": spacings,
             "scale_jitter": 0.05, "relax": {"iterations": 40},
             "parameterization": {"method": "projection", "view_direction": [0, -1, 0]}}
        ],
        "directions": {"axis": SPHERE_AXIS},
        "ordering": {"method": "axis", "axis": SPHERE_AXIS},
        "camera": {"view_direction": [-0.5, -0.35, -1.0], "fov": 30},
        "render": {"size": [640, 360], "lod": 0.6},
    }
    if mesh == "sphere_250.obj":
        # Coarse facets: with the automatic skin sample spacing a few barbs of the small feathers dip
        # between samples where two facets meet.
        scene["packing"] = {"skin_sample_spacing": 0.01}
    return scene, note


def sphere_scenes():
    # 426 feathers at three feather scales (the largest twice as long as the smallest: mean length 2, 3
    # and 4 follicle spacings) on the 250-triangle sphere (Fig 9.12) and on the 1,600-triangle sphere
    # (Fig 9.13 compares the two tessellations).
    for mesh, prefix in (("sphere_1600.obj", "sphere"), ("sphere_250.obj", "sphere_250")):
        tris = mesh[len("sphere_"):-len(".obj")]
        yield sphere_scene(prefix + "_small", mesh, 2.0,
                           tris + " triangles, feathers 2 spacings long")
        yield sphere_scene(prefix, mesh, 3.0, tris + " triangles, feathers 3 spacings long")
        yield sphere_scene(prefix + "_large", mesh, 4.0, tris + " triangles, feathers 4 spacings long")


def main():
    write("wing.json", wing_scene())
    write("wing_flap.json", wing_flap_scene())
    write("moult.json", moult_scene())
    write("moult_radial.json", moult_radial_scene())
    write("moult_helical.json", moult_helical_scene())
    write("crest.json", crest_scene())
    write("blend.json", blend_scene())
    for scene, _ in list(patch_scenes()) + list(sphere_scenes()):
        write(scene["name"] + ".json", scene)


if __name__ == "__main__":
    main()
    if STALE:
        print("out of date (run tools/scenes/make_thesis_scenes.py):", " ".join(STALE))
        sys.exit(1)
