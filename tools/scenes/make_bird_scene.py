#!/usr/bin/env python3
"""Writes data/scenes/bird.json and the bird's feather variants (data/feathers/bird/) from the bundled
bird mesh, its axes and the feather library. Re-run after changing the mesh; the outputs are committed."""
import json, math, os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..')
DATA = os.path.join(ROOT, 'data')

def load_obj_groups(path):
    verts, groups, cur = [], {}, None
    for line in open(path):
        t = line.split()
        if not t: continue
        if t[0] == 'v': verts.append(tuple(map(float, t[1:4])))
        elif t[0] == 'g': cur = t[1]
        elif t[0] == 'f':
            idx = [int(x.split('/')[0]) - 1 for x in t[1:]]
            c = tuple(sum(verts[i][k] for i in idx) / len(idx) for k in range(3))
            groups.setdefault(cur, []).append(c)
    return groups

def load_obj(path):
    """Vertices and (face, group) lists of an OBJ of triangles."""
    verts, faces, cur = [], [], None
    for line in open(path):
        t = line.split()
        if not t: continue
        if t[0] == 'v': verts.append(tuple(map(float, t[1:4])))
        elif t[0] == 'g': cur = t[1]
        elif t[0] == 'f': faces.append(([int(x.split('/')[0]) - 1 for x in t[1:]], cur))
    return verts, faces

def sub(a, b): return [a[i] - b[i] for i in range(3)]
def dot(a, b): return sum(a[i] * b[i] for i in range(3))
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def unit(a):
    l = math.sqrt(dot(a, a)); return [c / l for c in a]

def add(a, b): return [a[i] + b[i] for i in range(3)]
def scale(a, k): return [c * k for c in a]

def closest_on_triangle(p, a, b, c):
    """Closest point to p on triangle abc and its barycentric coordinates (Ericson, Real-Time Collision
    Detection 5.1.5)."""
    ab, ac, ap = sub(b, a), sub(c, a), sub(p, a)
    d1, d2 = dot(ab, ap), dot(ac, ap)
    if d1 <= 0 and d2 <= 0: return a, (1, 0, 0)
    bp = sub(p, b); d3, d4 = dot(ab, bp), dot(ac, bp)
    if d3 >= 0 and d4 <= d3: return b, (0, 1, 0)
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        v = d1 / (d1 - d3); return add(a, scale(ab, v)), (1 - v, v, 0)
    cp = sub(p, c); d5, d6 = dot(ab, cp), dot(ac, cp)
    if d6 >= 0 and d5 <= d6: return c, (0, 0, 1)
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        w = d2 / (d2 - d6); return add(a, scale(ac, w)), (1 - w, 0, w)
    va = d3 * d6 - d5 * d4
    if va <= 0 and (d4 - d3) >= 0 and (d5 - d6) >= 0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6)); return add(b, scale(sub(c, b), w)), (0, 1 - w, w)
    den = 1 / (va + vb + vc); v, w = vb * den, vc * den
    return add(a, add(scale(ab, v), scale(ac, w))), (1 - v - w, v, w)

_vnormals = {}
def vertex_normals(verts, faces):
    """Area-weighted vertex normals (sum of face cross products), as the skin computes them."""
    key = id(verts)
    if key not in _vnormals:
        acc = [[0.0, 0.0, 0.0] for _ in verts]
        for idx, g in faces:
            a, b, c = (verts[i] for i in idx)
            cr = cross(sub(b, a), sub(c, a))
            for i in idx: acc[i] = add(acc[i], cr)
        _vnormals[key] = [unit(n) if dot(n, n) > 0 else [0, 0, 1] for n in acc]
    return _vnormals[key]

def closest_surface(verts, faces, p, group_prefix):
    """Closest point to p on the faces of the given groups and the interpolated vertex normal there (the
    follicle frame's N)."""
    vn = vertex_normals(verts, faces)
    best = (1e30, None, None)
    for idx, g in faces:
        if not g or not g.startswith(group_prefix): continue
        q, bc = closest_on_triangle(p, *(verts[i] for i in idx))
        d = dot(sub(q, p), sub(q, p))
        if d < best[0]: best = (d, q, (idx, bc))
    idx, bc = best[2]
    n = [sum(bc[k] * vn[idx[k]][m] for k in range(3)) for m in range(3)]
    return best[1], unit(n)

def surface_normal(verts, faces, p, group_prefix):
    return closest_surface(verts, faces, p, group_prefix)[1]

def farthest_points(points, k):
    if not points: return []
    cx = [sum(p[i] for p in points) / len(points) for i in range(3)]
    first = min(points, key=lambda p: sum((p[i] - cx[i]) ** 2 for i in range(3)))
    chosen = [first]
    d = [sum((p[i] - first[i]) ** 2 for i in range(3)) for p in points]
    while len(chosen) < k:
        j = max(range(len(points)), key=lambda i: d[i])
        chosen.append(points[j])
        d = [min(d[i], sum((points[i][m] - points[j][m]) ** 2 for m in range(3))) for i in range(len(points))]
    return chosen

def resample(poly, n):
    seg = [math.dist(poly[i], poly[i + 1]) for i in range(len(poly) - 1)]
    total = sum(seg); out = []
    for k in range(n):
        s = total * (k + 0.5) / n; i = 0
        while i < len(seg) - 1 and s > seg[i]: s -= seg[i]; i += 1
        t = s / seg[i] if seg[i] > 0 else 0
        out.append([round(poly[i][m] + t * (poly[i + 1][m] - poly[i][m]), 5) for m in range(3)])
    return out

FTAG = os.environ.get('BIRD_FTAG', '')  # experiments: write feather variants under another name

def mirrored(f):
    """The mirror image of a feather across its shaft plane: vanes, silhouette and lateral curvature
    swapped (key barbs are given in a vane-symmetric barb frame, docs/feather-format.md, so each vane's
    curves move with it)."""
    f = dict(f)
    f['left_vane'], f['right_vane'] = f['right_vane'], f['left_vane']
    if 'silhouette' in f:
        f['silhouette'] = {'left': f['silhouette']['right'], 'right': f['silhouette']['left']}
    r = dict(f['rachis'])
    for k in ('lateral_curvature_deg', 'lateral_curvature'):
        if k in r: r[k] = -r[k]
    f['rachis'] = r
    return f

def variant(base, name, pattern=None, color=None, barbs_per_vane=None, afterfeather=True, barb_length=None, size=None, mirror=False, **over):
    """A bird feather from a library feather. barbs_per_vane sets the barb spacing so each vane has about
    that many barbs (full-geometry triangles ~ 16 per barb plus the shaft): the bird's ~3,150 feathers
    come to ~2.2M triangles at full detail, like the thesis' bird (issues #10, #12)."""
    f = json.load(open(os.path.join(DATA, 'feathers', base + '.json')))
    f['name'] = name
    if size:  # a larger feather of the same shape: rachis and (below) barbs scaled
        f['rachis'] = dict(f['rachis'], length=round(f['rachis']['length'] * size, 4))
        barb_length = (barb_length or f['barbs']['length']) * size
    if barbs_per_vane:
        b = dict(f['barbs'])
        ratio = b['spacing_tip'] / b['spacing_base']
        mean = f['rachis']['length'] / barbs_per_vane
        b['spacing_base'] = round(2 * mean / (1 + ratio), 4)
        b['spacing_tip'] = round(2 * mean * ratio / (1 + ratio), 4)
        f['barbs'] = b
    if barb_length:  # wider vanes: barb lengths (and the silhouette's length profile) scaled to it
        k = barb_length / f['barbs']['length']
        f['barbs'] = dict(f['barbs'], length=barb_length)
        if 'silhouette' in f:
            f['silhouette'] = {v: [[rp, round(l * k, 4)] for rp, l in f['silhouette'][v]] for v in ('left', 'right')}
    if not afterfeather:
        f.pop('afterfeather', None)
    mat = {}
    if pattern: mat['pattern'] = pattern
    if color: mat['base_color'] = color
    f['material'] = mat
    for k, v in over.items(): f[k] = v
    if mirror: f = mirrored(f)
    os.makedirs(os.path.join(DATA, 'feathers', 'bird'), exist_ok=True)
    json.dump(f, open(os.path.join(DATA, 'feathers', 'bird', name + FTAG + '.json'), 'w'), indent=2)
    return '../feathers/bird/' + name + FTAG + '.json'

GREATER = float(os.environ.get('BIRD_GREATER', 0))  # greater coverts: size relative to the wing coverts
FLIGHT_W = float(os.environ.get('BIRD_FLIGHT_W', 1.0))  # flight-feather vane width factor
BODY_BARBS = int(os.environ.get('BIRD_BODY_BARBS', 15))
FLIGHT_BARBS = int(os.environ.get('BIRD_FLIGHT_BARBS', 85))
feathers = {  # body feathers without afterfeathers (hidden under the vanes; they cost a third of the triangles)
    'back': variant('contour', 'back', 'scalloped_grey', barbs_per_vane=BODY_BARBS, afterfeather=False, barb_length=float(os.environ.get('BIRD_CONTOUR_W', 1.0))),
    'breast': variant('contour', 'breast', 'spotted', barbs_per_vane=BODY_BARBS, afterfeather=False, barb_length=float(os.environ.get('BIRD_CONTOUR_W', 1.0))),
    'head': variant('contour', 'head', 'barred_brown', barbs_per_vane=BODY_BARBS, afterfeather=False, barb_length=float(os.environ.get('BIRD_CONTOUR_W', 1.0))),
    'covert': variant('covert', 'covert', 'barred_brown', barbs_per_vane=BODY_BARBS, afterfeather=False, barb_length=float(os.environ.get('BIRD_COVERT_W', 1.7))),
    'flank': variant('semiplume', 'flank', 'down_grey', barbs_per_vane=BODY_BARBS, afterfeather=False, barb_length=float(os.environ.get('BIRD_FLANK_W', 0.75))),
    'primary': variant('primary', 'primary', 'flight_dark', barbs_per_vane=FLIGHT_BARBS, barb_length=4.0 * FLIGHT_W),
    'secondary': variant('secondary', 'secondary', 'flight_dark', barbs_per_vane=FLIGHT_BARBS, barb_length=3.8 * FLIGHT_W),
    'rectrix': variant('rectrix', 'rectrix', 'barred_brown', barbs_per_vane=FLIGHT_BARBS, barb_length=2.0 * FLIGHT_W),
}

# Mirror-image feathers on the right: asymmetric feathers (flight feathers and coverts have a narrow and a
# wide vane and a curved rachis) are mirrored on the right side of the body, so the right wing is the exact
# mirror image of the left (BIRD_MIRROR_FEATHERS=0: the same feathers on both sides). Until 2026-11-25 this
# was off, and its switch never reached the flight feathers (their tract was looked up by side, 'right',
# not by tract name), so the measurements that kept it off (2076 pairs, "not a handedness effect") had
# mirrored only the coverts. With the flight feathers mirrored too the two wings pack alike (the right
# wing's secondaries used to climb over the first primary: 42.7 vs 11.6 degrees at the last secondary):
# 1197 pairs, coverage 0.9465 (unmirrored 1191, 0.9460).
MIRROR_FEATHERS = os.environ.get('BIRD_MIRROR_FEATHERS', '1') == '1'
ASYMMETRIC = ('covert', 'primary', 'secondary') if MIRROR_FEATHERS else ()
if MIRROR_FEATHERS:
    feathers['covert_right'] = variant('covert', 'covert_right', 'barred_brown', barbs_per_vane=BODY_BARBS, afterfeather=False,
                                       barb_length=float(os.environ.get('BIRD_COVERT_W', 1.7)), mirror=True)
    feathers['primary_right'] = variant('primary', 'primary_right', 'flight_dark', barbs_per_vane=FLIGHT_BARBS,
                                        barb_length=4.0 * FLIGHT_W, mirror=True)
    feathers['secondary_right'] = variant('secondary', 'secondary_right', 'flight_dark', barbs_per_vane=FLIGHT_BARBS,
                                          barb_length=3.8 * FLIGHT_W, mirror=True)
def sided(kind, tract):
    return kind + '_right' if tract.endswith('_right') and kind in ASYMMETRIC else kind

if GREATER:
    feathers['greater_covert'] = variant('covert', 'greater_covert', 'barred_brown', barbs_per_vane=BODY_BARBS, afterfeather=False,
                                         barb_length=float(os.environ.get('BIRD_COVERT_W', 1.7)), size=GREATER)
groups = load_obj_groups(os.path.join(DATA, 'meshes', 'bird.obj'))
axes = json.load(open(os.path.join(DATA, 'meshes', 'bird.axes.json')))
DENSITY = float(os.environ.get('BIRD_DENSITY', 1140.0))  # follicles per unit area on body tracts (~3,000 body feathers)

body = [  # tract, feather types for its key feathers (cycled), key count
    ('capital', ['head'], 4), ('capital_left', ['head'], 3), ('capital_right', ['head'], 3),
    ('capital_throat', ['head', 'breast'], 4), ('cervical_dorsal', ['head', 'back'], 4),
    ('spinal', ['back'], 6), ('ventral', ['breast', 'flank'], 8), ('caudal', ['back', 'covert'], 4),
    ('humeral_left', ['back', 'covert'], 4), ('humeral_right', ['back', 'covert'], 4),
    ('alar_left', ['covert'], 6), ('alar_right', ['covert'], 6),
    ('femoral_left', ['flank', 'breast'], 3), ('femoral_right', ['flank', 'breast'], 3),
    ('crural_left', ['flank'], 3), ('crural_right', ['flank'], 3),
]
# Feather length in follicle spacings: short enough that the layers lie flat (a feather 2-2.5 spacings
# long rests on the next rows at a low angle; 3.6 stood them up to ~55 deg), longer on the wing coverts
# (flat, wide surfaces) and short on the leg stubs, whose feathers otherwise reach the other leg.
# Wing coverts 3.05 (was 2.8): alar coverage 0.86 -> 0.87-0.89, total 0.899 -> 0.905 for ~220 more pairs
# (3.3 gave 0.909 but stood the outer primaries up over them: +900 pairs). Leg feathers 2.1 covered
# the legs 0.70 -> 0.85 but crossed the other leg (+1900 pairs); pointing them down the leg
# (BIRD_LEG_DOWN=1, with or without BIRD_LEG_OUT) covered less for more pairs. With the current packer
# and sampling (2026-11-25): 1.6 -> 2.0 raises the legs 0.78 -> ~0.87 and the total 0.9288 -> 0.9316 for
# 3 more pairs (1366 -> 1369); 2.2 crosses the other leg again (1886 pairs). Those numbers were one-sided: the
# right leg is pinned to the mirror of the left with the scale stored in bird.json, which still was the 1.6
# scale (right leg feathers 0.045 long, left 0.056). With both legs at 2.0 they cross each other (641 pairs
# between the legs); at 1.8 on both sides (crural_right feather_scale 0.031704 = the left's mean length):
# 1191 pairs, coverage 0.946. Changing this spacing needs crural_right's feather_scale in bird.json scaled
# by the same factor.
SPACINGS = {'body': float(os.environ.get('BIRD_SPACINGS', 2.4)), 'alar': float(os.environ.get('BIRD_ALAR_SPACINGS', 3.05)),
            'crural': float(os.environ.get('BIRD_CRURAL_SPACINGS', 1.8)),
            'capital': float(os.environ.get('BIRD_CAPITAL_SPACINGS', 3.0)), 'humeral': float(os.environ.get('BIRD_HUMERAL_SPACINGS', 3.0))}
SPACINGS.update(femoral=2.8, ventral=2.7)  # a little longer on the flanks and belly: fewer bare gaps between rows
for k in ('femoral', 'ventral'):
    if os.environ.get('BIRD_%s_SPACINGS' % k.upper()): SPACINGS[k] = float(os.environ['BIRD_%s_SPACINGS' % k.upper()])
# The wing coverts' tracts also cover the band where the flight feathers root (greater coverts over the
# remiges' bases, as on a real wing): draped, that band was the least covered skin (0.86, total 0.968);
# with it 0.975 (2026-11-26).
ALAR_REMIGES = os.environ.get('BIRD_ALAR_REMIGES', '1') == '1'
tracts = []
for name, kinds, n in body:
    pts = farthest_points(groups[name], n)
    keys = [{'feather': sided(kinds[i % len(kinds)], name), 'at': [round(c, 5) for c in p]} for i, p in enumerate(pts)]
    if GREATER and name.startswith('alar'):
        # Greater coverts: larger key feathers along the wing's trailing border, over the band where the
        # flight feathers root (real wings have rows of coverts growing larger toward the remiges).
        for z in (0.45, 0.65, 0.85, 1.05):
            zs = [c for c in groups[name] if abs(abs(c[2]) - z) < 0.03 and c[1] > 0.15]
            c = min(zs, key=lambda c: c[0])
            keys.append({'feather': 'greater_covert', 'at': [round(v, 5) for v in c]})
    grp = [name]
    if ALAR_REMIGES and name.startswith('alar'):  # coverts also over the band where the flight feathers root
        grp.append('remiges_' + name.split('_')[1])
    t = {'name': name, 'groups': grp, 'density': DENSITY, 'feather_scale': 'auto', 'feather_spacings': SPACINGS.get(name.split('_')[0], SPACINGS['body']),
         'scale_jitter': 0.08, 'key_feathers': keys, 'relax': {'iterations': 30}}
    if name.startswith(('alar', 'humeral', 'spinal', 'caudal', 'capital', 'cervical')):
        t['parameterization'] = {'method': 'projection', 'view_direction': [0, -1, 0]}
    else:
        t['parameterization'] = {'method': 'projection', 'view_direction': [0, 1, 0]}
    tracts.append(t)

# Mirror symmetry: the mesh and its tracts are symmetric in z, but each tract scatters and relaxes its
# follicles with its own seed, so left and right got different follicle layouts (0.01 units apart, a
# third of a spacing), packed differently and covered differently (right side of the head 0.76 vs 0.88
# on the left). The right-side body tracts are instead pinned at the mirror images of the left tracts'
# relaxed follicles, with the left tracts' automatic feather scale, so both halves carry the same coat.
# The left follicles come from BIRD_FOLLICLES (lines "tract x y z length", one per feather, written by
# `pteryla_packdiag SCENE --follicles FILE`); without it the pinned lists and scales already in
# data/scenes/bird.json are kept, so re-running the script reproduces the committed scene. After changing
# a mirrored tract (its groups, density or spacing), regenerate in three steps:
#   BIRD_MIRROR=0 BIRD_OUT=_m1.json python3 tools/scenes/make_bird_scene.py
#   build/tools/packdiag/pteryla_packdiag data/scenes/_m1.json --follicles /tmp/f1.txt
#   BIRD_FOLLICLES=/tmp/f1.txt BIRD_OUT=_m2.json python3 tools/scenes/make_bird_scene.py
#   build/tools/packdiag/pteryla_packdiag data/scenes/_m2.json --follicles /tmp/f2.txt
#   BIRD_FOLLICLES=/tmp/f1.txt BIRD_UNSCALED=/tmp/f2.txt python3 tools/scenes/make_bird_scene.py
# (then delete data/scenes/_m1.json and _m2.json).
MIRROR = os.environ.get('BIRD_MIRROR', '1') == '1'
MIRRORED = ('capital', 'humeral', 'alar', 'femoral', 'crural')
def mirror_tracts(tracts):
    dump = os.environ.get('BIRD_FOLLICLES')
    old = {}
    if dump:
        for line in open(dump):
            t = line.split()
            old.setdefault(t[0], []).append((list(map(float, t[1:4])), float(t[4])))
    else:
        prev = json.load(open(os.path.join(DATA, 'scenes', 'bird.json')))
        prev = {t['name']: t for t in prev['tracts']}
    for t in tracts:
        base, _, side = t['name'].partition('_')
        if side != 'right' or base not in MIRRORED: continue
        if dump:
            left = old[base + '_left']
            pins = [[round(p[0], 6), round(p[1], 6), round(-p[2], 6)] for p, _ in left]
            # Scale: the left tract's mean feather length over this tract's unscaled one (BIRD_UNSCALED,
            # the same dump of a scene with this tract at feather_scale 1).
            fs = 1.0  # without BIRD_UNSCALED: a first pass, to measure the unscaled feather lengths
            if os.environ.get('BIRD_UNSCALED'):
                ul = [float(u.split()[4]) for u in open(os.environ['BIRD_UNSCALED']) if u.split()[0] == t['name']]
                fs = round((sum(l for _, l in left) / len(left)) / (sum(ul) / len(ul)), 6)
        else:
            pins = [q['at'] for q in prev[t['name']]['pinned']]
            fs = prev[t['name']]['feather_scale']
        t.pop('density', None); t.pop('relax', None)
        t.update(count=0, pinned=[{'at': q} for q in pins], feather_scale=fs)
        t.pop('feather_spacings', None)
if MIRROR: mirror_tracts(tracts)

# Down on the wing rims (experiment, BIRD_DOWN=density): Streit kept "two sets of tracts: one for down
# feathers and one for contour feathers" (9.2.1). The leading and trailing rims of the thin wing are where
# the contour feathers' flow parts and ends, so no contour feather lies over them.
DOWN = float(os.environ.get('BIRD_DOWN', 0))
DOWN_NY = float(os.environ.get('BIRD_DOWN_NY', 0.5))
if DOWN > 0:
    feathers['down'] = variant('down', 'down', color=[0.78, 0.74, 0.68], barbs_per_vane=int(os.environ.get('BIRD_DOWN_BARBS', 10)))
    _v, _f = load_obj(os.path.join(DATA, 'meshes', 'bird.obj'))
    down_tracts = []
    for side in ('left', 'right'):
        rim = []
        for k, (idx, g) in enumerate(_f):
            if g not in ('alar_' + side, 'remiges_' + side): continue
            a, b, c = (_v[i] for i in idx)
            n = unit(cross(sub(b, a), sub(c, a)))
            if abs(n[1]) < DOWN_NY: rim.append(k)
        down_tracts.append({'name': 'down_' + side, 'faces': rim, 'density': DOWN, 'feather_scale': 'auto',
                            'feather_spacings': float(os.environ.get('BIRD_DOWN_SPACINGS', 2.0)), 'scale_jitter': 0.08,
                            'feather': 'down', 'relax': {'iterations': 30},
                            'parameterization': {'method': 'projection', 'view_direction': [0, -1, 0]}})
    tracts = down_tracts + tracts

REMEX_SHIFT = float(os.environ.get('BIRD_REMEX_SHIFT', 0.0))
_vo, _fo = load_obj(os.path.join(DATA, 'meshes', 'bird.obj'))
def remex_pins(side):
    """Secondaries and primaries along the wing's axes. With REMEX_SHIFT the follicles move forward
    (and up) onto the upper side of the band where the flight feathers root (on a real wing they insert
    on the ulna and manus, inside the wing, not on its trailing edge), so their bases lie over the band."""
    prim = resample(axes['primaries_' + side], 10)
    sec = resample(axes['secondaries_' + side], 10)
    if REMEX_SHIFT > 0:
        move = lambda p: [round(c, 5) for c in closest_surface(_vo, _fo, add(p, [REMEX_SHIFT, 0.03, 0.0]), 'remiges_' + side)[0]]
        prim, sec = [move(p) for p in prim], [move(p) for p in sec]
    return prim, sec

for side, sgn in (('left', 1), ('right', -1)):
    prim, sec = remex_pins(side)
    tracts.append({'name': 'remiges_' + side, 'groups': ['remiges_' + side], 'count': 0, 'feather_scale': 0.05,
                   'pinned': [{'at': p} for p in sec + prim],
                   'key_feathers': [{'feather': sided('secondary', 'remiges_' + side), 'at': sec[0]}, {'feather': sided('secondary', 'remiges_' + side), 'at': sec[-1]},
                                    {'feather': sided('primary', 'remiges_' + side), 'at': prim[0]}, {'feather': sided('primary', 'remiges_' + side), 'at': prim[-1]}],
                   'parameterization': {'method': 'projection', 'view_direction': [0, -1, 0]}})
verts, faces = load_obj(os.path.join(DATA, 'meshes', 'bird.obj'))
rect = resample(axes['tail_edge'], 12)
# The tail edge runs around the stub's end, where the skin faces straight back: a rectrix pointing back
# would point along its normal (no tangent direction). Rectrices root on the upper back of the stub
# instead (over the pygostyle), where pointing back is a well-defined direction.
TAIL_LIFT = float(os.environ.get('BIRD_TAIL_LIFT', 0.04))
if TAIL_LIFT > 0:
    rect = [[round(c, 5) for c in closest_surface(verts, faces, add(p, [0.0, TAIL_LIFT, 0.0]), 'caudal')[0]] for p in rect]
tracts.append({'name': 'rectrices', 'groups': ['caudal'], 'count': 0, 'feather_scale': 0.055,
               'pinned': [{'at': p} for p in rect], 'feather': 'rectrix',
               'parameterization': {'method': 'projection', 'view_direction': [0, -1, 0]}})

# Draped packing with its defaults (docs/packing.md): every feather lies on the skin and on the feathers
# under it; flight feathers overhang the wing's and the tail's edges. No styling: the flight feathers
# spread by the remiges' and rectrices' direction vectors alone, as a groomer would comb them.
PACKING = {'method': 'drape'}
for kv in os.environ.get('BIRD_PACK', '').split(','):
    if kv: PACKING[kv.split('=')[0]] = json.loads(kv.split('=')[1])
body_axis = [[round(c, 5) for c in p] for p in axes['body_axis']]
# Framed on the feathered bird (body, spread wings, tail) so it fills most of the 1280x720 frame.
VIEW = unit([-0.45, -0.6, -0.66]); TARGET = [-0.38, 0.1, 0.02]; DIST = float(os.environ.get('BIRD_CAM_DIST', 5.0))
CAMERA = {'eye': [round(TARGET[k] - DIST * VIEW[k], 4) for k in range(3)], 'target': TARGET, 'fov': 30}
wing_dir = lambda sgn: [-1.0, 0.0, 0.45 * sgn]
WRAP = float(os.environ.get('BIRD_WRAP', 1.0))
WRAP_FALLOFF = float(os.environ.get('BIRD_WRAP_FALLOFF', 0.06))
TRAIL_DIR = [float(c) for c in os.environ['BIRD_TRAIL_DIR'].split(',')] if os.environ.get('BIRD_TRAIL_DIR') else None
LEAD_HUMERAL = os.environ.get('BIRD_LEAD_HUMERAL', '0') == '1'
# Marginal coverts: on the wing's leading edge the coverts point out along the edge toward the wing tip, as
# on a real wing, instead of back and up over it. The edge is where the flow parts (upper coverts go back
# over the top, lower ones back under the wing), so pointing back left a bare strip along it; along the
# edge each covert lies over the next one's follicle (measured 2026-11-25: alar cover 0.90 -> 0.95,
# total 0.932 -> 0.945). BIRD_LEAD_DIR=-1,1,0.45 restores the old wrap; BIRD_LEAD_HUMERAL=1 also turns
# the shoulders' leading edge (0.950, but 1808 pairs: the inner secondaries stand up under them).
LEAD_DIR = [float(c) for c in os.environ.get('BIRD_LEAD_DIR', '0.2,0.2,1').split(',')]

def edge_vectors(group, sgn, zs, back, wrap, out_z, inner):
    """Direction vectors for a wing tract: on its leading edge (the most forward vertices at each span
    position) the direction also points up, so feathers rooted on the rounded edge wrap over it onto the
    upper surface (marginal coverts) instead of lying along it; `back` units behind the edge and at the
    trailing edge they point back and out."""
    vs = [v for v, g in vert_groups if g == group or (ALAR_REMIGES and g == group.replace('alar', 'remiges'))]
    out = []
    for z in zs:
        s = [v for v in vs if abs(abs(v[2]) - z) < 0.03]
        if not s: continue
        lead = max(s, key=lambda v: v[0]); trail = min(s, key=lambda v: v[0])
        zz = z * sgn
        ld = LEAD_DIR if (LEAD_DIR and (group.startswith('alar') or LEAD_HUMERAL)) else [-1.0, wrap, out_z]
        out.append({'at': [round(lead[0], 4), round(lead[1], 4), round(zz, 4)], 'direction': [ld[0], ld[1], ld[2] * sgn]})
        for x in (lead[0] - back, trail[0]):
            if x >= trail[0] - 1e-9:
                td = TRAIL_DIR if (TRAIL_DIR and x == trail[0]) else [-1.0, 0.0, out_z]
                out.append({'at': [round(x, 4), round(trail[1] if (TRAIL_DIR and x == trail[0]) else lead[1], 4), round(zz, 4)], 'direction': [td[0], td[1], td[2] * sgn]})
    return out

LEG_DOWN = float(os.environ.get('BIRD_LEG_DOWN', 0))
LEG_OUT = float(os.environ.get('BIRD_LEG_OUT', 0))  # and out, away from the other leg
def leg_directions():
    """Leg (crural) feathers point down the leg toward the foot, as on real birds, instead of back along
    the body axis (around the leg), so they overhang the leg's end."""
    if LEG_DOWN <= 0: return {}
    return {'crural_' + side: {'vectors': [{'at': [-0.45, -0.22, 0.08 * sgn], 'direction': [-0.3, -LEG_DOWN, LEG_OUT * sgn]}]}
            for side, sgn in (('left', 1), ('right', -1))}

vert_groups = []
for idx, g in faces:
    for i in idx: vert_groups.append((verts[i], g))
def wing_directions(sgn, side):
    if WRAP <= 0:
        return {'alar_' + side: {'vectors': [{'at': [0.1, 0.2, 0.5 * sgn], 'direction': wing_dir(sgn)}]}}
    return {'alar_' + side: {'vectors': edge_vectors('alar_' + side, sgn, [0.42 + 0.08 * k for k in range(10)], 0.12, WRAP, 0.45, None),
                             'falloff': WRAP_FALLOFF},
            'humeral_' + side: {'vectors': edge_vectors('humeral_' + side, sgn, [0.3, 0.38, 0.46], 0.15, WRAP, 0.15, None),
                                'falloff': WRAP_FALLOFF}}
scene = {
    'pteryla': 1,
    'name': 'bird',
    'seed': 2003,
    'mesh': '../meshes/bird.obj',
    'feathers': feathers,
    'tracts': tracts,
    'directions': {
        'axis': body_axis,
        'tracts': {
            **wing_directions(1, 'left'), **wing_directions(-1, 'right'), **leg_directions(),
            'remiges_left': {'vectors': [{'at': [0.0, 0.2, 0.5], 'direction': [-1.0, 0.0, 0.25]},
                                         {'at': [0.0, 0.2, 1.0], 'direction': [-0.6, 0.0, 1.0]}]},
            'remiges_right': {'vectors': [{'at': [0.0, 0.2, -0.5], 'direction': [-1.0, 0.0, -0.25]},
                                          {'at': [0.0, 0.2, -1.0], 'direction': [-0.6, 0.0, -1.0]}]},
            # Rectrices fan out from the tail's end, the outer ones about 30 degrees from the body axis.
            'rectrices': {'vectors': [{'at': rect[0], 'direction': [-1.0, 0.0, round(math.tan(math.radians(30)) * (1 if rect[0][2] > 0 else -1), 4)]},
                                      {'at': rect[len(rect) // 2], 'direction': [-1.0, 0.0, 0.0]},
                                      {'at': rect[-1], 'direction': [-1.0, 0.0, round(math.tan(math.radians(30)) * (1 if rect[-1][2] > 0 else -1), 4)]}]},
        },
    },
    'ordering': dict({'method': os.environ.get('BIRD_ORDER', 'flow')}, **({'tracts': [t['name'] for t in tracts if t['name'].startswith('down_')]} if DOWN > 0 else {})),
    'packing': PACKING,
    'camera': CAMERA,
    'lights': [{'direction': [-0.4, -1.0, -0.5], 'intensity': 1.0},
               {'direction': [0.6, -0.2, 0.7], 'color': [0.6, 0.65, 0.75], 'intensity': 0.5}],
    'render': {'size': [1280, 720], 'lod': 0.6, 'background': [0.84, 0.87, 0.9]},
}
json.dump(scene, open(os.path.join(DATA, 'scenes', os.environ.get('BIRD_OUT', 'bird.json')), 'w'), indent=1)
print('keys', sum(len(t.get('key_feathers', [])) for t in tracts), 'tracts', len(tracts))
