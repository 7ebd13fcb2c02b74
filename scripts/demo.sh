#!/usr/bin/env bash
# Installs what is needed, builds, and runs the main job on the embedded
# default: a SQLite database in work/, fed with the bundled demo list (real
# sample videos from ../shared/data) and freshly generated synthetic clips.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
BUILD_TARGETS=doasido bash scripts/build.sh
WORK=${WORK:-work}
mkdir -p "$WORK"
DOASIDO=build/bin/doasido
# Synthetic clips with exact ground truth and a known defect mix (100DOH-style
# VOC annotations with hand and object boxes), next to the real samples.
$DOASIDO synth --out "$WORK/synth" --clips 8 --seed 1 --frames 60 \
  --mix clean=0.25,cut=0.125,fade=0.125,pan=0.125,out_of_frame=0.125,no_contact=0.125,static=0.125
$DOASIDO init --db "$WORK/doasido.db"
$DOASIDO run --db "$WORK/doasido.db" --jobs 2 examples/demo_clips.csv "$WORK/synth"
$DOASIDO report --db "$WORK/doasido.db" --out "$WORK/report"
echo
echo "Database: $WORK/doasido.db   (try: $DOASIDO status --db $WORK/doasido.db)"
echo "Report:   $WORK/report/report.html"
echo "Review the flagged clips: $DOASIDO review serve --db $WORK/doasido.db"
