#!/usr/bin/python3
"""Hand-made 2D hand keypoint labels (bench/hand_labels/, hands/hand_labels.h).

A person places the 21 MediaPipe-order keypoints by reading pixel coordinates
off zoomed, gridded crops of the frames; this script makes those images and
checks the result. It never runs a hand model: the labels are ground truth.
Needs numpy and ffmpeg/ffprobe only (no OpenCV or PIL on the Debian image).

  sheet   VIDEO --out DIR [--count 16]
          a contact sheet of COUNT frames spread over the video, each with its
          frame number and a coarse pixel grid: pick frames and hand regions.
  extract VIDEO --out DIR (--at F,F,.. | --count N [--span A:B])
          [--region X0,Y0,X1,Y1] [--zoom Z] [--step PX]
          per frame: frame_<F>.png (the whole frame, grid every 100 px) and,
          with --region, frame_<F>_crop.png (the region enlarged Z times, grid
          lines and pixel-coordinate ticks every STEP px of the video).
  check   LABELS.json... [--out DIR] [--zoom Z]
          validates each file (fields, 21 points per hand, visible ones inside
          the frame, joint-order sanity: warnings) and, with --out, draws the
          labels back as a skeleton on a zoomed, gridded crop per hand
          (DIR/<stem>/check_<F>_<side>.png) and a montage (check_all.png).
          Exit 1 on an error.
  import  NOTES.txt --video VIDEO --labeller WHO --out LABELS.json
          the labeller's notes as a label file: a line "frame F right|left"
          starts a hand, then 21 lines "J U V" (joint J in MediaPipe order,
          pixels), "J U V h" for a keypoint hidden and guessed (visible false);
          "#" starts a comment.
  compare A.json B.json [A2.json B2.json ...]
          pairs of labelling passes of the same frames: the distance per
          keypoint (both passes visible) between them, mean and 90th
          percentile, in px and in hand boxes, per hand and over all pairs.

Coordinates are pixels of the video as displayed (ffmpeg applies the
rotation), frame numbers the decoded frame index from 0. VIDEO (and a label
file's "video") is a file, a path under ../shared/data, "npm:<package>/<path>"
in the npm folder or "<file>.rcc:/<path>", an entry of a Qt resource file
(a photo, frame 0; hands/packaged_image.h reads the same); a cut-out
picture's transparent pixels are shown over white.
"""
import argparse
import json
import os
import struct
import subprocess
import sys
import zlib

import numpy as np

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data")
JOINTS = 21
# MediaPipe's joint order: wrist, then thumb, index, middle, ring, pinky from
# base to tip (4 joints each).
FINGERS = [(1, 2, 3, 4), (5, 6, 7, 8), (9, 10, 11, 12), (13, 14, 15, 16), (17, 18, 19, 20)]
BONES = [(0, f[0]) for f in FINGERS] + [(f[i], f[i + 1]) for f in FINGERS for i in range(3)] + \
    [(5, 9), (9, 13), (13, 17)]
FINGER_COLOURS = [(255, 60, 60), (255, 200, 0), (0, 220, 0), (0, 200, 255), (220, 0, 255)]

# 3x5 bitmap digits (and '-'), rows top to bottom, bits left to right.
GLYPHS = {
    "0": "111101101101111", "1": "010110010010111", "2": "111001111100111",
    "3": "111001111001111", "4": "101101111001001", "5": "111100111001111",
    "6": "111100111101111", "7": "111001001001001", "8": "111101111101111",
    "9": "111101111001111", "-": "000000111000000", "R": "110101110101101",
    "L": "100100100100111", "f": "011100110100100", " ": "000000000000000",
}


def fail(msg):
    sys.stderr.write("label_hands: " + msg + "\n")
    sys.exit(1)


# ---------------------------------------------------------------- video I/O

def video_size(path):
    """Displayed width and height (a 90/270 degree rotation swaps them)."""
    out = subprocess.run(
        ["ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries",
         "stream=width,height:stream_side_data=rotation", "-of", "json", path],
        capture_output=True, text=True)
    if out.returncode != 0:
        fail(f"{path}: ffprobe cannot read it: {out.stderr.strip()}")
    s = json.loads(out.stdout)["streams"][0]
    w, h = s["width"], s["height"]
    rot = next((int(d["rotation"]) for d in s.get("side_data_list", []) if "rotation" in d), 0)
    return (h, w) if rot % 180 else (w, h)


def frame_count(path):
    out = subprocess.run(
        ["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
         "stream=nb_read_frames", "-of", "csv=p=0", path], capture_output=True, text=True)
    return int(out.stdout.strip().split(",")[0])


def read_frames(path, frames):
    """The frames (decoded index from 0) as HxWx3 uint8 arrays, in one pass."""
    w, h = video_size(path)
    want = sorted(set(frames))
    expr = "+".join(f"eq(n\\,{f})" for f in want)
    out = subprocess.run(
        ["ffmpeg", "-v", "error", "-i", path, "-vf", f"select={expr}", "-fps_mode", "passthrough",
         "-f", "rawvideo", "-pix_fmt", "rgba", "-"], capture_output=True)
    if out.returncode != 0:
        fail(f"{path}: ffmpeg cannot decode it: {out.stderr.decode().strip()}")
    size = w * h * 4
    got = len(out.stdout) // size
    if got != len(want):
        fail(f"{path}: asked for frames {want}, decoded {got} (past the end?)")
    arr = np.frombuffer(out.stdout, np.uint8).reshape(got, h, w, 4).astype(np.uint32)
    # A cut-out photo's transparent pixels hold anything: over white, as shown
    # (hands/packaged_image.h does the same).
    a = arr[..., 3:]
    rgb = ((arr[..., :3] * a + 255 * (255 - a) + 127) // 255).astype(np.uint8)
    return {f: rgb[i].copy() for i, f in enumerate(want)}


def write_png(path, img):
    h, w, _ = img.shape
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(h))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + \
            struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


# ---------------------------------------------------------------- drawing

def text(img, x, y, s, colour=(255, 255, 0), scale=2):
    """Draws s with its top-left corner at (x, y), on a dark box for contrast."""
    h, w, _ = img.shape
    x0, y0 = max(0, x - 1), max(0, y - 1)
    x1, y1 = min(w, x + 4 * scale * len(s) + 1), min(h, y + 5 * scale + 1)
    img[y0:y1, x0:x1] = img[y0:y1, x0:x1] // 3
    for i, ch in enumerate(s):
        bits = GLYPHS.get(ch, GLYPHS[" "])
        for r in range(5):
            for c in range(3):
                if bits[r * 3 + c] == "1":
                    px, py = x + (4 * i + c) * scale, y + r * scale
                    img[max(0, py):max(0, min(h, py + scale)), max(0, px):max(0, min(w, px + scale))] = colour


def line(img, p, q, colour, width=1):
    h, w, _ = img.shape
    n = int(max(abs(q[0] - p[0]), abs(q[1] - p[1]))) + 1
    for t in np.linspace(0.0, 1.0, n):
        x, y = int(round(p[0] + t * (q[0] - p[0]))), int(round(p[1] + t * (q[1] - p[1])))
        img[max(0, y - width // 2):max(0, min(h, y + width - width // 2)),
            max(0, x - width // 2):max(0, min(w, x + width - width // 2))] = colour


def dot(img, p, colour, r=3):
    h, w, _ = img.shape
    x, y = int(round(p[0])), int(round(p[1]))
    img[max(0, y - r):max(0, min(h, y + r + 1)), max(0, x - r):max(0, min(w, x + r + 1))] = colour


def zoom_crop(frame, region, zoom, step):
    """The region enlarged zoom times (nearest pixel: video pixel k spans
    coordinates [k, k+1), a grid line at x is the left edge of column x) with
    grid lines every step video px and their coordinates; returns the image
    and a function mapping video coordinates into it."""
    h, w, _ = frame.shape
    x0, y0, x1, y1 = (max(0, region[0]), max(0, region[1]), min(w, region[2]), min(h, region[3]))
    if x1 <= x0 or y1 <= y0:
        fail(f"region {region} is outside the {w}x{h} frame")
    if step <= 0:  # tick labels at least 40 image px apart
        step = next(s for s in (5, 10, 20, 50, 100) if s * zoom >= 40)
    crop = frame[y0:y1, x0:x1].repeat(zoom, 0).repeat(zoom, 1)
    margin = 40  # room for the tick labels
    img = np.zeros((crop.shape[0] + margin, crop.shape[1] + margin, 3), np.uint8)
    img[margin:, margin:] = crop
    grid = img[margin:, margin:]
    for gx in range((x0 + step - 1) // step * step, x1, step):
        X = (gx - x0) * zoom
        grid[:, X] = (grid[:, X] // 2 + np.array([0, 110, 110], np.uint8))
        text(img, margin + X - 8, 4, str(gx), scale=2)
    for gy in range((y0 + step - 1) // step * step, y1, step):
        Y = (gy - y0) * zoom
        grid[Y, :] = (grid[Y, :] // 2 + np.array([0, 110, 110], np.uint8))
        text(img, 1, margin + Y - 4, str(gy), scale=1 if gy >= 1000 else 2)

    def to_img(p):
        return (margin + (p[0] - x0) * zoom, margin + (p[1] - y0) * zoom)

    return img, to_img


def full_with_grid(frame, step, label):
    img = frame.copy()
    h, w, _ = img.shape
    for gx in range(step, w, step):
        img[:, gx] = img[:, gx] // 2 + np.array([0, 110, 110], np.uint8)
        text(img, gx + 2, 2, str(gx))
    for gy in range(step, h, step):
        img[gy, :] = img[gy, :] // 2 + np.array([0, 110, 110], np.uint8)
        text(img, 2, gy + 2, str(gy))
    text(img, 2, h - 14, label, colour=(255, 255, 255))
    return img


def montage(images, columns):
    hmax = max(i.shape[0] for i in images)
    wmax = max(i.shape[1] for i in images)
    rows = (len(images) + columns - 1) // columns
    out = np.zeros((rows * (hmax + 4), columns * (wmax + 4), 3), np.uint8)
    for k, i in enumerate(images):
        r, c = divmod(k, columns)
        out[r * (hmax + 4):r * (hmax + 4) + i.shape[0], c * (wmax + 4):c * (wmax + 4) + i.shape[1]] = i
    return out


def shrink(img, factor):
    return img[::factor, ::factor] if factor > 1 else img


# ---------------------------------------------------------------- commands

def npm_dir():
    return os.environ.get("DOASIDO_NPM_DIR") or os.path.expanduser("~/.cache/doasido/npm")


def rcc_entry(file, path):
    """The bytes of entry `path` of a Qt resource file (hands/packaged_image.cc
    reads the same format: big-endian header, tree, data and names)."""
    with open(file, "rb") as f:
        b = f.read()
    if b[:4] != b"qres":
        fail(f"{file}: not a Qt resource file")
    version, tree, data, names = struct.unpack(">IIII", b[4:20])
    size = 22 if version >= 2 else 14

    def name(i):
        o = names + struct.unpack(">I", b[tree + i * size:tree + i * size + 4])[0]
        n = struct.unpack(">H", b[o:o + 2])[0]
        return b[o + 6:o + 6 + 2 * n].decode("utf-16-be")
    node = 0
    for part in [p for p in path.split("/") if p]:
        o = tree + node * size
        count, first = struct.unpack(">II", b[o + 6:o + 14])
        node = next((c for c in range(first, first + count) if name(c) == part), None)
        if node is None:
            fail(f"{file}: no entry {path}")
    o = tree + node * size
    if struct.unpack(">H", b[o + 4:o + 6])[0] & 7:
        fail(f"{file}: {path} is a directory or compressed")
    d = data + struct.unpack(">I", b[o + 10:o + 14])[0]
    return b[d + 4:d + 4 + struct.unpack(">I", b[d:d + 4])[0]]


def resolve_video(video):
    """A path ffmpeg reads: a file, one under ../shared/data, "npm:<package>/<path>"
    in the npm folder, or "<file>.rcc:/<path>" copied out of a Qt resource file."""
    if video.startswith("npm:"):
        return os.path.join(npm_dir(), "node_modules", video[4:])
    if ".rcc:" in video:
        file, path = video.split(".rcc:", 1)
        out = os.path.join("/tmp", "label_hands_rcc", path.lstrip("/"))
        os.makedirs(os.path.dirname(out), exist_ok=True)
        with open(out, "wb") as f:
            f.write(rcc_entry(file + ".rcc", path))
        return out
    return video if os.path.exists(video) else os.path.join(DATA, video)


def spread(count, first, last):
    if count <= 1:
        return [first]
    return sorted(set(int(round(first + i * (last - first) / (count - 1))) for i in range(count)))


def cmd_sheet(a):
    path = resolve_video(a.video)
    n = frame_count(path)
    frames = read_frames(path, spread(a.count, 0, n - 1))
    w, _ = video_size(path)
    factor = max(1, w // 400)
    thumbs = [shrink(full_with_grid(img, a.grid, f"f{f}"), factor) for f, img in frames.items()]
    os.makedirs(a.out, exist_ok=True)
    out = os.path.join(a.out, "sheet.png")
    write_png(out, montage(thumbs, 4))
    print(f"{out}: {len(thumbs)} of {n} frames, 1/{factor} size, grid every {a.grid} px")


def cmd_extract(a):
    path = resolve_video(a.video)
    if a.at:
        want = [int(f) for f in a.at.split(",")]
    else:
        first, last = (int(x) for x in a.span.split(":")) if a.span else (0, frame_count(path) - 1)
        want = spread(a.count, first, last)
    frames = read_frames(path, want)
    os.makedirs(a.out, exist_ok=True)
    region = [int(x) for x in a.region.split(",")] if a.region else None
    for f, img in frames.items():
        write_png(os.path.join(a.out, f"frame_{f}.png"), full_with_grid(img, 100, f"f{f}"))
        if region:
            crop, _ = zoom_crop(img, region, a.zoom, a.step)
            write_png(os.path.join(a.out, f"frame_{f}_crop.png"), crop)
        print(os.path.join(a.out, f"frame_{f}" + ("_crop" if region else "") + ".png"))


def check_hand(where, hand, w, h):
    """Errors (the file is wrong) and warnings (look again) of one hand."""
    errors, warnings = [], []
    if hand.get("side") not in ("right", "left"):
        errors.append(f"{where}: side must be right or left, not {hand.get('side')!r}")
    kp = hand.get("keypoints_2d")
    if not isinstance(kp, list) or len(kp) != JOINTS or any(len(p) != 2 for p in kp):
        return errors + [f"{where}: keypoints_2d must hold 21 [u, v] pairs"], warnings
    vis = hand.get("visible", [True] * JOINTS)
    if len(vis) != JOINTS or any(not isinstance(v, bool) for v in vis):
        errors.append(f"{where}: visible must hold 21 booleans")
        vis = [True] * JOINTS
    p = np.array(kp, float)
    for j, (u, v) in enumerate(p):
        if not (0 <= u < w and 0 <= v < h):  # a hidden guess may lie past the border
            (warnings if not vis[j] else errors).append(
                f"{where}: keypoint {j} ({u:.0f}, {v:.0f}) is outside the {w}x{h} frame")
    box = max(1.0, float((p.max(0) - p.min(0)).max()))
    for a_, b_ in BONES:
        if np.linalg.norm(p[a_] - p[b_]) < 0.01 * box:
            warnings.append(f"{where}: joints {a_} and {b_} coincide (bone of zero length)")
    # The knuckles run index -> pinky across the palm: along the index-pinky
    # axis the middle and ring knuckles lie between (a swapped finger or a
    # thumb/pinky mix-up breaks this).
    axis = p[17] - p[5]
    t = [float(np.dot(p[k] - p[5], axis)) / max(1e-9, float(np.dot(axis, axis))) for k in (5, 9, 13, 17)]
    if not (t[0] - 0.15 <= t[1] <= t[2] + 0.15 <= t[3] + 0.3):
        warnings.append(f"{where}: knuckles 5, 9, 13, 17 are not in order across the palm "
                        f"({', '.join(f'{x:.2f}' for x in t)})")
    # The thumb's base is nearer the wrist than the index knuckle is, and
    # the knuckles are nearer the wrist than the fingertips of a hand that
    # is not a fist.
    if np.linalg.norm(p[1] - p[0]) > np.linalg.norm(p[5] - p[0]):
        warnings.append(f"{where}: thumb base 1 is farther from the wrist than index knuckle 5")
    tips_nearer = sum(np.linalg.norm(p[f[3]] - p[0]) < np.linalg.norm(p[f[0]] - p[0]) for f in FINGERS[1:])
    if tips_nearer >= 3:
        warnings.append(f"{where}: {tips_nearer} fingertips nearer the wrist than their knuckles "
                        "(a fist, or base and tip swapped?)")
    return errors, warnings


def draw_hand(frame, hand, zoom, step):
    p = np.array(hand["keypoints_2d"], float)
    vis = hand.get("visible", [True] * JOINTS)
    pad = max(12, int(0.15 * (p.max(0) - p.min(0)).max()))
    lo, hi = p.min(0) - pad, p.max(0) + pad
    if zoom <= 0:  # fit the crop into about 900 px
        zoom = max(1, int(900 / max(1.0, float((hi - lo).max()))))
    img, to_img = zoom_crop(frame, [int(lo[0]), int(lo[1]), int(hi[0]) + 1, int(hi[1]) + 1], zoom, step)
    finger_of = {j: k for k, f in enumerate(FINGERS) for j in f}
    centre = lambda j: to_img(p[j])
    for a_, b_ in BONES:
        colour = FINGER_COLOURS[finger_of[b_]] if a_ == 0 or finger_of.get(a_) == finger_of.get(b_) \
            else (255, 255, 255)
        line(img, centre(a_), centre(b_), colour, width=3)
    for j in range(JOINTS):
        colour = FINGER_COLOURS[finger_of[j]] if j else (255, 255, 255)
        dot(img, centre(j), colour if vis[j] else (128, 128, 128), r=5)
        x, y = centre(j)
        text(img, int(x) + 6, int(y) + 4, str(j), colour=colour, scale=2)
    return img


def load_labels(file):
    try:
        with open(file) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{file}: cannot read it as JSON: {e}")


def cmd_check(a):
    failed = False
    for file in a.labels:
        failed |= not check_file(file, a)
    if failed:
        sys.exit(1)


def check_file(file, a):
    """Validates one label file and, with --out, draws it; False on an error."""
    labels = load_labels(file)
    for field in ("video", "labeller", "frames"):
        if field not in labels:
            print(f"error: {file}: field {field} is missing")
            return False
    path = resolve_video(labels["video"])
    if not os.path.exists(path):
        print(f"error: {file}: video {labels['video']} is not in {DATA} (or not installed)")
        return False
    w, h = video_size(path)
    errors, warnings = [], []
    seen = set()
    for i, fr in enumerate(labels["frames"]):
        f = fr.get("frame")
        if not isinstance(f, int) or f < 0 or f in seen:
            errors.append(f"{file}: frames[{i}].frame must be a new frame index, not {f!r}")
        seen.add(f)
        sides = [hd.get("side") for hd in fr.get("hands", [])]
        if len(sides) != len(set(sides)):
            errors.append(f"{file}: frame {f} labels two hands of one side")
        for k, hand in enumerate(fr.get("hands", [])):
            e, wn = check_hand(f"{file}: frame {f} hand {k} ({hand.get('side')})", hand, w, h)
            errors += e
            warnings += wn
    for m in warnings:
        print("warning: " + m)
    for m in errors:
        print("error: " + m)
    if errors:
        return False
    n = sum(len(fr["hands"]) for fr in labels["frames"])
    if a.out:
        draw_labels(labels, path, os.path.join(a.out, os.path.splitext(os.path.basename(file))[0]), a)
    print(f"{file}: {len(labels['frames'])} frames, {n} hands, {len(warnings)} warnings"
          + (f"; drawings in {a.out}" if a.out else ""))
    return True


def draw_labels(labels, path, out, a):
    frames = read_frames(path, [fr["frame"] for fr in labels["frames"]])
    os.makedirs(out, exist_ok=True)
    images = []
    for fr in labels["frames"]:
        for hand in fr["hands"]:
            img = draw_hand(frames[fr["frame"]], hand, a.zoom, a.step)
            text(img, 44, img.shape[0] - 16, f"f{fr['frame']} " + hand["side"][0].upper(), colour=(255, 255, 255))
            write_png(os.path.join(out, f"check_{fr['frame']}_{hand['side']}.png"), img)
            images.append(shrink(img, 2))
    if images:
        write_png(os.path.join(out, "check_all.png"), montage(images, 3))


def cmd_import(a):
    frames, hand = {}, None
    with open(a.notes) as f:
        for n, raw in enumerate(f, 1):
            words = raw.split("#")[0].split()
            if not words:
                continue
            if words[0] == "frame":
                if len(words) != 3 or words[2] not in ("right", "left"):
                    fail(f"{a.notes}:{n}: expected 'frame F right|left'")
                hand = {"side": words[2], "keypoints_2d": [None] * JOINTS, "visible": [True] * JOINTS}
                frames.setdefault(int(words[1]), []).append(hand)
                continue
            if hand is None or len(words) not in (3, 4) or (len(words) == 4 and words[3] != "h"):
                fail(f"{a.notes}:{n}: expected 'J U V' or 'J U V h' after a frame line")
            j = int(words[0])
            if not 0 <= j < JOINTS or hand["keypoints_2d"][j] is not None:
                fail(f"{a.notes}:{n}: joint {j} is not a new joint 0..20")
            hand["keypoints_2d"][j] = [float(words[1]), float(words[2])]
            hand["visible"][j] = len(words) == 3
    for f, hands in frames.items():
        for hd in hands:
            missing = [j for j, p in enumerate(hd["keypoints_2d"]) if p is None]
            if missing:
                fail(f"{a.notes}: frame {f} {hd['side']}: joints {missing} have no line")
    out = {"video": a.video, "labeller": a.labeller,
           "frames": [{"frame": f, "hands": frames[f]} for f in sorted(frames)]}
    with open(a.out, "w") as f:
        f.write(json.dumps(out, indent=1) + "\n")
    print(f"{a.out}: {len(frames)} frames, {sum(len(h) for h in frames.values())} hands")


def cmd_compare(a):
    if len(a.files) % 2:
        fail("compare takes pairs of label files: FIRST SECOND [FIRST SECOND ...]")
    dist, rel = [], []
    for first_file, second_file in zip(a.files[::2], a.files[1::2]):
        first, second = load_labels(first_file), load_labels(second_file)
        if first["video"] != second["video"]:
            fail(f"{first_file} labels {first['video']}, {second_file} {second['video']}")
        by_frame = {(fr["frame"], hd["side"]): hd for fr in second["frames"] for hd in fr["hands"]}
        for fr in first["frames"]:
            for hd in fr["hands"]:
                other = by_frame.get((fr["frame"], hd["side"]))
                if other is None:
                    continue
                p, q = np.array(hd["keypoints_2d"], float), np.array(other["keypoints_2d"], float)
                # Keypoints both passes saw; the box as hands_bench scores (hands/hand_labels.cc).
                both = np.array(hd.get("visible", [True] * JOINTS)) & np.array(other.get("visible", [True] * JOINTS))
                box = max(1.0, float((p[both].max(0) - p[both].min(0)).max()))
                d = np.linalg.norm(p - q, axis=1)
                worst = int(np.argmax(np.where(both, d, -1)))
                print(f"{first['video']} frame {fr['frame']} {hd['side']}: {both.sum()} keypoints, box {box:.0f} px, "
                      f"mean {d[both].mean():.1f} px ({d[both].mean() / box:.3f} box), max {d[worst]:.1f} px (joint {worst})")
                dist += list(d[both])
                rel += list(d[both] / box)
    if not dist:
        fail("the pairs share no labelled hand")
    dist, rel = np.array(dist), np.array(rel)
    print(f"all: {len(dist)} keypoints; distance mean {dist.mean():.2f} px, 90th percentile "
          f"{np.percentile(dist, 90):.2f} px; in hand boxes mean {rel.mean():.3f}, 90th percentile "
          f"{np.percentile(rel, 90):.3f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("sheet")
    s.add_argument("video")
    s.add_argument("--out", required=True)
    s.add_argument("--count", type=int, default=16)
    s.add_argument("--grid", type=int, default=100)
    e = sub.add_parser("extract")
    e.add_argument("video")
    e.add_argument("--out", required=True)
    e.add_argument("--at")
    e.add_argument("--count", type=int, default=6)
    e.add_argument("--span")
    e.add_argument("--region")
    e.add_argument("--zoom", type=int, default=4)
    e.add_argument("--step", type=int, default=0, help="grid step in video px (0: by zoom)")
    c = sub.add_parser("check")
    c.add_argument("labels", nargs="+")
    c.add_argument("--out", help="draw the labels into OUT/<file stem>/ (without: validate only)")
    c.add_argument("--zoom", type=int, default=0, help="0: fit each hand into about 900 px")
    c.add_argument("--step", type=int, default=0, help="grid step in video px (0: by zoom)")
    i = sub.add_parser("import")
    i.add_argument("notes")
    i.add_argument("--video", required=True, help="relative to ../shared/data, e.g. videos/02_cups.mp4")
    i.add_argument("--labeller", required=True)
    i.add_argument("--out", required=True)
    m = sub.add_parser("compare")
    m.add_argument("files", nargs="+", help="FIRST SECOND [FIRST SECOND ...]")
    a = ap.parse_args()
    {"sheet": cmd_sheet, "extract": cmd_extract, "check": cmd_check, "import": cmd_import,
     "compare": cmd_compare}[a.cmd](a)


if __name__ == "__main__":
    main()
