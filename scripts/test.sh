#!/usr/bin/env bash
# Installs what is needed, builds, and runs the whole test suite (unit,
# integration, end-to-end CLI and browser tests) with CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
cd "${BUILD_DIR:-build}"
ctest --output-on-failure -j"${JOBS:-$(nproc)}" --timeout 900
