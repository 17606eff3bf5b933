#!/usr/bin/env python3
"""Per-container table of an endurance run (scripts/endurance.sh): RSS, CPU share of one core since the previous
row, threads and open files, one row per WINDOW seconds (default 300) and the last sample.

Usage: scripts/endurance_summary.py SAMPLES.csv [WINDOW]
A process that was restarted (respawned container) gets rows of its own, under its new pid."""
import csv
import sys
from collections import OrderedDict

TICKS_PER_S = 100  # USER_HZ: /proc/<pid>/stat counts CPU time in 1/100 s on Linux


def main(argv):
    if len(argv) not in (2, 3):
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    path = argv[1]
    try:
        window = float(argv[2]) if len(argv) == 3 else 300.0
        if not window > 0:
            raise ValueError
    except ValueError:
        print(f"endurance_summary: WINDOW must be a positive number, got '{argv[2]}'", file=sys.stderr)
        return 2
    series = OrderedDict()
    try:
        with open(path, newline="") as f:
            for line, row in enumerate(csv.DictReader(f), start=2):
                try:
                    name = row["name"]
                    if "container --name" not in name:
                        continue
                    key = (name.split("--name ")[1].split()[0], row["pid"])
                    series.setdefault(key, []).append(
                        (float(row["t"]), int(row["rss_kb"]), int(row["cpu_ticks"]), row["threads"], row["fds"]))
                except (KeyError, IndexError, ValueError, TypeError) as e:
                    print(f"endurance_summary: {path}:{line}: malformed row ({e})", file=sys.stderr)
                    return 2
    except OSError as e:
        print(f"endurance_summary: {path}: {e.strerror}", file=sys.stderr)
        return 2
    for (container, pid), rows in series.items():
        print(f"{container} (pid {pid})")
        print("   t[s]  RSS[MB]  CPU[%]  threads  fds")
        last = None
        for i, (t, rss, cpu, threads, fds) in enumerate(rows):
            if last is not None and t - last[0] < window and i != len(rows) - 1:
                continue
            share = "" if last is None or t <= last[0] else f"{100.0 * (cpu - last[2]) / TICKS_PER_S / (t - last[0]):.1f}"
            print(f"  {t:5.0f}  {rss / 1024:7.1f}  {share:>6}  {threads:>7}  {fds:>3}")
            last = (t, rss, cpu)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
