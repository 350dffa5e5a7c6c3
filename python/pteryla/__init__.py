"""pteryla: bird feather coats on any triangle mesh.

A Python client of the host API (include/pteryla/pteryla.hpp):

    import numpy as np, pteryla
    s = pteryla.Session(positions, triangles, {"seed": 3, "tracts": [{"name": "all", "count": 300}]})
    s.set_pose(posed)                   # float32 (n, 3), same vertices as the rest skin
    if s.evaluate(progress=lambda stage, f: True):
        f = s.frame()                   # numpy arrays: f.positions, f.triangles, f.uvs, ...
    s.check()                           # dict, the numbers of `pteryla check`
    s.export("coat.ply")

Bad input raises pteryla.Error with .file and .element. docs/blender.md, "Python API".
"""
from ._error import Error
from ._pteryla import Control, Frame, Moult, Session, Setup, Tract, data_directory, version
from ._setup import setup_from_dict

__all__ = ["Control", "Error", "Frame", "Moult", "Session", "Setup", "Tract", "data_directory", "version", "setup_from_dict"]
__version__ = version()
