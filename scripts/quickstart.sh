#!/usr/bin/env bash
# The two commands of the README.
#   scripts/quickstart.sh demo : install what is missing, build Release, remesh a bundled example
#                                (examples/data/spot.obj → build/demo/spot_quads.{obj,glb})
#   scripts/quickstart.sh test : install what is missing, build Release, run the whole test suite,
#                                then the fast tests again under AddressSanitizer + UBSan
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
mode="${1:-demo}"
jobs="$(nproc 2>/dev/null || echo 2)"

configure_build() {  # dir, extra cmake args...
  local dir="$1"; shift
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
  cmake --build "$dir" -j "$jobs"
}

case "$mode" in
  demo)
    bash scripts/install_deps.sh
    configure_build build -DQUADIFY_BUILD_TESTS=OFF
    out="$here/build/demo"
    mkdir -p "$out"
    ./build/bin/quadify examples/data/spot.obj -o "$out/spot_quads.obj" --target-faces 3000 \
      --json "$out/spot_report.json"
    ./build/bin/quadify examples/data/spot.obj -o "$out/spot_quads.glb" --target-faces 3000 --quiet
    echo
    echo "quadify: quad mesh written to $out/spot_quads.obj (and $out/spot_quads.glb for a glTF viewer)"
    echo "quadify: report (timings, cones, quad quality, Hausdorff distance) in $out/spot_report.json"
    ;;
  test)
    bash scripts/install_deps.sh --with-test-tools
    configure_build build -DQUADIFY_BUILD_TESTS=ON -DQUADIFY_REQUIRE_TEST_TOOLS=ON
    (cd build && ctest -j "$jobs" --output-on-failure --timeout 900)
    # Fast tests again with AddressSanitizer + UndefinedBehaviorSanitizer (no CLI, no examples).
    configure_build build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQUADIFY_SANITIZE=ON \
      -DQUADIFY_BUILD_TOOLS=OFF -DQUADIFY_BUILD_EXAMPLES=OFF
    (cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
       ctest -j "$jobs" -L fast --output-on-failure --timeout 900)
    ;;
  *)
    echo "usage: scripts/quickstart.sh demo|test" >&2
    exit 2
    ;;
esac
