#!/usr/bin/env python3
"""Coverage map of a skin: renders the mesh from a few directions, each face coloured by the share of its
coverage samples that no feather covers (red), covered (grey-green), or outside the tracts (pale blue).

  pteryla_packdiag SCENE.json --face-cover /tmp/fc.txt
  python3 tools/packdiag/cover_map.py data/meshes/bird.obj /tmp/fc.txt /tmp/cover.png

Pure Python (no numpy): a z-buffered flat-shaded rasterizer writing a PNG with zlib."""
import math, struct, sys, zlib

def load_obj(path):
    verts, faces = [], []
    for line in open(path):
        t = line.split()
        if not t: continue
        if t[0] == 'v': verts.append(tuple(map(float, t[1:4])))
        elif t[0] == 'f':
            idx = [int(x.split('/')[0]) - 1 for x in t[1:]]
            for k in range(1, len(idx) - 1): faces.append((idx[0], idx[k], idx[k + 1]))
    return verts, faces

def png(path, w, h, rows):
    raw = b''.join(b'\x00' + bytes(r) for r in rows)
    def chunk(tag, data): return struct.pack('>I', len(data)) + tag + data + struct.pack('>I', zlib.crc32(tag + data) & 0xffffffff)
    open(path, 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)) +
                           chunk(b'IDAT', zlib.compress(raw, 6)) + chunk(b'IEND', b''))

def view_basis(d, up=(0, 1, 0)):
    d = [c / math.sqrt(sum(x * x for x in d)) for c in d]
    if abs(sum(d[i] * up[i] for i in range(3))) > 0.95: up = (1, 0, 0)
    r = [up[1] * d[2] - up[2] * d[1], up[2] * d[0] - up[0] * d[2], up[0] * d[1] - up[1] * d[0]]
    l = math.sqrt(sum(x * x for x in r)); r = [x / l for x in r]
    u = [d[1] * r[2] - d[2] * r[1], d[2] * r[0] - d[0] * r[2], d[0] * r[1] - d[1] * r[0]]
    return r, u, d

def render(verts, faces, colours, d, w, h, points=()):
    r, u, dd = view_basis(d)
    P = [(sum(v[i] * r[i] for i in range(3)), sum(v[i] * u[i] for i in range(3)), sum(v[i] * dd[i] for i in range(3))) for v in verts]
    used = sorted({v for f in faces for v in f})
    xs = [P[v][0] for v in used]; ys = [P[v][1] for v in used]
    s = 0.95 * min(w / (max(xs) - min(xs)), h / (max(ys) - min(ys)))
    cx, cy = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
    S = [((p[0] - cx) * s + w / 2, h / 2 - (p[1] - cy) * s, p[2]) for p in P]
    z = [[1e30] * w for _ in range(h)]
    img = [[230, 230, 230] * w for _ in range(h)]
    for fi, (a, b, c) in enumerate(faces):
        A, B, C = S[a], S[b], S[c]
        area = (B[0] - A[0]) * (C[1] - A[1]) - (B[1] - A[1]) * (C[0] - A[0])
        if area == 0: continue
        va, vb, vc = verts[a], verts[b], verts[c]
        e1 = [vb[i] - va[i] for i in range(3)]; e2 = [vc[i] - va[i] for i in range(3)]
        n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
        ln = math.sqrt(sum(x * x for x in n)) or 1
        shade = 0.35 + 0.65 * abs(sum(n[i] * dd[i] for i in range(3))) / ln
        col = [int(min(255, k * shade)) for k in colours[fi]]
        x0 = max(0, int(min(A[0], B[0], C[0]))); x1 = min(w - 1, int(max(A[0], B[0], C[0])) + 1)
        y0 = max(0, int(min(A[1], B[1], C[1]))); y1 = min(h - 1, int(max(A[1], B[1], C[1])) + 1)
        for y in range(y0, y1 + 1):
            py = y + 0.5
            zr = z[y]; row = img[y]
            for x in range(x0, x1 + 1):
                px = x + 0.5
                w0 = ((B[0] - px) * (C[1] - py) - (B[1] - py) * (C[0] - px)) / area
                w1 = ((C[0] - px) * (A[1] - py) - (C[1] - py) * (A[0] - px)) / area
                w2 = 1 - w0 - w1
                if w0 < 0 or w1 < 0 or w2 < 0: continue
                depth = w0 * A[2] + w1 * B[2] + w2 * C[2]
                if depth < zr[x]:
                    zr[x] = depth; row[3 * x:3 * x + 3] = col
    for p, col in points:  # dots: follicles, drawn when not hidden by the skin
        x, y, dep = (sum(p[i] * r[i] for i in range(3)) - cx) * s + w / 2, h / 2 - (sum(p[i] * u[i] for i in range(3)) - cy) * s, sum(p[i] * dd[i] for i in range(3))
        for yy in range(int(y) - 1, int(y) + 2):
            for xx in range(int(x) - 1, int(x) + 2):
                if 0 <= xx < w and 0 <= yy < h and dep <= z[yy][xx] + 0.01:
                    img[yy][3 * xx:3 * xx + 3] = col
    return img

def main():
    obj, fc, out = sys.argv[1:4]
    verts, faces = load_obj(obj)
    try:
        cov = [tuple(map(int, l.split()))[:2] for l in open(fc)]
    except ValueError:
        sys.exit('%s: expected lines "samples uncovered" (two integers), as pteryla_packdiag --face-cover writes' % fc)
    if len(cov) != len(faces): sys.exit('%s: %d faces, %s: %d lines' % (obj, len(faces), fc, len(cov)))
    if len(sys.argv) > 4:  # --box xmin,xmax,ymin,ymax,zmin,zmax: only faces whose centroid lies inside
        try:
            b = [float(x) for x in sys.argv[4].split(',')]
        except ValueError:
            b = []
        if len(b) != 6: sys.exit('box %r: expected xmin,xmax,ymin,ymax,zmin,zmax (six numbers)' % sys.argv[4])
        keep = [i for i, f in enumerate(faces) if all(b[2 * k] <= sum(verts[v][k] for v in f) / 3 <= b[2 * k + 1] for k in range(3))]
        faces = [faces[i] for i in keep]; cov = [cov[i] for i in keep]
    colours = []
    for s, un in cov:
        if s == 0: colours.append((170, 200, 230))
        else:
            f = un / s
            colours.append((int(150 + 105 * f), int(170 * (1 - f)), int(150 * (1 - f))))
    points = []
    if len(sys.argv) > 5:  # points file: lines "x y z r g b" (e.g. follicles)
        for l in open(sys.argv[5]):
            t = l.split()
            if len(t) >= 6: points.append((tuple(map(float, t[:3])), [int(c) for c in t[3:6]]))
    w, h = 480, 300
    views = [(0, 1, 0.0001), (0, -1, 0.0001), (-1, 0, 0), (0, 0.0001, -1)]  # looking down, up, back along -x (front), from +z
    imgs = [render(verts, faces, colours, d, w, h, points) for d in views]
    rows = [imgs[0][y] + imgs[1][y] for y in range(h)] + [imgs[2][y] + imgs[3][y] for y in range(h)]
    png(out, 2 * w, 2 * h, rows)

main()
