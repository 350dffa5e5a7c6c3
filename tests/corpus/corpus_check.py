#!/usr/bin/env python3
"""One corpus mesh against the bar of issue #22 (../shared/tools/corpus-check's bar).

usage: corpus_check.py PTERYLA MESH.obj bare|minimal

bare:    `pteryla check MESH.obj` (the bare-mesh defaults).
minimal: a scene holding only the mesh and one direction axis (the mesh's longest bounding-box axis), so
         every other setting is a default.
Bar: skin_penetrations 0, intersecting_pairs <= 5% of intersecting_pairs_unpacked, coverage >= 0.95,
elevation_p50 <= 25 degrees. Prints the figures; exit 0 when met, 1 when not, 2 when it could not run.
"""
import json
import os
import subprocess
import sys
import tempfile


def main():
    if len(sys.argv) != 4 or sys.argv[3] not in ("bare", "minimal"):
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    cli, mesh, variant = sys.argv[1:]
    if not os.path.isfile(mesh):
        print(f"corpus_check: no mesh at {mesh}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        target = mesh
        if variant == "minimal":
            lo = [float("inf")] * 3
            hi = [float("-inf")] * 3
            with open(mesh) as f:
                for line in f:
                    if line.startswith("v "):
                        p = [float(x) for x in line.split()[1:4]]
                        lo = [min(a, b) for a, b in zip(lo, p)]
                        hi = [max(a, b) for a, b in zip(hi, p)]
            ax = max(range(3), key=lambda k: hi[k] - lo[k])
            mid = [(a + b) / 2 for a, b in zip(lo, hi)]
            a, b = list(mid), list(mid)
            a[ax], b[ax] = lo[ax], hi[ax]
            target = os.path.join(tmp, "minimal.json")
            with open(target, "w") as f:
                json.dump({"pteryla": 1, "mesh": os.path.abspath(mesh), "directions": {"axis": [a, b]}}, f)
        r = subprocess.run([cli, "check", target, "--quiet"], capture_output=True, text=True, timeout=1800)
    if r.returncode != 0:
        print(f"corpus_check: pteryla check exited {r.returncode}: {r.stderr.strip()}", file=sys.stderr)
        return 2
    d = json.loads(r.stdout)
    p, u, pen, cov, e50 = (d.get(k) for k in ("intersecting_pairs", "intersecting_pairs_unpacked", "skin_penetrations",
                                             "coverage", "elevation_p50"))
    bad = []
    if pen != 0:
        bad.append(f"skin_penetrations {pen} (bar 0)")
    if not (u and p is not None and p <= 0.05 * u):
        bad.append(f"intersecting_pairs {p} of {u} unpacked (bar 5%)")
    if cov is None or cov < 0.95:
        bad.append(f"coverage {cov} (bar 0.95)")
    if e50 is None or e50 > 25:
        bad.append(f"elevation_p50 {e50} (bar 25)")
    print(f"{os.path.basename(mesh)} {variant}: pairs {p}/{u}, penetrations {pen}, coverage {cov}, elevation_p50 {e50}, "
          f"fixed {d.get('fixed_feathers')}, hidden {d.get('hidden_feathers')}")
    for b in bad:
        print("  fails:", b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
