"""The Python module against the library: what a broken binding would get wrong."""
import json
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import pteryla
from conftest import DATA, small_setup


def evaluated(sphere, setup=None, lod=0.3):
    s = pteryla.Session(*sphere, small_setup() if setup is None else setup)
    s.set_lod(lod)
    assert s.evaluate()
    return s


ARRAYS = ["follicle_keys", "tracts", "present", "origins", "normals", "tangents", "binormals", "elevations",
          "positions", "vertex_normals", "uvs", "alphas", "vertex_feathers", "triangles", "ranges"]


def test_check_matches_the_cli():
    """The same scene gives the same numbers through the module as through `pteryla check`."""
    scene = os.path.join(DATA, "scenes", "patch.json")
    out = subprocess.run([os.environ["PTERYLA_CLI"], "check", scene], check=True, capture_output=True, text=True)
    cli = json.loads(out.stdout)
    py = pteryla.Session.from_scene_file(scene).check()
    assert list(py) == list(cli)
    assert py["feathers"] > 0
    for k, v in cli.items():
        if v is None or isinstance(v, int):
            assert py[k] == v, k
        else:
            assert py[k] == pytest.approx(v, rel=1e-6, abs=1e-9), k


def test_shapes_dtypes_and_consistency(sphere):
    s = evaluated(sphere)
    f = s.frame()
    n, nv = f.feather_count, len(f.positions)
    assert n == 60 and nv > 0
    expect = {"follicle_keys": (np.uint64, (n,)), "tracts": (np.uint32, (n,)), "present": (np.bool_, (n,)),
              "origins": (np.float64, (n, 3)), "normals": (np.float64, (n, 3)), "tangents": (np.float64, (n, 3)),
              "binormals": (np.float64, (n, 3)), "elevations": (np.float64, (n,)),
              "positions": (np.float32, (nv, 3)), "vertex_normals": (np.float32, (nv, 3)),
              "uvs": (np.float32, (nv, 2)), "alphas": (np.float32, (nv,)), "vertex_feathers": (np.uint32, (nv,))}
    for name, (dtype, shape) in expect.items():
        a = getattr(f, name)
        assert a.dtype == dtype and a.shape == shape, name
    assert f.triangles.dtype == np.uint32 and f.triangles.ndim == 2 and f.triangles.shape[1] == 3
    assert f.triangles.max() < nv
    assert f.vertex_feathers.max() < n
    # Follicles sit on the skin (flat triangles inside the unit sphere); frames are orthonormal.
    r = np.linalg.norm(f.origins, axis=1)
    assert (r > 0.95).all() and (r < 1 + 1e-6).all()
    assert np.allclose(np.linalg.norm(f.normals, axis=1), 1.0, atol=1e-6)
    assert np.allclose(np.cross(f.normals, f.tangents), f.binormals, atol=1e-6)
    # Ranges partition the index buffer, one per present feather, and name existing materials.
    r = f.ranges
    assert r.dtype == np.uint32 and r.shape == (int(f.present.sum()), 4)
    assert r[:, 2].sum() == f.triangles.size
    assert set(r[:, 0]) <= set(range(n)) and r[:, 3].max() < len(f.materials)
    assert f.materials[0]["name"] == "contour" and len(f.materials[0]["base_color"]) == 3
    tri_feather = f.vertex_feathers[f.triangles[:, 0]]
    first = r[0]
    assert (tri_feather[first[1] // 3:(first[1] + first[2]) // 3] == first[0]).all()


def test_zero_copy_views_are_guarded(sphere):
    s = evaluated(sphere)
    copied = s.frame()
    view = s.frame(copy=False)
    for name in ARRAYS:
        a = getattr(view, name)
        assert not a.flags.owndata and not a.flags.writeable, name
        assert np.array_equal(a, getattr(copied, name)), name
    del a
    assert getattr(copied, "positions").flags.owndata
    with pytest.raises(pteryla.Error) as e:
        s.set_time(1.0)
    assert e.value.element == "frame"
    positions = view.positions
    del view
    with pytest.raises(pteryla.Error):
        s.evaluate()  # one array of the view is still alive
    del positions
    s.set_lod(0.5)
    assert s.evaluate()


def test_views_keep_the_session_alive(sphere):
    view = evaluated(sphere).frame(copy=False)  # the session has no other reference
    expect = view.positions.copy()
    import gc
    gc.collect()
    assert np.array_equal(view.positions, expect)


def test_same_seed_same_arrays_other_seed_other_coat(sphere):
    a = evaluated(sphere, small_setup(seed=11)).frame()
    b = evaluated(sphere, small_setup(seed=11)).frame()
    c = evaluated(sphere, small_setup(seed=12)).frame()
    for name in ARRAYS:
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name
    assert not np.array_equal(a.origins, c.origins)


def test_dict_and_typed_setup_agree(sphere):
    typed = pteryla.Setup(tracts=[pteryla.Tract("body", count=60)], axis=[(0, 1, 0), (0, -1, 0)], seed=5)
    a = evaluated(sphere, typed).frame()
    b = evaluated(sphere).frame()
    assert a.positions.tobytes() == b.positions.tobytes()


def test_two_tracts_from_face_groups(sphere):
    pos, tri = sphere
    groups = (pos[tri[:, 0], 1] > 0).astype(np.int32)  # 1: upper half, 0: lower half
    setup = {"seed": 3, "tracts": [{"name": "lower", "groups": ["lower"], "count": 20, "feather": "covert"},
                                   {"name": "upper", "groups": ["upper"], "count": 30}]}
    s = pteryla.Session(pos, tri, setup, face_groups=groups, group_names=["lower", "upper"])
    s.set_lod(0.3)
    assert s.evaluate()
    f = s.frame()
    assert np.bincount(f.tracts).tolist() == [20, 30]
    assert sorted(m["name"] for m in f.materials) == ["contour", "covert"]
    # Each tract's follicles lie on its half (a coarse sphere's equator triangles reach ~0.3 across).
    assert (f.origins[f.tracts == 1][:, 1] > -0.35).all() and (f.origins[f.tracts == 0][:, 1] < 0.35).all()
    assert f.origins[f.tracts == 1][:, 1].mean() > 0.3 and f.origins[f.tracts == 0][:, 1].mean() < -0.3


def test_pose_moves_the_coat_and_keeps_the_follicles(sphere):
    s = evaluated(sphere)
    rest = s.frame()
    pos = sphere[0] + np.array([2.0, 0, 0], np.float32)
    s.set_pose(pos)
    assert s.evaluate()
    moved = s.frame()
    assert np.array_equal(moved.follicle_keys, rest.follicle_keys)
    assert np.allclose(moved.origins - rest.origins, [2, 0, 0], atol=1e-5)
    s.clear_pose()
    assert s.evaluate()
    assert np.allclose(s.frame().origins, rest.origins, atol=1e-9)


def test_follow_pose_carries_the_rest_coat(sphere):
    """pose_mode 'follow': a rigid motion of the skin moves the laid coat rigidly, elevations kept."""
    s = evaluated(sphere)
    rest = s.frame()
    assert s.pose_mode == "repack"
    s.pose_mode = "follow"
    c, sn = np.cos(0.5), np.sin(0.5)
    rot = np.array([[c, -sn, 0], [sn, c, 0], [0, 0, 1]])
    s.set_pose(sphere[0] @ rot.T.astype(np.float32) + np.float32(1.5))
    assert s.evaluate()
    f = s.frame()
    assert np.allclose(f.positions, rest.positions @ rot.T + 1.5, atol=5e-5)
    assert np.allclose(f.vertex_normals, rest.vertex_normals @ rot.T, atol=5e-5)
    assert np.array_equal(f.elevations, rest.elevations)
    with pytest.raises(pteryla.Error):
        s.pose_mode = "sideways"
    s.pose_mode = "repack"  # keeps the pose: now repacked on it
    assert s.evaluate()
    assert np.allclose(s.frame().origins, rest.origins @ rot.T + 1.5, atol=1e-5)


def test_tract_seed_rescatters_only_its_tract(sphere):
    pos, tri = sphere
    groups = (pos[tri[:, 0], 1] > 0).astype(np.int32)

    def origins(seed):
        body = {"name": "upper", "groups": ["upper"], "count": 20}
        if seed is not None:
            body["seed"] = seed
        setup = {"seed": 3, "tracts": [{"name": "lower", "groups": ["lower"], "count": 20}, body]}
        s = pteryla.Session(pos, tri, setup, face_groups=groups, group_names=["lower", "upper"])
        s.set_lod(0.3)
        assert s.evaluate()
        f = s.frame()
        return f.origins[f.tracts == 0], f.origins[f.tracts == 1]

    lower0, upper0 = origins(None)
    lower1, upper1 = origins(9)
    assert np.array_equal(lower0, lower1) and not np.array_equal(upper0, upper1)
    assert np.array_equal(origins(9)[1], upper1)
    assert pteryla.Tract("t", seed=4).seed == 4 and pteryla.Tract("t").seed is None
    bad(lambda: pteryla.Session(pos, tri, {"tracts": [{"name": "t", "seed": -1}]}), "tracts[0].seed")


def test_moult_section_and_tract_opt_out(sphere):
    pos, tri = sphere
    groups = (pos[tri[:, 0], 1] > 0).astype(np.int32)
    setup = {"seed": 3, "tracts": [{"name": "lower", "groups": ["lower"], "count": 20, "moult": False},
                                   {"name": "upper", "groups": ["upper"], "count": 30}],
             "moult": {"start": 0, "duration": 4, "window": 0.4, "gap": 0.5}}
    s = pteryla.Session(pos, tri, setup, face_groups=groups, group_names=["lower", "upper"])
    s.set_lod(0.3)
    s.set_time(2.0)
    assert s.evaluate()
    f = s.frame()
    assert f.present[f.tracts == 0].all() and not f.present[f.tracts == 1].all()
    assert isinstance(pteryla.Setup(moult=pteryla.Moult(window=0.3)).moult, pteryla.Moult)
    kw = {"face_groups": groups, "group_names": ["lower", "upper"]}
    bad(lambda: pteryla.Session(pos, tri, dict(setup, moult={"window": 2}), **kw), "moult.window")
    bad(lambda: pteryla.Session(pos, tri, dict(setup, moult={"windw": 0.2}), **kw), "moult.windw")


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n", head[:8]
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


def test_render_matches_the_cli(tmp_path):
    """Session.render draws what `pteryla render` draws for the same scene file."""
    scene = os.path.join(DATA, "scenes", "patch.json")
    s = pteryla.Session.from_scene_file(scene)
    out = tmp_path / "py.png"
    s.render(out, width=160, height=120)
    assert png_size(out) == (160, 120)
    cli_png = tmp_path / "cli.png"
    subprocess.run([os.environ["PTERYLA_CLI"], "render", scene, "--out", str(cli_png), "--size", "160x120",
                    "--quiet"], check=True, capture_output=True, text=True)
    d = subprocess.run([os.environ["PTERYLA_CLI"], "diff", str(out), str(cli_png)], capture_output=True, text=True)
    assert d.returncode == 0, d.stdout + d.stderr
    s.render(tmp_path / "s.png", width=80, height=60, style="scratchboard")
    assert png_size(tmp_path / "s.png") == (80, 60)
    # The kept renderer, released, is made again and draws the same image.
    s.release_renderer()
    again = tmp_path / "again.png"
    s.render(again, width=160, height=120)
    d = subprocess.run([os.environ["PTERYLA_CLI"], "diff", str(again), str(out), "--tolerance", "0"], capture_output=True,
                       text=True)
    assert d.returncode == 0, d.stdout + d.stderr


def test_render_errors_name_the_setting(sphere, tmp_path):
    s = evaluated(sphere)
    for kw, element in (({"width": 0, "height": 10}, "width"), ({"width": 10, "height": 20000}, "height"),
                        ({"width": -5, "height": 10}, "width"), ({"style": "oil"}, "style")):
        with pytest.raises(pteryla.Error) as e:
            s.render(tmp_path / "x.png", **kw)
        assert e.value.element == element
    with pytest.raises(pteryla.Error) as e:
        s.render(tmp_path / "no" / "such" / "dir" / "x.png")
    assert "x.png" in e.value.file
    assert not (tmp_path / "no").exists()
    s.frame()  # still valid after the failures
    s.render(tmp_path / "ok.png", width=64, height=48)
    assert png_size(tmp_path / "ok.png") == (64, 48)
    s.pose_mode = "follow"
    s.set_pose(sphere[0] * 1.1)
    with pytest.raises(pteryla.Error) as e:
        s.render(tmp_path / "f.png")
    assert e.value.element == "poseMode"


def test_fixed_elevations(sphere):
    setup = dict(small_setup(), packing={"method": "height_field"})
    s = evaluated(sphere, setup)
    f = s.frame()
    keys = f.follicle_keys[[2, 9]]
    s.set_fixed_elevations(keys, np.array([0.4, 0.9]))
    assert s.evaluate()
    assert s.frame().elevations[2] == 0.4 and s.frame().elevations[9] == 0.9
    bad(lambda: s.set_fixed_elevations(keys, np.array([0.4, 3.0])), "elevations[1]")
    bad(lambda: s.set_fixed_elevations(np.array([keys[0], 987654321], np.uint64), np.array([0.4, 0.5])),
        "follicle_keys[1]")
    s.set_fixed_elevations(np.zeros(0, np.uint64), np.zeros(0))
    assert s.evaluate()
    assert np.array_equal(s.frame().elevations, f.elevations)
    draped = evaluated(sphere)
    bad(lambda: draped.set_fixed_elevations(keys, np.array([0.4, 0.9])), "packing")


def test_controls_from_dicts_and_typed(sphere):
    pos, tri = sphere
    setup = dict(small_setup(), packing={"method": "height_field"},
                 controls=[{"name": "crest", "at": [0, 0.8, 0.6], "radius": 0.8, "max_lift": 60,
                            "keys": [{"t": 0, "lift": 0}, {"t": 1, "lift": 1}]}])
    s = pteryla.Session(pos, tri, setup)
    s.set_lod(0.3)
    s.set_time(1.0)
    assert s.evaluate()
    f = s.frame()
    near = np.linalg.norm(f.origins - np.array([0, 0.8, 0.6]), axis=1) < 0.4
    assert near.sum() >= 1 and (f.elevations[near] >= np.radians(60) - 1e-9).all()
    typed = pteryla.Setup(tracts=[pteryla.Tract("body", count=60)], axis=[(0, 1, 0), (0, -1, 0)], seed=5,
                          packing="height_field",
                          controls=[pteryla.Control((0, 0.8, 0.6), 0.8, name="crest", max_lift=60,
                                                    keys=[{"t": 0, "lift": 0}, {"t": 1, "lift": 1}])])
    t = pteryla.Session(pos, tri, typed)
    t.set_lod(0.3)
    t.set_time(1.0)
    assert t.evaluate()
    assert np.array_equal(t.frame().elevations, f.elevations)
    bad(lambda: pteryla.Session(pos, tri, dict(setup, controls=[{"at": [0, 1, 0], "radius": 0.1,
                                                                 "keys": [{"t": 0, "lfit": 1}]}])),
        "controls[0].keys[0].lfit")
    bad(lambda: pteryla.Session(pos, tri, dict(setup, controls=[{"at": [0, 1, 0], "radius": -1, "lift": 1}])),
        "controls[0].radius")
    bad(lambda: pteryla.Session(pos, tri, dict(setup, controls=[{"radius": 1, "lift": 1}])), "controls[0].at")


def bad(call, element):
    with pytest.raises(pteryla.Error) as e:
        call()
    assert e.value.element == element, str(e.value)
    assert e.value.file == ""
    return e.value


def test_bad_arrays_raise_errors_naming_the_element(sphere):
    pos, tri = sphere
    bad(lambda: pteryla.Session(pos[:, :2], tri), "positions")
    bad(lambda: pteryla.Session(pos.astype(np.int32), tri), "positions")
    bad(lambda: pteryla.Session("not an array", tri), "positions")
    nan = pos.copy()
    nan[3, 1] = np.nan
    bad(lambda: pteryla.Session(nan, tri), "vertex 3")
    bad(lambda: pteryla.Session(pos, tri.astype(np.float32)), "triangles")
    bad(lambda: pteryla.Session(pos, tri[:, :2]), "triangles")
    bad(lambda: pteryla.Session(pos, tri[:0]), "triangles")
    far = tri.copy()
    far[7, 2] = len(pos)
    bad(lambda: pteryla.Session(pos, far), "face 7")
    neg = tri.astype(np.int64)
    neg[4, 0] = -1
    bad(lambda: pteryla.Session(pos, neg), "face 4")
    bad(lambda: pteryla.Session(pos, tri, face_groups=np.zeros(len(tri), np.int32), group_names=[]),
        "face_groups[0]")
    bad(lambda: pteryla.Session(pos, tri, {"tracts": [{"name": "a", "density": -1}]}), "tracts[0].density")
    bad(lambda: pteryla.Session(pos, tri, {"tracts": [{"name": "a", "faces": [10 ** 6]}]}), "tracts[0].faces[0]")
    bad(lambda: pteryla.Session(pos, tri, {"tracts": [{"name": "a", "faces": [0, -2]}]}), "tracts[0].faces[1]")
    bad(lambda: pteryla.Session(pos, tri, {"tracts": [{"name": "a", "countt": 3}]}), "tracts[0].countt")
    bad(lambda: pteryla.Session(pos, tri, {"packing": {"method": "tight"}}), "packing.method")
    s = evaluated(sphere)
    bad(lambda: s.set_pose(pos[:-1]), "positions")
    bad(lambda: s.set_pose(nan), "vertex 3")
    bad(lambda: s.set_lod(0), "lod")
    assert s.frame().feather_count == 60  # the session survived every refusal


def test_scene_file_errors_name_the_file(tmp_path):
    scene = tmp_path / "broken.json"
    scene.write_text('{"pteryla": 1, "mesh": "missing.obj"}')
    with pytest.raises(pteryla.Error) as e:
        pteryla.Session.from_scene_file(scene)
    assert "broken.json" in e.value.file or "missing.obj" in e.value.file


def test_cancel_then_carry_on(sphere):
    s = pteryla.Session(*sphere, small_setup())
    s.set_lod(0.3)
    stages = []

    def cancel_at_pack(stage, fraction):
        stages.append(stage)
        return stage != "pack"

    assert s.evaluate(progress=cancel_at_pack) is False
    assert "pack" in stages and "mesh" not in stages
    with pytest.raises(pteryla.Error):
        s.frame()
    assert s.evaluate()
    fresh = evaluated(sphere)
    assert s.frame().positions.tobytes() == fresh.frame().positions.tobytes()


def test_exception_in_progress_cancels_and_is_raised(sphere):
    s = pteryla.Session(*sphere, small_setup())

    def boom(stage, fraction):
        raise KeyError("from the callback")

    with pytest.raises(KeyError):
        s.evaluate(progress=boom)
    assert s.evaluate()


def test_gil_is_released_while_evaluating(sphere):
    s = pteryla.Session(*sphere, {"seed": 2, "tracts": [{"name": "all", "count": 150}]})
    s.set_lod(0.3)
    done = threading.Event()
    result = {}
    ticks = 0

    def work():
        result["ok"] = s.evaluate()
        done.set()

    t = threading.Thread(target=work)
    t.start()
    while not done.is_set():
        ticks += 1
        if ticks == 20:
            with pytest.raises(pteryla.Error) as e:  # the session is busy in the other thread
                s.set_lod(0.5)
            assert e.value.element == "session"
        time.sleep(0.001)
    t.join()
    assert result["ok"] and ticks > 20


def test_export_writes_the_frame(sphere, tmp_path):
    s = evaluated(sphere)
    f = s.frame()
    s.export(tmp_path / "coat.obj")
    s.export(str(tmp_path / "coat.ply"))
    lines = (tmp_path / "coat.obj").read_text().splitlines()
    assert sum(1 for line in lines if line.startswith("v ")) == len(f.positions)
    assert sum(1 for line in lines if line.startswith("f ")) == len(f.triangles)
    assert (tmp_path / "coat.ply").read_bytes().startswith(b"ply\n")
    with pytest.raises(pteryla.Error) as e:
        s.export(tmp_path / "coat.xyz")
    assert "coat.xyz" in e.value.file or "coat.xyz" in str(e.value)


def test_export_gltf_and_usd_from_python(sphere, tmp_path):
    s = evaluated(sphere)
    before = s.frame().positions.copy()
    r = s.export(tmp_path / "coat.glb")
    assert r["frames"] == 1 and r["bytes"] == (tmp_path / "coat.glb").stat().st_size
    assert (tmp_path / "coat.glb").read_bytes()[:4] == b"glTF"
    r = s.export(tmp_path / "coat.usda", times=[0.0, 0.5], fps=2.0, coat_as="cards")
    assert r["frames"] == 2
    text = (tmp_path / "coat.usda").read_text()
    assert text.startswith("#usda 1.0") and "timeSamples" in text and "metersPerUnit" in text
    # The session's own frame is unchanged by the export's other times.
    assert np.array_equal(s.frame().positions, before)
    with pytest.raises(pteryla.Error):
        s.export(tmp_path / "coat.usda", times=[1.0, 0.5])  # not increasing
    # A live zero-copy view would be overwritten by the export's evaluations: refused.
    view = s.frame(copy=False)
    with pytest.raises(pteryla.Error):
        s.export(tmp_path / "again.glb")
    del view


def test_version_and_data_directory():
    assert pteryla.__version__ == pteryla.version() and pteryla.version().count(".") == 2
    assert os.path.isfile(os.path.join(pteryla.data_directory(), "feathers", "contour.json"))


def test_instance_tolerance_keeps_topology_and_moves_little():
    """Instancing through the module: the same triangles and feathers, vertices within the tolerance of
    the unshared coat, back to the exact coat at 0, and a refused value changes nothing. (The sphere
    scene's packed feathers differ a little from each other; the small set-up's are identical.)"""
    s = pteryla.Session.from_scene_file(os.path.join(DATA, "scenes", "sphere_250.json"))
    assert s.evaluate()
    exact = s.frame()
    assert s.instance_tolerance == 0.0
    s.set_instance_tolerance(0.02)
    assert s.instance_tolerance == 0.02
    assert s.evaluate()
    shared = s.frame()
    assert np.array_equal(shared.triangles, exact.triangles)
    assert np.array_equal(shared.vertex_feathers, exact.vertex_feathers)
    moved = np.linalg.norm(shared.positions - exact.positions, axis=1)
    assert moved.max() > 0
    # Each vertex within twice the tolerance of its feather's extent (the scene is packed, not draped).
    reach = np.linalg.norm(exact.positions - exact.origins[exact.vertex_feathers], axis=1)
    extent = np.zeros(len(exact.origins))
    np.maximum.at(extent, exact.vertex_feathers, reach)
    assert np.all(moved <= 2 * 0.02 * extent[exact.vertex_feathers] + 1e-6)
    for bad in (-0.01, 0.2, float("nan")):
        with pytest.raises(pteryla.Error):
            s.set_instance_tolerance(bad)
    assert s.instance_tolerance == 0.02
    s.set_instance_tolerance(0.0)
    assert s.evaluate()
    assert s.frame().positions.tobytes() == exact.positions.tobytes()
