#!/usr/bin/python3
"""Reference model server for doasido's `bundle` stage (server mode).

Speaks the line protocol of recon/bundle/model_server.h on stdin/stdout: after
loading its "model" it prints {"type": "ready"}, then answers each request
line {"type": "clip", "clip", "video", "first_frame", "last_frame", "fps",
"output"} with {"type": "done", "clip", "bundle"} or {"type": "error",
"clip", "message"}. It exits when its stdin closes. Logs go to stderr.

The "model" is a stand-in: loading it is a sleep of --load-s seconds, and
running it on a clip copies the clip's synthetic ground-truth bundle (from
`doasido synth`: <synth>/bundles/<video name without extension>, or
--truth DIR/<that name>) into the output folder, reading its intrinsics with
numpy as a real adapter would read its model's outputs.

    # server mode ([bundle] server = "...")
    tools/bundle_server.py [--load-s S] [--truth DIR] [--fail CLIP] [--hang CLIP]
                           [--die CLIP] [--once DIR]
    # one clip, then exit ([bundle] command = "...", same stand-in)
    tools/bundle_server.py --load-s S --clip {clip} --video {video} --output {output}

--fail/--hang/--die (repeatable) make the server answer an error, sleep
forever, or exit with status 3 when it gets that clip; with --once DIR each
of them happens only the first time per clip (remembered by files in DIR).

To wrap a real model, keep main() and the protocol and replace Model: load
the networks in __init__ (before "ready"), and in run() read the video span,
run the networks and write the bundle (docs/clip_bundle.md, "Layout").
Needs only Debian's python3-numpy.
"""
import argparse
import json
import os
import shutil
import sys
import time

import numpy as np


def log(text):
    sys.stderr.write(f"bundle_server[{os.getpid()}]: {text}\n")
    sys.stderr.flush()


class Model:
    def __init__(self, load_s, truth):
        log(f"loading model ({load_s:g} s)")
        time.sleep(load_s)
        self.truth = truth
        log(f"model loaded in {load_s:g} s")

    def run(self, request):
        video = request["video"]
        name = os.path.splitext(os.path.basename(video))[0]
        root = self.truth or os.path.join(os.path.dirname(os.path.dirname(video)), "bundles")
        src = os.path.join(root, name)
        if not os.path.isdir(src):
            raise FileNotFoundError(f"no ground-truth bundle {src}")
        out = request["output"]
        shutil.copytree(src, out, dirs_exist_ok=True)
        k = np.load(os.path.join(out, "K.npz"))["K"]
        log(f"clip {request['clip']}: frames {request['first_frame']}..{request['last_frame']}"
            f" at {request['fps']} fps, fx {float(k.reshape(-1, 9)[0, 0]):.1f} -> {out}")
        return out


class Misbehaviour:
    def __init__(self, args):
        self.plan = {"fail": set(args.fail), "hang": set(args.hang), "die": set(args.die)}
        self.once = args.once

    def wants(self, kind, clip):
        if clip not in self.plan[kind]:
            return False
        if self.once is None:
            return True
        os.makedirs(self.once, exist_ok=True)
        mark = os.path.join(self.once, f"{kind}-{clip}")
        if os.path.exists(mark):
            return False
        open(mark, "w").close()
        return True


def serve_one(model, misbehaviour, request):
    clip = request["clip"]
    if misbehaviour.wants("die", clip):
        log(f"dying on purpose while holding clip {clip}")
        sys.exit(3)
    if misbehaviour.wants("hang", clip):
        log(f"hanging on purpose on clip {clip}")
        time.sleep(1e6)
    if misbehaviour.wants("fail", clip):
        log(f"RuntimeError: CUDA out of memory (on purpose, clip {clip})")
        return {"type": "error", "clip": clip, "message": "CUDA out of memory"}
    try:
        return {"type": "done", "clip": clip, "bundle": model.run(request)}
    except Exception as e:  # the clip fails, the server goes on
        log(f"clip {clip}: {e!r}")
        return {"type": "error", "clip": clip, "message": str(e)}


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--load-s", type=float, default=0.0)
    parser.add_argument("--truth")
    for kind in ("fail", "hang", "die"):
        parser.add_argument(f"--{kind}", action="append", default=[], metavar="CLIP")
    parser.add_argument("--once")
    parser.add_argument("--clip")
    parser.add_argument("--video")
    parser.add_argument("--output")
    parser.add_argument("--first-frame", type=int, default=0)
    parser.add_argument("--last-frame", type=int, default=-1)
    parser.add_argument("--fps", type=float, default=0.0)
    args = parser.parse_args()
    misbehaviour = Misbehaviour(args)
    model = Model(args.load_s, args.truth)
    if args.clip is not None:  # command mode: one clip
        reply = serve_one(model, misbehaviour,
                          {"clip": args.clip, "video": args.video, "output": args.output,
                           "first_frame": args.first_frame, "last_frame": args.last_frame,
                           "fps": args.fps})
        sys.exit(0 if reply["type"] == "done" else 1)
    print(json.dumps({"type": "ready"}), flush=True)
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        if request.get("type") != "clip":
            print(json.dumps({"type": "error", "clip": request.get("clip", ""),
                              "message": f"unknown request {request.get('type')!r}"}), flush=True)
            continue
        print(json.dumps(serve_one(model, misbehaviour, request)), flush=True)
    log("stdin closed: exiting")


if __name__ == "__main__":
    main()
