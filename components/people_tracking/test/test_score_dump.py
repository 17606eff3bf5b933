#!/usr/bin/env python3
"""Test of tools/score_dump.py (ctest people_tracking_test_score_dump): the bench's C++ scorer and the
independent Python one agree on the same run.

  test_score_dump.py CAIRN_PEOPLE_EXE TRAJECTORY_FILE

1. `cairn people bench --dump` on a trajectory excerpt, static robot and circling robot: every CLEAR MOT, HOTA,
   IDF1 and OSPA figure of the bench's JSON equals score_dump.py's from the dumped CSV files (counts exactly,
   ratios to the JSON's 4 decimals).
2. A dump without dontcare.csv: one line naming the directory, exit 2; a non-numeric row: one line naming
   file:line, exit 2.
"""
import json
import os
import subprocess
import sys
import tempfile

TOOL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools", "score_dump.py")
COUNTS = ["id_switches", "id_transfers", "fp", "fn", "matches", "gt", "gt_tracks"]
RATIOS = ["mota", "motp", "id_switches_per_100_tracks", "hota", "deta", "assa", "loca", "hota_at_0_5",
          "deta_at_0_5", "assa_at_0_5", "idf1", "idp", "idr", "ospa_m"]


def main():
    exe, traj = sys.argv[1], sys.argv[2]
    failures = 0
    with tempfile.TemporaryDirectory() as tmp:
        for robot in ([], ["--robot-path", "circle:2.0"]):
            d = os.path.join(tmp, "circle" if robot else "static")
            out = subprocess.run([exe, "bench", "--world", "auto", "--trajectories", traj, "--seed", "2", "--json",
                                  "--dump", d] + robot, check=True, capture_output=True, text=True).stdout
            bench = json.loads(out)["cairn"]
            py = json.loads(subprocess.run([sys.executable, TOOL, d, "--json"], check=True, capture_output=True,
                                           text=True).stdout)
            if bench["matches"] < 100 or bench["gt_tracks"] < 5:
                print(f"FAIL: the excerpt scored too little to compare ({bench})")
                failures += 1
            for k in COUNTS:
                if bench[k] != py[k]:
                    print(f"FAIL {robot or 'static'}: {k} bench {bench[k]} python {py[k]}")
                    failures += 1
            for k in RATIOS:
                if abs(bench[k] - py[k]) > 6e-4 * max(1.0, abs(py[k])):  # JSON prints 4 decimals (3 for per-100)
                    print(f"FAIL {robot or 'static'}: {k} bench {bench[k]} python {py[k]}")
                    failures += 1
            print(f"{robot or 'static'}: bench and score_dump.py agree: " + ", ".join(f"{k} {bench[k]}" for k in
                                                                                        COUNTS + RATIOS))
        # 2. Bad input.
        os.remove(os.path.join(tmp, "static", "dontcare.csv"))
        r = subprocess.run([sys.executable, TOOL, os.path.join(tmp, "static")], capture_output=True, text=True)
        lines = r.stderr.strip().splitlines()
        if r.returncode != 2 or len(lines) != 1 or "static" not in lines[0] or "dontcare.csv" not in lines[0]:
            print(f"FAIL: missing dontcare.csv gave exit {r.returncode}, stderr {r.stderr!r}")
            failures += 1
        with open(os.path.join(tmp, "circle", "tracks.csv"), "a") as f:
            f.write("1.0,7,abc,2.0\n")
        r = subprocess.run([sys.executable, TOOL, os.path.join(tmp, "circle")], capture_output=True, text=True)
        lines = r.stderr.strip().splitlines()
        if r.returncode != 2 or len(lines) != 1 or "tracks.csv:" not in lines[0]:
            print(f"FAIL: a non-numeric row gave exit {r.returncode}, stderr {r.stderr!r}")
            failures += 1
    print("FAILED" if failures else "PASSED")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
