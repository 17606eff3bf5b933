#!/usr/bin/env python3
"""Classify the ID switches of `cairn people bench --dump DIR` runs.

  switch_analysis.py DIR [DIR ...] [--list]

Reads each dump (groundtruth.csv, tracker_state.csv, and matches.csv: the bench's own CLEAR MOT correspondences
with the switched-from track, so the switches are exactly the bench's id_switches) and, for every switch of person g from published id A to B, reports:
  old track A at the switch: on_other (published on another person), alive_far (internal track > 0.5 m away,
    on nobody), alive_near (internal, within 0.5 m but not published: coasting or free space), deleted;
  new track B: new (born < 1 s before, on nobody else before), from_other (was on another person before),
    old_unmatched (older, on nobody before);
  person: switches within 3 s of the person's first counted scan ("early"); "appeared": the person was counted
    from the scan its walker appeared in (no uncounted walker within 0.6 m of that spot in the 0.4 s before, from
    dontcare.csv; runs without dontcare.csv count nobody as appeared), i.e. the recording's annotation began inside
    the field, and "appeared together": so did another person within 3 m and 1 s of it (a group materialising at
    once, which a robot never sees: real people walk in);
  old track: confirmed < 3 s before the switch ("young"), and whether another person was within 1 m when it was
    confirmed ("born in a group").
  gap: how long the person had been unmatched (a miss) before the switch (0.1 s = matched in the previous scan).
  situation: the nearest other counted person within +-1 s of the switch: "group" if closer than 1.2 m and
    walking with it (velocities, over +-0.5 s, differ by less than 0.5 m/s), "crossing" if closer than 1.2 m
    otherwise, "alone" if nobody came that close ("unknown": too few samples for a velocity);
  mutual: another person switched the other way (B -> A) within 1.5 s (two tracks traded people).
  annotation swap: the person is one of two within 1.5 m of each other whose annotated paths are far smoother with
    their ids exchanged after some time (second difference over 0.4 s, the annotation period: summed over both,
    exchanged < 1/4 of as recorded, and as recorded > 0.2 m), within 1.5 s of that time; i.e. the recording labelled
    two people walking side by side the wrong way round from then on, and the replay has them trade places through
    each other in one annotation period (ETH/UCY: three such events, docs/benchmarks.md).
--list prints one line per switch (t, person, A, B, classes, nearest other person in m).
--by-range (needs robot.csv and legs.csv in the dump) prints, per band of distance from the sensor, the counted
  person-scans, the switches and switches per 10 000 person-scans, and how often a counted person has a leg
  detection within 0.4 m: any leg scored >= 0.5, two such legs, any leg >= 0.2 (the tracker's weak-leg threshold).
"""
import bisect
import collections
import csv
import math
import sys

THRESHOLD = 0.5  # m, the bench's match threshold (for "alive_far")
NEIGHBOUR = 1.2  # m, "group"/"crossing": another person came this close within +-1 s of the switch
WITH = 0.5  # m/s, "group": velocity difference below this
MUTUAL = 1.5  # s, window for a mirrored switch
SWAP_STEP = 0.4  # s, the annotation period of ETH/UCY (annotation swaps)
SWAP_PAIR = 1.5  # m, the two people are this close at the swap
SWAP_RATIO = 0.25  # exchanged / recorded second differences (squared, summed over both people)
SWAP_MIN = 0.2  # m, recorded second difference (root of the sum of squares) at least this


def by_time(path):
    rows = collections.OrderedDict()
    with open(path) as f:
        for r in csv.DictReader(f):
            rows.setdefault(round(float(r["t"]), 3), []).append(r)
    return rows


def first_counted(gt):
    """person -> (t, x, y) of its first counted scan."""
    first = {}
    for t in sorted(gt):
        for r in gt[t]:
            first.setdefault(int(r["id"]), (t, float(r["x"]), float(r["y"])))
    return first


def analyse(d):
    gt, mt, st = by_time(d + "/groundtruth.csv"), by_time(d + "/matches.csv"), by_time(d + "/tracker_state.csv")
    on_person = collections.defaultdict(set)  # track id -> persons it was matched to so far
    first_state, confirmed_at, last_matched = {}, {}, {}
    first = first_counted(gt)
    out = []
    for t in sorted(set(gt) | set(mt) | set(st)):
        G = [(int(r["id"]), float(r["x"]), float(r["y"])) for r in gt.get(t, [])]
        M = [(int(r["person"]), int(r["track"]), int(r["switched_from"])) for r in mt.get(t, [])]
        S = {int(r["id"]): r for r in st.get(t, [])}
        for i, r in S.items():
            first_state.setdefault(i, t)
            if r["confirmed"] == "1" and i not in confirmed_at:
                others = sorted(math.hypot(float(r["x"]) - x, float(r["y"]) - y) for _, x, y in G)
                confirmed_at[i] = (t, len(others) > 1 and others[1] < 1.0)
        match = {g: h for g, h, _ in M}
        pos = {g: (x, y) for g, x, y in G}
        for g, h, a in M:
            if a < 0:
                continue
            x, y = pos[g]
            if any(h2 == a for g2, h2 in match.items() if g2 != g):
                old = "on_other"
            elif a in S:
                far = math.hypot(float(S[a]["x"]) - x, float(S[a]["y"]) - y) > THRESHOLD
                old = "alive_far" if far else "alive_near"
            else:
                old = "deleted"
            others = on_person[h] - {g}
            new = "from_other" if others else ("new" if t - first_state.get(h, t) < 1.0 else "old_unmatched")
            near = min([math.hypot(x - x2, y - y2) for g2, x2, y2 in G if g2 != g] or [float("inf")])
            conf_t, group = confirmed_at.get(a, (t, False))
            out.append({"t": t, "person": g, "old": a, "new_id": h, "old_class": old, "new_class": new,
                        "early": t - first[g][0] < 3.0, "young": t - conf_t < 3.0, "group": group,
                        "nearest": near, "gap": t - last_matched.get(g, t)})
        for g, h in match.items():
            on_person[h].add(g)
            last_matched[g] = t
    situations(gt, out)
    swaps = annotation_swaps(gt)
    appeared = appearances(d, first)
    for s in out:
        s["appeared"], s["appeared_together"] = appeared.get(s["person"], (False, False))
    for s in out:
        s["annotation_swap"] = any(s["person"] in pair and abs(s["t"] - ts) <= MUTUAL for ts, pair in swaps)
    for s in out:
        s["mutual"] = any(o is not s and abs(o["t"] - s["t"]) <= MUTUAL and o["old"] == s["new_id"] and
                          o["new_id"] == s["old"] for o in out)
    return out


APPEAR_NEAR = 0.6  # m, an uncounted walker this close to where a person is first counted was there before
APPEAR_BEFORE = 0.4  # s, looked back this far (one annotation period)
TOGETHER_T, TOGETHER_D = 1.0, 3.0  # s, m: "appeared together"


def appearances(d, first):
    """person -> (appeared, appeared together) (see the module docstring) from first_counted(); {} without
    dontcare.csv."""
    try:
        dc = by_time(d + "/dontcare.csv")
    except OSError:
        return {}
    dc_times = sorted(dc)
    new = {}
    for g, (t, x, y) in first.items():
        before = dc_times[bisect.bisect_left(dc_times, t - APPEAR_BEFORE - 1e-6):bisect.bisect_left(dc_times, t - 1e-6)]
        new[g] = not any(math.hypot(float(r["x"]) - x, float(r["y"]) - y) < APPEAR_NEAR for u in before for r in dc[u])
    out = {}
    for g, (t, x, y) in first.items():
        together = any(h != g and new[h] and abs(t2 - t) <= TOGETHER_T and math.hypot(x2 - x, y2 - y) < TOGETHER_D
                       for h, (t2, x2, y2) in first.items())
        out[g] = (new[g], new[g] and together)
    return out


def situations(gt, switches):
    """Sets s["situation"] (see the module docstring) from the counted people's positions around each switch."""
    pos = {(t, int(r["id"])): (float(r["x"]), float(r["y"])) for t, rows in gt.items() for r in rows}
    times = sorted(gt)

    def window(t, half):
        return [u for u in times if abs(u - t) <= half + 1e-6]

    def velocity(g, t):
        pts = [(u, pos[(u, g)]) for u in window(t, 0.5) if (u, g) in pos]
        if len(pts) < 2 or pts[-1][0] - pts[0][0] < 0.25:
            return None
        (ta, a), (tb, b) = pts[0], pts[-1]
        return ((b[0] - a[0]) / (tb - ta), (b[1] - a[1]) / (tb - ta))

    for s in switches:
        g, best = s["person"], (float("inf"), None, None)
        for u in window(s["t"], 1.0):
            if (u, g) not in pos:
                continue
            x, y = pos[(u, g)]
            for r in gt[u]:
                h = int(r["id"])
                d = math.hypot(float(r["x"]) - x, float(r["y"]) - y)
                if h != g and d < best[0]:
                    best = (d, h, u)
        d, h, u = best
        if d >= NEIGHBOUR:
            s["situation"] = "alone"
            continue
        va, vb = velocity(g, u), velocity(h, u)
        if va is None or vb is None:
            s["situation"] = "unknown"
        else:
            s["situation"] = "group" if math.hypot(va[0] - vb[0], va[1] - vb[1]) < WITH else "crossing"


def annotation_swaps(gt):
    """(t, {a, b}) of every likely id exchange in the recording (see the module docstring)."""
    pos = {(t, int(r["id"])): (float(r["x"]), float(r["y"])) for t, rows in gt.items() for r in rows}
    key = lambda t: round(t, 3)
    events = []
    for t, rows in gt.items():
        before, after = key(t - SWAP_STEP), key(t + SWAP_STEP)
        ids = [int(r["id"]) for r in rows if (before, int(r["id"])) in pos and (after, int(r["id"])) in pos]
        for i, a in enumerate(ids):
            for b in ids[i + 1:]:
                pa, pb = pos[(t, a)], pos[(t, b)]
                if math.hypot(pa[0] - pb[0], pa[1] - pb[1]) > SWAP_PAIR:
                    continue
                dd = lambda p0, p1, p2: (p2[0] - 2 * p1[0] + p0[0]) ** 2 + (p2[1] - 2 * p1[1] + p0[1]) ** 2
                kept = dd(pos[(before, a)], pa, pos[(after, a)]) + dd(pos[(before, b)], pb, pos[(after, b)])
                exchanged = dd(pos[(before, a)], pa, pos[(after, b)]) + dd(pos[(before, b)], pb, pos[(after, a)])
                if kept > SWAP_MIN ** 2 and exchanged < SWAP_RATIO * kept:
                    if not any(pair == {a, b} and abs(ts - t) <= MUTUAL for ts, pair in events):
                        events.append((t, {a, b}))
    return events


BANDS = (2.0, 4.0, 6.0, 8.0)  # m, upper edges of the distance bands of --by-range (the bench counts up to 8 m)
LEG_RADIUS = 0.4  # m, a leg detection this close to a person counts as that person's


def by_range(d, switches):
    """Per distance band: [person-scans, switches, scans with a leg >= 0.5, with two, with a leg >= 0.2]."""
    robot = {t: (float(r[0]["x"]), float(r[0]["y"])) for t, r in by_time(d + "/robot.csv").items()}
    legs = by_time(d + "/legs.csv")
    gt = by_time(d + "/groundtruth.csv")
    band = lambda t, x, y: next((k for k, b in enumerate(BANDS) if math.hypot(x - robot[t][0], y - robot[t][1]) <= b),
                                len(BANDS) - 1)
    rows = [[0, 0, 0, 0, 0] for _ in BANDS]
    where = {}
    for t, people in gt.items():
        L = [(float(r["x"]), float(r["y"]), float(r["confidence"])) for r in legs.get(t, [])]
        for r in people:
            x, y = float(r["x"]), float(r["y"])
            k = band(t, x, y)
            where[(t, int(r["id"]))] = k
            near = [c for lx, ly, c in L if math.hypot(lx - x, ly - y) < LEG_RADIUS]
            rows[k][0] += 1
            rows[k][2] += any(c >= 0.5 for c in near)
            rows[k][3] += sum(c >= 0.5 for c in near) >= 2
            rows[k][4] += any(c >= 0.2 for c in near)
    for s in switches:
        rows[where[(s["t"], s["person"])]][1] += 1
    return rows


def main():
    dirs = [a for a in sys.argv[1:] if not a.startswith("--")]
    if not dirs:
        print(__doc__)
        return 2
    allsw = []
    bands = [[0, 0, 0, 0, 0] for _ in BANDS]
    for d in dirs:
        try:
            sw = analyse(d)
            if "--by-range" in sys.argv:
                for k, row in enumerate(by_range(d, sw)):
                    bands[k] = [a + b for a, b in zip(bands[k], row)]
        except (OSError, KeyError, ValueError) as e:
            print(f"switch_analysis: {d}: {e}", file=sys.stderr)
            return 2
        allsw += sw
        if "--list" in sys.argv:
            for s in sw:
                print(f"{d}: t={s['t']:.2f} person {s['person']}: {s['old']} -> {s['new_id']} "
                      f"{s['old_class']}/{s['new_class']} {s['situation']}{' mutual' if s['mutual'] else ''} "
                      f"nearest {s['nearest']:.2f} m{' annotation-swap' if s['annotation_swap'] else ''}"
                      f"{' appeared' if s['appeared'] else ''}")
    n = len(allsw)
    print(f"switches: {n} in {len(dirs)} runs")
    for key in ("old_class", "new_class"):
        c = collections.Counter(s[key] for s in allsw)
        print(f"  {key}: " + ", ".join(f"{k} {v}" for k, v in c.most_common()))
    print(f"  another person within 1 m: {sum(s['nearest'] < 1.0 for s in allsw)}")
    print(f"  early (< 3 s after the person was first counted): {sum(s['early'] for s in allsw)}")
    print(f"  old track young (confirmed < 3 s before): {sum(s['young'] for s in allsw)}, "
          f"of them born in a group: {sum(s['young'] and s['group'] for s in allsw)}")
    early_appeared = sum(s["early"] and s["appeared"] for s in allsw)
    together = sum(s["early"] and s["appeared_together"] for s in allsw)
    print(f"  early and appeared inside the field: {early_appeared}, of them together with another person: {together}")
    gaps = collections.Counter("matched in the previous scan" if s["gap"] < 0.15 else "unmatched 0.2-0.5 s"
                               if s["gap"] < 0.55 else "unmatched 0.6-1.5 s" if s["gap"] < 1.55 else
                               "unmatched > 1.5 s" for s in allsw)
    print("  person before the switch: " + ", ".join(f"{k} {v}" for k, v in gaps.most_common()))
    c = collections.Counter(s["situation"] for s in allsw)
    print("  situation: " + ", ".join(f"{k} {v}" for k, v in c.most_common()) +
          f"; in mutual swaps (two tracks traded people): {sum(s['mutual'] for s in allsw)}")
    print(f"  at an annotation swap (the recording exchanged two people's ids): {sum(s['annotation_swap'] for s in allsw)}")
    if "--by-range" in sys.argv:
        print("| distance | person-scans | switches | per 10k | leg >= 0.5 | two legs >= 0.5 | leg >= 0.2 |")
        print("|---|---|---|---|---|---|---|")
        lo = 0.0
        for b, (n, k, one, two, weak) in zip(BANDS, bands):
            if n:
                print(f"| {lo:g}-{b:g} m | {n} | {k} | {1e4 * k / n:.1f} | {one / n:.2f} | {two / n:.2f} | {weak / n:.2f} |")
            lo = b
    return 0


if __name__ == "__main__":
    sys.exit(main())
