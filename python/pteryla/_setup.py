"""The dict form of a coat set-up: the scene format's section names (docs/scene-format.md).

    {"seed": 7,
     "feathers": {"body": "feathers/contour.json"},          # optional: names for feather files
     "tracts": [{"name": "back", "groups": ["back"], "faces": [...], "count": 200, "density": 0,
                 "feather": "body" | "covert" | "path/to/file.json", "feather_scale": "auto" | 1.5,
                 "feather_spacings": 3.5, "relax": {"iterations": 40}, "seed": 11}],
     "directions": {"axis": [[0, 1, 0], [0, -1, 0]]},
     "ordering": {"method": "axis" | "tracts" | "flow", "tracts": ["back", ...]},
     "packing": {"method": "drape" | "height_field"},
     "moult": {"start": 0, "duration": 10, "window": 0.2, "sequence": "centre_out", "gap": 0.05,
               "random": 0, "seed": 3, "enabled": True},                # optional; a tract's "moult": False
     "controls": [{"name": "crest", "at": [0.8, 0.5, 0], "radius": 0.1, "tracts": ["back"],
                   "keys": [{"t": 0, "lift": 0}, {"t": 1, "lift": 1}]}]}  # docs/controls.md (no "spring")

A "moult" section turns the moult on (docs/moult.md), as in a scene file.

A tract's "feather" is a key of "feathers", else a bundled feather's name (data/feathers/<name>.json),
else a file path. Unknown keys raise pteryla.Error: a typo must not be silently ignored.
"""
import os

from ._error import Error

_SECTIONS = {"pteryla", "name", "seed", "feathers", "tracts", "directions", "ordering", "packing", "moult",
             "controls"}
_CONTROL_KEYS = {"name", "at", "radius", "falloff", "tracts", "keys", "interpolation", "seed", "twist_angle",
                 "max_lift", "lift", "aim", "direction", "random", "dynamic", "offset"}
_ATTRIBUTES = ("lift", "aim", "direction", "random", "dynamic", "offset")
_MOULT_KEYS = {"enabled", "start", "duration", "window", "sequence", "gap", "random", "seed"}
_TRACT_KEYS = {"name", "groups", "faces", "count", "density", "feather", "feather_scale", "feather_spacings",
               "relax", "seed", "moult"}


def _check_keys(d, allowed, where):
    if not isinstance(d, dict):
        raise Error(f"{where}: expected an object (dict)", "", where)
    for k in d:
        if k not in allowed:
            el = f"{where}.{k}" if where else str(k)
            raise Error(f"{el}: unknown key (expected one of {', '.join(sorted(allowed))})", "", el)


def _number(v, where, kind=float):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or (kind is int and not float(v).is_integer()):
        raise Error(f"{where}: expected {'an integer' if kind is int else 'a number'}, got {v!r}", "", where)
    return kind(v)


def _feather_file(name, feathers, base, where):
    if name in feathers:
        path = feathers[name]
        return path if os.path.isabs(path) else os.path.join(base, path)
    from . import data_directory
    bundled = os.path.join(data_directory(), "feathers", name + ".json")
    if os.path.isfile(bundled):
        return bundled
    path = name if os.path.isabs(name) else os.path.join(base, name)
    if os.path.isfile(path):
        return path
    raise Error(f"{where}: '{name}' is neither a key of 'feathers', a bundled feather nor a file", "", where)


def setup_from_dict(d, base_dir=None):
    """A pteryla.Setup from scene-format sections; relative feather paths resolve against base_dir."""
    from . import Setup, Tract
    base = os.getcwd() if base_dir is None else os.fspath(base_dir)
    _check_keys(d, _SECTIONS, "")
    feathers = d.get("feathers", {})
    _check_keys(feathers, set(feathers) if isinstance(feathers, dict) else set(), "feathers")
    s = Setup()
    if "seed" in d:
        seed = _number(d["seed"], "seed", int)
        if seed < 0:
            raise Error("seed: must not be negative", "", "seed")
        s.seed = seed
    tracts = []
    for i, t in enumerate(d.get("tracts", [])):
        where = f"tracts[{i}]"
        _check_keys(t, _TRACT_KEYS, where)
        if "name" not in t:
            raise Error(f"{where}.name: required", "", f"{where}.name")
        tr = Tract(str(t["name"]))
        if "groups" in t:
            tr.groups = [str(g) for g in t["groups"]]
        if "faces" in t:
            try:
                tr.faces = t["faces"]
            except Error as e:  # the binding names the row ("faces 3"); name it in the set-up
                row = e.element.split(" ")[-1] if e.element.startswith("faces ") else ""
                el = f"{where}.faces[{row}]" if row else f"{where}.faces"
                raise Error(f"{el}: {e.detail}", "", el, e.detail) from None
        if "count" in t:
            c = _number(t["count"], f"{where}.count", int)
            if c < 0:
                raise Error(f"{where}.count: must not be negative", "", f"{where}.count")
            tr.count = c
        if "density" in t:
            tr.density = _number(t["density"], f"{where}.density")
        if "feather" in t:
            tr.feather_file = _feather_file(str(t["feather"]), feathers, base, f"{where}.feather")
        if "feather_scale" in t and t["feather_scale"] != "auto":
            tr.feather_scale = _number(t["feather_scale"], f"{where}.feather_scale")
        if "feather_spacings" in t:
            tr.feather_spacings = _number(t["feather_spacings"], f"{where}.feather_spacings")
        if "relax" in t:
            _check_keys(t["relax"], {"iterations"}, f"{where}.relax")
            if "iterations" in t["relax"]:
                tr.relax_iterations = _number(t["relax"]["iterations"], f"{where}.relax.iterations", int)
        if "moult" in t:
            if t["moult"] not in (True, False):
                raise Error(f"{where}.moult: expected true or false", "", f"{where}.moult")
            tr.moult = bool(t["moult"])
        if "seed" in t:
            seed = _number(t["seed"], f"{where}.seed", int)
            if seed < 0:
                raise Error(f"{where}.seed: must not be negative", "", f"{where}.seed")
            tr.seed = seed
        tracts.append(tr)
    s.tracts = tracts
    if "directions" in d:
        _check_keys(d["directions"], {"axis"}, "directions")
        s.axis = [tuple(_number(c, "directions.axis", float) for c in p) for p in d["directions"].get("axis", [])]
    if "ordering" in d:
        _check_keys(d["ordering"], {"method", "tracts", "axis"}, "ordering")
        s.ordering = d["ordering"].get("method", "axis")
        if "tracts" in d["ordering"]:
            s.tract_order = [str(n) for n in d["ordering"]["tracts"]]
        if "axis" in d["ordering"] and not s.axis:
            s.axis = [tuple(float(c) for c in p) for p in d["ordering"]["axis"]]
    if "packing" in d:
        _check_keys(d["packing"], {"method"}, "packing")
        s.packing = d["packing"].get("method", "drape")
    if "moult" in d:
        from . import Moult
        m = d["moult"]
        _check_keys(m, _MOULT_KEYS, "moult")
        mo = Moult()
        for k in ("start", "duration", "window", "gap", "random"):
            if k in m:
                setattr(mo, k, _number(m[k], f"moult.{k}"))
        if "seed" in m:
            mo.seed = _number(m["seed"], "moult.seed", int)
        if "sequence" in m:
            mo.sequence = str(m["sequence"])
        if "enabled" in m:
            if m["enabled"] not in (True, False):
                raise Error("moult.enabled: expected true or false", "", "moult.enabled")
            mo.enabled = bool(m["enabled"])
        s.moult = mo
    if "controls" in d:
        from . import Control
        if not isinstance(d["controls"], list):
            raise Error("controls: expected a list of controls", "", "controls")
        controls = []
        for i, c in enumerate(d["controls"]):
            where = f"controls[{i}]"
            _check_keys(c, _CONTROL_KEYS, where)
            for req in ("at", "radius"):
                if req not in c:
                    raise Error(f"{where}.{req}: required", "", f"{where}.{req}")
            # A constant attribute is a key at t = 0 (docs/controls.md: constants instead of keys).
            keys = [dict(k) for k in c.get("keys", [])]
            const = {a: c[a] for a in _ATTRIBUTES if a in c}
            if const:
                if keys:
                    raise Error(f"{where}: give constants or keys, not both", "", where)
                keys = [dict(t=0, **const)]
            try:
                kw = {k: c[k] for k in ("name", "falloff", "tracts", "interpolation", "seed", "twist_angle", "max_lift")
                      if k in c}
                controls.append(Control(tuple(_number(x, f"{where}.at") for x in c["at"]),
                                        _number(c["radius"], f"{where}.radius"), keys=keys, **kw))
            except Error as e:
                raise Error(f"{where}.{e.element}: {e.detail}", "", f"{where}.{e.element}") from None
            except (TypeError, RuntimeError) as e:
                raise Error(f"{where}: {e}", "", where) from None
        s.controls = controls
    return s
