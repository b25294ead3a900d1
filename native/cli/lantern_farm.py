"""`lantern farm`: sample- and frame-split Lantern renders on a Slurm cluster (stdlib only; run by the
`lantern` binary, which sets LANTERN_CLI to itself).

    lantern farm submit SCENE.blend --tasks N --samples S [--frames A-B] [--partition P]
                        [--dir DIR] [--blender PATH] [-- extra sbatch options]
    lantern farm status DIR
    lantern farm wait DIR [--timeout SECONDS]
    lantern farm resubmit DIR --tasks I[,J...]

submit writes DIR (default: SCENE_farm beside the .blend): task.sh, an sbatch job array with one
`blender -b` task per (frame, sample range); merge.sh, one `lantern merge` per frame, submitted with
--dependency=afterok on the array (and --kill-on-invalid-dep=yes: a failed task cancels the merge);
job.json, what was submitted. Parts go to DIR/parts, logs to DIR/logs, merged frames to
DIR/frame_FFFF.exr. status/wait name failed tasks with their log and the command that resubmits just
them and then the merge.
"""
import argparse
import json
import os
import shlex
import subprocess
import sys
import time

ACTIVE = {"PENDING", "RUNNING", "CONFIGURING", "COMPLETING", "SUSPENDED", "REQUEUED", "RESIZING",
          "REQUEUE_HOLD", "REQUEUE_FED", "SIGNALING", "STAGE_OUT"}
HERE = os.path.dirname(os.path.abspath(__file__))


def fail(msg):
    print("lantern farm: " + msg, file=sys.stderr)
    sys.exit(1)


def run(cmd, env=None):
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    except FileNotFoundError:
        fail("%s not found: is this a Slurm submit host (slurm-client installed, on PATH)?" % cmd[0])
    return p


def sbatch(args):
    # Jobs get the environment `lantern farm` was run in (sbatch exports it), with the user's PATH.
    env = dict(os.environ)
    env["PATH"] = os.environ.get("LANTERN_FARM_PATH", env.get("PATH", ""))
    p = run(["sbatch", "--parsable"] + args, env)
    if p.returncode != 0:
        fail("sbatch %s failed: %s" % (" ".join(map(shlex.quote, args)), p.stderr.strip()))
    return p.stdout.strip().split(";")[0]


def parse_frames(text):
    try:
        a, _, b = text.partition("-")
        a, b = int(a), int(b or a)
    except ValueError:
        fail("--frames wants A-B or A, got %r" % text)
    if b < a:
        fail("--frames %s: the last frame is before the first" % text)
    return a, b


# ---- submit ---------------------------------------------------------------------------------------

def split(samples, tasks):
    """Task k of `tasks` renders samples [k S / N, (k + 1) S / N): every range non-empty when N <= S."""
    return [(k * samples // tasks, (k + 1) * samples // tasks - k * samples // tasks) for k in range(tasks)]


def slurm_options(job):
    return (["--partition", job["partition"]] if job["partition"] else []) + job["sbatch_options"]


def resubmit_commands(job, indices):
    """The sbatch commands that rerun just these tasks, then the merge after them."""
    d = job["dir"]
    opts = " ".join(map(shlex.quote, slurm_options(job)))
    opts = (opts + " ") if opts else ""
    array = ",".join(str(i) for i in indices)
    return ("id=$(sbatch --parsable --array=%s %s%s) && sbatch --dependency=afterok:$id "
            "--kill-on-invalid-dep=yes %s%s" % (array, opts, shlex.quote(os.path.join(d, "task.sh")),
                                                opts, shlex.quote(os.path.join(d, "merge.sh"))))


def submit(args, extra):
    blend = os.path.abspath(args.scene)
    if not os.path.isfile(blend):
        fail("%s does not exist" % blend)
    if args.tasks < 1 or args.samples < 1:
        fail("--tasks and --samples must be at least 1")
    if args.tasks > args.samples:
        fail("--tasks %d exceeds --samples %d: every task needs at least one sample"
             % (args.tasks, args.samples))
    first, last = parse_frames(args.frames) if args.frames else (None, None)
    d = os.path.abspath(args.dir or os.path.splitext(blend)[0] + "_farm")
    if os.path.exists(os.path.join(d, "job.json")):
        fail("%s already holds a farm job (job.json): choose another --dir or remove it" % d)
    os.makedirs(os.path.join(d, "parts"), exist_ok=True)
    os.makedirs(os.path.join(d, "logs"), exist_ok=True)
    lantern = os.environ.get("LANTERN_CLI") or os.path.join(HERE, "lantern")
    task_py = os.path.join(HERE, "lantern_task.py")
    blender = [args.blender, "-b"]
    if os.environ.get("LANTERN_ADDON_DIR"):
        blender.append("--factory-startup")  # the add-on comes from LANTERN_ADDON_DIR, not the user's
    frames = [None] if first is None else list(range(first, last + 1))

    tasks, outputs = [], {}
    for frame in frames:
        name = "frame" if frame is None else "frame_%04d" % frame
        parts = []
        for k, (offset, count) in enumerate(split(args.samples, args.tasks)):
            part = os.path.join(d, "parts", "%s_s%06d-%06d.exr" % (name, offset, offset + count))
            cmd = blender + [blend, "--python-exit-code", "1", "--python", task_py, "--",
                             "--offset", str(offset), "--samples", str(count), "--out", part]
            if frame is not None:
                cmd += ["--frame", str(frame)]
            tasks.append({"index": len(tasks), "frame": frame, "offset": offset, "samples": count,
                          "part": part, "command": cmd})
            parts.append(part)
        outputs[name] = {"out": os.path.join(d, name + ".exr"), "parts": parts}

    lines = ["#!/bin/bash", "# Lantern farm task: one (frame, sample range) per array index.",
             "set -euo pipefail", 'case "$SLURM_ARRAY_TASK_ID" in']
    for t in tasks:
        lines.append("  %d) exec %s ;;" % (t["index"], " ".join(map(shlex.quote, t["command"]))))
    lines += ['  *) echo "lantern farm: no task $SLURM_ARRAY_TASK_ID" >&2; exit 1 ;;', "esac", ""]
    with open(os.path.join(d, "task.sh"), "w") as f:
        f.write("\n".join(lines))
    lines = ["#!/bin/bash", "# Lantern farm merge: runs after every task succeeded.", "set -euo pipefail"]
    for o in outputs.values():
        lines.append(" ".join(map(shlex.quote, [lantern, "merge", o["out"]] + o["parts"])))
    with open(os.path.join(d, "merge.sh"), "w") as f:
        f.write("\n".join(lines) + "\n")

    job = {"dir": d, "blend": blend, "samples": args.samples, "tasks_per_frame": args.tasks,
           "frames": frames, "partition": args.partition, "sbatch_options": extra,
           "tasks": tasks, "outputs": outputs}
    opts = slurm_options(job)
    array = sbatch(["--array=0-%d" % (len(tasks) - 1), "--job-name=lantern-task",
                    "--output=" + os.path.join(d, "logs", "task_%a.log")] + opts + [os.path.join(d, "task.sh")])
    try:
        merge = sbatch(["--dependency=afterok:" + array, "--kill-on-invalid-dep=yes", "--job-name=lantern-merge",
                        "--output=" + os.path.join(d, "logs", "merge.log")] + opts + [os.path.join(d, "merge.sh")])
    except SystemExit:
        run(["scancel", array])  # no tasks without their merge
        raise
    job["submissions"] = [{"array": array, "tasks": [t["index"] for t in tasks], "merge": merge}]
    save(job)
    print("lantern farm: submitted %d tasks (job %s, %d frame(s) x %d sample ranges) and the merge (job %s)"
          % (len(tasks), array, len(frames), args.tasks, merge))
    print("lantern farm: follow with: lantern farm status %s   (or: lantern farm wait %s)" % (d, d))


def save(job):
    tmp = os.path.join(job["dir"], "job.json.tmp")
    with open(tmp, "w") as f:
        json.dump(job, f, indent=1)
    os.replace(tmp, os.path.join(job["dir"], "job.json"))


def load(d):
    path = os.path.join(os.path.abspath(d), "job.json")
    if not os.path.isfile(path):
        fail("%s is not a farm job directory (no job.json)" % d)
    with open(path) as f:
        return json.load(f)


# ---- status ---------------------------------------------------------------------------------------

def job_records(job_id):
    """{array task index or None: (state, exit code, reason)} from scontrol (kept ~10 min after the end)."""
    p = run(["scontrol", "-o", "show", "job", job_id])
    records = {}
    if p.returncode != 0:
        return records
    for line in p.stdout.splitlines():
        f = dict(kv.split("=", 1) for kv in line.split() if "=" in kv)
        state = f.get("JobState", "UNKNOWN")
        task = f.get("ArrayTaskId")
        info = (state, f.get("ExitCode", ""), f.get("Reason", ""))
        if task is None:
            records[None] = info
            continue
        # Pending tasks are grouped ("3-7", "3,5", "3-9%2"): expand them.
        for piece in task.split("%")[0].split(","):
            a, _, b = piece.partition("-")
            for i in range(int(a), int(b or a) + 1):
                records[i] = info
    return records


def collect(job):
    """Per task: (state, detail); the merge's (state, detail) of the latest submission."""
    latest = {}
    for sub in job["submissions"]:
        for i in sub["tasks"]:
            latest[i] = sub["array"]
    cache = {}
    states = {}
    for t in job["tasks"]:
        i = t["index"]
        array = latest[i]
        if array not in cache:
            cache[array] = job_records(array)
        rec = cache[array].get(i)
        if rec is None:  # the record expired (or never existed): the part file tells
            states[i] = ("COMPLETED", "") if os.path.isfile(t["part"]) else ("UNKNOWN", "no Slurm record, no part")
        else:
            states[i] = (rec[0], "exit code %s, %s" % (rec[1], rec[2]))
    merge_id = job["submissions"][-1]["merge"]
    rec = job_records(merge_id).get(None)
    if rec is None:
        done = all(os.path.isfile(o["out"]) for o in job["outputs"].values())
        merge = ("COMPLETED", "") if done else ("UNKNOWN", "no Slurm record, no output")
    else:
        merge = (rec[0], "exit code %s, %s" % (rec[1], rec[2]))
    return states, merge


def describe(t):
    frame = "" if t["frame"] is None else "frame %d, " % t["frame"]
    return "task %d (%ssamples [%d, %d))" % (t["index"], frame, t["offset"], t["offset"] + t["samples"])


def report(job):
    """Prints progress; returns (finished, succeeded, something failed)."""
    states, merge = collect(job)
    counts = {}
    for s, _ in states.values():
        counts[s] = counts.get(s, 0) + 1
    summary = ", ".join("%d %s" % (n, s.lower()) for s, n in sorted(counts.items()))
    print("lantern farm: %s: %d tasks: %s; merge (job %s): %s" % (
        job["dir"], len(states), summary, job["submissions"][-1]["merge"], merge[0].lower()))
    failed = [t for t in job["tasks"] if states[t["index"]][0] not in ACTIVE | {"COMPLETED"}]
    active = any(s in ACTIVE for s, _ in states.values()) or merge[0] in ACTIVE
    for t in failed:
        log = os.path.join(job["dir"], "logs", "task_%d.log" % t["index"])
        print("lantern farm: FAILED %s: %s (%s); log: %s" % (describe(t), states[t["index"]][0],
                                                          states[t["index"]][1], log))
    if failed:
        idx = [t["index"] for t in failed]
        print("lantern farm: the merge did not run%s. Fix the cause, then resubmit just the failed "
              "task(s) and the merge with:" % ("" if not active else " (and will not)"))
        print("  %s resubmit %s --tasks %s" % (os.environ.get("LANTERN_CLI", "lantern") + " farm",
                                             shlex.quote(job["dir"]), ",".join(map(str, idx))))
        print("or, with Slurm alone:")
        print("  " + resubmit_commands(job, idx))
    if merge[0] == "COMPLETED":
        for o in job["outputs"].values():
            print("lantern farm: merged: %s" % o["out"])
    elif not failed and not active:
        print("lantern farm: the merge ended %s (%s); log: %s" % (merge[0], merge[1],
                                                               os.path.join(job["dir"], "logs", "merge.log")))
    merge_failed = not active and merge[0] != "COMPLETED"
    return not active, merge[0] == "COMPLETED" and not failed, bool(failed) or merge_failed


def status(args):
    """Exit code 0 while all is well (running or merged), 1 once a task or the merge failed."""
    _, _, failed = report(load(args.dir))
    sys.exit(1 if failed else 0)


def wait(args):
    job = load(args.dir)
    start = time.monotonic()
    while True:
        states, merge = collect(job)
        busy = any(s in ACTIVE for s, _ in states.values()) or merge[0] in ACTIVE
        if not busy:
            break
        if args.timeout and time.monotonic() - start > args.timeout:
            report(job)
            print("lantern farm: still running after %g s" % args.timeout)
            sys.exit(2)
        time.sleep(args.poll)
    _, ok, _ = report(job)
    sys.exit(0 if ok else 1)


def resubmit(args):
    job = load(args.dir)
    try:
        idx = sorted({int(x) for x in args.tasks.split(",")})
    except ValueError:
        fail("--tasks wants task numbers separated by commas, got %r" % args.tasks)
    known = {t["index"] for t in job["tasks"]}
    bad = [i for i in idx if i not in known]
    if bad:
        fail("no task %s in this job (tasks 0-%d)" % (bad, len(known) - 1))
    d = job["dir"]
    opts = slurm_options(job)
    array = sbatch(["--array=" + ",".join(map(str, idx)), "--job-name=lantern-task",
                    "--output=" + os.path.join(d, "logs", "task_%a.log")] + opts + [os.path.join(d, "task.sh")])
    merge = sbatch(["--dependency=afterok:" + array, "--kill-on-invalid-dep=yes", "--job-name=lantern-merge",
                    "--output=" + os.path.join(d, "logs", "merge.log")] + opts + [os.path.join(d, "merge.sh")])
    job["submissions"].append({"array": array, "tasks": idx, "merge": merge})
    save(job)
    print("lantern farm: resubmitted task(s) %s (job %s) and the merge (job %s)"
          % (",".join(map(str, idx)), array, merge))


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    p = argparse.ArgumentParser(prog="lantern farm", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("submit", help="submit a sample-split (and frame-split) render and its merge")
    s.add_argument("scene", help="the .blend file (on storage every node sees)")
    s.add_argument("--tasks", type=int, required=True, help="sample ranges per frame")
    s.add_argument("--samples", type=int, required=True, help="samples per pixel of the whole render")
    s.add_argument("--frames", help="A-B: render frames A to B (default: the current frame)")
    s.add_argument("--partition", help="Slurm partition")
    s.add_argument("--dir", help="job directory (default: SCENE_farm beside the .blend)")
    s.add_argument("--blender", default="blender", help="Blender on the nodes (default: blender)")
    for name, helptext in (("status", "print progress and failures"), ("wait", "wait for the end, then status")):
        q = sub.add_parser(name, help=helptext)
        q.add_argument("dir", help="the job directory")
        if name == "wait":
            q.add_argument("--timeout", type=float, default=0, help="give up after this many seconds (exit 2)")
            q.add_argument("--poll", type=float, default=2.0, help="seconds between checks")
    r = sub.add_parser("resubmit", help="rerun some tasks, then the merge")
    r.add_argument("dir", help="the job directory")
    r.add_argument("--tasks", required=True, help="task numbers, e.g. 2 or 2,5")
    args = p.parse_args(argv)
    if extra and args.command != "submit":
        fail("extra sbatch options (after --) only go with submit")
    if args.command == "submit":
        submit(args, extra)
    else:
        {"status": status, "wait": wait, "resubmit": resubmit}[args.command](args)


if __name__ == "__main__":
    main()
