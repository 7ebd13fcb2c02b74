#!/usr/bin/env bash
# Installs what is needed, builds, and runs the whole test suite (unit,
# integration, end-to-end CLI and browser tests) with CTest, then every
# libFuzzer target for a short run (scripts/fuzz.sh; FUZZ_SECONDS, 0 skips).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --test
mkdir -p "${BUILD_DIR:-build}"
BUILD_LOG=${BUILD_LOG:-$PWD/${BUILD_DIR:-build}/build.log} bash scripts/build.sh
(cd "${BUILD_DIR:-build}" && ctest --output-on-failure -j"${JOBS:-$(nproc)}" --timeout 900)
if [[ ${FUZZ_SECONDS:-15} != 0 ]]; then
  BUILD_LOG=quiet bash scripts/fuzz.sh all "${FUZZ_SECONDS:-15}"
fi
