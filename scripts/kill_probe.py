#!/usr/bin/env python3
"""Kill probe (issue #36): SIGKILL a doasido command at random moments and
check what each kill leaves, then that the same command run again succeeds.

For each operation the command is first timed once; each of --kills kills
then lands at a uniform random moment within that time. A kill "leaves the
old state" or "leaves the new state whole" when the check of that operation
says so; anything else is a failure and is printed. Operations:

  export-lerobot-new / -replace, export-robomimic-new / -replace
      the output is absent (new) or the previous export byte for byte
      (replace), or a complete export (LeRobot: meta/info.json and the
      manifest; robomimic: h5py opens it and reads every demo)
  publish    `doasido run` re-running retarget_kinematic after a reset: every
      run the database records done+pass has its complete trajectory.json,
      and no clip folder holds a half-written one under the published name
  merge      `doasido merge` of a finished shard: the parent's rows are the
      old ones (no merged run) or the new ones, and every trajectory the
      parent records done+pass is a complete file equal to the shard's, as
      any doasido command sees it (its open finishes a merge killed after
      its commit; the notes count those)
  shard      also checked: every shard folder is recorded by the parent and
      every recorded shard has its database
  report, hand-import, synth, shard, deploy-plan
      described only: what the kill left (files, leftovers) and whether the
      re-run succeeded
  rethreshold  `doasido rethreshold` with a stricter activity limit after the
      activity runs were queued again: killed, then run again at once (within
      the lease); the stage runs must equal an uninterrupted run's ("runs
      left running" counts kills that left a claim behind)
  full-disk  (needs `unshare -rm`) each export (new, replacing) and `dataset
      create` into a tmpfs of a random size between 5 % and 150 % of what it
      needs: it succeeds with a whole output, or fails with a message leaving
      the earlier output byte for byte (or none) and no temporary

Usage: scripts/kill_probe.py --bin build/bin/doasido --work /tmp/probe [--kills 20]
"""
import argparse
import hashlib
import json
import os
import random
import shutil
import signal
import sqlite3
import subprocess
import sys
import time

PIPELINE = ("download,probe,filters_analyze,shot_boundary,interaction,out_of_frame,activity,"
            "camera_motion,bundle,recon,retarget_kinematic")
BUNDLE = ('[bundle]\ncommand = "cp -r $(dirname $(dirname {video}))/bundles/$(basename '
          '{video} .mp4)/. {output}/"\n')


def run(bin_, args, check=True):
    r = subprocess.run([bin_] + args, capture_output=True, text=True)
    if check and r.returncode != 0:
        sys.exit(f"failed: doasido {' '.join(args)}\n{r.stderr}")
    return r


def timed(bin_, args):
    t0 = time.monotonic()
    run(bin_, args)
    return time.monotonic() - t0


def killed(bin_, args, at_s):
    p = subprocess.Popen([bin_] + args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(at_s)
    p.send_signal(signal.SIGKILL)
    p.wait()
    return p.returncode == -signal.SIGKILL  # False: it finished before the kill


def tree_hash(path):
    if not os.path.exists(path):
        return None
    if os.path.isfile(path):
        return hashlib.sha256(open(path, "rb").read()).hexdigest()
    h = hashlib.sha256()
    for root, dirs, files in sorted(os.walk(path)):
        dirs.sort()
        for f in sorted(files):
            p = os.path.join(root, f)
            h.update(os.path.relpath(p, path).encode())
            h.update(open(p, "rb").read())
    return h.hexdigest()


def leftovers(folder, tag=".tmp-"):
    return [f for f in os.listdir(folder) if tag in f] if os.path.isdir(folder) else []


def lerobot_whole(out):
    return (os.path.exists(os.path.join(out, "meta/info.json")) and
            os.path.exists(os.path.join(out, "meta/doasido_manifest.json")))


def robomimic_whole(out):
    r = subprocess.run(["/usr/bin/python3", "-c",
                        "import h5py,sys; f=h5py.File(sys.argv[1],'r'); "
                        "[f['data'][k]['actions'][()] for k in f['data']]", out],
                       capture_output=True)
    return r.returncode == 0


def absent_or(test):
    """Checks an output a kill left: absent, or whole by `test` (a
    temporary beside it is the next writer's to remove)."""
    return lambda out: not os.path.exists(out) or test(out)


def json_ok(path):
    try:
        json.load(open(path))
        return True
    except (OSError, ValueError):
        return False


hand_whole = absent_or(lambda out: any(f.endswith(".json") and json_ok(os.path.join(out, f))
                                       for f in os.listdir(out)))
plan_whole = absent_or(json_ok)
report_whole = absent_or(lambda out: os.path.exists(os.path.join(out, "report.html")) and
                         json_ok(os.path.join(out, "report.json")))
synth_whole = absent_or(lambda out: os.path.exists(os.path.join(out, "clips.csv")))


def done_trajectories(db):
    c = sqlite3.connect(db)
    rows = c.execute("SELECT clip_id FROM stage_runs WHERE stage = 'retarget_kinematic'"
                     " AND state = 'done' AND verdict = 'pass'").fetchall()
    c.close()
    return [r[0] for r in rows]


def complete_trajectory(path):
    try:
        json.load(open(path))
        return True
    except (OSError, ValueError):
        return False


class Probe:
    def __init__(self, args):
        self.bin = os.path.abspath(args.bin)
        self.work = os.path.abspath(args.work)
        self.kills = args.kills
        self.rng = random.Random(args.seed)
        self.results = {}

    def record(self, op, outcome, fine, note=""):
        r = self.results.setdefault(op, {"old": 0, "new": 0, "finished": 0, "bad": 0, "rerun_ok": 0,
                                         "notes": []})
        r[outcome if fine else "bad"] += 1
        if note:
            r["notes"].append(note)

    def setup(self):
        shutil.rmtree(self.work, ignore_errors=True)
        os.makedirs(self.work)
        self.pool = os.path.join(self.work, "s")
        run(self.bin, ["synth", "--out", self.pool, "--clips", "4", "--seed", "5", "--frames", "30",
                       "--width", "160", "--height", "120", "--mix", "clean=1"])
        self.config = os.path.join(self.work, "run.toml")
        open(self.config, "w").write(BUNDLE)
        self.db = os.path.join(self.work, "d", "d.db")
        os.makedirs(os.path.dirname(self.db))
        run(self.bin, ["init", "--db", self.db, "--pipeline", PIPELINE])
        run(self.bin, ["run", "--db", self.db, "--config", self.config, self.pool])
        self.root = os.path.join(self.work, "ds")
        run(self.bin, ["dataset", "create", "--db", self.db, "--root", self.root, "--select", "all",
                       "--no-thumbnails"])

    def export(self, fmt, replace):
        op = f"export-{fmt}-{'replace' if replace else 'new'}"
        out = os.path.join(self.work, f"out-{op}" + (".hdf5" if fmt == "robomimic" else ""))
        args = ["dataset", "export", "--root", self.root, "v1", "--format", fmt, "--out", out]
        whole = lerobot_whole if fmt == "lerobot" else robomimic_whole
        full = timed(self.bin, args)
        for _ in range(self.kills):
            if not replace:
                shutil.rmtree(out, ignore_errors=True) if os.path.isdir(out) else (
                    os.path.exists(out) and os.remove(out))
            before = tree_hash(out)
            finished = not killed(self.bin, args, self.rng.uniform(0, full))
            after = tree_hash(out)
            if finished:
                self.record(op, "finished", whole(out))
            elif after == before:
                self.record(op, "old", True)
            else:
                self.record(op, "new", whole(out), "" if whole(out) else f"partial {out}")
            r = run(self.bin, args, check=False)
            self.results[op]["rerun_ok"] += r.returncode == 0 and whole(out)
        self.results[op]["leftovers_after_reruns"] = leftovers(self.work)

    def publish(self):
        op = "publish"
        art = os.path.join(os.path.dirname(self.db), "artifacts")
        reset = ["queue", "reset", "--db", self.db, "--stage", "retarget_kinematic", "--all"]
        args = ["run", "--db", self.db, "--config", self.config, "--lease", "1"]
        run(self.bin, reset)
        full = timed(self.bin, args)
        for _ in range(self.kills):
            run(self.bin, reset)
            finished = not killed(self.bin, args, self.rng.uniform(0, full))
            ok = True
            done = done_trajectories(self.db)
            for clip in done:
                ok &= complete_trajectory(os.path.join(art, str(clip), "retarget_kinematic",
                                                       "trajectory.json"))
            # A folder under the published name without a done run is never read
            # (readers ask the database first); count it as a note.
            stray = [c for c in os.listdir(art) if c.isdigit() and int(c) not in done and
                     os.path.exists(os.path.join(art, c, "retarget_kinematic"))]
            self.record(op, "finished" if finished else ("new" if done else "old"), ok,
                        f"{len(stray)} published folders of runs not done" if stray else "")
            time.sleep(1.1)  # the killed worker's lease expires
            r = run(self.bin, args, check=False)
            self.results[op]["rerun_ok"] += (r.returncode == 0 and
                                             len(done_trajectories(self.db)) == len(os.listdir(self.pool + "/videos")))

    def merge(self):
        op = "merge"
        parent = os.path.join(self.work, "m", "d.db")
        os.makedirs(os.path.dirname(parent))
        run(self.bin, ["init", "--db", parent, "--pipeline", PIPELINE])
        run(self.bin, ["ingest", "--db", parent, self.pool])
        run(self.bin, ["shard", "--db", parent, "--shards", "1", "--out",
                       os.path.join(self.work, "m", "sh"), "--config", self.config])
        shard = os.path.join(self.work, "m", "sh", "shard-000", "doasido.db")
        run(self.bin, ["run", "--db", shard, "--config", self.config])
        snapshot = os.path.join(self.work, "m-snapshot")
        shutil.copytree(os.path.dirname(parent), snapshot, symlinks=True,
                        ignore=shutil.ignore_patterns("sh"))
        args = ["merge", "--db", parent, shard]
        full = timed(self.bin, args)
        shard_art = os.path.join(os.path.dirname(shard), "artifacts")
        parent_art = os.path.join(os.path.dirname(parent), "artifacts")
        for k in range(self.kills):
            for f in os.listdir(os.path.dirname(parent)):  # back to before the merge
                if f != "sh":
                    p = os.path.join(os.path.dirname(parent), f)
                    shutil.rmtree(p) if os.path.isdir(p) and not os.path.islink(p) else os.remove(p)
            for f in os.listdir(snapshot):
                src = os.path.join(snapshot, f)
                dst = os.path.join(os.path.dirname(parent), f)
                shutil.copytree(src, dst, symlinks=True) if os.path.isdir(src) else shutil.copy2(src, dst)
            # Copying into staging takes most of a merge; every other kill lands
            # in its last 30 % (the commit and the placing).
            finished = not killed(self.bin, args, self.rng.uniform(0.7 * full if k % 2 else 0, full))

            def placed():
                return all(tree_hash(os.path.join(parent_art, str(c), "retarget_kinematic", "trajectory.json")) ==
                           tree_hash(os.path.join(shard_art, str(c), "retarget_kinematic", "trajectory.json"))
                           for c in done_trajectories(parent))
            raw = placed()
            # The state any doasido command sees: its open finishes a merge
            # killed after its commit (the placement journal).
            run(self.bin, ["status", "--db", parent])
            ok = placed()
            done = done_trajectories(parent)
            outcome = "finished" if finished else ("new" if done else "old")
            self.record(op, outcome, ok,
                        "" if raw else "killed after the commit: files staged, placed by the next open")
            r = run(self.bin, args, check=False)
            good = r.returncode == 0 and all(
                tree_hash(os.path.join(parent_art, str(c), "retarget_kinematic", "trajectory.json")) ==
                tree_hash(os.path.join(shard_art, str(c), "retarget_kinematic", "trajectory.json"))
                for c in done_trajectories(parent))
            self.results[op]["rerun_ok"] += good

    def rethreshold(self):
        op = "rethreshold"
        base = os.path.join(self.work, "rt-base")
        shutil.copytree(os.path.dirname(self.db), base, symlinks=True)
        run(self.bin, ["queue", "reset", "--db", f"{base}/d.db", "--stage", "activity", "--all"])
        strict = os.path.join(self.work, "strict.toml")
        open(strict, "w").write("[activity]\nmin_active_fraction = 0.9\n")

        def fresh(name):
            d = os.path.join(self.work, name)
            shutil.rmtree(d, ignore_errors=True)
            shutil.copytree(base, d, symlinks=True)
            return f"{d}/d.db", ["rethreshold", "--db", f"{d}/d.db", "--config", strict]

        def runs(db):
            c = sqlite3.connect(db)
            rows = c.execute("SELECT clip_id, stage, state, IFNULL(verdict, ''), IFNULL(reason, '')"
                             " FROM stage_runs ORDER BY clip_id, position").fetchall()
            c.close()
            return rows

        db, args = fresh("rt-ref")
        full = timed(self.bin, args)
        want = runs(db)
        r = self.results.setdefault(op, {"old": 0, "new": 0, "finished": 0, "bad": 0, "rerun_ok": 0,
                                         "runs_left_running": 0, "notes": []})
        for k in range(self.kills):
            db, args = fresh("rt")
            before = runs(db)
            # Start-up takes most of a short run: every other kill lands in
            # its last half (the claims).
            finished = not killed(self.bin, args, self.rng.uniform(0.5 * full if k % 2 else 0, full))
            left = runs(db)
            r["runs_left_running"] += any(row[2] == "running" for row in left)
            self.record(op, "finished" if finished else ("old" if left == before else "new"), True)
            rr = run(self.bin, args, check=False)  # at once: within the killed run's lease
            same = rr.returncode == 0 and runs(db) == want
            r["rerun_ok"] += same
            if not same:
                r["bad"] += 1
                r["notes"].append(f"re-run exit {rr.returncode}: runs differ from an uninterrupted run")

    def full_disk(self):
        if subprocess.run(["unshare", "-rm", "true"], capture_output=True).returncode != 0:
            self.results["full-disk"] = {"skipped": "no user namespaces"}
            return
        w = os.path.join(self.work, "fd")
        os.makedirs(w, exist_ok=True)
        mnt = os.path.join(w, "mnt")
        os.makedirs(mnt, exist_ok=True)
        good = {"robomimic": os.path.join(w, "good.hdf5"), "lerobot": os.path.join(w, "good-lerobot"),
                "create": os.path.join(w, "good-root")}
        run(self.bin, ["dataset", "export", "--root", self.root, "v1", "--format", "robomimic",
                       "--out", good["robomimic"]])
        run(self.bin, ["dataset", "export", "--root", self.root, "v1", "--format", "lerobot",
                       "--out", good["lerobot"]])
        run(self.bin, ["dataset", "create", "--db", self.db, "--root", good["create"], "--select", "all",
                       "--no-thumbnails"])

        def size(p):
            return os.path.getsize(p) if os.path.isfile(p) else sum(
                os.path.getsize(os.path.join(a, f)) + 4096 for a, _, fs in os.walk(p) for f in fs)

        def args_for(kind, out):
            if kind == "create":
                return ["dataset", "create", "--db", self.db, "--root", out, "--select", "all",
                        "--no-thumbnails"]
            return ["dataset", "export", "--root", self.root, "v1", "--format", kind, "--out", out]

        whole = {"robomimic": robomimic_whole, "lerobot": lerobot_whole,
                 "create": lambda o: os.path.exists(os.path.join(o, "default", "v1", "manifest.json"))}
        q = lambda p: "'" + p + "'"
        for kind, replace in (("robomimic", False), ("robomimic", True), ("lerobot", False),
                              ("lerobot", True), ("create", False)):
            op = f"full-disk-{kind}-{'replace' if replace else 'new'}"
            r = self.results.setdefault(op, {"fit": 0, "failed_clean": 0, "bad": 0, "notes": []})
            need = size(good[kind])
            for _ in range(self.kills):
                kb = int(need * self.rng.uniform(0.05, 1.5) / 1024) + 8
                if replace:
                    kb += need // 1024 + 8
                out = os.path.join(mnt, "out")
                copy = os.path.join(w, "copy")
                shutil.rmtree(copy, ignore_errors=True) if os.path.isdir(copy) else (
                    os.path.exists(copy) and os.remove(copy))
                script = (f"mount -t tmpfs -o size={kb}k tmpfs {q(mnt)} || exit 90; "
                          + (f"cp -a {q(good[kind])} {q(out)} || exit 91; " if replace else "")
                          + " ".join(q(a) for a in [self.bin] + args_for(kind, out))
                          + f" > {q(w)}/log 2>&1; echo $? > {q(w)}/rc; ls -a {q(mnt)} > {q(w)}/ls; "
                          f"[ -e {q(out)} ] && cp -a {q(out)} {q(copy)}; umount {q(mnt)}; exit 0")
                if subprocess.run(["unshare", "-rm", "sh", "-c", script]).returncode != 0:
                    r["notes"].append(f"{kb} kB: the namespace script failed")
                    continue
                rc = int(open(f"{w}/rc").read())
                log = open(f"{w}/log").read().strip()
                names = set(open(f"{w}/ls").read().split()) - {".", ".."}
                if rc == 0:
                    fine = whole[kind](copy)
                    r["fit" if fine else "bad"] += 1
                    if not fine:
                        r["notes"].append(f"{kb} kB: exit 0 but the output is not whole")
                    continue
                kept = (tree_hash(copy) == tree_hash(good[kind])) if replace else (
                    not os.path.exists(copy) or (kind == "create" and not whole[kind](copy) and
                                                 not os.listdir(os.path.join(copy, "default"))))
                fine = kept and bool(log) and names <= {"out"}
                r["failed_clean" if fine else "bad"] += 1
                if not fine:
                    r["notes"].append(f"{kb} kB: exit {rc}, earlier output kept {kept}, "
                                      f"left {sorted(names)}, said {log.splitlines()[-1:] if log else 'nothing'}")
                elif log.splitlines()[-1:] and len(r["notes"]) < 3:
                    r["notes"].append(f"{kb} kB: {log.splitlines()[-1][:160]}")

    def shard_whole(self, out):
        """Every shard folder is recorded by the parent and every recorded
        shard has its database, after any doasido command opened the parent."""
        parent = os.path.join(os.path.dirname(out), "d.db")
        run(self.bin, ["status", "--db", parent])
        c = sqlite3.connect(parent)
        listed = {os.path.normpath(os.path.join(os.path.dirname(parent), p))
                  for (p,) in c.execute("SELECT path FROM shards")}
        c.close()
        folders = {os.path.join(out, f, "doasido.db") for f in os.listdir(out)} if os.path.isdir(out) else set()
        visible = {f for f in folders if not os.path.basename(os.path.dirname(f)).startswith(".")}
        return all(os.path.exists(p) for p in listed) and visible <= listed

    def describe(self, op, args_of, out_of, kills=None, check=None, force=False):
        """Kills and reports what is left; the re-run must succeed."""
        full = timed(self.bin, args_of(0))
        r = self.results.setdefault(op, {"left": {}, "rerun_ok": 0, "kills": 0})
        for i in range(kills or self.kills):
            args = args_of(i + 1)
            out = out_of(i + 1)
            killed(self.bin, args, self.rng.uniform(0, full))
            r["kills"] += 1
            if not os.path.exists(out):
                state = "nothing"
            elif os.path.isdir(out):
                state = f"folder with {sum(len(f) for _, _, f in os.walk(out))} files"
            else:
                state = f"file of {os.path.getsize(out)} bytes"
            r["left"][state] = r["left"].get(state, 0) + 1
            if check is not None:
                fine = check(out)
                r["whole"] = r.get("whole", 0) + fine
                r["bad"] = r.get("bad", 0) + (not fine)
            # The re-run replaces what a kill after the rename completed.
            rr = run(self.bin, args + (["--force"] if force else []), check=False)
            # A shard killed after its last commit had finished its work.
            done_before = op == "shard" and "nothing_to_shard" in rr.stderr
            r["rerun_ok"] += rr.returncode == 0 or done_before
            if rr.returncode != 0 and not done_before:
                r.setdefault("rerun_errors", []).append(rr.stderr.strip().splitlines()[-1:])

    def others(self):
        w = self.work
        self.describe("report", lambda i: ["report", "--db", self.db, "--out", f"{w}/report{i}"],
                      lambda i: f"{w}/report{i}", check=report_whole, force=True)
        hand = os.path.join(os.path.dirname(self.bin), "..", "..", "..", "shared", "data", "robots",
                            "wonik_allegro", "right_hand.xml")
        hand = os.environ.get("PROBE_HAND_MJCF", os.path.abspath(hand))
        self.describe("hand-import", lambda i: ["hand", "import", "--mjcf", hand, "--out", f"{w}/hand{i}"],
                      lambda i: f"{w}/hand{i}", check=hand_whole, force=True)
        self.describe("synth", lambda i: ["synth", "--out", f"{w}/synth{i}", "--clips", "3", "--frames",
                                          "30", "--width", "96", "--height", "72"],
                      lambda i: f"{w}/synth{i}", check=synth_whole, force=True)

        def shard_args(i):
            d = f"{w}/shardsrc{i}"
            if not os.path.exists(d):
                os.makedirs(d)
                run(self.bin, ["init", "--db", f"{d}/d.db", "--pipeline", PIPELINE])
                run(self.bin, ["ingest", "--db", f"{d}/d.db", self.pool])
            return ["shard", "--db", f"{d}/d.db", "--shards", "2", "--out", f"{d}/sh", "--config",
                    self.config]
        self.describe("shard", shard_args, lambda i: f"{w}/shardsrc{i}/sh", check=self.shard_whole)
        clip = str(done_trajectories(self.db)[0]) if done_trajectories(self.db) else "1"
        self.describe("deploy-plan", lambda i: ["deploy", "plan", "--db", self.db, "--clip", clip, "--out",
                                                f"{w}/plan{i}.json", "--no-replay"],
                      lambda i: f"{w}/plan{i}.json", check=plan_whole, force=True)
        self.results["others-leftovers-after-reruns"] = {"files": leftovers(self.work)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default="build/bin/doasido")
    ap.add_argument("--work", default="/tmp/doasido_kill_probe")
    ap.add_argument("--kills", type=int, default=20)
    ap.add_argument("--seed", type=int, default=36)
    ap.add_argument("--only", default="", help="comma-separated operations (default: all)")
    args = ap.parse_args()
    p = Probe(args)
    p.setup()
    only = set(filter(None, args.only.split(",")))
    steps = [("export", lambda: [p.export(f, r) for f in ("lerobot", "robomimic") for r in (False, True)]),
             ("publish", p.publish), ("merge", p.merge), ("rethreshold", p.rethreshold),
             ("full-disk", p.full_disk), ("others", p.others)]
    for name, step in steps:
        if not only or name in only:
            t0 = time.monotonic()
            step()
            print(f"# {name}: {time.monotonic() - t0:.0f} s", file=sys.stderr)
    print(json.dumps(p.results, indent=1))
    bad = sum(r.get("bad", 0) for r in p.results.values())
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
