#!/usr/bin/env python3
"""The ETA's accuracy on scale runs (docs/benchmarks.md "Scale"): reads each
OUT.log that scale_run.py wrote (each progress line of `fabatlas run` with
the seconds since start) and prints, for the progress line nearest 10, 20,
40, 60 and 80 % of the wall time, the ETA shown, the real remaining time
(end = the SUCCEEDED line) and the error (ETA / real remaining - 1), one
column per run; then, per run, how many progress lines after 20 % of the
wall time are within ±30 %.
  python3 bench/scale/eta_table.py OUT1.log [OUT2.log ...]
"""
import re, sys

FRACTIONS = [0.1, 0.2, 0.4, 0.6, 0.8]


def read(path):
    rows, end = [], None
    for line in open(path):
        m = re.match(r"([\d.]+) job \S+ (\w+)\s.*ETA (\S+)", line)
        if not m:
            continue
        t, state, eta = float(m[1]), m[2], m[3]
        if state == "SUCCEEDED" and end is None:
            end = t
        if state == "RUNNING":
            rows.append((t, None if eta == "-" else float(eta.rstrip("s"))))
    if end is None:
        sys.exit(f"{path}: no SUCCEEDED line")
    return rows, end


runs = [(p, *read(p)) for p in sys.argv[1:]]
print("| elapsed | " + " | ".join(f"{p}: ETA / real remaining, error" for p, _, _ in runs) + " |")
print("|---|" + "---|" * len(runs))
for f in FRACTIONS:
    cells = []
    for _, rows, end in runs:
        t, eta = min(rows, key=lambda r: abs(r[0] / end - f))
        real = end - t
        err = "-" if eta is None else f"{100.0 * (eta / real - 1):+.0f} %"
        cells.append(f"{'-' if eta is None else f'{eta:.0f}'} / {real:.0f} s, {err}")
    print(f"| {100 * f:.0f} % | " + " | ".join(cells) + " |")
for p, rows, end in runs:
    errs = [100.0 * (e / (end - t) - 1) for t, e in rows if t / end >= 0.2 and e is not None and t < end]
    inside = sum(1 for e in errs if abs(e) <= 30)
    print(f"{p}: wall {end:.0f} s; progress lines after 20 % of it: {len(errs)}, within ±30 %: {inside}; "
          f"error {min(errs):+.0f} % .. {max(errs):+.0f} %, mean |error| {sum(map(abs, errs)) / len(errs):.0f} %")
