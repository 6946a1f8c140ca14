#!/usr/bin/env python3
"""The ETA's accuracy on one scale run (docs/benchmarks.md "Scale"): reads
OUT.log that scale_run.py wrote (each progress line of `fabatlas run` with
the seconds since start) and prints, for the progress line nearest each tenth
of the wall time (and 95 %), the elapsed fraction, the ETA shown, the real
remaining time (end = the SUCCEEDED line) and the error in percent.
  python3 bench/scale/eta_table.py OUT.log
"""
import re, sys

rows = []
end = None
for line in open(sys.argv[1]):
    m = re.match(r"([\d.]+) job \S+ (\w+)\s.*ETA (\S+)", line)
    if not m:
        continue
    t, state, eta = float(m[1]), m[2], m[3]
    if state == "SUCCEEDED" and end is None:
        end = t
    if state == "RUNNING":
        rows.append((t, None if eta == "-" else float(eta)))
if end is None:
    sys.exit(f"{sys.argv[1]}: no SUCCEEDED line")
print(f"wall {end:.1f} s")
print("| elapsed | ETA s | real remaining s | error |")
print("|---|---|---|---|")
worst = 0.0
shown = set()
for target in [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95]:
    t, eta = min(rows, key=lambda r: abs(r[0] / end - target))
    if t in shown:
        continue
    shown.add(t)
    real = end - t
    err = None if eta is None else 100.0 * (eta - real) / real
    if err is not None and t / end >= 0.2:
        worst = max(worst, abs(err))
    print(f"| {100 * t / end:.0f} % ({t:.0f} s) | {'-' if eta is None else f'{eta:.0f}'} | {real:.0f} | "
          f"{'-' if err is None else f'{err:+.0f} %'} |")
after = [(t, e) for t, e in rows if t / end >= 0.2 and e is not None]
errs = [100.0 * (e - (end - t)) / (end - t) for t, e in after]
inside = sum(1 for e in errs if abs(e) <= 30)
print(f"progress lines after 20 % of the wall time: {len(errs)}, within ±30 %: {inside}; "
      f"error range {min(errs):+.0f} % .. {max(errs):+.0f} %")
