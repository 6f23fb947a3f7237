#!/usr/bin/env python3
"""The most events of the given kinds that one pair of bodies has within any WINDOW seconds of
an events CSV (palpable run --events): pair_event_peak.py EVENTS WINDOW KIND[,KIND...]. Prints
the count. Used by the pile tests to bound trains of collisions and storms of mode changes."""
import collections
import csv
import sys


def main():
    path, window, kinds = sys.argv[1], float(sys.argv[2]), set(sys.argv[3].split(","))
    times = collections.defaultdict(list)
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["kind"] in kinds:
                times[(row["body_a"], row["body_b"])].append(float(row["t"]))
    most = 0
    for ts in times.values():
        ts.sort()
        j = 0
        for i, t in enumerate(ts):
            while t - ts[j] > window:
                j += 1
            most = max(most, i - j + 1)
    print(most)


if __name__ == "__main__":
    main()
