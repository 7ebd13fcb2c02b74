#!/bin/sh
# A stand-in for a model command (the `bundle` stage's [bundle] command):
# copies the ground-truth bundle `doasido synth` wrote for a synthetic
# video (<synth out>/videos/NAME.mp4 -> <synth out>/bundles/NAME/) into
# the stage's output folder. For any other video it writes nothing and
# exits 0: no model output for that clip, so the `hands` stage's hand-only
# bundle stands in (stages/bundle_stage.h).
#   [bundle]
#   command = "sh tools/ground_truth_bundle.sh {video} {output}"
set -eu
video=$1
output=$2
truth=$(dirname "$(dirname "$video")")/bundles/$(basename "$video" .mp4)
if [ -f "$truth/meta.json" ]; then
  cp -r "$truth/." "$output/"
  echo "ground truth from $truth"
else
  echo "no ground truth for $video: nothing written"
fi
