#!/usr/bin/python3
"""Hand-made 2D cup labels (bench/object_labels/), for the objects' box keypoints.

A person reads, off gridded crops of the frames (scripts/label_hands.py
extract --region ... --step 20), the centres of each cup's upper and lower
rim ellipses; this script turns those notes into a label file and checks
it. It never runs a model: the labels are ground truth.

  import  NOTES.txt --video VIDEO --labeller WHO --out LABELS.json
          notes: "frame F" starts a frame, then one line per cup
          "cup UX UY LX LY" (upper rim centre, lower rim centre, pixels of
          the video as displayed); "#" starts a comment. The cup's centre is
          written as the midpoint of the two rim centres (the middle of its
          axis, as a box's centre keypoint is the middle of its box).
  check   LABELS.json...
          fields, points inside the frame, the upper rim above the lower
          (the cups stand on a table). Exit 1 on an error.
"""
import argparse
import json
import os
import subprocess
import sys


def video_size(video):
    out = subprocess.run(["ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries",
                          "stream=width,height", "-of", "csv=p=0", video],
                         check=True, capture_output=True, text=True).stdout.strip()
    w, h = out.split(",")[:2]
    return int(w), int(h)


def import_notes(args):
    width, height = video_size(args.video)
    frames, frame = [], None
    with open(args.notes) as f:
        for number, line in enumerate(f, 1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            words = line.split()
            if words[0] == "frame" and len(words) == 2:
                frame = {"frame": int(words[1]), "cups": []}
                frames.append(frame)
            elif words[0] == "cup" and len(words) == 5 and frame is not None:
                ux, uy, lx, ly = (float(w) for w in words[1:])
                frame["cups"].append({"upper": [ux, uy], "lower": [lx, ly],
                                      "centre": [(ux + lx) / 2, (uy + ly) / 2]})
            else:
                sys.exit(f"{args.notes}:{number}: expected 'frame F' or 'cup UX UY LX LY'")
    labels = {"video": os.path.relpath(args.video, os.path.dirname(os.path.abspath(args.out))),
              "video_name": os.path.basename(args.video), "width": width, "height": height,
              "labeller": args.labeller, "points": "rim centres read by eye off 20-px grid crops",
              "frames": frames}
    with open(args.out, "w") as f:
        json.dump(labels, f, indent=1)
        f.write("\n")
    print(f"{args.out}: {len(frames)} frames, {sum(len(fr['cups']) for fr in frames)} cups")


def check(args):
    bad = 0
    for path in args.labels:
        with open(path) as f:
            labels = json.load(f)
        w, h = labels["width"], labels["height"]
        for fr in labels["frames"]:
            for i, cup in enumerate(fr["cups"]):
                for key in ("upper", "lower", "centre"):
                    x, y = cup[key]
                    if not (0 <= x <= w and 0 <= y <= h):
                        print(f"{path}: frame {fr['frame']} cup {i}: {key} outside the frame")
                        bad += 1
                if cup["upper"][1] >= cup["lower"][1]:
                    print(f"{path}: frame {fr['frame']} cup {i}: upper rim not above the lower")
                    bad += 1
        print(f"{path}: {len(labels['frames'])} frames checked")
    sys.exit(1 if bad else 0)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    i = sub.add_parser("import")
    i.add_argument("notes")
    i.add_argument("--video", required=True)
    i.add_argument("--labeller", required=True)
    i.add_argument("--out", required=True)
    c = sub.add_parser("check")
    c.add_argument("labels", nargs="+")
    args = p.parse_args()
    import_notes(args) if args.command == "import" else check(args)


if __name__ == "__main__":
    main()
