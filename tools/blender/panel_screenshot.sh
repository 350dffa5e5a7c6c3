#!/usr/bin/env bash
# The Feathers panel's picture for docs/blender.md: `bash tools/blender/panel_screenshot.sh [build] [out.png]`.
# Blender runs with a throw-away user configuration whose only setting hides the splash screen.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
out=${2:-docs/blender_panel.png}
cfg=$(mktemp -d)
trap 'rm -rf "$cfg"' EXIT
BLENDER_USER_CONFIG=$cfg blender -b --factory-startup --python-expr \
  "import bpy; bpy.context.preferences.view.show_splash = False; bpy.ops.wm.save_userpref()" >/dev/null
BLENDER_USER_CONFIG=$cfg xvfb-run -a -s "-screen 0 1280x1200x24" \
  blender --python tools/blender/panel_screenshot.py -- "$build/python" "$out"
