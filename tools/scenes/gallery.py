#!/usr/bin/env python3
"""Render the bundled scenes into docs/gallery/ and write docs/gallery.md with their check and bench numbers.

    python3 tools/scenes/gallery.py --pteryla build/apps/pteryla/pteryla [--only wing,crest] [--no-bench]

Usually run through tools/gallery.sh (which builds the CLI first). Every image is rendered by
`pteryla render`, every number comes from `pteryla check` / `pteryla bench` on the same scene and time.
The bird goes last (it is the slowest: its full check runs for minutes). With --only, the other
sections keep the numbers recorded in docs/gallery/results.json.
"""
import argparse
import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
GALLERY = os.path.join(ROOT, "docs", "gallery")
RESULTS = os.path.join(GALLERY, "results.json")
MAX_BYTES = 300 * 1024

# Sections: (key, title, text, scene, images [(file stem, time, caption)], check times, bench time)
SECTIONS = [
    ("wing", "Wing: skin deformation (Figs 8.6, 9.19)",
     "`wing.json`: 210 feathers in two tracts on `wing.obj`: 166 coverts relaxed on the dorsal side and 44 "
     "flight feathers pinned in a row along the trailing edge (secondaries blending into primaries). The "
     "elbow and wrist are keyframed: rest at t = 0, bent down at t = 1, up at t = 2 and further up at t = 3. "
     "On every pose the follicles ride the skin and the coat is repacked in its rest layer order.",
     "wing.json", [("wing_rest", 0, "t = 0, rest"), ("wing_down", 1, "t = 1, bent down"),
                   ("wing_up", 3, "t = 3, bent up")], [0, 1, 2, 3], 1),
    ("wing_flap", "Wing flap: the dynamic chain (AnimFur dynamic blend, issue #30)",
     "`wing_flap.json`: the wing of `wing.json` held up (elbow 25, wrist 20 degrees) until t = 0.25, one quick "
     "downstroke to -20 degrees by t = 0.5, then held. A dynamic control over the outer wing (`dynamic` 1, "
     "spring 1.2 cycles per time unit, damping 0.3, 6 segments; docs/controls.md, \"Dynamic blend\") binds "
     "the flight feathers there: each is a spring chain whose root follows the skinned follicle and whose tip "
     "lags, so during the stroke the primaries bend up behind the motion, swing through below the wing when "
     "it stops, and settle back onto the rigid coat. The same frame at t = 0.45 with `dynamic` 0 (the rigid "
     "coat; rendered by hand with the control's `dynamic` set to 0): "
     "![t = 0.45, dynamic 0](gallery/wing_flap_rigid_t0.45.png) "
     "Packing does not see the bend: bent feathers cut into their neighbours while they swing (at t = 0.45 "
     "22666 intersecting pairs against 2892 with `dynamic` 0, and 23644 against 3195 at t = 0.6) and at "
     "t = 0.6 the swinging tips pass through the skin; the scene's own time, 0.45, stays above it. Cost: the "
     "controls stage takes 0.16 ms per frame with the chains against 0.10 ms with `dynamic` 0 (2 s at 24 "
     "frames per unit; a fresh evaluation at t = 1.9, from the clip start and past the last key, 0.3-0.4 ms); "
     "placing the bent feathers is lost in the mesh stage's noise.",
     "wing_flap.json", [("wing_flap_t0.2", 0.2, "t = 0.2, held up, at rest"),
                        ("wing_flap_t0.45", 0.45, "t = 0.45, mid-stroke: the primaries bend up behind it"),
                        ("wing_flap_t0.6", 0.6, "t = 0.6, stopped at 0.5: the tips swing through below"),
                        ("wing_flap_t2.5", 2.5, "t = 2.5, settled: the rigid coat again")], [0.45, 0.6], 0.45),
    ("moult", "Moult: sequential, radial and random (Figs 8.3-8.5)",
     "`moult.json`: three strips of one patch, each with its own moult sequence (docs/moult.md): left "
     "`increasing_v` (a sequential band), middle `radial` at constant wave speed (a ring moving out from the "
     "centre), right `random`. The window holds 30% of each strip's feathers; the first 30% of a feather's "
     "window is a gap (bare skin), then it regrows. Regrowing feathers are packed as they are grown at "
     "their age (docs/moult.md), so pin feathers and opening feathers stay above the skin. The old plumage "
     "is worn (`old_age` 1.8: barbs 24% shorter and more splits, docs/growth.md) beside the fresh new "
     "feathers.",
     "moult.json", [("moult_t3", 3, "t = 3"), ("moult_t6", 6, "t = 6")], [3, 6], 3),
    ("moult_radial", "Radial moult with and without randomness (Fig 8.5)",
     "`moult_radial.json`: two halves of the patch moult radially from their centres at constant wave speed. "
     "Left: the order is strictly the distance from the centre, a clean ring of gaps and regrowing feathers. "
     "Right: the order is jittered (`random` 0.4) and the window is wider (0.45), so the wave is ragged, "
     "but every feather still goes through the same loss and regrowth.",
     "moult_radial.json", [("moult_radial_t3", 3, "t = 3"), ("moult_radial_t6", 6, "t = 6")], [3, 6], 3),
    ("moult_helical", "Helical feathers regrowing in a moult (Zhang & Kanai)",
     "`moult_helical.json`: 60 helical contour feathers (`helical-contour.json`, docs/helical.md) moulting "
     "sequentially. A regrowing helical feather is the helical model at the growth time its age maps to "
     "(docs/growth.md, \"Helical feathers\"): its barbs grow rolled on the follicle collar, a tube with "
     "barbs added at the base as they fuse with the rachis (the small sheathed pins), then unfurl while the "
     "sheath sheds (the half-rolled tubes), then open into the feather's own vanes as the rachis curves. "
     "Frames at t = 2, 3 and 4: the wave of regrowth moves across the patch. Growing helical feathers are "
     "packed as grown at every age (their rolled barbs hang below the rachis), so the packer presses the "
     "youngest pins flat against the skin: they read as flattened pillows rather than round cones.",
     "moult_helical.json", [("moult_helical_t2", 2, "t = 2"), ("moult_helical_t3", 3, "t = 3"),
                            ("moult_helical_t4", 4, "t = 4")], [3], None),
    ("crest", "Crest: expressive lift control (AnimFur)",
     "`crest.json`: `head.obj` with 1,300 head and neck feathers and 110 longer, red crest feathers. One control on "
     "the crown binds the crest tract; its keyframed `lift` (max 75 degrees) and `random` twist raise the "
     "crest from t = 0 to t = 1, hold it to t = 2 and lower it by t = 3. Raised feathers become fixed-angle "
     "feathers and the rest of the coat packs against them.",
     "crest.json", [("crest_down", 0, "t = 0, crest lying"), ("crest_up", 1.5, "t = 1.5, crest raised")],
     [0, 1.5], 1.5),
    ("patch", "Follicle layouts on a patch (Fig 9.11)",
     "About 60 feathers between two key feathers (a contour feather on the left, a covert on the right) on "
     "`patch.obj`. `patch.json` relaxes random follicles with Lloyd's algorithm; `patch_grid.json` and "
     "`patch_hex.json` pin follicles on a grid and a hexagonal lattice; `patch_stretched.json` relaxes with a "
     "bias vector that packs follicles twice as close along the feathers as across them (6.1.4). In the "
     "grid each feather lies right on the one ahead of it, so the columns stack up.",
     None, [("patch", None, "patch.json: relaxed"), ("patch_grid", None, "patch_grid.json: grid"),
            ("patch_hex", None, "patch_hex.json: hexagonal"),
            ("patch_stretched", None, "patch_stretched.json: stretched")], None, None),
    ("sphere", "Spheres: feather scale and skin resolution (Figs 9.12, 9.13)",
     "426 feathers on unit spheres, flowing from pole to pole, with feathers 2, 3 and 4 follicle spacings "
     "long (the largest twice the smallest). Fig 9.12: the 250-triangle sphere (`sphere_250_small.json`, "
     "`sphere_250.json`, `sphere_250_large.json`): small feathers follow the coarse facets, larger ones hide "
     "them but bulk up toward the lower pole (the coarse spheres sample their skin every 0.01 units for "
     "packing: with the automatic spacing 8 barb vertices of the small feathers dipped between facets). Fig 9.13: the same on the 1,600-triangle sphere "
     "(`sphere_small.json`, `sphere.json`, `sphere_large.json`), where every scale follows the smooth surface.",
     None, [("sphere_250_small", None, "250 triangles, small"), ("sphere_250", None, "250 triangles, middle"),
            ("sphere_250_large", None, "250 triangles, large"), ("sphere_small", None, "1,600 triangles, small"),
            ("sphere", None, "1,600 triangles, middle"), ("sphere_large", None, "1,600 triangles, large")],
     None, None),
    ("bird", "Bird (Fig 9.20)",
     "`bird.json` (written by `tools/scenes/make_bird_scene.py`): the bundled bird with its 18 tracts, "
     "flight feathers on the wings and tail; the default scene of the README's main command.",
     "bird.json", [("bird", None, "bird.json")], [None], None),
    ("bird_dense", "Dense bird: about 20,000 feathers (issue #27)",
     "`bird_dense.json` (written by `python3 tools/scenes/make_dense_bird.py --dense PACKDIAG`): the bird's "
     "design at six times its follicle density, about as many contour feathers as a real bird carries. The "
     "left and midline tracts' densities are multiplied by 5.97 and their feathers keep `feather_scale: "
     "auto`, so they are 2.4 times shorter and the coat keeps its cover; the right side is pinned at the "
     "mirror images of the denser left follicles, as in `bird.json`; the flight feathers are the bird's own. "
     "It renders within the default 4 GB memory guard because a render meshes each feather by its size on "
     "screen (docs/render.md): at 1280x720 and `--lod 0.6` the coat is 1.8M triangles, not 8M "
     "(the numbers before and after: docs/render.md, \"A hero bird on one machine\"). Its numbers were "
     "regenerated on 2026-11-29 on an idle machine; `mesh` includes the drape, most of it. Compared "
     "with `bird.json` the wings' leading edges show skin between the smaller rim feathers.",
     "bird_dense.json", [("bird_dense", None, "bird_dense.json")], [None], None),
]


def run(cmd):
    t0 = time.time()
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("failed: " + " ".join(cmd) + "\n" + r.stderr)
    return r.stdout, time.time() - t0


def time_args(t):
    return [] if t is None else ["--time", str(t)]


def scene_path(name):
    return os.path.join("data", "scenes", name)


def process(pteryla, key, scene, images, check_times, bench_time, do_bench):
    out = {"images": {}, "checks": [], "bench": []}
    for stem, t, _ in images:
        path = os.path.join(GALLERY, stem + ".png")
        size = "960x540" if key.startswith("bird") else "640x360"
        _, secs = run([pteryla, "-q", "render", scene_path(scene or stem + ".json"), "--size", size, "-o", path]
                      + time_args(t))
        size = os.path.getsize(path)
        print(f"{key}: rendered {os.path.relpath(path, ROOT)} ({size // 1024} KB, {secs:.1f} s)")
        if size > MAX_BYTES:
            print(f"warning: {path} is larger than {MAX_BYTES // 1024} KB", file=sys.stderr)
        out["images"][stem] = {"seconds": round(secs, 1), "kb": size // 1024}
    # Scene and times for the numbers: a scene section checks its scene at each time, a multi-scene
    # section checks each image's scene at its own time.
    targets = [(scene, t) for t in check_times] if scene else [(s + ".json", t) for s, t, _ in images]
    for sc, t in targets:
        text, secs = run([pteryla, "-q", "check", scene_path(sc)] + time_args(t))
        m = json.loads(text)
        m["scene"] = sc
        m["time"] = t
        m["seconds"] = round(secs, 1)
        print(f"{key}: check {m['scene']} t={t}: skin_penetrations {m['skin_penetrations']} ({secs:.0f} s)")
        out["checks"].append(m)
    if do_bench:
        bench_targets = [(scene, bench_time)] if scene else [(s + ".json", t) for s, t, _ in images]
        for sc, t in bench_targets:
            text, _ = run([pteryla, "-q", "bench", scene_path(sc), "--size", "640x360"] + time_args(t))
            b = json.loads(text)
            b["scene"] = sc
            b["time"] = t
            print(f"{key}: bench {b['scene']}: {text.strip()}")
            out["bench"].append(b)
    return out


def fmt(v, digits=2):
    if v is None:
        return "-"
    if digits is None:
        return f"{v:g}"
    if isinstance(v, float):
        return f"{v:.{digits}f}"
    return str(v)


def write_markdown(results):
    lines = [
        "# Gallery",
        "",
        "Every image below is rendered by `pteryla render` from a scene in `data/scenes/` (640 x 360, the "
        "scene's level of detail), and every number is printed by `pteryla check` / `pteryla bench` on the "
        "same scene and time (the birds 960 x 540). Images and bench numbers made since 2026-11-29 mesh each "
        "feather by its size on screen with the scene's level of detail as the cap (the default since #27, "
        "docs/render.md); the sections not regenerated since were made with every feather at that level. "
        "Regenerate all of it (images, numbers and this page) with",
        "",
        "```sh",
        "bash tools/gallery.sh            # builds the CLI, renders, checks and benchmarks every scene (~10 min)",
        "bash tools/gallery.sh --only wing,crest --no-bench   # some sections; the others keep their numbers",
        "```",
        "",
        "The scenes themselves (all but `bird.json`) are written by `python3 tools/scenes/make_thesis_scenes.py`;",
        "`ctest -L scenes` checks that every scene evaluates, stays near its body and is free of skin "
        "penetrations.",
        "",
        "How these scenes look beside the thesis' own figures (bird, sphere, wing, moult), and what still",
        "falls short, is written up in [look.md](look.md).",
        "",
        "Columns: `feathers` present at that time; `skin_penetrations` coat vertices below the skin at full "
        "geometry (0 = none); `intersecting_pairs` triangle pairs of different feathers that cross, after "
        "packing and (`unpacked`) with every feather at the median elevation; `coverage` fraction of the "
        "tract area under feathers; `check s` the check's wall time. `t` - is the scene's own time. Bench "
        "(`pteryla bench --size 640x360`): first-evaluation seconds per stage, `pack warm` the best of three "
        "more full packs with warm memory (`pack_repeat`; - where not measured yet), `frame` a timeline step "
        "(pose, ages, controls, pack, mesh at the scene's level of detail), `triangles` the rendered coat. "
        "Times are wall seconds on the project's 2-core machine (this run: nothing else running; single runs vary by about 30%).",
        "",
    ]
    # The real-mesh corpus (issue #22): hand-kept in docs/gallery/corpus.md (its renders and figures come from
    # ../shared/meshes/, which is not in the repository, so this script does not regenerate them).
    corpus = os.path.join(ROOT, "docs", "gallery", "corpus.md")
    if os.path.exists(corpus):
        lines += open(corpus).read().rstrip("\n").split("\n") + [""]
    # A feather measured from a scan (issue #30): hand-kept too (docs/gallery/scan.md gives its commands).
    scan = os.path.join(ROOT, "docs", "gallery", "scan.md")
    if os.path.exists(scan):
        lines += open(scan).read().rstrip("\n").split("\n") + [""]
    # Materials blending between key feathers (issue #30): hand-kept (docs/gallery/blend.md gives its command).
    blend = os.path.join(ROOT, "docs", "gallery", "blend.md")
    if os.path.exists(blend):
        lines += open(blend).read().rstrip("\n").split("\n") + [""]
    # The birds first on the page (they are processed last: they are the slowest and change most).
    for key, title, text, scene, images, _, _ in sorted(SECTIONS, key=lambda s: not s[0].startswith("bird")):
        r = results.get(key)
        lines += [f"## {title}", "", text, ""]
        if not r:
            lines += ["(not generated yet)", ""]
            continue
        # Two or three images per row (GitHub scales table cells to the page width).
        per_row = 3 if len(images) % 3 == 0 else 2
        for k in range(0, len(images), per_row):
            row = images[k:k + per_row]
            lines.append("| " + " | ".join(f"![{c}](gallery/{s}.png)" for s, _, c in row) + " |")
            lines.append("|" + "---|" * len(row))
            lines.append("| " + " | ".join(f"*{c}*" for _, _, c in row) + " |")
            lines.append("")
        lines += ["| scene | t | feathers | skin_penetrations | intersecting_pairs | unpacked | coverage | check s |",
                  "|---|---|---|---|---|---|---|---|"]
        for m in r["checks"]:
            lines.append(f"| `{m['scene']}` | {fmt(m['time'], None)} | {m['feathers']} | **{m['skin_penetrations']}** | "
                         f"{m['intersecting_pairs']} | {m['intersecting_pairs_unpacked']} | {fmt(m['coverage'], 3)} | "
                         f"{fmt(m['seconds'], 0)} |")
        lines.append("")
        if r.get("bench"):
            lines += ["| bench | t | distribute s | interpolate s | pack s | pack warm s | mesh s | render s | frame s | triangles |",
                      "|---|---|---|---|---|---|---|---|---|---|"]
            for b in r["bench"]:
                lines.append(f"| `{b['scene']}` | {fmt(b['time'], None)} | {fmt(b['distribute'])} | {fmt(b['interpolate'])} | "
                             f"{fmt(b['pack'])} | {fmt(b.get('pack_repeat'))} | {fmt(b['mesh'])} | {fmt(b['render'])} | {fmt(b['frame'])} | "
                             f"{b['triangles']} |")
            lines.append("")
    with open(os.path.join(ROOT, "docs", "gallery.md"), "w") as f:
        f.write("\n".join(lines))
    print("wrote docs/gallery.md")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pteryla", default="build/apps/pteryla/pteryla")
    ap.add_argument("--only", default="")
    ap.add_argument("--no-bench", action="store_true")
    ap.add_argument("--markdown-only", action="store_true", help="rewrite docs/gallery.md from results.json")
    a = ap.parse_args()
    pteryla = os.path.abspath(a.pteryla)
    only = [s for s in a.only.split(",") if s]
    known = [s[0] for s in SECTIONS]
    for s in only:
        if s not in known:
            sys.exit(f"unknown section '{s}' (known: {', '.join(known)})")
    os.makedirs(GALLERY, exist_ok=True)
    results = json.load(open(RESULTS)) if os.path.exists(RESULTS) else {}
    for key, _, _, scene, images, check_times, bench_time in SECTIONS:
        if a.markdown_only or (only and key not in only):
            continue
        old = results.get(key, {})
        results[key] = process(pteryla, key, scene, images, check_times, bench_time, not a.no_bench)
        if a.no_bench and old.get("bench"):
            results[key]["bench"] = old["bench"]
        with open(RESULTS, "w") as f:
            json.dump(results, f, indent=1)
            f.write("\n")
    write_markdown(results)


if __name__ == "__main__":
    main()
