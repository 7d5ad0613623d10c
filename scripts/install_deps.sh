#!/usr/bin/env bash
# Installs what quadify needs and is missing: Debian packages (apt-get, non-interactive; sudo only
# when not root) and, for tests, the Khronos glTF validator (npm, into .deps/npm of this checkout)
# and headless Chromium (screenshots of `quadify compare` pages).
# Usage: scripts/install_deps.sh [--with-test-tools]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libopenmesh-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libtinygltf-dev libstb-dev libsuitesparse-dev libtbb-dev
  # An optimized, thread-safe BLAS/LAPACK for CHOLMOD's supernodal factorization (Debian's
  # alternatives then point libblas.so.3 at it): armadillo's factorizations 60.6 s → 39.8 s
  # against the reference BLAS. Not the serial OpenBLAS, which is unsafe for concurrent calls.
  libopenblas0-pthread
  libgtest-dev libcli11-dev nlohmann-json3-dev
)
with_test_tools=0
[[ "${1:-}" == "--with-test-tools" ]] && with_test_tools=1
if (( with_test_tools )); then
  packages+=(nodejs python3 chromium)
  command -v npm >/dev/null 2>&1 || packages+=(npm)
fi

sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null 2>&1 || { echo "install_deps: not root and no sudo" >&2; exit 1; }
  sudo_cmd=(sudo)
fi

missing=()
for p in "${packages[@]}"; do
  # nodejs/npm/chromium may come from another source than Debian: accept them when on PATH.
  case "$p" in
    nodejs) command -v node >/dev/null 2>&1 && continue ;;
    npm) command -v npm >/dev/null 2>&1 && continue ;;
    python3) command -v python3 >/dev/null 2>&1 && continue ;;
    chromium) command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 && continue ;;
  esac
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if (( ${#missing[@]} )); then
  echo "install_deps: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
else
  echo "install_deps: all Debian packages present" >&2
fi

if (( with_test_tools )); then
  validator="$here/.deps/npm/node_modules/gltf-validator/package.json"
  if [[ ! -f "$validator" ]]; then
    echo "install_deps: installing npm gltf-validator into .deps/npm" >&2
    mkdir -p "$here/.deps/npm"
    # The validator is published only as 2.0.0-dev.* prereleases, which a bare "@2" range excludes.
    (cd "$here/.deps/npm" && npm install --silent --no-audit --no-fund --prefix . gltf-validator@2.0.0-dev.3.10 >/dev/null)
  fi
fi
