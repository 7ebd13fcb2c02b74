#!/usr/bin/env bash
# Configures and builds doasido (Release) into build/. Extra arguments go to
# CMake's configure step, e.g. BUILD_TYPE=Debug scripts/build.sh -DDOASIDO_SANITIZE=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
# ccache, when installed (scripts/setup.sh installs it), makes rebuilds and
# fresh clones cheap; paths below the checkout's parent are hashed relative
# to the build folder, so two clones share the cache.
launcher=()
if command -v ccache >/dev/null; then
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$(cd .. && pwd)}
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" "${launcher[@]}" "$@" >/dev/null
# BUILD_TARGETS (space-separated) limits the build, e.g. BUILD_TARGETS=doasido.
targets=()
for t in ${BUILD_TARGETS:-}; do targets+=(--target "$t"); done
# BUILD_LOG=file sends the compiler's lines there (the test script does, so a
# green CI log stays short) and prints its last 80 lines only on failure.
if [[ -n ${BUILD_LOG:-} ]]; then
  if ! cmake --build "$BUILD_DIR" -j"$JOBS" "${targets[@]}" >"$BUILD_LOG" 2>&1; then
    tail -n 80 "$BUILD_LOG"; echo "build: failed (whole log: $BUILD_LOG)" >&2; exit 1
  fi
  echo "build: $BUILD_DIR up to date (log: $BUILD_LOG)"
else
  cmake --build "$BUILD_DIR" -j"$JOBS" "${targets[@]}"
fi
