"""Screenshot of the add-on's Feathers panel for docs/blender.md (needs a display: run under Xvfb):

    bash tools/blender/panel_screenshot.sh build docs/blender_panel.png

For the picture the panel is shown in the sidebar's Item tab (Blender 3.4's Python cannot switch the
sidebar to the add-on's own "Feathers" tab).
"""
import os
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "plugins", "blender"))
sys.path.insert(0, os.path.abspath(argv[0]))
OUT = os.path.abspath(argv[1])

import addon_utils  # noqa: E402


def setup():
    addon = addon_utils.enable("pteryla_blender", default_set=True, handle_error=None)
    bpy.utils.unregister_class(addon.PTERYLA_PT_feathers)
    addon.PTERYLA_PT_feathers.bl_category = "Item"
    addon.PTERYLA_PT_feathers.bl_order = -1
    bpy.utils.register_class(addon.PTERYLA_PT_feathers)
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=24, ring_count=12)
    body = bpy.context.active_object
    body.name = "body"
    body.data.transform(((2, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)))
    for name, sel in (("back", lambda c: c.x <= 0), ("front", lambda c: c.x > 0)):
        g = body.vertex_groups.new(name=name)
        g.add([v.index for v in body.data.vertices if sel(v.co)], 1.0, "REPLACE")
        body.vertex_groups.active_index = g.index
        bpy.ops.pteryla.tract_add()
    body.pteryla.tracts[0].feather = "covert"
    body.pteryla.tracts[1].feather = "contour"
    bpy.ops.pteryla.feather()
    for area in bpy.context.screen.areas:
        if area.type == "VIEW_3D":
            area.spaces[0].show_region_ui = True
            area.spaces[0].shading.type = "SOLID"
    return None


def frame_body():
    win = bpy.context.window_manager.windows[0]
    for area in win.screen.areas:
        if area.type == "VIEW_3D":
            region = next(r for r in area.regions if r.type == "WINDOW")
            with bpy.context.temp_override(window=win, screen=win.screen, area=area, region=region):
                bpy.ops.view3d.view_selected()
    return None


def shoot():
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == "VIEW_3D")
    with bpy.context.temp_override(window=win, screen=win.screen, area=area):
        bpy.ops.screen.screenshot_area(filepath=OUT)
    print("panel_screenshot: wrote " + OUT)
    bpy.ops.wm.quit_blender()


bpy.app.timers.register(setup, first_interval=1.0)
bpy.app.timers.register(frame_body, first_interval=6.0)
bpy.app.timers.register(shoot, first_interval=9.0)
