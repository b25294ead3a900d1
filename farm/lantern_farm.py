"""`lantern farm`: sample- and frame-split Lantern renders on a Slurm cluster (stdlib only; run by the
`lantern` binary, which sets LANTERN_CLI to itself).

    lantern farm submit SCENE.blend --tasks N --samples S [--frames A-B] [--partition P]
                        [--dir DIR] [--blender PATH] [--merge-group G] [-- extra sbatch options]
    lantern farm status DIR
    lantern farm wait DIR [--timeout SECONDS]
    lantern farm resubmit DIR [--tasks I[,J...]]

submit writes DIR (default: SCENE_farm beside the .blend): task.sh, an sbatch job array with one
`blender -b` task per (frame, sample range); merges/*.sh, `lantern merge` jobs per frame (one, or
for more than 16 tasks a tree: groups of about sqrt(N) parts, then their results), each submitted
with --dependency=afterok on exactly its inputs and --kill-on-invalid-dep=yes, so a failed task
cancels the merges after it and nothing else; job.json, what was submitted. Parts go to DIR/parts,
logs to DIR/logs, merged frames to DIR/frame_FFFF.exr (DIR/frame.exr without --frames).
status/wait name failed tasks with their log and the command that resubmits just them and then the
merges after them.
"""
import argparse
import hashlib
import json
import math
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


def merge_layout(frame_name, parts, group, d):
    """The merge jobs of one frame: with `group` < len(parts), a merge per group of `group` parts
    (they run in parallel) and a final merge of their results (merges of merges are exact); else
    one merge of every part. Inputs are ("task", index) or ("merge", name)."""
    final = {"name": frame_name, "frame": frame_name, "final": True, "out": os.path.join(d, frame_name + ".exr")}
    if group >= len(parts):
        final["inputs"] = [("task", i) for i in parts]
        return [final]
    merges = []
    for j in range(0, len(parts), group):
        name = "%s_group%d" % (frame_name, j // group)
        merges.append({"name": name, "frame": frame_name, "final": False,
                       "out": os.path.join(d, "parts", name + ".exr"),
                       "inputs": [("task", i) for i in parts[j:j + group]]})
    final["inputs"] = [("merge", m["name"]) for m in merges]
    return merges + [final]


def plan(job, rerun_tasks):
    """The merges to (re)submit after tasks `rerun_tasks`: those whose output is missing (groups
    before finals), each with the inputs it must wait for: rerun tasks and replanned merges."""
    planned, out = set(), []
    for m in job["merges"]:
        if os.path.isfile(m["out"]):
            continue
        deps = [(k, r) for k, r in m["inputs"] if (k == "task" and r in rerun_tasks) or (k == "merge" and r in planned)]
        planned.add(m["name"])
        out.append((m, deps))
    return out


def merge_script(job, m):
    return os.path.join(job["dir"], "merges", m["name"] + ".sh")


def submit_jobs(job, tasks):
    """sbatch: the array of `tasks`, then the merges that wait for them; records the submission."""
    d, opts = job["dir"], slurm_options(job)
    array = sbatch(["--array=" + ",".join(map(str, tasks)), "--job-name=lantern-task",
                    "--output=" + os.path.join(d, "logs", "task_%a.log")] + opts + [os.path.join(d, "task.sh")])
    ids = {}
    try:
        for m, deps in plan(job, set(tasks)):
            dep = ["%s_%d" % (array, r) if k == "task" else ids[r] for k, r in deps]
            after = ["--dependency=afterok:" + ":".join(dep), "--kill-on-invalid-dep=yes"] if dep else []
            ids[m["name"]] = sbatch(after + ["--job-name=lantern-merge",
                                             "--output=" + os.path.join(d, "logs", "merge_%s.log" % m["name"])]
                                    + opts + [merge_script(job, m)])
    except SystemExit:
        run(["scancel", array] + list(ids.values()))  # nothing half-submitted
        raise
    job["submissions"].append({"array": array, "tasks": sorted(tasks), "merges": ids})
    save(job)
    return array, ids


def resubmit_commands(job, tasks):
    """The same as `lantern farm resubmit --tasks ...`, with sbatch alone."""
    opts = " ".join(map(shlex.quote, slurm_options(job)))
    opts = (opts + " ") if opts else ""
    logs = os.path.join(job["dir"], "logs")
    lines = ["id=$(sbatch --parsable --array=%s --job-name=lantern-task %s %s%s)" % (
        ",".join(map(str, tasks)), shlex.quote("--output=" + os.path.join(logs, "task_%a.log")), opts,
        shlex.quote(os.path.join(job["dir"], "task.sh")))]
    for m, deps in plan(job, set(tasks)):
        dep = ["${id}_%d" % r if k == "task" else "$m_" + r for k, r in deps]
        lines.append("m_%s=$(sbatch --parsable %s--job-name=lantern-merge %s %s%s)" % (
            m["name"], ("--dependency=afterok:%s --kill-on-invalid-dep=yes " % ":".join(dep)) if dep else "",
            shlex.quote("--output=" + os.path.join(logs, "merge_%s.log" % m["name"])), opts,
            shlex.quote(merge_script(job, m))))
    return " && \\\n    ".join(lines)


def submit(args, extra):
    blend = os.path.abspath(args.scene)
    if not os.path.isfile(blend):
        fail("%s does not exist" % blend)
    if args.tasks < 1 or args.samples < 1:
        fail("--tasks and --samples must be at least 1")
    if args.tasks > args.samples:
        fail("--tasks %d exceeds --samples %d: every task needs at least one sample"
             % (args.tasks, args.samples))
    if args.merge_group is not None and args.merge_group < 2:
        fail("--merge-group must be at least 2")
    first, last = parse_frames(args.frames) if args.frames else (None, None)
    d = os.path.abspath(args.dir or os.path.splitext(blend)[0] + "_farm")
    if os.path.exists(os.path.join(d, "job.json")):
        fail("%s already holds a farm job (job.json): choose another --dir or remove it" % d)
    for sub in ("parts", "logs", "merges"):
        os.makedirs(os.path.join(d, sub), exist_ok=True)
    lantern = os.environ.get("LANTERN_CLI") or os.path.join(HERE, "lantern")
    task_py = os.path.join(HERE, "lantern_task.py")
    blender = [args.blender, "-b"]
    if os.environ.get("LANTERN_ADDON_DIR"):
        blender.append("--factory-startup")  # the add-on comes from LANTERN_ADDON_DIR, not the user's
    frames = [None] if first is None else list(range(first, last + 1))
    # The scene's identity in every part (the merge compares it): hashed once here, not per task.
    digest = hashlib.sha256()
    with open(blend, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    scene_id = digest.hexdigest()[:20]
    # Parts per merge job: one merge reads every part (about 1-3 s per 1080p part, bench/), so past
    # 16 tasks per frame the parts are merged in groups of about sqrt(N) on separate nodes.
    group = args.merge_group or (args.tasks if args.tasks <= 16 else math.ceil(math.sqrt(args.tasks)))

    tasks, merges = [], []
    for frame in frames:
        name = "frame" if frame is None else "frame_%04d" % frame
        indices = []
        for offset, count in split(args.samples, args.tasks):
            part = os.path.join(d, "parts", "%s_s%06d-%06d.exr" % (name, offset, offset + count))
            cmd = blender + [blend, "--python-exit-code", "1", "--python", task_py, "--",
                             "--offset", str(offset), "--samples", str(count), "--scene-id", scene_id, "--out", part]
            if frame is not None:
                cmd += ["--frame", str(frame)]
            indices.append(len(tasks))
            tasks.append({"index": len(tasks), "frame": frame, "offset": offset, "samples": count,
                          "part": part, "command": cmd})
        merges += merge_layout(name, indices, group, d)

    lines = ["#!/bin/bash", "# Lantern farm task: one (frame, sample range) per array index.",
             "set -euo pipefail", 'case "$SLURM_ARRAY_TASK_ID" in']
    for t in tasks:
        lines.append("  %d) exec %s ;;" % (t["index"], " ".join(map(shlex.quote, t["command"]))))
    lines += ['  *) echo "lantern farm: no task $SLURM_ARRAY_TASK_ID" >&2; exit 1 ;;', "esac", ""]
    with open(os.path.join(d, "task.sh"), "w") as f:
        f.write("\n".join(lines))
    job = {"dir": d, "blend": blend, "samples": args.samples, "tasks_per_frame": args.tasks,
           "frames": frames, "partition": args.partition, "sbatch_options": extra, "merge_group": group,
           "tasks": tasks, "merges": merges, "submissions": []}
    by_name = {m["name"]: m for m in merges}
    for m in merges:
        inputs = [tasks[r]["part"] if k == "task" else by_name[r]["out"] for k, r in m["inputs"]]
        with open(merge_script(job, m), "w") as f:
            f.write("#!/bin/bash\n# Lantern farm merge: runs once its inputs exist.\nset -euo pipefail\nexec %s\n"
                    % " ".join(map(shlex.quote, [lantern, "merge", m["out"]] + inputs)))
    array, ids = submit_jobs(job, [t["index"] for t in tasks])
    print("lantern farm: submitted %d tasks (job %s, %d frame(s) x %d sample ranges) and %d merge job(s) (%s)"
          % (len(tasks), array, len(frames), args.tasks, len(ids), " ".join(ids.values())))
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
    """Per task and per merge (by name): (state, detail) of its latest submission."""
    latest_task, latest_merge = {}, {}
    for sub in job["submissions"]:
        for i in sub["tasks"]:
            latest_task[i] = sub["array"]
        latest_merge.update(sub["merges"])
    cache = {}

    def record(job_id, index, path):
        if job_id not in cache:
            cache[job_id] = job_records(job_id)
        rec = cache[job_id].get(index)
        if rec is None:  # the record expired (or never existed): the file tells
            return ("COMPLETED", "") if os.path.isfile(path) else ("UNKNOWN", "no Slurm record, no output")
        return rec[0], "exit code %s, %s" % (rec[1], rec[2])

    tasks = {t["index"]: record(latest_task[t["index"]], t["index"], t["part"]) for t in job["tasks"]}
    merges = {}
    for m in job["merges"]:
        if m["name"] in latest_merge:
            merges[m["name"]] = record(latest_merge[m["name"]], None, m["out"])
        else:  # done before the latest resubmission
            merges[m["name"]] = ("COMPLETED", "") if os.path.isfile(m["out"]) else ("UNKNOWN", "never submitted")
    return tasks, merges


def describe(t):
    frame = "" if t["frame"] is None else "frame %d, " % t["frame"]
    return "task %d (%ssamples [%d, %d))" % (t["index"], frame, t["offset"], t["offset"] + t["samples"])


def counted(states):
    counts = {}
    for s, _ in states.values():
        counts[s] = counts.get(s, 0) + 1
    return ", ".join("%d %s" % (n, s.lower()) for s, n in sorted(counts.items()))


def report(job):
    """Prints progress; returns (finished, every frame merged, something failed)."""
    tasks, merges = collect(job)
    print("lantern farm: %s: %d tasks: %s; %d merges: %s" % (job["dir"], len(tasks), counted(tasks),
                                                             len(merges), counted(merges)))
    done = ACTIVE | {"COMPLETED"}
    failed = [t for t in job["tasks"] if tasks[t["index"]][0] not in done]
    # A merge cancelled because an input task failed is that task's failure, not the merge's.
    blocked = set()
    for m in job["merges"]:
        if any((k == "task" and tasks[r][0] not in done) or (k == "merge" and r in blocked) for k, r in m["inputs"]):
            blocked.add(m["name"])
    failed_merges = [m for m in job["merges"] if merges[m["name"]][0] not in done and m["name"] not in blocked]
    active = any(s in ACTIVE for s, _ in list(tasks.values()) + list(merges.values()))
    for t in failed:
        log = os.path.join(job["dir"], "logs", "task_%d.log" % t["index"])
        print("lantern farm: FAILED %s: %s (%s); log: %s" % (describe(t), tasks[t["index"]][0],
                                                          tasks[t["index"]][1], log))
    for m in failed_merges:
        log = os.path.join(job["dir"], "logs", "merge_%s.log" % m["name"])
        print("lantern farm: FAILED merge %s: %s (%s); log: %s" % (m["name"], merges[m["name"]][0],
                                                                 merges[m["name"]][1], log))
    if failed or failed_merges:
        idx = [t["index"] for t in failed]
        if failed:
            print("lantern farm: the merge of %s did not run. Fix the cause, then resubmit just the failed "
                  "task(s) and the merges after them with:" % ", ".join(
                      sorted({m["frame"] for m in job["merges"] if m["final"] and m["name"] in blocked})))
        else:
            print("lantern farm: fix the cause, then resubmit the merges with:")
        print("  %s farm resubmit %s%s" % (os.environ.get("LANTERN_CLI", "lantern"), shlex.quote(job["dir"]),
                                          " --tasks " + ",".join(map(str, idx)) if idx else ""))
        if idx:
            print("or, with Slurm alone:")
            print("  " + resubmit_commands(job, idx))
    ok = all(merges[m["name"]][0] == "COMPLETED" and os.path.isfile(m["out"]) for m in job["merges"] if m["final"])
    if ok:
        for m in job["merges"]:
            if m["final"]:
                print("lantern farm: merged: %s" % m["out"])
    return not active, ok and not failed, bool(failed or failed_merges)


def status(args):
    """Exit code 0 while all is well (running or merged), 1 once a task or a merge failed."""
    _, _, failed = report(load(args.dir))
    sys.exit(1 if failed else 0)


def wait(args):
    job = load(args.dir)
    start = time.monotonic()
    while True:
        tasks, merges = collect(job)
        if not any(s in ACTIVE for s, _ in list(tasks.values()) + list(merges.values())):
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
        idx = sorted({int(x) for x in args.tasks.split(",")}) if args.tasks else []
    except ValueError:
        fail("--tasks wants task numbers separated by commas, got %r" % args.tasks)
    known = {t["index"] for t in job["tasks"]}
    bad = [i for i in idx if i not in known]
    if bad:
        fail("no task %s in this job (tasks 0-%d)" % (bad, len(known) - 1))
    tasks, merges = collect(job)
    busy = [str(i) for i in idx if tasks[i][0] in ACTIVE]
    if busy:
        fail("task(s) %s are still queued or running" % ",".join(busy))
    # Merges still waiting from an earlier submission are replaced by the new ones.
    latest = {}
    for sub in job["submissions"]:
        latest.update(sub["merges"])
    stale = [latest[n] for n, (s, _) in merges.items() if s in ACTIVE and n in latest]
    if stale:
        run(["scancel"] + stale)
    if not idx and not plan(job, set()):
        fail("nothing to resubmit: every merge output exists")
    if idx:
        array, ids = submit_jobs(job, idx)
    else:
        array, ids = None, {}
        d, opts = job["dir"], slurm_options(job)
        for m, deps in plan(job, set()):
            dep = [ids[r] for k, r in deps]
            after = ["--dependency=afterok:" + ":".join(dep), "--kill-on-invalid-dep=yes"] if dep else []
            ids[m["name"]] = sbatch(after + ["--job-name=lantern-merge",
                                             "--output=" + os.path.join(d, "logs", "merge_%s.log" % m["name"])]
                                    + opts + [merge_script(job, m)])
        job["submissions"].append({"array": None, "tasks": [], "merges": ids})
        save(job)
    print("lantern farm: resubmitted task(s) %s (job %s) and %d merge job(s) (%s)"
          % (",".join(map(str, idx)) or "none", array, len(ids), " ".join(ids.values())))


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
    s.add_argument("--merge-group", type=int, help="parts per merge job (default: all up to 16 tasks per "
                                                  "frame, else about sqrt(tasks), merged again at the end)")
    for name, helptext in (("status", "print progress and failures"), ("wait", "wait for the end, then status")):
        q = sub.add_parser(name, help=helptext)
        q.add_argument("dir", help="the job directory")
        if name == "wait":
            q.add_argument("--timeout", type=float, default=0, help="give up after this many seconds (exit 2)")
            q.add_argument("--poll", type=float, default=2.0, help="seconds between checks")
    r = sub.add_parser("resubmit", help="rerun some tasks, then the merge")
    r.add_argument("dir", help="the job directory")
    r.add_argument("--tasks", help="task numbers, e.g. 2 or 2,5 (none: only the merges whose output is missing)")
    args = p.parse_args(argv)
    if extra and args.command != "submit":
        fail("extra sbatch options (after --) only go with submit")
    if args.command == "submit":
        submit(args, extra)
    else:
        {"status": status, "wait": wait, "resubmit": resubmit}[args.command](args)


if __name__ == "__main__":
    main()
