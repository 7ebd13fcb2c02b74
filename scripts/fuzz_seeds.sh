#!/usr/bin/env bash
# Seed inputs for the fuzz targets (scripts/fuzz.sh), made from the test
# data: real clip lists (the demo CSV, EPIC-KITCHENS, 100DOH frame names),
# the same rows as TSV/JSONL/JSON, a VOC annotation, config files, review
# requests, and a clip bundle's meta.json and .npy/.npz members (Debian's
# NumPy, hence /usr/bin/python3).
# Usage: scripts/fuzz_seeds.sh OUT_DIR
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: fuzz_seeds.sh OUT_DIR}
mkdir -p "$out"
/usr/bin/python3 - "$out" <<'PY'
import io, json, os, sys
import numpy as np

out = sys.argv[1]
lists = "../shared/data/lists"

def seed(target, name, first_byte, body):
    d = os.path.join(out, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(body, str):
        body = body.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write((bytes([first_byte]) if first_byte is not None else b"") + body)

def head(path, n):
    with open(path, encoding="utf-8", errors="replace") as f:
        return "".join(f.readline() for _ in range(n))

# Clip lists: byte 0 csv, 1 tsv, 2 jsonl, 3 json, 4 txt, 5 EPIC, 6 VOC.
demo = head("examples/demo_clips.csv", 6)
rows = [r.split(",")[:4] for r in demo.splitlines()[1:]]
seed("clip_list_fuzz", "demo.csv", 0, demo)
seed("clip_list_fuzz", "demo_checked.csv", 0x80, demo)
seed("clip_list_fuzz", "demo.tsv", 1, demo.replace(",", "\t"))
objs = [{"video": r[0], "id": r[1], "start_frame": r[2], "end_frame": r[3]} for r in rows]
seed("clip_list_fuzz", "demo.jsonl", 2, "".join(json.dumps(o) + "\n" for o in objs))
seed("clip_list_fuzz", "times.jsonl", 2, '{"url": "https://example.org/a.mp4", "start": "00:01.5", "end": "1:02:03.250"}\n')
seed("clip_list_fuzz", "demo.json", 3, json.dumps(objs))
seed("clip_list_fuzz", "whim.json", 0x43, json.dumps({"dQw4w9WgXcQ": {"fps": 30, "resolution": [1280, 720]}}))
seed("clip_list_fuzz", "frames.txt", 0x44, head(f"{lists}/100doh_ego_test_framenames.txt", 20))
epic = head(f"{lists}/EPIC_100_validation.csv", 8)
seed("clip_list_fuzz", "epic.csv", 5, epic[len("narration_id,"):] + "\n===\n" +
     head(f"{lists}/EPIC_100_video_info.csv", 8))
voc = ("<annotation><size><width>640</width><height>480</height></size><object><name>hand</name>"
       "<bndbox><xmin>21</xmin><ymin>11</ymin><xmax>60</xmax><ymax>80</ymax></bndbox>"
       "<contactstate>3</contactstate><handside>1</handside><unitdx>0.6</unitdx><unitdy>0.8</unitdy>"
       "<magnitude>50</magnitude></object><object><name>targetobject</name><bndbox><xmin>100</xmin>"
       "<ymin>100</ymin><xmax>150</xmax><ymax>140</ymax></bndbox></object></annotation>")
seed("clip_list_fuzz", "voc.xml", 6, voc + "\n===\n" + voc.replace("21", "31"))

# Configs: byte bit 0 picks JSON.
seed("config_fuzz", "stages.toml", 0,
     "[probe]\nvfr_tolerance = 0.25\n\n[interaction]\nreject_contact = 0.05\n\n"
     "[timeouts]\nprobe = 30\n\n[report.thumbnail]\npanel_height = 120\n")
seed("config_fuzz", "stages.json", 1,
     json.dumps({"camera_motion": {"reject_px": 2.5}, "report": {"max_failures": 10}}))

# Review requests.
for i, body in enumerate([
        {"clip_id": 14, "stage": "interaction", "decision": "accept", "reviewer": "ann"},
        {"clip_id": 3, "stage": "retarget", "decision": "reject", "reviewer": "bo",
         "reason_code": "slips", "reason_text": "the cup slides"},
        {"trial_id": 7, "rater": "cy", "choice": "left"}]):
    seed("request_body_fuzz", f"body{i}.json", None, json.dumps(body))
seed("request_body_fuzz", "path_id", None, "12345")

# Bundles: even first byte = one .npy; odd = meta.json | K.npz | hands.npz |
# object/poses.npz | gravity.npz | tracks.npz.
def npy(a):
    b = io.BytesIO(); np.save(b, a); return b.getvalue()
def npz(**arrays):
    b = io.BytesIO(); np.savez(b, **arrays); return b.getvalue()
T = 3
seed("bundle_fuzz", "k.npy", 0, npy(np.eye(3)))
seed("bundle_fuzz", "u1.npy", 0, npy(np.ones((T,), np.uint8)))
seed("bundle_fuzz", "f4.npy", 0, npy(np.zeros((2, 21, 3), np.float32)))
meta = json.dumps({"width": 64, "height": 48, "frames": T, "fps": 30, "units": "m",
                   "producers": {"hands": "fuzz"}}).encode()
K = np.array([[50.0, 0, 32], [0, 50.0, 24], [0, 0, 1]])
hands = npz(right_valid=np.ones(T, np.uint8), right_joints=np.random.default_rng(1).normal(0, .05, (T, 21, 3)) + [0, 0, .5],
            left_valid=np.zeros(T, np.uint8), left_joints=np.zeros((T, 21, 3)))
poses = npz(poses=np.tile([0, 0, .5, 1, 0, 0, 0], (T, 1)).astype(float))
gravity = npz(up=np.tile([0, -1.0, 0], (T, 1)))
tracks = npz(xy=np.zeros((4, T, 2), np.float32), visible=np.ones((4, T), np.uint8),
             query=np.zeros((4, 3), np.float32))
sep = b"\n===\n"
seed("bundle_fuzz", "bundle", 1, sep.join([meta, npz(K=K), hands, poses, gravity, tracks]))
seed("bundle_fuzz", "meta_only", 1, meta)
PY
echo "fuzz_seeds: $(find "$out" -type f | wc -l) seeds in $out"
