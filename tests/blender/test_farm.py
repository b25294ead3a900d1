"""End to end on a real Slurm: `lantern farm submit` of a test scene on a single-node cluster started
on loopback (slurm_cluster.py), the merged image against a one-machine render, and a deliberately
failing task that stops the merge, is named by `lantern farm wait`, and is rerun by the command it
prints. Needs root and Debian's slurmctld, slurmd, slurm-client and munge (scripts/setup.sh
installs them): without them the test FAILS, it does not skip. The cluster is stopped whatever
happens (context manager).
"""
import os
import re
import shlex
import subprocess

import numpy as np
import pytest

import bpy

import build_scenes
import render_utils
from slurm_cluster import SlurmCluster, missing_programs

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SAMPLES = 32
RESOLUTION = (40, 40)


def _build_dir():
    lib = os.environ.get("LANTERN_LIBRARY")
    assert lib, "LANTERN_LIBRARY must point at the build's liblantern.so (scripts/run_tests.sh sets it)"
    return os.path.dirname(os.path.abspath(lib))


def _run(cmd, env, timeout=600):
    p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
    return p.returncode, p.stdout + p.stderr


def _assert_same_render(merged_path, reference_path):
    """Every pass within float rounding (the bound test_merge.cpp derives): 1e-5 relative; Normal
    relative to 1; the Variance pass relative to mean^2 / samples (its pooled form cancels)."""
    merged, ref = render_utils.read_exr(merged_path), render_utils.read_exr(reference_path)
    assert sorted(merged) == sorted(ref)
    count = ref["SampleCount.X"]
    assert np.all(merged["SampleCount.X"] == SAMPLES) and np.all(count == SAMPLES)
    for name, r in ref.items():
        scale = np.abs(r).astype(np.float64)
        if name.startswith("Normal."):
            scale[:] = 1
        if name.startswith("Variance."):
            mean = ref[name.split(".")[1]].astype(np.float64)
            scale = np.maximum(scale, mean * mean / count)
        err = np.abs(merged[name].astype(np.float64) - r)
        assert np.all(err <= 1e-5 * scale), "%s differs: largest error %g" % (name, err.max())


@pytest.fixture(scope="module")
def farm_env(tmp_path_factory):
    missing = missing_programs()
    assert not missing, "Slurm/munge missing: %s; scripts/setup.sh installs them" % " ".join(missing)
    assert os.geteuid() == 0, "the Slurm end-to-end test needs root (CI runs as root)"
    work = tmp_path_factory.mktemp("farm")
    placeholder = build_scenes.reset_file()
    scene = build_scenes.build("cornell_area", resolution=RESOLUTION, samples=SAMPLES)
    scene.render.engine = "LANTERN"
    scene.lantern.integrator = "BIDIRECTIONAL"  # light-tracing splats go through the whole chain
    scene.lantern.samples = SAMPLES
    scene.lantern.seed = 5
    bpy.data.scenes.remove(placeholder)
    blend = str(work / "farm_scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend, copy=True)
    build = _build_dir()
    env = dict(os.environ, LANTERN_ADDON_DIR=os.path.join(REPO, "addon"),
               LANTERN_LIBRARY=os.path.join(build, "liblantern.so"))
    # The one-machine render: the whole sample range in one task, outside Slurm.
    reference = str(work / "reference.exr")
    code, out = _run(["blender", "-b", "--factory-startup", blend, "--python-exit-code", "1", "--python",
                      os.path.join(build, "lantern_task.py"), "--", "--offset", "0", "--samples", str(SAMPLES),
                      "--out", reference], env)
    assert code == 0, out
    with SlurmCluster() as cluster:
        env.update(SLURM_CONF=cluster.env["SLURM_CONF"], PATH=cluster.env["PATH"])
        yield {"blend": blend, "work": work, "env": env, "reference": reference,
               "lantern": os.path.join(build, "lantern")}


def test_four_task_split_merges_into_the_one_machine_render(farm_env):
    e = farm_env
    d = str(e["work"] / "job4")
    code, out = _run([e["lantern"], "farm", "submit", e["blend"], "--tasks", "4", "--samples", str(SAMPLES),
                      "--dir", d], e["env"])
    assert code == 0, out
    code, out = _run([e["lantern"], "farm", "wait", d, "--timeout", "300", "--poll", "0.5"], e["env"])
    assert code == 0, out
    assert "4 completed" in out and "merge" in out, out
    parts = sorted(os.listdir(os.path.join(d, "parts")))
    assert len(parts) == 4, parts
    _assert_same_render(os.path.join(d, "frame.exr"), e["reference"])
    # The CLI refuses a part given twice, writing nothing.
    part = os.path.join(d, "parts", parts[1])
    bad = os.path.join(d, "bad.exr")
    code, out = _run([e["lantern"], "merge", bad, part, part], e["env"])
    assert code == 1 and "sample ranges overlap" in out and not os.path.exists(bad), out
    # The task script's --part K/N (for farms that only number their tasks) renders the same samples
    # as Slurm task 1 did: [8, 16), bit for bit.
    assert parts[1] == "frame_s000008-000016.exr", parts
    again = str(e["work"] / "part_1_of_4.exr")
    code, out = _run(["blender", "-b", "--factory-startup", e["blend"], "--python-exit-code", "1", "--python",
                      os.path.join(os.path.dirname(e["lantern"]), "lantern_task.py"), "--",
                      "--samples", str(SAMPLES), "--part", "1/4", "--out", again], e["env"])
    assert code == 0, out
    a, b = render_utils.read_exr(again), render_utils.read_exr(part)
    assert all(np.array_equal(a[k], b[k]) for k in b), "--part 1/4 differs from task 1's part"


def test_failed_task_stops_its_merges_and_its_resubmission_completes_them(farm_env):
    """Two frames of 4 tasks, merged in groups of 2 (a merge tree): task 4 (frame 2) fails."""
    e = farm_env
    d = str(e["work"] / "job_fail")
    os.makedirs(os.path.join(d, "parts"))
    # Task 4 is frame 2, samples [0, 8): its part path taken by a directory, so the task's write
    # (a rename onto that path) really fails.
    blocker = os.path.join(d, "parts", "frame_0002_s000000-000008.exr")
    os.makedirs(blocker)
    code, out = _run([e["lantern"], "farm", "submit", e["blend"], "--tasks", "4", "--samples", str(SAMPLES),
                      "--frames", "1-2", "--merge-group", "2", "--dir", d], e["env"])
    assert code == 0 and "6 merge job(s)" in out, out
    code, out = _run([e["lantern"], "farm", "wait", d, "--timeout", "300", "--poll", "0.5"], e["env"])
    assert code == 1, out
    assert re.search(r"FAILED task 4 \(frame 2, samples \[0, 8\)\)", out), out
    assert "FAILED task" not in out.replace("FAILED task 4 ", ""), out  # only that one
    assert "the merge of frame_0002 did not run" in out, out
    # Frame 1 does not wait for frame 2: merged; frame 2's group 1 too, its group 0 and final not.
    assert os.path.exists(os.path.join(d, "frame_0001.exr"))
    assert os.path.exists(os.path.join(d, "parts", "frame_0002_group1.exr"))
    assert not os.path.exists(os.path.join(d, "frame_0002.exr"))
    code, status = _run([e["lantern"], "farm", "status", d], e["env"])
    assert code == 1 and "FAILED task 4" in status, status
    assert re.search(r"6 merges: .*2 cancelled", status), status
    # The printed command reruns just task 4, then frame 2's group 0 and final merges.
    resubmit = [line.strip() for line in out.splitlines() if " farm resubmit " in line]
    assert resubmit and resubmit[0].endswith("--tasks 4"), out
    os.rmdir(blocker)
    code, out = _run(shlex.split(resubmit[0]), e["env"])
    assert code == 0 and "resubmitted task(s) 4" in out and "2 merge job(s)" in out, out
    code, out = _run([e["lantern"], "farm", "wait", d, "--timeout", "300", "--poll", "0.5"], e["env"])
    assert code == 0, out
    # The scene does not move: both frames are the reference image.
    _assert_same_render(os.path.join(d, "frame_0001.exr"), e["reference"])
    _assert_same_render(os.path.join(d, "frame_0002.exr"), e["reference"])
