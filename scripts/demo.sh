#!/usr/bin/env bash
# Installs what the main job needs (scripts/setup.sh without --test), builds
# the doasido binary, and runs the whole chain (`doasido init`'s default
# pipeline) on the bundled real sample videos (examples/demo_clips.csv, from
# ../shared/data) and freshly generated synthetic clips: filters -> hands ->
# bundle -> recon -> retarget_kinematic -> retarget (dynamics, `fast`
# preset) -> a dataset version of the clips that succeeded -> its LeRobot
# export; then prints which episodes are hand-object (retargeted with
# dynamics) and which hand-only, where each clip stopped and why, and how
# long install, build and run took.
# Real videos: the category models' 2D detector finds no red cup in
# 02_cups, so one row of the list boxes the held cup on one frame (column
# object_box, as a person prompts SAM2): the objects stage follows it and
# lifts it to a metric pose sized by the touching fingertips, and that clip
# (cups_held, frames 12-40) is a real hand + object episode retargeted with
# dynamics; so is cups_carried_left (frames 82-97: the person's left hand
# lifts a cup and carries it behind the middle one, retargeted mirrored;
# about 20 CPU s of retarget at `fast`). The other real clips stay hand-only (real hand motion on the
# robot hand). The synthetic clips have exact ground truth: a stand-in for
# a model command (tools/ground_truth_bundle.sh) hands their bundles,
# objects included, to the bundle stage.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS=0
bash scripts/setup.sh
INSTALL_S=$SECONDS
BUILD_TARGETS=doasido bash scripts/build.sh
BUILD_S=$((SECONDS - INSTALL_S))
WORK=${WORK:-work}
mkdir -p "$WORK"
DOASIDO=build/bin/doasido
DB="$WORK/doasido.db"
# Synthetic clips with exact ground truth and a known defect mix (100DOH-style
# VOC annotations with hand and object boxes), next to the real samples.
$DOASIDO synth --out "$WORK/synth" --clips 8 --seed 1 --frames 60 \
  --mix clean=0.25,cut=0.125,fade=0.125,pan=0.125,out_of_frame=0.125,no_contact=0.125,static=0.125
# The paper's dynamics preset takes minutes per second of video on a CPU:
# the demo takes the fastest one.
cat > "$WORK/demo.toml" <<TOML
[bundle]
command = "sh '$PWD/tools/ground_truth_bundle.sh' {video} {output}"

[retarget]
preset = "fast"

# Look wide for a hand lost mid-clip (a hand lifting a cup fast loses its
# track: docs/hands.md).
[hands]
lost_wide_search = 3
TOML
$DOASIDO init --db "$DB"   # the whole chain
$DOASIDO run --db "$DB" --jobs 2 --config "$WORK/demo.toml" examples/demo_clips.csv "$WORK/synth"
$DOASIDO report --db "$DB" --out "$WORK/report"
echo
if VERSION=$($DOASIDO dataset create --db "$DB" --root "$WORK/datasets" --name demo \
               --select success --no-thumbnails | tail -1); then
  rm -rf "$WORK/lerobot/$(basename "$VERSION")"
  # The cameras ran at 25, 29.97 and 30 fps: one rate for the export.
  $DOASIDO dataset export "$VERSION" --format lerobot --fps 30 --out "$WORK/lerobot/$(basename "$VERSION")"
  # The hand-only episodes drop observation.object_pose from the whole
  # export; the hand-object episodes alone (the real cups_held and
  # cups_carried_left among them)
  # keep it.
  rm -rf "$WORK/lerobot/$(basename "$VERSION")-hand-object"
  $DOASIDO dataset export "$VERSION" --format lerobot --fps 30 --hand-object-only \
    --out "$WORK/lerobot/$(basename "$VERSION")-hand-object"
  echo
  echo "Episodes (kind: hand-object = retargeted with dynamics; hand-only = kinematic):"
  $DOASIDO dataset show "$VERSION"
else
  echo "No dataset version: no clip's trajectory succeeded."
fi
echo
echo "Where each clip stopped:"
$DOASIDO status --db "$DB" --clips
echo
echo "Database: $DB   (try: $DOASIDO status --db $DB)"
echo "Report:   $WORK/report/report.html"
[ -n "${VERSION:-}" ] && echo "Dataset:  $VERSION   LeRobot export: $WORK/lerobot/$(basename "$VERSION")" \
  "(hand-object episodes with observation.object_pose: $WORK/lerobot/$(basename "$VERSION")-hand-object)"
echo "Review the flagged clips: $DOASIDO review serve --db $DB"
RUN_S=$((SECONDS - INSTALL_S - BUILD_S))
echo "Check the robot trajectories beside their videos: $DOASIDO review serve --db $DB  (then /verify)"
echo "Took: install ${INSTALL_S} s, build ${BUILD_S} s, run ${RUN_S} s"
