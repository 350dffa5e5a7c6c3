#!/usr/bin/env bash
# Installs exactly the Debian 12 packages pteryla needs to build, test and render headlessly.
# `--fuzz` adds clang-14 + libclang-rt-14-dev (libFuzzer, ASan/UBSan runtimes) and llvm-14
# (llvm-symbolizer) for tools/fuzz.sh; gcc's own sanitizer runtimes (tools/sanitize.sh) come with
# build-essential.
# `--slurm` adds slurm-wlm and munge for the single-node Slurm test (tests/farm/slurm_single_node.sh,
# docs/farm.md); without them that test is skipped. The packages' services are not started.
# Idempotent and quiet: packages already present are skipped; apt-get update runs at most once.
set -euo pipefail
PACKAGES=(
  build-essential cmake ninja-build pkg-config ccache git ca-certificates
  libglm-dev libopenmesh-dev libcgal-dev libgmp-dev libmpfr-dev libeigen3-dev libtbb-dev
  libopenimageio-dev libosmesa6-dev libglfw3-dev libgl-dev libimgui-dev
  nlohmann-json3-dev libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev
  xvfb xauth
  python3-dev python3-pybind11 python3-numpy python3-pytest blender
  libtinygltf-dev nodejs
)
# npm: a package of its own on Debian 12, bundled with (and conflicting with) NodeSource's nodejs.
command -v npm >/dev/null 2>&1 || PACKAGES+=(npm)
for arg in "$@"; do
  case "$arg" in
    --fuzz) PACKAGES+=(clang-14 libclang-rt-14-dev llvm-14) ;;
    --slurm) PACKAGES+=(slurm-wlm munge) ;;
    *) echo "bootstrap.sh: unknown option '$arg' (expected --fuzz, --slurm)" >&2; exit 2 ;;
  esac
done
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
echo "pteryla bootstrap: installing ${#missing[@]} packages: ${missing[*]}" >&2
$SUDO apt-get update -qq >/dev/null
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
