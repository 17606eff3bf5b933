#!/usr/bin/env python3
"""Score a `cairn people bench --dump DIR` run from its CSV files alone: CLEAR MOT, HOTA, IDF1 and OSPA.

  score_dump.py DIR [--threshold 0.5] [--json]

Reads groundtruth.csv (t,id,x,y: the counted people), tracks.csv (t,id,x,y: the published tracks) and
dontcare.csv (t,x,y: people present but not counted) and applies the rules the bench states (README "Bench"):
hypotheses matched to a don't-care person are dropped first (MOTChallenge distractors); CLEAR MOT keeps last
frame's correspondences within the threshold and assigns the rest optimally, counting a switch when a person's
track differs from its last match; HOTA uses S = max(0, 1 - d / (2 threshold)) at alpha = 0.05 ... 0.95 with the
paper's matching (most matches, then A_max, then S); IDF1 assigns whole trajectories to maximise the frames
within the threshold; OSPA has cut-off 2 threshold and order 1.

A second implementation, in another language and from the CSV files only, of what the bench computes in C++
(clear_mot.cpp, track_metrics.cpp): test/test_score_dump.py checks that both agree on a real run, and any other
CLEAR MOT tool can be pointed at the same files. Pure Python (no numpy), so small frames only: fine for the bench.
"""
import argparse
import collections
import csv
import json
import math
import sys

FORBIDDEN = 1e9
ALPHAS = [0.05 * (k + 1) for k in range(19)]


def assignment(cost):
    """Rectangular min-cost assignment; entries >= FORBIDDEN are never used. Like the C++ solver, it minimises
    the number of forbidden pairs first (i.e. maximises the matches), then the cost. Returns row -> col or -1."""
    n = len(cost)
    m = len(cost[0]) if n else 0
    if n == 0 or m == 0:
        return [-1] * n
    transposed = n > m
    a = [list(r) for r in zip(*cost)] if transposed else [list(r) for r in cost]
    rows, cols = len(a), len(a[0])
    a = [[min(x, FORBIDDEN) for x in r] for r in a]
    inf = float("inf")
    u, v = [0.0] * (rows + 1), [0.0] * (cols + 1)
    p, way = [0] * (cols + 1), [0] * (cols + 1)
    for i in range(1, rows + 1):  # shortest augmenting paths with potentials
        p[0], j0 = i, 0
        minv, used = [inf] * (cols + 1), [False] * (cols + 1)
        while True:
            used[j0] = True
            i0, delta, j1 = p[j0], inf, 0
            for j in range(1, cols + 1):
                if used[j]:
                    continue
                cur = a[i0 - 1][j - 1] - u[i0] - v[j]
                if cur < minv[j]:
                    minv[j], way[j] = cur, j0
                if minv[j] < delta:
                    delta, j1 = minv[j], j
            for j in range(cols + 1):
                if used[j]:
                    u[p[j]] += delta
                    v[j] -= delta
                else:
                    minv[j] -= delta
            j0 = j1
            if p[j0] == 0:
                break
        while j0:
            j1 = way[j0]
            p[j0] = p[j1]
            j0 = j1
    row_to_col = [-1] * rows
    for j in range(1, cols + 1):
        if p[j]:
            row_to_col[p[j] - 1] = j - 1
    if transposed:
        out = [-1] * n
        for c, r in enumerate(row_to_col):
            if r >= 0:
                out[r] = c
    else:
        out = row_to_col
    return [c if c >= 0 and cost[r][c] < FORBIDDEN else -1 for r, c in enumerate(out)]


def dist(a, b):
    return math.hypot(a[0] - b[0], a[1] - b[1])


def gated(a, b, threshold):
    """The distance as an assignment cost, FORBIDDEN beyond the threshold."""
    d = dist(a, b)
    return d if d <= threshold else FORBIDDEN


def load(d):
    frames = collections.defaultdict(lambda: ([], [], []))  # t -> (gt, hyp, dont_care)
    for name, slot in (("groundtruth.csv", 0), ("tracks.csv", 1), ("dontcare.csv", 2)):
        path = f"{d}/{name}"
        with open(path) as f:
            for line, r in enumerate(csv.DictReader(f), start=2):
                try:
                    p = (float(r["x"]), float(r["y"]))
                    float(r["t"])
                    frames[r["t"]][slot].append(p if slot == 2 else (int(r["id"]), p))
                except (KeyError, TypeError, ValueError) as e:
                    raise ValueError(f"{path}:{line}: expected {'t,x,y' if slot == 2 else 't,id,x,y'} ({e})") from None
    return [frames[t] for t in sorted(frames, key=float)]


def drop_dont_care(gt, hyp, dc, threshold):
    if not dc or not hyp:
        return hyp
    objs = [p for _, p in gt] + dc
    cost = [[gated(o, h[1], threshold) for h in hyp] for o in objs]
    match = assignment(cost)
    dropped = {match[r] for r in range(len(gt), len(objs)) if match[r] >= 0}
    return [h for j, h in enumerate(hyp) if j not in dropped]


def clear_mot(frames, threshold):
    last, current, seen, hyp_last = {}, {}, set(), {}
    n_gt = matches = fp = fn = sw = transfers = 0
    dsum = 0.0
    for gt, hyp in frames:
        n_gt += len(gt)
        seen.update(g for g, _ in gt)
        gm, used = [-1] * len(gt), [False] * len(hyp)
        for i, (g, gp) in enumerate(gt):
            if g in current:
                for j, (h, hp) in enumerate(hyp):
                    if not used[j] and h == current[g] and dist(gp, hp) <= threshold:
                        gm[i], used[j] = j, True
        rows = [i for i in range(len(gt)) if gm[i] < 0]
        cols = [j for j in range(len(hyp)) if not used[j]]
        if rows and cols:
            cost = [[gated(gt[i][1], hyp[j][1], threshold) for j in cols] for i in rows]
            for r, c in enumerate(assignment(cost)):
                if c >= 0:
                    i, j = rows[r], cols[c]
                    gm[i], used[j] = j, True
                    if gt[i][0] in last and last[gt[i][0]] != hyp[j][0]:
                        sw += 1
        current = {}
        for i, (g, gp) in enumerate(gt):
            if gm[i] < 0:
                fn += 1
                continue
            h, hp = hyp[gm[i]]
            matches += 1
            dsum += dist(gp, hp)
            current[g] = last[g] = h
            if hyp_last.setdefault(h, g) != g:
                transfers += 1
                hyp_last[h] = g
        fp += used.count(False)
    return {"mota": 1 - (fn + fp + sw) / n_gt if n_gt else 0.0, "motp": dsum / matches if matches else 0.0,
            "id_switches": sw, "fp": fp, "fn": fn, "matches": matches, "gt": n_gt, "gt_tracks": len(seen),
            "id_transfers": transfers}


def hota(frames, zero):
    gt_n, hyp_n = collections.Counter(), collections.Counter()
    pot = [collections.Counter() for _ in ALPHAS]
    sims = []
    for gt, hyp in frames:
        gt_n.update(g for g, _ in gt)
        hyp_n.update(h for h, _ in hyp)
        pairs = [(g, h, 1 - dist(gp, hp) / zero) for g, gp in gt for h, hp in hyp]
        pairs = [x for x in pairs if x[2] > 0]
        for g, h, s in pairs:
            for k, a in enumerate(ALPHAS):
                if s >= a - 1e-9:
                    pot[k][(g, h)] += 1
        sims.append(pairs)
    gt_total, hyp_total = sum(gt_n.values()), sum(hyp_n.values())
    out = {"hota": 0.0, "deta": 0.0, "assa": 0.0}
    loca = []
    for k, a in enumerate(ALPHAS):
        matched, tp, loc = collections.Counter(), 0, 0.0
        for pairs in sims:
            cand = [x for x in pairs if x[2] >= a - 1e-9]
            if not cand:
                continue
            rows = sorted({g for g, _, _ in cand})
            cols = sorted({h for _, h, _ in cand})
            cost = [[FORBIDDEN] * len(cols) for _ in rows]
            for g, h, s in cand:
                c = pot[k][(g, h)]
                cost[rows.index(g)][cols.index(h)] = -(c / (gt_n[g] + hyp_n[h] - c) + 1e-3 * s)
            for r, c in enumerate(assignment(cost)):
                if c >= 0:
                    g, h = rows[r], cols[c]
                    tp += 1
                    matched[(g, h)] += 1
                    loc += next(s for gg, hh, s in cand if gg == g and hh == h)
        ass = sum(n * n / (gt_n[g] + hyp_n[h] - n) for (g, h), n in matched.items()) / tp if tp else 0.0
        det = tp / (gt_total + hyp_total - tp) if gt_total + hyp_total - tp > 0 else 0.0
        out["hota"] += math.sqrt(det * ass) / len(ALPHAS)
        out["deta"] += det / len(ALPHAS)
        out["assa"] += ass / len(ALPHAS)
        if tp:
            loca.append(loc / tp)
        if abs(a - 0.5) < 1e-9:
            out.update({"hota_at_0_5": math.sqrt(det * ass), "deta_at_0_5": det, "assa_at_0_5": ass})
    out["loca"] = sum(loca) / len(loca) if loca else 0.0
    return out


def idf1(frames, threshold):
    together, gt_total, hyp_total = collections.Counter(), 0, 0
    for gt, hyp in frames:
        gt_total += len(gt)
        hyp_total += len(hyp)
        for g, gp in gt:
            for h, hp in hyp:
                if dist(gp, hp) <= threshold:
                    together[(g, h)] += 1
    # The trajectory pairs that were ever together form small connected groups: assign each group on its own.
    adj = collections.defaultdict(set)
    for g, h in together:
        adj[("g", g)].add(("h", h))
        adj[("h", h)].add(("g", g))
    idtp, done = 0, set()
    for start in adj:
        if start in done:
            continue
        stack, comp = [start], []
        done.add(start)
        while stack:
            x = stack.pop()
            comp.append(x)
            for y in adj[x]:
                if y not in done:
                    done.add(y)
                    stack.append(y)
        gs = [i for k, i in comp if k == "g"]
        hs = [i for k, i in comp if k == "h"]
        cost = [[-together.get((g, h), 0) for h in hs] for g in gs]
        for r, c in enumerate(assignment(cost)):
            if c >= 0:
                idtp -= cost[r][c]
    total = gt_total + hyp_total
    return {"idf1": 2 * idtp / total if total else 0.0, "idp": idtp / hyp_total if hyp_total else 0.0,
            "idr": idtp / gt_total if gt_total else 0.0}


def ospa(frames, c):
    vals = []
    for gt, hyp in frames:
        n, m = max(len(gt), len(hyp)), min(len(gt), len(hyp))
        if n == 0:
            continue
        s = c * (n - m)
        if m:
            cost = [[min(c, dist(gp, hp)) for _, hp in hyp] for _, gp in gt]
            s += sum(cost[r][k] for r, k in enumerate(assignment(cost)) if k >= 0)
        vals.append(s / n)
    return sum(vals) / len(vals) if vals else 0.0


def score(d, threshold=0.5):
    frames = [(gt, drop_dont_care(gt, hyp, dc, threshold)) for gt, hyp, dc in load(d)]
    out = clear_mot(frames, threshold)
    out["id_switches_per_100_tracks"] = 100.0 * out["id_switches"] / out["gt_tracks"] if out["gt_tracks"] else 0.0
    out.update(hota(frames, 2 * threshold))
    out.update(idf1(frames, threshold))
    out["ospa_m"] = ospa(frames, 2 * threshold)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--threshold", type=float, default=0.5)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    try:
        s = score(a.dir, a.threshold)
    except OSError as e:
        print(f"score_dump.py: {a.dir}: {e}", file=sys.stderr)
        return 2
    except ValueError as e:
        print(f"score_dump.py: {e}", file=sys.stderr)
        return 2
    if a.json:
        print(json.dumps(s))
    else:
        print(f"MOTA {s['mota']:.4f}  MOTP {s['motp']:.4f} m  IDSW {s['id_switches']}  FP {s['fp']}  FN {s['fn']}  "
              f"HOTA {s['hota']:.4f} (DetA {s['deta']:.4f} AssA {s['assa']:.4f} LocA {s['loca']:.4f})  "
              f"IDF1 {s['idf1']:.4f}  OSPA {s['ospa_m']:.4f} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
