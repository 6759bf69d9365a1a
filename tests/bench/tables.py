#!/usr/bin/env python3
"""Turns the JSON output of bench_gjk / bench_engine / bench_calib into the Markdown tables of docs/explanation/benchmarks.md.

Usage: tables.py gjk.json engine.json [calib.json]
       tables.py --calib calib.json
"""
import json
import re
import sys


def load(path):
    with open(path) as f:
        return json.load(f)["benchmarks"]


def gjk_table(rows):
    med = {r["run_name"]: r["real_time"] for r in rows if r.get("aggregate_name") == "median"}
    out = ["| pair | points | KCCD GJK (ns) | FCL libccd (ns) | FCL indep (ns) | FCL libccd / KCCD |",
           "|---|---|---|---|---|---|"]
    regimes = {0: "separated", 1: "near-touching (1e-4)", 2: "overlapping"}
    for regime in (0, 1, 2):
        for n in (4, 8, 16, 64):
            key = f"regime:{regime}/points:{n}"
            k = med.get(f"BM_KccdGjk/{key}")
            a = med.get(f"BM_FclGjkLibccd/{key}")
            b = med.get(f"BM_FclGjkIndep/{key}")
            if k is None:
                continue
            ratio = f"{a / k:.1f}x" if a else "-"
            out.append(f"| {regimes[regime]} | {n} | {k:.0f} | {a:.0f} | {b:.0f} | {ratio} |" if a else
                       f"| {regimes[regime]} | {n} | {k:.0f} | - | - | - |")
    return "\n".join(out)


def engine_tables(rows):
    scenes = ["humanoid", "industrial_cell"]
    modes = ["exact (point)", "accurate"]
    types = ["collision", "closest", "nclosest (5)", "distances"]
    q = {}
    for r in rows:
        m = re.match(r"BM_Query/scene:(\d)/mode:(\d)/type:(\d)/warm:(\d)", r["name"])
        if m:
            q[tuple(int(x) for x in m.groups())] = r
    out = []
    for s, scene in enumerate(scenes):
        out.append(f"**{scene}** — per query, median / 99.9th percentile in µs (cold: no reuse; "
                   "warm: the table carried over from the previous cycle of a moving robot)\n")
        out.append("| sweep mode | " + " | ".join(f"{t} cold | {t} warm" for t in types) + " |")
        out.append("|---|" + "---|" * (2 * len(types)))
        for md, mode in enumerate(modes):
            cells = []
            for t in range(len(types)):
                for warm in (0, 1):
                    r = q.get((s, md, t, warm))
                    cells.append(f"{r['p50_us']:.1f} / {r['p99.9_us']:.1f}" if r else "-")
            out.append(f"| {mode} | " + " | ".join(cells) + " |")
        out.append("")
    fcl = {int(re.search(r"scene:(\d)", r["name"]).group(1)): r for r in rows if r["name"].startswith("BM_FclSampled10")}
    miss = {int(re.search(r"scene:(\d)", r["name"]).group(1)): r for r in rows if r["name"].startswith("BM_MissedCollisions")}
    if fcl:
        out.append("Side by side: FCL 0.7 checking the same volumes (hull distance minus radii) at 10 configurations "
                   "evenly spaced from the lower to the upper end of each box, stopping at the first pair within "
                   "the margin; KCCD accurate collision query on the same boxes. Missed collisions: 200 boxes "
                   "with 3x wider intervals, a box counts as colliding when one of 600 exact samples is within "
                   "the margin.\n")
        out.append("| scene | FCL 10 samples, median µs | KCCD collision cold, median µs | colliding boxes | "
                   "missed by FCL | missed by KCCD | KCCD stops without a sampled collision |")
        out.append("|---|---|---|---|---|---|---|")
        for s, scene in enumerate(scenes):
            f = fcl.get(s)
            k = q.get((s, 2, 0, 0))
            m = miss.get(s, {})
            out.append(f"| {scene} | {f['p50_us']:.0f} | {k['p50_us']:.1f} | {int(m.get('real_collisions', 0))} | "
                       f"{int(m.get('fcl10_missed', 0))} | {int(m.get('kccd_missed', 0))} | "
                       f"{int(m.get('kccd_extra_stops', 0))} |")
    return "\n".join(out)


def calib_table(rows):
    """Median ms of each calibration benchmark and its ratio to detection alone, from one run."""
    med = {r["run_name"].split("/")[0]: r for r in rows if r.get("aggregate_name") == "median"}
    if not med:  # a run without repetitions
        med = {r["name"].split("/")[0]: r for r in rows if r.get("run_type", "iteration") == "iteration"}
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}

    def ms(r):
        return r["real_time"] * scale[r.get("time_unit", "ns")]

    base = med.get("BM_DetectTags")
    out = ["| step | ms per frame | ratio to detection |", "|---|---|---|"]
    names = {"BM_DetectTags": "detectTags (baseline)",
             "BM_DetectAndSolve": "detectTags + tagCorrespondences + solvePose",
             "BM_Solve": "solvePose alone (32 points)"}
    for key, label in names.items():
        r = med.get(key)
        if r is None:
            continue
        ratio = f"{ms(r) / ms(base):.2f}" if base else "-"
        out.append(f"| {label} | {ms(r):.1f} | {ratio} |")
    # The refinements (masks, edges) against the label-only solve they start from (the same run).
    labels = med.get("BM_SolveLabels")
    if labels:
        out += ["", "| step (10 frames of 960x540) | ms | ratio to the label solve | rotation error (deg) | position error (mm) |",
                "|---|---|---|---|---|"]
        refine = {"BM_SolveLabels": "solvePose on 12 labels, 8 px off (baseline)",
                  "BM_RefineFromLabels": "refineToMasks from that solve",
                  "BM_RefineFromTenDegrees": "refineToMasks from 10 deg / 10 cm off",
                  "BM_RefineEdgesFromLabels": "refineToEdges from that solve (no masks; the labels as clicks)"}
        for key, label in refine.items():
            r = med.get(key)
            if r is None:
                continue
            out.append(f"| {label} | {ms(r):.1f} | {ms(r) / ms(labels):.1f} | {r.get('rotation_error_deg', float('nan')):.3f} | "
                       f"{r.get('position_error_mm', float('nan')):.2f} |")
    return "\n".join(out)


if __name__ == "__main__":
    if sys.argv[1] == "--calib":
        print(calib_table(load(sys.argv[2])))
        sys.exit(0)
    print(gjk_table(load(sys.argv[1])))
    print()
    print(engine_tables(load(sys.argv[2])))
    if len(sys.argv) > 3:
        print()
        print(calib_table(load(sys.argv[3])))
