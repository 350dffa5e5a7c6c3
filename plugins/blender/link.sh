#!/usr/bin/env bash
# Links the add-on and the built Python module into Blender's user script directories, so Blender finds
# both: `bash plugins/blender/link.sh [build-dir]` (default ./build), then enable "pteryla feathers" in
# Preferences > Add-ons (or: blender --addons pteryla_blender). Re-run after moving the build; a rebuild
# needs no re-link. Remove with the same command and --unlink.
set -euo pipefail
cd "$(dirname "$0")/../.."
unlink=0
build=build
for a in "$@"; do
  case "$a" in
    --unlink) unlink=1 ;;
    *) build=$a ;;
  esac
done
scripts=$(blender -b --factory-startup --python-expr \
  "import bpy; print('PTERYLA_SCRIPTS=' + bpy.utils.user_resource('SCRIPTS'))" 2>/dev/null |
  sed -n 's/^PTERYLA_SCRIPTS=//p')
[ -n "$scripts" ] || { echo "link.sh: could not ask blender for its user scripts directory" >&2; exit 1; }
if [ "$unlink" = 1 ]; then
  rm -f "$scripts/addons/pteryla_blender" "$scripts/modules/pteryla"
  echo "unlinked pteryla from $scripts"
  exit 0
fi
module=$PWD/$build/python/pteryla
[ -d "$module" ] || { echo "link.sh: $module is missing: build pteryla first (tools/build.sh)" >&2; exit 1; }
mkdir -p "$scripts/addons" "$scripts/modules"
ln -sfn "$PWD/plugins/blender/pteryla_blender" "$scripts/addons/pteryla_blender"
ln -sfn "$module" "$scripts/modules/pteryla"
echo "linked the add-on and $module into $scripts"
