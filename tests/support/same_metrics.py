#!/usr/bin/env python3
"""same_metrics.py A.json B.json: exit 0 when two results.json files hold the same rows with the same
method and every metric exactly equal (timings aside), else exit 1 naming every difference.

Rows are matched by (scene, config, light), as `shadowlab gate` does; JSON numbers read back as the
doubles that were written, so equality here is bit equality of the metrics."""
import json
import sys


def rows(path):
    with open(path) as f:
        doc = json.load(f)
    out = {}
    for i, r in enumerate(doc["rows"]):
        key = (r["scene"], r["config"], r["light"])
        if key in out:
            raise SystemExit(f"{path}: /rows/{i}: row {' | '.join(key)} appears twice")
        out[key] = r
    return out


def main():
    if len(sys.argv) != 3:
        raise SystemExit("usage: same_metrics.py A.json B.json")
    a_path, b_path = sys.argv[1:]
    a, b = rows(a_path), rows(b_path)
    problems = []
    for key in sorted(a.keys() - b.keys()):
        problems.append(f"row {' | '.join(key)} is only in {a_path}")
    for key in sorted(b.keys() - a.keys()):
        problems.append(f"row {' | '.join(key)} is only in {b_path}")
    for key in sorted(a.keys() & b.keys()):
        ra, rb = a[key], b[key]
        name = " | ".join(key)
        if ra["method"] != rb["method"]:
            problems.append(f"row {name}: the methods differ")
        ma, mb = ra["metrics"], rb["metrics"]
        for metric in sorted(ma.keys() | mb.keys()):
            if metric not in ma or metric not in mb:
                problems.append(f"row {name}: metric {metric} is in one file only")
            elif ma[metric] != mb[metric]:
                problems.append(f"row {name}: metric {metric} is {ma[metric]!r} in A, {mb[metric]!r} in B")
    if not a:
        problems.append(f"{a_path} has no rows")
    for p in problems:
        print(f"same_metrics: {p}", file=sys.stderr)
    if problems:
        print(f"same_metrics: DIFFER: {len(problems)} difference(s) between {a_path} and {b_path}", file=sys.stderr)
        return 1
    print(f"same_metrics: same {len(a)} rows, every metric equal ({a_path} vs {b_path})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
