#!/usr/bin/env bash
# pteryla export through the CLI: the bundled scenes at one time and over a frame range, every glTF
# checked by the Khronos validator (0 errors), every USD format written; bad input exits 2 naming the
# problem and a failed export keeps the previous file.
# Usage: export_cli.sh PTERYLA DATA_DIR NODE_MODULES OUT_DIR
set -uo pipefail
PTERYLA=$1 DATA=$2 NODE_MODULES=$3 OUT=$4
HERE=$(cd "$(dirname "$0")" && pwd)
rm -rf "$OUT" && mkdir -p "$OUT"
fail=0
bad() { echo "FAIL: $*"; fail=1; }
if ! command -v node >/dev/null; then echo "FAIL: node not found (tools/bootstrap.sh installs nodejs)"; exit 1; fi
UNREACHABLE="$(dirname "$NODE_MODULES")/registry_unreachable.txt"
if [ -f "$UNREACHABLE" ]; then
  echo "NOTE: the npm registry was unreachable for export.npm_ci ($(grep -m1 -o 'SELF_SIGNED_CERT[A-Z_]*\|E[A-Z]*' "$UNREACHABLE" || true)): every check but the Khronos validator runs"
elif [ ! -d "$NODE_MODULES/gltf-validator" ]; then echo "FAIL: gltf-validator missing in $NODE_MODULES (export.npm_ci fixture)"; exit 1; fi

run() {  # run NAME ARGS...: export, expecting success
  local name=$1; shift
  local t0=$(date +%s.%N)
  if ! "$PTERYLA" export "$@" -q 2>"$OUT/$name.err"; then bad "export $name: $(cat "$OUT/$name.err")"; return; fi
  echo "ok   export $name ($(stat -c %s "${@: -1}" 2>/dev/null || true) bytes, $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.2f", b - a}') s)"
}

S=$DATA/scenes
gltfs=()
for scene in patch sphere_250 crest; do
  run $scene.glb "$S/$scene.json" --lod 0.1 -o "$OUT/$scene.glb"; gltfs+=("$OUT/$scene.glb")
done
run patch.gltf "$S/patch.json" --lod 0.3 -o "$OUT/patch.gltf"; gltfs+=("$OUT/patch.gltf")
run bird.glb "$S/bird.json" --lod 0.2 -o "$OUT/bird.glb"; gltfs+=("$OUT/bird.glb")
run moult_range.glb "$S/moult.json" --lod 0.1 --from 3.5 --to 4.25 --fps 4 -o "$OUT/moult_range.glb"; gltfs+=("$OUT/moult_range.glb")
run moult_range.gltf "$S/moult.json" --lod 0.1 --from 3.5 --to 4 --fps 4 -o "$OUT/moult_range.gltf"; gltfs+=("$OUT/moult_range.gltf")
for as in curves cards instances; do
  run patch_$as.usda "$S/patch.json" --lod 0.3 --as $as -o "$OUT/patch_$as.usda"
  head -1 "$OUT/patch_$as.usda" | grep -qx '#usda 1.0' || bad "patch_$as.usda: no usda header"
done
run moult_range.usda "$S/moult.json" --lod 0.1 --from 3.5 --to 4 --fps 4 --as instances -o "$OUT/moult_range.usda"
grep -q 'positions.timeSamples' "$OUT/moult_range.usda" || bad "moult_range.usda: positions not time-sampled"
run patch.obj "$S/patch.json" --lod 0.3 -o "$OUT/patch.obj"

echo "--- Khronos glTF validator"
if [ -f "$UNREACHABLE" ]; then
  echo "    skipped: npm registry unreachable (see $UNREACHABLE)"
else
  PTERYLA_NODE_MODULES=$NODE_MODULES node "$HERE/validate_gltf.mjs" "${gltfs[@]}" || bad "glTF validator reported errors"
fi

echo "--- bad input"
expect2() {  # expect2 WHAT PATTERN ARGS...: exit 2 and stderr matching PATTERN
  local what=$1 pattern=$2; shift 2
  "$PTERYLA" export "$@" -q 2>"$OUT/err.txt"; local rc=$?
  if [ $rc -ne 2 ] || ! grep -q -- "$pattern" "$OUT/err.txt"; then bad "$what: exit $rc, stderr: $(cat "$OUT/err.txt")"; else echo "ok   $what: $(head -1 "$OUT/err.txt")"; fi
}
expect2 "unknown extension" "\.fbx" "$S/patch.json" -o "$OUT/coat.fbx"
expect2 "--from after --to" "\-\-from" "$S/patch.json" --from 2 --to 1 -o "$OUT/r.glb"
expect2 "--from without --to" "\-\-to" "$S/patch.json" --from 2 -o "$OUT/r.glb"
expect2 "range into OBJ" "\-\-from" "$S/patch.json" --from 0 --to 1 -o "$OUT/r.obj"
expect2 "--as curves into glTF" "\-\-as" "$S/patch.json" --as curves -o "$OUT/r.glb"
expect2 "--as unknown" "\-\-as" "$S/patch.json" --as hair -o "$OUT/r.usda"
echo x > "$OUT/plainfile"
expect2 "unwritable path" "plainfile/c.glb" "$S/patch.json" --lod 0.1 -o "$OUT/plainfile/c.glb"
[ -e "$OUT/r.glb" ] && bad "a refused export left r.glb"

echo "--- a failed write keeps the old file"
echo "previous export" > "$OUT/keep.glb"
( trap "" XFSZ; ulimit -f 64; "$PTERYLA" export "$S/patch.json" --lod 0.3 -q -o "$OUT/keep.glb" 2>"$OUT/err.txt" ); rc=$?
[ $rc -eq 2 ] || bad "write past the file size limit: exit $rc ($(cat "$OUT/err.txt"))"
[ "$(cat "$OUT/keep.glb")" = "previous export" ] || bad "the previous keep.glb was overwritten"
ls "$OUT" | grep -q 'keep.glb.tmp' && bad "a temporary file was left behind"
echo "ok   exit $rc, previous file intact"

echo "--- help"
"$PTERYLA" export --help > "$OUT/help.txt" 2>&1 || bad "export --help failed"
for word in --from --to --fps --as .usda .glb KHR_materials_anisotropy; do grep -q -- "$word" "$OUT/help.txt" || bad "export --help lacks $word"; done

exit $fail
