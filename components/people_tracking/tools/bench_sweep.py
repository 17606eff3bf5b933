#!/usr/bin/env python3
"""ID-switch sweep: `cairn people bench` over ETH/hotel/zara01 x static/circle:2.0 x seeds, for one or more
binaries/option sets in the same session. Prints per-scene medians (MOTA, switches per 100 person-tracks, HOTA,
IDF1; switches summed) and totals over all runs (switches, FP, FN,
id transfers, lowest MOTA; mean HOTA, DetA, AssA, lowest HOTA; mean IDF1). The runs are deterministic; -j runs several at once.

  bench_sweep.py [--data DIR] [--seeds 1,2,3] [-j N] LABEL=BINARY[::EXTRA OPTIONS] ...

Example (baseline build vs new build, same run; run it under the CPU lock):
  flock /tmp/cairn_heavy.lock components/people_tracking/tools/bench_sweep.py \
      base=/tmp/cairn-people-base new=build/bin/cairn-people "new-noX=build/bin/cairn-people::--foo 0"
"""
import argparse
import concurrent.futures
import json
import statistics
import subprocess
import sys

SCENES = ["seq_eth", "seq_hotel", "ucy_zara01"]
ROBOTS = ["", "circle:2.0"]


def run(binary, extra, scene, robot, seed, data):
    cmd = [binary, "bench", "--world", "auto", "--trajectories", f"{data}/{scene}/obsmat.txt",
           "--seed", str(seed), "--json"] + extra
    if robot:
        cmd += ["--robot-path", robot]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out)["cairn"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default="/work/shared/data/people/eth_ucy")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("-j", type=int, default=1, help="runs at once")
    ap.add_argument("variants", nargs="+")
    a = ap.parse_args()
    seeds = [int(s) for s in a.seeds.split(",")]
    variants = []
    for v in a.variants:
        label, _, rest = v.partition("=")
        binary, _, extra = rest.partition("::")
        variants.append((label, binary, extra.split()))
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.j)) as pool:
        jobs = {(label, scene, robot): [pool.submit(run, binary, extra, scene, robot, s, a.data) for s in seeds]
                for label, binary, extra in variants for scene in SCENES for robot in ROBOTS}
        rows = {k: [f.result() for f in fs] for k, fs in jobs.items()}
    print("| scene | robot | " + " | ".join(f"{l} MOTA / IDSW/100 [range] / IDSW / HOTA / IDF1" for l, _, _ in variants)
          + " |")
    print("|---|---|" + "---|" * len(variants))
    for scene in SCENES:
        for robot in ROBOTS:
            cells = []
            for label, _, _ in variants:
                r = rows[(label, scene, robot)]
                mota = statistics.median(x["mota"] for x in r)
                per = [x["id_switches_per_100_tracks"] for x in r]
                cells.append(f"{mota:.3f} / {statistics.median(per):.1f} [{min(per):.1f}-{max(per):.1f}] / "
                             f"{sum(x['id_switches'] for x in r)} / {statistics.median(x['hota'] for x in r):.3f} / "
                             f"{statistics.median(x['idf1'] for x in r):.3f}")
            print(f"| {scene} | {robot or 'static'} | " + " | ".join(cells) + " |")
    print()
    for label, _, _ in variants:
        allr = [x for (l, _, _), r in rows.items() if l == label for x in r]
        tracks = sum(x["gt_tracks"] for x in allr)
        sw = sum(x["id_switches"] for x in allr)
        print(f"{label}: runs {len(allr)}  IDSW {sw} ({100.0 * sw / tracks:.2f} per 100 tracks)  "
              f"id transfers {sum(x['id_transfers'] for x in allr)}  "
              f"FP {sum(x['fp'] for x in allr)}  FN {sum(x['fn'] for x in allr)}  "
              f"min MOTA {min(x['mota'] for x in allr):.3f}  "
              f"HOTA {statistics.mean(x['hota'] for x in allr):.3f} (DetA {statistics.mean(x['deta'] for x in allr):.3f} "
              f"AssA {statistics.mean(x['assa'] for x in allr):.3f}; min HOTA {min(x['hota'] for x in allr):.3f})  "
              f"IDF1 {statistics.mean(x['idf1'] for x in allr):.3f}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
