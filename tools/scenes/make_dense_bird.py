#!/usr/bin/env python3
"""Writes data/scale/bird_10k.json and bird_30k.json: the bundled bird (data/scenes/bird.json) with every
density-driven tract's density multiplied, for the farm's scale table (issue #31, docs/farm.md) and the
hero-bird memory work (#27). Feathers keep `feather_scale: auto`, so they shrink with the spacing and the
coat keeps its cover. Tracts given by `count` (mirrors, remiges, rectrices) are unchanged.

    python3 tools/scenes/make_dense_bird.py          # rewrites both files (committed)
"""
import json, os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..')
SCENES = os.path.join(ROOT, 'data', 'scenes')
# Not in data/scenes: the suite evaluates every scene there. data/scale/ sits beside it, so the bird's
# relative paths (../meshes, ../feathers) stay valid.
OUT = os.path.join(ROOT, 'data', 'scale')

# Density factors for about 10,000 and 30,000 feathers: the count grows linearly with the factor (bird.json:
# 3,392 = 996 from count tracts + 2,396 x 1; measured 8,423 at 3.1 and 23,997 at 9.6).
VARIANTS = {'bird_10k': 3.76, 'bird_30k': 12.1}

def main():
    with open(os.path.join(SCENES, 'bird.json')) as f:
        base = json.load(f)
    for name, factor in VARIANTS.items():
        scene = json.loads(json.dumps(base))
        scene['name'] = f"{base.get('name', 'bird')} (density x{factor})"
        for tract in scene['tracts']:
            if 'density' in tract:
                tract['density'] = round(tract['density'] * factor, 3)
        os.makedirs(OUT, exist_ok=True)
        path = os.path.join(OUT, name + '.json')
        tmp = path + '.tmp'
        with open(tmp, 'w') as f:
            json.dump(scene, f, indent=1)
            f.write('\n')
        os.replace(tmp, path)
        print('wrote', os.path.relpath(path, ROOT))

if __name__ == '__main__':
    main()
