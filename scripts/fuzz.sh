#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz with clang (AddressSanitizer +
# UndefinedBehaviorSanitizer, every library instrumented) into build-fuzz/
# and fuzzes them. BUILD_LOG=any sends the build's lines to build-fuzz/build.log.
#
#   scripts/fuzz.sh                    # every target, 600 s each
#   scripts/fuzz.sh clip_list_fuzz 60  # one target, 60 s
#   scripts/fuzz.sh all 15             # every target briefly (the test suite does this)
#
# Seeds: tests/fuzz/regressions/<target>/ (inputs that once crashed, kept as
# regression tests: each is run first) and seeds made from the test data
# (scripts/fuzz_seeds.sh; hand_import_fuzz writes its own URDF seed, made by
# the C++ of the import tests). The working corpus and crashes are in
# build-fuzz/corpus/<target>/ and build-fuzz/crashes/<target>/; a crash
# ends the run with exit 1, naming the input file.
set -euo pipefail
cd "$(dirname "$0")/.."
target=${1:-all}
seconds=${2:-600}
BUILD_DIR=${FUZZ_BUILD_DIR:-build-fuzz}
targets=(bundle_fuzz clip_list_fuzz config_fuzz hand_import_fuzz request_body_fuzz)
[[ $target == all ]] || targets=("$target")

mkdir -p "$BUILD_DIR"
CC=clang CXX=clang++ BUILD_DIR=$BUILD_DIR BUILD_TYPE=RelWithDebInfo BUILD_LOG=${BUILD_LOG:+$PWD/$BUILD_DIR/build.log} \
  BUILD_TARGETS="${targets[*]}" bash scripts/build.sh \
  -DDOASIDO_FUZZ=ON -DDOASIDO_BUILD_TESTS=OFF -DDOASIDO_BUILD_BENCH=OFF -DDOASIDO_WERROR=OFF
bash scripts/fuzz_seeds.sh "$BUILD_DIR/seeds"

status=0
for t in "${targets[@]}"; do
  corpus=$BUILD_DIR/corpus/$t crashes=$BUILD_DIR/crashes/$t
  mkdir -p "$corpus" "$crashes"
  regressions=tests/fuzz/regressions/$t
  # The inputs that once crashed come first: each must now pass.
  if compgen -G "$regressions/*" >/dev/null; then
    "$BUILD_DIR/fuzz/$t" -rss_limit_mb=2048 "$regressions"/* >"$crashes/regressions.out" 2>"$crashes/regressions.log" || {
      echo "fuzz: $t fails a regression input (see $crashes/regressions.log)"; status=1; continue; }
  fi
  echo "fuzz: $t for ${seconds}s"
  # (a target may add seeds only C++ can make: DOASIDO_FUZZ_SEEDS)
  if ! DOASIDO_FUZZ_SEEDS=$BUILD_DIR/seeds/$t "$BUILD_DIR/fuzz/$t" "$corpus" "$BUILD_DIR/seeds/$t" -max_total_time="$seconds" \
      -timeout=20 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
      -artifact_prefix="$crashes/" >"$crashes/run.out" 2>"$crashes/run.log"; then
    echo "fuzz: $t found a crash, hang or leak:"; grep -E "ERROR|artifact|SUMMARY" "$crashes/run.log" | head -5
    status=1
    continue
  fi
  grep -E "^stat::number_of_executed_units|^#[0-9]+ *DONE" "$crashes/run.log" | tr '\n' ' '; echo
done
exit $status
