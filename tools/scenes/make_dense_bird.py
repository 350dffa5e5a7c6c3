#!/usr/bin/env python3
"""Writes the bundled bird (data/scenes/bird.json) at higher follicle densities.

data/scale/bird_10k.json and bird_30k.json: every density-driven tract's density multiplied, for the farm's
scale table (issue #31, docs/farm.md). Feathers keep `feather_scale: auto`, so they shrink with the spacing
and the coat keeps its cover. Tracts given by `count` (the right side's mirrors, remiges, rectrices) are
unchanged, so those two are denser on the left than on the right.

data/scenes/bird_dense.json (issue #27, "a hero bird on one machine"): the same design at about 20,000
feathers, symmetric like bird.json. The left and midline tracts' densities are multiplied by DENSE_FACTOR;
the right side's body tracts are pinned at the mirror images of the denser left follicles, with the scale
that gives them the left tracts' mean feather length (as tools/scenes/make_bird_scene.py mirrors bird.json).
The flight feathers (remiges, rectrices) are the bird's own. Finding the mirrored follicles evaluates the
dense scene twice with the packing diagnostic (a minute or two each on two cores):

    python3 tools/scenes/make_dense_bird.py                                   # the data/scale files
    python3 tools/scenes/make_dense_bird.py --dense build/tools/packdiag/pteryla_packdiag
"""
import json, os, subprocess, sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..')
SCENES = os.path.join(ROOT, 'data', 'scenes')
# Not in data/scenes: the suite evaluates every scene there. data/scale/ sits beside it, so the bird's
# relative paths (../meshes, ../feathers) stay valid.
OUT = os.path.join(ROOT, 'data', 'scale')

# Density factors for about 10,000 and 30,000 feathers: the count grows linearly with the factor (bird.json:
# 3,392 = 996 from count tracts + 2,396 x 1; measured 8,423 at 3.1 and 23,997 at 9.6).
VARIANTS = {'bird_10k': 3.76, 'bird_30k': 12.1}
# bird_dense: 52 flight feathers + 3,340 x the factor (the mirrored right side grows with the left).
DENSE_FACTOR = 5.97
MIRRORED = ('capital', 'humeral', 'alar', 'femoral', 'crural')


def write(path, scene):
    tmp = path + '.tmp'
    with open(tmp, 'w') as f:
        json.dump(scene, f, indent=1)
        f.write('\n')
    os.replace(tmp, path)


def denser(base, factor):
    scene = json.loads(json.dumps(base))
    for tract in scene['tracts']:
        if 'density' in tract:
            tract['density'] = round(tract['density'] * factor, 3)
    return scene


def follicles(packdiag, scene, tag):
    """Per tract: [(position, feather length)] of `scene` as pteryla_packdiag --follicles dumps them."""
    path = os.path.join(SCENES, f'_dense_{tag}.json')  # beside bird.json: its relative paths hold
    dump = f'/tmp/pteryla_dense_{tag}.txt'
    write(path, scene)
    try:
        subprocess.run([packdiag, path, '--follicles', dump], check=True, stdout=subprocess.DEVNULL)
    finally:
        os.remove(path)
    out = {}
    for line in open(dump):
        t = line.split()
        out.setdefault(t[0], []).append((list(map(float, t[1:4])), float(t[4])))
    os.remove(dump)
    return out


def mirrored_right(scene):
    for t in scene['tracts']:
        base, _, side = t['name'].partition('_')
        if side == 'right' and base in MIRRORED:
            yield base, t


def dense(packdiag):
    with open(os.path.join(SCENES, 'bird.json')) as f:
        base = json.load(f)
    scene = denser(base, DENSE_FACTOR)
    scene['name'] = f"{base.get('name', 'bird')} dense (density x{DENSE_FACTOR}, mirrored)"
    # Pass 1: the left tracts' follicles at the new density (the right side is still the bird's).
    left = follicles(packdiag, scene, 'left')
    for b, t in mirrored_right(scene):
        t['pinned'] = [{'at': [round(p[0], 6), round(p[1], 6), round(-p[2], 6)]} for p, _ in left[b + '_left']]
        t['feather_scale'] = 1.0
    # Pass 2: the mirrored tracts' feather lengths at scale 1; each gets the left tract's mean length.
    unscaled = follicles(packdiag, scene, 'unscaled')
    for b, t in mirrored_right(scene):
        mean_left = sum(l for _, l in left[b + '_left']) / len(left[b + '_left'])
        mean_right = sum(l for _, l in unscaled[t['name']]) / len(unscaled[t['name']])
        t['feather_scale'] = round(mean_left / mean_right, 6)
    path = os.path.join(SCENES, 'bird_dense.json')
    write(path, scene)
    print('wrote', os.path.relpath(path, ROOT), f'({sum(len(v) for v in unscaled.values())} follicles)')


def main():
    if len(sys.argv) == 3 and sys.argv[1] == '--dense':
        dense(sys.argv[2])
        return
    if len(sys.argv) != 1:
        sys.exit(__doc__)
    with open(os.path.join(SCENES, 'bird.json')) as f:
        base = json.load(f)
    for name, factor in VARIANTS.items():
        scene = denser(base, factor)
        scene['name'] = f"{base.get('name', 'bird')} (density x{factor})"
        os.makedirs(OUT, exist_ok=True)
        path = os.path.join(OUT, name + '.json')
        write(path, scene)
        print('wrote', os.path.relpath(path, ROOT))


if __name__ == '__main__':
    main()
