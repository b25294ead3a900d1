"""A throwaway single-node Slurm cluster on loopback (Debian's slurmctld, slurmd, munge; no systemd),
everything under one temporary directory: see /work/shared/notes/slurm-single-node.md for the facts
behind each setting. Used as a context manager; stop() always runs, also after a failure.

    with SlurmCluster() as cluster:
        subprocess.run(["sbatch", ...], env=cluster.env)
"""
import os
import shutil
import socket
import subprocess
import tempfile
import time

DAEMONS = ("munged", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol", "scancel")


def missing_programs():
    """Programs the cluster needs that are not installed (scripts/setup.sh installs them)."""
    path = os.environ.get("PATH", "") + ":/usr/sbin:/sbin"
    return [p for p in DAEMONS if shutil.which(p, path=path) is None]


def _memory_mb():
    with open("/proc/meminfo") as f:
        for line in f:
            if line.startswith("MemTotal:"):
                return int(line.split()[1]) // 1024
    return 1024


def _alive(pid):
    """A stopped daemon lingers as a zombie for a while: only a live, non-zombie process counts."""
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith("State:"):
                    return "Z" not in line.split()[1]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return False


class SlurmCluster:
    def __init__(self, cpus=2):
        self.cpus = cpus
        self.dir = None
        self.env = None
        self.pidfiles = []

    def __enter__(self):
        try:
            self.start()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, *exc):
        self.stop()

    def _path(self, *parts):
        return os.path.join(self.dir, *parts)

    def start(self):
        missing = missing_programs()
        if missing:
            raise RuntimeError("Slurm/munge programs missing: %s (scripts/setup.sh installs slurmctld "
                               "slurmd slurm-client munge)" % " ".join(missing))
        if os.geteuid() != 0:
            raise RuntimeError("a test Slurm cluster needs root (SlurmUser=root)")
        self.dir = tempfile.mkdtemp(prefix="lantern_slurm_")
        os.chmod(self.dir, 0o755)
        for sub in ("munge_key", "munge_run", "state", "spool", "log"):
            os.makedirs(self._path(sub))
        os.chmod(self._path("munge_key"), 0o700)
        os.chmod(self._path("munge_run"), 0o755)
        key = self._path("munge_key", "munge.key")
        with open(key, "wb") as f:
            f.write(os.urandom(1024))
        os.chmod(key, 0o400)
        sock = self._path("munge_run", "munge.socket.2")
        munged = shutil.which("munged", path=os.environ.get("PATH", "") + ":/usr/sbin")
        self.pidfiles.append(self._path("munge_run", "munged.pid"))
        subprocess.run([munged, "--force", "--socket=" + sock, "--key-file=" + key,
                        "--pid-file=" + self.pidfiles[-1], "--log-file=" + self._path("log", "munged.log"),
                        "--seed-file=" + self._path("munge_key", "munged.seed")], check=True)

        host = socket.gethostname().split(".")[0]
        conf = self._path("slurm.conf")
        with open(conf, "w") as f:
            f.write("\n".join([
                "ClusterName=lantern-test",
                "SlurmctldHost=%s(127.0.0.1)" % host,
                "CommunicationParameters=NoInAddrAny,NoCtldInAddrAny",
                "SlurmUser=root", "SlurmdUser=root",
                "AuthType=auth/munge", "CredType=cred/munge", "AuthInfo=socket=" + sock,
                "ProctrackType=proctrack/linuxproc", "TaskPlugin=task/none",
                "JobAcctGatherType=jobacct_gather/none", "AccountingStorageType=accounting_storage/none",
                "SelectType=select/cons_tres", "SelectTypeParameters=CR_Core",
                "DependencyParameters=kill_invalid_depend",
                "MailProg=/bin/true", "ReturnToService=2", "MinJobAge=600",
                "SlurmctldPort=16817", "SlurmdPort=16818",
                "StateSaveLocation=" + self._path("state"),
                "SlurmdSpoolDir=" + self._path("spool"),
                "SlurmctldPidFile=" + self._path("slurmctld.pid"),
                "SlurmdPidFile=" + self._path("slurmd.pid"),
                "SlurmctldLogFile=" + self._path("log", "slurmctld.log"),
                "SlurmdLogFile=" + self._path("log", "slurmd.log"),
                "NodeName=%s NodeAddr=127.0.0.1 CPUs=%d RealMemory=%d State=UNKNOWN"
                % (host, self.cpus, max(256, _memory_mb() - 512)),
                "PartitionName=lantern Nodes=%s Default=YES MaxTime=INFINITE State=UP" % host,
                ""]))
        self.env = dict(os.environ, SLURM_CONF=conf)
        self.env["PATH"] = self.env.get("PATH", "") + ":/usr/sbin"
        self.pidfiles += [self._path("slurmctld.pid"), self._path("slurmd.pid")]
        subprocess.run(["slurmctld", "-i"], env=self.env, check=True)  # -i: ignore stale state
        self._until(lambda: self._ok(["scontrol", "ping"]) and "UP" in self._out(["scontrol", "ping"]),
                    "slurmctld answering scontrol ping")
        subprocess.run(["slurmd"], env=self.env, check=True)
        self._until(lambda: self._out(["sinfo", "-h", "-o", "%T"]).strip() in ("idle", "mixed", "allocated"),
                    "the node idle in sinfo")

    def _out(self, cmd):
        return subprocess.run(cmd, env=self.env, capture_output=True, text=True).stdout

    def _ok(self, cmd):
        return subprocess.run(cmd, env=self.env, capture_output=True).returncode == 0

    def _until(self, cond, what, timeout=30):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if cond():
                return
            time.sleep(0.1)
        logs = ""
        for name in ("slurmctld.log", "slurmd.log", "munged.log"):
            p = self._path("log", name)
            if os.path.exists(p):
                with open(p) as f:
                    logs += "\n--- %s ---\n%s" % (name, f.read()[-3000:])
        raise RuntimeError("timed out waiting for %s%s" % (what, logs))

    def stop(self):
        """Cancels every job (job processes outlive slurmd), then stops the daemons by their pids."""
        if self.env is not None:
            subprocess.run(["scancel", "--full", "--user", "root"], env=self.env, capture_output=True)
            end = time.monotonic() + 15
            while time.monotonic() < end and self._out(["squeue", "-h"]).strip():
                time.sleep(0.2)
        pids = []
        for pidfile in reversed(self.pidfiles):  # slurmd, slurmctld, munged
            try:
                with open(pidfile) as f:
                    pid = int(f.read().split()[0])
            except (OSError, ValueError, IndexError):
                continue
            try:
                os.kill(pid, 15)
                pids.append(pid)
            except ProcessLookupError:
                pass
        end = time.monotonic() + 15
        while time.monotonic() < end and any(_alive(p) for p in pids):
            time.sleep(0.1)
        for p in pids:
            if _alive(p):
                os.kill(p, 9)
        self.pidfiles = []
        self.env = None
        if self.dir:
            shutil.rmtree(self.dir, ignore_errors=True)
            self.dir = None
