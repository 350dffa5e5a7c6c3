import os

import numpy as np
import pytest

DATA = os.environ.get("PTERYLA_DATA_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "data"))


def read_obj(path):
    """Vertices and triangles of a triangulated OBJ (v and f lines only)."""
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                faces.append([int(p.split("/")[0]) - 1 for p in parts[1:4]])
    return np.asarray(verts, np.float32), np.asarray(faces, np.uint32)


@pytest.fixture(scope="session")
def sphere():
    """The bundled 250-triangle sphere (127 vertices)."""
    return read_obj(os.path.join(DATA, "meshes", "sphere_250.obj"))


def small_setup(seed=5):
    return {"seed": seed, "tracts": [{"name": "body", "count": 60}], "directions": {"axis": [[0, 1, 0], [0, -1, 0]]}}
