#!/usr/bin/env bash
# Installs what is needed, builds, and runs the main job on the embedded
# default: a SQLite database in work/, fed with the bundled demo list (real
# sample videos from ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
BUILD_TARGETS=doasido bash scripts/build.sh
WORK=${WORK:-work}
mkdir -p "$WORK"
DOASIDO=build/bin/doasido
$DOASIDO init --db "$WORK/doasido.db"
$DOASIDO run --db "$WORK/doasido.db" --jobs 2 examples/demo_clips.csv
echo
echo "Database: $WORK/doasido.db   (try: $DOASIDO status --db $WORK/doasido.db)"
