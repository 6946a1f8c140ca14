#!/usr/bin/env python3
"""One scale run (docs/benchmarks.md "Scale"): `fabatlas run JOB --workers 2`
or `fabatlas sample JOB` into OUT, sampling once a second the size of
OUT/cluster-state (peak, and state.db at the end) and the resident set of
every fabatlas process of the run (peak VmHWM of each). Prints one JSON line:
samples, wall s, CPU s (user+sys of the command and its workers), CPU ms per
sample, peaks, artifact bytes.
  python3 bench/scale/scale_run.py run|sample JOB OUT [--fabatlas build/bin/fabatlas] [extra args]
(`run` gets --workers 2 unless the extra args name --workers.)
"""
import json, os, subprocess, sys, threading, time

mode, job, out = sys.argv[1], sys.argv[2], os.path.abspath(sys.argv[3])
extra = sys.argv[4:]
fab = "build/bin/fabatlas"
if extra[:1] == ["--fabatlas"]:
    fab, extra = extra[1], extra[2:]
cmd = [os.path.abspath(fab), mode, job, "--out", out] + (["--workers", "2"] if mode == "run" and "--workers" not in extra else []) + extra
state = os.path.join(out, "cluster-state")
peak = {"state_bytes": 0}
rss = {}
cpu_ticks = {}  # last seen utime+stime (clock ticks) of each process of the run
done = False

def du(p):
    t = 0
    for r, _, fs in os.walk(p):
        for f in fs:
            try: t += os.lstat(os.path.join(r, f)).st_size
            except OSError: pass
    return t

def watch(root_pid):
    while not done:
        if os.path.isdir(state):
            peak["state_bytes"] = max(peak["state_bytes"], du(state))
        for pid in os.listdir("/proc"):
            if not pid.isdigit(): continue
            try:
                cmdline = open(f"/proc/{pid}/cmdline", "rb").read().split(b"\0")
                if int(pid) != root_pid and not any(out.encode() in a for a in cmdline): continue
                if b"python" in cmdline[0]: continue
                status = open(f"/proc/{pid}/status").read()
                hwm = int(status.split("VmHWM:")[1].split()[0])
                name = os.path.basename(cmdline[0].decode()) + ("" if int(pid) == root_pid else f"[{pid}]")
                rss[name] = max(rss.get(name, 0), hwm)
                fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
                cpu_ticks[name] = int(fields[11]) + int(fields[12])
            except (OSError, IndexError, ValueError):
                pass
        time.sleep(1.0)

t0 = time.time()
p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
th = threading.Thread(target=watch, args=(p.pid,)); th.start()

def log_lines():  # OUT.log: each stderr line (progress with its ETA) with seconds since start
    with open(out + ".log", "w") as f:
        for line in p.stderr:
            f.write(f"{time.time() - t0:.1f} {line}"); f.flush()
lt = threading.Thread(target=log_lines); lt.start()
_, status, usage = os.wait4(p.pid, 0)
wall = time.time() - t0
done = True; th.join(); lt.join()
stats = json.load(open(os.path.join(out, "statistics.json")))
n = stats["samples"]
artifact = [f for f in os.listdir(out) if f.endswith(".fabatlas")]
cpu = usage.ru_utime + usage.ru_stime
print(json.dumps({
    "mode": mode, "job": job, "exit": os.waitstatus_to_exitcode(status), "samples": n,
    "wall_s": round(wall, 1), "cpu_s": round(cpu, 1), "cpu_ms_per_sample": round(1000 * cpu / max(n, 1), 2),
    "state_peak_bytes": peak["state_bytes"], "state_kib_per_sample": round(peak["state_bytes"] / 1024 / max(n, 1), 2),
    "sqlite_bytes": os.path.getsize(os.path.join(state, "state.db")) if os.path.exists(os.path.join(state, "state.db")) else 0,
    "artifact_bytes": os.path.getsize(os.path.join(out, artifact[0])) if artifact else 0,
    "rss_peak_mib": {k: round(v / 1024) for k, v in rss.items()},
    # CPU of each process up to its last second (so slightly under its total): where the CPU went
    "cpu_s_by_process": {k: round(v / os.sysconf("SC_CLK_TCK"), 1) for k, v in cpu_ticks.items()},
    "load": os.getloadavg()[0]}))
